//! Cameras in pbrt-v4's conventions: raster (0, 0) is the top-left corner of the full image,
//! the field of view spans the shorter image axis, and camera space looks down +z with +y
//! up in a left-handed frame (so LookAt scenes come out exactly as pbrt-v4 frames them).

mod footprint;
mod realistic;
pub mod settings;

use std::sync::Arc;

use glam::{Affine3A, DMat4, Vec2, Vec3};

pub use footprint::{Differentials, Footprint};
pub use realistic::RealisticLens;

use crate::camera::settings::{CameraSettings, Projection};
use crate::geometry::{MotionTransform, Ray};
use crate::sampling::warp::concentric_disk;
use crate::sampling::warp::{equal_area_sphere_to_square, equal_area_square_to_sphere};

/// A camera that turns film positions into world-space rays.
#[derive(Clone, Debug)]
pub struct Camera {
    world_from_camera: Affine3A,
    /// Its inverse (of the start transform for a moving camera).
    camera_from_world: Affine3A,
    /// The camera's motion over the shutter interval, for animated camera transforms.
    motion: Option<MotionTransform>,
    shutter_open: f32,
    shutter_close: f32,
    /// Screen-space window [xmin, xmax] × [ymin, ymax].
    screen_min: Vec2,
    screen_max: Vec2,
    resolution: Vec2,
    perspective: bool,
    /// For a spherical camera, whether its mapping is equal-area (else equirectangular).
    spherical: Option<bool>,
    /// tan(fov / 2) for perspective cameras.
    tan_half_fov: f32,
    lens_radius: f32,
    focal_distance: f32,
    /// A realistic camera's lens system (its rays replace the projection above).
    realistic: Option<Arc<RealisticLens>>,
}

/// A camera ray and its weight (pbrt-v4's `CameraRay`): 1 but through a realistic camera's
/// lens, whose weight carries the cos⁴ falloff and the exit-pupil sampling density.
#[derive(Clone, Copy, Debug)]
pub struct CameraRay {
    /// The ray, in world space.
    pub ray: Ray,
    /// The factor on the radiance it brings back.
    pub weight: f32,
}

impl Camera {
    /// A camera for a film of `full_resolution` pixels whose diagonal is `diagonal_mm` (the
    /// film's `diagonal`, used by realistic cameras). Fails only for a realistic camera's lens
    /// that cannot be focused or lets no light through.
    pub fn new(
        settings: &CameraSettings,
        world_from_camera: &DMat4,
        full_resolution: [u32; 2],
        diagonal_mm: f32,
    ) -> crate::error::Result<Camera> {
        let res = Vec2::new(full_resolution[0] as f32, full_resolution[1] as f32);
        let frame = settings.frame_aspect_ratio.unwrap_or(res.x / res.y);
        let (screen_min, screen_max) = match settings.screen_window {
            Some([x0, x1, y0, y1]) => (Vec2::new(x0, y0), Vec2::new(x1, y1)),
            None if frame > 1.0 => (Vec2::new(-frame, -1.0), Vec2::new(frame, 1.0)),
            None => (Vec2::new(-1.0, -1.0 / frame), Vec2::new(1.0, 1.0 / frame)),
        };
        let (perspective, tan_half_fov) = match settings.projection {
            Projection::Perspective { fov } => (true, (fov.to_radians() / 2.0).tan()),
            Projection::Orthographic | Projection::Spherical { .. } | Projection::Realistic(_) => (false, 1.0),
        };
        let realistic = match &settings.projection {
            Projection::Realistic(r) => Some(RealisticLens::shared(r, full_resolution, diagonal_mm)?),
            _ => None,
        };
        let spherical = match settings.projection {
            Projection::Spherical { equal_area } => Some(equal_area),
            _ => None,
        };
        Ok(Camera {
            world_from_camera: Affine3A::from_mat4(world_from_camera.as_mat4()),
            camera_from_world: Affine3A::from_mat4(world_from_camera.as_mat4()).inverse(),
            motion: None,
            shutter_open: settings.shutter_open,
            shutter_close: settings.shutter_close,
            screen_min,
            screen_max,
            resolution: res,
            perspective,
            spherical,
            tan_half_fov,
            lens_radius: settings.lens_radius,
            focal_distance: settings.focal_distance,
            realistic,
        })
    }

