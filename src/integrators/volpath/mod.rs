//! `volpath`: pbrt-v4's volumetric path tracer, the reference every other method is checked
//! against.

mod settings;

pub use settings::{LightSamplerKind, VolPathSettings};
