//! Where a grid's parts lie in an OpenVDB file, found by walking the stream without decoding
//! values (OpenVDB's `Archive::readGrid`, `RootNode/InternalNode/LeafNode::readTopology`,
//! `readBuffers` and `io::readCompressedValues`, file format 222 and later).
//!
//! nimbus needs this beside vdb-rs because vdb-rs 0.6 panics on transforms other than
//! (uniform) scale(-translate) maps, drops the root's background and tiles, and misreads
//! compressed half-float grids: OpenVDB writes nothing at all for an empty half-float array
//! (`HalfWriter::write` returns early) where vdb-rs expects a byte count. The walk records
//! the transform, background, root tiles and every place such an empty array was left out,
//! and checks that the topology ends where the descriptor's block position says and the
//! leaf buffers where its end position says — so a misread shows up as an error here, not
//! as garbage from vdb-rs.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};

use glam::{DAffine3, DMat3, DVec3, IVec3};

/// The oldest file format walked: per-node compression metadata arrived in 222 (OpenVDB 3.0).
pub(crate) const MIN_FILE_VERSION: u32 = 222;

/// vdb-rs's `Compression` bits.
const COMPRESS_ZIP: u32 = 0x1;
const COMPRESS_ACTIVE_MASK: u32 = 0x2;
const COMPRESS_BLOSC: u32 = 0x4;

/// Why a walk failed.
#[derive(Debug)]
pub(crate) enum LayoutError {
    /// Reading the file failed.
    Io(std::io::Error),
    /// The bytes are not a grid as described.
    Malformed(String),
    /// A transform nimbus cannot use: (map type, reason).
    UnsupportedMap(String, String),
    /// Something valid that nimbus does not read.
    Unsupported(String),
}

impl From<std::io::Error> for LayoutError {
    fn from(e: std::io::Error) -> Self {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            LayoutError::Malformed("the file ends inside the grid".into())
        } else {
            LayoutError::Io(e)
        }
    }
}

/// What precedes a grid's tree: compression flags and transform.
#[derive(Clone, Debug)]
pub(crate) struct GridHeader {
    /// Compression flags as stored (vdb-rs needs them repeated in a rewritten header).
    pub(crate) compression: u32,
    /// Index to world.
    pub(crate) world_from_index: DAffine3,
    /// Where the tree topology starts (for an instance grid, where it would).
    pub(crate) end: u64,
}

/// Where a grid's tree lies and what vdb-rs does not read of it.
#[derive(Clone, Debug, Default)]
pub(crate) struct TreeLayout {
    /// The root's background value.
    pub(crate) background: f32,
    /// Root tiles: (origin, value, active); each covers 4096³ voxels.
    pub(crate) root_tiles: Vec<(IVec3, f32, bool)>,
    /// Topology bytes: [start, end).
    pub(crate) topology: (u64, u64),
    /// Leaf buffer bytes: [start, end).
    pub(crate) buffers: (u64, u64),
    /// File positions in the topology where an empty half-float array was written as
    /// nothing; vdb-rs must find an 8-byte zero count there.
    pub(crate) topology_gaps: Vec<u64>,
    /// The same in the leaf buffers.
    pub(crate) buffer_gaps: Vec<u64>,
    /// Leaf nodes in the tree.
    pub(crate) leaf_count: usize,
}

/// A position-tracking reader over the file.
struct Scan {
    r: BufReader<File>,
    pos: u64,
}

