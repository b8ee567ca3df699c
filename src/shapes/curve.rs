//! pbrt-v4's `curve` shape (pbrt-v4 §6.7, `shapes.cpp`): cubic Bézier curves of varying
//! width, `flat` (a ribbon always facing the ray), `cylinder` (flat, shaded as a tube) or
//! `ribbon` (oriented by normals at its ends), intersected by recursive subdivision in a
//! coordinate system where the ray runs along +z from the origin.
//!
//! A curve segment is split at load into 2^splitdepth pieces, each its own primitive over
//! [u_min, u_max] of the segment, so the BVH bounds them tightly.

use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::{SurfaceHit, swaps_handedness, transform_normal};
use crate::geometry::{Bounds3, Ray};

/// The three kinds of curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveType {
    /// A flat strip perpendicular to the ray.
    Flat,
    /// Flat, with normals of a cylinder across its width.
    Cylinder,
    /// A strip oriented by interpolating the normals at its ends.
    Ribbon,
}

/// What the pieces of one curve segment share.
#[derive(Clone, Debug)]
pub struct CurveCommon {
    /// Control points of the cubic Bézier segment (object space).
    cp: [Vec3; 4],
    /// Width at u = 0 and u = 1.
    width: [f32; 2],
    kind: CurveType,
    /// Ribbon normals at the ends (unit), with the angle between them.
    n: [Vec3; 2],
    normal_angle: f32,
    inv_sin_normal_angle: f32,
    world_from_object: Affine3A,
    object_from_world: Affine3A,
    flip_normal: bool,
}

impl CurveCommon {
    /// A segment with control points `cp`, widths `width` at its ends, and for ribbons the
    /// normals at its ends.
    pub fn new(
        cp: [Vec3; 4],
        width: [f32; 2],
        kind: CurveType,
        normals: Option<[Vec3; 2]>,
        world_from_object: Affine3A,
        reverse_orientation: bool,
    ) -> CurveCommon {
        let n = normals.map_or([Vec3::Z; 2], |[a, b]| [a.normalize_or_zero(), b.normalize_or_zero()]);
        let normal_angle = angle_between(n[0], n[1]);
        CurveCommon {
            cp,
            width,
            kind,
            n,
            normal_angle,
            inv_sin_normal_angle: 1.0 / normal_angle.sin(),
            world_from_object,
            object_from_world: world_from_object.inverse(),
            flip_normal: reverse_orientation ^ swaps_handedness(&world_from_object),
        }
    }

    fn width_at(&self, u: f32) -> f32 {
        lerp(u, self.width[0], self.width[1])
    }
}

/// One piece [u_min, u_max] of a curve segment.
#[derive(Clone, Copy, Debug)]
pub struct Curve {
    /// Index of its [`CurveCommon`].
    pub common: u32,
    u_min: f32,
    u_max: f32,
}

impl Curve {
    /// The piece [u_min, u_max] of segment `common`.
    pub fn new(common: u32, u_min: f32, u_max: f32) -> Curve {
        Curve { common, u_min, u_max }
    }

    /// World-space bounds: the hull of the piece's control points grown by half its width.
    pub fn bounds(&self, c: &CurveCommon) -> Bounds3 {
        let cp = cubic_bezier_control_points(&c.cp, self.u_min, self.u_max);
        let half = 0.5 * c.width_at(self.u_min).max(c.width_at(self.u_max));
        let (lo, hi) = cp
            .iter()
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        Bounds3::new(lo - Vec3::splat(half), hi + Vec3::splat(half)).transformed(&c.world_from_object)
    }

