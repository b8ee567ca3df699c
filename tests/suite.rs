//! The scene suite in pbrt-scenes/: every scene, rendered at low spp with each integrator
//! its README names, agrees with its volpath reference within the noise we measure.

use nimbus::render::{RenderOptions, render};
use nimbus::scene::{BuildOptions, build_scene};

/// The integrators pbrt-scenes/README.md names for a scene.
fn integrators_for(readme: &str, scene: &str) -> Vec<String> {
    readme
        .lines()
        .find(|l| l.starts_with(&format!("| `{scene}.pbrt`")))
        .and_then(|l| l.trim_end().trim_end_matches('|').rsplit('|').next().map(str::to_string))
        .map(|s| s.split(',').map(|x| x.trim().to_string()).filter(|x| !x.is_empty() && x != "—").collect())
        .unwrap_or_default()
}

#[test]
fn every_scene_matches_its_reference() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes");
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap();
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "pbrt") {
            continue;
        }
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        assert!(readme.contains(&format!("| `{name}.pbrt`")), "{name} has no line in pbrt-scenes/README.md");
        let integrators = integrators_for(&readme, &name);
        if integrators.is_empty() {
            continue;
        }
        let reference = nimbus::imageio::read_exr(&dir.join(format!("references/{name}.exr")))
            .unwrap_or_else(|e| panic!("{name}: missing reference: {e}"));
        let desc = nimbus::parser::load_file(&path).unwrap();
        for integrator in integrators {
            let render_seed = |seed| {
                let opts = BuildOptions {
                    integrator: Some(integrator.clone()),
                    spp: Some(16),
                    seed: Some(seed),
                    ..Default::default()
                };
                let scene = build_scene(&desc, &opts).unwrap_or_else(|e| panic!("{name}/{integrator}: {e}"));
                let i = scene.integrator.create();
                render(&scene, i.as_ref(), &RenderOptions { time_budget: None, quiet: true }).image
            };
            let (a, b) = (render_seed(101), render_seed(202));
            assert_eq!((a.width, a.height), (reference.width, reference.height), "{name}");
            // Image mean per channel: within 4 standard errors (from the pixels' (A − B)/2,
            // plus the reference's share at its 128× higher sample count) and 0.5 %.
            let n = a.pixels.len() as f64;
            for c in 0..3 {
                let m: f64 = a.pixels.iter().zip(&b.pixels).map(|(x, y)| 0.5 * (x[c] + y[c]) as f64).sum::<f64>() / n;
                let r: f64 = reference.pixels.iter().map(|x| x[c] as f64).sum::<f64>() / n;
                let var: f64 =
                    a.pixels.iter().zip(&b.pixels).map(|(x, y)| (0.5 * (x[c] - y[c]) as f64).powi(2)).sum::<f64>() / n;
                let se = (var / n * (1.0 + 1.0 / 64.0)).sqrt();
                assert!(
                    (m - r).abs() < 4.0 * se + 0.005 * r,
                    "{name}/{integrator}: channel {c} mean {m} vs reference {r} (se {se})"
                );
            }
            // No region biased: block z-scores (per-pixel noise) of at most 5 in 99 % of blocks.
            let z = nimbus::metrics::block_z_scores(&a, &b, &reference);
            let outliers = z.iter().filter(|b| b.z.abs() > 5.0).count();
            assert!(
                outliers * 100 <= z.len(),
                "{name}/{integrator}: {outliers} of {} blocks beyond 5σ, worst {:?}",
                z.len(),
                z.first()
            );
            checked += 1;
        }
    }
    assert!(checked >= 7, "checked {checked} scene/integrator pairs");
}
