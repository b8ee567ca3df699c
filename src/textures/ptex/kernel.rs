//! The Ptex library's separable kernel (`PtexSeparableKernel`) and how its width-4
//! B-spline is built along one axis (`PtexWidth4Filter::buildKernelAxis`), ported with its
//! rounding; `filter.rs` splits it across face edges and applies it.

use super::file::{BorderMode, Res, Texel};
use super::res_from_width;

/// Room for a kernel's weights along one axis (the library's is 10; upsampling a kernel for
/// a subface doubles it).
pub(super) const KMAX: usize = 24;

/// A separable kernel over a face's texels at resolution `res`: weights `ku` over texels
/// `u..u + uw` and `kv` over `v..v + vw` (the library's `PtexSeparableKernel`, its weight
/// pointers kept at the start of the arrays).
#[derive(Clone, Copy, Debug)]
pub(super) struct Kernel {
    pub(super) res: Res,
    pub(super) u: i32,
    pub(super) v: i32,
    pub(super) uw: i32,
    pub(super) vw: i32,
    pub(super) ku: [f32; KMAX],
    pub(super) kv: [f32; KMAX],
    /// Quarter turns the kernel was rotated by on its way to this face.
    pub(super) rot: i32,
}

/// Σ of `k`, in order (the library's `accumulate`).
fn sum(k: &[f32]) -> f32 {
    k.iter().fold(0.0, |a, &x| a + x)
}

impl Kernel {
    pub(super) fn empty() -> Kernel {
        Kernel { res: Res::new(0, 0), u: 0, v: 0, uw: 0, vw: 0, ku: [0.0; KMAX], kv: [0.0; KMAX], rot: 0 }
    }

    /// A new kernel (rotation 0) with weights copied from `ku` and `kv`.
    pub(super) fn with(res: Res, u: i32, v: i32, ku: &[f32], kv: &[f32]) -> Kernel {
        let mut k = Kernel { res, u, v, uw: ku.len() as i32, vw: kv.len() as i32, ..Kernel::empty() };
        k.ku[..ku.len()].copy_from_slice(ku);
        k.kv[..kv.len()].copy_from_slice(kv);
        k
    }

    pub(super) fn kus(&self) -> &[f32] {
        &self.ku[..self.uw.max(0) as usize]
    }

    pub(super) fn kvs(&self) -> &[f32] {
        &self.kv[..self.vw.max(0) as usize]
    }

    pub(super) fn weight(&self) -> f32 {
        sum(self.kus()) * sum(self.kvs())
    }

    /// Drops zero weights at both ends.
    pub(super) fn strip_zeros(&mut self) {
        let lead = self.kus().iter().take_while(|&&w| w == 0.0).count();
        self.ku.copy_within(lead..self.uw as usize, 0);
        self.u += lead as i32;
        self.uw -= lead as i32;
        while self.uw > 0 && self.ku[self.uw as usize - 1] == 0.0 {
            self.uw -= 1;
        }
        let lead = self.kvs().iter().take_while(|&&w| w == 0.0).count();
        self.kv.copy_within(lead..self.vw as usize, 0);
        self.v += lead as i32;
        self.vw -= lead as i32;
        while self.vw > 0 && self.kv[self.vw as usize - 1] == 0.0 {
            self.vw -= 1;
        }
    }

    /// Folds the part left of the face into its first column (clamp) or drops it (black).
    pub(super) fn merge_l(&mut self, mode: BorderMode) {
        if -self.u >= self.uw {
            self.outside(mode, false);
            return;
        }
        let w = (-self.u) as usize;
        if mode != BorderMode::Black {
            self.ku[w] += sum(&self.ku[..w]);
        }
        self.ku.copy_within(w..self.uw as usize, 0);
        self.uw -= w as i32;
        self.u = 0;
    }

    pub(super) fn merge_r(&mut self, mode: BorderMode) {
        if self.u >= self.res.u() {
            self.outside(mode, false);
            return;
        }
        let w = self.uw + self.u - self.res.u();
        let start = (self.uw - w) as usize;
        if mode != BorderMode::Black {
            self.ku[start - 1] += sum(&self.ku[start..self.uw as usize]);
        }
        self.uw -= w;
    }

    pub(super) fn merge_b(&mut self, mode: BorderMode) {
        if -self.v >= self.vw {
            self.outside(mode, true);
            return;
        }
        let w = (-self.v) as usize;
        if mode != BorderMode::Black {
            self.kv[w] += sum(&self.kv[..w]);
        }
        self.kv.copy_within(w..self.vw as usize, 0);
        self.vw -= w as i32;
        self.v = 0;
    }

