//! Participating media: phase functions, media (homogeneous, grids, procedural, VDB), the
//! volume data they are built from, and majorant grids for delta tracking.

pub mod cloud;
pub mod dense;
pub mod grid;
pub mod majorant;
mod medium;
pub mod phase;
mod rgbgrid;

pub use medium::{Density, Emission, Field, GridMedium, Medium, MediumKind, MediumPoint, MediumView, Segments};
pub use rgbgrid::RgbGridMedium;
