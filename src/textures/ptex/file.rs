//! Ptex files (Burley and Lacewell 2008; the format of Disney's Ptex library, version 1): a
//! texture per face of a mesh, each with its own resolution and its neighbours' ids, so
//! filters can cross face edges. Read whole into memory, texels kept in the file's own type;
//! the library's reductions (its MIP levels, anisotropic ones made on demand) are reproduced
//! with its rounding, since its filter reads them.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;
use std::sync::{Arc, RwLock};

pub use super::texels::{Texel, Texels};
use super::texels::{interleave, reduce, reduce_triangle, texels_from};
use crate::error::{Error, Result};

/// A texel's storage type (Ptex's `DataType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataType {
    /// 8-bit unsigned, 255 is 1.
    U8,
    /// 16-bit unsigned, 65535 is 1.
    U16,
    /// IEEE half float.
    Half,
    /// 32-bit float.
    F32,
}

impl DataType {
    fn size(self) -> usize {
        match self {
            DataType::U8 => 1,
            DataType::U16 | DataType::Half => 2,
            DataType::F32 => 4,
        }
    }

    /// The stored value that stands for 1 (Ptex's `OneValue`).
    pub fn one(self) -> f32 {
        match self {
            DataType::U8 => 255.0,
            DataType::U16 => 65535.0,
            DataType::Half | DataType::F32 => 1.0,
        }
    }
}

/// What lookups beyond a face's edge without a neighbour read (Ptex's `BorderMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BorderMode {
    /// The edge texels.
    Clamp,
    /// Black.
    Black,
    /// The face's other side.
    Periodic,
}

/// A face resolution as log₂ texels per axis (Ptex's `Res`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Res {
    /// log₂ of the u resolution.
    pub ulog2: i8,
    /// log₂ of the v resolution.
    pub vlog2: i8,
}

impl Res {
    /// A resolution from its logs.
    pub const fn new(ulog2: i8, vlog2: i8) -> Res {
        Res { ulog2, vlog2 }
    }

    /// Texels along u.
    #[inline]
    pub fn u(self) -> i32 {
        1 << self.ulog2
    }

    /// Texels along v.
    #[inline]
    pub fn v(self) -> i32 {
        1 << self.vlog2
    }

    /// The resolution with u and v exchanged.
    pub fn swapped(self) -> Res {
        Res::new(self.vlog2, self.ulog2)
    }
}

/// A face's resolution, neighbours and flags (Ptex's `FaceInfo`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceInfo {
    /// Resolution.
    pub res: Res,
    /// Per edge (bottom, right, top, left), the neighbour's edge it meets, 2 bits each.
    adjedges: u8,
    flags: u8,
    /// Per edge, the neighbouring face, or −1.
    adjfaces: [i32; 4],
}

impl FaceInfo {
    const CONSTANT: u8 = 1;
    const HAS_EDITS: u8 = 2;
    const NEIGHBOURHOOD_CONSTANT: u8 = 4;
    const SUBFACE: u8 = 8;

    /// The face across edge `eid` (0 bottom, 1 right, 2 top, 3 left), or −1.
    #[inline]
    pub fn adjface(&self, eid: i32) -> i32 {
        self.adjfaces[(eid & 3) as usize]
    }

    /// The edge of [`FaceInfo::adjface`] that edge `eid` meets.
    #[inline]
    pub fn adjedge(&self, eid: i32) -> i32 {
        ((self.adjedges >> (2 * (eid & 3))) & 3) as i32
    }

    /// Every texel has one value.
    pub fn is_constant(&self) -> bool {
        self.flags & FaceInfo::CONSTANT != 0
    }

    /// The face and its neighbours are constant with one value.
    pub fn is_neighbourhood_constant(&self) -> bool {
        self.flags & FaceInfo::NEIGHBOURHOOD_CONSTANT != 0
    }

    /// One of the faces a non-quad face of the mesh is split into.
    pub fn is_subface(&self) -> bool {
        self.flags & FaceInfo::SUBFACE != 0
    }
}

