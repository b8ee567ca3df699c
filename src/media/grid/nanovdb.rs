//! NanoVDB files (`.nvdb`), the format pbrt-v4's `nanovdb` medium reads, parsed directly.
//!
//! A file is a run of segments: a 16-byte header (magic, version, grid count, codec), then for
//! each grid a 176-byte metadata record and its name, then each grid's buffer, compressed as
//! the header's codec says. Newer NanoVDB (32.6+) may also write a raw buffer of grids with no
//! segment header. A grid buffer is the in-memory grid: `GridData` (672 bytes: name, the
//! index↔world map, world bounds, class, value type), `TreeData` (byte offsets of the first node
//! of each level), the root (background and a table of 32-byte tiles), then upper (32³),
//! lower (16³) and leaf (8³) nodes. Children are found by signed byte offsets from their
//! parent. Layouts follow NanoVDB 32.x (`NanoVDB.h`, `io/IO.h`), whose 32.3–32.7 files pbrt-v4's
//! bundled NanoVDB reads; every offset is checked, so a file of another layout is reported as
//! malformed rather than misread.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use glam::{DAffine3, DMat3, DVec3, IVec3};

use super::error::GridError;
use super::sparse::{BRICK_VOXELS, BuildIssue, SparseGrid, SparseGridBuilder};
use crate::geometry::Bounds3;

/// "NanoVDB0": the legacy magic of both files and grids.
const MAGIC_LEGACY: u64 = 0x304244566f6e614e;
/// "NanoVDB1": a grid buffer (32.6+ with new magic numbers).
const MAGIC_GRID: u64 = 0x314244566f6e614e;
/// "NanoVDB2": a file with segments (32.6+ with new magic numbers).
const MAGIC_FILE: u64 = 0x324244566f6e614e;
/// The NanoVDB major version whose layout this reader knows.
const MAJOR_VERSION: u32 = 32;
const FILE_HEADER_BYTES: usize = 16;
const FILE_METADATA_BYTES: usize = 176;
/// sizeof(GridData): the tree follows it.
const GRID_DATA_BYTES: usize = 672;
/// Root header (bbox, table size, background, statistics) padded to 32 bytes.
const ROOT_HEADER_BYTES: usize = 64;
const ROOT_TILE_BYTES: usize = 32;

/// NanoVDB's `GridType` values that hold scalar floats this reader decodes.
const TYPE_FLOAT: u32 = 1;
const TYPE_FP4: u32 = 13;
const TYPE_FP8: u32 = 14;
const TYPE_FP16: u32 = 15;
const TYPE_FPN: u32 = 16;

/// NanoVDB's `GridClass` values pbrt-v4 accepts for media.
const CLASS_UNKNOWN: u32 = 0;
const CLASS_FOG_VOLUME: u32 = 2;

/// Name of a NanoVDB `GridType`.
fn type_name(t: u32) -> String {
    const NAMES: [&str; 27] = [
        "unknown",
        "float",
        "double",
        "int16",
        "int32",
        "int64",
        "vec3f",
        "vec3d",
        "mask",
        "half",
        "uint32",
        "bool",
        "rgba8",
        "fp4",
        "fp8",
        "fp16",
        "fpN",
        "vec4f",
        "vec4d",
        "index",
        "onindex",
        "indexmask",
        "onindexmask",
        "pointindex",
        "vec3u8",
        "vec3u16",
        "uint8",
    ];
    NAMES.get(t as usize).map_or_else(|| format!("type #{t}"), |s| s.to_string())
}

/// Name of a NanoVDB `GridClass`.
fn class_name(c: u32) -> String {
    const NAMES: [&str; 10] = [
        "Unknown",
        "LevelSet",
        "FogVolume",
        "Staggered",
        "PointIndex",
        "PointData",
        "Topology",
        "VoxelVolume",
        "IndexGrid",
        "TensorGrid",
    ];
    NAMES.get(c as usize).map_or_else(|| format!("class #{c}"), |s| s.to_string())
}