    /// The closest hit before `t_max` with its surface details (pbrt-v4's `Curve::intersect`).
    pub fn intersect(&self, c: &CurveCommon, ray: &Ray, t_max: f32) -> Option<(f32, SurfaceHit)> {
        // The ray in object space, then a frame where it starts at the origin and runs along
        // +z, with x roughly along the curve (pbrt-v4's LookAt with up = d × (p3 − p0)).
        let o = c.object_from_world.transform_point3(ray.o);
        let d = c.object_from_world.transform_vector3(ray.d);
        let cp_obj = cubic_bezier_control_points(&c.cp, self.u_min, self.u_max);
        let mut up = d.cross(cp_obj[3] - cp_obj[0]);
        if up.length_squared() == 0.0 {
            up = d.normalize().any_orthonormal_vector();
        }
        let dir = d.normalize();
        let right = up.normalize().cross(dir).normalize_or_zero();
        if right == Vec3::ZERO {
            return None;
        }
        let new_up = dir.cross(right);
        // Rows of the rotation take object vectors into the ray frame.
        let ray_from_object = Mat3::from_cols(right, new_up, dir).transpose();
        let cp = cp_obj.map(|p| ray_from_object * (p - o));

        let max_width = c.width_at(self.u_min).max(c.width_at(self.u_max));
        let ray_length = d.length();
        if !overlaps(&cp, max_width, ray_length * t_max) {
            return None;
        }
        // Refinement depth: enough halvings for the pieces to be nearly straight.
        let mut l0: f32 = 0.0;
        for i in 0..2 {
            let second = (cp[i] - 2.0 * cp[i + 1] + cp[i + 2]).abs();
            l0 = l0.max(second.max_element());
        }
        let eps = c.width[0].max(c.width[1]) * 0.05;
        let r0 = log2_int(std::f32::consts::SQRT_2 * 6.0 * l0 / (8.0 * eps)) / 2;
        let max_depth = r0.clamp(0, 10);
        let ctx = Ctx { c, d, ray_length };
        let mut best: Option<Found> = None;
        ctx.recurse(&cp, self.u_min, self.u_max, max_depth, t_max, &mut best);
        let f = best?;

        // Surface details (pbrt-v4): ∂p/∂u along the curve, ∂p/∂v across its width.
        let (_, dpdu) = evaluate_cubic_bezier(&c.cp, f.u);
        let dpdv = match c.kind {
            CurveType::Ribbon => f.n_hit.cross(dpdu).normalize_or_zero() * f.hit_width,
            CurveType::Flat | CurveType::Cylinder => {
                let dpdu_plane = ray_from_object * dpdu;
                let mut dpdv_plane = Vec3::new(-dpdu_plane.y, dpdu_plane.x, 0.0).normalize_or_zero() * f.hit_width;
                if c.kind == CurveType::Cylinder {
                    // Rotate across the width for a tube's appearance: −90° at v = 0 to 90°.
                    let theta = lerp(f.v, -90.0f32, 90.0).to_radians();
                    let axis = dpdu_plane.normalize_or_zero();
                    dpdv_plane = glam::Quat::from_axis_angle(axis, -theta) * dpdv_plane;
                }
                ray_from_object.transpose() * dpdv_plane
            }
        };
        let p_obj = o + d * f.t;
        let mut n = transform_normal(&c.object_from_world, dpdu.cross(dpdv).normalize_or_zero());
        if c.flip_normal {
            n = -n;
        }
        let hit = SurfaceHit {
            t: f.t,
            p: c.world_from_object.transform_point3(p_obj),
            n,
            ns: n,
            uv: Vec2::new(f.u, f.v),
            dpdu: c.world_from_object.transform_vector3(dpdu),
            // pbrt-v4 bounds a curve hit's error by the width at the hit (its pError). Twice
            // that, as here before, offset rays from a curve's base to below the ground it
            // stands on (measured: 0.6 % darker at the base of a width-0.15 curve).
            p_error: f.hit_width * c.world_from_object.matrix3.determinant().abs().cbrt(),
        };
        Some((f.t, hit))
    }
}

struct Found {
    t: f32,
    u: f32,
    v: f32,
    hit_width: f32,
    n_hit: Vec3,
}

struct Ctx<'a> {
    c: &'a CurveCommon,
    d: Vec3,
    ray_length: f32,
}

