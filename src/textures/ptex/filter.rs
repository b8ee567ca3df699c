//! The Ptex library's separable B-spline filter (`PtexBicubicFilter` with sharpness 0, its
//! `f_bspline`, as pbrt-v4 asks for it; no lerp between resolutions, edge blending on): a
//! 4-texel-wide cubic kernel at the resolution the footprint picks, split where it crosses
//! a face edge and applied to the neighbour (rotated into its frame), with corners shared
//! among the faces around a vertex. Ported step by step from the library
//! (`PtexSeparableFilter`, `PtexSeparableKernel`, `PtexWidth4Filter`) so that lookups agree
//! with pbrt-v4's to float rounding.

use super::file::{BorderMode, FaceInfo, FaceRef, PtexFile, Res, Texels};
use super::kernel::{Kernel, build_axis};

/// Deepest chain of subface re-splits followed (a well-formed file needs two).
const MAX_DEPTH: u32 = 8;

/// The B-spline kernel's weighted sums of `face`'s first `nchan` channels at (u, v) over
/// the footprint (uw1, vw1, uw2, vw2), and the weight applied (the library's
/// `PtexSeparableFilter::eval` with width 1 and no blur, before normalising).
pub fn eval(file: &PtexFile, nchan: usize, face: i32, f: &FaceInfo, u: f32, v: f32, w: [f32; 4]) -> ([f32; 4], f32) {
    let [uw1, vw1, uw2, vw2] = w;
    let uw = uw1.abs() + uw2.abs();
    let vw = vw1.abs() + vw2.abs();
    let mut black = false;
    let mut border = |x: f32, mode: BorderMode| match mode {
        BorderMode::Clamp => x.clamp(0.0, 1.0),
        BorderMode::Periodic => x - x.floor(),
        BorderMode::Black => {
            black |= x <= -1.0 || x >= 2.0;
            x
        }
    };
    let (u, v) = (border(u, file.u_mode), border(v, file.v_mode));
    if black {
        return ([0.0; 4], 1.0);
    }
    let mut k = Kernel::empty();
    if f.is_subface() {
        // As if on the main face, then one level down.
        let res = Res::new(f.res.ulog2 + 1, f.res.vlog2 + 1);
        (k.res.ulog2, k.u, k.uw) = build_axis(u * 0.5, uw * 0.5, res.ulog2, &mut k.ku);
        (k.res.vlog2, k.v, k.vw) = build_axis(v * 0.5, vw * 0.5, res.vlog2, &mut k.kv);
        if k.res.ulog2 == 0 {
            k.upres_u();
        }
        if k.res.vlog2 == 0 {
            k.upres_v();
        }
        k.res.ulog2 -= 1;
        k.res.vlog2 -= 1;
    } else {
        (k.res.ulog2, k.u, k.uw) = build_axis(u, uw, f.res.ulog2, &mut k.ku);
        (k.res.vlog2, k.v, k.vw) = build_axis(v, vw, f.res.vlog2, &mut k.kv);
    }
    k.strip_zeros();
    if k.uw <= 0 || k.vw <= 0 {
        return ([0.0; 4], 0.0);
    }
    let mut e = Eval { file, nchan, result: [0.0; 4], weight: k.weight() };
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
    fn info(&self, face: i32) -> Option<&FaceInfo> {
        self.file.faces.get(usize::try_from(face).ok()?)
    }

    fn split_and_apply(&mut self, mut k: Kernel, face: i32, f: &FaceInfo, depth: u32) {
        if depth > MAX_DEPTH {
            return;
        }
        let (u_mode, v_mode) = (self.file.u_mode, self.file.v_mode);
        let split_r = k.u + k.uw > k.res.u();
        let split_l = k.u < 0;
        let split_t = k.v + k.vw > k.res.v();
        let split_b = k.v < 0;
        if split_r {
            if f.adjface(1) >= 0 {
                let mut ka = k.split_r();
                if split_t {
                    if f.adjface(2) >= 0 {
                        let kc = ka.split_t();
                        self.apply_to_corner(kc, face, f, 2, depth);
                    } else {
                        ka.merge_t(v_mode);
                    }
                }
                if split_b {
                    if f.adjface(0) >= 0 {
                        let kc = ka.split_b();
                        self.apply_to_corner(kc, face, f, 1, depth);
                    } else {
                        ka.merge_b(v_mode);
                    }
                }
                self.apply_across_edge(ka, face, f, 1, depth);
            } else {
                k.merge_r(u_mode);
            }
        }
        if split_l {
            if f.adjface(3) >= 0 {
                let mut ka = k.split_l();
                if split_t {
                    if f.adjface(2) >= 0 {
                        let kc = ka.split_t();
                        self.apply_to_corner(kc, face, f, 3, depth);
                    } else {
                        ka.merge_t(v_mode);
                    }
                }
                if split_b {
                    if f.adjface(0) >= 0 {
                        let kc = ka.split_b();
                        self.apply_to_corner(kc, face, f, 0, depth);
                    } else {
                        ka.merge_b(v_mode);
                    }
                }
                self.apply_across_edge(ka, face, f, 3, depth);
            } else {
                k.merge_l(u_mode);
            }
        }
        if split_t {
            if f.adjface(2) >= 0 {
                let ka = k.split_t();
                self.apply_across_edge(ka, face, f, 2, depth);
            } else {
                k.merge_t(v_mode);
            }
        }
        if split_b {
            if f.adjface(0) >= 0 {
                let ka = k.split_b();
                self.apply_across_edge(ka, face, f, 0, depth);
            } else {
                k.merge_b(v_mode);
            }
        }
        self.apply(&k, face, f);
    }

    fn apply_across_edge(&mut self, mut k: Kernel, face: i32, f: &FaceInfo, eid: i32, depth: u32) {
        let mut afid = f.adjface(eid);
        let mut aeid = f.adjedge(eid);
        let Some(mut af) = self.info(afid).copied() else { return };
        let mut rot = eid - aeid + 2;
        if f.is_subface() != af.is_subface() {
            if af.is_subface() {
                if !k.adjust_main_to_subface(eid) {
                    // On to the secondary subface.
                    let neid = (aeid + 3) % 4;
                    afid = af.adjface(neid);
                    aeid = af.adjedge(neid);
                    let Some(next) = self.info(afid).copied() else { return };
                    af = next;
                    rot += neid - aeid + 2;
                }
            } else {
                let primary = af.adjface(aeid) == face;
                k.adjust_subface_to_main(eid - primary as i32);
            }
        }
        k.rotate(rot);
        if af.is_subface() {
            self.split_and_apply(k, afid, &af, depth + 1);
        } else {
            self.apply(&k, afid, &af);
        }
    }

    fn apply_to_corner(&mut self, mut k: Kernel, face: i32, f: &FaceInfo, eid: i32, depth: u32) {
        const MAX_VALENCE: usize = 10;
        let mut afid = face;
        let mut aeid = eid;
        let mut af = *f;
        let mut prev_is_subface = af.is_subface();
        let mut corners = [(0i32, 0i32, *f); MAX_VALENCE];
        let mut num_corners: i32 = 0;
        for (i, corner) in corners.iter_mut().enumerate() {
            let prev_face = afid;
            afid = af.adjface(aeid);
            aeid = (af.adjedge(aeid) + 1) % 4;
            // A boundary, or back at the start (checking the edge too: a periodic texture
            // may have all four corners on one face).
            if afid < 0 || (afid == face && aeid == eid) {
                num_corners = i as i32 - 2;
                break;
            }
            let Some(next) = self.info(afid).copied() else { return };
            af = next;
            *corner = (afid, aeid, af);
            let is_subface = af.is_subface();
            if prev_is_subface && !is_subface && af.adjface((aeid + 3) % 4) == prev_face {
                // A subface "tee": the corner is the main face's.
                let primary = (i == 1) as i32;
                k.adjust_subface_to_main(eid + primary * 2);
                k.rotate(eid - aeid + 3 - primary);
                self.split_and_apply(k, afid, &af, depth + 1);
                return;
            }
            prev_is_subface = is_subface;
        }
        if num_corners == 1 {
            let (cfid, ceid, cf) = corners[1];
            self.apply_to_corner_face(k, f, eid, cfid, &cf, ceid, depth);
        } else if num_corners > 1 {
            // Valence five or more: a symmetric kernel, shared equally.
            k.rotate(eid + 2);
            let initial = k.weight();
            let new = k.make_symmetric(initial);
            for &(cfid, ceid, cf) in &corners[1..=num_corners as usize] {
                self.apply_to_corner_face(k, f, 2, cfid, &cf, ceid, depth);
            }
            self.weight += new * num_corners as f32 - initial;
        } else {
            // Valence two or three: no corner face; its share of the weight goes.
            self.weight -= k.weight();
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn apply_to_corner_face(
        &mut self,
        mut k: Kernel,
        f: &FaceInfo,
        eid: i32,
        cfid: i32,
        cf: &FaceInfo,
        ceid: i32,
        depth: u32,
    ) {
        if f.is_subface() != cf.is_subface() {
            if cf.is_subface() {
                k.adjust_main_to_subface(eid + 3);
            } else {
                k.adjust_subface_to_main(eid + 3);
            }
        }
        k.rotate(eid - ceid + 2);
        if cf.is_subface() {
            self.split_and_apply(k, cfid, cf, depth + 1);
        } else {
            self.apply(&k, cfid, cf);
        }
    }

    fn apply(&mut self, k: &Kernel, face: i32, f: &FaceInfo) {
        if k.uw <= 0 || k.vw <= 0 {
            return;
        }
        // A kernel outside its face comes from an inconsistent file: skipped, not read.
        if k.u < 0 || k.v < 0 || k.u + k.uw > k.res.u() || k.v + k.vw > k.res.v() {
            return;
        }
        let mut k = *k;
        while k.res.u() > f.res.u() {
            k.downres_u();
        }
        while k.res.v() > f.res.v() {
            k.downres_v();
        }
        if k.res.ulog2 < 0 || k.res.vlog2 < 0 {
            return;
        }
        let (nchan, channels) = (self.nchan, self.file.channels);
        // Constant data (a constant face, or any face at 1×1) is added as it is: the
        // library returns before turning tangent vectors for it.
        let reduced;
        let d = match self.file.data(face as usize, k.res) {
            FaceRef::Constant(i) => {
                let w = k.weight();
                for (c, t) in self.result.iter_mut().enumerate().take(nchan) {
                    *t += self.file.constant_value(i, c) * w;
                }
                return;
            }
            FaceRef::Stored(d) => d,
            FaceRef::Reduced(d) => {
                reduced = d;
                &*reduced
            }
        };
        if d.constant {
            let w = k.weight();
            for (c, t) in self.result.iter_mut().enumerate().take(nchan) {
                *t += d.texels.value(c) * w;
            }
            return;
        }
        let tangent = self.file.tangent_vectors && nchan >= 2 && k.rot > 0;
        let mut sums = [0f32; 4];
        let target = if tangent { &mut sums } else { &mut self.result };
        match &d.texels {
            Texels::U8(t) => k.apply(target, t, nchan, channels),
            Texels::U16(t) => k.apply(target, t, nchan, channels),
            Texels::Half(t) => k.apply(target, t, nchan, channels),
            Texels::F32(t) => k.apply(target, t, nchan, channels),
        }
        if tangent {
            // Tangent-space vectors turn with the kernel.
            let r = &mut self.result;
            match k.rot {
                1 => {
                    r[0] -= sums[1];
                    r[1] += sums[0];
                }
                2 => {
                    r[0] -= sums[0];
                    r[1] -= sums[1];
                }
                _ => {
                    r[0] += sums[1];
                    r[1] -= sums[0];
                }
            }
            for c in 2..nchan {
                r[c] += sums[c];
            }
        }
    }
}
