//! Transforms that move over the shutter interval: pbrt-v4's `AnimatedTransform`
//! (`ActiveTransform` / `TransformTimes`). Each end is decomposed into translation, rotation
//! and scale (a polar decomposition, Shoemake and Duff 1992); between the two times the
//! translation and scale are interpolated linearly and the rotation by slerp, as pbrt-v4 does.

use glam::{Affine3A, DMat3, DMat4, Mat3, Quat, Vec3};

use super::Bounds3;

/// A transform interpolated between two keyframes.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionTransform {
    start: Affine3A,
    end: Affine3A,
    start_time: f32,
    end_time: f32,
    translation: [Vec3; 2],
    rotation: [Quat; 2],
    scale: [Mat3; 2],
}

/// Splits the linear part `m` into a rotation and a stretch with `m = r s` (pbrt-v4's
/// `AnimatedTransform::Decompose`: iterate r ← (r + r⁻ᵀ)/2 to the orthogonal polar factor).
/// A reflection is moved into the stretch so that the rotation is proper.
fn decompose(m: DMat3) -> (DMat3, DMat3) {
    let mut r = m;
    for _ in 0..100 {
        let next = (r + r.transpose().inverse()) * 0.5;
        let diff = next - r;
        let norm = (0..3).map(|i| diff.row(i).abs().element_sum()).fold(0.0, f64::max);
        r = next;
        if norm < 1e-10 {
            break;
        }
    }
    if r.determinant() < 0.0 {
        r = -r;
    }
    let s = r.inverse() * m;
    (r, s)
}

impl MotionTransform {
    /// The motion from `start` (at `start_time`) to `end` (at `end_time`); both must be affine
    /// and invertible, which callers check.
    pub fn new(start: &DMat4, end: &DMat4, start_time: f32, end_time: f32) -> MotionTransform {
        let parts = |m: &DMat4| {
            let linear = DMat3::from_mat4(*m);
            let (r, s) = decompose(linear);
            (m.w_axis.truncate().as_vec3(), Quat::from_mat3(&r.as_mat3()).normalize(), s.as_mat3())
        };
        let (t0, r0, s0) = parts(start);
        let (t1, mut r1, s1) = parts(end);
        // The shorter way round.
        if r0.dot(r1) < 0.0 {
            r1 = -r1;
        }
        MotionTransform {
            start: Affine3A::from_mat4(start.as_mat4()),
            end: Affine3A::from_mat4(end.as_mat4()),
            start_time,
            end_time,
            translation: [t0, t1],
            rotation: [r0, r1],
            scale: [s0, s1],
        }
    }

    /// The transform at `time` (the keyframes themselves outside the interval).
    pub fn at(&self, time: f32) -> Affine3A {
        if time <= self.start_time || self.end_time <= self.start_time {
            return self.start;
        }
        if time >= self.end_time {
            return self.end;
        }
        let dt = (time - self.start_time) / (self.end_time - self.start_time);
        let t = self.translation[0].lerp(self.translation[1], dt);
        let r = self.rotation[0].slerp(self.rotation[1], dt);
        let s = self.scale[0] * (1.0 - dt) + self.scale[1] * dt;
        Affine3A::from_mat3_translation(Mat3::from_quat(r) * s, t)
    }

    /// The transform at the start of the motion.
    pub fn start(&self) -> Affine3A {
        self.start
    }

