//! Helpers shared by the test modules.

use std::path::{Path, PathBuf};

use glam::DMat4;
use nimbus_parser::{Directive, Error, SceneDescription, directives_of_str, load_str};

/// The file name test scenes parsed from strings are given.
pub const NAME: &str = "t.pbrt";

/// Builds the scene `text`, which must load.
#[track_caller]
pub fn load(text: &str) -> SceneDescription {
    match load_str(text, NAME) {
        Ok(scene) => scene,
        Err(e) => panic!("scene failed to load: {e}\n--- scene ---\n{text}"),
    }
}

/// Builds the scene `text`, which must fail; returns the error.
#[track_caller]
pub fn load_err(text: &str) -> Error {
    match load_str(text, NAME) {
        Ok(_) => panic!("scene loaded but should not have:\n{text}"),
        Err(e) => e,
    }
}

/// The error of `text` as `file:line:col: message`.
#[track_caller]
pub fn load_err_string(text: &str) -> String {
    load_err(text).to_string()
}

/// The directives of `text`, which must parse.
#[track_caller]
pub fn directives(text: &str) -> Vec<Directive> {
    match directives_of_str(text, NAME) {
        Ok(d) => d,
        Err(e) => panic!("directives failed to parse: {e}\n--- text ---\n{text}"),
    }
}

/// The single directive of `text`.
#[track_caller]
pub fn directive(text: &str) -> Directive {
    let mut d = directives(text);
    assert_eq!(d.len(), 1, "expected one directive in {text:?}, got {d:?}");
    d.remove(0)
}

/// The parse error of `text` (directives only, no scene building) as `file:line:col: message`.
#[track_caller]
pub fn parse_err_string(text: &str) -> String {
    match directives_of_str(text, NAME) {
        Ok(d) => panic!("text parsed but should not have: {d:?}\n--- text ---\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A scene with the options block `options` and the world block `world`.
pub fn scene(options: &str, world: &str) -> String {
    format!("{options}\nWorldBegin\n{world}\n")
}

/// A temporary directory removed when dropped.
pub struct TempDir(tempfile::TempDir);

impl TempDir {
    pub fn new() -> TempDir {
        TempDir(tempfile::Builder::new().prefix("nimbus-parser-test-").tempdir().expect("create a temporary directory"))
    }

    pub fn path(&self) -> &Path {
        self.0.path()
    }

    /// Writes `text` to `name` (which may contain subdirectories) and returns its path.
    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.path().join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("create directories");
        }
        std::fs::write(&path, text).expect("write a test file");
        path
    }

    /// Writes `text` gzip-compressed to `name` and returns its path.
    pub fn write_gz(&self, name: &str, text: &str) -> PathBuf {
        use std::io::Write;
        let path = self.path().join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("create directories");
        }
        let file = std::fs::File::create(&path).expect("create a test file");
        let mut gz = flate2::write::GzEncoder::new(file, flate2::Compression::default());
        gz.write_all(text.as_bytes()).expect("compress");
        gz.finish().expect("finish the gzip stream");
        path
    }
}

/// Asserts that two matrices agree to within `1e-9` in every element.
#[track_caller]
pub fn assert_mat_close(actual: DMat4, expected: DMat4) {
    let a = actual.to_cols_array();
    let e = expected.to_cols_array();
    let ok = a.iter().zip(e.iter()).all(|(x, y)| (x - y).abs() < 1e-9);
    assert!(ok, "matrices differ:\nactual   {actual:?}\nexpected {expected:?}");
}

/// A matrix given row by row, as matrices are written on paper.
pub fn rows(r: [[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(&r).transpose()
}