    pub(super) fn merge_t(&mut self, mode: BorderMode) {
        if self.v >= self.res.v() {
            self.outside(mode, true);
            return;
        }
        let w = self.vw + self.v - self.res.v();
        let start = (self.vw - w) as usize;
        if mode != BorderMode::Black {
            self.kv[start - 1] += sum(&self.kv[start..self.vw as usize]);
        }
        self.vw -= w;
    }

    /// A kernel wholly beyond an edge without a neighbour (only a lookup outside [0, 1]
    /// with a `black` border gets one, where the library reads outside its arrays): nothing
    /// for black, else all its weight on the nearest edge texel.
    pub(super) fn outside(&mut self, mode: BorderMode, along_v: bool) {
        let (pos, w, k, n) = if along_v {
            (&mut self.v, &mut self.vw, &mut self.kv, self.res.v())
        } else {
            (&mut self.u, &mut self.uw, &mut self.ku, self.res.u())
        };
        if mode == BorderMode::Black {
            *w = 0;
            return;
        }
        k[0] = sum(&k[..*w as usize]);
        *pos = (*pos).clamp(0, n - 1);
        *w = 1;
    }

    /// Splits off the part left of the face, in the coordinates of the face on the left.
    pub(super) fn split_l(&mut self) -> Kernel {
        let w = -self.u;
        if w < self.uw {
            let k = Kernel::with(self.res, self.res.u() - w, self.v, &self.ku[..w as usize], self.kvs());
            self.u = 0;
            self.ku.copy_within(w as usize..self.uw as usize, 0);
            self.uw -= w;
            k
        } else {
            let mut k = *self;
            k.u += self.res.u();
            self.u = 0;
            self.uw = 0;
            k
        }
    }

    pub(super) fn split_r(&mut self) -> Kernel {
        let w = self.u + self.uw - self.res.u();
        if w < self.uw {
            let k = Kernel::with(self.res, 0, self.v, &self.ku[(self.uw - w) as usize..self.uw as usize], self.kvs());
            self.uw -= w;
            k
        } else {
            let mut k = *self;
            k.u -= self.res.u();
            self.u = 0;
            self.uw = 0;
            k
        }
    }

    pub(super) fn split_b(&mut self) -> Kernel {
        let w = -self.v;
        if w < self.vw {
            let k = Kernel::with(self.res, self.u, self.res.v() - w, self.kus(), &self.kv[..w as usize]);
            self.v = 0;
            self.kv.copy_within(w as usize..self.vw as usize, 0);
            self.vw -= w;
            k
        } else {
            let mut k = *self;
            k.v += self.res.v();
            self.v = 0;
            self.vw = 0;
            k
        }
    }

    pub(super) fn split_t(&mut self) -> Kernel {
        let w = self.v + self.vw - self.res.v();
        if w < self.vw {
            let k = Kernel::with(self.res, self.u, 0, self.kus(), &self.kv[(self.vw - w) as usize..self.vw as usize]);
            self.vw -= w;
            k
        } else {
            let mut k = *self;
            k.v -= self.res.v();
            self.v = 0;
            self.vw = 0;
            k
        }
    }

    pub(super) fn flip_u(&mut self) {
        self.u = self.res.u() - self.u - self.uw;
        self.ku[..self.uw as usize].reverse();
    }

    pub(super) fn flip_v(&mut self) {
        self.v = self.res.v() - self.v - self.vw;
        self.kv[..self.vw as usize].reverse();
    }

    pub(super) fn swap_uv(&mut self) {
        self.res = self.res.swapped();
        std::mem::swap(&mut self.u, &mut self.v);
        std::mem::swap(&mut self.uw, &mut self.vw);
        std::mem::swap(&mut self.ku, &mut self.kv);
    }

    /// Rotates the kernel `r` quarter turns counter-clockwise.
    pub(super) fn rotate(&mut self, r: i32) {
        match r & 3 {
            1 => {
                self.flip_u();
                self.swap_uv();
            }
            2 => {
                self.flip_u();
                self.flip_v();
            }
            3 => {
                self.flip_v();
                self.swap_uv();
            }
            _ => return,
        }
        self.rot = (self.rot + r) & 3;
    }