impl Ctx<'_> {
    /// pbrt-v4's `recursiveIntersect`: halve the piece until `depth` runs out, skipping
    /// halves whose widened hull misses the ray, then intersect the nearly straight piece.
    fn recurse(&self, cp: &[Vec3; 4], u0: f32, u1: f32, depth: i32, t_max: f32, best: &mut Option<Found>) {
        let c = self.c;
        if depth > 0 {
            let split = subdivide_cubic_bezier(cp);
            let u = [u0, 0.5 * (u0 + u1), u1];
            for seg in 0..2 {
                let cps = [split[3 * seg], split[3 * seg + 1], split[3 * seg + 2], split[3 * seg + 3]];
                let max_width = c.width_at(u[seg]).max(c.width_at(u[seg + 1]));
                let t_limit = best.as_ref().map_or(t_max, |b| b.t);
                if !overlaps(&cps, max_width, self.ray_length * t_limit) {
                    continue;
                }
                self.recurse(&cps, u[seg], u[seg + 1], depth - 1, t_max, best);
            }
            return;
        }
        // The ray (the origin of the xy plane) must lie between the perpendiculars to the
        // tangents at the piece's ends.
        let edge = (cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x);
        if edge < 0.0 {
            return;
        }
        let edge = (cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x);
        if edge < 0.0 {
            return;
        }
        // The closest point of the chord to the ray gives w, then u.
        let seg_dir = Vec2::new(cp[3].x - cp[0].x, cp[3].y - cp[0].y);
        let denom = seg_dir.length_squared();
        if denom == 0.0 {
            return;
        }
        let w = (-Vec2::new(cp[0].x, cp[0].y)).dot(seg_dir) / denom;
        let u = lerp(w, u0, u1).clamp(u0, u1);
        let mut hit_width = c.width_at(u);
        let mut n_hit = Vec3::ZERO;
        if c.kind == CurveType::Ribbon {
            // A ribbon seen edge-on is narrower.
            n_hit = if c.normal_angle > 1e-4 {
                let sin0 = ((1.0 - u) * c.normal_angle).sin() * c.inv_sin_normal_angle;
                let sin1 = (u * c.normal_angle).sin() * c.inv_sin_normal_angle;
                sin0 * c.n[0] + sin1 * c.n[1]
            } else {
                // Equal end normals: the slerp's limit (pbrt-v4 divides by sin 0 here).
                lerp3(u, c.n[0], c.n[1]).normalize_or_zero()
            };
            hit_width *= n_hit.dot(self.d).abs() / self.ray_length;
        }
        let (pc, dpcdw) = evaluate_cubic_bezier(cp, w.clamp(0.0, 1.0));
        let dist2 = pc.x * pc.x + pc.y * pc.y;
        if dist2 > hit_width * hit_width * 0.25 {
            return;
        }
        let t_limit = best.as_ref().map_or(t_max, |b| b.t);
        if pc.z < 0.0 || pc.z > self.ray_length * t_limit {
            return;
        }
        // v across the width: 0.5 on the curve, 0 and 1 at its edges.
        let dist = dist2.sqrt();
        let edge_func = dpcdw.x * -pc.y + pc.x * dpcdw.y;
        let v = if edge_func > 0.0 { 0.5 + dist / hit_width } else { 0.5 - dist / hit_width };
        *best = Some(Found { t: pc.z / self.ray_length, u, v, hit_width, n_hit });
    }
}

/// Whether the hull of `cp` widened by half of `width` can touch the ray between z = 0 and
/// `z_max` (the ray runs along +z through the origin).
fn overlaps(cp: &[Vec3; 4], width: f32, z_max: f32) -> bool {
    let half = 0.5 * width;
    let lo = cp[0].min(cp[1]).min(cp[2]).min(cp[3]);
    let hi = cp[0].max(cp[1]).max(cp[2]).max(cp[3]);
    !(hi.y + half < 0.0
        || lo.y - half > 0.0
        || hi.x + half < 0.0
        || lo.x - half > 0.0
        || hi.z + half < 0.0
        || lo.z - half > z_max)
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

fn lerp3(t: f32, a: Vec3, b: Vec3) -> Vec3 {
    (1.0 - t) * a + t * b
}

/// ⌊log2 v⌋ for positive v (pbrt-v4's `Log2Int(float)`), 0 otherwise.
fn log2_int(v: f32) -> i32 {
    if v < 1.0 || !v.is_finite() {
        if v.is_finite() && v > 0.0 {
            return v.log2().floor() as i32;
        }
        return 0;
    }
    v.log2().floor() as i32
}

fn angle_between(a: Vec3, b: Vec3) -> f32 {
    // pbrt-v4's numerically careful form.
    if a.dot(b) < 0.0 {
        std::f32::consts::PI - 2.0 * ((a + b).length() / 2.0).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).clamp(-1.0, 1.0).asin()
    }
}

