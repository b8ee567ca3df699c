//! `nimbus cluster` and `nimbus merge` without a scheduler: the tasks of tasks.txt are run as
//! Slurm would run them (each line by bash), then merged. Tiles merge bit for bit into the
//! single-machine image; seed batches match one render of all their samples within noise;
//! missing, foreign, overlapping and repeated parts are refused by name; `--resume` asks for
//! exactly the missing tasks. (`tests/slurm/run.sh` does the same through a real Slurm.)

use std::path::Path;

use crate::common::{nimbus, scratch_dir};

/// A small noisy scene: a medium sphere over a floor under a sun and a sky, 20×12 pixels.
fn scene(spp: u32) -> String {
    format!(
        "LookAt 0 1 4  0 0.3 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
         Sampler \"zsobol\" \"integer pixelsamples\" {spp}\n\
         Film \"rgb\" \"integer xresolution\" 20 \"integer yresolution\" 12\n\
         MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.1 0.1] \"rgb sigma_s\" [2 2 2]\n\
         WorldBegin\nLightSource \"distant\" \"point3 from\" [1 3 2] \"rgb L\" [3 3 3]\n\
         LightSource \"infinite\" \"rgb L\" [0.2 0.3 0.5]\n\
         AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 0.8\nAttributeEnd\n"
    )
}

fn ok(args: &[&str]) -> String {
    let out = nimbus(args);
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "nimbus {args:?}: {text}");
    text
}

