//! Shape settings with pbrt-v4's parameter names and defaults. Mesh arrays are borrowed from
//! the scene description, not copied.

use std::path::PathBuf;

use nimbus_parser::loc_shown as shown;
use nimbus_parser::{Error, FileLoc, ShapeEntity};

use crate::params::{FloatInput, checked_float, checked_int, float_input};
use crate::shapes::{CurveType, cubic_bspline_to_bezier, elevate_quadratic, quadratic_bspline_to_bezier};
use glam::Vec3;

/// A triangle or bilinear-patch mesh given inline.
#[derive(Clone, Debug, PartialEq)]
pub struct InlineMesh<'a> {
    /// Vertex positions (object space).
    pub positions: &'a [[f32; 3]],
    /// Vertex indices: 3 per triangle, or 4 per bilinear patch.
    pub indices: Vec<u32>,
    /// Per-vertex normals (empty if none).
    pub normals: &'a [[f32; 3]],
    /// Per-vertex texture coordinates (empty if none).
    pub uvs: &'a [[f32; 2]],
    /// Per face, its Ptex face id (`faceIndices`; empty if none).
    pub face_indices: Vec<i32>,
}

/// What a shape is.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeKind<'a> {
    /// `sphere`
    Sphere {
        /// Radius.
        radius: f32,
        /// Lower z clip.
        zmin: f32,
        /// Upper z clip.
        zmax: f32,
        /// Sweep in degrees.
        phimax: f32,
    },
    /// `disk`
    Disk {
        /// Height along z.
        height: f32,
        /// Outer radius.
        radius: f32,
        /// Inner radius.
        inner_radius: f32,
        /// Sweep in degrees.
        phimax: f32,
    },
    /// `cylinder`
    Cylinder {
        /// Radius.
        radius: f32,
        /// Lower z.
        zmin: f32,
        /// Upper z.
        zmax: f32,
        /// Sweep in degrees.
        phimax: f32,
    },
    /// `trianglemesh`
    TriangleMesh(InlineMesh<'a>),
    /// `bilinearmesh` (split into two triangles per patch)
    BilinearMesh(InlineMesh<'a>),
    /// `curve`: cubic Bézier segments (degree-2 and B-spline input converted), each with its
    /// widths at its ends and, for ribbons, its end normals.
    Curve {
        /// Bézier control points per segment (object space).
        segments: Vec<[[f32; 3]; 4]>,
        /// Widths at each segment's ends.
        widths: Vec<[f32; 2]>,
        /// End normals per segment (ribbons only).
        normals: Vec<[[f32; 3]; 2]>,
        /// `flat`, `cylinder` or `ribbon`.
        kind: CurveType,
        /// Each segment is split into 2^splitdepth primitives.
        split_depth: u32,
    },
    /// `loopsubdiv`: a control mesh refined at load.
    LoopSubdiv {
        /// The control mesh (`P`, `indices`).
        mesh: InlineMesh<'a>,
        /// Subdivision levels.
        levels: u32,
    },
    /// `plymesh`, with pbrt-v4's displacement: the float texture and the `edgelength` the
    /// mesh is refined to first.
    PlyMesh(PathBuf, Option<(String, f32)>),
    /// `objmesh` (nimbus extension: a Wavefront OBJ file)
    ObjMesh(PathBuf),
    /// `gltfmesh` (nimbus extension: a glTF 2.0 file)
    GltfMesh(PathBuf),
}

/// Everything a shape entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeSettings<'a> {
    /// The geometry.
    pub kind: ShapeKind<'a>,
    /// Alpha (cut-out) value or texture; 1 means opaque.
    pub alpha: FloatInput,
}

fn file_param(shape: &ShapeEntity, kind: &str) -> Result<PathBuf, Error> {
    let p = &shape.entity.params;
    let Some(name) = p.get_opt_string("filename")? else {
        return Err(Error::new(&shape.entity.loc, format!("{kind}: missing \"string filename\"")));
    };
    let loc: &FileLoc = p.loc("filename").unwrap_or(&shape.entity.loc);
    let path = loc.resolve(name);
    if !path.is_file() {
        return Err(Error::new(loc, format!("{kind}: cannot find file \"{name}\" (tried {})", shown(&path))));
    }
    Ok(path)
}