/// One face's texels at one resolution: a single texel for a constant face.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceData {
    /// One texel standing for all.
    pub constant: bool,
    /// Row-major (u fastest), channels interleaved.
    pub texels: Texels,
}

/// A Ptex file in memory.
pub struct PtexFile {
    /// Texel type.
    pub data_type: DataType,
    /// Channels per texel.
    pub channels: usize,
    /// Border mode along u.
    pub u_mode: BorderMode,
    /// Border mode along v.
    pub v_mode: BorderMode,
    /// Whether the first two channels are tangent-space vectors (rotated across edges).
    pub tangent_vectors: bool,
    /// A triangle mesh's file: each face a triangle, its texels in a square array (the
    /// library's `mt_triangle`), filtered by [`super::triangle`].
    pub triangles: bool,
    /// Per face.
    pub faces: Vec<FaceInfo>,
    /// Per face, its average (its value if constant), `channels` texels each.
    constant: Texels,
    /// Per face, its stored levels: the face, then its square reductions (2×2 averages)
    /// as far as the file has them. Empty for constant faces.
    levels: Vec<Vec<FaceData>>,
    /// Reductions the file does not store, made on first use (the library's
    /// `_reductions` cache), by face and resolution.
    reductions: RwLock<HashMap<(u32, Res), Arc<FaceData>>>,
}

const MAGIC: u32 = u32::from_le_bytes(*b"Ptex");
const HEADER_SIZE: usize = 64;
const FACE_INFO_SIZE: usize = 20;

/// Little-endian reads from a byte slice, with errors for reads past its end.
struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    fn at(data: &'a [u8], pos: usize) -> Bytes<'a> {
        Bytes { data, pos }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.data.len()).ok_or_else(|| {
            format!("truncated (needs {} bytes at offset {}, file has {})", n, self.pos, self.data.len())
        })?;
        let s = &self.data[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn u16(&mut self) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.take(2)?.try_into().unwrap()))
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }

    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }

    fn i32(&mut self) -> Result<i32, String> {
        Ok(self.u32()? as i32)
    }

    /// A zlib block of `zipsize` bytes that inflates to exactly `size` bytes.
    fn zip(&mut self, zipsize: usize, size: usize) -> Result<Vec<u8>, String> {
        let at = self.pos;
        let zipped = self.take(zipsize)?;
        // Not reserved in full: a corrupt size must not allocate before the data says so.
        let mut out = Vec::with_capacity(size.min(1 << 20));
        flate2::read::ZlibDecoder::new(zipped)
            .take(size as u64 + 1)
            .read_to_end(&mut out)
            .map_err(|e| format!("corrupt compressed block at offset {at}: {e}"))?;
        if out.len() != size {
            return Err(format!("compressed block at offset {at} holds {} bytes, not {size}", out.len()));
        }
        Ok(out)
    }
}

impl PtexFile {
    /// Reads a Ptex file: [`Error::Io`] if it cannot be read, [`Error::Malformed`] if its
    /// contents are not a Ptex file nimbus reads.
    pub fn open(path: &Path) -> Result<PtexFile> {
        let data = std::fs::read(path).map_err(|e| Error::io(path, "read", e))?;
        // Every error of parse is about the bytes: with the file to name, they are the file's.
        PtexFile::parse(&data).map_err(|e| match e {
            Error::Invalid(m) => Error::malformed(path, m),
            other => other,
        })
    }

    /// Parses a Ptex file's bytes. Having no file to name, the errors are [`Error::Invalid`]
    /// with the message alone.
    pub fn parse(data: &[u8]) -> Result<PtexFile> {
        PtexFile::parse_bytes(data).map_err(Error::Invalid)
    }

