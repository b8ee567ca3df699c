//! The parser's test suite, one binary with a module per topic.

mod common;
mod directives;
mod errors;
mod params;
mod roundtrip;
