//! From description to scene objects. Each entity kind has a settings reader that takes its
//! parameters with pbrt-v4's names and defaults, validates them, and leaves unknown ones to
//! be reported; rendering builds on these settings.

pub mod lights;
pub mod materials;
pub mod media;
pub mod shapes;
pub mod textures;
pub mod transport;

mod build;
mod check;
mod spectra;

pub use build::{BuildOptions, BuildStats, Scene, build_scene};
pub use check::{SceneCheck, check_scene, unused_parameters};
