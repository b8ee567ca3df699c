//! `nimbus compare` and `nimbus diff` from the command line, and the render driver's
//! checkpoints they rest on.

use nimbus::imageio::{Image, read_exr, read_image, write_image};
use nimbus::render::{RenderOptions, render, render_with_passes};
use nimbus::scene::BuildOptions;

use crate::common::{nimbus, scratch_dir};

/// A diffuse sphere under an infinite light, 24×16.
const TINY: &str = r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Sampler "zsobol" "integer pixelsamples" 4
Film "rgb" "integer xresolution" 24 "integer yresolution" 16 "string filename" "tiny.exr"
WorldBegin
LightSource "infinite" "rgb L" [0.5 0.5 0.5]
Material "diffuse" "rgb reflectance" [0.6 0.4 0.3]
Shape "sphere"
"#;

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn compare_writes_every_output_and_reuses_its_cached_reference() {
    let dir = scratch_dir("compare");
    let scene = dir.join("tiny.pbrt");
    std::fs::write(&scene, TINY).unwrap();
    let out_dir = dir.join("out");
    let args = |out: &std::path::Path, time: bool| -> Vec<String> {
        let mut v: Vec<String> =
            ["compare", scene.to_str().unwrap(), "--integrators", "volpath"].into_iter().map(String::from).collect();
        v.extend(
            ["--reference-spp", "16", "--seed", "3", "--spp", "4", "--out", out.to_str().unwrap()].map(String::from),
        );
        if time {
            v.extend(["--time", "1"].map(String::from));
        }
        v
    };
    let run = |a: Vec<String>| nimbus(&a.iter().map(String::as_str).collect::<Vec<_>>());

    let out = run(args(&out_dir, true));
    assert!(out.status.success(), "{}", stderr(&out));
    // The reference is cached next to the scene as two independent halves, at the renders'
    // seed + 1000 and + 1001.
    for seed in ["1003", "1004"] {
        let cached = dir.join(format!("tiny.volpath-8spp-seed{seed}.exr"));
        let reference = read_exr(&cached).unwrap();
        assert_eq!((reference.width, reference.height), (24, 16));
        assert_eq!(reference.metadata.get("nimbus:spp").map(String::as_str), Some("8"));
        assert_eq!(reference.metadata.get("nimbus:seed").map(String::as_str), Some(seed));
    }
    assert!(stderr(&out).contains("reference: rendering volpath at 8 spp"), "{}", stderr(&out));
    for name in [
        "results.csv",
        "results.json",
        "results.md",
        "relmse-vs-time.svg",
        "relmse-vs-time.png",
        "relmse-bars.svg",
        "relmse-bars.png",
        "volpath.exr",
        "volpath-diff.png",
        "volpath-4spp.exr",
        "volpath-4spp-diff.png",
    ] {
        let path = out_dir.join(name);
        assert!(std::fs::metadata(&path).is_ok_and(|m| m.len() > 0), "{} is missing", path.display());
    }
    for chart in ["relmse-vs-time.png", "relmse-bars.png"] {
        let img = read_image(&out_dir.join(chart)).unwrap();
        assert_eq!((img.width, img.height), (800, 500));
    }
    let svg = std::fs::read_to_string(out_dir.join("relmse-vs-time.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("\nvolpath\n</text>"), "{svg}");
    let md = std::fs::read_to_string(out_dir.join("results.md")).unwrap();
    assert!(md.contains("| volpath | equal-time | "), "{md}");
    assert!(md.contains("| volpath | equal-spp | "), "{md}");
    assert_eq!(String::from_utf8_lossy(&out.stdout), md, "stdout is the Markdown table");

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "nimbus-compare/2");
    assert_eq!(json["reference"]["source"], "rendered");
    assert_eq!(json["reference"]["halves"], true);
    assert_eq!(json["reference"]["spp"], 16);
    let noise = json["reference"]["reference_noise"]["relmse"].as_f64().unwrap();
    assert!(noise > 0.0, "two 8-spp halves differ");
    let runs = json["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    let equal_time = &runs[0];
    assert_eq!(equal_time["mode"], "equal-time");
    let checkpoints = equal_time["checkpoints"].as_array().unwrap();
    let spp: Vec<u64> = checkpoints.iter().map(|c| c["spp"].as_u64().unwrap()).collect();
    let seconds: Vec<f64> = checkpoints.iter().map(|c| c["seconds"].as_f64().unwrap()).collect();
    assert!(seconds.windows(2).all(|w| w[0] <= w[1]), "{seconds:?}");
    assert!(spp.windows(2).all(|w| w[0] <= w[1]), "{spp:?}");
    // Checkpoints are at 2^(j/2) spp, rounded, plus the pass where the time ran out.
    let grid = [1, 2, 3, 4, 6, 8, 11, 16, 23, 32];
    let n = (spp.len() - 1).min(grid.len());
    assert_eq!(spp[..n], grid[..n], "{spp:?}");
    assert!(*seconds.last().unwrap() >= 1.0, "{seconds:?}");
    assert_eq!(checkpoints.iter().filter(|c| c["final"] == true).count(), 1);
    let relmse = |c: &serde_json::Value| c["error"]["relmse"].as_f64().unwrap();
    let removed = |c: &serde_json::Value| c["error_noise_removed"]["relmse"].as_f64().unwrap();
    assert!(relmse(checkpoints.last().unwrap()) < relmse(&checkpoints[0]));
    // Without the reference's noise, every error is lower by exactly that noise's relMSE
    // within the noisy weights' effect.
    for c in checkpoints {
        assert!(removed(c) < relmse(c), "{c}");
    }
    let equal_spp = &runs[1];
    assert_eq!(equal_spp["mode"], "equal-spp");
    assert_eq!(equal_spp["final"]["spp"], 4);
    let spp_ladder: Vec<u64> =
        equal_spp["checkpoints"].as_array().unwrap().iter().map(|c| c["spp"].as_u64().unwrap()).collect();
    assert_eq!(spp_ladder, [1, 2, 3, 4]);
    let csv = std::fs::read_to_string(out_dir.join("results.csv")).unwrap();
    assert!(csv.starts_with("integrator,mode,seed,checkpoint,seconds,spp,mse,rmse,relmse,mae,mpe,mne,"));
    assert_eq!(csv.lines().count(), 1 + checkpoints.len() + spp_ladder.len());

    // Same seed again, equal spp only: the cached reference is reused and the image is the same.
    // With --html, the page embeds the reference and the one method (the browser test,
    // tests/browser/report.sh, loads such a page in Chromium).
    let again = dir.join("again");
    let page = again.join("report.html");
    let mut a = args(&again, false);
    a.extend(["--html".to_string(), page.to_str().unwrap().to_string()]);
    let out = run(a);
    assert!(out.status.success(), "{}", stderr(&out));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.contains("<td>volpath</td>"), "{html}");
    assert_eq!(html.matches("\"rgb\":\"").count(), 2, "the reference and one method");
    assert!(stderr(&out).contains("(cached)"), "{}", stderr(&out));
    let a = read_exr(&out_dir.join("volpath-4spp.exr")).unwrap();
    let b = read_exr(&again.join("volpath.exr")).unwrap();
    assert_eq!(a.pixels, b.pixels);
    assert_eq!(b.metadata.get("nimbus:spp").map(String::as_str), Some("4"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(again.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["reference"]["source"], "cached");
    assert_eq!(json["runs"][0]["final"]["error"]["relmse"], equal_spp["final"]["error"]["relmse"]);
}

#[test]
fn compare_over_seeds_reports_standard_errors_bias_and_equal_error_times() {
    let dir = scratch_dir("compare-seeds");
    let scene = dir.join("tiny.pbrt");
    std::fs::write(&scene, TINY).unwrap();
    let s = scene.to_str().unwrap();
    // A reference given as two independent halves.
    let halves = [dir.join("a.exr"), dir.join("b.exr")];
    for (half, seed) in halves.iter().zip(["101", "102"]) {
        let out = nimbus(&["render", s, "--spp", "16", "--seed", seed, "--outfile", half.to_str().unwrap(), "--quiet"]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let reference = format!("{},{}", halves[0].display(), halves[1].display());
    let out_dir = dir.join("out");
    let args = ["compare", s, "--integrators", "volpath,simplevolpath", "--seeds", "3", "--seed", "1", "--spp", "4"];
    let out = nimbus(&[&args[..], &["--reference", &reference, "--out", out_dir.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["seeds"], serde_json::json!([1, 2, 3]));
    assert_eq!(json["reference"]["halves"], true);
    assert_eq!(json["reference"]["spp"], 32);
    assert!(json["reference"]["mean_standard_error"].as_f64().unwrap() > 0.0);
    assert_eq!(json["runs"].as_array().unwrap().len(), 6);
    let summaries = json["summaries"].as_array().unwrap();
    assert_eq!(summaries.len(), 2);
    for sum in summaries {
        for key in ["error", "error_noise_removed"] {
            let relmse = &sum[key]["relmse"];
            assert_eq!(relmse["n"], 3, "{sum}");
            assert!(relmse["standard_error"].as_f64().unwrap() > 0.0, "{sum}");
        }
        assert!(sum["bias"]["bias_z"].as_f64().unwrap().is_finite(), "{sum}");
    }
    let (volpath, simple) = (&summaries[0], &summaries[1]);
    assert_eq!(volpath["integrator"], "volpath");
    assert!(volpath["time_to_equal_error"].is_null(), "the baseline is not measured against itself");
    let equal = &simple["time_to_equal_error"]["relmse"];
    assert_eq!(equal["speedup"]["n"], 3, "{simple}");
    assert!(equal["speedup"]["mean"].as_f64().unwrap() > 0.0, "{simple}");
    assert!(simple["relmse_ratio"]["mean"].as_f64().unwrap() > 0.0, "{simple}");
    // Every seed's image is written, the first seed's under the plain name.
    for name in ["volpath.exr", "volpath-seed2.exr", "simplevolpath-seed3.exr", "simplevolpath-seed3-diff.png"] {
        assert!(out_dir.join(name).exists(), "{name}");
    }
    let md = std::fs::read_to_string(out_dir.join("results.md")).unwrap();
    assert!(md.contains("seeds 1–3 (mean ± standard error)"), "{md}");
    assert!(md.contains("| simplevolpath | equal-spp | 3 |"), "{md}");

    // The same image twice is not two halves; three images are not a reference; a reference
    // seed among the renders' is refused.
    let same = format!("{},{}", halves[0].display(), halves[0].display());
    let out = nimbus(&["compare", s, "--spp", "2", "--reference", &same, "--out", out_dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("are the same image"), "{}", stderr(&out));
    let three = format!("{reference},{}", halves[0].display());
    let out = nimbus(&["compare", s, "--spp", "2", "--reference", &three]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("one image or two independent halves, not 3"), "{}", stderr(&out));
    let out = nimbus(&[
        "compare",
        s,
        "--spp",
        "2",
        "--seeds",
        "4",
        "--seed",
        "1",
        "--reference-spp",
        "8",
        "--reference-seed",
        "3",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("would share seed 3 with the renders"), "{}", stderr(&out));
}

#[test]
fn compare_errors_are_clear() {
    let dir = scratch_dir("compare-errors");
    let scene = dir.join("tiny.pbrt");
    std::fs::write(&scene, TINY).unwrap();
    let small = dir.join("small.exr");
    write_image(&small, &Image::new(8, 8)).unwrap();
    let s = scene.to_str().unwrap();
    let out_dir = dir.join("out");
    let o = out_dir.to_str().unwrap();
    let out = nimbus(&["compare", s, "--reference", small.to_str().unwrap(), "--spp", "2", "--out", o]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("small.exr is 8x8 but the scene's film renders 24x16 pixels"), "{}", stderr(&out));

    let out = nimbus(&["compare", s, "--reference", dir.join("nope.exr").to_str().unwrap(), "--spp", "2"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("reading the reference"), "{}", stderr(&out));

    let out = nimbus(&["compare", s, "--integrators", "volpath,bdpt", "--reference-spp", "4", "--spp", "2"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("unknown integrator \"bdpt\" (nimbus has: volpath"), "{}", stderr(&out));

    // Neither --time nor --spp: a usage error.
    let out = nimbus(&["compare", s, "--reference-spp", "4"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--time"), "{}", stderr(&out));
}

#[test]
fn diff_reports_size_mismatch_and_unreadable_files() {
    let dir = scratch_dir("diff-errors");
    let (a, b, junk) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("junk.exr"));
    write_image(&a, &Image::new(4, 3)).unwrap();
    write_image(&b, &Image::new(3, 4)).unwrap();
    std::fs::write(&junk, "not an image").unwrap();
    let (a, b, junk) = (a.to_str().unwrap(), b.to_str().unwrap(), junk.to_str().unwrap());
    let out = nimbus(&["diff", a, b]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("the images differ in size"), "{}", stderr(&out));
    assert!(stderr(&out).contains("is 4x3, the reference"), "{}", stderr(&out));
    let out = nimbus(&["diff", junk, a]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("cannot read the test image"), "{}", stderr(&out));
    let out = nimbus(&["diff", a, dir.join("missing.exr").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("cannot read the reference"), "{}", stderr(&out));
    let out = nimbus(&["diff", a, a, "--out", dir.join("d.png").to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn difference_image_is_green_where_brighter_and_red_where_darker() {
    let mut test = Image::new(3, 1);
    let mut reference = Image::new(3, 1);
    test.pixels = vec![glam::Vec3::splat(0.75), glam::Vec3::splat(0.25), glam::Vec3::splat(0.5)];
    reference.pixels = vec![glam::Vec3::splat(0.5); 3];
    let d = nimbus::metrics::difference_image(&test, &reference, 0.5);
    assert_eq!(d.pixels, [glam::Vec3::new(0.0, 0.5, 0.0), glam::Vec3::new(0.5, 0.0, 0.0), glam::Vec3::ZERO]);
    let m = nimbus::metrics::error_metrics(&test, &reference).unwrap();
    // Per channel: errors +0.25, −0.25, 0 (the reference is 0.5 everywhere).
    assert!((m.mse - 0.125 / 3.0).abs() < 1e-12);
    assert!((m.rel_mse - 0.0625 * 2.0 / 0.26 / 3.0).abs() < 1e-12);
    assert!((m.mpe - 0.25 / 3.0).abs() < 1e-12 && (m.mne - 0.25 / 3.0).abs() < 1e-12);
}

#[test]
fn pass_checkpoints_cost_no_extra_rendering() {
    let desc = nimbus::parser::load_str(TINY, "tiny.pbrt").unwrap();
    let scene = nimbus::setup::build(&desc, &BuildOptions { spp: Some(8), ..Default::default() }).unwrap();
    let integrator = scene.integrator.create(&scene).unwrap();
    let options = RenderOptions { time_budget: None, quiet: true };
    let plain = render(&scene, integrator.as_ref(), &options);
    let mut passes = Vec::new();
    let mut last_image = None;
    let result = render_with_passes(&scene, integrator.as_ref(), &options, &[1, 2, 3, 4, 6, 8], &mut |p| {
        passes.push((p.spp, p.seconds, p.last));
        if p.last {
            last_image = Some(p.image());
        }
    });
    assert_eq!(passes.iter().map(|p| p.0).collect::<Vec<_>>(), [1, 2, 3, 4, 6, 8]);
    assert!(passes.windows(2).all(|w| w[0].1 <= w[1].1));
    assert_eq!(passes.iter().map(|p| p.2).collect::<Vec<_>>(), [false, false, false, false, false, true]);
    assert_eq!(result.spp, 8);
    assert_eq!(last_image.as_ref(), Some(&result.image));
    // Splitting the passes only regroups floating-point sums.
    for (a, b) in plain.image.pixels.iter().zip(&result.image.pixels) {
        assert!((*a - *b).abs().max_element() <= 1e-6 * a.max_element().max(1.0), "{a} vs {b}");
    }
}
