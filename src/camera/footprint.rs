//! The screen-space footprint of a shading point: pbrt-v4's `Approximate_dp_dxy`, which
//! its textures use to filter (procedural noise sums only the octaves a pixel can show, a 3D
//! checkerboard blurs its edges over the footprint).
//!
//! pbrt-v4 finds, once per camera, the smallest change of a camera ray's origin and direction
//! between neighbouring pixels (`FindMinimumDifferentials`, over 512 film positions along the
//! diagonal), and at every surface point intersects rays offset by those changes with the
//! tangent plane. Where a path still carries ray differentials — the camera ray's own, up to
//! its first hit, and reflected or refracted ones after perfectly specular bounces — it
//! intersects those instead ([`Differentials`]), as nimbus does for perspective and
//! orthographic cameras and, numerically as pbrt-v4, spherical and realistic ones.

use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::Camera;
use crate::geometry::Ray;

/// A camera's smallest per-pixel ray differentials and the sample-count scale.
#[derive(Clone, Debug)]
pub struct Footprint {
    world_from_camera: Affine3A,
    camera_from_world: Affine3A,
    min_pos: [Vec3; 2],
    min_dir: [Vec3; 2],
    /// pbrt-v4's max(1/8, 1/√spp): more samples per pixel, smaller footprints.
    spp_scale: f32,
}

impl Footprint {
    /// The footprint model of `camera` rendering `spp` samples per pixel of a film of
    /// `resolution` pixels.
    pub fn new(camera: &Camera, resolution: [u32; 2], spp: u32) -> Footprint {
        let world_from_camera = camera.world_from_camera_at(0.5);
        let camera_from_world = world_from_camera.inverse();
        let mut min_pos = [Vec3::splat(f32::INFINITY); 2];
        let mut min_dir = [Vec3::splat(f32::INFINITY); 2];
        let n = 512;
        let lens = Vec2::splat(0.5);
        for i in 0..n {
            let t = i as f32 / (n - 1) as f32;
            let p = Vec2::new(t * resolution[0] as f32, t * resolution[1] as f32);
            let Some(ray) = camera.generate_ray(p, lens, 0.5) else { continue };
            let (o, d) =
                (camera_from_world.transform_point3(ray.ray.o), camera_from_world.transform_vector3(ray.ray.d));
            let d = d.normalize();
            // The ray direction's local frame, pbrt-v4's `Frame::FromZ` (the differentials'
            // orientation in it is part of pbrt-v4's answer on tilted surfaces).
            let (fx, fy) = coordinate_system(d);
            let to_local = |v: Vec3| Vec3::new(v.dot(fx), v.dot(fy), v.dot(d));
            for (k, offset) in [Vec2::X, Vec2::Y].into_iter().enumerate() {
                let Some(r) = camera.generate_ray(p + offset, lens, 0.5) else { continue };
                let (ro, rd) =
                    (camera_from_world.transform_point3(r.ray.o), camera_from_world.transform_vector3(r.ray.d));
                let dox = ro - o;
                if dox.length() < min_pos[k].length() {
                    min_pos[k] = dox;
                }
                let ddf = to_local(rd.normalize()) - Vec3::Z;
                if ddf.length() < min_dir[k].length() {
                    min_dir[k] = ddf;
                }
            }
        }
        for v in min_pos.iter_mut().chain(min_dir.iter_mut()) {
            if !v.is_finite() {
                *v = Vec3::ZERO;
            }
        }
        let spp_scale = (1.0 / (spp.max(1) as f32).sqrt()).max(0.125);
        Footprint { world_from_camera, camera_from_world, min_pos, min_dir, spp_scale }
    }

    /// The differentials of camera ray `ray` from `camera` (whose footprint this is), scaled
    /// by max(1/8, 1/√spp) as pbrt-v4 scales them; `None` where the camera cannot give them
    /// (a realistic camera's ray its lens would not trace back).
    pub fn camera_differentials(&self, camera: &Camera, ray: &Ray) -> Option<Differentials> {
        let d = camera.differentials(ray)?;
        let s = self.spp_scale;
        let scale = |(o, dir): (Vec3, Vec3)| (ray.o + (o - ray.o) * s, ray.d + (dir - ray.d) * s);
        Some(Differentials { rx: scale(d.rx), ry: scale(d.ry) })
    }

