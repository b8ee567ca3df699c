//! PLY mesh files (ASCII and binary, optionally gzipped), as pbrt-v4's `plymesh` reads them:
//! vertex positions, optional normals and texture coordinates, and faces of 3 or 4 vertices
//! (quads are kept as pbrt-v4's bilinear patches).

use std::io::Read;
use std::path::Path;

use super::MeshData;
use crate::error::{Error, Result};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    BinaryLittle,
    BinaryBig,
}

/// Reads values from the body in the file's format.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    format: Format,
}

impl Body<'_> {
    fn value(&mut self, t: Scalar) -> Result<f64, String> {
        if self.format == Format::Ascii {
            while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            let start = self.pos;
            while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            let tok =
                std::str::from_utf8(&self.data[start..self.pos]).map_err(|_| "invalid text in body".to_string())?;
            if tok.is_empty() {
                return Err("file ends before all elements are read".into());
            }
            return tok.parse::<f64>().map_err(|_| format!("\"{tok}\" is not a number"));
        }
        let n = t.size();
        if self.pos + n > self.data.len() {
            return Err("file ends before all elements are read".into());
        }
        let b = &self.data[self.pos..self.pos + n];
        self.pos += n;
        let big = self.format == Format::BinaryBig;
        macro_rules! get {
            ($ty:ty) => {{
                let arr: [u8; std::mem::size_of::<$ty>()] = b.try_into().expect("sized");
                (if big { <$ty>::from_be_bytes(arr) } else { <$ty>::from_le_bytes(arr) }) as f64
            }};
        }
        Ok(match t {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => get!(i16),
            Scalar::U16 => get!(u16),
            Scalar::I32 => get!(i32),
            Scalar::U32 => get!(u32),
            Scalar::F32 => get!(f32),
            Scalar::F64 => get!(f64),
        })
    }
}

/// Reads a PLY file (`.ply` or `.ply.gz`). The errors name the file; callers add the scene
/// location.
pub fn read_ply(path: &Path) -> Result<MeshData> {
    let mut data = Vec::new();
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, "read", e))?;
    if path.extension().is_some_and(|x| x == "gz") {
        flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file)).read_to_end(&mut data)
    } else {
        std::io::BufReader::new(file).read_to_end(&mut data)
    }
    .map_err(|e| match e.kind() {
        // The gzip decoder reports a corrupt or truncated stream as an I/O error.
        std::io::ErrorKind::InvalidData | std::io::ErrorKind::InvalidInput | std::io::ErrorKind::UnexpectedEof => {
            Error::malformed(path, e.to_string())
        }
        _ => Error::io(path, "read", e),
    })?;
    parse(&data).map_err(|m| Error::malformed(path, m))
}

/// Parses PLY bytes. Having no file to name, the errors are [`Error::Invalid`] with the
/// message alone.
pub fn parse_ply(data: &[u8]) -> Result<MeshData> {
    parse(data).map_err(Error::Invalid)
}

