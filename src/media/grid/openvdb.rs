//! OpenVDB files (`.vdb`), read for nimbus's `vdb` medium through vdb-rs.
//!
//! vdb-rs 0.6 decodes the tree (including Blosc and Zip compression and half floats); its gaps
//! are closed here rather than left to crash or to yield an empty medium:
//! - Transforms: vdb-rs panics on anything but (uniform) scale and scale-translate maps. nimbus
//!   reads the transform itself ([`openvdb_layout`](super::openvdb_layout)): scale,
//!   scale-translate, translation, affine and unitary maps; frustum maps are an error.
//! - Compressed half-float grids: OpenVDB omits empty half arrays entirely, which throws
//!   vdb-rs off ("Invalid node meta-data" or a failed assertion). The layout walk finds every
//!   omission and vdb-rs is shown the stream with an empty array written in.
//! - Non-float grids (vec3, double, …): vdb-rs would read them as empty; the grid type is
//!   checked first and reported.
//! - vdb-rs drops the root's background and tiles: both are read by the layout walk; a
//!   nonzero background is refused because vdb-rs fills inactive values as if it were zero.
//!
//! - Instance grids (sharing another grid's tree): vdb-rs would read a tree that is not there;
//!   the parent's tree is read with the instance's transform.
//!
//! vdb-rs is shown each grid in a form it reads: pieces appended after the file's end
//! ([`SplicedStream`]) hold a header with a transform it understands, then the tree's
//! topology and leaf buffers with the omitted arrays written in, and the grid's descriptor
//! points there. The file is neither copied nor changed. Any panic left in vdb-rs is caught
//! and reported as an error.

use std::fs::File;
use std::io::Read;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use glam::IVec3;
use vdb_rs::{GridDescriptor, MetadataValue, VdbReader};

use super::error::GridError;
use super::openvdb_layout::{
    GridHeader, LayoutError, MIN_FILE_VERSION, TreeLayout, read_grid_header, read_tree_layout,
};
use super::sparse::{BRICK_VOXELS, BuildIssue, SparseGrid, SparseGridBuilder};
use super::spliced_stream::{Piece, SplicedStream};

/// An OpenVDB file whose grid descriptors have been read; grids are read on request.
#[derive(Debug)]
pub struct OpenVdbFile {
    path: PathBuf,
    /// Descriptors in file order.
    grids: Vec<GridDescriptor>,
}

/// The message of a caught panic.
fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// The value type in an OpenVDB grid type name ("Tree_float_5_4_3_HalfFloat" → "float"), and
/// whether the tree has the standard 5-4-3 shape.
fn value_type(grid_type: &str) -> (&str, bool) {
    let t = grid_type.strip_prefix("Tree_").unwrap_or(grid_type);
    let t = t.strip_suffix("_HalfFloat").unwrap_or(t);
    match t.strip_suffix("_5_4_3") {
        Some(v) => (v, true),
        None => (t.split('_').next().unwrap_or(t), false),
    }
}

/// The grid's `class` metadata, if any.
fn grid_class(gd: &GridDescriptor) -> Option<&str> {
    match gd.meta_data.0.get("class") {
        Some(MetadataValue::String(s)) => Some(s.as_str()),
        _ => None,
    }
}

/// The file pieces of `range` with an 8-byte zero count written in at each of `gaps`.
fn pieces_with_gaps(range: (u64, u64), gaps: &[u64]) -> Vec<Piece> {
    let mut pieces = Vec::with_capacity(2 * gaps.len() + 1);
    let mut at = range.0;
    for &gap in gaps {
        pieces.push(Piece::File { start: at, len: gap - at });
        pieces.push(Piece::Bytes(vec![0; 8]));
        at = gap;
    }
    pieces.push(Piece::File { start: at, len: range.1 - at });
    pieces
}

/// A grid header vdb-rs can read: the grid's compression flags, no metadata, and a unit
/// `UniformScaleMap` (nimbus has read the real transform already).
fn substitute_header(compression: u32) -> Vec<u8> {
    let mut h = Vec::new();
    h.extend_from_slice(&compression.to_le_bytes());
    h.extend_from_slice(&0u32.to_le_bytes());
    let name = b"UniformScaleMap";
    h.extend_from_slice(&(name.len() as u32).to_le_bytes());
    h.extend_from_slice(name);
    for _ in 0..5 * 3 {
        h.extend_from_slice(&1.0f64.to_le_bytes());
    }
    h
}

