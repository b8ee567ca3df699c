//! pbrt-v4's bilinear patches (`bilinearmesh`, and the quads of `plymesh`): each patch is the
//! doubly ruled surface p(u, v) = lerp(u, lerp(v, p00, p01), lerp(v, p10, p11)), intersected
//! exactly (Reshetov's ray–patch solution, as pbrt-v4 implements it) rather than split into
//! two triangles, which differs wherever the four corners are not coplanar.

use glam::{Affine3A, Vec2, Vec3};

use super::{ShapeSample, SurfaceDerivatives, SurfaceHit, WorldVertices};
use crate::geometry::{Bounds3, Ray};
use crate::math::quadratic;

/// Vertex data shared by a mesh's patches.
#[derive(Clone, Debug, Default)]
pub struct BilinearMesh {
    /// World-space positions.
    pub positions: Vec<Vec3>,
    /// World-space unit normals per vertex (empty if none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates per vertex (empty if none).
    pub uvs: Vec<Vec2>,
    /// Four indices per patch: p00, p10, p01, p11.
    pub indices: Vec<u32>,
    /// ReverseOrientation xor a handedness-swapping transform.
    pub flip_normals: bool,
    /// Per patch, its Ptex face id (pbrt-v4's `faceIndices`); empty: 0 for all.
    pub face_indices: Vec<i32>,
}

/// pbrt-v4's `SampleLinear`: a sample of the density ∝ lerp(x, a, b) on [0, 1].
fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    let x = u * (a + b) / (a + (a * a + u * (b * b - a * a)).max(0.0).sqrt());
    x.min(crate::sampling::warp::ONE_MINUS_EPSILON)
}

/// pbrt-v4's `SampleBilinear` over corner weights w (at (0,0), (1,0), (0,1), (1,1)).
fn sample_bilinear(u: Vec2, w: [f32; 4]) -> Vec2 {
    let y = sample_linear(u.y, w[0] + w[1], w[2] + w[3]);
    let x = sample_linear(u.x, w[0] + (w[2] - w[0]) * y, w[1] + (w[3] - w[1]) * y);
    Vec2::new(x, y)
}

/// pbrt-v4's `BilinearPDF`: the density [`sample_bilinear`] samples with.
fn bilinear_pdf(p: Vec2, w: [f32; 4]) -> f32 {
    if p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 {
        return 0.0;
    }
    let sum = w[0] + w[1] + w[2] + w[3];
    if sum == 0.0 {
        return 1.0;
    }
    4.0 * ((1.0 - p.x) * (1.0 - p.y) * w[0] + p.x * (1.0 - p.y) * w[1] + (1.0 - p.x) * p.y * w[2] + p.x * p.y * w[3])
        / sum
}

#[inline]
fn det3(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    // The determinant of the matrix with columns a, b, c.
    a.dot(b.cross(c))
}

impl BilinearMesh {
    /// A mesh from object-space data (four indices per patch: p00, p10, p01, p11) and its
    /// world-from-object transform.
    pub fn new(
        world_from_object: &Affine3A,
        reverse_orientation: bool,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        uvs: &[[f32; 2]],
        indices: Vec<u32>,
    ) -> BilinearMesh {
        let v = WorldVertices::new(world_from_object, reverse_orientation, positions, normals, uvs);
        BilinearMesh {
            positions: v.positions,
            normals: v.normals,
            uvs: v.uvs,
            indices,
            flip_normals: v.flip_normals,
            face_indices: Vec::new(),
        }
    }

    /// The mesh with per-patch Ptex face ids (one per patch, or none).
    pub fn with_face_indices(mut self, face_indices: Vec<i32>) -> BilinearMesh {
        debug_assert!(face_indices.is_empty() || face_indices.len() == self.indices.len() / 4);
        self.face_indices = face_indices;
        self
    }