/// [`parse_ply`] with the message alone, for [`read_ply`] to name the file.
fn parse(data: &[u8]) -> Result<MeshData, String> {
    let header_end = find_header_end(data).ok_or("not a PLY file (no end_header)")?;
    let header = std::str::from_utf8(&data[..header_end.0]).map_err(|_| "PLY header is not text")?;
    let mut lines = header.lines();
    if lines.next().map(str::trim) != Some("ply") {
        return Err("not a PLY file (missing \"ply\" magic)".into());
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLittle,
                    "binary_big_endian" => Format::BinaryBig,
                    other => return Err(format!("unknown PLY format \"{other}\"")),
                })
            }
            ["element", name, count] => elements.push(Element {
                name: name.to_string(),
                count: count.parse().map_err(|_| format!("bad element count \"{count}\""))?,
                properties: Vec::new(),
            }),
            ["property", "list", ct, it, name] => {
                let el = elements.last_mut().ok_or("property before any element")?;
                let ct = Scalar::parse(ct).ok_or_else(|| format!("unknown PLY type \"{ct}\""))?;
                let it = Scalar::parse(it).ok_or_else(|| format!("unknown PLY type \"{it}\""))?;
                el.properties.push(Property::List(name.to_string(), ct, it));
            }
            ["property", t, name] => {
                let el = elements.last_mut().ok_or("property before any element")?;
                let t = Scalar::parse(t).ok_or_else(|| format!("unknown PLY type \"{t}\""))?;
                el.properties.push(Property::Scalar(name.to_string(), t));
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["end_header"] => break,
            _ => return Err(format!("unrecognised PLY header line \"{line}\"")),
        }
    }
    let format = format.ok_or("PLY header has no format line")?;
    let mut body = Body { data, pos: header_end.1, format };
    let mut mesh = MeshData::default();
    for el in &elements {
        match el.name.as_str() {
            "vertex" => read_vertices(&mut body, el, &mut mesh)?,
            "face" => read_faces(&mut body, el, &mut mesh)?,
            _ => skip_element(&mut body, el)?,
        }
    }
    let n = mesh.positions.len();
    if let Some(&bad) = mesh.indices.iter().chain(&mesh.quads).find(|&&i| i as usize >= n) {
        return Err(format!("face index {bad} out of range ({n} vertices)"));
    }
    Ok(mesh)
}

/// Returns (end of the header text, start of the body).
fn find_header_end(data: &[u8]) -> Option<(usize, usize)> {
    let key = b"end_header";
    let at = data.windows(key.len()).position(|w| w == key)?;
    let mut body = at + key.len();
    if data.get(body) == Some(&b'\r') {
        body += 1;
    }
    if data.get(body) == Some(&b'\n') {
        body += 1;
    }
    Some((at + key.len(), body))
}

fn read_vertices(body: &mut Body<'_>, el: &Element, mesh: &mut MeshData) -> Result<(), String> {
    let index = |names: &[&str]| {
        el.properties.iter().position(|p| matches!(p, Property::Scalar(n, _) if names.contains(&n.as_str())))
    };
    let (x, y, z) = (index(&["x"]), index(&["y"]), index(&["z"]));
    let (Some(x), Some(y), Some(z)) = (x, y, z) else {
        return Err("vertex element lacks x, y, z".into());
    };
    let (nx, ny, nz) = (index(&["nx"]), index(&["ny"]), index(&["nz"]));
    let u = index(&["u", "s", "texture_u", "texture_s"]);
    let v = index(&["v", "t", "texture_v", "texture_t"]);
    let has_n = nx.is_some() && ny.is_some() && nz.is_some();
    let has_uv = u.is_some() && v.is_some();
    mesh.positions.reserve(el.count);
    let mut vals = vec![0.0f64; el.properties.len()];
    for _ in 0..el.count {
        for (i, p) in el.properties.iter().enumerate() {
            vals[i] = match p {
                Property::Scalar(_, t) => body.value(*t)?,
                Property::List(_, ct, it) => {
                    let n = body.value(*ct)? as usize;
                    for _ in 0..n {
                        body.value(*it)?;
                    }
                    0.0
                }
            };
        }
        let pos = [vals[x] as f32, vals[y] as f32, vals[z] as f32];
        if pos.iter().any(|c| !c.is_finite()) {
            return Err(format!("vertex {} has a non-finite position", mesh.positions.len()));
        }
        mesh.positions.push(pos);
        if has_n {
            mesh.normals.push([vals[nx.unwrap()] as f32, vals[ny.unwrap()] as f32, vals[nz.unwrap()] as f32]);
        }
        if has_uv {
            mesh.uvs.push([vals[u.unwrap()] as f32, vals[v.unwrap()] as f32]);
        }
    }
    Ok(())
}