/// The blossom p(u0, u1, u2) of a cubic Bézier curve.
fn blossom(p: &[Vec3; 4], u0: f32, u1: f32, u2: f32) -> Vec3 {
    let a = [lerp3(u0, p[0], p[1]), lerp3(u0, p[1], p[2]), lerp3(u0, p[2], p[3])];
    let b = [lerp3(u1, a[0], a[1]), lerp3(u1, a[1], a[2])];
    lerp3(u2, b[0], b[1])
}

/// Control points of the part [u0, u1] of a cubic Bézier curve.
pub fn cubic_bezier_control_points(p: &[Vec3; 4], u0: f32, u1: f32) -> [Vec3; 4] {
    [blossom(p, u0, u0, u0), blossom(p, u0, u0, u1), blossom(p, u0, u1, u1), blossom(p, u1, u1, u1)]
}

/// The curve's two halves (7 control points, the middle one shared).
fn subdivide_cubic_bezier(cp: &[Vec3; 4]) -> [Vec3; 7] {
    [
        cp[0],
        (cp[0] + cp[1]) / 2.0,
        (cp[0] + 2.0 * cp[1] + cp[2]) / 4.0,
        (cp[0] + 3.0 * cp[1] + 3.0 * cp[2] + cp[3]) / 8.0,
        (cp[1] + 2.0 * cp[2] + cp[3]) / 4.0,
        (cp[2] + cp[3]) / 2.0,
        cp[3],
    ]
}

/// The point at u and the derivative there (the chord's direction where it vanishes).
pub fn evaluate_cubic_bezier(cp: &[Vec3; 4], u: f32) -> (Vec3, Vec3) {
    let a = [lerp3(u, cp[0], cp[1]), lerp3(u, cp[1], cp[2]), lerp3(u, cp[2], cp[3])];
    let b = [lerp3(u, a[0], a[1]), lerp3(u, a[1], a[2])];
    let deriv = if (b[1] - b[0]).length_squared() > 0.0 { 3.0 * (b[1] - b[0]) } else { cp[3] - cp[0] };
    (lerp3(u, b[0], b[1]), deriv)
}

/// A quadratic Bézier curve as a cubic.
pub fn elevate_quadratic(cp: [Vec3; 3]) -> [Vec3; 4] {
    [cp[0], lerp3(2.0 / 3.0, cp[0], cp[1]), lerp3(1.0 / 3.0, cp[1], cp[2]), cp[2]]
}

/// A uniform quadratic B-spline segment as a quadratic Bézier curve.
pub fn quadratic_bspline_to_bezier(cp: [Vec3; 3]) -> [Vec3; 3] {
    [lerp3(0.5, cp[0], cp[1]), cp[1], lerp3(0.5, cp[1], cp[2])]
}

