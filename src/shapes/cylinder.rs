//! Cylinders around the z axis, as pbrt-v4 defines them.

use std::f32::consts::PI;

use glam::{Affine3A, Vec2, Vec3};

use super::{
    ShapeSample, SurfaceDerivatives, SurfaceHit, swaps_handedness, transform_normal, transform_normal_unnormalized,
    uniform_scale, weingarten,
};
use crate::geometry::{Bounds3, Ray};

/// An open cylinder of the given radius between z_min and z_max.
#[derive(Clone, Debug)]
pub struct Cylinder {
    radius: f32,
    z_min: f32,
    z_max: f32,
    phi_max: f32,
    world_from_object: Affine3A,
    object_from_world: Affine3A,
    flip_normal: bool,
}

impl Cylinder {
    /// A cylinder with pbrt-v4's parameters (`phimax` in degrees).
    pub fn new(
        world_from_object: Affine3A,
        reverse_orientation: bool,
        radius: f32,
        z_min: f32,
        z_max: f32,
        phi_max_deg: f32,
    ) -> Cylinder {
        Cylinder {
            radius,
            z_min: z_min.min(z_max),
            z_max: z_min.max(z_max),
            phi_max: phi_max_deg.clamp(0.0, 360.0).to_radians(),
            world_from_object,
            object_from_world: world_from_object.inverse(),
            flip_normal: reverse_orientation ^ swaps_handedness(&world_from_object),
        }
    }

    /// World-space bounds.
    pub fn bounds(&self) -> Bounds3 {
        Bounds3::new(Vec3::new(-self.radius, -self.radius, self.z_min), Vec3::new(self.radius, self.radius, self.z_max))
            .transformed(&self.world_from_object)
    }

    /// Object-space area.
    pub fn area(&self) -> f32 {
        (self.z_max - self.z_min) * self.radius * self.phi_max
    }

    /// Nearest hit in (0, t_max): distance and object-space point.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let o = self.object_from_world.transform_point3(ray.o).as_dvec3();
        let d = self.object_from_world.transform_vector3(ray.d).as_dvec3();
        let r = self.radius as f64;
        let a = d.x * d.x + d.y * d.y;
        if a == 0.0 {
            return None;
        }
        let b = 2.0 * (d.x * o.x + d.y * o.y);
        let c = o.x * o.x + o.y * o.y - r * r;
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        let q = if b < 0.0 { -0.5 * (b - root) } else { -0.5 * (b + root) };
        let (mut t0, mut t1) = (q / a, c / q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        for t in [t0, t1] {
            if t <= 0.0 || t > t_max as f64 {
                continue;
            }
            let mut p = o + d * t;
            let hyp = (p.x * p.x + p.y * p.y).sqrt();
            p.x *= r / hyp;
            p.y *= r / hyp;
            if p.z < self.z_min as f64 || p.z > self.z_max as f64 {
                continue;
            }
            let p = p.as_vec3();
            if self.phi_max < 2.0 * PI && phi_of(p.x, p.y) > self.phi_max {
                continue;
            }
            return Some((t as f32, p));
        }
        None
    }

    /// Texture coordinates of world point `p` on the surface (an area light's alpha test at a
    /// sampled point).
    pub fn uv_at(&self, p: Vec3) -> Vec2 {
        self.hit(0.0, self.object_from_world.transform_point3(p)).uv
    }

    /// Surface details of a hit.
    pub fn hit(&self, t: f32, p_obj: Vec3) -> SurfaceHit {
        let phi = phi_of(p_obj.x, p_obj.y);
        let uv = Vec2::new(phi / self.phi_max, (p_obj.z - self.z_min) / (self.z_max - self.z_min));
        let dpdu = Vec3::new(-self.phi_max * p_obj.y, self.phi_max * p_obj.x, 0.0);
        let mut n = transform_normal(&self.object_from_world, Vec3::new(p_obj.x, p_obj.y, 0.0));
        if self.flip_normal {
            n = -n;
        }
        SurfaceHit {
            t,
            p: self.world_from_object.transform_point3(p_obj),
            n,
            ns: n,
            uv,
            dpdu: self.world_from_object.transform_vector3(dpdu),
            p_error: 0.0,
        }
    }

    /// ∂p/∂v and the normal's derivatives at a hit (pbrt-v4's
    /// `Cylinder::InteractionFromIntersection`: only ∂²p/∂u² is non-zero).
    pub fn derivatives(&self, hit: &SurfaceHit) -> SurfaceDerivatives {
        let p_obj = self.object_from_world.transform_point3(hit.p);
        let dpdu = Vec3::new(-self.phi_max * p_obj.y, self.phi_max * p_obj.x, 0.0);
        let dpdv = Vec3::new(0.0, 0.0, self.z_max - self.z_min);
        let d2pduu = -self.phi_max * self.phi_max * Vec3::new(p_obj.x, p_obj.y, 0.0);
        let (dndu, dndv) = weingarten(dpdu, dpdv, d2pduu, Vec3::ZERO, Vec3::ZERO);
        SurfaceDerivatives {
            dpdu: hit.dpdu,
            dpdv: self.world_from_object.transform_vector3(dpdv),
            dndu: transform_normal_unnormalized(&self.object_from_world, dndu),
            dndv: transform_normal_unnormalized(&self.object_from_world, dndv),
        }
    }

    /// Uniform area sample; `None` when the transform is not a similarity.
    pub fn sample_area(&self, u: Vec2) -> Option<ShapeSample> {
        let s = uniform_scale(&self.world_from_object)?;
        let z = self.z_min + u.x * (self.z_max - self.z_min);
        let phi = u.y * self.phi_max;
        let h = self.hit(0.0, Vec3::new(self.radius * phi.cos(), self.radius * phi.sin(), z));
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
