//! Helpers shared by the end-to-end tests.

use std::path::PathBuf;
use std::process::{Command, Output};

/// The pbrt-v4 parity scenes shipped beside the repository.
pub fn reference_scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/pbrt-v4-references/scenes")
}

/// All `.pbrt` files of the parity suite, sorted.
pub fn reference_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(reference_scenes_dir())
        .expect("../shared/pbrt-v4-references/scenes exists beside the repository")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "pbrt"))
        .collect();
    v.sort();
    v
}

/// Runs the `nimbus` binary.
pub fn nimbus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nimbus")).args(args).output().expect("nimbus runs")
}

/// A fresh directory for one test's files.
pub fn scratch_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nimbus-test-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