/// How a grid's buffer is stored in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Codec {
    None,
    Zip,
    Blosc,
}

/// One grid of the file, as its metadata describes it.
#[derive(Clone, Debug)]
struct Entry {
    name: String,
    grid_type: u32,
    grid_class: u32,
    codec: Codec,
    /// Uncompressed bytes.
    grid_size: u64,
    /// Bytes in the file (compressed, with byte counts).
    file_size: u64,
    /// Where the (possibly compressed) buffer starts.
    offset: u64,
}

/// A NanoVDB file whose grid list has been read; grids are read on request.
#[derive(Clone, Debug)]
pub struct NanoVdbFile {
    path: PathBuf,
    grids: Vec<Entry>,
}

/// Little-endian reads from a byte slice that fail, not panic, past its end.
#[derive(Clone, Copy)]
struct Bytes<'a> {
    data: &'a [u8],
}

impl Bytes<'_> {
    fn array<const N: usize>(&self, at: usize) -> Result<[u8; N], String> {
        at.checked_add(N)
            .and_then(|end| self.data.get(at..end))
            .map(|s| s.try_into().expect("slice of length N"))
            .ok_or_else(|| format!("truncated: needs bytes {at}..{} of {}", at + N, self.data.len()))
    }
    fn u16(&self, at: usize) -> Result<u16, String> {
        self.array(at).map(u16::from_le_bytes)
    }
    fn u32(&self, at: usize) -> Result<u32, String> {
        self.array(at).map(u32::from_le_bytes)
    }
    fn i32(&self, at: usize) -> Result<i32, String> {
        self.array(at).map(i32::from_le_bytes)
    }
    fn u64(&self, at: usize) -> Result<u64, String> {
        self.array(at).map(u64::from_le_bytes)
    }
    fn i64(&self, at: usize) -> Result<i64, String> {
        self.array(at).map(i64::from_le_bytes)
    }
    fn f32(&self, at: usize) -> Result<f32, String> {
        self.array(at).map(f32::from_le_bytes)
    }
    fn f64(&self, at: usize) -> Result<f64, String> {
        self.array(at).map(f64::from_le_bytes)
    }
    fn dvec3(&self, at: usize) -> Result<DVec3, String> {
        Ok(DVec3::new(self.f64(at)?, self.f64(at + 8)?, self.f64(at + 16)?))
    }
    fn ivec3(&self, at: usize) -> Result<IVec3, String> {
        Ok(IVec3::new(self.i32(at)?, self.i32(at + 4)?, self.i32(at + 8)?))
    }
    fn bit(&self, mask_at: usize, n: usize) -> Result<bool, String> {
        Ok(self.u64(mask_at + (n >> 6) * 8)? >> (n & 63) & 1 == 1)
    }
    fn words<const N: usize>(&self, at: usize) -> Result<[u64; N], String> {
        let mut w = [0; N];
        for (i, word) in w.iter_mut().enumerate() {
            *word = self.u64(at + 8 * i)?;
        }
        Ok(w)
    }
    /// `base + offset` as a position inside the buffer.
    fn child(&self, base: usize, offset: i64) -> Result<usize, String> {
        let at = base as i64 + offset;
        if offset == 0 || at < 0 || at as usize >= self.data.len() {
            return Err(format!("child offset {offset} from byte {base} leaves the grid"));
        }
        Ok(at as usize)
    }
}

fn version_major(v: u32) -> u32 {
    v >> 21
}

fn version_string(v: u32) -> String {
    format!("{}.{}.{}", v >> 21, (v >> 10) & 0x7ff, v & 0x3ff)
}

