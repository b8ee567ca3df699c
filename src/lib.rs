//! nimbus: a renderer for participating media that reads pbrt-v4 scenes.
//!
//! Data flows one way: the `nimbus-parser` crate reads a scene file into a
//! [`nimbus_parser::SceneDescription`]; [`scene`] reads each entity's settings (pbrt-v4's
//! parameter names and defaults) and builds the scene; [`setup`] pairs it with the method
//! ([`integrators`]) that renders it; [`render`] runs the method over the film.
#![deny(missing_docs)]

pub mod accel;
pub mod camera;
pub mod channels;
pub mod color;
pub mod error;
pub mod film;
pub mod geometry;
pub mod imageio;
pub mod integrators;
pub mod lights;
pub mod materials;
pub mod math;
pub mod media;
pub mod metrics;
pub mod params;
pub mod render;
pub mod samplers;
pub mod sampling;
pub mod scene;
pub mod setup;
pub mod shapes;
pub mod spectra;
pub mod textures;

pub use error::{Error, Result};
pub use nimbus_parser as parser;
