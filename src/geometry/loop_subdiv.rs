//! Loop subdivision surfaces (pbrt-v4's `loopsubdiv` shape, `util/loopsubdiv.cpp`; Loop 1987):
//! a triangle mesh refined `levels` times with Loop's even- and odd-vertex rules (boundary
//! rules on open edges), its vertices then pushed to the limit surface and given the limit
//! surface's normals. The result is an ordinary triangle mesh, built once at load.
//!
//! The limit normals are pbrt-v4's tangents crossed the other way round (T × S): pbrt-v4's
//! S × T points into a mesh wound counter-clockwise as seen from outside, against the
//! triangles' own orientation, and since a mesh's geometric normals follow its shading
//! normals, a subdivision surface there has its inside and outside swapped for one-sided
//! lights and `MediumInterface` (and `subsurface`, whose medium would end up outside). nimbus
//! orients them with the winding, as every other mesh; two-sided materials see no difference.
//!
//! The mesh is kept as per-level arrays of faces and vertices that refer to each other by
//! index (pbrt-v4 uses pointers); each level is computed from the previous one.

use std::collections::HashMap;
use std::f32::consts::PI;

use glam::Vec3;

use crate::error::{Error, Result};

const NONE: u32 = u32::MAX;

#[inline]
fn next(i: usize) -> usize {
    (i + 1) % 3
}

#[inline]
fn prev(i: usize) -> usize {
    (i + 2) % 3
}

#[derive(Clone, Copy)]
struct Vert {
    p: Vec3,
    /// A face that uses the vertex.
    start_face: u32,
    regular: bool,
    boundary: bool,
}

#[derive(Clone, Copy)]
struct Face {
    /// Corners, counter-clockwise.
    v: [u32; 3],
    /// Neighbour across edge (v[i], v[i+1]), or `NONE` on a boundary.
    f: [u32; 3],
}

/// A refined mesh: limit positions, limit normals and triangles.
#[derive(Debug)]
pub struct Subdivided {
    /// Vertex positions on the limit surface.
    pub positions: Vec<[f32; 3]>,
    /// Limit-surface normals (unnormalised, as pbrt-v4 stores them).
    pub normals: Vec<[f32; 3]>,
    /// Three vertex indices per triangle.
    pub indices: Vec<u32>,
}

struct Level {
    verts: Vec<Vert>,
    faces: Vec<Face>,
}

impl Level {
    fn vnum(&self, face: u32, v: u32) -> usize {
        // Topology built here always has v among the face's corners.
        self.faces[face as usize].v.iter().position(|&x| x == v).unwrap_or(0)
    }

    fn next_face(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].f[self.vnum(face, v)]
    }

    fn prev_face(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].f[prev(self.vnum(face, v))]
    }

    fn next_vert(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].v[next(self.vnum(face, v))]
    }

    fn prev_vert(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].v[prev(self.vnum(face, v))]
    }

    fn other_vert(&self, face: u32, a: u32, b: u32) -> u32 {
        let f = &self.faces[face as usize];
        f.v.iter().copied().find(|&x| x != a && x != b).unwrap_or(f.v[0])
    }

    /// Number of neighbouring vertices (pbrt-v4's `SDVertex::valence`).
    fn valence(&self, v: u32) -> usize {
        let vert = &self.verts[v as usize];
        let limit = self.faces.len() + 1;
        let mut f = vert.start_face;
        let mut nf = 1;
        if !vert.boundary {
            loop {
                f = self.next_face(f, v);
                if f == vert.start_face || nf > limit {
                    return nf;
                }
                nf += 1;
            }
        }
        loop {
            f = self.next_face(f, v);
            if f == NONE || nf > limit {
                break;
            }
            nf += 1;
        }
        f = vert.start_face;
        loop {
            f = self.prev_face(f, v);
            if f == NONE || nf > limit {
                break;
            }
            nf += 1;
        }
        nf + 1
    }

    /// The one-ring of neighbour positions, in order around the vertex (boundary vertices:
    /// from one boundary neighbour to the other).
    fn one_ring(&self, v: u32, ring: &mut Vec<Vec3>) {
        ring.clear();
        let vert = &self.verts[v as usize];
        let limit = self.faces.len() + 1;
        if !vert.boundary {
            let mut face = vert.start_face;
            loop {
                ring.push(self.verts[self.next_vert(face, v) as usize].p);
                face = self.next_face(face, v);
                if face == vert.start_face || ring.len() > limit {
                    break;
                }
            }
        } else {
            let mut face = vert.start_face;
            let mut steps = 0;
            loop {
                let f2 = self.next_face(face, v);
                if f2 == NONE || steps > limit {
                    break;
                }
                face = f2;
                steps += 1;
            }
            ring.push(self.verts[self.next_vert(face, v) as usize].p);
            loop {
                ring.push(self.verts[self.prev_vert(face, v) as usize].p);
                face = self.prev_face(face, v);
                if face == NONE || ring.len() > limit {
                    break;
                }
            }
        }
    }

    /// (1 − n·β)·p + β·Σ ring.
    fn weight_one_ring(&self, v: u32, beta: f32, ring: &mut Vec<Vec3>) -> Vec3 {
        self.one_ring(v, ring);
        let p = self.verts[v as usize].p;
        (1.0 - ring.len() as f32 * beta) * p + beta * ring.iter().copied().sum::<Vec3>()
    }

    /// (1 − 2β)·p + β·(first + last boundary neighbour).
    fn weight_boundary(&self, v: u32, beta: f32, ring: &mut Vec<Vec3>) -> Vec3 {
        self.one_ring(v, ring);
        let p = self.verts[v as usize].p;
        (1.0 - 2.0 * beta) * p + beta * (ring[0] + ring[ring.len() - 1])
    }
}

