//! pbrt-v4's `realistic` camera end to end: its lens files, errors that name the file and
//! line, vignetting, and every integrator path (per camera ray and whole-image) applying the
//! lens's ray weights and stopped rays alike.

use crate::common::{load_scene, medium_cube, render_scene, render_with, scratch_dir};
use nimbus::integrators::common::PathConfig;
use nimbus::integrators::volpath::VolPath;
use nimbus::scene::BuildOptions;

/// pbrt-v4-scenes' `lenses/dgauss.50mm.dat` (a 50 mm f/2 double-Gauss lens), as published.
const DGAUSS: &str = "# D-GAUSS F/2 22deg HFOV
# US patent 2,673,491 Tronnier
#    radius\t axpos\tN\taperture
29.475\t3.76\t1.67\t25.2
84.83\t0.12\t1\t25.2
19.275\t4.025\t1.67\t23
40.77\t3.275\t1.699\t23
12.75\t5.705\t1\t18
0\t4.5\t0\t17.1
-14.495\t1.18\t1.603\t17
40.77\t6.065\t1.658\t20
-20.385\t0.19\t1\t20
437.065\t3.22\t1.717\t20
-39.73\t0\t1\t20
";

/// A scene seen through `lens` (a path), rendered by `integrator` (with `params`): a medium
/// cube over a floor under a sky and a sun, or only the sky when `sky_only`.
fn scene(lens: &std::path::Path, camera_params: &str, integrator: &str, params: &str, sky_only: bool) -> String {
    let world = if sky_only {
        String::new()
    } else {
        format!(
            r#"LightSource "distant" "point3 from" [0.3 1 0.2] "point3 to" [0 0 0] "rgb L" [2 2 2]
MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_s" [1 1 1] "rgb sigma_a" [0.05 0.05 0.05]
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "point3 P" [-4 -1 -4  4 -1 -4  4 -1 4  -4 -1 4] "integer indices" [0 2 1 0 3 2]
{}
"#,
            medium_cube("m")
        )
    };
    format!(
        r#"LookAt 0 1 6  0 0 0  0 1 0
Camera "realistic" "string lensfile" "{}" {camera_params}
Film "rgb" "integer xresolution" 32 "integer yresolution" 24
Sampler "zsobol" "integer pixelsamples" 8
Integrator "{integrator}" "integer maxdepth" 10 {params}
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
{world}"#,
        lens.display()
    )
}

/// Under a uniform sky the image is what the lens lets through: brightest at the centre,
/// darker towards the corners (cos⁴ and the lens's vignetting), every pixel finite, and the
/// centre the camera equation's share of the sky's radiance, π/4N², for an f-number N between
/// 3 and 5 (a 10-mm stop behind the front group of a 50-mm lens).
#[test]
fn a_lens_under_a_uniform_sky_vignettes() {
    let dir = scratch_dir("realistic-sky");
    let lens = dir.join("dgauss.50mm.dat");
    std::fs::write(&lens, DGAUSS).unwrap();
    let text = scene(&lens, r#""float aperturediameter" 10 "float focusdistance" 6"#, "volpath", "", true);
    let image = render_scene(&load_scene(&text, &BuildOptions { seed: Some(3), ..Default::default() }));
    assert!(image.pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
    let at = |x: usize, y: usize| image.pixels[y * image.width + x].x;
    let centre = (at(15, 11) + at(16, 11) + at(15, 12) + at(16, 12)) / 4.0;
    let corners = (at(0, 0) + at(31, 0) + at(0, 23) + at(31, 23)) / 4.0;
    assert!(centre > 0.031 && centre < 0.088, "centre {centre}");
    assert!(corners < 0.9 * centre, "corners {corners}, centre {centre}");
}

/// The whole-image method applies the lens's weights and its stopped rays as the per-ray
/// ones do: pathgraph with clusters of one is volpath through the same lens, to rounding.
#[test]
fn pathgraph_sees_through_the_lens_as_volpath_does() {
    let dir = scratch_dir("realistic-pathgraph");
    let lens = dir.join("dgauss.50mm.dat");
    std::fs::write(&lens, DGAUSS).unwrap();
    let params = r#""float aperturediameter" 17 "float focusdistance" 6"#;
    let opts = BuildOptions { seed: Some(2), ..Default::default() };
    let graph_params = r#""integer clustersize" 1 "integer iterations" 2 "integer linesamples" 0"#;
    let graph = load_scene(&scene(&lens, params, "pathgraph", graph_params, false), &opts);
    let volpath = load_scene(&scene(&lens, params, "volpath", "", false), &opts);
    let line = VolPath::with_config(PathConfig { camera_line: true, ..PathConfig::volpath(10, false) });
    let (g, v) = (render_scene(&graph), render_with(&volpath, &line));
    let peak = v.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max);
    let d = g.pixels.iter().zip(&v.pixels).map(|(a, b)| (*a - *b).abs().max_element()).fold(0.0, f32::max);
    assert!(peak > 0.0 && d <= 1e-4 * peak, "max difference {d} (peak {peak})");
}

/// What is wrong with a lens is said with the file and the line, by `check` as by rendering:
/// no lens file given, one that does not exist, a word where a number belongs, rows that are
/// not of four, a focus closer than the lens can focus.
#[test]
fn lens_errors_name_the_file_and_line() {
    let dir = scratch_dir("realistic-errors");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let good = write("good.dat", DGAUSS);
    let cases: Vec<(String, &str)> = vec![
        (
            scene(&good, "", "volpath", "", true).replace(r#""string lensfile" ""#, r#""string lens" ""#),
            "no \"lensfile\"",
        ),
        (scene(&dir.join("missing.dat"), "", "volpath", "", true), "missing.dat"),
        (scene(&write("word.dat", "29.475 3.76 1.67 25.2\n84.83 x 1 25.2\n"), "", "volpath", "", true), "word.dat:2"),
        (scene(&write("three.dat", "29.475 3.76 1.67 25.2\n84.83 0.12 1\n"), "", "volpath", "", true), "rows of four"),
        (scene(&good, r#""float focusdistance" 0.01"#, "volpath", "", true), "too short"),
    ];
    for (text, expected) in cases {
        let path = dir.join("s.pbrt");
        std::fs::write(&path, &text).unwrap();
        let desc = nimbus::parser::load_file(&path).unwrap();
        let err = nimbus::setup::build(&desc, &BuildOptions::default()).err().map(|e| e.to_string());
        let err = err.unwrap_or_else(|| panic!("no error for {expected}"));
        assert!(err.contains(expected) && err.contains("s.pbrt:2:"), "{err}");
        // `check` refuses what rendering refuses, with the same message.
        let check = nimbus::setup::check_scene(&desc).err().map(|e| e.to_string());
        assert_eq!(check.as_deref(), Some(err.as_str()));
    }
}
