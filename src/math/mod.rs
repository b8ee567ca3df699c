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
