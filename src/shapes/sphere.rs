//! Spheres (possibly clipped in z and φ), as pbrt-v4 defines them.

use std::f32::consts::PI;

use glam::{Affine3A, DVec3, Vec2, Vec3};

use super::{
    ShapeSample, SurfaceDerivatives, SurfaceHit, swaps_handedness, transform_normal, transform_normal_unnormalized,
    uniform_scale, weingarten,
};
use crate::geometry::{Bounds3, Ray};
use crate::math::Frame;
use crate::sampling::warp;

/// A sphere centred at the object-space origin.
#[derive(Clone, Debug)]
pub struct Sphere {
    radius: f32,
    z_min: f32,
    z_max: f32,
    theta_z_min: f32,
    theta_z_max: f32,
    phi_max: f32,
    world_from_object: Affine3A,
    object_from_world: Affine3A,
    flip_normal: bool,
}

impl Sphere {
    /// A sphere with pbrt-v4's parameters (`phimax` in degrees).
    pub fn new(
        world_from_object: Affine3A,
        reverse_orientation: bool,
        radius: f32,
        z_min: f32,
        z_max: f32,
        phi_max_deg: f32,
    ) -> Sphere {
        let zmin = z_min.min(z_max).clamp(-radius, radius);
        let zmax = z_min.max(z_max).clamp(-radius, radius);
        Sphere {
            radius,
            z_min: zmin,
            z_max: zmax,
            theta_z_min: (zmin / radius).clamp(-1.0, 1.0).acos(),
            theta_z_max: (zmax / radius).clamp(-1.0, 1.0).acos(),
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

    /// For a full sphere, a world-space ball that holds it: centre and radius.
    pub fn ball(&self) -> Option<(Vec3, f32)> {
        let m = &self.world_from_object.matrix3;
        let stretch = m.x_axis.length().max(m.y_axis.length()).max(m.z_axis.length());
        self.is_full().then(|| (self.world_from_object.translation.into(), self.radius * stretch))
    }

    /// Whether world point `p` lies strictly inside the (full) sphere.
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        self.object_from_world.transform_point3(p).length_squared() < self.radius * self.radius
    }

    fn is_full(&self) -> bool {
        self.z_min <= -self.radius && self.z_max >= self.radius && self.phi_max >= 2.0 * PI
    }

    /// Surface area (in object space, as pbrt-v4 computes it).
    pub fn area(&self) -> f32 {
        self.phi_max * self.radius * (self.z_max - self.z_min)
    }

    /// Nearest hit in (0, t_max): distance and object-space point.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let o = self.object_from_world.transform_point3(ray.o).as_dvec3();
        let d = self.object_from_world.transform_vector3(ray.d).as_dvec3();
        let r = self.radius as f64;
        // Solve |o + t d|^2 = r^2 in double precision (a robust form of pbrt-v4's interval
        // arithmetic quadratic).
        let a = d.length_squared();
        let b = 2.0 * d.dot(o);
        let c = o.length_squared() - r * r;
        if c > 0.0 && b > 0.0 {
            // Outside and moving away: both roots are negative (their product c/a is
            // positive, their sum −b/a negative), so the test below would find none either.
            // Every ray that has just left a medium's sphere bound (shadow rays through the
            // Disney cloud's) asks this.
            return None;
        }
        // c = |o|^2 - r^2 computed as the distance to the closest point on the line, which
        // avoids cancellation for far-away origins.
        let v = o - b / (2.0 * a) * d;
        let disc = 4.0 * a * (r * r - v.length_squared());
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        let q = if b < 0.0 { -0.5 * (b - root) } else { -0.5 * (b + root) };
        let (mut t0, mut t1) = (q / a, c / q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        let tmax = t_max as f64;
        if t0 > tmax || t1 <= 0.0 {
            return None;
        }
        for t in [t0, t1] {
            if t <= 0.0 || t > tmax {
                continue;
            }
            let mut p = o + d * t;
            p *= r / p.length();
            if p.x == 0.0 && p.y == 0.0 {
                p.x = 1e-5 * r;
            }
            if self.clipped(p) {
                continue;
            }
            return Some((t as f32, p.as_vec3()));
        }
        None
    }

    fn clipped(&self, p: DVec3) -> bool {
        let r = self.radius as f64;
        if (self.z_min as f64 > -r && p.z < self.z_min as f64) || ((self.z_max as f64) < r && p.z > self.z_max as f64) {
            return true;
        }
        self.phi_max < 2.0 * PI && phi_of(p.x as f32, p.y as f32) > self.phi_max
    }

    /// Texture coordinates of world point `p` on the surface (an area light's alpha test at a
    /// sampled point).
    pub fn uv_at(&self, p: Vec3) -> Vec2 {
        self.hit(0.0, self.object_from_world.transform_point3(p)).uv
    }

    /// Surface details of a hit found by [`Sphere::intersect`].
    pub fn hit(&self, t: f32, p_obj: Vec3) -> SurfaceHit {
        let phi = phi_of(p_obj.x, p_obj.y);
        let cos_theta = (p_obj.z / self.radius).clamp(-1.0, 1.0);
        let theta = cos_theta.acos();
        let uv = Vec2::new(phi / self.phi_max, (theta - self.theta_z_min) / (self.theta_z_max - self.theta_z_min));
        let dpdu_obj = Vec3::new(-self.phi_max * p_obj.y, self.phi_max * p_obj.x, 0.0);
        let mut n = transform_normal(&self.object_from_world, p_obj);
        if self.flip_normal {
            n = -n;
        }
        let p = self.world_from_object.transform_point3(p_obj);
        SurfaceHit { t, p, n, ns: n, uv, dpdu: self.world_from_object.transform_vector3(dpdu_obj), p_error: 0.0 }
    }

    /// ∂p/∂v and the normal's derivatives at a hit (pbrt-v4's
    /// `Sphere::InteractionFromIntersection`: the Weingarten equations).
    pub fn derivatives(&self, hit: &SurfaceHit) -> SurfaceDerivatives {
        let p_obj = self.object_from_world.transform_point3(hit.p);
        let cos_theta = (p_obj.z / self.radius).clamp(-1.0, 1.0);
        let dpdu_obj = Vec3::new(-self.phi_max * p_obj.y, self.phi_max * p_obj.x, 0.0);
        let z_radius = (p_obj.x * p_obj.x + p_obj.y * p_obj.y).sqrt();
        let (cos_phi, sin_phi) = if z_radius > 0.0 { (p_obj.x / z_radius, p_obj.y / z_radius) } else { (1.0, 0.0) };
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let dtheta = self.theta_z_max - self.theta_z_min;
        let dpdv_obj = dtheta * Vec3::new(p_obj.z * cos_phi, p_obj.z * sin_phi, -self.radius * sin_theta);
        let d2pduu = -self.phi_max * self.phi_max * Vec3::new(p_obj.x, p_obj.y, 0.0);
        let d2pduv = dtheta * p_obj.z * self.phi_max * Vec3::new(-sin_phi, cos_phi, 0.0);
        let d2pdvv = -dtheta * dtheta * p_obj;
        let (dndu, dndv) = weingarten(dpdu_obj, dpdv_obj, d2pduu, d2pduv, d2pdvv);
        SurfaceDerivatives {
            dpdu: hit.dpdu,
            dpdv: self.world_from_object.transform_vector3(dpdv_obj),
            dndu: transform_normal_unnormalized(&self.object_from_world, dndu),
            dndv: transform_normal_unnormalized(&self.object_from_world, dndv),
        }
    }

    /// Samples a point on the sphere as seen from `reference`: uniformly within the cone of
    /// directions it subtends (full, uniformly scaled spheres; pbrt-v4's Sphere::Sample), or
    /// uniformly by area otherwise.
    pub fn sample(&self, reference: Vec3, u: Vec2) -> Option<ShapeSample> {
        let center = self.world_from_object.transform_point3(Vec3::ZERO);
        let scale = uniform_scale(&self.world_from_object);
        if let (true, Some(s)) = (self.is_full(), scale) {
            let radius = self.radius * s;
            let dc2 = reference.distance_squared(center);
            if dc2 > radius * radius * 1.0001 {
                let dc = dc2.sqrt();
                let sin2_max = radius * radius / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                let one_minus_cos_max = 1.0 - cos_max;
                // Small cones lose precision in 1 - cos; use a Taylor expansion (pbrt-v4).
                let (cos_t, sin2_t, one_minus_cos_max) = if sin2_max < 0.00068523 {
                    let sin2_t = sin2_max * u.x;
                    ((1.0 - sin2_t).sqrt(), sin2_t, sin2_max / 2.0)
                } else {
                    let cos_t = (cos_max - 1.0) * u.x + 1.0;
                    (cos_t, (1.0 - cos_t * cos_t).max(0.0), one_minus_cos_max)
                };
                // Angle at the sphere's centre between the reference direction and the point.
                let sin_max = sin2_max.sqrt();
                let cos_alpha = sin2_t / sin_max + cos_t * (1.0 - sin2_t / sin2_max).max(0.0).sqrt();
                let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
                let phi = u.y * 2.0 * PI;
                let w_c = (center - reference) / dc;
                let frame = Frame::from_z(-w_c);
                let n_local = Vec3::new(sin_alpha * phi.cos(), sin_alpha * phi.sin(), cos_alpha);
                let n_out = frame.to_world(n_local);
                let p = center + radius * n_out;
                let n = if self.flip_normal { -n_out } else { n_out };
                return Some(ShapeSample { p, n, pdf: 1.0 / (2.0 * PI * one_minus_cos_max), solid_angle: true });
            }
        }
        self.sample_area(u).map(|mut s| {
            s.solid_angle = false;
            s
        })
    }

    /// Density of [`Sphere::sample`] for the direction `wi` from `reference` hitting the
    /// sphere at `hit` (per solid angle).
    pub fn pdf(&self, reference: Vec3, wi: Vec3, hit: &SurfaceHit) -> f32 {
        let center = self.world_from_object.transform_point3(Vec3::ZERO);
        if let (true, Some(s)) = (self.is_full(), uniform_scale(&self.world_from_object)) {
            let radius = self.radius * s;
            let dc2 = reference.distance_squared(center);
            if dc2 > radius * radius * 1.0001 {
                let sin2_max = radius * radius / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                let one_minus = if sin2_max < 0.00068523 { sin2_max / 2.0 } else { 1.0 - cos_max };
                return 1.0 / (2.0 * PI * one_minus);
            }
        }
        area_to_solid_angle(1.0 / self.world_area(), reference, wi, hit)
    }

    fn world_area(&self) -> f32 {
        let s = uniform_scale(&self.world_from_object).unwrap_or(1.0);
        self.area() * s * s
    }

    /// A point uniform in area on the (clipped) sphere, density per unit area.
    pub fn sample_area(&self, u: Vec2) -> Option<ShapeSample> {
        // Uniform on the full sphere, rejected against the clipping (rarely used: partial
        // sphere lights).
        for i in 0..16 {
            let uu = if i == 0 {
                u
            } else {
                Vec2::new((u.x + 0.618_034 * i as f32).fract(), (u.y + 0.754_877_7 * i as f32).fract())
            };
            let p_obj = self.radius * warp::uniform_sphere(uu);
            if self.clipped(p_obj.as_dvec3()) {
                continue;
            }
            let hit = self.hit(0.0, p_obj);
            return Some(ShapeSample { p: hit.p, n: hit.n, pdf: 1.0 / self.world_area(), solid_angle: false });
        }
        None
    }
}

/// Converts an area density at a hit into a solid-angle density seen from `reference`.
#[inline]
pub fn area_to_solid_angle(pdf_area: f32, reference: Vec3, wi: Vec3, hit: &SurfaceHit) -> f32 {
    let d2 = reference.distance_squared(hit.p);
    let cos = hit.n.dot(wi).abs();
    if cos == 0.0 { 0.0 } else { pdf_area * d2 / cos }
}

#[inline]
fn phi_of(x: f32, y: f32) -> f32 {
    let phi = y.atan2(x);
    if phi < 0.0 { phi + 2.0 * PI } else { phi }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_sphere_hits_and_normals() {
        let s = Sphere::new(Affine3A::from_translation(Vec3::new(0.0, 0.0, 5.0)), false, 1.0, -1.0, 1.0, 360.0);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        let (t, p) = s.intersect(&ray, f32::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-5);
        let h = s.hit(t, p);
        assert!((h.n - (-Vec3::Z)).length() < 1e-4, "outward normal faces the ray origin: {:?}", h.n);
        assert!(s.intersect(&ray, 3.9).is_none());
        // From inside, the far side.
        let inside = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
        let (t, _) = s.intersect(&inside, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-5);
        let rev = Sphere::new(Affine3A::IDENTITY, true, 1.0, -1.0, 1.0, 360.0);
        let (t, p) = rev.intersect(&Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::Z), f32::INFINITY).unwrap();
        assert!((rev.hit(t, p).n - Vec3::Z).length() < 1e-4, "ReverseOrientation points inward");
    }

