//! Closed convex triangle meshes as one primitive each. A medium's box (`Material
//! "interface"` on a closed convex mesh) is the commonest volume set-up in pbrt-v4 scenes,
//! and every event inside it asks for the next surface: on grid-cloud (a box over a ground
//! quad) BVH traversal and triangle tests were 30 % of the render. A ray meets a convex
//! polyhedron at most twice, so the face it meets first follows from one dot product pair
//! per face plane; only that face's triangles are then tested, with the mesh's own triangle
//! test, so the hit is the one the BVH would have found. The BVH holds the hull in place of
//! its triangles (grid-cloud's 14 triangles become three primitives, tested without a BVH).
//! A full sphere (homogeneous-sphere's, the Disney cloud's bound) that nothing else reaches
//! into is likewise answered by its own test alone for rays from inside.

use glam::Vec3;
use std::collections::HashMap;

use super::{Candidate, Detail, Geometry, NONE, Primitive};
use crate::geometry::{Bounds3, Ray};
use crate::shapes::{Mesh, Sphere, barycentrics, intersect_triangle};

/// Face planes per hull: beyond this the planes cost more than the BVH over the triangles.
const MAX_PLANES: usize = 16;

/// A face plane: inside is `n·x < d` (`n` unit, pointing out).
#[derive(Clone, Copy, Debug)]
struct Plane {
    n: Vec3,
    d: f32,
}

/// A triangle of a hull with its corners.
#[derive(Clone, Copy, Debug)]
struct Tri {
    prim: Primitive,
    corners: [Vec3; 3],
}

/// A closed convex triangle mesh.
#[derive(Clone, Debug)]
pub struct Hull {
    planes: Vec<Plane>,
    /// Per plane, the range of `tris` lying in it.
    faces: Vec<(u32, u32)>,
    /// The hull's triangles, grouped by plane.
    tris: Vec<Tri>,
    /// Radius of the hull's bounding sphere about its centroid.
    scale: f32,
    /// The primitive standing for the hull in the BVH.
    pub(super) prim: Primitive,
    /// Faces (bits by plane) with another primitive just beyond them (a ground plane under a
    /// box), which a ray leaving through them may meet at the same distance.
    touched: u32,
}

impl Hull {
    /// The box around the hull's corners.
    pub fn bounds(&self) -> Bounds3 {
        let mut b = Bounds3::EMPTY;
        self.tris.iter().flat_map(|t| t.corners).for_each(|c| b.extend(c));
        b
    }

    /// Where a ray that starts strictly inside the hull leaves it: the distance to the
    /// exit face's plane and that face (for [`Hull::hit_on_face`]); `None` from elsewhere.
    /// Two dot products per face and no triangle test: inside a dense medium most
    /// segments end in a collision long before the boundary, whose triangle is then never
    /// needed.
    #[inline]
    pub(super) fn exit(&self, ray: &Ray) -> Option<(f32, u32)> {
        let (mut t_out, mut face) = (f32::INFINITY, u32::MAX);
        for (i, p) in self.planes.iter().enumerate() {
            let inside = p.d - p.n.dot(ray.o);
            if inside <= 0.0 || inside.is_nan() {
                return None;
            }
            let c = p.n.dot(ray.d);
            if c > 0.0 && inside < t_out * c {
                (t_out, face) = (inside / c, i as u32);
            }
        }
        // Through a touched face the BVH decides: its tie rule picks between the face and the
        // surface beyond it.
        (face != u32::MAX && self.touched >> face & 1 == 0).then_some((t_out, face))
    }

    /// The triangle of face `face` that a ray from inside leaves through (see [`Hull::exit`]):
    /// the primitive, the distance and the barycentrics of vertices 1 and 2.
    pub(super) fn hit_on_face(&self, face: u32, ray: &Ray) -> Candidate {
        let (prim, t, b1, b2) = self.triangle_on_face(face, ray);
        Candidate { t, prim, instance: NONE, detail: Detail::Barycentric(b1, b2) }
    }

