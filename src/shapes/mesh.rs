//! Triangle meshes in world space (pbrt-v4 transforms mesh vertices once at load).

use glam::{Affine3A, Vec2, Vec3};

use super::{ShapeSample, SurfaceDerivatives, SurfaceHit, WorldVertices};
use crate::geometry::{Bounds3, Ray};
use crate::sampling::warp;

/// Vertex data shared by a mesh's triangles.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// World-space positions.
    pub positions: Vec<Vec3>,
    /// World-space unit normals per vertex (empty if none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates per vertex (empty if none).
    pub uvs: Vec<Vec2>,
    /// Three indices per triangle.
    pub indices: Vec<u32>,
    /// ReverseOrientation xor a handedness-swapping transform.
    pub flip_normals: bool,
    /// Per triangle, its Ptex face id (pbrt-v4's `faceIndices`); empty: 0 for all.
    pub face_indices: Vec<i32>,
}

impl Mesh {
    /// A mesh from object-space data and its world-from-object transform.
    pub fn new(
        world_from_object: &Affine3A,
        reverse_orientation: bool,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        uvs: &[[f32; 2]],
        indices: Vec<u32>,
    ) -> Mesh {
        let v = WorldVertices::new(world_from_object, reverse_orientation, positions, normals, uvs);
        Mesh {
            positions: v.positions,
            normals: v.normals,
            uvs: v.uvs,
            indices,
            flip_normals: v.flip_normals,
            face_indices: Vec::new(),
        }
    }

    /// The mesh with per-triangle Ptex face ids (one per triangle, or none).
    pub fn with_face_indices(mut self, face_indices: Vec<i32>) -> Mesh {
        debug_assert!(face_indices.is_empty() || face_indices.len() == self.triangle_count());
        self.face_indices = face_indices;
        self
    }