/// Loop's weight for an interior vertex of valence n.
fn beta(valence: usize) -> f32 {
    if valence == 3 { 3.0 / 16.0 } else { 3.0 / (8.0 * valence as f32) }
}

/// The weight that moves a vertex to its limit position.
fn loop_gamma(valence: usize) -> f32 {
    1.0 / (valence as f32 + 3.0 / (8.0 * beta(valence)))
}

fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Subdivides the triangles `indices` over `positions` `levels` times (pbrt-v4's
/// `LoopSubdivide`). Vertices no triangle uses are dropped. Refuses meshes whose edges are
/// shared by more than two triangles or whose neighbouring triangles disagree on their
/// winding, where the one-rings Loop's rules need do not exist; these are
/// [`Error::Invalid`].
pub fn loop_subdivide(positions: &[[f32; 3]], indices: &[u32], levels: u32) -> Result<Subdivided> {
    subdivide(positions, indices, levels).map_err(Error::Invalid)
}

/// [`loop_subdivide`], its errors as plain messages.
fn subdivide(positions: &[[f32; 3]], indices: &[u32], levels: u32) -> Result<Subdivided, String> {
    if indices.is_empty() {
        return Err("no triangles".into());
    }
    // Each level quadruples the triangles: refuse what would not fit in memory.
    let triangles = (indices.len() / 3) as u128 * 4u128.pow(levels);
    if triangles > 1 << 26 {
        return Err(format!(
            "{levels} levels would make {triangles} triangles (nimbus refines to at most 2^26); use fewer \"levels\""
        ));
    }
    // Compact to the vertices faces use.
    let mut remap = vec![NONE; positions.len()];
    let mut verts = Vec::new();
    let mut faces = Vec::with_capacity(indices.len() / 3);
    for (fi, tri) in indices.chunks_exact(3).enumerate() {
        let mut v = [0u32; 3];
        for (slot, &i) in v.iter_mut().zip(tri) {
            let i = i as usize;
            if remap[i] == NONE {
                remap[i] = verts.len() as u32;
                verts.push(Vert { p: Vec3::from(positions[i]), start_face: 0, regular: false, boundary: false });
            }
            *slot = remap[i];
            verts[remap[i] as usize].start_face = fi as u32;
        }
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            return Err(format!("triangle {fi} repeats a vertex"));
        }
        faces.push(Face { v, f: [NONE; 3] });
    }

    // Neighbours: each edge joins at most two faces, traversed in opposite directions.
    let mut open: HashMap<(u32, u32), (u32, usize)> = HashMap::with_capacity(faces.len() * 2);
    let mut closed: HashMap<(u32, u32), ()> = HashMap::new();
    for fi in 0..faces.len() {
        for k in 0..3 {
            let (a, b) = (faces[fi].v[k], faces[fi].v[next(k)]);
            let key = edge_key(a, b);
            if closed.contains_key(&key) {
                return Err(format!("edge between vertices {a} and {b} is shared by more than two triangles"));
            }
            match open.remove(&key) {
                None => {
                    open.insert(key, (fi as u32, k));
                }
                Some((g, kg)) => {
                    if faces[g as usize].v[kg] == a {
                        return Err(format!(
                            "triangles {g} and {fi} are wound in opposite directions (their shared edge runs the same way)"
                        ));
                    }
                    faces[g as usize].f[kg] = fi as u32;
                    faces[fi].f[k] = g;
                    closed.insert(key, ());
                }
            }
        }
    }

    let mut level = Level { verts, faces };
    let mut ring = Vec::with_capacity(16);
    for v in 0..level.verts.len() as u32 {
        let start = level.verts[v as usize].start_face;
        let mut f = start;
        let mut steps = 0;
        loop {
            f = level.next_face(f, v);
            steps += 1;
            if f == NONE || f == start || steps > level.faces.len() {
                break;
            }
        }
        if f != NONE && f != start {
            return Err(format!("the triangles around vertex {v} do not form a fan"));
        }
        let boundary = f == NONE;
        level.verts[v as usize].boundary = boundary;
        let valence = level.valence(v);
        level.verts[v as usize].regular = if boundary { valence == 4 } else { valence == 6 };
    }

    for _ in 0..levels {
        level = refine(&level, &mut ring);
    }

    // Push the vertices to the limit surface.
    let limit: Vec<Vec3> = (0..level.verts.len() as u32)
        .map(|v| {
            if level.verts[v as usize].boundary {
                level.weight_boundary(v, 1.0 / 5.0, &mut ring)
            } else {
                level.weight_one_ring(v, loop_gamma(level.valence(v)), &mut ring)
            }
        })
        .collect();
    for (v, p) in level.verts.iter_mut().zip(&limit) {
        v.p = *p;
    }

    // Limit-surface tangents from the one-ring (pbrt-v4's rules), normal = S × T.
    let normals = (0..level.verts.len() as u32)
        .map(|v| {
            level.one_ring(v, &mut ring);
            let valence = ring.len();
            let p = level.verts[v as usize].p;
            let (s, t) = if !level.verts[v as usize].boundary {
                let mut s = Vec3::ZERO;
                let mut t = Vec3::ZERO;
                for (j, q) in ring.iter().enumerate() {
                    let a = 2.0 * PI * j as f32 / valence as f32;
                    s += a.cos() * *q;
                    t += a.sin() * *q;
                }
                (s, t)
            } else {
                let s = ring[valence - 1] - ring[0];
                let t = match valence {
                    2 => ring[0] + ring[1] - 2.0 * p,
                    3 => ring[1] - p,
                    4 => -ring[0] + 2.0 * ring[1] + 2.0 * ring[2] - ring[3] - 2.0 * p,
                    _ => {
                        let theta = PI / (valence - 1) as f32;
                        let mut t = theta.sin() * (ring[0] + ring[valence - 1]);
                        for (k, q) in ring.iter().enumerate().take(valence - 1).skip(1) {
                            t += (2.0 * theta.cos() - 2.0) * (k as f32 * theta).sin() * *q;
                        }
                        -t
                    }
                };
                (s, t)
            };
            t.cross(s).to_array()
        })
        .collect();

    Ok(Subdivided {
        positions: level.verts.iter().map(|v| v.p.to_array()).collect(),
        normals,
        indices: level.faces.iter().flat_map(|f| f.v).collect(),
    })
}