    fn triangle_on_face(&self, face: u32, ray: &Ray) -> (Primitive, f32, f32, f32) {
        let (start, end) = self.faces[face as usize];
        let tris = &self.tris[start as usize..end as usize];
        if let Some(hit) = self.closest_among(tris, ray, f32::INFINITY).or_else(|| self.brute_force(ray, f32::INFINITY))
        {
            return hit;
        }
        // Rounding lost the ray between triangles (through an edge or a corner): the face
        // plane's point in the face's first triangle, its barycentrics clamped.
        let p = &self.planes[face as usize];
        let t = (p.d - p.n.dot(ray.o)) / p.n.dot(ray.d);
        // (Hull triangles have area; should rounding still call one degenerate, its corner 0.)
        let (b1, b2) = barycentrics(tris[0].corners, ray.o + ray.d * t).unwrap_or((0.0, 0.0));
        let b1 = b1.clamp(0.0, 1.0);
        (tris[0].prim, t, b1, b2.clamp(0.0, 1.0 - b1))
    }

    /// The closest of the hull's triangles the ray hits before `t_max`: the primitive, the
    /// distance and the barycentrics of vertices 1 and 2.
    #[inline]
    pub(super) fn closest(&self, ray: &Ray, t_max: f32) -> Option<(Primitive, f32, f32, f32)> {
        // Clip the ray against every face plane: it is inside over [t_in, t_out].
        let (mut t_in, mut t_out) = (0.0f32, f32::INFINITY);
        let (mut face_in, mut face_out) = (usize::MAX, usize::MAX);
        for (i, p) in self.planes.iter().enumerate() {
            let s = p.n.dot(ray.o) - p.d;
            let c = p.n.dot(ray.d);
            let t = -s / c;
            if c < 0.0 {
                if t > t_in {
                    (t_in, face_in) = (t, i);
                }
            } else if c > 0.0 {
                if t < t_out {
                    (t_out, face_out) = (t, i);
                }
            } else if s > 0.0 {
                return None;
            }
        }
        if face_out == usize::MAX {
            // A bounded hull is left through some face: only a degenerate direction gets here.
            return self.brute_force(ray, t_max);
        }
        if t_out < 0.0 {
            // The origin is outside, moving away (a ray leaving through a face): a hit its
            // triangle test could still report would be rounding.
            return None;
        }
        let slack = 1e-4 * self.scale;
        let length = ray.d.length();
        if (t_in - t_out) * length > slack {
            // The line misses the hull by more than rounding.
            return None;
        }
        // Outside, the entry face; inside, the exit face.
        let (face, t_face) = if face_in != usize::MAX { (face_in, t_in) } else { (face_out, t_out) };
        if (t_face - t_max) * length > slack {
            return None;
        }
        let (start, end) = self.faces[face];
        self.closest_among(&self.tris[start as usize..end as usize], ray, t_max)
            // Rounding at an edge between faces, or a grazing ray: test them all.
            .or_else(|| self.brute_force(ray, t_max))
    }

    fn brute_force(&self, ray: &Ray, t_max: f32) -> Option<(Primitive, f32, f32, f32)> {
        self.closest_among(&self.tris, ray, t_max)
    }

    #[inline]
    fn closest_among(&self, tris: &[Tri], ray: &Ray, t_max: f32) -> Option<(Primitive, f32, f32, f32)> {
        let mut best: Option<(Primitive, f32, f32, f32)> = None;
        for tri in tris {
            let limit = best.map_or(t_max, |b| b.1);
            if let Some((t, b1, b2)) = intersect_triangle(tri.corners, ray, limit) {
                best = Some((tri.prim, t, b1, b2));
            }
        }
        best
    }
}

/// The hulls of a scene's top level, and those of them nothing else reaches into.
#[derive(Default)]
pub struct Hulls {
    /// Indexed by [`Geometry::Hull`].
    pub all: Vec<Hull>,
    /// Hulls into which no other primitive's bounds reach (they may touch a face from
    /// outside): a ray from inside meets nothing before their boundary. At most
    /// [`MAX_ALONE`] (every query tests each).
    pub alone: Vec<u32>,
    /// Full spheres no other primitive's bounds reach into ([`lone_spheres`]): from inside
    /// one, its own test is the only one to run. At most [`MAX_ALONE`].
    pub spheres: Vec<Primitive>,
}

/// Hulls a ray is tested to start inside before the BVH is asked.
const MAX_ALONE: usize = 4;

