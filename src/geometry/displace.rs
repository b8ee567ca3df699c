//! pbrt-v4's displaced `plymesh` (`TriQuadMesh::Displace`): quads split into triangles, every
//! triangle refined by splitting its longest edge at the midpoint until all edges are shorter
//! than `edgelength` (measured after the shape's transform), each vertex moved along its normal
//! by the displacement texture at its (p, uv), and the normals computed again from the result.

use std::collections::HashMap;

use glam::{Affine3A, Vec2, Vec3};

use super::MeshData;

/// The most triangles a refinement may make: beyond it the `edgelength` is too small for the
/// mesh (each halving of it quadruples the count), and the error says so.
const MAX_TRIANGLES: usize = 1 << 26;

/// `mesh` refined to edges shorter than `edge_length` in world space (`world` maps the mesh's
/// points there) and displaced along its normals by `displacement(p, uv)`, both in the mesh's
/// own space, as pbrt-v4 evaluates the texture.
pub fn displace(
    mesh: &MeshData,
    world: &Affine3A,
    edge_length: f32,
    displacement: impl Fn(Vec3, Vec2) -> f32,
) -> crate::error::Result<MeshData> {
    if mesh.uvs.is_empty() {
        return Err(crate::error::Error::invalid(
            "displacement needs per-vertex uv coordinates, which this mesh does not have (pbrt-v4 requires them too)",
        ));
    }
    let mut p: Vec<Vec3> = mesh.positions.iter().map(|&v| Vec3::from(v)).collect();
    let mut uv: Vec<Vec2> = mesh.uvs.iter().map(|&v| Vec2::from(v)).collect();
    // The triangles, quads last, each as pbrt-v4's `ConvertToOnlyTriangles` splits a patch
    // (p00, p10, p01, p11): (p00, p10, p11) and (p00, p11, p01).
    let mut tris = mesh.indices.clone();
    for q in mesh.quads.chunks_exact(4) {
        tris.extend_from_slice(&[q[0], q[1], q[3], q[0], q[3], q[2]]);
    }
    let mut n: Vec<Vec3> = if mesh.normals.is_empty() {
        vertex_normals(&p, &tris)
    } else {
        mesh.normals.iter().map(|&v| Vec3::from(v)).collect()
    };
    let dist = |a: Vec3, b: Vec3| world.transform_point3(a).distance(world.transform_point3(b));
    let mut out = Vec::with_capacity(tris.len());
    let mut split: HashMap<(u32, u32), u32> = HashMap::new();
    // Pending triangles, depth first in pbrt-v4's order (its recursion, written as a stack).
    let mut stack = Vec::new();
    for t in tris.chunks_exact(3) {
        stack.push([t[0], t[1], t[2]]);
        while let Some([v0, v1, v2]) = stack.pop() {
            let (p0, p1, p2) = (p[v0 as usize], p[v1 as usize], p[v2 as usize]);
            let (d01, d12, d20) = (dist(p0, p1), dist(p1, p2), dist(p2, p0));
            if d01 < edge_length && d12 < edge_length && d20 < edge_length {
                out.extend_from_slice(&[v0, v1, v2]);
                if out.len() / 3 > MAX_TRIANGLES {
                    return Err(crate::error::Error::Invalid(format!(
                        "displacement with \"edgelength\" {edge_length} makes more than {MAX_TRIANGLES} triangles; give a larger one"
                    )));
                }
                continue;
            }
            // The longest edge first (v[0], v[1]), as pbrt-v4 orders them.
            let v = if d01 > d12 {
                if d01 > d20 { [v0, v1, v2] } else { [v2, v0, v1] }
            } else if d12 > d20 {
                [v1, v2, v0]
            } else {
                [v2, v0, v1]
            };
            let key = (v[0].min(v[1]), v[0].max(v[1]));
            let mid = *split.entry(key).or_insert_with(|| {
                let (a, b) = (v[0] as usize, v[1] as usize);
                p.push((p[a] + p[b]) / 2.0);
                n.push((n[a] + n[b]).try_normalize().unwrap_or(n[a] + n[b]));
                uv.push((uv[a] + uv[b]) / 2.0);
                p.len() as u32 - 1
            });
            // pbrt-v4 refines (v0, mid, v2) before (mid, v1, v2): pushed in reverse.
            stack.push([mid, v[1], v[2]]);
            stack.push([v[0], mid, v[2]]);
        }
    }
    for i in 0..p.len() {
        let d = displacement(p[i], uv[i]);
        p[i] += d * n[i];
    }
    let normals = vertex_normals(&p, &out);
    Ok(MeshData {
        positions: p.iter().map(|v| v.to_array()).collect(),
        normals: normals.iter().map(|v| v.to_array()).collect(),
        uvs: uv.iter().map(|v| v.to_array()).collect(),
        indices: out,
        ..Default::default()
    })
}