fn fails(args: &[&str]) -> String {
    let out = nimbus(args);
    assert!(!out.status.success(), "nimbus {args:?} should fail");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs task lines of `dir/tasks.txt` (all, or those `keep` accepts) with bash.
fn run_tasks(dir: &Path, keep: impl Fn(usize) -> bool) {
    let tasks = std::fs::read_to_string(dir.join("tasks.txt")).unwrap();
    for (i, line) in tasks.lines().enumerate().filter(|(i, _)| keep(*i)) {
        let st = std::process::Command::new("bash").args(["-c", line]).status().unwrap();
        assert!(st.success(), "task {i}: {line}");
    }
}

fn read(path: &Path) -> nimbus::imageio::Image {
    nimbus::imageio::read_exr(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn tiles_merge_bit_for_bit_and_missing_parts_are_named() {
    let dir = scratch_dir("cluster-tiles");
    let s = dir.join("s.pbrt");
    std::fs::write(&s, scene(4)).unwrap();
    let out = dir.join("split");
    ok(&["cluster", s.to_str().unwrap(), "--tiles", "3", "--seed", "7", "--out", out.to_str().unwrap()]);
    let sbatch = std::fs::read_to_string(out.join("render.sbatch")).unwrap();
    assert!(sbatch.contains("#SBATCH --array=0-2"), "{sbatch}");
    assert!(!out.join("precompute.sbatch").exists(), "volpath precomputes nothing");
    assert_eq!(std::fs::read_to_string(out.join("tasks.txt")).unwrap().lines().count(), 3);
    // A task that never ran: merge names it, --resume asks for it alone.
    run_tasks(&out, |i| i != 1);
    let err = fails(&["merge", out.to_str().unwrap(), "-o", dir.join("m.exr").to_str().unwrap()]);
    assert!(err.contains("1 of 3 parts are missing") && err.contains("tile-001.exr"), "{err}");
    let said = ok(&["cluster", "--resume", out.to_str().unwrap()]);
    assert!(said.contains("1 of 3 parts missing: tile-001.exr"), "{said}");
    let resume = std::fs::read_to_string(out.join("resume.sbatch")).unwrap();
    assert!(resume.contains("#SBATCH --array=1\n"), "{resume}");
    run_tasks(&out, |i| i == 1);
    assert!(ok(&["cluster", "--resume", out.to_str().unwrap()]).contains("nothing to resubmit"));

    let merged = dir.join("merged.exr");
    ok(&["merge", out.to_str().unwrap(), "-o", merged.to_str().unwrap()]);
    let single = dir.join("single.exr");
    ok(&["render", s.to_str().unwrap(), "--seed", "7", "--quiet", "--outfile", single.to_str().unwrap()]);
    let (m, r) = (read(&merged), read(&single));
    assert_eq!((m.width, m.height), (20, 12));
    assert!(m.pixels == r.pixels, "tiles of one seed merge bit for bit into the single render");

    // Parts that do not belong together are refused by name.
    let loose = dir.join("loose");
    std::fs::create_dir_all(&loose).unwrap();
    let part = |name: &str, scene: &Path, extra: &[&str]| {
        let o = loose.join(name);
        let mut a = vec!["render", scene.to_str().unwrap(), "--quiet", "--outfile", o.to_str().unwrap()];
        a.extend_from_slice(extra);
        ok(&a);
    };
    part("a.exr", &s, &["--pixelbounds", "0", "20", "0", "7", "--seed", "1"]);
    part("b.exr", &s, &["--pixelbounds", "0", "20", "5", "12", "--seed", "1"]);
    let merge_loose = || fails(&["merge", loose.to_str().unwrap(), "-o", dir.join("x.exr").to_str().unwrap()]);
    assert!(merge_loose().contains("a.exr (pixels 0 20 0 7) and b.exr (pixels 0 20 5 12) overlap"));
    std::fs::remove_file(loose.join("b.exr")).unwrap();
    assert!(merge_loose().contains("leave 100 pixels of the film uncovered, the first at (0, 7)"));
    part("b.exr", &s, &["--pixelbounds", "0", "20", "0", "7", "--seed", "1"]);
    assert!(merge_loose().contains("a.exr and b.exr are the same pixels with the same seed (1)"));
    let other = dir.join("other.pbrt");
    std::fs::write(&other, scene(4).replace("[3 3 3]", "[2 2 2]")).unwrap();
    part("b.exr", &other, &["--pixelbounds", "0", "20", "7", "12"]);
    assert!(merge_loose().contains("b.exr is from another scene"));
}

#[test]
fn seed_batches_average_to_one_longer_render() {
    let dir = scratch_dir("cluster-seeds");
    let s = dir.join("s.pbrt");
    std::fs::write(&s, scene(8)).unwrap();
    let out = dir.join("split");
    ok(&["cluster", s.to_str().unwrap(), "--seeds", "4", "--seed", "10", "--out", out.to_str().unwrap()]);
    run_tasks(&out, |_| true);
    let merged = dir.join("merged.exr");
    ok(&["merge", out.to_str().unwrap(), "-o", merged.to_str().unwrap()]);
    let single = dir.join("single.exr");
    ok(&[
        "render",
        s.to_str().unwrap(),
        "--spp",
        "32",
        "--seed",
        "99",
        "--quiet",
        "--outfile",
        single.to_str().unwrap(),
    ]);
    let (m, r) = (read(&merged), read(&single));
    assert_eq!(m.metadata["nimbus:spp"], "32");
    assert_eq!(m.metadata["nimbus:seeds"], "10 11 12 13");
    // Two independent 32-spp estimates: their per-pixel differences have mean zero.
    let d: Vec<f64> = m.pixels.iter().zip(&r.pixels).map(|(a, b)| ((*a - *b).element_sum() / 3.0) as f64).collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let se = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    assert!(mean.abs() < 4.0 * se, "mean difference {mean} against a standard error {se}");
    assert!(se > 0.0 && se < 0.05, "{se}");
}

#[test]
fn a_graph_orbit_precomputes_once_and_renders_each_frame() {
    let dir = scratch_dir("cluster-orbit");
    let s = dir.join("s.pbrt");
    std::fs::write(&s, scene(2).replace("LightSource \"infinite\" \"rgb L\" [0.2 0.3 0.5]\n", "")).unwrap();
    std::fs::write(
        dir.join("s.json"),
        r#"{"graphBuilder": {"radiusModifier": 60, "dimensionSteps": 40, "iterationsPerStep": 4}, "lightingCalculator": {"bounces": [5]}}"#,
    )
    .unwrap();
    let cams = dir.join("orbit.txt");
    std::fs::write(&cams, "# two frames\nLookAt 0 1 4  0 0.3 0  0 1 0\n4 1 0  0 0.3 0  0 1 0\n").unwrap();
    let out = dir.join("orbit");
    let (s_str, out_str) = (s.to_str().unwrap(), out.to_str().unwrap());
    ok(&["cluster", s_str, "--cameras", cams.to_str().unwrap(), "--integrator", "graph", "--out", out_str]);
    let pre = std::fs::read_to_string(out.join("precompute.sbatch")).unwrap();
    assert!(pre.contains(" graph build ") && pre.contains("--out"), "{pre}");
    let submit = std::fs::read_to_string(out.join("submit.sh")).unwrap();
    assert!(submit.contains("--dependency=afterok:"), "{submit}");
    let tasks = std::fs::read_to_string(out.join("tasks.txt")).unwrap();
    assert!(tasks.lines().all(|l| l.contains("--precomputed") && l.contains("--lookat")), "{tasks}");
    // The precomputation, as its job would run it, then the frames.
    let line = pre.lines().last().unwrap();
    assert!(std::process::Command::new("bash").args(["-c", line]).status().unwrap().success());
    run_tasks(&out, |_| true);
    let graph = out.join("graph/s_d6.txt");
    let local = dir.join("local.exr");
    ok(&[
        "render",
        s_str,
        "--integrator",
        "graph",
        "--graph-data",
        graph.to_str().unwrap(),
        "--quiet",
        "--outfile",
        local.to_str().unwrap(),
        "--lookat",
        "4",
        "1",
        "0",
        "0",
        "0.3",
        "0",
        "0",
        "1",
        "0",
    ]);
    let (frame, local) = (read(&out.join("frame-001.exr")), read(&local));
    assert!(frame.pixels == local.pixels, "a frame is the local render of its camera");
    assert!(read(&out.join("frame-000.exr")).pixels != frame.pixels, "the frames see different views");
    let err = fails(&["merge", out_str, "-o", dir.join("m.exr").to_str().unwrap()]);
    assert!(err.contains("camera frames") && err.contains("all 2 are there"), "{err}");
    // Bad camera lines are reported with their line.
    std::fs::write(&cams, "LookAt 0 1 4  0 0.3 0\n").unwrap();
    let err =
        fails(&["cluster", s_str, "--cameras", cams.to_str().unwrap(), "--out", dir.join("o2").to_str().unwrap()]);
    assert!(err.contains("orbit.txt:1: 6 numbers"), "{err}");
}

#[test]
fn guided_tasks_load_the_trees_their_precompute_job_trained() {
    let dir = scratch_dir("cluster-guided");
    let s = dir.join("s.pbrt");
    std::fs::write(&s, scene(2)).unwrap();
    let out = dir.join("split");
    ok(&[
        "cluster",
        s.to_str().unwrap(),
        "--seeds",
        "2",
        "--integrator",
        "guided",
        "--spp",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let pre = std::fs::read_to_string(out.join("precompute.sbatch")).unwrap();
    let line = pre.lines().last().unwrap();
    assert!(line.contains("--precomputed") && line.matches("--spp").count() == 1, "{line}");
    assert!(std::process::Command::new("bash").args(["-c", line]).status().unwrap().success());
    let cache = out.join("guide.cache");
    let trained = std::fs::metadata(&cache).expect("the precompute job saved the trees").modified().unwrap();
    run_tasks(&out, |_| true);
    assert_eq!(std::fs::metadata(&cache).unwrap().modified().unwrap(), trained, "the tasks loaded, not retrained");
    let merged = dir.join("m.exr");
    ok(&["merge", out.to_str().unwrap(), "-o", merged.to_str().unwrap()]);
    assert_eq!(read(&merged).metadata["nimbus:spp"], "4");
}

#[test]
fn extra_film_channels_merge_with_their_tiles() {
    let dir = scratch_dir("cluster-channels");
    // A G-buffer film: its 22 channels are placed tile by tile, bit for bit.
    let s = dir.join("g.pbrt");
    let floor = "Material \"diffuse\"\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
                 \"point3 P\" [-5 -0.8 -5 5 -0.8 -5 5 -0.8 5 -5 -0.8 5]\n";
    let text = scene(2).replace("Film \"rgb\"", "Film \"gbuffer\"") + floor;
    std::fs::write(&s, &text).unwrap();
    let out = dir.join("tiles");
    ok(&["cluster", s.to_str().unwrap(), "--tiles", "2", "--seed", "3", "--out", out.to_str().unwrap()]);
    run_tasks(&out, |_| true);
    let merged = dir.join("merged.exr");
    ok(&["merge", out.to_str().unwrap(), "-o", merged.to_str().unwrap()]);
    let single = dir.join("single.exr");
    ok(&["render", s.to_str().unwrap(), "--seed", "3", "--quiet", "--outfile", single.to_str().unwrap()]);
    let channels = |p: &Path| nimbus::imageio::read_exr_channels(p).unwrap();
    let (m, r) = (channels(&merged), channels(&single));
    assert!(
        m.len() >= 20 && m.iter().any(|(n, _)| n == "Variance.R"),
        "{:?}",
        m.iter().map(|c| &c.0).collect::<Vec<_>>()
    );
    assert!(m == r, "every channel of the tiles is the single render's");
    // Its variance channels cannot be averaged over seed batches: refused, not guessed.
    let seeds = dir.join("seeds");
    ok(&["cluster", s.to_str().unwrap(), "--seeds", "2", "--out", seeds.to_str().unwrap()]);
    run_tasks(&seeds, |_| true);
    let err = fails(&["merge", seeds.to_str().unwrap(), "-o", dir.join("x.exr").to_str().unwrap()]);
    assert!(err.contains("Variance.") && err.contains("--tiles"), "{err}");
    // A spectral film's bands average over seed batches like its RGB.
    let sp = dir.join("s.pbrt");
    std::fs::write(&sp, scene(4).replace("Film \"rgb\"", "Film \"spectral\" \"integer nbuckets\" 4")).unwrap();
    let batches = dir.join("bands");
    ok(&["cluster", sp.to_str().unwrap(), "--seeds", "2", "--out", batches.to_str().unwrap()]);
    run_tasks(&batches, |_| true);
    ok(&["merge", batches.to_str().unwrap(), "-o", merged.to_str().unwrap()]);
    let parts = [batches.join("seed-000.exr"), batches.join("seed-001.exr")].map(|p| channels(&p));
    let m = channels(&merged);
    assert_eq!(m.len(), 4);
    for (c, (name, values)) in m.iter().enumerate() {
        assert!(name.starts_with("S0."), "{name}");
        for (i, v) in values.iter().enumerate() {
            let mean = 0.5 * (parts[0][c].1[i] + parts[1][c].1[i]);
            assert!((v - mean).abs() <= 1e-6 * mean.abs().max(1.0), "{name}[{i}]: {v} vs {mean}");
        }
    }
    assert_eq!(read(&merged).metadata.get("spectralLayoutVersion").map(String::as_str), Some("1.0"));
}
