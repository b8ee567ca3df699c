//! Sparse voxel grids and the VDB files they are read from.

mod error;
mod nanovdb;
mod openvdb;
mod openvdb_layout;
mod sparse;
mod spliced_stream;

pub use error::GridError;
pub use nanovdb::NanoVdbFile;
pub use openvdb::OpenVdbFile;
pub use sparse::SparseGrid;