/// One level of Loop subdivision: every face splits into four (children 0–2 at its corners,
/// 3 in the middle); vertex i of the new level is the child of old vertex i, edge vertices
/// follow.
fn refine(old: &Level, ring: &mut Vec<Vec3>) -> Level {
    let nv = old.verts.len();
    let mut verts: Vec<Vert> = Vec::with_capacity(nv * 4);
    // Even vertices: Loop's one-ring rule inside, the boundary rule on open edges.
    for v in 0..nv as u32 {
        let o = &old.verts[v as usize];
        let p = if o.boundary {
            old.weight_boundary(v, 1.0 / 8.0, ring)
        } else if o.regular {
            old.weight_one_ring(v, 1.0 / 16.0, ring)
        } else {
            old.weight_one_ring(v, beta(old.valence(v)), ring)
        };
        // The child's first face: the corner child of the old start face.
        let start_face = 4 * o.start_face + old.vnum(o.start_face, v) as u32;
        verts.push(Vert { p, start_face, regular: o.regular, boundary: o.boundary });
    }
    // Odd (edge) vertices: 3/8 of the edge's ends and 1/8 of the opposite corners, or the
    // midpoint on a boundary.
    let mut edge_verts: HashMap<(u32, u32), u32> = HashMap::with_capacity(old.faces.len() * 2);
    for (fi, face) in old.faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (face.v[k], face.v[next(k)]);
            edge_verts.entry(edge_key(a, b)).or_insert_with(|| {
                let (pa, pb) = (old.verts[a as usize].p, old.verts[b as usize].p);
                let boundary = face.f[k] == NONE;
                let p = if boundary {
                    0.5 * pa + 0.5 * pb
                } else {
                    let c = old.verts[old.other_vert(fi as u32, a, b) as usize].p;
                    let d = old.verts[old.other_vert(face.f[k], a, b) as usize].p;
                    3.0 / 8.0 * (pa + pb) + 1.0 / 8.0 * (c + d)
                };
                verts.push(Vert { p, start_face: 4 * fi as u32 + 3, regular: true, boundary });
                verts.len() as u32 - 1
            });
        }
    }
    // Children and their neighbours.
    let mut faces = vec![Face { v: [0; 3], f: [NONE; 3] }; old.faces.len() * 4];
    for (fi, face) in old.faces.iter().enumerate() {
        let child = |j: usize| 4 * fi + j;
        for j in 0..3 {
            faces[child(3)].f[j] = child(next(j)) as u32;
            faces[child(j)].f[next(j)] = child(3) as u32;
            let f2 = face.f[j];
            faces[child(j)].f[j] = if f2 == NONE { NONE } else { 4 * f2 + old.vnum(f2, face.v[j]) as u32 };
            let f2 = face.f[prev(j)];
            faces[child(j)].f[prev(j)] = if f2 == NONE { NONE } else { 4 * f2 + old.vnum(f2, face.v[j]) as u32 };
        }
        for j in 0..3 {
            faces[child(j)].v[j] = face.v[j];
            let vert = edge_verts[&edge_key(face.v[j], face.v[next(j)])];
            faces[child(j)].v[next(j)] = vert;
            faces[child(next(j))].v[j] = vert;
            faces[child(3)].v[j] = vert;
        }
    }
    Level { verts, faces }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An octahedron: every vertex has valence 4, so none is regular.
    fn octahedron() -> (Vec<[f32; 3]>, Vec<u32>) {
        let p = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let i = vec![0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5];
        (p, i)
    }

    #[test]
    fn each_level_quadruples_the_triangles_of_a_closed_mesh_and_keeps_it_closed() {
        let (p, i) = octahedron();
        for levels in 0..4 {
            let s = loop_subdivide(&p, &i, levels).unwrap();
            let f = 8 * 4usize.pow(levels);
            assert_eq!(s.indices.len(), 3 * f);
            // Euler: V − E + F = 2 with E = 3F/2.
            assert_eq!(s.positions.len() as i64 - (3 * f / 2) as i64 + f as i64, 2);
        }
    }

    #[test]
    fn the_limit_surface_is_smooth_symmetric_and_oriented_with_its_winding() {
        let (p, i) = octahedron();
        let s = loop_subdivide(&p, &i, 3).unwrap();
        // The octahedron's symmetry survives: the six original vertices' limit points are
        // equidistant from the centre and inside the octahedron. Every limit normal is
        // radial and points out of the counter-clockwise-wound mesh (pbrt-v4's would point
        // in: see the module's documentation).
        let r0 = Vec3::from(s.positions[0]).length();
        for k in 0..6 {
            let q = Vec3::from(s.positions[k]);
            assert!((q.length() - r0).abs() < 1e-5 && r0 < 1.0 && r0 > 0.3, "{q}");
        }
        for (q, n) in s.positions.iter().zip(&s.normals) {
            let (q, n) = (Vec3::from(*q), Vec3::from(*n).normalize());
            assert!(n.dot(q.normalize()) > 0.8, "normal {n} at {q}");
        }
    }

    #[test]
    fn a_flat_open_patch_stays_flat_and_keeps_its_boundary() {
        // Two triangles of the square [0, 1]² in z = 0: boundary rules keep the corners'
        // neighbourhoods on the square's edges, and everything stays in the plane.
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let i = vec![0, 1, 2, 0, 2, 3];
        let s = loop_subdivide(&p, &i, 2).unwrap();
        assert_eq!(s.indices.len(), 3 * 2 * 16);
        for (q, n) in s.positions.iter().zip(&s.normals) {
            assert!(q[2].abs() < 1e-6 && (0.0..=1.0).contains(&q[0]) && (0.0..=1.0).contains(&q[1]), "{q:?}");
            let n = Vec3::from(*n).normalize();
            assert!((n.z.abs() - 1.0).abs() < 1e-5, "{n}");
        }
    }

    #[test]
    fn broken_topology_is_refused() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
        // Three triangles on the edge 0–1.
        let e = loop_subdivide(&p, &[0, 1, 2, 1, 0, 3, 0, 1, 4], 1).unwrap_err();
        assert!(e.to_string().contains("more than two"), "{e}");
        // Two triangles wound the same way across an edge.
        let e = loop_subdivide(&p, &[0, 1, 2, 0, 1, 3], 1).unwrap_err();
        assert!(e.to_string().contains("opposite directions"), "{e}");
        assert!(loop_subdivide(&p, &[0, 0, 1], 1).unwrap_err().to_string().contains("repeats"));
        assert!(loop_subdivide(&p, &[0, 1, 2], 14).unwrap_err().to_string().contains("levels"));
    }
}
