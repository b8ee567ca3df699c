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

/// A cube [-1, 1]³ bounding medium `name` through an `interface` surface, in its own attribute
/// block: the media tests' standard volume.
pub fn medium_cube(name: &str) -> String {
    format!(
        r#"AttributeBegin
  MediumInterface "{name}" ""
  Material "interface"
  Shape "trianglemesh" "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  3 7 6 3 6 2  0 4 7 0 7 3  1 2 6 1 6 5 ]
    "point3 P" [ -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ]
AttributeEnd"#
    )
}

/// Camera, sampler and 16×16 film looking down −z at the unit cube's centre (the central ray
/// sees through [-1, 1]³), rendered by `integrator` with `maxdepth` `depth`.
pub fn media_header(integrator: &str, spp: u32, depth: u32) -> String {
    format!(
        r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-0.5 0.5 -0.5 0.5]
Sampler "sobol" "integer pixelsamples" {spp}
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "{integrator}" "integer maxdepth" {depth}
"#
    )
}

/// `n`³ copies of the voxel value(s) `v`, as a grid parameter's text.
pub fn grid_values(n: usize, v: &str) -> String {
    vec![v; n * n * n].join(" ")
}
