//! The Ptex library's filter for triangle-mesh files (`PtexTriangleFilter`, which it uses
//! for every filter type but `point`): an elliptical Gaussian over the footprint, clamped to
//! at least a texel and an eccentricity of 15, at the resolution its minor axis picks, split
//! across the triangle's edges into its neighbours. A face of 2ⁿ texels a side holds
//! 2ⁿ × 2ⁿ "even" texels (pointing like the face) and as many "odd" ones (pointing the other
//! way), stored together in one square array. Ported step by step from the library
//! (`PtexTriangleFilter`, `PtexTriangleKernel`).

use super::file::{FaceInfo, FaceRef, PtexFile, Res, Texel, Texels};
use super::res_from_width;

/// Kernel width as a multiple of the filter width (the library's `PtexTriangleKernelWidth`).
const KERNEL_WIDTH: f32 = 3.5;

/// Deepest chain of edge crossings followed.
const MAX_DEPTH: u32 = 16;

/// A kernel in a face's barycentric (u, v, w = 1 − u − v) coordinates: its centre, bounds
/// per coordinate and ellipse A u² + B u v + C v² (the library's `PtexTriangleKernel`).
#[derive(Clone, Copy, Debug)]
struct Kernel {
    res_log2: i8,
    u: f32,
    v: f32,
    u1: f32,
    v1: f32,
    w1: f32,
    u2: f32,
    v2: f32,
    w2: f32,
    a: f32,
    b: f32,
    c: f32,
}

impl Kernel {
    #[allow(clippy::too_many_arguments)]
    fn place(&mut self, u: f32, v: f32, u1: f32, v1: f32, w1: f32, u2: f32, v2: f32, w2: f32) {
        (self.u, self.v, self.u1, self.v1, self.w1, self.u2, self.v2, self.w2) = (u, v, u1, v1, w1, u2, v2, w2);
    }

    /// The ellipse with u' = w, v' = u, w' = v.
    fn rotate1(&mut self) {
        let (a, b, c) = (self.a, self.b, self.c);
        (self.a, self.b, self.c) = (c, 2.0 * c - b, a + c - b);
    }

    /// The ellipse with u' = v, v' = w, w' = u.
    fn rotate2(&mut self) {
        let (a, b, c) = (self.a, self.b, self.c);
        (self.a, self.b, self.c) = (a + c - b, 2.0 * a - b, a);
    }

    /// The kernel in the frame of the face across edge `eid`, whose edge `aeid` it is.
    fn reorient(&mut self, eid: i32, aeid: i32) {
        let Kernel { u, v, u1, v1, w1, u2, v2, w2, .. } = *self;
        let w = 1.0 - u - v;
        match (eid, aeid) {
            (0, 0) => self.place(1.0 - u, -v, 1.0 - u2, -v2, 1.0 - w2, 1.0 - u1, -v1, 1.0 - w1),
            (0, 1) => {
                self.place(1.0 - w, 1.0 - u, 1.0 - w2, 1.0 - u2, -v2, 1.0 - w1, 1.0 - u1, -v1);
                self.rotate1();
            }
            (0, 2) => {
                self.place(-v, 1.0 - w, -v2, 1.0 - w2, 1.0 - u2, -v1, 1.0 - w1, 1.0 - u1);
                self.rotate2();
            }
            (1, 0) => {
                self.place(1.0 - v, -w, 1.0 - v2, -w2, 1.0 - u2, 1.0 - v1, -w1, 1.0 - u1);
                self.rotate2();
            }
            (1, 1) => self.place(1.0 - u, 1.0 - v, 1.0 - u2, 1.0 - v2, -w2, 1.0 - u1, 1.0 - v1, -w1),
            (1, 2) => {
                self.place(-w, 1.0 - u, -w2, 1.0 - u2, 1.0 - v2, -w1, 1.0 - u1, 1.0 - v1);
                self.rotate1();
            }
            (2, 0) => {
                self.place(1.0 - w, -u, 1.0 - w2, -u2, 1.0 - v2, 1.0 - w1, -u1, 1.0 - v1);
                self.rotate1();
            }
            (2, 1) => {
                self.place(1.0 - v, 1.0 - w, 1.0 - v2, 1.0 - w2, -u2, 1.0 - v1, 1.0 - w1, -u1);
                self.rotate2();
            }
            (2, 2) => self.place(-u, 1.0 - v, -u2, 1.0 - v2, 1.0 - w2, -u1, 1.0 - v1, 1.0 - w1),
            // Edge 3 does not exist on a triangle: an inconsistent file.
            _ => {}
        }
    }
}

/// The texels one half (even or odd) of a kernel covers, in texel units (the library's
/// `PtexTriangleKernelIter`).
struct Iter {
    rowlen: i32,
    u: f32,
    v: f32,
    u1: i32,
    v1: i32,
    w1: i32,
    u2: i32,
    v2: i32,
    w2: i32,
    a: f32,
    b: f32,
    c: f32,
    wscale: f32,
}