fn inline_mesh<'a>(shape: &'a ShapeEntity, per_face: usize) -> Result<InlineMesh<'a>, Error> {
    let e = &shape.entity;
    let p = &e.params;
    let positions = p.get_point3s("P")?;
    if positions.is_empty() {
        return Err(Error::new(&e.loc, format!("{}: vertex positions \"P\" are missing", e.name)));
    }
    let raw = p.get_ints("indices")?;
    let indices: Vec<u32> = if raw.is_empty() {
        if positions.len() == per_face {
            (0..per_face as u32).collect()
        } else {
            return Err(Error::new(&e.loc, format!("{}: vertex indices \"indices\" are missing", e.name)));
        }
    } else {
        let loc = p.loc("indices").unwrap_or(&e.loc);
        if raw.len() % per_face != 0 {
            return Err(Error::new(loc, format!("{}: {} indices is not a multiple of {per_face}", e.name, raw.len())));
        }
        let mut out = Vec::with_capacity(raw.len());
        for &i in raw {
            if i < 0 || i as usize >= positions.len() {
                return Err(Error::new(
                    loc,
                    format!("{}: index {i} out of range (there are {} vertices)", e.name, positions.len()),
                ));
            }
            out.push(i as u32);
        }
        out
    };
    let normals = p.get_normals("N")?;
    if !normals.is_empty() && normals.len() != positions.len() {
        return Err(Error::new(
            p.loc("N").unwrap_or(&e.loc),
            format!("{}: {} normals for {} vertices", e.name, normals.len(), positions.len()),
        ));
    }
    let uvs = p.get_point2s("uv")?;
    if !uvs.is_empty() && uvs.len() != positions.len() {
        return Err(Error::new(
            p.loc("uv").unwrap_or(&e.loc),
            format!("{}: {} uvs for {} vertices", e.name, uvs.len(), positions.len()),
        ));
    }
    if per_face == 3 {
        let s = p.get_vector3s("S")?;
        if !s.is_empty() && s.len() != positions.len() {
            return Err(Error::new(
                p.loc("S").unwrap_or(&e.loc),
                format!("{}: {} tangents for {} vertices", e.name, s.len(), positions.len()),
            ));
        }
    }
    let face_indices = p.get_ints("faceIndices")?;
    if !face_indices.is_empty() && face_indices.len() != indices.len() / per_face {
        return Err(Error::new(
            p.loc("faceIndices").unwrap_or(&e.loc),
            format!("{}: {} face indices for {} faces", e.name, face_indices.len(), indices.len() / per_face),
        ));
    }
    Ok(InlineMesh { positions, indices, normals, uvs, face_indices: face_indices.to_vec() })
}

/// pbrt-v4's `Curve::Create`: degree 2 or 3, Bézier or uniform B-spline control points, every
/// segment converted to a cubic Bézier curve, widths interpolated along the whole curve.
fn curve<'a>(shape: &ShapeEntity) -> Result<ShapeKind<'a>, Error> {
    let e = &shape.entity;
    let p = &e.params;
    let at = |name: &str| p.loc(name).unwrap_or(&e.loc);
    let width = p.get_one_float("width", 1.0)?;
    let width0 = p.get_one_float("width0", width)?;
    let width1 = p.get_one_float("width1", width)?;
    if !(width0 >= 0.0 && width1 >= 0.0 && width0.is_finite() && width1.is_finite()) {
        return Err(Error::new(at("width"), "curve: widths must be finite and not negative"));
    }
    let degree = p.get_one_int("degree", 3)?;
    if degree != 2 && degree != 3 {
        return Err(Error::new(at("degree"), format!("curve: degree {degree} (pbrt-v4 has 2 and 3)")));
    }
    let degree = degree as usize;
    let basis = p.get_one_string("basis", "bezier")?;
    let cp: Vec<Vec3> = p.get_point3s("P")?.iter().map(|q| Vec3::from(*q)).collect();
    let n_segments = match basis {
        "bezier" => {
            if cp.len() < degree + 1 || !(cp.len() - 1 - degree).is_multiple_of(degree) {
                return Err(Error::new(
                    at("P"),
                    format!(
                        "curve: {} control points; a degree-{degree} Bézier curve needs {} + n·{degree}",
                        cp.len(),
                        degree + 1
                    ),
                ));
            }
            (cp.len() - 1) / degree
        }
        "bspline" => {
            if cp.len() < degree + 1 {
                return Err(Error::new(
                    at("P"),
                    format!(
                        "curve: {} control points; a degree-{degree} B-spline needs at least {}",
                        cp.len(),
                        degree + 1
                    ),
                ));
            }
            cp.len() - degree
        }
        other => {
            return Err(Error::new(at("basis"), format!("curve: unknown basis \"{other}\" (bezier or bspline)")));
        }
    };
    let kind = match p.get_one_string("type", "flat")? {
        "flat" => CurveType::Flat,
        "ribbon" => CurveType::Ribbon,
        "cylinder" => CurveType::Cylinder,
        other => {
            return Err(Error::new(at("type"), format!("curve: unknown type \"{other}\" (flat, ribbon or cylinder)")));
        }
    };
    let n = p.get_normals("N")?;
    let normals: Vec<[[f32; 3]; 2]> = match kind {
        CurveType::Ribbon if n.len() == n_segments + 1 => (0..n_segments).map(|s| [n[s], n[s + 1]]).collect(),
        CurveType::Ribbon => {
            return Err(Error::new(
                at("N"),
                format!(
                    "curve: a ribbon with {n_segments} segments needs {} normals \"N\", not {}",
                    n_segments + 1,
                    n.len()
                ),
            ));
        }
        // pbrt-v4 ignores normals on other types (with a warning).
        _ => Vec::new(),
    };
    let split_depth = p.get_one_int("splitdepth", 3)?;
    if !(0..=12).contains(&split_depth) {
        return Err(Error::new(at("splitdepth"), "curve: \"splitdepth\" must be between 0 and 12"));
    }
    let mut segments = Vec::with_capacity(n_segments);
    let mut widths = Vec::with_capacity(n_segments);
    for seg in 0..n_segments {
        let bezier = if basis == "bezier" {
            let o = seg * degree;
            if degree == 2 {
                elevate_quadratic([cp[o], cp[o + 1], cp[o + 2]])
            } else {
                [cp[o], cp[o + 1], cp[o + 2], cp[o + 3]]
            }
        } else if degree == 2 {
            elevate_quadratic(quadratic_bspline_to_bezier([cp[seg], cp[seg + 1], cp[seg + 2]]))
        } else {
            cubic_bspline_to_bezier([cp[seg], cp[seg + 1], cp[seg + 2], cp[seg + 3]])
        };
        segments.push(bezier.map(|q| q.to_array()));
        let f = |k: usize| k as f32 / n_segments as f32;
        widths.push([(1.0 - f(seg)) * width0 + f(seg) * width1, (1.0 - f(seg + 1)) * width0 + f(seg + 1) * width1]);
    }
    Ok(ShapeKind::Curve { segments, widths, normals, kind, split_depth: split_depth as u32 })
}

