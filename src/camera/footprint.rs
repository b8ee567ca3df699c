//! The screen-space footprint of a shading point: pbrt-v4's `Approximate_dp_dxy`, which
//! its textures use to filter (procedural noise sums only the octaves a pixel can show, a 3D
//! checkerboard blurs its edges over the footprint).
//!
//! pbrt-v4 finds, once per camera, the smallest change of a camera ray's origin and direction
//! between neighbouring pixels (`FindMinimumDifferentials`, over 512 film positions along the
//! diagonal), and at every surface point intersects rays offset by those changes with the
//! tangent plane. It uses the camera ray's own differentials at the first hit and reflected or
//! refracted ones after specular bounces; nimbus uses the approximation everywhere (they agree
//! at the image centre of a perspective camera, where the smallest differential is).

use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::Camera;

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
    use crate::scene::camera::CameraSettings;
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
