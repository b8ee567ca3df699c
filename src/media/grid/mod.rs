//! Sparse voxel grids and the VDB files they are read from.
//!
//! [`SparseGrid`] is the one grid type media sample: float voxels in 8³ bricks found
//! through a dense table, with trilinear lookups as pbrt-v4's `nanovdb` medium does them and
//! per-brick maxima for majorants. [`NanoVdbFile`] parses NanoVDB files itself;
//! [`OpenVdbFile`] reads OpenVDB files through vdb-rs, with nimbus's own walk of the file
//! layout covering what vdb-rs cannot read. [`VdbFile`] opens either. Both readers accept
//! what pbrt-v4 accepts for media: float grids of class fog volume or unknown.
//!
//! Fixtures for the tests are written by `tests/fixtures/vdb/generate.py`.

mod error;
mod file;
mod nanovdb;
mod openvdb;
mod openvdb_layout;
mod sparse;
mod spliced_stream;

pub use error::GridError;
pub use file::VdbFile;
pub use nanovdb::NanoVdbFile;
pub use openvdb::OpenVdbFile;
pub use sparse::SparseGrid;

#[cfg(test)]
mod vdb_tests;
