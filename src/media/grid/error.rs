//! Why a volume grid file could not be read. Every message names the file, and the grid where
//! one is concerned, so a scene error points at what to fix.

use std::path::PathBuf;

/// An error reading a NanoVDB or OpenVDB grid.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    /// The file could not be opened or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not what its format says it should be (truncated, corrupt, wrong format).
    #[error("{}: {message}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        message: String,
    },
    /// No grid of that name; lists the grids present.
    #[error("{}: no grid named \"{name}\"; the file holds {}", path.display(), list_grids(available))]
    GridNotFound {
        /// The file.
        path: PathBuf,
        /// The name asked for.
        name: String,
        /// Grids in the file, as "name (type)".
        available: Vec<String>,
    },
    /// The grid's values are not of a type nimbus reads.
    #[error(
        "{}: grid \"{grid}\" holds {value_type} values; only float (scalar) grids are supported{}",
        path.display(),
        hint_for(value_type)
    )]
    UnsupportedValueType {
        /// The file.
        path: PathBuf,
        /// The grid.
        grid: String,
        /// The value type as the file names it.
        value_type: String,
    },
    /// pbrt-v4 reads only fog volumes (or grids of unknown class) as media.
    #[error(
        "{}: grid \"{grid}\" is a {class} grid, not a fog volume; pbrt-v4 reads only \
         FogVolume (or Unknown) grids as media",
        path.display()
    )]
    NotFogVolume {
        /// The file.
        path: PathBuf,
        /// The grid.
        grid: String,
        /// The grid class found.
        class: String,
    },
    /// The file's compression is not supported.
    #[error("{}: {codec} compression is not supported; {advice}", path.display())]
    UnsupportedCodec {
        /// The file.
        path: PathBuf,
        /// The codec.
        codec: String,
        /// What to do instead.
        advice: String,
    },
    /// The grid's index-to-world transform is of a kind nimbus cannot use.
    #[error("{}: grid \"{grid}\" has a {map} transform, which is not supported ({reason})", path.display())]
    UnsupportedTransform {
        /// The file.
        path: PathBuf,
        /// The grid.
        grid: String,
        /// The transform's type name.
        map: String,
        /// Why.
        reason: String,
    },
    /// The grid has something nimbus's OpenVDB reader cannot represent faithfully.
    #[error("{}: grid \"{grid}\": {message}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// The grid.
        grid: String,
        /// What, and what to do about it.
        message: String,
    },
    /// The grid has no active voxels (an empty medium is almost certainly a mistake).
    #[error("{}: grid \"{grid}\" has no active voxels", path.display())]
    EmptyGrid {
        /// The file.
        path: PathBuf,
        /// The grid.
        grid: String,
    },
    /// The grid's bounding box is too large for the brick table.
    #[error(
        "{}: grid \"{grid}\" spans {cells} 8³ bricks, more than the sparse grid's table allows",
        path.display()
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The grid.
        grid: String,
        /// Table cells needed.
        cells: u64,
    },
}

fn list_grids(available: &[String]) -> String {
    if available.is_empty() { "no grids".to_string() } else { available.join(", ") }
}

fn hint_for(value_type: &str) -> &'static str {
    if value_type == "half" {
        " (NanoVDB half grids are not read: write float, or quantise with nanovdb_convert --fp16)"
    } else if value_type.contains("vec3") || value_type.contains("Vec3") {
        " (a vector grid, e.g. velocity, cannot be a density or temperature)"
    } else {
        ""
    }
}
