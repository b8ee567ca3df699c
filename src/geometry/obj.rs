//! Wavefront OBJ meshes for nimbus's `objmesh` shape (a nimbus extension), read with tobj.

use std::path::Path;

use super::MeshData;
use crate::error::{Error, Result};

/// Reads every object of an OBJ file as a triangle mesh (polygons are triangulated).
pub fn read_obj(path: &Path) -> Result<Vec<MeshData>> {
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, _materials) =
        tobj::load_obj(path, &options).map_err(|e| Error::malformed(path, format!("objmesh: {e}")))?;
    let mut out = Vec::with_capacity(models.len());
    for m in models {
        let mesh = m.mesh;
        let data = MeshData {
            positions: mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            normals: mesh.normals.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            uvs: mesh.texcoords.chunks_exact(2).map(|c| [c[0], c[1]]).collect(),
            indices: mesh.indices,
            ..Default::default()
        };
        data.validate(&format!("objmesh: {}: object \"{}\"", path.display(), m.name))?;
        out.push(data);
    }
    if out.iter().all(|m| m.indices.is_empty()) {
        return Err(Error::malformed(path, "objmesh: no faces"));
    }
    Ok(out)
}
