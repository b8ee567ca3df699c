//! Disks and annuli in the plane z = height, as pbrt-v4 defines them.

use std::f32::consts::PI;

use glam::{Affine3A, Vec2, Vec3};

use super::{ShapeSample, SurfaceDerivatives, SurfaceHit, swaps_handedness, transform_normal, uniform_scale};
use crate::geometry::{Bounds3, Ray};

/// A disk (or annulus, or sector) facing +z.
#[derive(Clone, Debug)]
pub struct Disk {
    height: f32,
    radius: f32,
    inner_radius: f32,
    phi_max: f32,
    world_from_object: Affine3A,
    object_from_world: Affine3A,
    flip_normal: bool,
}

impl Disk {
    /// A disk with pbrt-v4's parameters (`phimax` in degrees).
    pub fn new(
        world_from_object: Affine3A,
        reverse_orientation: bool,
        height: f32,
        radius: f32,
        inner_radius: f32,
        phi_max_deg: f32,
    ) -> Disk {
        Disk {
            height,
            radius,
            inner_radius,
            phi_max: phi_max_deg.clamp(0.0, 360.0).to_radians(),
            world_from_object,
            object_from_world: world_from_object.inverse(),
            flip_normal: reverse_orientation ^ swaps_handedness(&world_from_object),
        }
    }

    /// World-space bounds.
    pub fn bounds(&self) -> Bounds3 {
        Bounds3::new(
            Vec3::new(-self.radius, -self.radius, self.height),
            Vec3::new(self.radius, self.radius, self.height),
        )
        .transformed(&self.world_from_object)
    }

    /// Object-space area.
    pub fn area(&self) -> f32 {
        self.phi_max * 0.5 * (self.radius * self.radius - self.inner_radius * self.inner_radius)
    }

    /// Nearest hit in (0, t_max): distance and object-space point.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let o = self.object_from_world.transform_point3(ray.o);
        let d = self.object_from_world.transform_vector3(ray.d);
        if d.z == 0.0 {
            return None;
        }
        let t = (self.height - o.z) / d.z;
        if t <= 0.0 || t >= t_max {
            return None;
        }
        let p = o + d * t;
        let dist2 = p.x * p.x + p.y * p.y;
        if dist2 > self.radius * self.radius || dist2 < self.inner_radius * self.inner_radius {
            return None;
        }
        if self.phi_max < 2.0 * PI && phi_of(p.x, p.y) > self.phi_max {
            return None;
        }
        Some((t, Vec3::new(p.x, p.y, self.height)))
    }

    /// Texture coordinates of world point `p` on the surface (an area light's alpha test at a
    /// sampled point).
    pub fn uv_at(&self, p: Vec3) -> Vec2 {
        self.hit(0.0, self.object_from_world.transform_point3(p)).uv
    }

    /// Surface details of a hit.
    pub fn hit(&self, t: f32, p_obj: Vec3) -> SurfaceHit {
        let phi = phi_of(p_obj.x, p_obj.y);
        let r = (p_obj.x * p_obj.x + p_obj.y * p_obj.y).sqrt();
        let uv = Vec2::new(phi / self.phi_max, (self.radius - r) / (self.radius - self.inner_radius));
        let dpdu = Vec3::new(-self.phi_max * p_obj.y, self.phi_max * p_obj.x, 0.0);
        let mut n = transform_normal(&self.object_from_world, Vec3::Z);
        if self.flip_normal {
            n = -n;
        }
        let dpdu = self.world_from_object.transform_vector3(dpdu);
        SurfaceHit { t, p: self.world_from_object.transform_point3(p_obj), n, ns: n, uv, dpdu, p_error: 0.0 }
    }

    /// ∂p/∂v at a hit (pbrt-v4's Disk: it points inwards; a plane does not bend, ∂n = 0).
    pub fn derivatives(&self, hit: &SurfaceHit) -> SurfaceDerivatives {
        let p_obj = self.object_from_world.transform_point3(hit.p);
        let r = (p_obj.x * p_obj.x + p_obj.y * p_obj.y).sqrt();
        let dpdv = if r > 0.0 {
            Vec3::new(p_obj.x, p_obj.y, 0.0) * ((self.inner_radius - self.radius) / r)
        } else {
            Vec3::ZERO
        };
        SurfaceDerivatives {
            dpdu: hit.dpdu,
            dpdv: self.world_from_object.transform_vector3(dpdv),
            dndu: Vec3::ZERO,
            dndv: Vec3::ZERO,
        }
    }

    /// Uniform area sample (pdf per world-space area). `None` when the transform is not a
    /// similarity (area would not be known).
    pub fn sample_area(&self, u: Vec2) -> Option<ShapeSample> {
        let s = uniform_scale(&self.world_from_object)?;
        // Uniform in area over the annular sector: r² uniform between the radii.
        let r = (self.inner_radius * self.inner_radius
            + u.x * (self.radius * self.radius - self.inner_radius * self.inner_radius))
            .sqrt();
        let phi = u.y * self.phi_max;
        let p_obj = Vec3::new(r * phi.cos(), r * phi.sin(), self.height);
        let h = self.hit(0.0, p_obj);
        Some(ShapeSample { p: h.p, n: h.n, pdf: 1.0 / (self.area() * s * s), solid_angle: false })
    }

    /// World-space area, if the transform is a similarity.
    pub fn world_area(&self) -> Option<f32> {
        uniform_scale(&self.world_from_object).map(|s| self.area() * s * s)
    }
}

#[inline]
fn phi_of(x: f32, y: f32) -> f32 {
    let phi = y.atan2(x);
    if phi < 0.0 { phi + 2.0 * PI } else { phi }
}
