//! Small geometric helpers on top of glam.

pub mod cell_map;
pub mod fnv;
mod frame;
mod lanes;
pub mod noise;
pub mod trig;

pub use frame::Frame;
pub use lanes::{exp4, ln4};

use glam::Vec3;

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
