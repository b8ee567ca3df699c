//! Geometry shared by shapes and integrators: rays, bounds, mesh file formats and mesh
//! refinement.

mod bounds;
pub mod displace;
pub mod gltf;
pub mod loop_subdiv;
mod motion;
pub mod obj;
pub mod ply;
mod ray;

use crate::error::{Error, Result};

pub use bounds::Bounds3;
pub use motion::MotionTransform;
pub use ray::{Ray, offset_origin, offset_origin_by, position_error, spawn_ray, spawn_ray_to};

/// Triangle mesh data as read from a file, in the file's (object) space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex normals (empty if the file has none).
    pub normals: Vec<[f32; 3]>,
    /// Per-vertex texture coordinates (empty if none).
    pub uvs: Vec<[f32; 2]>,
    /// Triangle vertex indices.
    pub indices: Vec<u32>,
    /// Quads as bilinear patches, four indices each in pbrt-v4's patch order p00, p10, p01,
    /// p11 (a PLY face a b c d becomes a b d c); only PLY files have them.
    pub quads: Vec<u32>,
    /// Per triangle, its `face_indices` value (a Ptex face id); empty if the file has none.
    pub triangle_faces: Vec<i32>,
    /// Per quad, its `face_indices` value; empty if the file has none.
    pub quad_faces: Vec<i32>,
}

impl MeshData {
    /// Checks indices, array lengths and finiteness; `what` prefixes messages. The errors are
    /// [`Error::Invalid`]: `what` names the file where there is one.
    pub fn validate(&self, what: &str) -> Result<()> {
        let n = self.positions.len();
        if let Some(&bad) = self.indices.iter().chain(&self.quads).find(|&&i| i as usize >= n) {
            return Err(Error::Invalid(format!("{what}: vertex index {bad} out of range ({n} vertices)")));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(Error::Invalid(format!("{what}: {} indices is not a multiple of 3", self.indices.len())));
        }
        if self.positions.iter().flatten().any(|c| !c.is_finite()) {
            return Err(Error::Invalid(format!("{what}: non-finite vertex position")));
        }
        if !self.normals.is_empty() && self.normals.len() != n {
            return Err(Error::Invalid(format!("{what}: {} normals for {n} vertices", self.normals.len())));
        }
        if !self.uvs.is_empty() && self.uvs.len() != n {
            return Err(Error::Invalid(format!("{what}: {} texture coordinates for {n} vertices", self.uvs.len())));
        }
        Ok(())
    }
}
