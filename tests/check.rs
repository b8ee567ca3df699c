//! `nimbus check`: summaries of good scenes, located errors for bad ones.

use crate::common::{nimbus, reference_scenes, scratch_dir};

#[test]
fn every_parity_scene_checks_clean() {
    let scenes = reference_scenes();
    assert!(scenes.len() >= 9, "expected the parity scenes, found {scenes:?}");
    for scene in scenes {
        let out = nimbus(&["check", "--strict", scene.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{}: {stderr}", scene.display());
        assert!(stderr.is_empty(), "{}: unexpected warnings: {stderr}", scene.display());
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("film        128x128"), "{stdout}");
    }
}

#[test]
fn summary_counts_shapes_triangles_lights_and_media() {
    let dir = scratch_dir("summary");
    let scene = dir.join("s.pbrt");
    std::fs::write(
        &scene,
        r#"Film "rgb" "integer xresolution" 64 "integer yresolution" 32
Integrator "volpath" "float rrthreshold" 0 "integer maxdepth" 7
WorldBegin
LightSource "distant" "rgb L" [1 1 1]
MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_s" [1 1 1]
AttributeBegin
  MediumInterface "fog" ""
  Material "interface"
  Shape "sphere"
AttributeEnd
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [0 0 0 1 0 0 1 1 0 0 1 0]
"#,
    )
    .unwrap();
    let out = nimbus(&["check", scene.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("film        64x32"), "{stdout}");
    // A parameter the method does not read is warned about, not listed as a setting
    // (transparent-machines gives volpath pbrt-v3's "rrthreshold").
    assert!(stdout.contains("integrator  volpath maxdepth 7\n"), "{stdout}");
    assert!(!stdout.contains("rrthreshold"), "{stdout}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("\"float rrthreshold\": unused parameter"));
    assert!(stdout.contains("shapes      2 (sphere 1, trianglemesh 1), 2 triangles"), "{stdout}");
    assert!(stdout.contains("lights      1 (distant 1)"), "{stdout}");
    assert!(stdout.contains("media       1 (homogeneous 1)"), "{stdout}");
}

/// Each malformed scene must fail with exit code 1 and this exact first line on stderr.
#[test]
fn malformed_scenes_fail_with_their_location() {
    let dir = scratch_dir("malformed");
    let cases: &[(&str, &str)] = &[
        ("WorldBegin\nShpe \"sphere\"\n", "bad.pbrt:2:1: error: unknown directive \"Shpe\""),
        (
            "WorldBegin\nCamera \"perspective\"\n",
            "bad.pbrt:2:1: error: Camera is not allowed after WorldBegin (options block only)",
        ),
        ("Shape \"sphere\"\n", "bad.pbrt:1:1: error: Shape is not allowed before WorldBegin (world block only)"),
        (
            "WorldBegin\nShape \"sphere\" \"integer radius\" 2\n",
            "bad.pbrt:2:16: error: parameter \"radius\" has type \"integer\" but must be \"float\"",
        ),
        (
            "WorldBegin\nShape \"sphere\" \"float radius\" [1 2]\n",
            "bad.pbrt:2:16: error: more than one value provided for parameter \"radius\" (expected one float)",
        ),
        (
            "WorldBegin\nNamedMaterial \"gold\"\nShape \"sphere\"\n",
            "bad.pbrt:2:1: error: named material \"gold\" is not defined",
        ),
        (
            "WorldBegin\nMediumInterface \"smoke\" \"\"\nShape \"sphere\"\n",
            "bad.pbrt:2:1: error: medium \"smoke\" is not defined",
        ),
        (
            "WorldBegin\nMaterial \"diffuse\" \"texture reflectance\" \"wood\"\nShape \"sphere\"\n",
            "bad.pbrt:2:20: error: texture \"wood\" is not defined",
        ),
        (
            "WorldBegin\nShape \"sphere\" \"string name\" \"abc\n",
            "bad.pbrt:2:30: error: unterminated string: newline before the closing '\"'",
        ),
        ("WorldBegin\nTranslate 1 2\n", "bad.pbrt:3:1: error: premature end of file: expected a number for Translate"),
        (
            "WorldBegin\nShape \"hyperboloid\"\n",
            "bad.pbrt:2:1: error: shape \"hyperboloid\" is not supported by nimbus (it has sphere, disk, cylinder, trianglemesh, bilinearmesh, loopsubdiv, curve, plymesh, and the extensions objmesh and gltfmesh)",
        ),
        (
            "WorldBegin\nShape \"curve\"\n",
            "bad.pbrt:2:1: error: curve: 0 control points; a degree-3 Bézier curve needs 4 + n·3",
        ),
    ];
    let path = dir.join("bad.pbrt");
    for (text, expected) in cases {
        std::fs::write(&path, text).unwrap();
        // Run from the scratch directory so the location prints as `bad.pbrt`.
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_nimbus"))
            .current_dir(&dir)
            .args(["check", "bad.pbrt"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{text}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.lines().next().unwrap_or(""), *expected, "scene:\n{text}");
    }
}

#[test]
fn missing_include_names_the_include_directive() {
    let dir = scratch_dir("include");
    std::fs::write(dir.join("main.pbrt"), "WorldBegin\n  Include \"parts/missing.pbrt\"\n").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_nimbus"))
        .current_dir(&dir)
        .args(["check", "main.pbrt"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.starts_with("main.pbrt:2:3: error: Include \"parts/missing.pbrt\": cannot read"), "{stderr}");
}

#[test]
fn unused_parameters_warn_and_fail_under_strict() {
    let dir = scratch_dir("unused");
    let scene = dir.join("u.pbrt");
    std::fs::write(&scene, "WorldBegin\nShape \"sphere\" \"float radius\" 1 \"float raduis\" 2\n").unwrap();
    let out = nimbus(&["check", scene.to_str().unwrap()]);
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("u.pbrt:2:33: warning: \"float raduis\": unused parameter"), "{stderr}");
    let strict = nimbus(&["check", "--strict", scene.to_str().unwrap()]);
    assert_eq!(strict.status.code(), Some(1));
}

#[test]
fn missing_scene_file_is_an_error_not_a_panic() {
    let out = nimbus(&["check", "/nonexistent/scene.pbrt"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("/nonexistent/scene.pbrt: cannot read scene file"), "{stderr}");
}

#[test]
fn help_lists_subcommands() {
    let out = nimbus(&["--help"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("check"));
}

/// pbrt-v4 resolves relative paths from the directory of the scene named on the command line,
/// whichever file names them (San Miguel's included files name `geometry/…` from the top);
/// for a scene on standard input, from the working directory. A path that only exists
/// relative to the included file is an error naming where it was written and what was tried.
#[test]
fn relative_paths_resolve_from_the_scene_directory() {
    let dir = scratch_dir("search-dir");
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(scenes.join("parts")).unwrap();
    std::fs::create_dir_all(scenes.join("geometry")).unwrap();
    let obj = "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(scenes.join("geometry/tri.obj"), obj).unwrap();
    std::fs::write(scenes.join("parts/near.obj"), obj).unwrap();
    std::fs::write(scenes.join("parts/geo.pbrt"), "Shape \"objmesh\" \"string filename\" \"geometry/tri.obj\"\n")
        .unwrap();
    std::fs::write(scenes.join("parts/bad.pbrt"), "Shape \"objmesh\" \"string filename\" \"near.obj\"\n").unwrap();
    let header = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n";
    std::fs::write(scenes.join("main.pbrt"), format!("{header}Include \"parts/geo.pbrt\"\n")).unwrap();
    std::fs::write(scenes.join("bad.pbrt"), format!("{header}Include \"parts/bad.pbrt\"\n")).unwrap();
    let run = |cwd: &std::path::Path, args: &[&str], stdin: Option<&str>| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_nimbus"));
        cmd.current_dir(cwd).args(args).stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped());
        cmd.stdin(if stdin.is_some() { std::process::Stdio::piped() } else { std::process::Stdio::null() });
        let mut child = cmd.spawn().unwrap();
        if let Some(text) = stdin {
            use std::io::Write;
            child.stdin.take().unwrap().write_all(text.as_bytes()).unwrap();
        }
        child.wait_with_output().unwrap()
    };
    // From the parent directory: "scenes/main.pbrt" includes parts/geo.pbrt, whose mesh path
    // resolves from scenes/.
    let out = run(&dir, &["render", "scenes/main.pbrt", "--spp", "1", "--quiet", "--outfile", "out.exr"], None);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // Standard input resolves from the working directory.
    let text = std::fs::read_to_string(scenes.join("main.pbrt")).unwrap();
    assert!(run(&scenes, &["check", "-"], Some(&text)).status.success());
    assert_eq!(run(&dir, &["check", "-"], Some(&text)).status.code(), Some(1));
    // near.obj sits beside parts/bad.pbrt, not beside the scene.
    let out = run(&dir, &["check", "scenes/bad.pbrt"], None);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let tried = std::path::absolute(dir.join("scenes/near.obj")).unwrap();
    assert!(
        stderr.starts_with("scenes/parts/bad.pbrt:1:17: error: objmesh: cannot find file \"near.obj\""),
        "{stderr}"
    );
    assert!(stderr.contains(&format!("(tried {})", tried.display())), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The radiance-graph thesis's scenes name their VolPath reference `volpathcustom`.
#[test]
fn volpathcustom_is_volpath() {
    let dir = scratch_dir("volpathcustom");
    let scene = dir.join("s.pbrt");
    std::fs::write(
        &scene,
        "Integrator \"volpathcustom\" \"integer maxdepth\" 10\nWorldBegin\nLightSource \"distant\"\n",
    )
    .unwrap();
    let out = nimbus(&["check", scene.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("integrator  volpath (as \"volpathcustom\") maxdepth 10"), "{stdout}");
}

/// `check` builds what `render` builds short of tracing rays: it stops at the same first error
/// as `render` (an image texture read only when the scene is built, a method's constraints),
/// and lists every other problem its readers find rather than only the first missing file.
#[test]
fn check_reports_every_error_and_the_first_one_render_stops_at() {
    let dir = scratch_dir("check-render");
    let first_error = |out: &std::process::Output| {
        String::from_utf8_lossy(&out.stderr).lines().find(|l| l.contains(": error: ")).unwrap_or_default().to_string()
    };
    let head = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n";
    let cases = [
        // Two missing meshes and a missing image: every one named, the build's first.
        (
            "missing.pbrt",
            format!(
                "{head}WorldBegin\nTexture \"img\" \"spectrum\" \"imagemap\" \"string filename\" \"nope.png\"\n\
                 Material \"diffuse\" \"texture reflectance\" \"img\"\nShape \"plymesh\" \"string filename\" \"a.ply\"\n\
                 Shape \"plymesh\" \"string filename\" \"b.ply\"\n"
            ),
            3,
        ),
        // Readers pass; the radiance graph's constraints do not (a medium too anisotropic).
        (
            "constraints.pbrt",
            format!(
                "{head}Integrator \"radiancegraph\"\nWorldBegin\nLightSource \"distant\" \"rgb L\" [1 1 1]\n\
                 MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"float g\" 0.98\n\
                 AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\nShape \"sphere\"\nAttributeEnd\n"
            ),
            1,
        ),
    ];
    for (name, text, count) in cases {
        let scene = dir.join(name);
        std::fs::write(&scene, text).unwrap();
        let s = scene.to_str().unwrap();
        let check = nimbus(&["check", s]);
        let render = nimbus(&["render", s, "--outfile", dir.join("o.exr").to_str().unwrap()]);
        assert_eq!(check.status.code(), Some(1), "{name}");
        assert_eq!(render.status.code(), Some(1), "{name}");
        assert_eq!(first_error(&check), first_error(&render), "{name}");
        assert!(!first_error(&check).is_empty(), "{name}");
        let errors = String::from_utf8_lossy(&check.stderr).matches(": error: ").count();
        assert_eq!(errors, count, "{name}: {}", String::from_utf8_lossy(&check.stderr));
    }
}
