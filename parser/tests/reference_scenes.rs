//! Every pbrt-v4 reference scene of the project (`pbrt-scenes/pbrt-v4-references/scenes`)
//! loads, prints and parses back, and reads the same from a `.pbrt.gz`.

use std::path::{Path, PathBuf};

use nimbus_parser::{SceneDescription, directives_of_str, load_file, load_str, to_pbrt};

use crate::common::TempDir;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../pbrt-scenes/pbrt-v4-references/scenes")
}

/// Every `.pbrt` file of the reference scenes, sorted.
fn scene_files() -> Vec<PathBuf> {
    let dir = scenes_dir();
    let entries = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("the reference scenes should be at {} (in the repository): {e}", dir.display()));
    let mut files: Vec<PathBuf> =
        entries.map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "pbrt")).collect();
    files.sort();
    files
}

/// What each known scene holds: shapes, lights, area lights, (medium, type), camera medium.
type Expected = (&'static str, usize, usize, usize, &'static [(&'static str, &'static str)], Option<&'static str>);

const EXPECTED: [Expected; 9] = [
    ("cornell-surfaces", 6, 0, 1, &[], None),
    ("emissive-grid", 2, 1, 0, &[("fire", "uniformgrid")], None),
    ("fog-spotlight", 3, 1, 0, &[("fog", "homogeneous")], Some("fog")),
    ("graph-cloud", 1, 1, 0, &[("cloud", "uniformgrid")], None),
    ("grid-cloud", 2, 2, 0, &[("cloud", "uniformgrid")], None),
    ("homogeneous-sphere", 2, 2, 0, &[("cloud", "homogeneous")], None),
    ("rgbgrid-smoke", 1, 2, 0, &[("smoke", "rgbgrid")], None),
    ("vdb-cloud", 2, 2, 0, &[("cloud", "nanovdb")], None),
    ("wax-dielectric", 3, 0, 1, &[("wax", "homogeneous")], None),
];

/// The counts a scene is compared by.
fn summary(s: &SceneDescription) -> (usize, usize, usize, Vec<(String, String)>, Option<String>) {
    (
        s.shapes.len(),
        s.lights.len(),
        s.area_lights.len(),
        s.media.iter().map(|m| (m.name.clone(), m.entity.name.clone())).collect(),
        s.camera.medium.clone(),
    )
}

#[test]
fn every_reference_scene_loads() {
    let files = scene_files();
    assert!(
        files.len() >= EXPECTED.len(),
        "expected at least {} scenes in {}, found {files:?}",
        EXPECTED.len(),
        scenes_dir().display()
    );
    for path in &files {
        let scene = load_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(scene.warnings.is_empty(), "{}: {:?}", path.display(), scene.warnings);
        assert!(!scene.shapes.is_empty(), "{}", path.display());
    }
}

#[test]
fn reference_scenes_hold_what_they_say() {
    for (name, shapes, lights, area_lights, media, camera_medium) in EXPECTED {
        let path = scenes_dir().join(format!("{name}.pbrt"));
        let scene = load_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let media: Vec<(String, String)> = media.iter().map(|(n, t)| (n.to_string(), t.to_string())).collect();
        assert_eq!(summary(&scene), (shapes, lights, area_lights, media, camera_medium.map(str::to_string)), "{name}");
        assert_eq!(scene.camera.entity.name, "perspective", "{name}");
        assert_eq!(scene.film.params.get_one_int("xresolution", 0), Ok(128));
        assert_eq!(scene.sampler.params.get_one_int("pixelsamples", 0), Ok(64));
    }
}

#[test]
fn grid_media_hold_every_voxel() {
    for (name, values, param, per_voxel) in [
        ("emissive-grid", "fire", "density", 1),
        ("emissive-grid", "fire", "temperature", 1),
        ("graph-cloud", "cloud", "density", 1),
        ("grid-cloud", "cloud", "density", 1),
        ("rgbgrid-smoke", "smoke", "sigma_s", 3),
        ("rgbgrid-smoke", "smoke", "sigma_a", 3),
    ] {
        let scene = load_file(&scenes_dir().join(format!("{name}.pbrt"))).unwrap();
        let p = &scene.medium(values).unwrap().entity.params;
        let n = |axis: &str| p.get_one_int(axis, 0).unwrap() as usize;
        let voxels = n("nx") * n("ny") * n("nz");
        let count =
            if per_voxel == 3 { p.get_rgbs(param).unwrap().len() * 3 } else { p.get_floats(param).unwrap().len() };
        assert_eq!(count, voxels * per_voxel, "{name} {param}");
    }
}

#[test]
fn fog_spotlight_media_and_interfaces() {
    let scene = load_file(&scenes_dir().join("fog-spotlight.pbrt")).unwrap();
    assert_eq!(scene.camera.medium.as_deref(), Some("fog"));
    assert_eq!(scene.lights[0].medium.as_deref(), Some("fog"));
    let bounding = &scene.shapes[0];
    assert_eq!(bounding.entity.params.get_one_float("radius", 1.0), Ok(30.0));
    assert_eq!(
        bounding.medium_interface,
        Some(nimbus_parser::MediumInterface { inside: Some("fog".into()), outside: None })
    );
}

#[test]
fn cornell_surfaces_named_spectra() {
    let scene = load_file(&scenes_dir().join("cornell-surfaces.pbrt")).unwrap();
    let gold = scene.materials.iter().find(|m| m.name == "conductor").unwrap();
    match gold.params.get_one_spectrum("eta").unwrap().unwrap().value {
        nimbus_parser::SpectrumValue::Named(n) => assert_eq!(n, "metal-Au-eta"),
        other => panic!("{other:?}"),
    }
    assert_eq!(scene.shapes[0].area_light, Some(0));
}

#[test]
fn reference_scenes_print_and_parse_back() {
    for path in scene_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        let name = path.to_string_lossy();
        let directives = directives_of_str(&text, &name).unwrap();
        let printed = to_pbrt(&directives);
        assert_eq!(directives_of_str(&printed, "printed.pbrt").unwrap(), directives, "{name}");
        let original = load_file(&path).unwrap();
        let reloaded = load_str(&printed, &name).unwrap();
        assert_eq!(summary(&reloaded), summary(&original), "{name}");
    }
}

#[test]
fn reference_scenes_read_the_same_gzip_compressed() {
    let dir = TempDir::new();
    for path in scene_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        let file = path.file_name().unwrap().to_string_lossy();
        let gz = dir.write_gz(&format!("{file}.gz"), &text);
        let original = load_file(&path).unwrap();
        let compressed = load_file(&gz).unwrap();
        assert_eq!(summary(&compressed), summary(&original), "{file}");
        // Same parameters, everywhere.
        for (a, b) in original.shapes.iter().zip(&compressed.shapes) {
            let values = |s: &nimbus_parser::ShapeEntity| {
                s.entity.params.iter().map(|p| (p.ty, p.name.clone(), p.values.clone())).collect::<Vec<_>>()
            };
            assert_eq!(values(a), values(b), "{file}");
        }
    }
}