    /// Triangle `tri`'s Ptex face id.
    #[inline]
    pub fn face_index(&self, tri: u32) -> i32 {
        self.face_indices.get(tri as usize).copied().unwrap_or(0)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The three vertices of triangle `i`.
    #[inline]
    pub fn vertices(&self, i: u32) -> [Vec3; 3] {
        let k = 3 * i as usize;
        [
            self.positions[self.indices[k] as usize],
            self.positions[self.indices[k + 1] as usize],
            self.positions[self.indices[k + 2] as usize],
        ]
    }

    /// Bounds of triangle `i`.
    pub fn triangle_bounds(&self, i: u32) -> Bounds3 {
        let [a, b, c] = self.vertices(i);
        let mut bb = Bounds3::new(a, b);
        bb.extend(c);
        bb
    }

    /// Area of triangle `i`.
    pub fn triangle_area(&self, i: u32) -> f32 {
        let [a, b, c] = self.vertices(i);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Ray-triangle intersection (Möller-Trumbore): distance and barycentrics (b1, b2) of
    /// vertices 1 and 2.
    #[inline]
    pub fn intersect(&self, i: u32, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        intersect_triangle(self.vertices(i), ray, t_max)
    }
}

/// Ray-triangle intersection (Möller-Trumbore) with the triangle's corners: distance and
/// barycentrics (b1, b2) of corners 1 and 2.
#[inline]
pub fn intersect_triangle([p0, p1, p2]: [Vec3; 3], ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = ray.d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = ray.o - p0;
    let b1 = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let qv = tv.cross(e1);
    let b2 = ray.d.dot(qv) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    (t > 0.0 && t < t_max).then_some((t, b1, b2))
}

/// Barycentrics (b1, b2) of corners 1 and 2 of the point of the triangle's plane nearest `p`;
/// `None` for a degenerate triangle.
pub fn barycentrics([v0, v1, v2]: [Vec3; 3], p: Vec3) -> Option<(f32, f32)> {
    let (e1, e2, w) = (v1 - v0, v2 - v0, p - v0);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (w.dot(e1), w.dot(e2));
    let det = d00 * d11 - d01 * d01;
    (det != 0.0).then(|| ((d11 * d20 - d01 * d21) / det, (d00 * d21 - d01 * d20) / det))
}

/// Surface details of a hit on triangle `i` of `mesh` with barycentrics (b1, b2).
pub fn triangle_hit(mesh: &Mesh, i: u32, t: f32, b1: f32, b2: f32) -> SurfaceHit {
    let k = 3 * i as usize;
    let idx = [mesh.indices[k] as usize, mesh.indices[k + 1] as usize, mesh.indices[k + 2] as usize];
    let [p0, p1, p2] = [mesh.positions[idx[0]], mesh.positions[idx[1]], mesh.positions[idx[2]]];
    let b0 = 1.0 - b1 - b2;
    let p = b0 * p0 + b1 * p1 + b2 * p2;
    let uv_of = |j: usize| {
        if mesh.uvs.is_empty() { [Vec2::ZERO, Vec2::X, Vec2::ONE][j] } else { mesh.uvs[idx[j]] }
    };
    let (uv0, uv1, uv2) = (uv_of(0), uv_of(1), uv_of(2));
    let uv = b0 * uv0 + b1 * uv1 + b2 * uv2;
    // pbrt-v4: n = normalize(cross(p0 - p2, p1 - p2)), flipped for reversed or
    // handedness-swapping meshes, or turned towards the interpolated shading normal.
    let mut n = (p0 - p2).cross(p1 - p2).normalize_or_zero();
    let ns = if mesh.normals.is_empty() {
        if mesh.flip_normals {
            n = -n;
        }
        n
    } else {
        let ns =
            (b0 * mesh.normals[idx[0]] + b1 * mesh.normals[idx[1]] + b2 * mesh.normals[idx[2]]).normalize_or_zero();
        if ns == Vec3::ZERO {
            if mesh.flip_normals {
                n = -n;
            }
            n
        } else {
            if n.dot(ns) < 0.0 {
                n = -n;
            }
            ns
        }
    };
    // ∂p/∂u from the uv parameterisation (pbrt-v4), or any tangent when it is degenerate.
    let duv02 = uv0 - uv2;
    let duv12 = uv1 - uv2;
    let dp02 = p0 - p2;
    let dp12 = p1 - p2;
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    let dpdu = if det.abs() > 1e-9 { (duv12.y * dp02 - duv02.y * dp12) / det } else { Vec3::ZERO };
    SurfaceHit { t, p, n, ns, uv, dpdu, p_error: 0.0 }
}

/// The shading derivatives of a hit on triangle `i` (pbrt-v4's
/// `Triangle::InteractionFromIntersection`): with per-vertex normals, ∂p/∂u made
/// perpendicular to ns, ∂p/∂v = ns × ∂p/∂u, and ∂n/∂u, ∂n/∂v from the normals' differences
/// over uv; without, the geometric ∂p/∂v and no bending.
pub fn triangle_derivatives(mesh: &Mesh, i: u32, hit: &SurfaceHit) -> SurfaceDerivatives {
    let k = 3 * i as usize;
    let idx = [mesh.indices[k] as usize, mesh.indices[k + 1] as usize, mesh.indices[k + 2] as usize];
    let [p0, p1, p2] = [mesh.positions[idx[0]], mesh.positions[idx[1]], mesh.positions[idx[2]]];
    let uv_of = |j: usize| {
        if mesh.uvs.is_empty() { [Vec2::ZERO, Vec2::X, Vec2::ONE][j] } else { mesh.uvs[idx[j]] }
    };
    let (duv02, duv12) = (uv_of(0) - uv_of(2), uv_of(1) - uv_of(2));
    let (dp02, dp12) = (p0 - p2, p1 - p2);
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    let dpdv = if det.abs() > 1e-9 { (duv02.x * dp12 - duv12.x * dp02) / det } else { Vec3::ZERO };
    if mesh.normals.is_empty() {
        return SurfaceDerivatives { dpdu: hit.dpdu, dpdv, dndu: Vec3::ZERO, dndv: Vec3::ZERO };
    }
    let ns = hit.ns;
    let ts = ns.cross(hit.dpdu);
    let (ss, ts) = if ts.length_squared() > 0.0 { (ts.cross(ns), ts) } else { (Vec3::ZERO, Vec3::ZERO) };
    let (dndu, dndv) = if det.abs() > 1e-9 {
        let dn1 = mesh.normals[idx[0]] - mesh.normals[idx[2]];
        let dn2 = mesh.normals[idx[1]] - mesh.normals[idx[2]];
        ((duv12.y * dn1 - duv02.y * dn2) / det, (duv02.x * dn2 - duv12.x * dn1) / det)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    };
    SurfaceDerivatives { dpdu: ss, dpdv: ts, dndu, dndv }
}

/// Uniform area sample on triangle `i`.
pub fn triangle_sample(mesh: &Mesh, i: u32, u: Vec2) -> ShapeSample {
    let (b0, b1) = warp::uniform_triangle(u);
    let b2 = 1.0 - b0 - b1;
    let h = triangle_hit(mesh, i, 0.0, b1, b2);
    ShapeSample { p: h.p, n: h.n, pdf: 1.0 / mesh.triangle_area(i), solid_angle: false }
}

/// pbrt-v4's ray–triangle test (`IntersectTriangle`, the watertight test of Woop, Benthin
/// and Wald, "Watertight Ray/Triangle Intersection", JCGT 2013) in its exact single-precision
/// arithmetic, with the fused multiply-adds pbrt-v4's release build makes of it: the hit's
/// `t`, the scaled distance and the determinant (for pbrt-v4's range test against a later
/// `t_max`). nimbus intersects with Möller–Trumbore; this is for deciding ties between
/// coplanar surfaces the way pbrt-v4's rounding decides them ([`crate::accel`]).
pub fn pbrt_intersect_triangle([p0, p1, p2]: [Vec3; 3], o: Vec3, d: Vec3, t_max: f32) -> Option<PbrtTriangleHit> {
    if (p2 - p0).cross(p1 - p0).length_squared() == 0.0 {
        return None;
    }
    let (p0t, p1t, p2t) = (p0 - o, p1 - o, p2 - o);
    let a = d.abs();
    let kz = if a.x > a.y {
        if a.x > a.z { 0 } else { 2 }
    } else if a.y > a.z {
        1
    } else {
        2
    };
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    let perm = |v: Vec3| Vec3::new(v[kx], v[ky], v[kz]);
    let (d, mut p0t, mut p1t, mut p2t) = (perm(d), perm(p0t), perm(p1t), perm(p2t));
    let (sx, sy, sz) = (-d.x / d.z, -d.y / d.z, 1.0 / d.z);
    for p in [&mut p0t, &mut p1t, &mut p2t] {
        p.x = sx.mul_add(p.z, p.x);
        p.y = sy.mul_add(p.z, p.y);
    }
    // pbrt-v4's DifferenceOfProducts: a·b − c·d with the product's rounding error added back.
    let dop = |a: f32, b: f32, c: f32, d: f32| {
        let cd = c * d;
        a.mul_add(b, -cd) + (-c).mul_add(d, cd)
    };
    let mut e0 = dop(p1t.x, p2t.y, p1t.y, p2t.x);
    let mut e1 = dop(p2t.x, p0t.y, p2t.y, p0t.x);
    let mut e2 = dop(p0t.x, p1t.y, p0t.y, p1t.x);
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        let f = |v: f32| v as f64;
        e0 = (f(p2t.y) * f(p1t.x) - f(p2t.x) * f(p1t.y)) as f32;
        e1 = (f(p0t.y) * f(p2t.x) - f(p0t.x) * f(p2t.y)) as f32;
        e2 = (f(p1t.y) * f(p0t.x) - f(p1t.x) * f(p0t.y)) as f32;
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    let (z0, z1, z2) = (p0t.z * sz, p1t.z * sz, p2t.z * sz);
    let t_scaled = e2.mul_add(z2, e0.mul_add(z0, e1 * z1));
    let hit = PbrtTriangleHit { t: t_scaled * (1.0 / det), t_scaled, det };
    (hit.within(t_max) && hit.t > 0.0).then_some(hit)
}

/// A hit of [`pbrt_intersect_triangle`].
#[derive(Clone, Copy, Debug)]
pub struct PbrtTriangleHit {
    /// Distance along the ray.
    pub t: f32,
    t_scaled: f32,
    det: f32,
}

impl PbrtTriangleHit {
    /// pbrt-v4's test of the hit against a ray's `t_max` (in scaled form, so a hit at the
    /// same computed `t` as an earlier one may pass or fail).
    pub fn within(&self, t_max: f32) -> bool {
        if self.det < 0.0 {
            !(self.t_scaled >= 0.0 || self.t_scaled < t_max * self.det)
        } else {
            !(self.t_scaled <= 0.0 || self.t_scaled > t_max * self.det)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_hit_and_orientation() {
        let mesh = Mesh::new(
            &Affine3A::IDENTITY,
            false,
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[],
            &[],
            vec![0, 1, 2],
        );
        let ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        let (t, b1, b2) = mesh.intersect(0, &ray, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-6);
        let h = triangle_hit(&mesh, 0, t, b1, b2);
        assert!((h.p - Vec3::new(0.2, 0.2, 0.0)).length() < 1e-6);
        assert!((h.n - Vec3::Z).length() < 1e-6, "counter-clockwise triangles face +z: {:?}", h.n);
        assert!(mesh.intersect(0, &Ray::new(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z), f32::INFINITY).is_none());
        let rev = Mesh::new(
            &Affine3A::IDENTITY,
            true,
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[],
            &[],
            vec![0, 1, 2],
        );
        assert!((triangle_hit(&rev, 0, t, b1, b2).n + Vec3::Z).length() < 1e-6);
        assert!((mesh.triangle_area(0) - 0.5).abs() < 1e-6);
    }

    /// pbrt-v4's watertight test finds the hits Möller–Trumbore finds, at the same distance
    /// to within rounding, and misses where it misses (away from the edges, where either may
    /// round the other way).
    #[test]
    fn pbrt_triangle_test_agrees_with_moller_trumbore() {
        let mut rng = crate::sampling::rng::Pcg32::new(7, 1);
        let mut v = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0;
        let (mut hits, mut checked) = (0, 0);
        for _ in 0..20000 {
            let tri = [v(), v(), v()];
            let (o, target) = (v() * 2.0, v() * 0.5);
            let d = (target - o).normalize();
            let mt = intersect_triangle(tri, &Ray::new(o, d), f32::INFINITY);
            let wt = pbrt_intersect_triangle(tri, o, d, f32::INFINITY);
            if let Some((_, b1, b2)) = mt
                && b1.min(b2).min(1.0 - b1 - b2) < 1e-3
            {
                continue;
            }
            checked += 1;
            match (mt, wt) {
                (Some((t, ..)), Some(h)) => {
                    assert!((t - h.t).abs() <= 1e-4 * t.max(1.0), "t {t} vs {}", h.t);
                    assert!(h.within(h.t * 1.0001) && !h.within(h.t * 0.9999));
                    hits += 1;
                }
                (None, None) => {}
                (mt, wt) => panic!("Möller–Trumbore {mt:?} vs pbrt-v4 {wt:?}"),
            }
        }
        assert!(hits > 1000 && checked > 15000, "{hits} hits of {checked}");
    }

    /// Rays through the shared edge of two triangles hit at least one of them: the test is
    /// watertight, as pbrt-v4's.
    #[test]
    fn pbrt_triangle_test_is_watertight() {
        let quad = [
            Vec3::new(-1.3, 0.2, -0.7),
            Vec3::new(1.1, 0.25, -0.9),
            Vec3::new(0.9, 0.3, 1.7),
            Vec3::new(-1.2, 0.2, 1.1),
        ];
        let (a, b) = ([quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]);
        let mut rng = crate::sampling::rng::Pcg32::new(3, 9);
        for _ in 0..20000 {
            let on_edge = quad[0].lerp(quad[2], rng.uniform());
            let o = Vec3::new(rng.uniform() * 4.0 - 2.0, 3.0 + rng.uniform(), rng.uniform() * 4.0 - 2.0);
            let d = (on_edge - o).normalize();
            let hit = |t| pbrt_intersect_triangle(t, o, d, f32::INFINITY).is_some();
            assert!(hit(a) || hit(b), "a ray through the shared edge at {on_edge} slips through");
        }
    }
}