fn read_faces(body: &mut Body<'_>, el: &Element, mesh: &mut MeshData) -> Result<(), String> {
    mesh.indices.reserve(el.count * 3);
    let mut face = Vec::with_capacity(4);
    let has_face_index = el.properties.iter().any(|p| matches!(p, Property::Scalar(name, _) if name == "face_indices"));
    for f in 0..el.count {
        face.clear();
        let mut face_index = 0;
        for p in &el.properties {
            match p {
                Property::List(name, ct, it) if name == "vertex_indices" || name == "vertex_index" => {
                    let n = body.value(*ct)? as usize;
                    for _ in 0..n {
                        let i = body.value(*it)?;
                        if i < 0.0 || i.fract() != 0.0 {
                            return Err(format!("face {f} has invalid vertex index {i}"));
                        }
                        face.push(i as u32);
                    }
                }
                Property::List(_, ct, it) => {
                    let n = body.value(*ct)? as usize;
                    for _ in 0..n {
                        body.value(*it)?;
                    }
                }
                // pbrt-v4's per-face Ptex face ids.
                Property::Scalar(name, t) if name == "face_indices" => {
                    face_index = body.value(*t)? as i32;
                }
                Property::Scalar(_, t) => {
                    body.value(*t)?;
                }
            }
        }
        match face.len() {
            3 => {
                mesh.indices.extend_from_slice(&face);
                if has_face_index {
                    mesh.triangle_faces.push(face_index);
                }
            }
            // pbrt-v4 makes a quad a bilinear patch: p00 = a, p10 = b, p01 = d, p11 = c.
            4 => {
                mesh.quads.extend_from_slice(&[face[0], face[1], face[3], face[2]]);
                if has_face_index {
                    mesh.quad_faces.push(face_index);
                }
            }
            n => {
                return Err(format!("face {f} has {n} vertices; plymesh supports triangles and quads"));
            }
        }
    }
    Ok(())
}

fn skip_element(body: &mut Body<'_>, el: &Element) -> Result<(), String> {
    for _ in 0..el.count {
        for p in &el.properties {
            match p {
                Property::Scalar(_, t) => {
                    body.value(*t)?;
                }
                Property::List(_, ct, it) => {
                    let n = body.value(*ct)? as usize;
                    for _ in 0..n {
                        body.value(*it)?;
                    }
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_quad_becomes_a_bilinear_patch() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let m = parse_ply(text.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert!(m.indices.is_empty());
        assert_eq!(m.quads, vec![0, 1, 3, 2]);
    }

    /// pbrt-v4's per-face `face_indices` (Ptex face ids) reach both triangles and quads.
    #[test]
    fn face_indices_are_kept_per_face() {
        let text = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 2\nproperty list uchar int vertex_indices\nproperty int face_indices\nend_header\n\
                    0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3 7\n3 1 4 2 3\n";
        let m = parse_ply(text.as_bytes()).unwrap();
        assert_eq!((m.quad_faces, m.triangle_faces), (vec![7], vec![3]));
        let without = text.replace("property int face_indices\n", "").replace("3 7\n3 1 4 2 3\n", "3\n3 1 4 2\n");
        let without = parse_ply(without.as_bytes()).unwrap();
        assert!(without.quad_faces.is_empty() && without.triangle_faces.is_empty());
    }

    #[test]
    fn binary_little_endian_with_normals() {
        let mut data = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
            .to_vec();
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for c in v.iter().chain([0.0f32, 0.0, 1.0].iter()) {
                data.extend_from_slice(&c.to_le_bytes());
            }
        }
        data.push(3);
        for i in [0u32, 1, 2] {
            data.extend_from_slice(&i.to_le_bytes());
        }
        let m = parse_ply(&data).unwrap();
        assert_eq!(m.positions[1], [1.0, 0.0, 0.0]);
        assert_eq!(m.normals[2], [0.0, 0.0, 1.0]);
        assert_eq!(m.indices, vec![0, 1, 2]);
    }

    #[test]
    fn truncated_and_out_of_range_files_are_errors() {
        let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
        assert!(parse_ply(text.as_bytes()).unwrap_err().to_string().contains("ends before"));
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 1 2\n";
        assert!(parse_ply(text.as_bytes()).unwrap_err().to_string().contains("out of range"));
        assert!(parse_ply(b"hello").is_err());
    }
}
