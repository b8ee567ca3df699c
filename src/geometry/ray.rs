//! Rays and the offsets that keep rays leaving a surface from hitting it again.

use glam::Vec3;

/// A ray with a unit direction, at a time within the shutter interval (which only moving
/// shapes and cameras look at).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: Vec3,
    /// Unit direction.
    pub d: Vec3,
    /// Time (pbrt-v4's ray time: the camera's shutter interval, 0 to 1 by default).
    pub time: f32,
}

impl Ray {
    /// A ray from `o` along the unit vector `d` at time 0.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Ray {
        Ray { o, d, time: 0.0 }
    }

    /// A ray from `o` along the unit vector `d` at `time`.
    #[inline]
    pub fn timed(o: Vec3, d: Vec3, time: f32) -> Ray {
        Ray { o, d, time }
    }

    /// The point at distance `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// Conservative bound on the floating-point error of a hit point at `p`: intersection
/// routines compute positions to a few ulps of the largest coordinate.
#[inline]
pub fn position_error(p: Vec3) -> f32 {
    (p.abs().max_element() + 1.0) * 4e-6
}

/// Moves a point on a surface with geometric normal `n` off the surface to the side `w`
/// points to, far enough that a ray from it cannot hit the surface it left (pbrt-v4's
/// OffsetRayOrigin, with a uniform error bound instead of per-shape bounds).
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    offset_origin_by(p, n, w, 0.0)
}

/// [`offset_origin`] for a point known only within `p_error` in each coordinate (pbrt-v4
/// offsets by dot(|n|, pError)).
#[inline]
pub fn offset_origin_by(p: Vec3, n: Vec3, w: Vec3, p_error: f32) -> Vec3 {
    let d = (position_error(p) * 4.0).max(p_error * n.abs().element_sum());
    if n.dot(w) < 0.0 { p - n * d } else { p + n * d }
}

/// A ray from surface point `p` (normal `n`) in direction `d`, offset off the surface.
#[inline]
pub fn spawn_ray(p: Vec3, n: Vec3, d: Vec3) -> Ray {
    Ray::new(offset_origin(p, n, d), d)
}

/// A ray from surface point `p` (normal `n`) towards `target`; returns the ray and the
/// distance at which it reaches the target (slightly short, so the target's own surface is
/// not counted as an occluder).
#[inline]
pub fn spawn_ray_to(p: Vec3, n: Vec3, target: Vec3) -> (Ray, f32) {
    let o = offset_origin(p, n, target - p);
    let v = target - o;
    let dist = v.length();
    (Ray::new(o, v / dist), dist * (1.0 - 1e-4))
}