    /// The camera moving with `motion` (its transform at each ray's time).
    pub fn with_motion(mut self, motion: MotionTransform) -> Camera {
        self.world_from_camera = motion.start();
        self.camera_from_world = self.world_from_camera.inverse();
        self.motion = Some(motion);
        self
    }

    /// True when the camera moves during the shutter interval.
    pub fn moves(&self) -> bool {
        self.motion.is_some()
    }

    /// True when [`Self::generate_ray`] reads its lens sample: a realistic camera's, or a
    /// thin lens (perspective and orthographic cameras with a lens radius).
    pub fn samples_lens(&self) -> bool {
        self.realistic.is_some() || (self.spherical.is_none() && self.lens_radius > 0.0)
    }

    /// The ray time for a camera sample's time `u` in [0, 1): pbrt-v4's lerp over the
    /// shutter interval.
    #[inline]
    pub fn time(&self, u: f32) -> f32 {
        self.shutter_open + u * (self.shutter_close - self.shutter_open)
    }

    /// World-from-camera at `time`.
    pub fn world_from_camera_at(&self, time: f32) -> Affine3A {
        match &self.motion {
            Some(m) => m.at(time),
            None => self.world_from_camera,
        }
    }

    /// Camera space from world space (at the start of its motion).
    pub fn camera_from_world(&self) -> Affine3A {
        self.camera_from_world
    }

    /// Camera position in world space (at the start of its motion).
    pub fn position(&self) -> Vec3 {
        self.world_from_camera.translation.into()
    }

    /// The ray through continuous raster position `p_film` (pixel (x, y) covers
    /// [x, x+1)×[y, y+1)), with `u_lens` sampling the lens, at time `time`; `None` when a
    /// realistic camera's lens stops it (the sample then brings back nothing, as in pbrt-v4).
    pub fn generate_ray(&self, p_film: Vec2, u_lens: Vec2, time: f32) -> Option<CameraRay> {
        if let Some(lens) = &self.realistic {
            let (o, d, weight) = lens.generate(p_film, self.resolution, u_lens)?;
            let w = self.world_from_camera_at(time);
            let ray = Ray::timed(w.transform_point3(o), w.transform_vector3(d).normalize(), time);
            return Some(CameraRay { ray, weight });
        }
        let ray = if let Some(equal_area) = self.spherical {
            self.spherical_ray(p_film, equal_area, time)
        } else {
            self.projective_ray(p_film, u_lens, time)
        };
        Some(CameraRay { ray, weight: 1.0 })
    }

    /// A perspective or orthographic camera's ray, through its thin lens if it has one.
    fn projective_ray(&self, p_film: Vec2, u_lens: Vec2, time: f32) -> Ray {
        // Raster → screen: x grows right, y grows down in raster space but up on screen.
        let sx = self.screen_min.x + p_film.x / self.resolution.x * (self.screen_max.x - self.screen_min.x);
        let sy = self.screen_max.y - p_film.y / self.resolution.y * (self.screen_max.y - self.screen_min.y);
        let (mut o, mut d) = if self.perspective {
            (Vec3::ZERO, Vec3::new(sx * self.tan_half_fov, sy * self.tan_half_fov, 1.0).normalize())
        } else {
            (Vec3::new(sx, sy, 0.0), Vec3::Z)
        };
        if self.lens_radius > 0.0 {
            let lens = self.lens_radius * concentric_disk(u_lens);
            let ft = self.focal_distance / d.z;
            let focus = o + d * ft;
            // The ray leaves from the lens point itself, as in pbrt-v4 for both projections:
            // an orthographic camera with a lens thus loses its film offset and sees the focus
            // plane in perspective from the lens (pbrt-v4's image, which scenes are made for).
            o = Vec3::new(lens.x, lens.y, 0.0);
            d = (focus - o).normalize();
        }
        let w = self.world_from_camera_at(time);
        Ray::timed(w.transform_point3(o), w.transform_vector3(d).normalize(), time)
    }
}

