//! nimbus: a renderer for participating media that reads pbrt-v4 scenes.
//!
//! Data flows one way: the `nimbus-parser` crate reads a scene file into a
//! [`nimbus_parser::SceneDescription`]; [`scene`] reads each entity's settings (pbrt-v4's
//! parameter names and defaults); integrators render from there.
#![deny(missing_docs)]

pub mod color;
pub mod geometry;
pub mod integrators;
pub mod materials;
pub mod math;
pub mod sampling;
pub mod scene;
pub mod spectra;

pub use nimbus_parser as parser;