    /// Patch `patch`'s Ptex face id.
    #[inline]
    pub fn face_index(&self, patch: u32) -> i32 {
        self.face_indices.get(patch as usize).copied().unwrap_or(0)
    }

    /// Number of patches.
    pub fn patch_count(&self) -> usize {
        self.indices.len() / 4
    }

    #[inline]
    fn index(&self, i: u32) -> [usize; 4] {
        let k = 4 * i as usize;
        [
            self.indices[k] as usize,
            self.indices[k + 1] as usize,
            self.indices[k + 2] as usize,
            self.indices[k + 3] as usize,
        ]
    }

    /// The corners p00, p10, p01, p11 of patch `i`.
    #[inline]
    pub fn corners(&self, i: u32) -> [Vec3; 4] {
        self.index(i).map(|k| self.positions[k])
    }

    /// Bounds of patch `i` (a bilinear patch lies in its corners' convex hull).
    pub fn bounds(&self, i: u32) -> Bounds3 {
        let [a, b, c, d] = self.corners(i);
        let mut bb = Bounds3::new(a, b);
        bb.extend(c);
        bb.extend(d);
        bb
    }

    /// True when the patch is a planar rectangle.
    fn is_rectangle(&self, i: u32) -> bool {
        let [p00, p10, p01, p11] = self.corners(i);
        if p00 == p01 || p01 == p11 || p11 == p10 || p10 == p00 {
            return false;
        }
        let n = (p10 - p00).cross(p01 - p00).normalize_or_zero();
        if (p11 - p00).normalize_or_zero().dot(n).abs() > 1e-5 {
            return false;
        }
        let pc = (p00 + p01 + p10 + p11) * 0.25;
        let d2 = [p00, p01, p10, p11].map(|p| p.distance_squared(pc));
        d2.iter().all(|d| (d - d2[0]).abs() <= 1e-4 * d2[0])
    }

    /// Area of patch `i`: exact for rectangles, else pbrt-v4's estimate from a 3×3 grid of
    /// quadrilaterals.
    pub fn area(&self, i: u32) -> f32 {
        let [p00, p10, p01, p11] = self.corners(i);
        if self.is_rectangle(i) {
            return p00.distance(p01) * p00.distance(p10);
        }
        const NA: usize = 3;
        let at = |a: usize, b: usize| {
            let (u, v) = (a as f32 / NA as f32, b as f32 / NA as f32);
            p00.lerp(p01, v).lerp(p10.lerp(p11, v), u)
        };
        let mut area = 0.0;
        for a in 0..NA {
            for b in 0..NA {
                area += 0.5 * (at(a + 1, b + 1) - at(a, b)).cross(at(a + 1, b) - at(a, b + 1)).length();
            }
        }
        area
    }

    /// pbrt-v4's `IntersectBilinearPatch`: the distance and the patch parameters (u, v) of the
    /// closest hit before `t_max`. u solves the quadratic for the u-isoline the ray meets, then v
    /// and t follow from that line.
    #[inline]
    pub fn intersect(&self, i: u32, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let [p00, p10, p01, p11] = self.corners(i);
        let a = (p10 - p00).cross(p01 - p11).dot(ray.d);
        let c = (p00 - ray.o).cross(ray.d).dot(p01 - p00);
        let b = (p10 - ray.o).cross(ray.d).dot(p11 - p10) - (a + c);
        let (u1, u2) = quadratic(a, b, c)?;
        let eps = 1.2e-6
            * (ray.o.abs().max_element()
                + ray.d.abs().max_element()
                + p00.abs().max_element()
                + p10.abs().max_element()
                + p01.abs().max_element()
                + p11.abs().max_element());
        let mut best: Option<(f32, f32, f32)> = None;
        for u in [u1, u2] {
            if !(0.0..=1.0).contains(&u) || best.is_some_and(|(_, bu, _)| bu == u) {
                continue;
            }
            let uo = p00.lerp(p10, u);
            let ud = p01.lerp(p11, u) - uo;
            let deltao = uo - ray.o;
            let perp = ray.d.cross(ud);
            let p2 = perp.length_squared();
            let v = det3(deltao, ray.d, perp);
            let t = det3(deltao, ud, perp);
            if t > p2 * eps && (0.0..=p2).contains(&v) && best.is_none_or(|(bt, _, _)| t / p2 < bt) {
                best = Some((t / p2, u, v / p2));
            }
        }
        let (t, u, v) = best?;
        (t < t_max).then_some((t, u, v))
    }