    /// Moves a kernel crossing edge `eid` of a main face onto the subface pair there; true
    /// when it lands on the primary one.
    pub(super) fn adjust_main_to_subface(&mut self, eid: i32) -> bool {
        if self.res.ulog2 == 0 {
            self.upres_u();
        }
        if self.res.vlog2 == 0 {
            self.upres_v();
        }
        if self.res.ulog2 > 0 {
            self.res.ulog2 -= 1;
        }
        if self.res.vlog2 > 0 {
            self.res.vlog2 -= 1;
        }
        let (resu, resv) = (self.res.u(), self.res.v());
        match eid & 3 {
            0 => {
                let primary = self.u < resu;
                self.v -= resv;
                if !primary {
                    self.u -= resu;
                }
                primary
            }
            1 => {
                let primary = self.v < resv;
                if !primary {
                    self.v -= resv;
                }
                primary
            }
            2 => {
                let primary = self.u >= resu;
                if primary {
                    self.u -= resu;
                }
                primary
            }
            _ => {
                let primary = self.v >= resv;
                self.u -= resu;
                if primary {
                    self.v -= resv;
                }
                primary
            }
        }
    }

    pub(super) fn adjust_subface_to_main(&mut self, eid: i32) {
        match eid & 3 {
            0 => self.v += self.res.v(),
            1 => {}
            2 => self.u += self.res.u(),
            _ => {
                self.u += self.res.u();
                self.v += self.res.v();
            }
        }
        self.res.ulog2 += 1;
        self.res.vlog2 += 1;
    }

    /// Halves the kernel's u resolution, summing weights of texel pairs.
    pub(super) fn downres_u(&mut self) {
        let (mut src, mut dst) = (0usize, 0usize);
        let mut uw = self.uw;
        if self.u & 1 != 0 {
            src += 1;
            dst += 1;
            uw -= 1;
        }
        for _ in 0..uw / 2 {
            self.ku[dst] = self.ku[src] + self.ku[src + 1];
            dst += 1;
            src += 2;
        }
        if uw & 1 != 0 {
            self.ku[dst] = self.ku[src];
            dst += 1;
        }
        self.u /= 2;
        self.uw = dst as i32;
        self.res.ulog2 -= 1;
    }

    pub(super) fn downres_v(&mut self) {
        let (mut src, mut dst) = (0usize, 0usize);
        let mut vw = self.vw;
        if self.v & 1 != 0 {
            src += 1;
            dst += 1;
            vw -= 1;
        }
        for _ in 0..vw / 2 {
            self.kv[dst] = self.kv[src] + self.kv[src + 1];
            dst += 1;
            src += 2;
        }
        if vw & 1 != 0 {
            self.kv[dst] = self.kv[src];
            dst += 1;
        }
        self.v /= 2;
        self.vw = dst as i32;
        self.res.vlog2 -= 1;
    }

    /// Doubles the kernel's u resolution, each weight split in two.
    pub(super) fn upres_u(&mut self) {
        let uw = (self.uw as usize).min(KMAX / 2);
        for i in (0..uw).rev() {
            let w = self.ku[i] / 2.0;
            self.ku[2 * i] = w;
            self.ku[2 * i + 1] = w;
        }
        self.uw = 2 * uw as i32;
        self.u *= 2;
        self.res.ulog2 += 1;
    }

    pub(super) fn upres_v(&mut self) {
        let vw = (self.vw as usize).min(KMAX / 2);
        for i in (0..vw).rev() {
            let w = self.kv[i] / 2.0;
            self.kv[2 * i] = w;
            self.kv[2 * i + 1] = w;
        }
        self.vw = 2 * vw as i32;
        self.v *= 2;
        self.res.vlog2 += 1;
    }

    /// Makes a corner kernel (at u = v = 0) the same along both axes, for a vertex of valence
    /// five or more, keeping its weight (the library's `makeSymmetric`).
    pub(super) fn make_symmetric(&mut self, initial_weight: f32) -> f32 {
        while self.res.ulog2 > self.res.vlog2 {
            self.downres_u();
        }
        while self.res.vlog2 > self.res.ulog2 {
            self.downres_v();
        }
        let n = self.uw.min(self.vw);
        self.uw = n;
        self.vw = n;
        let mut new_weight = 0.0;
        for i in 0..n as usize {
            let s = self.ku[i] + self.kv[i];
            self.ku[i] = s;
            self.kv[i] = s;
            new_weight += s;
        }
        new_weight *= new_weight;
        let scale = if new_weight == 0.0 { 1.0 } else { initial_weight / new_weight };
        if scale < 1.0 {
            if scale < -1.0 {
                for w in &mut self.ku[..n as usize] {
                    *w *= -1.0;
                }
                new_weight = -new_weight;
            } else {
                for w in &mut self.ku[..n as usize] {
                    *w *= scale;
                }
                new_weight = initial_weight;
            }
        }
        new_weight
    }