impl NanoVdbFile {
    /// Reads the grid list of the file at `path` (headers only).
    pub fn open(path: impl AsRef<Path>) -> Result<NanoVdbFile, GridError> {
        let path = path.as_ref().to_path_buf();
        let io = |source| GridError::Io { path: path.clone(), source };
        let malformed = |message: String| GridError::Malformed { path: path.clone(), message };
        let mut file = File::open(&path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let mut grids = Vec::new();
        let mut pos = 0u64;
        while pos < len {
            let mut header = [0u8; FILE_HEADER_BYTES + 16];
            let n = read_up_to(&mut file, pos, &mut header).map_err(io)?;
            if n < FILE_HEADER_BYTES {
                return Err(malformed(format!("truncated segment header at byte {pos}")));
            }
            let h = Bytes { data: &header[..n] };
            let magic = h.u64(0).map_err(malformed)?;
            let version = h.u32(8).map_err(malformed)?;
            let raw_grid = match magic {
                MAGIC_GRID => true,
                MAGIC_LEGACY | MAGIC_FILE if version_major(version) == MAJOR_VERSION => false,
                // A raw grid with the legacy magic: GridData's version sits at byte 16.
                MAGIC_LEGACY if h.u32(16).is_ok_and(|v| version_major(v) == MAJOR_VERSION) => true,
                MAGIC_LEGACY | MAGIC_FILE => {
                    return Err(malformed(format!(
                        "NanoVDB version {} is not supported (this reader knows {MAJOR_VERSION}.x)",
                        version_string(version)
                    )));
                }
                _ if &header[..8] == b" BDV\0\0\0\0" => {
                    return Err(malformed("this is an OpenVDB file; use the \"vdb\" medium for .vdb files".into()));
                }
                _ => {
                    return Err(malformed(format!("not a NanoVDB file (no NanoVDB magic at byte {pos})")));
                }
            };
            if raw_grid {
                let entry = read_raw_entry(&mut file, pos).map_err(io)?.map_err(malformed)?;
                if entry.grid_size > len - pos {
                    return Err(malformed(format!("grid \"{}\" runs past the end of the file", entry.name)));
                }
                pos += entry.grid_size;
                grids.push(entry);
                continue;
            }
            let codec = match h.u16(14).map_err(malformed)? {
                0 => Codec::None,
                1 => Codec::Zip,
                2 => Codec::Blosc,
                c => return Err(malformed(format!("unknown codec {c}"))),
            };
            let count = h.u16(12).map_err(malformed)? as usize;
            pos += FILE_HEADER_BYTES as u64;
            let mut sizes = Vec::with_capacity(count);
            let first = grids.len();
            for _ in 0..count {
                let mut meta = [0u8; FILE_METADATA_BYTES];
                file.seek(SeekFrom::Start(pos)).map_err(io)?;
                file.read_exact(&mut meta).map_err(|_| malformed(format!("truncated grid metadata at byte {pos}")))?;
                let m = Bytes { data: &meta };
                let name_size = m.u32(136).map_err(malformed)? as usize;
                if name_size > 1 << 16 {
                    return Err(malformed(format!("grid name of {name_size} bytes at byte {pos}")));
                }
                let mut name = vec![0u8; name_size];
                file.read_exact(&mut name).map_err(|_| malformed("truncated grid name".into()))?;
                let name = String::from_utf8_lossy(name.split(|&b| b == 0).next().unwrap_or(&[])).into_owned();
                pos += (FILE_METADATA_BYTES + name_size) as u64;
                sizes.push(m.u64(8).map_err(malformed)?);
                grids.push(Entry {
                    name,
                    grid_type: m.u32(32).map_err(malformed)?,
                    grid_class: m.u32(36).map_err(malformed)?,
                    codec,
                    grid_size: m.u64(0).map_err(malformed)?,
                    file_size: 0,
                    offset: 0,
                });
            }
            for (entry, file_size) in grids[first..].iter_mut().zip(sizes) {
                entry.offset = pos;
                entry.file_size = file_size;
                pos = pos
                    .checked_add(file_size)
                    .filter(|&end| end <= len)
                    .ok_or_else(|| malformed(format!("grid \"{}\" runs past the end of the file", entry.name)))?;
            }
        }
        Ok(NanoVdbFile { path, grids })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Names of the grids in the file, in file order.
    pub fn grid_names(&self) -> Vec<&str> {
        self.grids.iter().map(|g| g.name.as_str()).collect()
    }

    /// True if the file has a grid named `name`.
    pub fn has_grid(&self, name: &str) -> bool {
        self.grids.iter().any(|g| g.name == name)
    }

    /// Reads the first grid named `name` (as NanoVDB's `readGrid` by name does) into a
    /// [`SparseGrid`]. The grid must be a fog volume or of unknown class, as pbrt-v4 requires,
    /// and hold float values (float, or the quantised fp4/fp8/fp16/fpN).
    pub fn read_grid(&self, name: &str) -> Result<SparseGrid, GridError> {
        let Some(entry) = self.grids.iter().find(|g| g.name == name) else {
            return Err(GridError::GridNotFound {
                path: self.path.clone(),
                name: name.to_string(),
                available: self.grids.iter().map(|g| format!("{} ({})", g.name, type_name(g.grid_type))).collect(),
            });
        };
        if entry.grid_class != CLASS_FOG_VOLUME && entry.grid_class != CLASS_UNKNOWN {
            return Err(GridError::NotFogVolume {
                path: self.path.clone(),
                grid: name.to_string(),
                class: class_name(entry.grid_class),
            });
        }
        if !matches!(entry.grid_type, TYPE_FLOAT | TYPE_FP4 | TYPE_FP8 | TYPE_FP16 | TYPE_FPN) {
            return Err(GridError::UnsupportedValueType {
                path: self.path.clone(),
                grid: name.to_string(),
                value_type: type_name(entry.grid_type),
            });
        }
        let buffer = self.load(entry)?;
        let malformed = |message: String| GridError::Malformed {
            path: self.path.clone(),
            message: format!("grid \"{name}\": {message}"),
        };
        let (builder, map, world_bbox) = parse_grid(&buffer, entry.grid_type).map_err(malformed)?;
        drop(buffer);
        let mut grid = builder.build().map_err(|issue| match issue {
            BuildIssue::NoActiveVoxels => GridError::EmptyGrid { path: self.path.clone(), grid: name.to_string() },
            BuildIssue::TooLarge { cells } => {
                GridError::TooLarge { path: self.path.clone(), grid: name.to_string(), cells }
            }
        })?;
        grid.set_transform(map);
        // pbrt-v4 bounds the medium with the file's world box; keep it when it is sane.
        if !world_bbox.is_empty() && world_bbox.min.is_finite() && world_bbox.max.is_finite() {
            grid.set_world_bounds(world_bbox);
        }
        Ok(grid)
    }

    /// The uncompressed grid buffer of `entry`.
    fn load(&self, entry: &Entry) -> Result<Vec<u8>, GridError> {
        let io = |source| GridError::Io { path: self.path.clone(), source };
        let mut file = File::open(&self.path).map_err(io)?;
        file.seek(SeekFrom::Start(entry.offset)).map_err(io)?;
        let size = usize::try_from(entry.grid_size).map_err(|_| GridError::Malformed {
            path: self.path.clone(),
            message: format!("grid \"{}\" of {} bytes", entry.name, entry.grid_size),
        })?;
        match entry.codec {
            Codec::None => {
                if entry.grid_size > entry.file_size {
                    return Err(GridError::Malformed {
                        path: self.path.clone(),
                        message: format!(
                            "grid \"{}\" of {} bytes stored in {}",
                            entry.name, entry.grid_size, entry.file_size
                        ),
                    });
                }
                let mut buffer = vec![0u8; size];
                file.read_exact(&mut buffer).map_err(io)?;
                Ok(buffer)
            }
            Codec::Zip => {
                let mut n = [0u8; 8];
                file.read_exact(&mut n).map_err(io)?;
                let zipped = u64::from_le_bytes(n);
                // A corrupt size must not reserve memory up front; the buffer grows as
                // the data inflates and is checked against the size after.
                let mut buffer = Vec::with_capacity(size.min(1 << 30));
                let decoder = flate2::read::ZlibDecoder::new(std::io::BufReader::new(file.take(zipped)));
                decoder.take(entry.grid_size + 1).read_to_end(&mut buffer).map_err(|e| GridError::Malformed {
                    path: self.path.clone(),
                    message: format!("grid \"{}\": zip data: {e}", entry.name),
                })?;
                if buffer.len() != size {
                    return Err(GridError::Malformed {
                        path: self.path.clone(),
                        message: format!(
                            "grid \"{}\" unzips to {} bytes, not the {size} its metadata says",
                            entry.name,
                            buffer.len()
                        ),
                    });
                }
                Ok(buffer)
            }
            Codec::Blosc => Err(GridError::UnsupportedCodec {
                path: self.path.clone(),
                codec: "BLOSC".into(),
                advice: "write the file uncompressed or with ZIP (nanovdb_convert without \
                         -b/--blosc, or with -z/--zip)"
                    .into(),
            }),
        }
    }
}

/// Reads into `buf` from `pos` until it is full or the file ends; returns the bytes read.
fn read_up_to(file: &mut File, pos: u64, buf: &mut [u8]) -> std::io::Result<usize> {
    file.seek(SeekFrom::Start(pos))?;
    let mut n = 0;
    while n < buf.len() {
        match file.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// The entry of a raw grid buffer at `pos` (no segment header: the grid describes itself).
fn read_raw_entry(file: &mut File, pos: u64) -> std::io::Result<Result<Entry, String>> {
    let mut data = vec![0u8; GRID_DATA_BYTES];
    file.seek(SeekFrom::Start(pos))?;
    if file.read_exact(&mut data).is_err() {
        return Ok(Err(format!("truncated grid at byte {pos}")));
    }
    let g = Bytes { data: &data };
    let entry = (|| {
        let name_bytes = &data[40..296];
        let name = String::from_utf8_lossy(name_bytes.split(|&b| b == 0).next().unwrap_or(&[]));
        let grid_size = g.u64(32)?.max(GRID_DATA_BYTES as u64);
        Ok(Entry {
            name: name.into_owned(),
            grid_type: g.u32(636)?,
            grid_class: g.u32(632)?,
            codec: Codec::None,
            grid_size,
            file_size: grid_size,
            offset: pos,
        })
    })();
    Ok(entry)
}

/// How a leaf's values are encoded.
#[derive(Clone, Copy)]
enum LeafCodec {
    Float,
    /// Fixed-width codes: bits per value.
    Fixed(u32),
    /// Per-leaf width in the leaf's flags.
    Variable,
}

/// Walks a grid buffer into a builder; returns it with the world-from-index map and the
/// file's world bounding box.
fn parse_grid(data: &[u8], expected_type: u32) -> Result<(SparseGridBuilder, DAffine3, Bounds3), String> {
    let b = Bytes { data };
    let magic = b.u64(0)?;
    if magic != MAGIC_LEGACY && magic != MAGIC_GRID {
        return Err("grid buffer lacks the NanoVDB magic".into());
    }
    let version = b.u32(16)?;
    if version_major(version) != MAJOR_VERSION {
        return Err(format!(
            "grid of NanoVDB version {} (this reader knows {MAJOR_VERSION}.x)",
            version_string(version)
        ));
    }
    let grid_type = b.u32(636)?;
    if grid_type != expected_type {
        return Err(format!("metadata says {} but the grid holds {}", type_name(expected_type), type_name(grid_type)));
    }
    // Map (at 296): float matrices first (88 bytes), then the doubles pbrt-v4's float map
    // was rounded from: row-major matrix (world = M * index + t), its inverse, translation.
    const MAP: usize = 296;
    let mut m = [0.0; 9];
    for (i, v) in m.iter_mut().enumerate() {
        *v = b.f64(MAP + 88 + 8 * i)?;
    }
    let translation = b.dvec3(MAP + 88 + 144)?;
    let matrix = DMat3::from_cols_array(&m).transpose();
    if !(matrix.is_finite() && translation.is_finite()) || matrix.determinant() == 0.0 {
        return Err("the index-to-world map is not invertible".into());
    }
    let map = DAffine3::from_mat3_translation(matrix, translation);
    let world_bbox = Bounds3::new(b.dvec3(560)?.as_vec3(), b.dvec3(584)?.as_vec3());
    let leaf_codec = match grid_type {
        TYPE_FLOAT => LeafCodec::Float,
        TYPE_FP4 => LeafCodec::Fixed(4),
        TYPE_FP8 => LeafCodec::Fixed(8),
        TYPE_FP16 => LeafCodec::Fixed(16),
        _ => LeafCodec::Variable,
    };

    const TREE: usize = GRID_DATA_BYTES;
    let root_offset = b.u64(TREE + 24)?;
    let node_counts = [b.u32(TREE + 32)?, b.u32(TREE + 36)?, b.u32(TREE + 40)?];
    let root = TREE
        .checked_add(usize::try_from(root_offset).map_err(|_| "root offset overflows")?)
        .filter(|&r| r < data.len())
        .ok_or("root offset leaves the grid")?;
    let table_size = b.u32(root + 24)? as usize;
    let background = b.f32(root + 28)?;
    if table_size > (data.len() - root) / ROOT_TILE_BYTES {
        return Err(format!("root table of {table_size} tiles does not fit the grid"));
    }

    let mut walk = Walk {
        b,
        builder: SparseGridBuilder::new(background),
        codec: leaf_codec,
        visited: [0; 3],
        counts: node_counts,
        values: [0.0; BRICK_VOXELS],
    };
    for t in 0..table_size {
        let tile = root + ROOT_HEADER_BYTES + t * ROOT_TILE_BYTES;
        let key = b.u64(tile)?;
        // Single 64-bit root key: 21 bits per axis of (coordinate >> 12), x highest.
        let axis = |shift: u32| ((((key >> shift) & 0x1f_ffff) as u32) << 12) as i32;
        let origin = IVec3::new(axis(42), axis(21), axis(0));
        let child = b.i64(tile + 8)?;
        if child == 0 {
            let active = b.u32(tile + 16)? != 0;
            walk.builder.add_tile(origin, 4096, b.f32(tile + 20)?, active);
        } else {
            walk.upper(b.child(root, child)?, origin)?;
        }
    }
    Ok((walk.builder, map, world_bbox))
}

/// State of a walk down the tree.
struct Walk<'a> {
    b: Bytes<'a>,
    builder: SparseGridBuilder,
    codec: LeafCodec,
    /// Nodes visited per level (leaf, lower, upper), checked against the tree's counts so a
    /// corrupt file cannot make the walk revisit nodes without end.
    visited: [u32; 3],
    counts: [u32; 3],
    values: [f32; BRICK_VOXELS],
}

impl Walk<'_> {
    fn visit(&mut self, level: usize) -> Result<(), String> {
        self.visited[level] += 1;
        if self.visited[level] > self.counts[level] {
            return Err(format!("more level-{level} nodes than the {} the tree declares", self.counts[level]));
        }
        Ok(())
    }

    /// An internal node of `log2` (5 upper, 4 lower) at byte `at` with index origin `origin`.
    /// Layout: bbox (24), flags (8), value mask, child mask, 4 statistics, table of 8-byte
    /// tiles aligned to 32 (value in the low 4 bytes, or a child's byte offset).
    fn internal(&mut self, at: usize, origin: IVec3, log2: u32) -> Result<(), String> {
        self.visit(if log2 == 5 { 2 } else { 1 })?;
        let mask_bytes = 1usize << (3 * log2 - 3);
        let value_mask = at + 32;
        let child_mask = value_mask + mask_bytes;
        // The table is aligned to 32 bytes within the node (nodes start 32-byte aligned).
        let table = at + (32 + 2 * mask_bytes + 16).next_multiple_of(32);
        let child_total = if log2 == 5 { 7 } else { 3 };
        for n in 0..1usize << (3 * log2) {
            let local = IVec3::new(
                (n >> (2 * log2)) as i32,
                ((n >> log2) & ((1 << log2) - 1)) as i32,
                (n & ((1 << log2) - 1)) as i32,
            );
            let child_origin = origin + (local << child_total);
            let entry = table + 8 * n;
            if self.b.bit(child_mask, n)? {
                let child = self.b.child(at, self.b.i64(entry)?)?;
                if log2 == 5 {
                    self.internal(child, child_origin, 4)?;
                } else {
                    self.leaf(child, child_origin)?;
                }
            } else {
                let value = self.b.f32(entry)?;
                let active = self.b.bit(value_mask, n)?;
                self.builder.add_tile(child_origin, 1 << child_total, value, active);
            }
        }
        Ok(())
    }

    fn upper(&mut self, at: usize, origin: IVec3) -> Result<(), String> {
        self.internal(at, origin, 5)
    }

    /// A leaf at byte `at`: origin (12), bbox extent (3), flags (1), value mask (64), then
    /// for float leaves min, max, average, deviation and the values at 96; for quantised
    /// leaves (value = code × quantum + minimum) minimum at 80, quantum at 84, codes at 96.
    fn leaf(&mut self, at: usize, origin: IVec3) -> Result<(), String> {
        self.visit(0)?;
        let stored = self.b.ivec3(at)?;
        if stored & !7 != origin {
            return Err(format!("leaf at byte {at} says origin {stored}, its parent places it at {origin}"));
        }
        let mask: [u64; 8] = self.b.words(at + 16)?;
        let codes = at + 96;
        let bits = match self.codec {
            LeafCodec::Float => {
                let bytes = self.b.data.get(codes..codes + 4 * BRICK_VOXELS).ok_or("truncated leaf")?;
                for (v, c) in self.values.iter_mut().zip(bytes.chunks_exact(4)) {
                    *v = f32::from_le_bytes(c.try_into().expect("4 bytes"));
                }
                None
            }
            LeafCodec::Fixed(bits) => Some(bits),
            LeafCodec::Variable => {
                // FpN keeps log2 of its bit width (1..16) in the top 3 bits of the flags.
                let log2 = u32::from(self.b.array::<1>(at + 15)?[0] >> 5);
                if log2 > 4 {
                    return Err(format!("leaf at byte {at} has {log2} as log2 bit width"));
                }
                Some(1 << log2)
            }
        };
        if let Some(bits) = bits {
            let minimum = self.b.f32(at + 80)?;
            let quantum = self.b.f32(at + 84)?;
            let bytes = self.b.data.get(codes..codes + (BRICK_VOXELS * bits as usize) / 8).ok_or("truncated leaf")?;
            let code_mask = (1u32 << bits) - 1;
            for (n, v) in self.values.iter_mut().enumerate() {
                // Codes are packed lowest bits first (NanoVDB reads them from little-endian
                // words), and at most 16 bits wide, so two bytes hold any code.
                let bit = n * bits as usize;
                let lo = u32::from(bytes[bit / 8]);
                let hi = u32::from(bytes.get(bit / 8 + 1).copied().unwrap_or(0));
                let code = ((lo | hi << 8) >> (bit % 8)) & code_mask;
                *v = code as f32 * quantum + minimum;
            }
        }
        self.builder.add_leaf(origin, &self.values, &mask);
        Ok(())
    }
}