    /// [`PtexFile::parse`] with the message alone: the byte readers' errors are plain
    /// messages, given their kind once at the public boundary.
    fn parse_bytes(data: &[u8]) -> Result<PtexFile, String> {
        let mut h = Bytes::at(data, 0);
        if data.len() < 4 || h.u32()? != MAGIC {
            return Err("not a Ptex file".into());
        }
        let version = h.u32()?;
        if version != 1 {
            return Err(format!("Ptex file version {version} is not supported (only version 1 exists)"));
        }
        let mesh_type = h.u32()?;
        let data_type = match h.u32()? {
            0 => DataType::U8,
            1 => DataType::U16,
            2 => DataType::Half,
            3 => DataType::F32,
            other => return Err(format!("unknown data type {other}")),
        };
        let alpha_channel = h.i32()?;
        let channels = h.u16()? as usize;
        let nlevels = h.u16()? as usize;
        let nfaces = h.u32()? as usize;
        let ext_header_size = h.u32()? as usize;
        let face_info_size = h.u32()? as usize;
        let const_data_size = h.u32()? as usize;
        let level_info_size = h.u32()? as usize;
        let _minor_version = h.u32()?;
        let level_data_size = h.u64()? as usize;
        let meta_zip_size = h.u32()? as usize;
        let _meta_mem_size = h.u32()?;
        debug_assert_eq!(h.pos, HEADER_SIZE);
        let triangles = match mesh_type {
            0 => true,
            1 => false,
            other => return Err(format!("unknown mesh type {other}")),
        };
        if channels == 0 {
            return Err("no channels".into());
        }
        // The extended header, as much of it as the file has (older files have less).
        let mut ext = [0u8; 40];
        let n = ext_header_size.min(ext.len());
        ext[..n].copy_from_slice(Bytes::at(data, HEADER_SIZE).take(n)?);
        let mut e = Bytes::at(&ext, 0);
        let border = |m: u16| match m {
            0 => Ok(BorderMode::Clamp),
            1 => Ok(BorderMode::Black),
            2 => Ok(BorderMode::Periodic),
            other => Err(format!("unknown border mode {other}")),
        };
        let u_mode = border(e.u16()?)?;
        let _pad = e.u16()?;
        let v_mode = border(e.u16()?)?;
        let tangent_vectors = e.u16()? == 1;
        let lmd_header_zip_size = e.u32()? as usize;
        let _lmd_header_mem_size = e.u32()?;
        let lmd_data_size = e.u64()? as usize;
        let edit_data_size = e.u64()?;
        let edit_data_pos = e.u64()? as usize;

        let face_info_pos = HEADER_SIZE + ext_header_size;
        let const_data_pos = face_info_pos + face_info_size;
        let level_info_pos = const_data_pos + const_data_size;
        let level_data_pos = level_info_pos + level_info_size;
        let meta_pos = level_data_pos + level_data_size;
        // After the metadata: an 8-byte barrier, the large metadata, then edits.
        let edits_pos = (meta_pos + meta_zip_size + 8 + lmd_header_zip_size + lmd_data_size).max(edit_data_pos);
        let has_edits = if edit_data_pos > 0 {
            edit_data_size > 0
        } else {
            // Older files: edits run to the end of the file; a zero size ends them.
            let mut b = Bytes::at(data, edits_pos);
            b.u8().is_ok() && b.u32().is_ok_and(|size| size != 0)
        };
        if has_edits {
            return Err("Ptex files with edits (PtexWriter::edit) are not supported by nimbus".into());
        }

        let info = Bytes::at(data, face_info_pos).zip(face_info_size, FACE_INFO_SIZE * nfaces)?;
        let mut b = Bytes::at(&info, 0);
        let mut faces = Vec::with_capacity(nfaces);
        for _ in 0..nfaces {
            let (ulog2, vlog2) = (b.u8()? as i8, b.u8()? as i8);
            let (adjedges, flags) = (b.u8()?, b.u8()?);
            let adjfaces = [b.i32()?, b.i32()?, b.i32()?, b.i32()?];
            faces.push(FaceInfo { res: Res::new(ulog2, vlog2), adjedges, flags, adjfaces });
        }
        for (i, f) in faces.iter().enumerate() {
            if !(0..=15).contains(&f.res.ulog2) || !(0..=15).contains(&f.res.vlog2) {
                return Err(format!("face {i} has resolution 2^{} × 2^{}", f.res.ulog2, f.res.vlog2));
            }
            if f.adjfaces.iter().any(|&a| a < -1 || a >= nfaces as i32) {
                return Err(format!("face {i} names a neighbour that does not exist ({:?})", f.adjfaces));
            }
            if triangles && f.res.ulog2 != f.res.vlog2 {
                return Err(format!("triangle face {i} has a resolution that is not square"));
            }
            if f.flags & FaceInfo::HAS_EDITS != 0 {
                return Err(format!("face {i} has edits, which nimbus does not support"));
            }
        }
        let pixel_size = channels * data_type.size();
        let has_alpha = alpha_channel >= 0 && (alpha_channel as usize) < channels;
        let mut constant =
            texels_from(&Bytes::at(data, const_data_pos).zip(const_data_size, pixel_size * nfaces)?, data_type);
        if let Some(i) = constant.first_non_finite() {
            return Err(format!("face {}'s average is {} (not a finite number)", i / channels, constant.value(i)));
        }
        if has_alpha {
            constant.multiply_alpha(channels, alpha_channel as usize, data_type.one());
        }

        // Reduction levels hold faces in order of decreasing smaller dimension (constant
        // faces counting as 2¹), stably (`PtexUtils::genRfaceids`).
        let mut by_size: Vec<usize> = (0..nfaces).collect();
        let smaller = |f: &FaceInfo| if f.is_constant() { 1 } else { f.res.ulog2.min(f.res.vlog2) };
        by_size.sort_by_key(|&i| std::cmp::Reverse(smaller(&faces[i])));

        let mut levels: Vec<Vec<FaceData>> = vec![Vec::new(); nfaces];
        let mut li = Bytes::at(data, level_info_pos);
        let mut pos = level_data_pos;
        for level in 0..nlevels {
            let level_size = li.u64()? as usize;
            let header_size = li.u32()? as usize;
            let level_faces = li.u32()? as usize;
            if level_faces > nfaces {
                return Err(format!("level {level} lists {level_faces} faces of {nfaces}"));
            }
            let mut r = Bytes::at(data, pos);
            let headers = r.zip(header_size, 4 * level_faces)?;
            let mut at = r.pos;
            for (k, h) in headers.chunks_exact(4).enumerate() {
                let fdh = u32::from_le_bytes(h.try_into().unwrap());
                let face = if level == 0 { k } else { by_size[k] };
                let f = &faces[face];
                let block = (fdh & 0x3fff_ffff) as usize;
                // Levels come in order, so a face's list grows one level at a time.
                if !f.is_constant() && levels[face].len() == level && f.res.ulog2.min(f.res.vlog2) >= level as i8 {
                    let res = Res::new(f.res.ulog2 - level as i8, f.res.vlog2 - level as i8);
                    let face_data = read_face(data, at, fdh, res, data_type, channels)
                        .map_err(|e| format!("face {face} at level {level}: {e}"))?;
                    if let Some(i) = face_data.texels.first_non_finite() {
                        return Err(format!(
                            "face {face} at level {level}: texel {} is {} (not a finite number)",
                            i / channels,
                            face_data.texels.value(i)
                        ));
                    }
                    let mut face_data = face_data;
                    if level == 0 && has_alpha {
                        face_data.texels.multiply_alpha(channels, alpha_channel as usize, data_type.one());
                    }
                    levels[face].push(face_data);
                }
                at += block;
            }
            pos += level_size;
        }
        for (i, f) in faces.iter().enumerate() {
            if !f.is_constant() && levels[i].is_empty() {
                return Err(format!("face {i} has no data"));
            }
        }
        Ok(PtexFile {
            data_type,
            channels,
            u_mode,
            v_mode,
            tangent_vectors,
            triangles,
            faces,
            constant,
            levels,
            reductions: RwLock::new(HashMap::new()),
        })
    }

