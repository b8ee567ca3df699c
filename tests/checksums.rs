//! Every shipped scene × every method nimbus has, at a fixed seed and one sample per pixel on a
//! quarter of the film: the images' checksums are those recorded in
//! `tests/fixtures/image-checksums.txt`, bit for bit. They hold the renders fixed while the
//! code is reorganised (issue 34): a change that alters an image must say so in its commit and
//! re-record them (`NIMBUS_RECORD_CHECKSUMS=1 cargo test --test tests checksums`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nimbus::integrators::INTEGRATOR_NAMES;
use nimbus::render::{RenderOptions, render};
use nimbus::scene::BuildOptions;

use crate::common::scratch_dir;

/// The recorded checksums, one line per scene and method: `scene method checksum`, where the
/// checksum is FNV-1a over the image's size and pixels' bits, or `refused`.
const RECORD: &str = "tests/fixtures/image-checksums.txt";

/// A coarse, quick radiance graph for scenes inside its constraints (the checksum is of the
/// method's code, not of a good graph).
const GRAPH_CONFIG: &str = r#"{"graphBuilder": {"radiusModifier": 40, "dimensionSteps": 40, "iterationsPerStep": 4},
 "lightingCalculator": {"lightIterations": 1, "bounces": [4]}}"#;

/// Every scene nimbus ships: the suite, pbrt-v4's references and nimbus's own parity scenes.
fn shipped_scenes(root: &Path) -> Vec<PathBuf> {
    let mut scenes = Vec::new();
    for dir in [
        "pbrt-scenes",
        "pbrt-scenes/pbrt-v4-references/scenes",
        "pbrt-scenes/pbrt-v4-parity",
        "pbrt-scenes/disney-cloud",
    ] {
        for entry in std::fs::read_dir(root.join(dir)).unwrap_or_else(|e| panic!("{dir}: {e}")) {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "pbrt") {
                scenes.push(path);
            }
        }
    }
    scenes.sort();
    scenes
}

/// FNV-1a, 64 bits, over the image's size and its pixels' bits.
fn checksum(img: &nimbus::imageio::Image) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let words = [img.width as u32, img.height as u32]
        .into_iter()
        .chain(img.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)));
    for w in words {
        for b in w.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// `scene`'s line for `integrator`: its checksum, or `refused`.
fn line(root: &Path, scene: &Path, integrator: &str, graph_dir: &Path) -> String {
    let name = scene.strip_prefix(root).unwrap().to_string_lossy().into_owned();
    let desc = nimbus::parser::load_file(scene).unwrap_or_else(|e| panic!("{name}: {e}"));
    // The radiance graph reads its config beside the scene file: a coarse one in scratch.
    let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
    std::fs::write(graph_dir.join(format!("{stem}.json")), GRAPH_CONFIG).unwrap();
    let opts = BuildOptions {
        integrator: Some(integrator.into()),
        spp: Some(1),
        seed: Some(17),
        quick: true,
        scene_file: Some(graph_dir.join(format!("{stem}.pbrt"))),
        ..Default::default()
    };
    let outcome = nimbus::setup::build(&desc, &opts).map_err(|e| e.to_string()).and_then(|scene| {
        let method = scene.integrator.create(&scene)?;
        Ok(render(&scene, method.as_ref(), &RenderOptions { time_budget: None, quiet: true }).image)
    });
    match outcome {
        Ok(img) => format!("{name} {integrator} {:016x}", checksum(&img)),
        Err(_) => format!("{name} {integrator} refused"),
    }
}

#[test]
fn every_shipped_scene_renders_as_recorded() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let graph_dir = scratch_dir("checksums");
    let mut lines = String::new();
    for scene in shipped_scenes(root) {
        for &integrator in INTEGRATOR_NAMES {
            writeln!(lines, "{}", line(root, &scene, integrator, &graph_dir)).unwrap();
        }
    }
    if std::env::var_os("NIMBUS_RECORD_CHECKSUMS").is_some() {
        std::fs::write(root.join(RECORD), &lines).unwrap();
        return;
    }
    let recorded = std::fs::read_to_string(root.join(RECORD)).unwrap_or_else(|e| panic!("{RECORD}: {e}"));
    let changed: Vec<String> = lines
        .lines()
        .zip(recorded.lines().chain(std::iter::repeat("")))
        .filter(|(now, then)| now != then)
        .map(|(now, then)| format!("  now {now}\n  was {then}"))
        .collect();
    assert!(
        changed.is_empty() && lines.lines().count() == recorded.lines().count(),
        "{} of {} images differ from {RECORD} (re-record only for a change the commit names):\n{}",
        changed.len(),
        lines.lines().count(),
        changed.join("\n")
    );
}