impl Scan {
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], LayoutError> {
        let mut b = [0u8; N];
        self.r.read_exact(&mut b)?;
        self.pos += N as u64;
        Ok(b)
    }
    fn u8(&mut self) -> Result<u8, LayoutError> {
        Ok(self.bytes::<1>()?[0])
    }
    fn u32(&mut self) -> Result<u32, LayoutError> {
        self.bytes().map(u32::from_le_bytes)
    }
    fn i32(&mut self) -> Result<i32, LayoutError> {
        self.bytes().map(i32::from_le_bytes)
    }
    fn i64(&mut self) -> Result<i64, LayoutError> {
        self.bytes().map(i64::from_le_bytes)
    }
    fn f32(&mut self) -> Result<f32, LayoutError> {
        self.bytes().map(f32::from_le_bytes)
    }
    fn f64(&mut self) -> Result<f64, LayoutError> {
        self.bytes().map(f64::from_le_bytes)
    }
    fn dvec3(&mut self) -> Result<DVec3, LayoutError> {
        Ok(DVec3::new(self.f64()?, self.f64()?, self.f64()?))
    }
    fn ivec3(&mut self) -> Result<IVec3, LayoutError> {
        Ok(IVec3::new(self.i32()?, self.i32()?, self.i32()?))
    }
    fn skip(&mut self, n: u64) -> Result<(), LayoutError> {
        let n = i64::try_from(n).map_err(|_| LayoutError::Malformed("absurd skip".into()))?;
        self.r.seek_relative(n)?;
        self.pos += n as u64;
        Ok(())
    }
    fn seek(&mut self, to: u64) -> Result<(), LayoutError> {
        self.r.seek(SeekFrom::Start(to))?;
        self.pos = to;
        Ok(())
    }
    /// An OpenVDB string: u32 length, then bytes.
    fn string(&mut self) -> Result<String, LayoutError> {
        let len = self.u32()? as usize;
        if len > 1 << 20 {
            return Err(LayoutError::Malformed(format!("string of {len} bytes")));
        }
        let mut s = vec![0u8; len];
        self.r.read_exact(&mut s)?;
        self.pos += len as u64;
        Ok(String::from_utf8_lossy(&s).into_owned())
    }
    /// A node mask of `bits` bits, counting its set bits.
    fn mask(&mut self, bits: usize) -> Result<(Vec<u64>, usize), LayoutError> {
        let mut words = vec![0u64; bits / 64];
        for w in words.iter_mut() {
            *w = u64::from_le_bytes(self.bytes()?);
        }
        let ones = words.iter().map(|w| w.count_ones() as usize).sum();
        Ok((words, ones))
    }
}

/// Opens `file` for a walk.
fn scan(file: &File) -> Result<Scan, LayoutError> {
    Ok(Scan { r: BufReader::with_capacity(1 << 16, file.try_clone()?), pos: 0 })
}

/// Reads the grid header at `grid_pos`: compression flags, metadata (skipped) and transform.
pub(crate) fn read_grid_header(file: &File, grid_pos: u64) -> Result<GridHeader, LayoutError> {
    let mut s = scan(file)?;
    s.seek(grid_pos)?;
    let compression = s.u32()?;
    let count = s.u32()?;
    for _ in 0..count {
        s.string()?;
        s.string()?;
        let len = s.u32()?;
        s.skip(u64::from(len))?;
    }
    let map_name = s.string()?;
    let (matrix, translation) = match map_name.as_str() {
        // Scale maps store scale, voxel size and three derived vectors.
        "UniformScaleMap" | "ScaleMap" => {
            let scale = s.dvec3()?;
            s.skip(4 * 24)?;
            (DMat3::from_diagonal(scale), DVec3::ZERO)
        }
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
            let translation = s.dvec3()?;
            let scale = s.dvec3()?;
            s.skip(4 * 24)?;
            (DMat3::from_diagonal(scale), translation)
        }
        "TranslationMap" => (DMat3::IDENTITY, s.dvec3()?),
        // A 4×4 matrix for row vectors (world = [i j k 1] · M): its rows are the columns of
        // the column-vector matrix, its last row the translation.
        "AffineMap" | "UnitaryMap" => {
            let mut m = [0.0; 16];
            for v in m.iter_mut() {
                *v = s.f64()?;
            }
            let row = |r: usize| DVec3::new(m[4 * r], m[4 * r + 1], m[4 * r + 2]);
            if m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0 {
                return Err(LayoutError::UnsupportedMap(map_name, "its matrix is projective, not affine".into()));
            }
            (DMat3::from_cols(row(0), row(1), row(2)), row(3))
        }
        "NonlinearFrustumMap" => {
            return Err(LayoutError::UnsupportedMap(
                map_name,
                "frustum grids are not linear; resample the grid to a linear transform".into(),
            ));
        }
        _ => {
            return Err(LayoutError::UnsupportedMap(map_name, "unknown transform type".into()));
        }
    };
    if !(matrix.is_finite() && translation.is_finite()) || matrix.determinant() == 0.0 {
        return Err(LayoutError::UnsupportedMap(map_name, "its matrix is not invertible".into()));
    }
    Ok(GridHeader { compression, world_from_index: DAffine3::from_mat3_translation(matrix, translation), end: s.pos })
}