    /// Face `face`'s average (or constant) texel, channel `c`, unscaled.
    pub fn constant_value(&self, face: usize, c: usize) -> f32 {
        self.constant.value(face * self.channels + c)
    }

    /// Face `face`'s data at `res` (no finer than the face's own), as the library's
    /// `PtexReader::getData(faceid, res)` gives it: the face's constant or average texel for
    /// a constant face or a 1×1 request, else stored levels, else reductions of the next finer
    /// resolution (along u or v, alternating for square reductions).
    pub fn data(&self, face: usize, res: Res) -> FaceRef<'_> {
        let f = &self.faces[face];
        if f.is_constant() || (res.ulog2 == 0 && res.vlog2 == 0) {
            return FaceRef::Constant(face);
        }
        let (redu, redv) = (f.res.ulog2 - res.ulog2, f.res.vlog2 - res.vlog2);
        if redu < 0 || redv < 0 {
            // Finer than the face (the filters never ask): the library has no data either.
            return FaceRef::Constant(face);
        }
        if redu == redv
            && let Some(d) = self.levels[face].get(redu as usize)
        {
            return FaceRef::Stored(d);
        }
        let key = (face as u32, res);
        if let Some(d) = self.reductions.read().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return FaceRef::Reduced(d.clone());
        }
        // Triangles halve both ways at once; quads along one axis, alternating for square
        // reductions.
        let (how, finer) = if self.triangles {
            (Reduction::Triangle, Res::new(res.ulog2 + 1, res.vlog2 + 1))
        } else if (redu == redv && res.ulog2 & 1 != 0) || redu > redv {
            (Reduction::U, Res::new(res.ulog2 + 1, res.vlog2))
        } else {
            (Reduction::V, Res::new(res.ulog2, res.vlog2 + 1))
        };
        let reduced = match self.data(face, finer) {
            FaceRef::Constant(_) => unreachable!("a finer resolution than 1×1 of a face with data"),
            FaceRef::Stored(d) => reduce_face(d, finer, self.channels, how),
            FaceRef::Reduced(d) => reduce_face(&d, finer, self.channels, how),
        };
        let d = Arc::new(reduced);
        self.reductions.write().unwrap_or_else(|e| e.into_inner()).entry(key).or_insert(d).clone().into()
    }

    /// Bytes of texel data in memory.
    pub fn memory_bytes(&self) -> usize {
        let size = self.data_type.size();
        let stored: usize = self.levels.iter().flatten().map(|d| d.texels.len()).sum();
        let reduced: usize = self.reductions.read().map_or(0, |r| r.values().map(|d| d.texels.len()).sum());
        (self.constant.len() + stored + reduced) * size
    }
}