/// A uniform cubic B-spline segment as a cubic Bézier curve.
pub fn cubic_bspline_to_bezier(cp: [Vec3; 4]) -> [Vec3; 4] {
    let p122 = lerp3(2.0 / 3.0, cp[0], cp[1]);
    let p223 = lerp3(1.0 / 3.0, cp[1], cp[2]);
    let p233 = lerp3(2.0 / 3.0, cp[1], cp[2]);
    let p334 = lerp3(1.0 / 3.0, cp[2], cp[3]);
    [lerp3(0.5, p122, p223), p223, p233, lerp3(0.5, p233, p334)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(width: f32, kind: CurveType) -> CurveCommon {
        let cp = [
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(-1.0 / 3.0, 0.0, 0.0),
            Vec3::new(1.0 / 3.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        CurveCommon::new(cp, [width; 2], kind, Some([Vec3::Z, Vec3::Z]), Affine3A::IDENTITY, false)
    }

    #[test]
    fn a_straight_flat_curve_is_a_strip_of_its_width() {
        let c = straight(0.2, CurveType::Flat);
        let piece = Curve::new(0, 0.0, 1.0);
        // Rays down the z axis hit within |y| < 0.1 and |x| < 1, at t = 5.
        for (x, y, hit) in
            [(0.0, 0.0, true), (0.5, 0.09, true), (-0.7, -0.09, true), (0.0, 0.11, false), (1.1, 0.0, false)]
        {
            let ray = Ray::new(Vec3::new(x, y, 5.0), -Vec3::Z);
            let found = piece.intersect(&c, &ray, f32::INFINITY);
            assert_eq!(found.is_some(), hit, "({x}, {y})");
            if let Some((t, s)) = found {
                assert!((t - 5.0).abs() < 1e-4, "{t}");
                assert!((s.uv.x - (x + 1.0) / 2.0).abs() < 0.02, "u {} at x {x}", s.uv.x);
                assert!((s.uv.y - (0.5 + y / 0.2)).abs() < 0.02 || (s.uv.y - (0.5 - y / 0.2)).abs() < 0.02);
                assert!(s.n.z.abs() > 0.999, "a flat curve faces the ray: {}", s.n);
            }
        }
        // Not beyond t_max.
        assert!(piece.intersect(&c, &Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z), 4.0).is_none());
        let b = piece.bounds(&c);
        assert!(b.min.x <= -1.0 && b.max.x >= 1.0 && b.min.y <= -0.1 && b.max.y >= 0.1);
    }

    #[test]
    fn a_cylinder_curve_turns_its_normal_across_the_width() {
        let c = straight(0.2, CurveType::Cylinder);
        let piece = Curve::new(0, 0.0, 1.0);
        let centre = piece.intersect(&c, &Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z), f32::INFINITY).unwrap().1;
        let edge = piece.intersect(&c, &Ray::new(Vec3::new(0.0, 0.095, 5.0), -Vec3::Z), f32::INFINITY).unwrap().1;
        assert!(centre.n.z.abs() > 0.999, "{}", centre.n);
        assert!(edge.n.y.abs() > 0.9, "near the edge the normal points sideways: {}", edge.n);
    }

    #[test]
    fn a_ribbon_seen_edge_on_is_thin() {
        // Normals along +y: the ribbon lies in the xz plane; rays along −z see it edge-on.
        let cp =
            [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(-0.3, 0.0, 0.0), Vec3::new(0.3, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        let c = CurveCommon::new(cp, [0.2; 2], CurveType::Ribbon, Some([Vec3::Y, Vec3::Y]), Affine3A::IDENTITY, false);
        let piece = Curve::new(0, 0.0, 1.0);
        assert!(piece.intersect(&c, &Ray::new(Vec3::new(0.0, 0.05, 5.0), -Vec3::Z), f32::INFINITY).is_none());
        // From above (along −y) it is its full width.
        assert!(piece.intersect(&c, &Ray::new(Vec3::new(0.0, 5.0, 0.09), -Vec3::Y), f32::INFINITY).is_some());
    }

    #[test]
    fn bezier_helpers_agree() {
        let cp = [Vec3::ZERO, Vec3::new(1.0, 2.0, 0.0), Vec3::new(3.0, 2.0, 1.0), Vec3::new(4.0, 0.0, 0.0)];
        // A part's end points are the curve's points there.
        let part = cubic_bezier_control_points(&cp, 0.25, 0.75);
        assert!((part[0] - evaluate_cubic_bezier(&cp, 0.25).0).length() < 1e-5);
        assert!((part[3] - evaluate_cubic_bezier(&cp, 0.75).0).length() < 1e-5);
        // Halves meet at the midpoint.
        let s = subdivide_cubic_bezier(&cp);
        assert!((s[3] - evaluate_cubic_bezier(&cp, 0.5).0).length() < 1e-5);
        // A cubic B-spline of collinear evenly spaced points is the straight segment between
        // the points' 1/6-2/3-1/6 averages.
        let b = cubic_bspline_to_bezier([Vec3::ZERO, Vec3::X, 2.0 * Vec3::X, 3.0 * Vec3::X]);
        assert!((b[0] - Vec3::X).length() < 1e-5 && (b[3] - 2.0 * Vec3::X).length() < 1e-5);
        let e = elevate_quadratic([Vec3::ZERO, Vec3::Y, Vec3::X]);
        // The quadratic (0, y, x) at ½ is ¼·x + ½·y.
        assert!((evaluate_cubic_bezier(&e, 0.5).0 - Vec3::new(0.25, 0.5, 0.0)).length() < 1e-5);
    }
}