impl OpenVdbFile {
    /// Reads the header and grid descriptors of the file at `path`.
    pub fn open(path: impl AsRef<Path>) -> Result<OpenVdbFile, GridError> {
        let path = path.as_ref().to_path_buf();
        let malformed = |message: String| GridError::Malformed { path: path.clone(), message };
        let mut file = File::open(&path).map_err(|source| GridError::Io { path: path.clone(), source })?;
        let len = file.metadata().map_err(|source| GridError::Io { path: path.clone(), source })?.len();
        let mut head = [0u8; 12];
        if file.read_exact(&mut head).is_err() {
            return Err(malformed("too short for an OpenVDB file".into()));
        }
        if &head[..8] != b" BDV\0\0\0\0" {
            return Err(malformed(if head.starts_with(b"NanoVDB") {
                "this is a NanoVDB file; use the \"nanovdb\" medium for .nvdb files".into()
            } else {
                "not an OpenVDB file (no OpenVDB magic number)".into()
            }));
        }
        let file_version = u32::from_le_bytes(head[8..12].try_into().expect("4 bytes"));
        if file_version < MIN_FILE_VERSION {
            return Err(malformed(format!(
                "OpenVDB file format {file_version} predates format {MIN_FILE_VERSION} \
                 (OpenVDB 3.0), the oldest read; re-save the file with a newer OpenVDB"
            )));
        }
        let stream = SplicedStream::new(file, vec![Piece::File { start: 0, len }]);
        let reader = catch_unwind(AssertUnwindSafe(|| VdbReader::new(stream)))
            .map_err(|p| malformed(format!("vdb-rs failed reading the header: {}", panic_message(p))))?
            .map_err(|e| malformed(format!("vdb-rs could not read the header: {e}")))?;
        let mut grids: Vec<GridDescriptor> = reader.grid_descriptors.into_values().collect();
        grids.sort_by_key(|g| g.grid_pos);
        Ok(OpenVdbFile { path, grids })
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

    fn descriptor(&self, name: &str) -> Option<&GridDescriptor> {
        self.grids.iter().find(|g| g.name == name)
    }

    /// Maps a layout walk's error for grid `grid`.
    fn layout_error(&self, grid: &str, e: LayoutError) -> GridError {
        match e {
            LayoutError::Io(source) => GridError::Io { path: self.path.clone(), source },
            LayoutError::Malformed(message) => {
                GridError::Malformed { path: self.path.clone(), message: format!("grid \"{grid}\": {message}") }
            }
            LayoutError::UnsupportedMap(map, reason) => {
                GridError::UnsupportedTransform { path: self.path.clone(), grid: grid.to_string(), map, reason }
            }
            LayoutError::Unsupported(message) => self.unsupported(grid, message),
        }
    }

    fn unsupported(&self, grid: &str, message: String) -> GridError {
        GridError::Unsupported { path: self.path.clone(), grid: grid.to_string(), message }
    }

    /// Reads grid `name` into a [`SparseGrid`]. Only float grids (stored as float or half)
    /// of class fog volume or unknown are read, as pbrt-v4 reads NanoVDB media.
    pub fn read_grid(&self, name: &str) -> Result<SparseGrid, GridError> {
        let Some(gd) = self.descriptor(name) else {
            return Err(GridError::GridNotFound {
                path: self.path.clone(),
                name: name.to_string(),
                available: self.grids.iter().map(|g| format!("{} ({})", g.name, value_type(&g.grid_type).0)).collect(),
            });
        };
        match grid_class(gd) {
            None | Some("fog volume") | Some("unknown") => {}
            Some(class) => {
                return Err(GridError::NotFogVolume {
                    path: self.path.clone(),
                    grid: name.to_string(),
                    class: class.to_string(),
                });
            }
        }
        let (value, standard_shape) = value_type(&gd.grid_type);
        if value != "float" {
            return Err(GridError::UnsupportedValueType {
                path: self.path.clone(),
                grid: name.to_string(),
                value_type: value.to_string(),
            });
        }
        if !standard_shape {
            return Err(self
                .unsupported(name, format!("tree type {} is not the standard 5-4-3 tree vdb-rs reads", gd.grid_type)));
        }

        let io = |source| GridError::Io { path: self.path.clone(), source };
        let file = File::open(&self.path).map_err(io)?;
        let header = read_grid_header(&file, gd.grid_pos).map_err(|e| self.layout_error(name, e))?;
        // An instance grid shares its parent's tree and has a transform of its own.
        let tree_gd = if gd.instance_parent.is_empty() {
            gd
        } else {
            self.descriptor(&gd.instance_parent).ok_or_else(|| GridError::Malformed {
                path: self.path.clone(),
                message: format!("grid \"{name}\" is an instance of \"{}\", which the file lacks", gd.instance_parent),
            })?
        };
        let tree_header = if std::ptr::eq(tree_gd, gd) {
            header.clone()
        } else {
            read_grid_header(&file, tree_gd.grid_pos).map_err(|e| self.layout_error(name, e))?
        };
        let half = tree_gd.meta_data.is_half_float();
        let layout =
            read_tree_layout(&file, tree_header.end, tree_gd.block_pos, tree_gd.end_pos, tree_header.compression, half)
                .map_err(|e| self.layout_error(name, e))?;
        if layout.background != 0.0 {
            return Err(self.unsupported(
                name,
                format!(
                    "its background value is {}; vdb-rs fills inactive voxels as if the \
                     background were 0, so only grids with background 0 are read",
                    layout.background
                ),
            ));
        }
        let tree = self.read_tree(file, name, tree_gd, &tree_header, &layout)?;
        let builder = convert_tree(&tree, &layout).map_err(|message| GridError::Malformed {
            path: self.path.clone(),
            message: format!("grid \"{name}\": {message}"),
        })?;
        let mut grid = builder.build().map_err(|issue| match issue {
            BuildIssue::NoActiveVoxels => GridError::EmptyGrid { path: self.path.clone(), grid: name.to_string() },
            BuildIssue::TooLarge { cells } => {
                GridError::TooLarge { path: self.path.clone(), grid: name.to_string(), cells }
            }
        })?;
        grid.set_transform(header.world_from_index);
        Ok(grid)
    }

    /// Has vdb-rs decode the tree of `tree_gd`, shown to it as the file followed by a grid
    /// header it can read, the topology and the buffers (with omitted arrays written in).
    fn read_tree(
        &self,
        file: File,
        name: &str,
        tree_gd: &GridDescriptor,
        tree_header: &GridHeader,
        layout: &TreeLayout,
    ) -> Result<vdb_rs::Grid<f32>, GridError> {
        let len = file.metadata().map_err(|source| GridError::Io { path: self.path.clone(), source })?.len();
        let mut pieces = vec![Piece::File { start: 0, len }, Piece::Bytes(substitute_header(tree_header.compression))];
        pieces.extend(pieces_with_gaps(layout.topology, &layout.topology_gaps));
        let buffers_piece = pieces.len();
        pieces.extend(pieces_with_gaps(layout.buffers, &layout.buffer_gaps));
        let stream = SplicedStream::new(file, pieces);
        let grid_pos = stream.piece_start(1);
        let block_pos = stream.piece_start(buffers_piece);

        let vdb_rs_failed = |what: String| self.unsupported(name, format!("vdb-rs could not read the grid: {what}"));
        let read = catch_unwind(AssertUnwindSafe(|| {
            let mut reader = VdbReader::new(stream)?;
            let mut descriptor = tree_gd.clone();
            descriptor.name = name.to_string();
            descriptor.instance_parent.clear();
            descriptor.grid_pos = grid_pos;
            descriptor.block_pos = block_pos;
            reader.grid_descriptors.insert(name.to_string(), descriptor);
            reader.read_grid::<f32>(name)
        }));
        let tree = match read {
            Ok(Ok(grid)) => grid,
            Ok(Err(e)) => return Err(vdb_rs_failed(e.to_string())),
            Err(panic) => return Err(vdb_rs_failed(panic_message(panic))),
        };
        Ok(tree)
    }
}

/// Origin of child `n` of an internal node of `log2` at `origin`, children spanning
/// `1 << child_log2` voxels.
fn child_origin(origin: IVec3, n: usize, log2: u32, child_log2: u32) -> IVec3 {
    let m = (1usize << log2) - 1;
    let local = IVec3::new((n >> (2 * log2)) as i32, ((n >> log2) & m) as i32, (n & m) as i32);
    origin + (local << child_log2)
}

/// Copies vdb-rs's tree and the walk's root tiles into a builder.
fn convert_tree(grid: &vdb_rs::Grid<f32>, layout: &TreeLayout) -> Result<SparseGridBuilder, String> {
    let mut builder = SparseGridBuilder::new(layout.background);
    for &(origin, value, active) in &layout.root_tiles {
        builder.add_tile(origin, 4096, value, active);
    }
    let mut leaves = 0;
    for upper in &grid.tree.root_nodes {
        let origin = IVec3::new(upper.origin.x, upper.origin.y, upper.origin.z);
        if upper.data.len() != 1 << 15 || upper.child_mask.len() != 1 << 15 {
            return Err("vdb-rs returned an upper node of the wrong size".into());
        }
        for n in 0..1usize << 15 {
            let at = child_origin(origin, n, 5, 7);
            if !upper.child_mask[n] {
                builder.add_tile(at, 128, upper.data[n], upper.value_mask[n]);
                continue;
            }
            let lower: &vdb_rs::Node4<f32> = upper.nodes.get(&(n as u32)).ok_or("vdb-rs lost a lower node")?;
            if lower.data.len() != 1 << 12 || lower.child_mask.len() != 1 << 12 {
                return Err("vdb-rs returned a lower node of the wrong size".into());
            }
            for m in 0..1usize << 12 {
                let leaf_at = child_origin(at, m, 4, 3);
                if !lower.child_mask[m] {
                    builder.add_tile(leaf_at, 8, lower.data[m], lower.value_mask[m]);
                    continue;
                }
                let leaf = lower.nodes.get(&(m as u32)).ok_or("vdb-rs lost a leaf")?;
                let mask: [u64; 8] = leaf
                    .value_mask
                    .as_raw_slice()
                    .try_into()
                    .map_err(|_| "vdb-rs returned a leaf mask of the wrong size")?;
                if leaf.buffer.len() != BRICK_VOXELS {
                    return Err("vdb-rs returned a leaf of the wrong size".into());
                }
                builder.add_leaf(leaf_at, &leaf.buffer, &mask);
                leaves += 1;
            }
        }
    }
    if leaves != layout.leaf_count {
        return Err(format!("vdb-rs decoded {leaves} leaves where the file has {}", layout.leaf_count));
    }
    Ok(builder)
}