    /// Adds the kernel's weighted sum of `texels` (at the kernel's resolution) to `result`,
    /// row by row as the library sums.
    pub(super) fn apply<T: Texel>(&self, result: &mut [f32; 4], texels: &[T], nchan: usize, channels: usize) {
        let row_len = self.res.u() as usize;
        for (j, &kv) in self.kvs().iter().enumerate() {
            let row = (self.v as usize + j) * row_len + self.u as usize;
            let mut row_result = [0f32; 4];
            for (i, &ku) in self.kus().iter().enumerate() {
                let p = &texels[(row + i) * channels..];
                for c in 0..nchan {
                    if i == 0 {
                        row_result[c] = p[c].value() * ku;
                    } else {
                        row_result[c] += p[c].value() * ku;
                    }
                }
            }
            for c in 0..nchan {
                result[c] += row_result[c] * kv;
            }
        }
    }
}

/// The 2-unit cubic Hermite the library blends with for wide footprints.
fn blur(x: f32) -> f32 {
    let x = x.abs();
    if x < 1.0 { (2.0 * x - 3.0) * x * x + 1.0 } else { 0.0 }
}

/// The cubic B-spline (Mitchell–Netravali B = 1, C = 0) with the library's coefficients.
fn bspline(x: f32) -> f32 {
    const B: f32 = 1.0;
    const C: [f32; 7] = [
        1.5 - B,
        1.5 * B - 2.5,
        1.0 - (1.0 / 3.0) * B,
        (1.0 / 3.0) * B - 0.5,
        2.5 - 1.5 * B,
        2.0 * B - 4.0,
        2.0 - (2.0 / 3.0) * B,
    ];
    let x = x.abs();
    if x < 1.0 {
        (C[0] * x + C[1]) * x * x + C[2]
    } else if x < 2.0 {
        ((C[3] * x + C[4]) * x + C[5]) * x + C[6]
    } else {
        0.0
    }
}

/// One axis of the kernel for footprint width `uw` at `u` on a face of 2^`face_log2`
/// texels (the library's `PtexWidth4Filter::buildKernelAxis`, lerp off): (resolution log₂,
/// first texel, weights).
pub(super) fn build_axis(u: f32, uw: f32, face_log2: i8, k: &mut [f32; KMAX]) -> (i8, i32, i32) {
    let uw = uw.max(f32::from_bits(((127 - face_log2 as i32) as u32) << 23));
    let res_log2 = res_from_width(uw);
    if uw >= 0.25 {
        if uw < 0.5 {
            let upix = u * 4.0 - 0.5;
            let u1 = (upix - 2.0).ceil() as i32 & !1;
            let u2 = ((upix + 2.0).ceil() as i32 + 1) & !1;
            let x1 = u1 as f32 - upix;
            let kw = (u2 - u1).min(KMAX as i32);
            for i in (0..kw).step_by(2) {
                let xa = x1 + i as f32;
                k[i as usize] = bspline(xa);
                k[i as usize + 1] = bspline(xa + 1.0);
            }
            return (2, u1, kw);
        } else if uw < 1.0 {
            let upix = u * 2.0 - 0.5;
            let ku = (u - 0.5).floor() as i32 * 2;
            let x1 = ku as f32 - upix;
            let s = 1.0 / (uw * 1.5 + 0.5);
            for i in (0..4).step_by(2) {
                let xa = x1 + i as f32;
                k[i] = blur(xa * s);
                k[i + 1] = blur((xa + 1.0) * s);
            }
            return (1, ku, 4);
        } else {
            let upix = u - 0.5;
            let ui = upix.floor();
            k[0] = blur(upix - ui);
            k[1] = 1.0 - k[0];
            return (0, ui as i32, 2);
        }
    }
    let resu = (1 << res_log2) as f32;
    let upix = u * resu - 0.5;
    let uwpix = uw * resu;
    let dupix = 2.0 * uwpix;
    let u1 = (upix - dupix).ceil() as i32;
    let u2 = (upix + dupix).ceil() as i32;
    let x1 = (u1 as f32 - upix) / uwpix;
    let step = 1.0 / uwpix;
    let kw = (u2 - u1).min(KMAX as i32);
    for i in 0..kw {
        k[i as usize] = bspline(x1 + i as f32 * step);
    }
    (res_log2 as i8, u1, kw)
}