    /// The texture coordinates at patch parameters `uv`, and ∂(s,t)/∂(u,v) inverted per
    /// component as pbrt-v4 does (duds, dudt, dvds, dvdt).
    fn st(&self, i: u32, uv: Vec2) -> (Vec2, [f32; 4]) {
        if self.uvs.is_empty() {
            return (uv, [1.0, 0.0, 0.0, 1.0]);
        }
        let [t00, t10, t01, t11] = self.index(i).map(|k| self.uvs[k]);
        let st = t00.lerp(t01, uv.y).lerp(t10.lerp(t11, uv.y), uv.x);
        let dstdu = t10.lerp(t11, uv.y) - t00.lerp(t01, uv.y);
        let dstdv = t01.lerp(t11, uv.x) - t00.lerp(t10, uv.x);
        let inv = |x: f32| if x.abs() < 1e-8 { 0.0 } else { 1.0 / x };
        (st, [inv(dstdu.x), inv(dstdu.y), inv(dstdv.x), inv(dstdv.y)])
    }

    /// ∂p/∂u and ∂p/∂v at patch parameters `uv`, with respect to the texture coordinates
    /// when the mesh has them (pbrt-v4), and the geometric normal.
    fn frame(&self, i: u32, uv: Vec2) -> (Vec3, Vec3, Vec3, [f32; 4]) {
        let [p00, p10, p01, p11] = self.corners(i);
        let mut dpdu = p10.lerp(p11, uv.y) - p00.lerp(p01, uv.y);
        let mut dpdv = p01.lerp(p11, uv.x) - p00.lerp(p10, uv.x);
        let (_, [duds, dudt, dvds, dvdt]) = self.st(i, uv);
        if !self.uvs.is_empty() {
            let dpds = dpdu * duds + dpdv * dvds;
            let mut dpdt = dpdu * dudt + dpdv * dvdt;
            if dpds.cross(dpdt) != Vec3::ZERO {
                if dpdu.cross(dpdv).dot(dpds.cross(dpdt)) < 0.0 {
                    dpdt = -dpdt;
                }
                dpdu = dpds;
                dpdv = dpdt;
            }
        }
        let mut n = dpdu.cross(dpdv).normalize_or_zero();
        if self.flip_normals {
            n = -n;
        }
        (dpdu, dpdv, n, [duds, dudt, dvds, dvdt])
    }

    /// Surface details at patch parameters (u, v) found at distance `t`.
    pub fn hit(&self, i: u32, t: f32, u: f32, v: f32) -> SurfaceHit {
        let uv = Vec2::new(u, v);
        let [p00, p10, p01, p11] = self.corners(i);
        let p = p00.lerp(p01, v).lerp(p10.lerp(p11, v), u);
        let (st, _) = self.st(i, uv);
        let (dpdu, _, mut n, _) = self.frame(i, uv);
        let mut ns = n;
        let mut tangent = dpdu;
        if !self.normals.is_empty() {
            let [n00, n10, n01, n11] = self.index(i).map(|k| self.normals[k]);
            let s = n00.lerp(n01, v).lerp(n10.lerp(n11, v), u);
            if s.length_squared() > 0.0 {
                ns = s.normalize();
                // The shading normal is authoritative: the geometric one faces its side.
                if n.dot(ns) < 0.0 {
                    n = -n;
                }
                tangent = (dpdu - ns * ns.dot(dpdu)).normalize_or_zero();
            }
        }
        let p_error = 6.0 * f32::EPSILON * 0.5 * p.abs().max_element();
        SurfaceHit { t, p, n, ns, uv: st, dpdu: tangent, p_error }
    }