    #[test]
    fn clipped_sphere_misses_the_clipped_cap() {
        let s = Sphere::new(Affine3A::IDENTITY, false, 1.0, -1.0, 0.5, 360.0);
        let (t, _) = s.intersect(&Ray::new(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z), f32::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-4, "enters through the open top, hits the bottom: {t}");
    }

    #[test]
    fn cone_sampling_pdf_matches_sample() {
        let s = Sphere::new(Affine3A::from_translation(Vec3::new(0.0, 3.0, 0.0)), false, 0.5, -0.5, 0.5, 360.0);
        let r = Vec3::ZERO;
        let smp = s.sample(r, Vec2::new(0.3, 0.7)).unwrap();
        assert!(smp.solid_angle);
        assert!((smp.p.distance(Vec3::new(0.0, 3.0, 0.0)) - 0.5).abs() < 1e-4);
        let wi = (smp.p - r).normalize();
        let (t, p) = s.intersect(&Ray::new(r, wi), f32::INFINITY).unwrap();
        let h = s.hit(t, p);
        assert!((s.pdf(r, wi, &h) - smp.pdf).abs() < 1e-3 * smp.pdf);
        // Solid angle of the cone: 2π(1 - cos θmax).
        let cos_max = (1.0f32 - 0.25 / 9.0).sqrt();
        assert!((smp.pdf - 1.0 / (2.0 * PI * (1.0 - cos_max))).abs() < 1e-2 * smp.pdf);
    }
}