impl Hulls {
    /// Where a ray leaves the hull it starts inside, if that is one nothing else reaches
    /// into: the closest hit, its triangle found only when resolved ([`Hulls::resolve`]).
    #[inline]
    pub(super) fn exit(&self, ray: &Ray) -> Option<Candidate> {
        self.alone.iter().find_map(|&k| {
            let hull = &self.all[k as usize];
            hull.exit(ray).map(|(t, face)| Candidate {
                t,
                prim: hull.prim,
                instance: NONE,
                detail: Detail::HullExit(face),
            })
        })
    }

    /// The candidate with its triangle, if it is a hull's exit.
    #[inline]
    pub(super) fn resolve(&self, c: &Candidate, ray: &Ray) -> Candidate {
        match (c.detail, c.prim.geometry) {
            (Detail::HullExit(face), Geometry::Hull(k)) => self.all[k as usize].hit_on_face(face, ray),
            _ => *c,
        }
    }
}

/// Replaces each closed convex mesh among `prims` (bounds `bounds`) by one primitive
/// [`Geometry::Hull`] with its triangles' attachments. Meshes with alpha textures or area
/// lights (a light per triangle) stay triangles.
pub fn gather_hulls(prims: &mut Vec<Primitive>, bounds: &mut Vec<Bounds3>, meshes: &[Mesh]) -> Hulls {
    let mut by_mesh: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, p) in prims.iter().enumerate() {
        if let Geometry::Triangle { mesh, .. } = p.geometry {
            by_mesh.entry(mesh).or_default().push(i);
        }
    }
    let mut keys: Vec<u32> = by_mesh.keys().copied().collect();
    keys.sort_unstable();
    let mut hulls = Vec::new();
    let mut gathered = vec![false; prims.len()];
    let mut added = Vec::new();
    for mesh in keys {
        let members = &by_mesh[&mesh];
        let m = &meshes[mesh as usize];
        let plain = |&i: &usize| prims[i].alpha == NONE && prims[i].area_light == NONE;
        if members.len() != m.triangle_count() || members.len() < 4 || !members.iter().all(plain) {
            continue;
        }
        let prim = Primitive { geometry: Geometry::Hull(hulls.len() as u32), ..prims[members[0]] };
        let Some(hull) = hull_of(members.iter().map(|&i| prims[i]), m, prim) else { continue };
        let hull_bounds = members.iter().fold(Bounds3::EMPTY, |b, &i| b.union(&bounds[i]));
        added.push((prim, hull_bounds));
        hulls.push(hull);
        for &i in members {
            gathered[i] = true;
        }
    }
    if hulls.is_empty() {
        return Hulls { all: hulls, ..Hulls::default() };
    }
    let mut k = 0;
    prims.retain(|_| (!gathered[k], k += 1).0);
    let mut k = 0;
    bounds.retain(|_| (!gathered[k], k += 1).0);
    for (p, b) in added {
        prims.push(p);
        bounds.push(b);
    }
    // The hulls' own primitives are the last ones, in order.
    let first = bounds.len() - hulls.len();
    let mut alone: Vec<u32> =
        (0..hulls.len()).filter(|&k| alone_with_touches(&mut hulls[k], bounds, first + k)).map(|k| k as u32).collect();
    if alone.len() > MAX_ALONE {
        alone.clear();
    }
    Hulls { all: hulls, alone, spheres: Vec::new() }
}

/// The full spheres among `prims` (bounds `bounds`) whose bounding ball no other primitive's
/// bounds reach into (a ground plane may touch it): at most [`MAX_ALONE`], none if more.
pub fn lone_spheres(prims: &[Primitive], bounds: &[Bounds3], spheres: &[Sphere]) -> Vec<Primitive> {
    let mut lone: Vec<Primitive> = prims
        .iter()
        .enumerate()
        .filter(|(k, p)| {
            let Geometry::Sphere(i) = p.geometry else { return false };
            let Some((center, radius)) = spheres[i as usize].ball() else { return false };
            let apart = |b: &Bounds3| center.clamp(b.min, b.max).distance_squared(center) >= radius * radius;
            p.alpha == NONE && bounds.iter().enumerate().all(|(j, b)| j == *k || apart(b))
        })
        .map(|(_, p)| *p)
        .collect();
    if lone.len() > MAX_ALONE {
        lone.clear();
    }
    lone
}

