//! One handle for either VDB format, as the `nanovdb` and `vdb` media need.

use std::path::Path;

use super::{GridError, NanoVdbFile, OpenVdbFile, SparseGrid};

/// A NanoVDB or OpenVDB file, opened once and asked for grids by name.
#[derive(Debug)]
pub enum VdbFile {
    /// A `.nvdb` file (pbrt-v4's `nanovdb` medium).
    NanoVdb(NanoVdbFile),
    /// A `.vdb` file (nimbus's `vdb` medium).
    OpenVdb(OpenVdbFile),
}

impl VdbFile {
    /// Opens `path` as OpenVDB if `openvdb`, else as NanoVDB (the medium's type decides, not
    /// the file name).
    pub fn open(path: impl AsRef<Path>, openvdb: bool) -> Result<VdbFile, GridError> {
        Ok(if openvdb {
            VdbFile::OpenVdb(OpenVdbFile::open(path)?)
        } else {
            VdbFile::NanoVdb(NanoVdbFile::open(path)?)
        })
    }

    /// Names of the grids in the file, in file order.
    pub fn grid_names(&self) -> Vec<&str> {
        match self {
            VdbFile::NanoVdb(f) => f.grid_names(),
            VdbFile::OpenVdb(f) => f.grid_names(),
        }
    }

    /// True if the file has a grid named `name`.
    pub fn has_grid(&self, name: &str) -> bool {
        match self {
            VdbFile::NanoVdb(f) => f.has_grid(name),
            VdbFile::OpenVdb(f) => f.has_grid(name),
        }
    }

    /// Reads grid `name`; see [`NanoVdbFile::read_grid`] and [`OpenVdbFile::read_grid`].
    pub fn read_grid(&self, name: &str) -> Result<SparseGrid, GridError> {
        match self {
            VdbFile::NanoVdb(f) => f.read_grid(name),
            VdbFile::OpenVdb(f) => f.read_grid(name),
        }
    }
}
