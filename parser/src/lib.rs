//! Reads pbrt-v4 scene files.
//!
//! The pipeline is the one pbrt-v4 uses: a tokenizer splits the text, the parser turns tokens
//! into [`Directive`]s and hands them to a [`ParserTarget`], and the [`SceneBuilder`] target
//! follows the graphics state to produce a [`SceneDescription`]: typed entities (camera, film,
//! shapes, lights, media, ...) with their parameters, transforms and source locations. Every
//! error names `file:line:col`. This crate knows nothing about rendering.
//!
//! ```
//! let scene = nimbus_parser::load_str(
//!     r#"Camera "perspective" "float fov" 45
//!        WorldBegin
//!        Shape "sphere" "float radius" 2"#,
//!     "example.pbrt",
//! ).unwrap();
//! assert_eq!(scene.shapes[0].entity.params.get_one_float("radius", 1.0).unwrap(), 2.0);
//! ```
#![deny(missing_docs)]

mod builder;
mod description;
mod directive;
mod error;
mod loc;
mod number;
mod params;
mod parser;
mod printer;
mod tokenizer;
pub mod transform;

use std::path::Path;

pub use builder::SceneBuilder;
pub use description::{
    AnimatedTransform, CameraEntity, ColorSpace, Entity, InstanceDefinition, InstanceUse, LightEntity, MaterialRef,
    MediumEntity, MediumInterface, NamedMaterialEntity, SceneDescription, SceneOptions, ShapeEntity, TextureEntity,
    TextureValue,
};
pub use directive::{ActiveTransform, Directive};
pub use error::{Error, Result, Warning};
pub use loc::{FileLoc, shown as loc_shown};
pub use params::{
    FloatOrTexture, Param, ParamType, ParamValues, ParameterDictionary, SpectrumOrTexture, SpectrumParam, SpectrumValue,
};
pub use parser::{DirectiveRecorder, ParserTarget, parse_bytes, parse_file, parse_str};
pub use printer::{directive_to_string, quote, to_pbrt};

/// Reads a scene file (`.pbrt`, `.pbrt.gz`, or `-` for standard input) into a description.
pub fn load_file(path: &Path) -> Result<SceneDescription> {
    let mut builder = SceneBuilder::new();
    parse_file(path, &mut builder)?;
    builder.finish()
}

/// Reads scene text into a description; `name` stands for its file in locations.
pub fn load_str(text: &str, name: &str) -> Result<SceneDescription> {
    let mut builder = SceneBuilder::new();
    parse_str(text, name, &mut builder)?;
    builder.finish()
}

/// Reads the directives of scene text without following `Include`/`Import` or building a
/// scene: what a formatter or a round-trip test wants.
pub fn directives_of_str(text: &str, name: &str) -> Result<Vec<Directive>> {
    let mut r = DirectiveRecorder::default();
    parse_str(text, name, &mut r)?;
    Ok(r.directives.into_iter().map(|(d, _)| d).collect())
}
