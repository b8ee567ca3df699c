//! Errors from reading or converting spectra.

use std::path::PathBuf;

/// Why a spectrum could not be read or converted.
#[derive(Debug, thiserror::Error)]
pub enum SpectrumError {
    /// A spectrum file could not be read at all.
    #[error("{}: cannot read spectrum file: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A spectrum's samples are malformed; `origin` names the file or says "inline".
    #[error("{origin}: {message}")]
    Invalid {
        /// The file, or a description of where the samples came from.
        origin: String,
        /// What is wrong with them.
        message: String,
    },
    /// A name that is not one of pbrt-v4's named spectra.
    #[error("\"{0}\" is not a named spectrum")]
    UnknownName(String),
}