impl Camera {
    /// The unscaled differentials of `ray`, a ray this camera generated: the rays through the
    /// film positions one pixel over in x and in y with the same lens point and time, as
    /// pbrt-v4's perspective and orthographic cameras compute them. A projective ray determines
    /// its film position (and its lens point), so they follow from the ray alone. A spherical
    /// camera's are pbrt-v4's numerical ones (`CameraBase::GenerateRayDifferential`: the rays
    /// 0.05 pixel over, scaled up), its film position found from the direction; a realistic
    /// camera's too, its film position and pupil sample found by tracing the ray back
    /// through the lens (`None` where that fails or the lens stops both offset rays).
    pub fn differentials(&self, ray: &Ray) -> Option<Differentials> {
        if let Some(lens) = &self.realistic {
            return self.realistic_differentials(lens, ray);
        }
        let w = self.world_from_camera_at(ray.time);
        let c = if self.motion.is_some() { w.inverse() } else { self.camera_from_world };
        if let Some(equal_area) = self.spherical {
            return Some(self.spherical_differentials(ray, c.transform_vector3(ray.d).normalize(), equal_area));
        }
        let (o, d) = (c.transform_point3(ray.o), c.transform_vector3(ray.d));
        if d.z <= 0.0 {
            return None;
        }
        // One pixel's step on the film, in camera space (on the z = 1 plane for perspective).
        let k = if self.perspective { self.tan_half_fov } else { 1.0 };
        let step = [
            Vec3::new((self.screen_max.x - self.screen_min.x) / self.resolution.x * k, 0.0, 0.0),
            Vec3::new(0.0, -(self.screen_max.y - self.screen_min.y) / self.resolution.y * k, 0.0),
        ];
        let offset = |dx: Vec3| -> (Vec3, Vec3) {
            match (self.perspective, self.lens_radius > 0.0) {
                // The pinhole direction to the film point, one pixel over.
                (true, false) => (o, (d / d.z + dx).normalize()),
                // Through the same lens point to the focus-plane point of the next pixel.
                (true, true) => {
                    let focus = o + d * (self.focal_distance / d.z);
                    let dir = (focus / focus.z + dx).normalize();
                    (o, (dir * (self.focal_distance / dir.z) - o).normalize())
                }
                (false, false) => (o + dx, d),
                // The film point one pixel over, pushed to the focus plane by pbrt-v4's
                // focal distance over the lens ray's z (not the film ray's).
                (false, true) => {
                    let film = o + d * (self.focal_distance / d.z) - Vec3::new(0.0, 0.0, self.focal_distance);
                    (o, (film + dx + Vec3::new(0.0, 0.0, self.focal_distance / d.z) - o).normalize())
                }
            }
        };
        // A rotation (LookAt's) keeps unit directions unit: one square root less per ray.
        let unit = [w.matrix3.x_axis, w.matrix3.y_axis, w.matrix3.z_axis]
            .iter()
            .all(|a| (a.length_squared() - 1.0).abs() < 1e-5);
        let to_world = |(o, d): (Vec3, Vec3)| {
            let d = w.transform_vector3(d);
            (w.transform_point3(o), if unit { d } else { d.normalize() })
        };
        Some(Differentials { rx: to_world(offset(step[0])), ry: to_world(offset(step[1])) })
    }

    /// pbrt-v4's numerical differentials of a realistic camera's `ray`
    /// (`CameraBase::GenerateRayDifferential`): the rays through the film positions 0.05 pixel
    /// over (−0.05 where the lens stops that one) with the same exit-pupil sample, their
    /// offsets scaled up by 20. The film position and pupil sample are found by tracing the
    /// ray back through the lens; the offsets are taken from the ray regenerated from them,
    /// so that rounding in the back-trace does not enter the 20× scaling.
    fn realistic_differentials(&self, lens: &RealisticLens, ray: &Ray) -> Option<Differentials> {
        let w = self.world_from_camera_at(ray.time);
        let c = if self.motion.is_some() { w.inverse() } else { self.camera_from_world };
        let (p_film, u_lens) =
            lens.film_sample(c.transform_point3(ray.o), c.transform_vector3(ray.d), self.resolution)?;
        let world = |(o, d, _): (Vec3, Vec3, f32)| (w.transform_point3(o), w.transform_vector3(d).normalize());
        let centre = world(lens.generate(p_film, self.resolution, u_lens)?);
        let offset = |axis: Vec2| {
            [0.05f32, -0.05].into_iter().find_map(|eps| {
                let (o, d) = world(lens.generate(p_film + axis * eps, self.resolution, u_lens)?);
                Some((ray.o + (o - centre.0) / eps, ray.d + (d - centre.1) / eps))
            })
        };
        Some(Differentials { rx: offset(Vec2::X)?, ry: offset(Vec2::Y)? })
    }

