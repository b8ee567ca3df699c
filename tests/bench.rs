//! `nimbus bench`: figures from speed.json, equal-error arithmetic, bad input.

use crate::common::{nimbus, scratch_dir};

/// A tiny scene at `dir`/scenes/tiny.pbrt with its own 64-spp render as the reference,
/// `dir`/images/tiny.exr (as a speed.json folder lays them out).
fn tiny_scene(dir: &std::path::Path) -> std::path::PathBuf {
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::create_dir_all(dir.join("images")).unwrap();
    let scene = dir.join("scenes/tiny.pbrt");
    std::fs::write(
        &scene,
        "LookAt 0 0 4  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"diffuse\" \"rgb reflectance\" [0.7 0.2 0.1]\nShape \"sphere\"\n",
    )
    .unwrap();
    let reference = dir.join("images/tiny.exr");
    let out = nimbus(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        "64",
        "--quiet",
        "--outfile",
        reference.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    scene
}

/// A one-pixel-per-sample scene bench can time in a moment, against its own image as
/// reference: the JSON's equal-error ratio must be (t_pbrt·mse_pbrt)/(t·mse) of its own
/// columns, and a malformed speed.json an error naming the file.
#[test]
fn bench_reports_equal_spp_and_equal_error_ratios() {
    let dir = scratch_dir("bench");
    let scene = tiny_scene(&dir);
    std::fs::write(dir.join("speed.json"), r#"{"spp": 4, "scenes": {"tiny": {"seconds": 2.0, "mse": 0.001}}}"#)
        .unwrap();
    let json = dir.join("out.json");
    let out = nimbus(&[
        "bench",
        "--references",
        dir.to_str().unwrap(),
        "--spp",
        "4",
        "--repeat",
        "2",
        "--nthreads",
        "1",
        "--json",
        json.to_str().unwrap(),
        scene.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("| tiny | 4 | rgb (off) |") && stdout.contains("| tiny | 4 | spectral (on) |"), "{stdout}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        let (t, mse) = (r["seconds"].as_f64().unwrap(), r["mse"].as_f64().unwrap());
        assert!(t > 0.0 && mse > 0.0, "{r}");
        let want = 2.0 * 0.001 / (t * mse);
        assert!((r["speedup_equal_error"].as_f64().unwrap() / want - 1.0).abs() < 1e-9, "{r}");
        assert!((r["speedup_equal_spp"].as_f64().unwrap() - 2.0 / t).abs() < 1e-9, "{r}");
    }
    std::fs::write(dir.join("speed.json"), r#"{"spp": 4, "scenes": {"tiny": {"seconds": "fast"}}}"#).unwrap();
    let out = nimbus(&["bench", "--references", dir.to_str().unwrap(), "--spp", "4", scene.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("speed.json") && stderr.contains("scenes.tiny.seconds"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scene that fails makes the bench fail (after the others ran) and is listed in the JSON;
/// a scene without a reference image says why it has no MSE.
#[test]
fn bench_failures_and_missing_references_are_reported() {
    let dir = scratch_dir("bench-failures");
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    let good = dir.join("scenes/noref.pbrt");
    std::fs::write(
        &good,
        "Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\nLightSource \"infinite\"\nShape \"sphere\"\n",
    )
    .unwrap();
    let bad = dir.join("scenes/bad.pbrt");
    std::fs::write(&bad, "WorldBegin\nShape \"plymesh\" \"string filename\" \"missing.ply\"\n").unwrap();
    std::fs::write(dir.join("speed.json"), r#"{"spp": 1, "threads": 1, "scenes": {}}"#).unwrap();
    let json = dir.join("out.json");
    let args = ["bench", "--references", dir.to_str().unwrap(), "--spp", "1", "--nthreads", "1", "--spectral", "off"];
    let mut args: Vec<&str> = args.to_vec();
    args.extend(["--json", json.to_str().unwrap(), good.to_str().unwrap(), bad.to_str().unwrap()]);
    let out = nimbus(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("noref: no MSE") && stderr.contains("noref.exr"), "{stderr}");
    assert!(stderr.contains("1 scene/transport run(s) failed"), "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["rows"].as_array().unwrap().len(), 1);
    let failures = v["failures"].as_array().unwrap();
    assert_eq!(failures.len(), 1);
    assert_eq!(failures[0]["scene"], "bad");
    assert!(failures[0]["error"].as_str().unwrap().contains("missing.ply"), "{failures:?}");
}

/// A speed.json may name its scene and two independent reference halves: the MSE is then
/// against their mean with its own noise, E[(h1 − h2)²]/4, removed — for an image equal to one
/// half, MSE(h1, mean) − MSE(h1, h2)/4 = 0 — and the default spp is the file's.
#[test]
fn bench_removes_the_noise_of_reference_halves() {
    let dir = scratch_dir("bench-halves");
    std::fs::create_dir_all(dir.join("refs")).unwrap();
    let scene = dir.join("tiny.pbrt");
    std::fs::write(
        &scene,
        "LookAt 0 0 4  0 0 0  0 1 0\nCamera \"perspective\"\nSampler \"zsobol\" \"integer seed\" 1\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"diffuse\" \"rgb reflectance\" [0.7 0.2 0.1]\nShape \"sphere\"\n",
    )
    .unwrap();
    // The halves: nimbus's own renders at bench's seeds 1 and 2 and its spp, so each run's
    // image is one of them.
    for seed in ["1", "2"] {
        let half = dir.join(format!("refs/h{seed}.exr"));
        let args = ["render", scene.to_str().unwrap(), "--spp", "3", "--seed", seed, "--spectral", "off", "--quiet"];
        let mut args = args.to_vec();
        args.extend(["--nthreads", "1", "--outfile", half.to_str().unwrap()]);
        let out = nimbus(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    std::fs::write(
        dir.join("speed.json"),
        r#"{"spp": 3, "scenes": {"tiny": {"seconds": 2.0, "mse": 0.001, "scene": "tiny.pbrt",
            "reference": ["refs/h1.exr", "refs/h2.exr"]}}}"#,
    )
    .unwrap();
    let json = dir.join("out.json");
    let args = ["bench", "--references", dir.to_str().unwrap(), "--nthreads", "1", "--spectral", "off"];
    let mut args: Vec<&str> = args.to_vec();
    args.extend(["--json", json.to_str().unwrap(), scene.to_str().unwrap()]);
    let out = nimbus(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    let tiny = rows.iter().find(|r| r["scene"] == "tiny").expect("the file's scene");
    assert_eq!(tiny["spp"], 3);
    let mse = tiny["mse"].as_f64().unwrap();
    // Each half against the mean: MSE(h1, h2)/4 each, minus the same noise.
    assert!(mse.abs() < 1e-9, "{tiny}");
    // A reference list of three paths is an error naming the file and key.
    std::fs::write(
        dir.join("speed.json"),
        r#"{"spp": 3, "scenes": {"tiny": {"seconds": 2.0, "mse": 0.001, "reference": ["a", "b", "c"]}}}"#,
    )
    .unwrap();
    let out = nimbus(&["bench", "--references", dir.to_str().unwrap(), scene.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("speed.json") && stderr.contains("scenes.tiny.reference"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--pbrt PATH` times that executable in the same run, on bench's seeds, spp and threads,
/// and takes its figures from it: here a stand-in that renders with nimbus itself in RGB, so
/// its MSE must equal nimbus's RGB row's (the same seeds give the same images) and the ratios
/// follow from the measured columns. A stand-in that fails makes the scene's row a failure
/// with its message.
#[cfg(unix)]
#[test]
fn bench_times_pbrt_in_the_same_run() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch_dir("bench-pbrt");
    let scene = tiny_scene(&dir);
    std::fs::write(dir.join("speed.json"), r#"{"spp": 4, "scenes": {"tiny": {"seconds": 1000.0, "mse": 1.0}}}"#)
        .unwrap();
    let script = |name: &str, body: String| {
        let p = dir.join(name);
        std::fs::write(&p, body).unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
        p
    };
    let stand_in =
        script("pbrt", format!("#!/bin/sh\nexec '{}' render --spectral off \"$@\"\n", env!("CARGO_BIN_EXE_nimbus")));
    let json = dir.join("out.json");
    let args = ["bench", "--references", dir.to_str().unwrap(), "--nthreads", "1", "--json", json.to_str().unwrap()];
    let mut args: Vec<&str> = args.to_vec();
    args.extend(["--pbrt", stand_in.to_str().unwrap(), scene.to_str().unwrap()]);
    let out = nimbus(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    let rgb = rows.iter().find(|r| r["mode"] == "off").expect("an RGB row");
    let (t, mse) = (rgb["seconds"].as_f64().unwrap(), rgb["mse"].as_f64().unwrap());
    let (tp, msep) = (rgb["pbrt_seconds"].as_f64().unwrap(), rgb["pbrt_mse"].as_f64().unwrap());
    assert!(tp > 0.0 && tp < 1000.0, "pbrt-v4's time is measured, not speed.json's: {rgb}");
    assert!((msep / mse - 1.0).abs() < 1e-9, "the stand-in's MSE is nimbus's RGB MSE: {rgb}");
    assert!((rgb["speedup_equal_error"].as_f64().unwrap() / (tp * msep / (t * mse)) - 1.0).abs() < 1e-9, "{rgb}");

    let failing = script("pbrt-fails", "#!/bin/sh\necho 'Error: cannot open scene' >&2\nexit 3\n".into());
    let out = nimbus(&[
        "bench",
        "--references",
        dir.to_str().unwrap(),
        "--pbrt",
        failing.to_str().unwrap(),
        scene.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("| tiny | 4 | pbrt-v4 | failed:") && stdout.contains("cannot open scene"), "{stdout}");
}
