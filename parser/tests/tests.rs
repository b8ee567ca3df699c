//! The parser's test suite: one test binary, a module per topic.

mod common;
mod directives;
mod errors;
mod files;
mod params;
mod reference_scenes;
mod roundtrip;
mod scene;
mod transforms;