    /// pbrt-v4's numerical differentials of a spherical camera's `ray`, whose camera-space
    /// direction is `d`.
    fn spherical_differentials(&self, ray: &Ray, d: Vec3, equal_area: bool) -> Differentials {
        // Undo the y/z swap, then the mapping.
        let m = Vec3::new(d.x, d.z, d.y);
        let uv = if equal_area {
            equal_area_sphere_to_square(m)
        } else {
            let phi = m.y.atan2(m.x).rem_euclid(2.0 * std::f32::consts::PI);
            Vec2::new(phi / (2.0 * std::f32::consts::PI), m.z.clamp(-1.0, 1.0).acos() / std::f32::consts::PI)
        };
        let p_film = uv * self.resolution;
        let offset = |axis: Vec2| {
            // pbrt-v4 tries +0.05 first and −0.05 where that fails; a spherical ray never fails.
            let eps = 0.05;
            let r = self.spherical_ray(p_film + axis * eps, equal_area, ray.time);
            (ray.o + (r.o - ray.o) / eps, ray.d + (r.d - ray.d) / eps)
        };
        Differentials { rx: offset(Vec2::X), ry: offset(Vec2::Y) }
    }

    /// pbrt-v4's `SphericalCamera::GenerateRay`: the film is a map of all directions (no lens,
    /// no screen window), then y and z swap so that the map's pole is camera +y.
    fn spherical_ray(&self, p_film: Vec2, equal_area: bool, time: f32) -> Ray {
        let uv = p_film / self.resolution;
        let d = if equal_area {
            equal_area_square_to_sphere(wrap_equal_area_square(uv))
        } else {
            let (theta, phi) = (std::f32::consts::PI * uv.y, 2.0 * std::f32::consts::PI * uv.x);
            Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
        };
        let d = Vec3::new(d.x, d.z, d.y);
        let w = self.world_from_camera_at(time);
        Ray::timed(w.transform_point3(Vec3::ZERO), w.transform_vector3(d).normalize(), time)
    }
}

/// pbrt-v4's `WrapEqualAreaSquare`: points just outside the square (a filter's reach past the
/// film's edge) mirror back into it as the octahedral map's edges meet.
fn wrap_equal_area_square(mut uv: Vec2) -> Vec2 {
    if uv.x < 0.0 {
        uv = Vec2::new(-uv.x, 1.0 - uv.y);
    } else if uv.x > 1.0 {
        uv = Vec2::new(2.0 - uv.x, 1.0 - uv.y);
    }
    if uv.y < 0.0 {
        uv = Vec2::new(1.0 - uv.x, -uv.y);
    } else if uv.y > 1.0 {
        uv = Vec2::new(1.0 - uv.x, 2.0 - uv.y);
    }
    uv
}

#[cfg(test)]
mod tests {
    use super::*;
    use nimbus_parser::transform::look_at;

    fn settings(fov: f32) -> CameraSettings {
        CameraSettings::perspective(fov)
    }

