//! `nimbus render` from the command line: outputs, metadata, flags and errors.

use crate::common::{nimbus, scratch_dir};

const SMALL: &str = r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Sampler "independent" "integer pixelsamples" 2
Film "rgb" "integer xresolution" 24 "integer yresolution" 16 "string filename" "small.exr"
WorldBegin
LightSource "infinite" "rgb L" [0.3 0.3 0.3]
Material "diffuse"
Shape "sphere"
"#;

#[test]
fn renders_exr_with_metadata_and_png() {
    let dir = scratch_dir("render-cli");
    let scene = dir.join("s.pbrt");
    std::fs::write(&scene, SMALL).unwrap();
    let exr = dir.join("out.exr");
    let out = nimbus(&[
        "render",
        scene.to_str().unwrap(),
        "--quiet",
        "--spp",
        "3",
        "--seed",
        "7",
        "--outfile",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let img = nimbus::imageio::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (24, 16));
    assert_eq!(img.metadata.get("nimbus:spp").map(String::as_str), Some("3"));
    assert_eq!(img.metadata.get("nimbus:seed").map(String::as_str), Some("7"));
    assert_eq!(img.metadata.get("nimbus:integrator").map(String::as_str), Some("volpath"));
    assert!(img.metadata.contains_key("nimbus:time"));
    let png = dir.join("out.png");
    let out = nimbus(&[
        "render",
        scene.to_str().unwrap(),
        "--quiet",
        "--outfile",
        png.to_str().unwrap(),
        "--pixelbounds",
        "0",
        "8",
        "0",
        "4",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let img = nimbus::imageio::read_image(&png).unwrap();
    assert_eq!((img.width, img.height), (8, 4));
    // pbrt-v4 writes the four numbers with commas; both forms select the same pixels.
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let bounds = |out: &std::path::Path, b: &[&str]| {
        let mut args =
            vec!["render", scene.to_str().unwrap(), "--quiet", "--seed", "2", "--outfile", out.to_str().unwrap()];
        args.extend_from_slice(b);
        nimbus(&args)
    };
    assert!(bounds(&a, &["--pixelbounds", "2,10,1,5"]).status.success());
    assert!(bounds(&b, &["--pixelbounds", "2", "10", "1", "5"]).status.success());
    let (a, b) = (nimbus::imageio::read_exr(&a).unwrap(), nimbus::imageio::read_exr(&b).unwrap());
    assert_eq!((a.width, a.height), (8, 4));
    assert_eq!(a.pixels, b.pixels);
    assert!(bounds(&dir.join("c.exr"), &["--cropwindow", "0,0.5,0,0.5"]).status.success());
    let three = bounds(&dir.join("d.exr"), &["--pixelbounds", "2,10,1"]);
    assert!(!three.status.success() && String::from_utf8_lossy(&three.stderr).contains("takes four numbers"));
}

#[test]
fn time_budget_renders_progressively() {
    let dir = scratch_dir("render-time");
    let scene = dir.join("s.pbrt");
    std::fs::write(&scene, SMALL).unwrap();
    let exr = dir.join("t.exr");
    let out =
        nimbus(&["render", scene.to_str().unwrap(), "--quiet", "--time", "0.5", "--outfile", exr.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let img = nimbus::imageio::read_exr(&exr).unwrap();
    let spp: u32 = img.metadata["nimbus:spp"].parse().unwrap();
    assert!(spp >= 1);
}

/// pmj02bn draws from sequences of 65,536 points: a time budget stops there, and an `--spp`
/// beyond it is refused at the sampler directive, as pbrt-v4 refuses it.
#[test]
fn pmj02bn_sample_counts_stay_within_its_sequences() {
    let dir = scratch_dir("render-pmj02bn");
    let scene = dir.join("s.pbrt");
    std::fs::write(&scene, SMALL.replace(r#"Sampler "independent""#, r#"Sampler "pmj02bn""#)).unwrap();
    let exr = dir.join("t.exr");
    let out =
        nimbus(&["render", scene.to_str().unwrap(), "--quiet", "--time", "0.3", "--outfile", exr.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let img = nimbus::imageio::read_exr(&exr).unwrap();
    let spp: u32 = img.metadata["nimbus:spp"].parse().unwrap();
    assert!((1..=65536).contains(&spp), "{spp}");
    assert!(img.pixels.iter().all(|p| p.is_finite()));
    let out = nimbus(&["render", scene.to_str().unwrap(), "--quiet", "--spp", "65537"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("s.pbrt:3:1: error: pmj02bn takes at most 65536 samples per pixel"), "{stderr}");
}

#[test]
fn unknown_integrator_lists_the_available_ones() {
    let dir = scratch_dir("render-integrator");
    let scene = dir.join("s.pbrt");
    let exr = dir.join("x.exr");
    let render = |integrator: &str, extra: &[&str]| {
        std::fs::write(&scene, SMALL.replace("WorldBegin", &format!("Integrator \"{integrator}\"\nWorldBegin")))
            .unwrap();
        let mut args = vec!["render", scene.to_str().unwrap(), "--quiet", "--outfile", exr.to_str().unwrap()];
        args.extend_from_slice(extra);
        nimbus(&args)
    };
    let out = render("nosuchmethod", &[]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("s.pbrt:5:1: error: integrator \"nosuchmethod\" is not available in nimbus (it has: volpath"),
        "{stderr}"
    );
    // pbrt-v4's integrators nimbus lacks are refused with the one that computes their image...
    let out = render("bdpt", &[]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("s.pbrt:5:1: error: integrator \"bdpt\"") && stderr.contains("\"volpath\""), "{stderr}");
    // ...unless --integrator chooses another, which is no complaint.
    let out = render("bdpt", &["--integrator", "volpath"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("bdpt"));
    // pbrt-v4's surface path tracer runs as volpath, with a note.
    let out = render("path", &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("integrator \"path\"") && stderr.contains("runs as \"volpath\""), "{stderr}");
    let out = nimbus(&["render", dir.join("nope.pbrt").to_str().unwrap(), "--quiet"]);
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn output_format_errors_are_clear() {
    let dir = scratch_dir("render-format");
    let scene = dir.join("s.pbrt");
    std::fs::write(&scene, SMALL).unwrap();
    let out =
        nimbus(&["render", scene.to_str().unwrap(), "--quiet", "--outfile", dir.join("x.tiff").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unsupported output format"));
}

/// `--maxdepth` (the radiance-graph thesis's pbrt-v4 flag for its VolPath references)
/// overrides the scene's `maxdepth`: the image equals the one rendered with that depth in the
/// file, not the one with the file's own depth; the radiance graph, which has no such
/// parameter, refuses it naming the integrator directive.
#[test]
fn maxdepth_flag_overrides_the_scene() {
    let dir = scratch_dir("render-maxdepth");
    let scene = |depth: u32, integrator: &str| {
        let path = dir.join(format!("{integrator}-{depth}.pbrt"));
        let text = SMALL
            .replace("WorldBegin", &format!("Integrator \"{integrator}\" \"integer maxdepth\" {depth}\nWorldBegin"));
        std::fs::write(&path, text).unwrap();
        path
    };
    let render = |scene: &std::path::Path, extra: &[&str], out: &str| {
        let exr = dir.join(out);
        let mut args = vec!["render", scene.to_str().unwrap(), "--quiet", "--seed", "3", "--outfile"];
        args.push(exr.to_str().unwrap());
        args.extend_from_slice(extra);
        let out = nimbus(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        nimbus::imageio::read_exr(&exr).unwrap().pixels
    };
    // Depth 0 sees only the sky (the sphere is black); depth 5 lights the sphere.
    let flagged = render(&scene(5, "volpathcustom"), &["--maxdepth", "0"], "flag.exr");
    let written = render(&scene(0, "volpath"), &[], "file.exr");
    let own = render(&scene(5, "volpath"), &[], "own.exr");
    assert!(flagged == written, "--maxdepth 0 differs from maxdepth 0 in the file");
    assert!(flagged != own, "--maxdepth 0 rendered the file's maxdepth 5");
    let graph = scene(5, "graph");
    let out = nimbus(&["render", graph.to_str().unwrap(), "--quiet", "--maxdepth", "10"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("graph-5.pbrt:5:1") && stderr.contains("radiancegraph has no maxdepth"), "{stderr}");
}
