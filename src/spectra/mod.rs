//! Spectral data: the named spectra pbrt-v4 scenes may refer to.

mod named;

pub use named::{NAMED_SPECTRA, is_named_spectrum};