impl Iter {
    fn valid(&self) -> bool {
        self.u2 > self.u1 && self.v2 > self.v1 && self.w2 > self.w1
    }

    /// Visits each texel the ellipse covers with its weight (the library's finite-difference
    /// walk of Q = A U² + B U V + C V², Heckbert 1989).
    fn walk(&self, mut texel: impl FnMut(usize, f32)) {
        let ddq = 2.0 * self.a;
        for vi in self.v1..self.v2 {
            let xw = self.rowlen - vi;
            let x1 = self.u1.max(xw - self.w2);
            let x2 = self.u2.min(xw - self.w1);
            let big_u = x1 as f32 - self.u;
            let big_v = vi as f32 - self.v;
            let mut dq = self.a * (2.0 * big_u + 1.0) + self.b * big_v;
            let mut q = self.a * big_u * big_u + (self.b * big_u + self.c * big_v) * big_v;
            for x in x1..x2 {
                if q < 1.0 {
                    texel((vi * self.rowlen + x) as usize, gaussian(q) * self.wscale);
                }
                q += dq;
                dq += ddq;
            }
        }
    }
}

fn gaussian(x_squared: f32) -> f32 {
    (-0.5 * (KERNEL_WIDTH * KERNEL_WIDTH) * x_squared).exp()
}

/// The elliptical Gaussian's weighted sums of triangle `face`'s first `nchan` channels at
/// (u, v) over the footprint (uw1, vw1, uw2, vw2), and the weight applied (the library's
/// `PtexTriangleFilter::eval` with width 1 and no blur, before normalising).
pub fn eval(file: &PtexFile, nchan: usize, face: i32, f: &FaceInfo, u: f32, v: f32, w: [f32; 4]) -> ([f32; 4], f32) {
    let [uw1, vw1, uw2, vw2] = w;
    let (u, v) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));

    // The footprint's ellipse A u² + B u v + C v² = AC − B²/4, in Cartesian coordinates.
    let sqrt3 = 1.732_050_8_f32;
    let (scale_ac, scale_b) = (0.25f32, -0.5f32);
    let a = (vw1 * vw1 + vw2 * vw2) * scale_ac;
    let b = (uw1 * vw1 + uw2 * vw2) * scale_b;
    let c = (uw1 * uw1 + uw2 * uw2) * scale_ac;
    let mut ac = 0.75 * a;
    let bc = (sqrt3 / 2.0) * (b - a);
    let mut cc = 0.25 * a - 0.5 * b + c;
    // Blur enough to keep the eccentricity at most 15 and the ellipse no smaller than a
    // texel.
    const MAX_ECC: f32 = 15.0;
    let ecc_ratio = (MAX_ECC * MAX_ECC + 1.0) / (MAX_ECC * MAX_ECC - 1.0);
    let x = ((ac - cc) * (ac - cc) + bc * bc).sqrt();
    let b_e = 0.5 * (ecc_ratio * x - (ac + cc));
    let b_t = (0.5 / f.res.u() as f32).powi(2);
    let blur = 0.0f32.max(b_e.max(b_t));
    ac += blur;
    cc += blur;
    let minor = (2.0 * (ac * cc - 0.25 * bc * bc) / (ac + cc + x)).sqrt();
    let res_log2 = res_from_width(2.0 * minor).max(0);
    // Back to the triangle's coordinates, scaled to the kernel's width.
    let a = 4.0f32 / 3.0 * ac;
    let b = (2.0 / sqrt3) * bc + a;
    let c = -0.25 * a + 0.5 * b + cc;
    let s = KERNEL_WIDTH * KERNEL_WIDTH;
    let (a, b, c) = (a * s, b * s, c * s);
    let uw = c.sqrt().min(1.0);
    let vw = a.sqrt().min(1.0);
    let ww = (a - b + c).sqrt().min(1.0);
    let w = 1.0 - u - v;
    let k = Kernel {
        res_log2: res_log2.min(i8::MAX as i32) as i8,
        u,
        v,
        u1: u - uw,
        v1: v - vw,
        w1: w - ww,
        u2: u + uw,
        v2: v + vw,
        w2: w + ww,
        a,
        b,
        c,
    };
    let mut e = Eval { file, nchan, result: [0.0; 4], weight: 0.0 };
    e.split_and_apply(k, face, f, 0);
    (e.result, e.weight)
}

/// One lookup's running sums.
struct Eval<'a> {
    file: &'a PtexFile,
    nchan: usize,
    result: [f32; 4],
    weight: f32,
}