    /// (∂p/∂x, ∂p/∂y) at world point `p` with normal `n`: where rays offset by the smallest
    /// differentials meet the tangent plane, relative to `p` (pbrt-v4's `Approximate_dp_dxy`).
    pub fn dp_dxy(&self, p: Vec3, n: Vec3) -> (Vec3, Vec3) {
        let p_camera = self.camera_from_world.transform_point3(p);
        let n_camera = self.camera_from_world.transform_vector3(n);
        let Some(dir) = p_camera.try_normalize() else { return (Vec3::ZERO, Vec3::ZERO) };
        let down_z = rotate_from_to(dir, Vec3::Z);
        let p_down = down_z * p_camera;
        let n_down = down_z * n_camera;
        let d = n_down.z * p_down.z;
        let hit = |o: Vec3, dir: Vec3| {
            let t = -(n_down.dot(o) - d) / n_down.dot(dir);
            let q = o + t * dir;
            if q.is_finite() { down_z.transpose() * (q - p_down) } else { Vec3::ZERO }
        };
        let dx = hit(self.min_pos[0], Vec3::Z + self.min_dir[0]);
        let dy = hit(self.min_pos[1], Vec3::Z + self.min_dir[1]);
        (
            self.spp_scale * self.world_from_camera.transform_vector3(dx),
            self.spp_scale * self.world_from_camera.transform_vector3(dy),
        )
    }
}

/// A ray's differentials (pbrt-v4's `RayDifferential`): the rays through the neighbouring
/// pixels in x and y, scaled by the footprint's sample-count factor, as lines (a path crossing
/// an `interface` keeps them unchanged).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Differentials {
    /// Origin and direction of the ray one pixel over in x.
    pub rx: (Vec3, Vec3),
    /// Origin and direction of the ray one pixel over in y.
    pub ry: (Vec3, Vec3),
}

impl Differentials {
    /// (∂p/∂x, ∂p/∂y) at `p` with geometric normal `n`: where the offset rays meet the tangent
    /// plane, relative to `p` (pbrt-v4's `ComputeDifferentials`); `None` when one of them runs
    /// parallel to it.
    pub fn dp_dxy(&self, p: Vec3, n: Vec3) -> Option<(Vec3, Vec3)> {
        let d = n.dot(p);
        let meet = |(o, dir): (Vec3, Vec3)| {
            let nd = n.dot(dir);
            (nd != 0.0).then(|| o + (d - n.dot(o)) / nd * dir - p).filter(|v| v.is_finite())
        };
        Some((meet(self.rx)?, meet(self.ry)?))
    }

    /// The differentials of the ray leaving `p` along `wi` after a perfectly specular
    /// reflection (`eta` = None) or transmission (relative index `eta`) of the ray that
    /// arrived along −`wo` with these differentials: pbrt-v4's `SurfaceInteraction::SpawnRay`
    /// for specular flags, with the hit's footprint (`dpdx`, `dpdy`) and the change of its
    /// shading normal `ns` across the footprint (`dndx`, `dndy`). `None` where pbrt-v4 drops
    /// them (beyond 10⁸). Refraction follows pbrt-v4's formula term for term, whose change of
    /// direction along the surface is η times the incoming one where Snell's law's derivative
    /// gives 1/η (pbrt-v3 had the inverse index there): textures seen through glass filter
    /// over η² times the footprint, as in pbrt-v4's images.
    #[allow(clippy::too_many_arguments)] // pbrt-v4's formula reads all of them
    pub fn specular(
        &self,
        p: Vec3,
        (dpdx, dpdy): (Vec3, Vec3),
        ns: Vec3,
        (dndx, dndy): (Vec3, Vec3),
        wo: Vec3,
        wi: Vec3,
        eta: Option<f32>,
    ) -> Option<Differentials> {
        let dwodx = -self.rx.1 - wo;
        let dwody = -self.ry.1 - wo;
        let (rx_d, ry_d) = match eta {
            None => {
                let dx = dwodx.dot(ns) + wo.dot(dndx);
                let dy = dwody.dot(ns) + wo.dot(dndy);
                (wi - dwodx + 2.0 * (wo.dot(ns) * dndx + dx * ns), wi - dwody + 2.0 * (wo.dot(ns) * dndy + dy * ns))
            }
            Some(eta) => {
                // The normal on wo's side.
                let (n, dndx, dndy) = if wo.dot(ns) < 0.0 { (-ns, -dndx, -dndy) } else { (ns, dndx, dndy) };
                let dx = dwodx.dot(n) + wo.dot(dndx);
                let dy = dwody.dot(n) + wo.dot(dndy);
                let mu = wo.dot(n) / eta - wi.dot(n).abs();
                let k = 1.0 / eta + 1.0 / (eta * eta) * wo.dot(n) / wi.dot(n);
                (wi - eta * dwodx + (mu * dndx + dx * k * n), wi - eta * dwody + (mu * dndy + dy * k * n))
            }
        };
        let out = Differentials { rx: (p + dpdx, rx_d), ry: (p + dpdy, ry_d) };
        let fine = [out.rx.0, out.rx.1, out.ry.0, out.ry.1].iter().all(|v| v.length_squared() <= 1e16);
        fine.then_some(out)
    }
}

