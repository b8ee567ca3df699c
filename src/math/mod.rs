//! Small geometric helpers on top of glam.

pub mod cell_map;
pub mod fnv;
mod frame;
mod lanes;
pub mod noise;
pub mod trig;

pub use frame::Frame;
pub use lanes::{exp4, ln4};

use glam::{IVec3, Vec3};

/// Cosine of the angle between `w` and the local +z axis.
#[inline]
pub fn cos_theta(w: Vec3) -> f32 {
    w.z
}

/// |cos θ| of a local direction.
#[inline]
pub fn abs_cos_theta(w: Vec3) -> f32 {
    w.z.abs()
}

/// True when two local directions are on the same side of the surface.
#[inline]
pub fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// Mirror reflection of `wo` about `n`.
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refraction of `wi` through a surface with normal `n` (on `wi`'s side) and relative index
/// `eta` = η_transmitted / η_incident. Returns the transmitted direction and the relative eta
/// actually used (flipped when `wi` is on the back side), or `None` on total internal
/// reflection.
#[inline]
pub fn refract(wi: Vec3, mut n: Vec3, mut eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wi / eta + (cos_i / eta - cos_t) * n, eta))
}

/// Real roots of a x² + b x + c, smaller first (pbrt-v4's `Quadratic`, with its linear case).
pub fn quadratic(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    if a == 0.0 {
        if b == 0.0 {
            return None;
        }
        let t = -c / b;
        return Some((t, t));
    }
    let discrim = (b as f64) * (b as f64) - 4.0 * (a as f64) * (c as f64);
    if discrim < 0.0 {
        return None;
    }
    let root = discrim.sqrt();
    let q = if b < 0.0 { -0.5 * (b as f64 - root) } else { -0.5 * (b as f64 + root) };
    let (mut t0, mut t1) = ((q / a as f64) as f32, (c as f64 / q) as f32);
    if q == 0.0 {
        t1 = t0;
    }
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    Some((t0, t1))
}

/// Squares its argument.
#[inline]
pub fn sqr(x: f32) -> f32 {
    x * x
}

/// sqrt that returns 0 for (slightly) negative arguments.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// ⌊p⌋ per axis as integers. `Vec3::floor` is a libm call on targets without SSE4.1 (3.5 % of
/// a Disney-cloud render went to `floorf`); truncation, corrected where it rounded a negative
/// non-integer up, is exact for |p| < 2³¹ and saturates beyond, as `as_ivec3` does.
#[inline(always)]
pub fn floor_ivec3(p: Vec3) -> IVec3 {
    let t = p.as_ivec3();
    t.saturating_sub(IVec3::select(p.cmplt(t.as_vec3()), IVec3::ONE, IVec3::ZERO))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_ivec3_is_floor() {
        for v in [-2.5f32, -2.0, -1e-7, -0.0, 0.0, 0.3, 1.0, 7.999, 1e6 + 0.5, -3e9, 3e9, f32::NAN] {
            let p = Vec3::new(v, -v, v * 0.5);
            let want = p.floor().as_ivec3();
            assert_eq!(floor_ivec3(p), want, "{p}");
        }
    }
}