/// How a face is halved.
#[derive(Clone, Copy)]
enum Reduction {
    /// Along u.
    U,
    /// Along v.
    V,
    /// A triangle, both ways.
    Triangle,
}

/// `d` (at `res`) halved.
fn reduce_face(d: &FaceData, res: Res, channels: usize, how: Reduction) -> FaceData {
    if d.constant {
        return d.clone();
    }
    let texels = match how {
        Reduction::U => reduce(&d.texels, res, channels, true),
        Reduction::V => reduce(&d.texels, res, channels, false),
        Reduction::Triangle => reduce_triangle(&d.texels, res.u() as usize, channels),
    };
    FaceData { constant: false, texels }
}

/// Where a face's texels are.
pub enum FaceRef<'a> {
    /// The face's constant (or average) texel: [`PtexFile::constant_value`].
    Constant(usize),
    /// Stored in the file.
    Stored(&'a FaceData),
    /// Reduced on demand.
    Reduced(Arc<FaceData>),
}

impl From<Arc<FaceData>> for FaceRef<'_> {
    fn from(d: Arc<FaceData>) -> Self {
        FaceRef::Reduced(d)
    }
}

/// Decodes one face block (constant, tiled, zipped or difference-zipped) at `pos`.
fn read_face(data: &[u8], pos: usize, fdh: u32, res: Res, dt: DataType, channels: usize) -> Result<FaceData, String> {
    let block = (fdh & 0x3fff_ffff) as usize;
    let pixel_size = channels * dt.size();
    let mut b = Bytes::at(data, pos);
    match fdh >> 30 {
        // Constant: one texel, not compressed.
        0 => Ok(FaceData { constant: true, texels: texels_from(b.take(pixel_size)?, dt) }),
        // Zipped, difference-zipped: planar channels.
        1 | 2 => {
            let (uw, vw) = (res.u() as usize, res.v() as usize);
            let mut planar = b.zip(block, pixel_size * uw * vw)?;
            if fdh >> 30 == 2 {
                decode_difference(&mut planar, dt);
            }
            let planar = texels_from(&planar, dt);
            let n = uw * vw;
            let interleaved = match planar {
                Texels::U8(t) => Texels::U8(interleave(&t, n, channels)),
                Texels::U16(t) => Texels::U16(interleave(&t, n, channels)),
                Texels::Half(t) => Texels::Half(interleave(&t, n, channels)),
                Texels::F32(t) => Texels::F32(interleave(&t, n, channels)),
            };
            Ok(FaceData { constant: false, texels: interleaved })
        }
        // Tiled: a tile resolution, zipped tile headers, then each tile as a face.
        _ => {
            let tile_res = Res::new(b.u8()? as i8, b.u8()? as i8);
            if tile_res.ulog2 < 0 || tile_res.vlog2 < 0 || tile_res.ulog2 > res.ulog2 || tile_res.vlog2 > res.vlog2 {
                return Err(format!(
                    "tile resolution 2^{} × 2^{} for a face of 2^{} × 2^{}",
                    tile_res.ulog2, tile_res.vlog2, res.ulog2, res.vlog2
                ));
            }
            let header_size = b.u32()? as usize;
            let (ntu, ntv) = (res.u() / tile_res.u(), res.v() / tile_res.v());
            let ntiles = (ntu * ntv) as usize;
            let headers = b.zip(header_size, 4 * ntiles)?;
            let mut at = b.pos;
            let mut tiles = Vec::with_capacity(ntiles);
            for h in headers.chunks_exact(4) {
                let tdh = u32::from_le_bytes(h.try_into().unwrap());
                if tdh >> 30 == 3 {
                    return Err("a tile is itself tiled".into());
                }
                tiles.push(read_face(data, at, tdh, tile_res, dt, channels)?);
                at += (tdh & 0x3fff_ffff) as usize;
            }
            let layout = TileLayout {
                ntu: ntu as usize,
                uw: res.u() as usize,
                vw: res.v() as usize,
                tu: tile_res.u() as usize,
                tv: tile_res.v() as usize,
                channels,
            };
            let texels = match dt {
                DataType::U8 => Texels::U8(layout.assemble(&tiles, |t| match t {
                    Texels::U8(x) => x,
                    _ => unreachable!("tiles share the file's type"),
                })),
                DataType::U16 => Texels::U16(layout.assemble(&tiles, |t| match t {
                    Texels::U16(x) => x,
                    _ => unreachable!("tiles share the file's type"),
                })),
                DataType::Half => Texels::Half(layout.assemble(&tiles, |t| match t {
                    Texels::Half(x) => x,
                    _ => unreachable!("tiles share the file's type"),
                })),
                DataType::F32 => Texels::F32(layout.assemble(&tiles, |t| match t {
                    Texels::F32(x) => x,
                    _ => unreachable!("tiles share the file's type"),
                })),
            };
            Ok(FaceData { constant: false, texels })
        }
    }
}