/// pbrt-v4's `CoordinateSystem` (Duff et al. 2017): two unit vectors completing `z` to an
/// orthonormal basis.
fn coordinate_system(z: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(z.z);
    let a = -1.0 / (sign + z.z);
    let b = z.x * z.y * a;
    (Vec3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x), Vec3::new(b, sign + z.y * z.y * a, -z.y))
}

/// pbrt-v4's `RotateFromTo`: the rotation taking unit vector `from` to `to`, as two
/// reflections through an intermediate axis (its choice fixes the twist about `to`).
fn rotate_from_to(from: Vec3, to: Vec3) -> Mat3 {
    let refl = if from.x.abs() < 0.72 && to.x.abs() < 0.72 {
        Vec3::X
    } else if from.y.abs() < 0.72 && to.y.abs() < 0.72 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let (u, v) = (refl - from, refl - to);
    let (uu, vv, uv) = (u.dot(u), v.dot(v), u.dot(v));
    let r = |i: usize, j: usize| {
        let delta = if i == j { 1.0 } else { 0.0 };
        delta - 2.0 / uu * u[i] * u[j] - 2.0 / vv * v[i] * v[j] + 4.0 * uv / (uu * vv) * v[i] * u[j]
    };
    // glam's matrices are column-major: column j holds r[·][j].
    Mat3::from_cols(
        Vec3::new(r(0, 0), r(1, 0), r(2, 0)),
        Vec3::new(r(0, 1), r(1, 1), r(2, 1)),
        Vec3::new(r(0, 2), r(1, 2), r(2, 2)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::settings::CameraSettings;
    use nimbus_parser::transform::look_at;

    #[test]
    fn footprints_follow_pbrt_v4s_smallest_differentials() {
        // A 90° perspective camera over 100×100 pixels: the smallest change of direction
        // between neighbouring pixels is at the film's corners, (1, 1, 1)/√3, where a step of
        // 0.02 in x turns the direction by 0.02·√(2/3)/√3. On a plane facing the camera at
        // distance 5 the footprint is that times 5 times max(1/8, 1/√16).
        let settings = CameraSettings::perspective(90.0);
        let world_from_camera = look_at([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]).unwrap().inverse();
        let camera = Camera::new(&settings, &world_from_camera, [100, 100], 35.0).unwrap();
        let f = Footprint::new(&camera, [100, 100], 16);
        let expected = 0.02 * (2.0f32 / 3.0).sqrt() / 3f32.sqrt() * 5.0 * 0.25;
        let (dx, dy) = f.dp_dxy(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        for d in [dx, dy] {
            assert!((d.length() - expected).abs() < 0.02 * expected && d.z.abs() < 1e-5, "{d} vs {expected}");
        }
        // Tilted 60° away the plane stretches footprints along the tilt, up to 1/cos 60°.
        let n = Vec3::new(0.0, (60f32).to_radians().sin(), -(60f32).to_radians().cos());
        let (tx, ty) = f.dp_dxy(Vec3::new(0.0, 0.0, 5.0), n);
        let longest = tx.length().max(ty.length());
        assert!(longest > 1.2 * expected && longest < 2.01 * expected, "{tx} {ty}");
        assert!(tx.dot(n).abs() < 1e-5 && ty.dot(n).abs() < 1e-5, "footprints lie in the tangent plane");
    }

    /// A camera looking down +z from the origin, over 80×60 pixels.
    fn camera(settings: &CameraSettings) -> Camera {
        let world_from_camera = look_at([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]).unwrap().inverse();
        Camera::new(settings, &world_from_camera, [80, 60], 35.0).unwrap()
    }

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).length() <= tol
    }

    /// A projective camera ray's differentials are the rays through the film positions one
    /// pixel over with the same lens point, as pbrt-v4's cameras compute them: for pinhole and
    /// thin-lens perspective cameras and a pinhole orthographic one; a spherical camera's
    /// numerically, as pbrt-v4's generic camera does.
    #[test]
    fn camera_differentials_are_the_next_pixels_rays() {
        let ortho = CameraSettings {
            projection: crate::camera::settings::Projection::Orthographic,
            ..CameraSettings::perspective(0.0)
        };
        let lens = CameraSettings { lens_radius: 0.3, focal_distance: 7.0, ..CameraSettings::perspective(50.0) };
        for settings in [CameraSettings::perspective(50.0), lens, ortho] {
            let cam = camera(&settings);
            for (p, u) in [(Vec2::new(40.0, 30.0), Vec2::new(0.2, 0.9)), (Vec2::new(3.3, 55.1), Vec2::new(0.7, 0.4))] {
                let ray = cam.generate_ray(p, u, 0.5).unwrap().ray;
                let d = cam.differentials(&ray).unwrap();
                for (got, offset) in [(d.rx, Vec2::X), (d.ry, Vec2::Y)] {
                    let want = cam.generate_ray(p + offset, u, 0.5).unwrap().ray;
                    assert!(
                        close(got.0, want.o, 1e-4) && close(got.1, want.d, 1e-5),
                        "{settings:?} at {p}: {got:?} vs {want:?}"
                    );
                }
            }
        }
        // Spherical cameras: pbrt-v4's numerical differentials, 0.05 pixel over scaled up,
        // from the film position the direction maps back to.
        for equal_area in [true, false] {
            let sph = CameraSettings {
                projection: crate::camera::settings::Projection::Spherical { equal_area },
                ..CameraSettings::perspective(0.0)
            };
            let cam = camera(&sph);
            let p = Vec2::new(13.3, 21.7);
            let ray = cam.generate_ray(p, Vec2::ZERO, 0.5).unwrap().ray;
            let d = cam.differentials(&ray).unwrap();
            for (got, offset) in [(d.rx, Vec2::X), (d.ry, Vec2::Y)] {
                let r = cam.generate_ray(p + offset * 0.05, Vec2::ZERO, 0.5).unwrap().ray;
                let want = ray.d + (r.d - ray.d) / 0.05;
                assert!(close(got.1, want, 2e-3 * (want - ray.d).length()), "{equal_area}: {got:?} vs {want}");
                assert!(close(got.0, ray.o, 1e-5));
            }
        }
    }

    /// A realistic camera's differentials are pbrt-v4's numerical ones: the rays 0.05 pixel
    /// over with the same pupil sample, scaled up (the film position and pupil sample found
    /// by tracing the ray back through the lens).
    #[test]
    fn realistic_differentials_are_the_shifted_rays() {
        let settings = CameraSettings {
            projection: crate::camera::settings::Projection::Realistic(crate::camera::settings::RealisticSettings {
                elements: crate::camera::realistic::tests::DGAUSS.to_vec(),
                aperture_diameter: 20.0,
                focus_distance: 3.0,
                aperture: None,
            }),
            ..CameraSettings::perspective(0.0)
        };
        let cam = camera(&settings);
        let mut checked = 0;
        for (p, u) in [(Vec2::new(40.3, 30.2), Vec2::new(0.5, 0.5)), (Vec2::new(12.6, 50.3), Vec2::new(0.3, 0.7))] {
            let Some(ray) = cam.generate_ray(p, u, 0.5).map(|c| c.ray) else { continue };
            let d = cam.differentials(&ray).expect("differentials");
            for (got, axis) in [(d.rx, Vec2::X), (d.ry, Vec2::Y)] {
                let r = cam.generate_ray(p + axis * 0.05, u, 0.5).unwrap().ray;
                let (want_o, want_d) = (ray.o + (r.o - ray.o) / 0.05, ray.d + (r.d - ray.d) / 0.05);
                assert!(close(got.0, want_o, 0.02 * (want_o - ray.o).length() + 1e-5), "{p}: {got:?} vs {want_o}");
                assert!(close(got.1, want_d, 0.02 * (want_d - ray.d).length() + 1e-6), "{p}: {got:?} vs {want_d}");
            }
            checked += 1;
        }
        assert_eq!(checked, 2);
    }

    /// A camera ray's footprint on a plane facing a pinhole perspective camera is one pixel's
    /// step on that plane (times the sample-count factor) wherever the ray goes, since the
    /// projection onto such a plane is linear; the approximation, from the smallest change of
    /// direction anywhere on the film (at a 90° camera's corners), is smaller at the centre.
    #[test]
    fn ray_footprints_are_one_pixel_on_a_facing_plane() {
        let cam = camera(&CameraSettings::perspective(90.0));
        let f = Footprint::new(&cam, [80, 60], 16);
        let n = Vec3::new(0.0, 0.0, -1.0);
        // Screen 2·(80/60) wide over 80 pixels, tan 45° = 1, at distance 5, spp factor 1/4.
        let step = 2.0 * (80.0 / 60.0) / 80.0 * 5.0 * 0.25;
        for p_film in [Vec2::new(40.0, 30.0), Vec2::new(1.0, 1.0), Vec2::new(77.5, 20.0)] {
            let ray = cam.generate_ray(p_film, Vec2::ZERO, 0.5).unwrap().ray;
            let p = ray.o + ray.d * (5.0 / ray.d.z);
            let (dx, dy) = f.camera_differentials(&cam, &ray).unwrap().dp_dxy(p, n).unwrap();
            // pbrt-v4 scales the difference of unit directions, not the step on the film: off
            // axis that is not exactly a quarter pixel on the plane (0.9 % at the corner).
            assert!(close(dx, Vec3::new(step, 0.0, 0.0), 0.015 * step), "{dx} at {p_film}");
            assert!(close(dy, Vec3::new(0.0, -step, 0.0), 0.015 * step), "{dy} at {p_film}");
            if p_film == Vec2::new(40.0, 30.0) {
                let (ax, _) = f.dp_dxy(p, n);
                assert!(ax.length() < 0.5 * step, "{ax}");
            }
        }
    }

    /// A flat mirror reflects the differentials as lines: the reflected offset rays are the
    /// mirror images of the incoming ones. A flat interface bends them by Snell's law to
    /// first order.
    #[test]
    fn specular_differentials_reflect_and_refract_the_offset_rays() {
        let n = Vec3::Y;
        let p = Vec3::new(0.3, 0.0, -0.2);
        let d0 = Vec3::new(0.4, -1.0, 0.3).normalize();
        let o0 = p - 3.0 * d0;
        // Offset rays: the neighbouring pixels' (a small change of direction and origin).
        let rx = (o0 + Vec3::new(0.001, 0.0, 0.0), (d0 + Vec3::new(0.002, 0.0, -0.001)).normalize());
        let ry = (o0, (d0 + Vec3::new(0.0, 0.0015, 0.002)).normalize());
        let diff = Differentials { rx, ry };
        let (dpdx, dpdy) = diff.dp_dxy(p, n).unwrap();
        let wo = -d0;
        let reflect = |d: Vec3| d - 2.0 * d.dot(n) * n;
        let r = diff.specular(p, (dpdx, dpdy), n, (Vec3::ZERO, Vec3::ZERO), wo, reflect(d0), None).unwrap();
        for (out, inc) in [(r.rx, rx), (r.ry, ry)] {
            // Where the incoming offset ray meets the plane, and its reflected direction.
            let hit = inc.0 + inc.1 * (-inc.0.y / inc.1.y);
            assert!(close(out.0, hit, 1e-5), "{out:?} vs {hit}");
            assert!(close(out.1, reflect(inc.1), 1e-4), "{out:?} vs {}", reflect(inc.1));
        }
        // An index-matched interface (η = 1) passes the offset rays on unbent.
        let t = diff.specular(p, (dpdx, dpdy), n, (Vec3::ZERO, Vec3::ZERO), wo, d0, Some(1.0)).unwrap();
        for (out, inc) in [(t.rx, rx), (t.ry, ry)] {
            let hit = inc.0 + inc.1 * (-inc.0.y / inc.1.y);
            assert!(close(out.0, hit, 1e-5) && close(out.1, inc.1, 1e-5), "{out:?} vs {inc:?}");
        }
        // Through η = 1.5 the spread of directions is pbrt-v4's: η times the incoming spread
        // where it is parallel to the surface (Snell's law's derivative would give 1/η).
        let t = diff.specular(p, (dpdx, dpdy), n, (Vec3::ZERO, Vec3::ZERO), wo, d0, Some(1.5)).unwrap();
        let tangential = |v: Vec3| v - v.dot(n) * n;
        let spread_in = tangential(rx.1 - d0);
        assert!(close(tangential(t.rx.1 - d0), 1.5 * spread_in, 1e-6), "{:?}", t.rx);
    }

    #[test]
    fn pbrt_frames_are_orthonormal_and_rotations_rotate() {
        for z in [Vec3::Z, -Vec3::Z, Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::new(-0.9, 0.1, -0.2).normalize()] {
            let (x, y) = coordinate_system(z);
            assert!((x.length() - 1.0).abs() < 1e-5 && x.dot(y).abs() < 1e-5 && x.dot(z).abs() < 1e-5);
            assert!((x.cross(y) - z).length() < 1e-4, "right-handed");
            let r = rotate_from_to(z, Vec3::Z);
            assert!((r * z - Vec3::Z).length() < 1e-5 && (r.determinant() - 1.0).abs() < 1e-4, "{z}");
        }
    }
}