/// How a grid's value arrays are stored.
struct Values {
    compression: u32,
    half: bool,
}

impl Values {
    /// Skips one `io::readCompressedValues` array of `num_values` values of which `active`
    /// are active; records where an empty half-float array was left out.
    fn skip(&self, s: &mut Scan, num_values: usize, active: usize, gaps: &mut Vec<u64>) -> Result<(), LayoutError> {
        let flag = s.u8()?;
        if flag > 6 {
            return Err(LayoutError::Malformed(format!("per-node compression flag {flag} at byte {}", s.pos - 1)));
        }
        // Flags 2, 4, 5 store one inactive value (always full float), 5 a second one.
        if matches!(flag, 2 | 4 | 5) {
            s.skip(4)?;
        }
        if flag == 5 {
            s.skip(4)?;
        }
        // Flags 3, 4, 5 store a selection mask choosing between inactive values.
        if matches!(flag, 3..=5) {
            s.skip(num_values as u64 / 8)?;
        }
        // Flag 6 (no mask, all values) stores every value; otherwise only the active ones.
        let count = if self.compression & COMPRESS_ACTIVE_MASK != 0 && flag != 6 { active } else { num_values };
        let compressed = self.compression & (COMPRESS_ZIP | COMPRESS_BLOSC) != 0;
        if self.half && count == 0 {
            if compressed {
                gaps.push(s.pos);
            }
            return Ok(());
        }
        if compressed {
            // A byte count: negative for data stored uncompressed.
            let n = s.i64()?;
            s.skip(n.unsigned_abs())
        } else {
            s.skip(count as u64 * if self.half { 2 } else { 4 })
        }
    }
}

/// Walks the tree whose topology starts at `topology_start`, for a grid whose descriptor
/// says its leaf buffers span [`block_pos`, `end_pos`).
pub(crate) fn read_tree_layout(
    file: &File,
    topology_start: u64,
    block_pos: u64,
    end_pos: u64,
    compression: u32,
    half: bool,
) -> Result<TreeLayout, LayoutError> {
    let mut s = scan(file)?;
    s.seek(topology_start)?;
    let values = Values { compression, half };
    let mut layout = TreeLayout { topology: (topology_start, 0), ..TreeLayout::default() };
    let buffer_count = s.u32()?;
    if buffer_count != 1 {
        return Err(LayoutError::Unsupported(format!(
            "the tree has {buffer_count} buffers per leaf; only single-buffer trees are read"
        )));
    }
    layout.background = s.f32()?;
    let tiles = s.u32()?;
    let children = s.u32()?;
    for _ in 0..tiles {
        let origin = s.ivec3()?;
        let value = s.f32()?;
        let active = s.u8()? != 0;
        layout.root_tiles.push((origin, value, active));
    }
    for _ in 0..children {
        s.ivec3()?;
        let (child_mask, _) = s.mask(1 << 15)?;
        let (_, active) = s.mask(1 << 15)?;
        values.skip(&mut s, 1 << 15, active, &mut layout.topology_gaps)?;
        let lowers: u32 = child_mask.iter().map(|w| w.count_ones()).sum();
        for _ in 0..lowers {
            let (lower_children, _) = s.mask(1 << 12)?;
            let (_, active) = s.mask(1 << 12)?;
            values.skip(&mut s, 1 << 12, active, &mut layout.topology_gaps)?;
            let leaves: usize = lower_children.iter().map(|w| w.count_ones() as usize).sum();
            // A leaf's topology is its value mask.
            s.skip(64 * leaves as u64)?;
            layout.leaf_count += leaves;
        }
    }
    layout.topology.1 = s.pos;
    if s.pos != block_pos {
        return Err(LayoutError::Malformed(format!(
            "the tree topology ends at byte {} but the leaf data starts at {block_pos}",
            s.pos
        )));
    }
    for _ in 0..layout.leaf_count {
        let (_, active) = s.mask(512)?;
        values.skip(&mut s, 512, active, &mut layout.buffer_gaps)?;
    }
    layout.buffers = (block_pos, s.pos);
    if s.pos != end_pos {
        return Err(LayoutError::Malformed(format!("the leaf data ends at byte {} but the grid at {end_pos}", s.pos)));
    }
    Ok(layout)
}