/// How a tiled face's tiles cover it.
struct TileLayout {
    ntu: usize,
    uw: usize,
    vw: usize,
    tu: usize,
    tv: usize,
    channels: usize,
}

impl TileLayout {
    /// The face's texels from its tiles (row-major tiles, each constant or row-major texels).
    fn assemble<T: Copy + Default>(&self, tiles: &[FaceData], texels: impl Fn(&Texels) -> &[T]) -> Box<[T]> {
        let Self { ntu, uw, vw, tu, tv, channels } = *self;
        let mut out = vec![T::default(); uw * vw * channels];
        for (t, tile) in tiles.iter().enumerate() {
            let src = texels(&tile.texels);
            let (x0, y0) = ((t % ntu) * tu, (t / ntu) * tv);
            for y in 0..tv {
                for x in 0..tu {
                    for c in 0..channels {
                        let i = if tile.constant { c } else { (y * tu + x) * channels + c };
                        out[((y0 + y) * uw + x0 + x) * channels + c] = src[i];
                    }
                }
            }
        }
        out.into()
    }
}

/// Undoes the difference coding of integer data (`PtexUtils::decodeDifference`): each value
/// was stored as the difference from the one before it, across the whole block.
fn decode_difference(bytes: &mut [u8], dt: DataType) {
    match dt {
        DataType::U8 => {
            let mut prev = 0u8;
            for b in bytes.iter_mut() {
                *b = b.wrapping_add(prev);
                prev = *b;
            }
        }
        DataType::U16 => {
            let mut prev = 0u16;
            for b in bytes.chunks_exact_mut(2) {
                let v = u16::from_le_bytes([b[0], b[1]]).wrapping_add(prev);
                b.copy_from_slice(&v.to_le_bytes());
                prev = v;
            }
        }
        DataType::Half | DataType::F32 => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn fixture(name: &str) -> Vec<u8> {
        std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/ptex").join(name)).unwrap()
    }

    /// The fixtures' layouts as their generator wrote them: types, channels, resolutions,
    /// constant faces, the tiled face read whole.
    #[test]
    fn reads_the_fixtures_layouts() {
        let grid = PtexFile::parse(&fixture("grid-rgb8.ptx")).unwrap();
        assert_eq!((grid.data_type, grid.channels, grid.faces.len()), (DataType::U8, 3, 6));
        assert_eq!(grid.faces[1].res, Res::new(5, 3));
        assert!(grid.faces[4].is_constant());
        assert_eq!((grid.faces[0].adjface(1), grid.faces[0].adjedge(1)), (1, 3));
        let big = PtexFile::parse(&fixture("big-rgb16.ptx")).unwrap();
        assert_eq!((big.data_type, big.faces[0].res), (DataType::U16, Res::new(8, 8)));
        let FaceRef::Stored(d) = big.data(0, Res::new(8, 8)) else { panic!("face 0 is stored") };
        assert_eq!(d.texels.len(), 256 * 256 * 3);
        let cube = PtexFile::parse(&fixture("cube-half.ptx")).unwrap();
        assert_eq!((cube.data_type, cube.channels), (DataType::Half, 1));
    }

    /// Corrupt and truncated files are errors or load, never a panic, and lookups on what
    /// loads (at points in and outside the face, any footprint) stay finite or zero.
    #[test]
    fn damaged_files_do_not_panic() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        assert!(PtexFile::parse(b"PNG not ptex").is_err());
        assert!(PtexFile::parse(&[]).is_err());
        for name in ["grid-rgb8.ptx", "cube-half.ptx", "fan-float.ptx", "subfaces-rgb8.ptx", "tri-rgb8.ptx"] {
            let good = fixture(name);
            for trial in 0..300 {
                let mut bytes = good.clone();
                match trial % 3 {
                    0 => bytes.truncate(next() as usize % good.len()),
                    // The uncompressed header, extended header and level info.
                    1 => bytes[next() as usize % 128] = next() as u8,
                    _ => {
                        let i = next() as usize % bytes.len();
                        bytes[i] ^= 1 << (next() % 8);
                    }
                }
                let Ok(file) = PtexFile::parse(&bytes) else { continue };
                for _ in 0..20 {
                    let f = |n: u64| (n % 3000) as f32 / 1000.0 - 1.0;
                    let face = (next() % (file.faces.len() as u64 + 1)) as i32;
                    let v =
                        super::super::filtered(&file, 3, face, f(next()), f(next()), f(next()), 0.0, 0.0, f(next()));
                    assert!(v.iter().all(|x| !x.is_nan()), "{name} trial {trial}: {v:?}");
                }
            }
        }
    }
}