    #[test]
    fn spherical_cameras_map_the_film_to_every_direction() {
        let look = look_at([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]).unwrap().inverse();
        let spherical =
            |equal_area| CameraSettings { projection: Projection::Spherical { equal_area }, ..settings(90.0) };
        // Equirectangular: the top row looks up (camera +y), the bottom down, the centre along
        // camera −x (φ = π), a quarter across along camera +z (φ = π/2).
        let cam = Camera::new(&spherical(false), &look, [64, 32], 35.0).unwrap();
        let d = |x: f32, y: f32| cam.generate_ray(Vec2::new(x, y), Vec2::ZERO, 0.0).unwrap().ray.d;
        assert!((d(32.0, 0.0) - Vec3::Y).length() < 1e-5, "{:?}", d(32.0, 0.0));
        assert!((d(32.0, 32.0) + Vec3::Y).length() < 1e-5);
        assert!((d(32.0, 16.0) + Vec3::X).length() < 1e-5, "{:?}", d(32.0, 16.0));
        assert!((d(16.0, 16.0) - Vec3::Z).length() < 1e-5, "{:?}", d(16.0, 16.0));
        // Equal-area: the centre of the square is the pole (up), its corners the other pole.
        let cam = Camera::new(&spherical(true), &look, [32, 32], 35.0).unwrap();
        let d = |x: f32, y: f32| cam.generate_ray(Vec2::new(x, y), Vec2::ZERO, 0.0).unwrap().ray.d;
        assert!((d(16.0, 16.0) - Vec3::Y).length() < 1e-5, "{:?}", d(16.0, 16.0));
        assert!((d(0.0, 0.0) + Vec3::Y).length() < 1e-5, "{:?}", d(0.0, 0.0));
        // A filter's reach past the edge wraps back onto the sphere continuously.
        assert!((d(-0.01, 8.0) - d(0.01, 24.0)).length() < 0.01);
    }

    #[test]
    fn center_ray_looks_at_the_target_and_fov_spans_the_short_axis() {
        let cam_from_world = look_at([0.0, 1.0, 3.4], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]).unwrap();
        let cam = Camera::new(&settings(90.0), &cam_from_world.inverse(), [200, 100], 35.0).unwrap();
        let r = cam.generate_ray(Vec2::new(100.0, 50.0), Vec2::ZERO, 0.0).unwrap().ray;
        assert!((r.o - Vec3::new(0.0, 1.0, 3.4)).length() < 1e-5);
        assert!((r.d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5);
        // Top edge at the centre column: 45° up (fov 90 on the shorter, vertical axis).
        let top = cam.generate_ray(Vec2::new(100.0, 0.0), Vec2::ZERO, 0.0).unwrap().ray;
        assert!((top.d.y - (0.5f32).sqrt()).abs() < 1e-4, "{:?}", top.d);
        // pbrt-v4's left-handed camera: raster +x goes towards world -x for this LookAt.
        let right = cam.generate_ray(Vec2::new(200.0, 50.0), Vec2::ZERO, 0.0).unwrap().ray;
        assert!(right.d.x < -0.5, "{:?}", right.d);
    }

    #[test]
    fn thin_lens_rays_leave_from_the_lens_point_as_in_pbrt() {
        // pbrt-v4 sets a lens ray's origin to the lens sample for both projections, so an
        // orthographic camera with a lens looks at its focus plane in perspective from the
        // lens: a film corner's ray leaves from within the lens radius of the camera origin
        // and still reaches the corner of the screen window at the focal distance.
        let cam_from_world = look_at([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]).unwrap();
        let ortho = CameraSettings {
            projection: Projection::Orthographic,
            lens_radius: 0.1,
            focal_distance: 5.0,
            screen_window: Some([-2.0, 2.0, -1.0, 1.0]),
            ..settings(90.0)
        };
        let cam = Camera::new(&ortho, &cam_from_world.inverse(), [40, 20], 35.0).unwrap();
        for u in [Vec2::new(0.5, 0.5), Vec2::new(0.9, 0.2), Vec2::new(0.1, 0.7)] {
            let r = cam.generate_ray(Vec2::ZERO, u, 0.0).unwrap().ray;
            assert!(r.o.z.abs() < 1e-6 && r.o.truncate().length() <= 0.1 + 1e-6, "{:?}", r.o);
            let focus = r.o + r.d * ((5.0 - r.o.z) / r.d.z);
            // Raster (0, 0) is the screen window's top left, camera (−2, 1): world (−2, 1) here.
            assert!((focus - Vec3::new(-2.0, 1.0, 5.0)).length() < 1e-4, "{focus:?}");
        }
    }
}