    /// The patch parameters (u, v) of the point where `ray` meets patch `i` (for densities
    /// and derivatives of points found by tracing).
    pub fn param(&self, i: u32, ray: &Ray) -> Option<(f32, f32)> {
        self.intersect(i, ray, f32::INFINITY).map(|(_, u, v)| (u, v))
    }

    /// The corner weights pbrt-v4's area sampling uses: |∂p/∂u × ∂p/∂v| at the corners.
    fn corner_weights(&self, i: u32) -> [f32; 4] {
        let [p00, p10, p01, p11] = self.corners(i);
        [
            (p10 - p00).cross(p01 - p00).length(),
            (p10 - p00).cross(p11 - p10).length(),
            (p01 - p00).cross(p11 - p01).length(),
            (p11 - p10).cross(p11 - p01).length(),
        ]
    }

    /// Density per unit area of [`BilinearMesh::sample_area`] at patch parameters `uv`.
    pub fn pdf_area(&self, i: u32, uv: Vec2) -> f32 {
        let [p00, p10, p01, p11] = self.corners(i);
        let dpdu = p10.lerp(p11, uv.y) - p00.lerp(p01, uv.y);
        let dpdv = p01.lerp(p11, uv.x) - p00.lerp(p10, uv.x);
        let j = dpdu.cross(dpdv).length();
        if j == 0.0 {
            return 0.0;
        }
        let pdf_uv = if self.is_rectangle(i) { 1.0 } else { bilinear_pdf(uv, self.corner_weights(i)) };
        pdf_uv / j
    }

    /// A point on patch `i`: uniform in (u, v) for rectangles (uniform in area), else pbrt-v4's
    /// approximately area-uniform bilinear warp; its density per unit area is exact.
    pub fn sample_area(&self, i: u32, u: Vec2) -> Option<ShapeSample> {
        let uv = if self.is_rectangle(i) { u } else { sample_bilinear(u, self.corner_weights(i)) };
        let pdf = self.pdf_area(i, uv);
        if pdf == 0.0 || !pdf.is_finite() {
            return None;
        }
        let h = self.hit(i, 0.0, uv.x, uv.y);
        Some(ShapeSample { p: h.p, n: h.n, pdf, solid_angle: false })
    }

    /// The shading derivatives at a hit (pbrt-v4's `InteractionFromIntersection`): the
    /// surface's curvature from the fundamental forms (only the twist ∂²p/∂u∂v is nonzero),
    /// or the interpolated normals' derivatives when the mesh has normals.
    pub fn derivatives(&self, i: u32, hit: &SurfaceHit, uv: Vec2) -> SurfaceDerivatives {
        let [p00, p10, p01, p11] = self.corners(i);
        let (dpdu, dpdv, _, [duds, dudt, dvds, dvdt]) = self.frame(i, uv);
        let (mut dndu, mut dndv);
        if !self.normals.is_empty() {
            let [n00, n10, n01, n11] = self.index(i).map(|k| self.normals[k]);
            dndu = n10.lerp(n11, uv.y) - n00.lerp(n01, uv.y);
            dndv = n01.lerp(n11, uv.x) - n00.lerp(n10, uv.x);
        } else {
            let d2puv = (p00 - p01) + (p11 - p10);
            let (e, f, g) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
            let n = dpdu.cross(dpdv).normalize_or_zero();
            let ff = n.dot(d2puv);
            let egf2 = e * g - f * f;
            let inv = if egf2 == 0.0 { 0.0 } else { 1.0 / egf2 };
            dndu = (ff * f) * inv * dpdu + (-ff * e) * inv * dpdv;
            dndv = (-ff * g) * inv * dpdu + (ff * f) * inv * dpdv;
        }
        if !self.uvs.is_empty() {
            let (a, b) = (dndu, dndv);
            dndu = a * duds + b * dvds;
            dndv = a * dudt + b * dvdt;
        }
        // Shading tangents perpendicular to the shading normal, as for triangles with normals.
        let ns = hit.ns;
        let ss = (dpdu - ns * ns.dot(dpdu)).normalize_or_zero() * dpdu.length();
        let ts = if self.normals.is_empty() { dpdv } else { ns.cross(ss) };
        SurfaceDerivatives { dpdu: ss, dpdv: ts, dndu, dndv }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn patch(corners: [[f32; 3]; 4]) -> BilinearMesh {
        BilinearMesh::new(&Affine3A::IDENTITY, false, &corners, &[], &[], vec![0, 1, 2, 3])
    }

    /// A saddle z = x y over the unit square: its exact surface, not two triangles.
    fn saddle() -> BilinearMesh {
        patch([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 1.0]])
    }

