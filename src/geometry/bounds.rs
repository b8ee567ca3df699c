//! Axis-aligned boxes.

use glam::{Affine3A, Vec3};

/// An axis-aligned box; empty when `min > max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Bounds3 {
    fn default() -> Self {
        Bounds3::EMPTY
    }
}

impl Bounds3 {
    /// The empty box (union identity).
    pub const EMPTY: Bounds3 = Bounds3 { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// The box spanned by two corners.
    pub fn new(a: Vec3, b: Vec3) -> Bounds3 {
        Bounds3 { min: a.min(b), max: a.max(b) }
    }

    /// True when the box contains nothing.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Grows the box to contain `p`.
    pub fn extend(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both.
    pub fn union(&self, o: &Bounds3) -> Bounds3 {
        Bounds3 { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// Center point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The bounding box of this box's corners under `m`.
    pub fn transformed(&self, m: &Affine3A) -> Bounds3 {
        let mut out = Bounds3::EMPTY;
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            out.extend(m.transform_point3(c));
        }
        out
    }

    /// A sphere enclosing the box: (center, radius).
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        if self.is_empty() {
            return (Vec3::ZERO, 0.0);
        }
        let c = self.center();
        (c, (self.max - c).length())
    }

    /// The parametric range (t0, t1) where the ray `o + t d` is inside the box, clipped to
    /// [0, t_max]; `None` if it misses.
    #[inline]
    pub fn intersect_ray(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let inv = d.recip();
        let t_a = (self.min - o) * inv;
        let t_b = (self.max - o) * inv;
        let near = t_a.min(t_b);
        let far = t_a.max(t_b);
        // NaN (0 * inf) components are ignored by max/min on f32 in the right direction.
        let t0 = near.max_element().max(0.0);
        let t1 = far.min_element().min(t_max);
        (t0 <= t1).then_some((t0, t1))
    }
}