/// Whether no primitive but the hull's own reaches into its interior, going by their bounds;
/// marks the faces that one lies just beyond (all its bounds' corners on the outer side of
/// the face's plane, up to rounding: a ground plane under a box).
fn alone_with_touches(hull: &mut Hull, bounds: &[Bounds3], own: usize) -> bool {
    let hb = bounds[own];
    let pad = 1e-4 * (hb.max - hb.min).max_element();
    let eps = 1e-5 * hull.scale;
    for (i, b) in bounds.iter().enumerate() {
        let reaches_in = (b.min - pad).cmple(hb.max).all() && (b.max + pad).cmpge(hb.min).all();
        if i == own || !reaches_in {
            continue;
        }
        let corners = (0..8).map(|c| Vec3::select(glam::BVec3::new(c & 1 != 0, c & 2 != 0, c & 4 != 0), b.max, b.min));
        let beyond = |p: &Plane| corners.clone().all(|c| p.n.dot(c) >= p.d - eps);
        match hull.planes.iter().position(beyond) {
            Some(face) => hull.touched |= 1 << face,
            None => return false,
        }
    }
    true
}

/// The hull of mesh `m` from its triangles `tris`, if they close a convex polyhedron with
/// at most [`MAX_PLANES`] face planes.
fn hull_of(tris: impl Iterator<Item = Primitive>, m: &Mesh, prim: Primitive) -> Option<Hull> {
    let tris: Vec<Tri> = tris
        .map(|prim| match prim.geometry {
            Geometry::Triangle { tri, .. } => Tri { prim, corners: m.vertices(tri) },
            _ => unreachable!("grouped by mesh"),
        })
        .collect();
    let corners = || tris.iter().flat_map(|t| t.corners);
    let center = corners().fold(Vec3::ZERO, |s, v| s + v) / (3 * tris.len()) as f32;
    let scale = corners().map(|v| (v - center).length()).fold(0.0f32, f32::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    let eps = 1e-5 * scale;
    // Closed: every edge (between positions, welded bit for bit) shared by exactly two
    // triangles.
    let key = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut edges: HashMap<_, u32> = HashMap::new();
    for t in &tris {
        for k in 0..3 {
            let (a, b) = (key(t.corners[k]), key(t.corners[(k + 1) % 3]));
            *edges.entry(if a < b { (a, b) } else { (b, a) }).or_default() += 1;
        }
    }
    if edges.values().any(|&n| n != 2) {
        return None;
    }
    let mut planes: Vec<Plane> = Vec::new();
    let mut plane_of = Vec::with_capacity(tris.len());
    for t in &tris {
        let [a, b, c] = t.corners;
        let n = (b - a).cross(c - a);
        let len = n.length();
        if len <= 1e-10 * scale * scale || len.is_nan() {
            return None;
        }
        let mut n = n / len;
        let mut d = n.dot(a);
        if n.dot(center) > d {
            (n, d) = (-n, -d);
        }
        if n.dot(center) >= d - eps {
            return None;
        }
        let i = match planes.iter().position(|p| p.n.dot(n) > 1.0 - 1e-6 && (p.d - d).abs() <= eps) {
            Some(i) => i,
            None => {
                planes.push(Plane { n, d });
                planes.len() - 1
            }
        };
        plane_of.push(i);
    }
    if !(4..=MAX_PLANES).contains(&planes.len()) {
        return None;
    }
    // Convex: no corner outside any face plane.
    if corners().any(|v| planes.iter().any(|p| p.n.dot(v) > p.d + eps)) {
        return None;
    }
    let mut grouped = Vec::with_capacity(tris.len());
    let mut faces = Vec::with_capacity(planes.len());
    for i in 0..planes.len() {
        let start = grouped.len() as u32;
        grouped.extend(tris.iter().zip(&plane_of).filter(|(_, p)| **p == i).map(|(t, _)| *t));
        faces.push((start, grouped.len() as u32));
    }
    Some(Hull { planes, faces, tris: grouped, scale, prim, touched: 0 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Affine3A, Vec2};

    const BOX: [u32; 36] =
        [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5];
    const CORNERS: [[f32; 3]; 8] = [
        [0., 0., 0.],
        [1., 0., 0.],
        [1., 1., 0.],
        [0., 1., 0.],
        [0., 0., 1.],
        [1., 0., 1.],
        [1., 1., 1.],
        [0., 1., 1.],
    ];

    fn tris(mesh: u32, m: &Mesh) -> (Vec<Primitive>, Vec<Bounds3>) {
        (0..m.triangle_count() as u32)
            .map(|tri| {
                let p = Primitive {
                    geometry: Geometry::Triangle { mesh, tri },
                    material: 0,
                    area_light: NONE,
                    interface: NONE,
                    alpha: NONE,
                };
                (p, m.triangle_bounds(tri))
            })
            .unzip()
    }

    /// A ground quad at height `y`.
    fn ground(y: f32) -> Mesh {
        let corners = [[-9., y, -9.], [9., y, -9.], [9., y, 9.], [-9., y, 9.]];
        Mesh::new(&Affine3A::IDENTITY, false, &corners, &[], &[], vec![0, 1, 2, 0, 2, 3])
    }

    /// A rotated, non-uniformly scaled box.
    fn cube(indices: &[u32]) -> Mesh {
        let world = Affine3A::from_rotation_y(0.3) * Affine3A::from_scale(Vec3::new(2.0, 1.5, 1.0));
        Mesh::new(&world, false, &CORNERS, &[], &[], indices.to_vec())
    }

    /// The closest hit among `tris` by the mesh's own triangle test: distance and primitive.
    fn brute(m: &Mesh, tris: &[Primitive], ray: &Ray, t_max: f32) -> Option<(f32, Primitive)> {
        let mut want: Option<(f32, Primitive)> = None;
        for &p in tris {
            let Geometry::Triangle { tri, .. } = p.geometry else { unreachable!() };
            if let Some((t, _, _)) = m.intersect(tri, ray, want.map_or(t_max, |w| w.0)) {
                want = Some((t, p));
            }
        }
        want
    }

    #[test]
    fn a_box_hull_finds_the_hits_its_triangles_give() {
        let m = cube(&BOX);
        let (mut prims, mut bounds) = tris(0, &m);
        let all = prims.clone();
        let meshes = [m];
        let hulls = gather_hulls(&mut prims, &mut bounds, &meshes);
        assert_eq!((hulls.all.len(), hulls.all[0].planes.len(), hulls.alone.as_slice()), (1, 6, &[0][..]));
        assert_eq!(prims, vec![Primitive { geometry: Geometry::Hull(0), ..all[0] }]);
        let hull = &hulls.all[0];
        let mut rng = crate::sampling::rng::Pcg32::new(7, 1);
        let (mut hits, mut inside) = (0, 0);
        for _ in 0..50000 {
            let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
            // Origins inside, outside and at the corners (shared bit for bit by the faces).
            let o = match rng.uniform() {
                x if x < 0.1 => meshes[0].positions[(8.0 * u.x) as usize],
                _ => Vec3::new(-1.5, -0.5, -1.5) + u * Vec3::new(4.0, 2.5, 4.0),
            };
            let d =
                crate::sampling::warp::uniform_sphere(Vec2::new(rng.uniform(), rng.uniform())) * (0.5 + rng.uniform());
            let ray = Ray::new(o, d);
            let t_max = if rng.uniform() < 0.5 { f32::INFINITY } else { 3.0 * rng.uniform() };
            let want = brute(&meshes[0], &all, &ray, t_max);
            let got = hull.closest(&ray, t_max).map(|(p, t, _, _)| (t, p));
            hits += got.is_some() as u32;
            assert_eq!(got.map(|g| g.0), want.map(|w| w.0), "ray {ray:?} t_max {t_max}");
            // From inside: the exit plane's distance, and the exit face's triangle.
            if let Some((t, face)) = hull.exit(&ray) {
                inside += 1;
                let (want_t, want_prim) =
                    brute(&meshes[0], &all, &ray, f32::INFINITY).expect("a ray from inside leaves");
                assert!((t - want_t).abs() <= 1e-5 * want_t.max(1.0), "plane {t}, triangle {want_t}");
                let Candidate { prim, t, .. } = hull.hit_on_face(face, &ray);
                assert_eq!(t, want_t);
                let plane_of = |p: Primitive| {
                    hull.tris
                        .iter()
                        .position(|t| t.prim == p)
                        .map(|i| hull.faces.iter().position(|&(s, e)| (s as usize..e as usize).contains(&i)))
                };
                assert_eq!(plane_of(prim), plane_of(want_prim));
            }
        }
        assert!(hits > 5000 && inside > 1000, "{hits} hits, {inside} from inside");
    }

    #[test]
    fn open_or_concave_meshes_stay_triangles() {
        for mesh in [cube(&BOX[..30]), {
            let mut corners = CORNERS;
            corners[6] = [0.6, 0.6, 0.6];
            Mesh::new(&Affine3A::IDENTITY, false, &corners, &[], &[], BOX.to_vec())
        }] {
            let (mut prims, mut bounds) = tris(0, &mesh);
            let n = prims.len();
            assert!(gather_hulls(&mut prims, &mut bounds, &[mesh]).all.is_empty());
            assert_eq!((prims.len(), bounds.len()), (n, n));
        }
    }

    #[test]
    fn a_ground_under_a_box_touches_its_bottom_face_and_one_through_it_reaches_in() {
        let box_mesh = Mesh::new(&Affine3A::IDENTITY, false, &CORNERS, &[], &[], BOX.to_vec());
        for (ground_y, alone, touched) in [(-0.001, true, false), (0.0, true, true), (0.5, false, false)] {
            let ground = ground(ground_y);
            let (mut prims, mut bounds) = tris(0, &box_mesh);
            let (p, b) = tris(1, &ground);
            prims.extend(p);
            bounds.extend(b);
            let hulls = gather_hulls(&mut prims, &mut bounds, &[box_mesh.clone(), ground]);
            assert_eq!((hulls.all.len(), prims.len()), (1, 3));
            assert_eq!(hulls.alone.len() == 1, alone, "ground at y = {ground_y}");
            // From inside, a ray leaving through the bottom is left to the BVH where the ground
            // touches it; one leaving through the top never is.
            let hull = &hulls.all[0];
            let down = Ray::new(Vec3::splat(0.5), Vec3::new(0.1, -1.0, 0.2));
            let up = Ray::new(Vec3::splat(0.5), Vec3::new(0.1, 1.0, 0.2));
            assert_eq!(hull.exit(&down).is_none(), touched, "ground at y = {ground_y}");
            assert!(hull.exit(&up).is_some());
        }
    }

    #[test]
    fn from_inside_a_lone_sphere_its_own_test_finds_what_the_bvh_finds() {
        use crate::accel::{Accel, Surfaces};
        // An ellipsoid (scaled 2x in y) whose bottom, at y = -1.5, a ground quad touches.
        let world =
            Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)) * Affine3A::from_scale(Vec3::new(1.0, 2.0, 1.0));
        for (ground_y, lone) in [(-1.5, true), (-1.0, false)] {
            let mut s = Surfaces::default();
            s.shapes.spheres.push(Sphere::new(world, false, 1.0, -1.0, 1.0, 360.0));
            s.shapes.meshes.push(ground(ground_y));
            let sphere = Primitive {
                geometry: Geometry::Sphere(0),
                material: 1,
                area_light: NONE,
                interface: NONE,
                alpha: NONE,
            };
            let (mut prims, mut bounds) = tris(0, &s.shapes.meshes[0]);
            prims.push(sphere);
            bounds.push(s.shapes.spheres[0].bounds());
            let found = lone_spheres(&prims, &bounds, &s.shapes.spheres);
            assert_eq!(found.len() == 1, lone, "ground at y = {ground_y}");
            s.top = Accel::build(prims, bounds);
            let mut rng = crate::sampling::rng::Pcg32::new(3, 5);
            let mut inside = 0;
            for _ in 0..5000 {
                let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                let o = Vec3::new(-1.0, -1.5, -1.0) + u * Vec3::new(2.0, 4.0, 2.0);
                let d = crate::sampling::warp::uniform_sphere(Vec2::new(rng.uniform(), rng.uniform()));
                let ray = Ray::new(o, d);
                let t_max = if rng.uniform() < 0.5 { f32::INFINITY } else { 3.0 * rng.uniform() };
                s.hulls.spheres.clear();
                let by_bvh = s.find(&ray, t_max).map(|f| (f.t(), f.prim()));
                s.hulls.spheres = found.clone();
                let by_sphere = s.find(&ray, t_max).map(|f| (f.t(), f.prim()));
                assert_eq!(by_sphere, by_bvh, "ray {ray:?}");
                inside += s.shapes.spheres[0].contains(o) as u32;
            }
            assert!(inside > 1000, "{inside} rays from inside");
        }
    }
}