    #[test]
    fn rays_meet_the_exact_surface() {
        let m = saddle();
        let mut rng = crate::sampling::rng::Pcg32::new(1, 2);
        for _ in 0..1000 {
            let (x, y) = (rng.uniform(), rng.uniform());
            // Vertical rays hit the saddle at z = x y with (u, v) = (x, y).
            let (t, u, v) = m.intersect(0, &Ray::new(Vec3::new(x, y, 5.0), -Vec3::Z), f32::INFINITY).unwrap();
            assert!((t - (5.0 - x * y)).abs() < 1e-4, "t {t} at ({x}, {y})");
            assert!((u - x).abs() < 1e-4 && (v - y).abs() < 1e-4, "({u}, {v}) vs ({x}, {y})");
            let h = m.hit(0, t, u, v);
            assert!((h.p - Vec3::new(x, y, x * y)).length() < 1e-4);
            // The normal of z = x y is (−y, −x, 1) normalised (p10 − p00 × p01 − p00 = +z).
            let n = Vec3::new(-y, -x, 1.0).normalize();
            assert!((h.n - n).length() < 1e-4, "{:?} vs {n:?}", h.n);
            // An oblique ray through the same point finds it too.
            let d = Vec3::new(0.3, -0.2, -1.0).normalize();
            let o = h.p - d * 3.0;
            let (t2, _, _) = m.intersect(0, &Ray::new(o, d), f32::INFINITY).unwrap();
            assert!((o + d * t2 - h.p).length() < 1e-3, "oblique hit");
        }
        assert!(m.intersect(0, &Ray::new(Vec3::new(1.5, 0.5, 5.0), -Vec3::Z), f32::INFINITY).is_none());
    }

    #[test]
    fn area_sampling_density_integrates_to_one_and_matches_the_area() {
        let m = saddle();
        // ∫ |p_u × p_v| du dv = ∫∫ sqrt(1 + x² + y²) = 1.28079 (numerically).
        let area = m.area(0);
        assert!((area - 1.28079).abs() < 0.01, "area {area}");
        // E[1 / pdf_area] over the sampling distribution is the exact area.
        let mut rng = crate::sampling::rng::Pcg32::new(3, 4);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let s = m.sample_area(0, Vec2::new(rng.uniform(), rng.uniform())).unwrap();
            sum += 1.0 / s.pdf as f64;
            let z = s.p.x * s.p.y;
            assert!((s.p.z - z).abs() < 1e-5, "samples lie on the surface");
        }
        assert!((sum / n as f64 - 1.28079).abs() < 0.003, "{}", sum / n as f64);
        // A rectangle samples uniformly.
        let r = patch([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 1.0, 0.0]]);
        assert_eq!(r.area(0), 2.0);
        assert!((r.sample_area(0, Vec2::new(0.3, 0.7)).unwrap().pdf - 0.5).abs() < 1e-6);
    }
}