/// pbrt-v4's `TriQuadMesh::ComputeNormals`: the sum of the unit normals of the triangles
/// around each vertex, normalised (zero where there are none).
fn vertex_normals(p: &[Vec3], tris: &[u32]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; p.len()];
    for t in tris.chunks_exact(3) {
        let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
        if let Some(f) = (p[b] - p[a]).cross(p[c] - p[b]).try_normalize() {
            n[a] += f;
            n[b] += f;
            n[c] += f;
        }
    }
    n.iter().map(|v| v.try_normalize().unwrap_or(*v)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit quad in the xy plane, uv = xy.
    fn quad() -> MeshData {
        MeshData {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
            normals: Vec::new(),
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
            indices: Vec::new(),
            quads: vec![0, 1, 2, 3],
            ..Default::default()
        }
    }

    /// Refinement splits until every edge (after the transform) is shorter than the limit,
    /// shares the midpoints of common edges (no cracks), and keeps the area and the winding.
    #[test]
    fn refinement_meets_the_edge_length_without_cracks() {
        let world = Affine3A::from_scale(Vec3::splat(2.0));
        let m = displace(&quad(), &world, 0.3, |_, _| 0.0).unwrap();
        let p: Vec<Vec3> = m.positions.iter().map(|&v| Vec3::from(v)).collect();
        let mut area = 0.0;
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]];
            for (x, y) in [(a, b), (b, c), (c, a)] {
                assert!(2.0 * x.distance(y) < 0.3);
            }
            let cross = (b - a).cross(c - a);
            assert!(cross.z > 0.0, "winding kept");
            area += 0.5 * cross.length();
        }
        assert!((area - 1.0).abs() < 1e-5);
        // No two vertices at the same place: shared edges were split once.
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                assert!(p[i].distance(p[j]) > 1e-6, "duplicate vertex {i} {j}");
            }
        }
    }

    /// Each vertex moves along its normal by the texture at its (p, uv); the normals are
    /// then the displaced surface's: a plane displaced by a ramp in u tilts by its slope.
    #[test]
    fn vertices_move_along_their_normals() {
        let m = displace(&quad(), &Affine3A::IDENTITY, 0.26, |_, uv| 0.5 * uv.x).unwrap();
        for (p, uv) in m.positions.iter().zip(&m.uvs) {
            assert!((p[2] - 0.5 * uv[0]).abs() < 1e-6, "{p:?} {uv:?}");
        }
        let tilt = Vec3::new(-0.5, 0.0, 1.0).normalize();
        for n in &m.normals {
            assert!((Vec3::from(*n) - tilt).length() < 1e-5, "{n:?}");
        }
        let mut no_uv = quad();
        no_uv.uvs.clear();
        assert!(displace(&no_uv, &Affine3A::IDENTITY, 0.1, |_, _| 0.0).unwrap_err().to_string().contains("uv"));
    }
}