impl Eval<'_> {
    fn split_and_apply(&mut self, mut k: Kernel, face: i32, f: &FaceInfo, depth: u32) {
        if depth > MAX_DEPTH {
            return;
        }
        // The edges: 0 along v = 0, 1 along w = 0, 2 along u = 0.
        if k.u1 < 0.0 && f.adjface(2) >= 0 {
            let mut ka = k;
            k.u1 = 0.0;
            ka.u2 = 0.0;
            self.apply_across_edge(ka, f, 2, depth);
        }
        if k.v1 < 0.0 && f.adjface(0) >= 0 {
            let mut ka = k;
            k.v1 = 0.0;
            ka.v2 = 0.0;
            self.apply_across_edge(ka, f, 0, depth);
        }
        if k.w1 < 0.0 && f.adjface(1) >= 0 {
            let mut ka = k;
            k.w1 = 0.0;
            ka.w2 = 0.0;
            self.apply_across_edge(ka, f, 1, depth);
        }
        self.apply(k, face, f);
    }

    fn apply_across_edge(&mut self, mut k: Kernel, f: &FaceInfo, eid: i32, depth: u32) {
        let afid = f.adjface(eid);
        let Some(af) = self.file.faces.get(afid as usize).copied() else { return };
        k.reorient(eid, f.adjedge(eid));
        self.split_and_apply(k, afid, &af, depth + 1);
    }

    fn apply(&mut self, mut k: Kernel, face: i32, f: &FaceInfo) {
        k.res_log2 = k.res_log2.min(f.res.ulog2);
        k.u1 = k.u1.max(0.0);
        k.v1 = k.v1.max(0.0);
        k.w1 = k.w1.max(0.0);
        k.u2 = k.u2.min(1.0 - (k.v1 + k.w1));
        k.v2 = k.v2.min(1.0 - (k.w1 + k.u1));
        k.w2 = k.w2.min(1.0 - (k.u1 + k.v1));
        let resu = 1i32 << k.res_log2;
        let fres = resu as f32;
        let finv = 1.0 / (fres * fres * (k.a * k.c - 0.25 * k.b * k.b));
        let (ak, bk, ck) = (k.a * finv, k.b * finv, k.c * finv);
        let third = 1.0f32 / 3.0;
        let at = |x: f32| (x * fres - third).ceil() as i32;
        let wscale = 1.0 / (fres * fres);
        let even = Iter {
            rowlen: resu,
            u: k.u * fres - third,
            v: k.v * fres - third,
            u1: at(k.u1),
            v1: at(k.v1),
            w1: at(k.w1),
            u2: at(k.u2),
            v2: at(k.v2),
            w2: at(k.w2),
            a: ak,
            b: bk,
            c: ck,
            wscale,
        };
        // The odd texels: the kernel flipped across the diagonal (u = 1 − v, v = 1 − u,
        // w = −w).
        let odd = Iter {
            rowlen: resu,
            u: (1.0 - k.v) * fres - third,
            v: (1.0 - k.u) * fres - third,
            u1: at(1.0 - k.v2),
            v1: at(1.0 - k.u2),
            w1: at(-k.w2),
            u2: at(1.0 - k.v1),
            v2: at(1.0 - k.u1),
            w2: at(-k.w1),
            a: ck,
            b: bk,
            c: ak,
            wscale,
        };
        if !even.valid() && !odd.valid() {
            return;
        }
        // Texel indices outside [0, resu) only come from inconsistent files.
        let inside = |it: &Iter| it.u1 >= 0 && it.v1 >= 0 && it.u2 <= resu && it.v2 <= resu;
        let res = Res::new(k.res_log2, k.res_log2);
        let reduced;
        let data = match self.file.data(face as usize, res) {
            FaceRef::Constant(i) => Err(i),
            FaceRef::Stored(d) => Ok(d),
            FaceRef::Reduced(d) => {
                reduced = d;
                Ok(&*reduced)
            }
        };
        for it in [even, odd] {
            if !it.valid() || !inside(&it) {
                continue;
            }
            let (nchan, channels) = (self.nchan, self.file.channels);
            let mut weight = 0.0f32;
            match data {
                Err(i) => {
                    it.walk(|_, w| weight += w);
                    for c in 0..nchan {
                        self.result[c] += self.file.constant_value(i, c) * weight;
                    }
                }
                Ok(d) if d.constant => {
                    it.walk(|_, w| weight += w);
                    for c in 0..nchan {
                        self.result[c] += d.texels.value(c) * weight;
                    }
                }
                Ok(d) => {
                    let result = &mut self.result;
                    fn add<T: Texel>(t: &[T], i: usize, w: f32, channels: usize, nchan: usize, result: &mut [f32; 4]) {
                        if let Some(p) = t.get(i * channels..i * channels + nchan) {
                            for (r, x) in result.iter_mut().zip(p) {
                                *r += x.value() * w;
                            }
                        }
                    }
                    it.walk(|i, w| {
                        weight += w;
                        match &d.texels {
                            Texels::U8(t) => add(t, i, w, channels, nchan, result),
                            Texels::U16(t) => add(t, i, w, channels, nchan, result),
                            Texels::Half(t) => add(t, i, w, channels, nchan, result),
                            Texels::F32(t) => add(t, i, w, channels, nchan, result),
                        }
                    });
                }
            }
            self.weight += weight;
        }
    }
}