impl<'a> ShapeSettings<'a> {
    /// Reads a shape entity. Shapes nimbus lacks are reported by name.
    pub fn from_entity(shape: &'a ShapeEntity) -> Result<ShapeSettings<'a>, Error> {
        let e = &shape.entity;
        let p = &e.params;
        let positive = |v: f32| v > 0.0;
        let phimax = |p: &nimbus_parser::ParameterDictionary| -> Result<f32, Error> {
            checked_float(p, "phimax", 360.0, |v| v > 0.0 && v <= 360.0, "phimax must be in (0, 360] degrees")
        };
        let kind = match e.name.as_str() {
            "sphere" => {
                let radius = checked_float(p, "radius", 1.0, positive, "the radius must be positive")?;
                let zmin = p.get_one_float("zmin", -radius)?;
                let zmax = p.get_one_float("zmax", radius)?;
                ShapeKind::Sphere { radius, zmin, zmax, phimax: phimax(p)? }
            }
            "disk" => ShapeKind::Disk {
                height: p.get_one_float("height", 0.0)?,
                radius: checked_float(p, "radius", 1.0, positive, "the radius must be positive")?,
                inner_radius: checked_float(
                    p,
                    "innerradius",
                    0.0,
                    |v| v >= 0.0,
                    "the inner radius cannot be negative",
                )?,
                phimax: phimax(p)?,
            },
            "cylinder" => ShapeKind::Cylinder {
                radius: checked_float(p, "radius", 1.0, positive, "the radius must be positive")?,
                zmin: p.get_one_float("zmin", -1.0)?,
                zmax: p.get_one_float("zmax", 1.0)?,
                phimax: phimax(p)?,
            },
            "trianglemesh" => ShapeKind::TriangleMesh(inline_mesh(shape, 3)?),
            "bilinearmesh" => ShapeKind::BilinearMesh(inline_mesh(shape, 4)?),
            "curve" => curve(shape)?,
            "loopsubdiv" => ShapeKind::LoopSubdiv {
                mesh: inline_mesh(shape, 3)?,
                // pbrt-v4's default; each level quadruples the triangles, so 12 (16 M per
                // control triangle) bounds what fits in memory.
                levels: checked_int(p, "levels", 3, |v| (0..=12).contains(&v), "must be between 0 and 12")? as u32,
            },
            "plymesh" => {
                let edge = checked_float(p, "edgelength", 1.0, positive, "the edge length must be positive")?;
                let displacement = p.get_texture("displacement")?.map(|d| (d.to_string(), edge));
                ShapeKind::PlyMesh(file_param(shape, "plymesh")?, displacement)
            }
            "objmesh" => ShapeKind::ObjMesh(file_param(shape, "objmesh")?),
            "gltfmesh" => ShapeKind::GltfMesh(file_param(shape, "gltfmesh")?),
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "shape \"{other}\" is not supported by nimbus (it has sphere, disk, cylinder, trianglemesh, bilinearmesh, loopsubdiv, curve, plymesh, and the extensions objmesh and gltfmesh)"
                    ),
                ));
            }
        };
        let alpha = float_input(p, "alpha")?.unwrap_or(FloatInput::Value(1.0));
        Ok(ShapeSettings { kind, alpha })
    }
}
