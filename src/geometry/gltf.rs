//! glTF 2.0 meshes for nimbus's `gltfmesh` shape (a nimbus extension): the triangle
//! primitives of every mesh in the default scene, with node transforms applied.

use std::path::Path;

use glam::{Mat3, Mat4, Vec3};

use super::MeshData;
use crate::error::{Error, Result};

/// Reads the triangle meshes of a `.gltf`/`.glb` file's default scene, in scene space.
pub fn read_gltf(path: &Path) -> Result<Vec<MeshData>> {
    let gltf = gltf::Gltf::open(path).map_err(|e| Error::malformed(path, format!("gltfmesh: {e}")))?;
    let buffers = load_buffers(&gltf, path)?;
    let doc = gltf.document;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| Error::malformed(path, "gltfmesh: no scene"))?;
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let m = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            let nm = Mat3::from_mat4(m).inverse().transpose();
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    return Err(Error::malformed(path, "gltfmesh: only triangle primitives are supported"));
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
                let positions: Vec<[f32; 3]> = reader
                    .read_positions()
                    .ok_or_else(|| Error::malformed(path, "gltfmesh: primitive without positions"))?
                    .map(|p| m.transform_point3(Vec3::from(p)).into())
                    .collect();
                let normals: Vec<[f32; 3]> = reader
                    .read_normals()
                    .map(|it| it.map(|n| (nm * Vec3::from(n)).normalize_or_zero().into()).collect())
                    .unwrap_or_default();
                let uvs: Vec<[f32; 2]> = reader.read_tex_coords(0).map(|t| t.into_f32().collect()).unwrap_or_default();
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                let data = MeshData { positions, normals, uvs, indices, ..Default::default() };
                data.validate(&format!("gltfmesh: {}", path.display()))?;
                out.push(data);
            }
        }
        stack.extend(node.children().map(|c| (c, m)));
    }
    if out.is_empty() {
        return Err(Error::malformed(path, "gltfmesh: no meshes in the scene"));
    }
    Ok(out)
}

/// Buffer data: the GLB blob, external `.bin` files (relative to the glTF file) or base64
/// `data:` URIs. Textures are not needed, so images are never read.
fn load_buffers(gltf: &gltf::Gltf, path: &Path) -> Result<Vec<Vec<u8>>> {
    let dir = path.parent().unwrap_or(Path::new("."));
    gltf.document
        .buffers()
        .map(|b| {
            let data = match b.source() {
                gltf::buffer::Source::Bin => {
                    gltf.blob.clone().ok_or_else(|| Error::malformed(path, "gltfmesh: missing binary chunk"))?
                }
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    let (_, payload) = uri
                        .split_once(";base64,")
                        .ok_or_else(|| Error::malformed(path, "gltfmesh: unsupported data URI"))?;
                    base64_decode(payload).ok_or_else(|| Error::malformed(path, "gltfmesh: invalid base64 buffer"))?
                }
                gltf::buffer::Source::Uri(uri) => {
                    let file = dir.join(uri.replace("%20", " "));
                    std::fs::read(&file).map_err(|e| Error::io(&file, "read the glTF buffer", e))?
                }
            };
            if data.len() < b.length() {
                return Err(Error::malformed(path, format!("gltfmesh: buffer {} is shorter than declared", b.index())));
            }
            Ok(data)
        })
        .collect()
}

fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => (c - b'A') as u32,
            b'a'..=b'z' => (c - b'a' + 26) as u32,
            b'0'..=b'9' => (c - b'0' + 52) as u32,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        })
    };
    let bytes: Vec<u8> = s.bytes().filter(|c| !c.is_ascii_whitespace() && *c != b'=').collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * i);
        }
        let n = chunk.len();
        if n < 2 {
            return None;
        }
        out.push((acc >> 16) as u8);
        if n > 2 {
            out.push((acc >> 8) as u8);
        }
        if n > 3 {
            out.push(acc as u8);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes() {
        assert_eq!(base64_decode("TWFu").unwrap(), b"Man");
        assert_eq!(base64_decode("TWE=").unwrap(), b"Ma");
        assert!(base64_decode("T!==").is_none());
    }

    #[test]
    fn reads_an_embedded_triangle() {
        // One triangle: 3 float3 positions (36 bytes) in a data URI.
        let mut bin = Vec::new();
        for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
        const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut b64 = String::new();
        for c in bin.chunks(3) {
            let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
            for i in 0..4 {
                if i <= c.len() { b64.push(T[(n >> (18 - 6 * i) & 63) as usize] as char) } else { b64.push('=') }
            }
        }
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"translation":[0,0,2]}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],
            "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
        );
        let dir = std::env::temp_dir().join(format!("nimbus-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tri.gltf");
        std::fs::write(&path, json).unwrap();
        let meshes = read_gltf(&path);
        std::fs::remove_dir_all(&dir).unwrap();
        let meshes = meshes.unwrap();
        assert_eq!(meshes[0].positions[1], [1.0, 0.0, 2.0]);
        assert_eq!(meshes[0].indices, vec![0, 1, 2]);
    }
}