    /// A box holding `b` (in the moving object's space) at every time of the motion.
    ///
    /// Translation alone moves every point along a segment, so the two end boxes bound it
    /// exactly. Otherwise the box is bounded at 65 evenly spaced times and grown by how far
    /// any of its points can move between two of them: a point x moves at most at speed
    /// |ΔT| + θ max|S x| + |ΔS x| (θ the rotation angle), which bounds the corners' paths
    /// conservatively rather than exactly (pbrt-v4 solves for each corner's extrema).
    pub fn bounds(&self, b: &Bounds3) -> Bounds3 {
        if b.is_empty() {
            return *b;
        }
        let ends = b.transformed(&self.start).union(&b.transformed(&self.end));
        let rotates = self.rotation[0].angle_between(self.rotation[1]) > 0.0;
        if !rotates && self.scale[0] == self.scale[1] {
            return ends;
        }
        const STEPS: usize = 64;
        let reach = b.min.abs().max(b.max.abs()).length();
        let norm =
            |m: &Mat3| (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt();
        let theta = self.rotation[0].angle_between(self.rotation[1]);
        let speed = (self.translation[1] - self.translation[0]).length()
            + theta * norm(&self.scale[0]).max(norm(&self.scale[1])) * reach
            + norm(&(self.scale[1] - self.scale[0])) * reach;
        let margin = Vec3::splat(speed / (2.0 * STEPS as f32) * 1.001);
        let mut out = ends;
        for k in 0..=STEPS {
            let dt = k as f32 / STEPS as f32;
            let time = self.start_time + dt * (self.end_time - self.start_time);
            let bk = b.transformed(&self.at(time));
            out = out.union(&Bounds3 { min: bk.min - margin, max: bk.max + margin });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn motion(end: DMat4) -> MotionTransform {
        MotionTransform::new(&DMat4::IDENTITY, &end, 0.0, 1.0)
    }

    #[test]
    fn keyframes_and_interpolation() {
        let m = motion(DMat4::from_translation(DVec3::new(2.0, 0.0, 0.0)));
        assert_eq!(m.at(-1.0), Affine3A::IDENTITY);
        assert!((m.at(0.25).translation - glam::Vec3A::new(0.5, 0.0, 0.0)).length() < 1e-6);
        assert!((m.at(2.0).translation - glam::Vec3A::new(2.0, 0.0, 0.0)).length() < 1e-6);
        // A quarter turn about z is an eighth turn halfway.
        let r = motion(DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2));
        let p = r.at(0.5).transform_point3(Vec3::X);
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert!((p - Vec3::new(h, h, 0.0)).length() < 1e-5, "{p}");
        // Scale interpolates linearly; rotation and scale come apart again.
        let rs = motion(DMat4::from_rotation_z(1.0) * DMat4::from_scale(DVec3::new(3.0, 1.0, 1.0)));
        let a = rs.at(0.5);
        let expect = Mat3::from_rotation_z(0.5) * Mat3::from_diagonal(Vec3::new(2.0, 1.0, 1.0));
        assert!((Mat3::from(a.matrix3) - expect).abs_diff_eq(Mat3::ZERO, 1e-5), "{a:?}");
        // A mirrored keyframe: the reflection stays in the scale.
        let mirror = motion(DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)));
        let m1 = mirror.at(1.0);
        assert!((m1.transform_point3(Vec3::X) + Vec3::X).length() < 1e-5);
    }

    #[test]
    fn motion_bounds_hold_the_box_at_every_time() {
        let b = Bounds3::new(Vec3::new(-0.5, -0.2, 0.3), Vec3::new(0.7, 0.4, 1.1));
        let ends = [
            DMat4::from_translation(DVec3::new(1.0, -2.0, 0.5)),
            DMat4::from_rotation_y(2.5) * DMat4::from_translation(DVec3::new(0.5, 0.0, 0.0)),
            DMat4::from_translation(DVec3::new(0.0, 1.0, 0.0))
                * DMat4::from_rotation_x(-1.2)
                * DMat4::from_scale(DVec3::new(1.5, 0.5, 2.0)),
        ];
        for end in ends {
            let m = motion(end);
            let mb = m.bounds(&b);
            for k in 0..=1000 {
                let bk = b.transformed(&m.at(k as f32 / 1000.0));
                assert!(
                    mb.min.cmple(bk.min + 1e-5).all() && mb.max.cmpge(bk.max - 1e-5).all(),
                    "t = {}: {bk:?} outside {mb:?}",
                    k as f32 / 1000.0
                );
            }
        }
    }
}
