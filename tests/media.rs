//! Participating media checked against analytic answers, against each other, and against
//! pbrt-v4's renders of the media parity scenes.

use nimbus::integrators::common::PathConfig;
use nimbus::integrators::volpath::VolPath;
use nimbus::scene::BuildOptions;
use nimbus::setup::Setup;

use nimbus::channels::rgb_spectrum;
use nimbus::lights::LightKind;
use nimbus::media::MediumKind;
use nimbus::spectra::{RgbRole, Sampled};

use crate::common::{
    assert_channels, film_rgb, grid_values, load_scene, mean_difference, media_header, medium_cube,
    reference_scenes_dir, render_scene, render_with, transport,
};

fn scene(text: &str) -> Setup {
    load_scene(text, &BuildOptions::default())
}

/// Transmittance through a 2-unit slab of absorbing medium is exp(−σa·2), for a homogeneous
/// medium, a density grid and a chromatic rgbgrid; the backdrop is a uniform environment of
/// radiance 1 and rays through the slab's centre see nothing else. RGB transport applies it
/// per channel; spectral transport per wavelength, so its answer is the film's response to
/// L(λ)·exp(−2σa(λ)), integrated here from the scene's own spectra.
#[test]
fn slab_transmittance_is_exponential() {
    let media = [
        (
            r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.3 0.6 0.9] "rgb sigma_s" [0 0 0]"#
                .to_string(),
            [0.3, 0.6, 0.9],
        ),
        (
            format!(
                r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 4 "integer ny" 4 "integer nz" 4 "float density" [{}]
    "point3 p0" [-2 -2 -2] "point3 p1" [2 2 2] "rgb sigma_a" [0.5 0.5 0.5] "rgb sigma_s" [0 0 0]"#,
                grid_values(4, "1")
            ),
            [0.5, 0.5, 0.5],
        ),
        (
            format!(
                r#"MakeNamedMedium "m" "string type" "rgbgrid" "integer nx" 4 "integer ny" 4 "integer nz" 4 "rgb sigma_a" [{}]
    "rgb sigma_s" [{}] "point3 p0" [-2 -2 -2] "point3 p1" [2 2 2]"#,
                grid_values(4, "0.2 0.4 0.8"),
                grid_values(4, "0 0 0")
            ),
            [0.2, 0.4, 0.8],
        ),
    ];
    for (medium, sigma) in media {
        let text = format!(
            "{}WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n{medium}\nAttributeBegin\n{}\nAttributeEnd\n",
            media_header("volpath", 64, 5),
            medium_cube("m")
        );
        let img = render_scene(&load_scene(&text, &transport(false)));
        let expected = sigma.map(|s: f64| (-2.0 * s).exp());
        assert_channels(&img, expected, &medium);

        let s = load_scene(&text, &transport(true));
        let LightKind::UniformInfinite { l } = &s.lights[0].kind else { panic!("an infinite light") };
        let sigma_a: Sampled = match &s.media[0].kind {
            MediumKind::Homogeneous { sigma_a, .. } => sigma_a.sampled,
            MediumKind::Grid(g) => g.sigma_a.sampled,
            MediumKind::RgbGrid(_) => rgb_spectrum(
                glam::Vec3::from(sigma.map(|v| v as f32)),
                RgbRole::Unbounded,
                nimbus::parser::ColorSpace::Srgb,
            ),
        };
        let expected = film_rgb(|lambda| l.sampled.eval(lambda) * (-2.0 * sigma_a.eval(lambda)).exp());
        assert_channels(&render_scene(&s), expected, &format!("spectral: {medium}"));
    }
}

/// White furnace: a non-absorbing medium in a uniform environment of radiance L, with
/// enough bounces, returns L everywhere (light is only redistributed).
#[test]
fn white_furnace_returns_the_environment() {
    let media = [
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0 0 0] "rgb sigma_s" [2 2 2] "float g" 0.4"#
            .to_string(),
        format!(
            r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 3 "integer ny" 3 "integer nz" 3 "float density" [{}]
    "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "rgb sigma_a" [0 0 0] "rgb sigma_s" [3 3 3] "float g" -0.3"#,
            grid_values(3, "0.8")
        ),
    ];
    for medium in media {
        let text = format!(
            "{}WorldBegin\nLightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\n{medium}\nAttributeBegin\n{}\nAttributeEnd\n",
            media_header("volpath", 64, 200),
            medium_cube("m")
        );
        let img = render_scene(&scene(&text));
        assert_channels(&img, [0.5, 0.5, 0.5], &medium);
    }
}

/// An infinite emissive medium (camera inside) is in equilibrium: L = Le whatever σs and g,
/// for constant Le and for blackbody emission from a temperature grid.
#[test]
fn infinite_emissive_medium_radiance_equals_le() {
    let homogeneous = r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [1 1 1] "rgb sigma_s" [2 2 2] "rgb Le" [0.5 0.25 0.125] "float g" 0.5"#;
    let text = format!("MediumInterface \"m\" \"m\"\n{homogeneous}\n{}WorldBegin\n", media_header("volpath", 32, 400));
    assert_channels(&render_scene(&scene(&text)), [0.5, 0.25, 0.125], "homogeneous Le");
    // Temperature 20 scaled by 100: a 2000 K blackbody, peak-normalised as pbrt-v4 emits it.
    // The grid spans far beyond the camera's reach, so pbrt-v4's Lescale fade is 1 here.
    let grid = format!(
        r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 2 "integer ny" 2 "integer nz" 2
    "float density" [{}] "float temperature" [{}] "float temperaturescale" 100
    "point3 p0" [-1000 -1000 -1000] "point3 p1" [1000 1000 1000] "rgb sigma_a" [1 1 1] "rgb sigma_s" [2 2 2] "float g" 0.5"#,
        grid_values(2, "1"),
        grid_values(2, "20")
    );
    let text = format!("MediumInterface \"m\" \"m\"\n{grid}\n{}WorldBegin\n", media_header("volpath", 32, 400));
    let le = nimbus::spectra::blackbody_emission_rgb(2000.0, nimbus::parser::ColorSpace::Srgb);
    assert_channels(&render_scene(&scene(&text)), [le.x as f64, le.y as f64, le.z as f64], "blackbody grid");
}

/// Published scenes (pbrt-v4-scenes' explosion) spell `Lescale` as an older pbrt-v4 did,
/// `LeScale`: it is read as the same parameter (half the emission at 0.5), with one note for
/// the scene however many media spell it so.
#[test]
fn the_old_lescale_spelling_is_read_with_one_note() {
    let grid = |name: &str| {
        format!(
            r#"MakeNamedMedium "{name}" "string type" "uniformgrid" "integer nx" 2 "integer ny" 2 "integer nz" 2
    "float density" [{}] "float temperature" [{}] "float temperaturescale" 100 "float LeScale" 0.5
    "point3 p0" [-1000 -1000 -1000] "point3 p1" [1000 1000 1000] "rgb sigma_a" [1 1 1] "rgb sigma_s" [2 2 2]"#,
            grid_values(2, "1"),
            grid_values(2, "20")
        )
    };
    let text = format!(
        "MediumInterface \"m\" \"m\"\n{}\n{}\n{}WorldBegin\n",
        grid("m"),
        grid("m2"),
        media_header("volpath", 16, 400)
    );
    let setup = scene(&text);
    let notes =
        setup.scene.warnings.iter().filter(|w| w.message.contains("\"LeScale\" is read as \"Lescale\"")).count();
    assert_eq!(notes, 1, "{:?}", setup.scene.warnings);
    let le = nimbus::spectra::blackbody_emission_rgb(2000.0, nimbus::parser::ColorSpace::Srgb) * 0.5;
    assert_channels(&render_scene(&setup), [le.x as f64, le.y as f64, le.z as f64], "LeScale 0.5");
}

/// A uniformgrid of constant density d renders like the homogeneous medium with σ·d.
#[test]
fn constant_grid_matches_homogeneous_medium() {
    let body = |medium: &str| {
        format!(
            r#"LookAt 0 0.5 4  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Sampler "sobol" "integer pixelsamples" 32
Film "rgb" "integer xresolution" 24 "integer yresolution" 24
Integrator "volpath" "integer maxdepth" 20
WorldBegin
LightSource "distant" "point3 from" [1 3 2] "point3 to" [0 0 0] "rgb L" [2 2 2]
LightSource "infinite" "rgb L" [0.1 0.1 0.1]
{medium}
AttributeBegin
{}
AttributeEnd
"#,
            medium_cube("m")
        )
    };
    let homogeneous = body(
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.1 0.1 0.1] "rgb sigma_s" [0.9 0.9 0.9] "float g" 0.3"#,
    );
    let grid = body(&format!(
        r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 2 "integer ny" 2 "integer nz" 2 "float density" [{}]
    "point3 p0" [-2 -2 -2] "point3 p1" [2 2 2] "rgb sigma_a" [0.2 0.2 0.2] "rgb sigma_s" [1.8 1.8 1.8] "float g" 0.3"#,
        grid_values(2, "0.5")
    ));
    let (a, b) = (render_scene(&scene(&homogeneous)), render_scene(&scene(&grid)));
    let (md, sd) = mean_difference(&a, &b);
    assert!(md.abs() < 4.0 * sd, "homogeneous vs grid: {md} ± {sd}");
}

/// Next-event estimation with MIS and phase/BSDF sampling alone agree inside media whose
/// majorant cells have minorants (a grid of constant density, gray and chromatic grids of
/// densities 0.6–1, a chromatic homogeneous cube), lit by a uniform sky and a large area light, where both techniques
/// carry weight. Shadow rays track only the residual σmaj − σc, and delta tracking's
/// light-sampling probability `r_l` must say so, or the MIS weights of the two techniques no
/// longer sum to one and the MIS image is biased. Per-pixel differences of the two unbiased
/// images average to 0 within 4 standard errors.
#[test]
fn mis_and_phase_sampling_only_agree_with_residual_tracking() {
    let densities = (0..64).map(|k| format!("{}", 0.6 + 0.4 * ((k * 7 % 11) as f32 / 10.0))).collect::<Vec<_>>();
    let grid = |density: &str, sigma_s: &str| {
        format!(
            r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 4 "integer ny" 4 "integer nz" 4 "float density" [{density}]
    "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "rgb sigma_a" [0.1 0.1 0.1] "rgb sigma_s" [{sigma_s}] "float g" 0.4"#
        )
    };
    let media = [
        grid(&grid_values(4, "1"), "1.5 1.5 1.5"),
        grid(&densities.join(" "), "1.5 1.5 1.5"),
        grid(&densities.join(" "), "2.5 1.2 0.4"),
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.1 0.3 0.05] "rgb sigma_s" [2 1 0.5] "float g" 0.3"#
            .to_string(),
    ];
    for medium in media {
        let text = format!(
            r#"LookAt 0 0.3 3.4  0 0 0  0 1 0
Camera "perspective" "float fov" 45
Sampler "sobol" "integer pixelsamples" 64
Film "rgb" "integer xresolution" 24 "integer yresolution" 24
Integrator "volpath" "integer maxdepth" 8
WorldBegin
LightSource "infinite" "rgb L" [0.5 0.5 0.5]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [2 2 2]
  Material "diffuse" "rgb reflectance" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 1.6 -2  2 1.6 -2  2 1.6 2  -2 1.6 2]
AttributeEnd
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-4 -1.2 -4  4 -1.2 -4  4 -1.2 4  -4 -1.2 4]
{medium}
AttributeBegin
  Scale 0.8 0.8 0.8
{}
AttributeEnd
"#,
            medium_cube("m")
        );
        let s = scene(&text);
        let mis = render_with(&s.scene, &VolPath::with_config(PathConfig::volpath(8, false)));
        let alone = render_with(
            &s.scene,
            &VolPath::with_config(PathConfig { next_event: false, ..PathConfig::volpath(8, false) }),
        );
        let (md, sd) = mean_difference(&mis, &alone);
        let mean = mis.pixels.iter().map(|p| (p.x + p.y + p.z) as f64 / 3.0).sum::<f64>() / mis.pixels.len() as f64;
        assert!(md.abs() < 4.0 * sd, "{medium}: MIS − phase sampling only = {md} ± {sd} (image mean {mean})");
        assert!(mean > 0.02, "the medium is lit: {mean}");
    }
}

/// The same cloud through `nanovdb` (NanoVDB file) and `vdb` (OpenVDB file) renders the same
/// image: the grids hold identical voxels and transforms.
#[test]
fn nanovdb_and_openvdb_files_render_alike() {
    let dir = reference_scenes_dir();
    let text = std::fs::read_to_string(dir.join("vdb-cloud.pbrt")).unwrap();
    let vdb = text.replace(
        r#""nanovdb" ] "string filename" [ "vdb-cloud.nvdb" ]"#,
        r#""vdb" ] "string filename" [ "vdb-cloud.vdb" ]"#,
    );
    assert_ne!(text, vdb, "the scene names its NanoVDB file");
    let build = |t: &str| {
        let desc = nimbus::parser::load_str(t, dir.join("vdb-cloud.pbrt").to_str().unwrap()).unwrap();
        nimbus::setup::build(&desc, &BuildOptions { spp: Some(2), quick: true, ..Default::default() }).unwrap()
    };
    assert_eq!(render_scene(&build(&text)).pixels, render_scene(&build(&vdb)).pixels);
}

/// Parity with pbrt-v4 on every media scene of the reference suite in `auto` transport, judged
/// as its README does (two seeds, mean of the worst channel, 8×8 block excess), at small spp.
/// The mean tolerance widens by 4 standard errors of our estimate where a scene is too noisy
/// for the README's bound at this spp (the wax caustics).
///
/// The excess is averaged over three independent pairs of renders. One pair's excess is a
/// heavy-tailed statistic (a cloud's error sits in a few bright blocks at its lit edge): on
/// graph-cloud at 16 spp six pairs read 0.77–1.97 (mean 1.13) before f2a1ac4 and 0.71–1.76
/// (1.04) after; on vdb-cloud 14 pairs 0.56–1.54 (1.01) and 0.57–1.79 (1.17), the two versions
/// against each other at 256 spp × 2 seeds reading 0.85 with means within 0.01 %; guided on
/// the wax at 32 spp 0.67–1.43 and 0.64–1.71 (four pairs). With one pair, any change of random
/// streams could tip an unbiased scene over the bound.
#[test]
fn media_scenes_match_pbrt_v4() {
    media_scenes_match_pbrt_v4_with(None, 3, &[]);
}

/// Path guiding converges to the same answer as volpath on every media scene of the reference
/// suite, judged by the same parity check (its guide trained anew for each seed), with its
/// defaults, which guide only the wax (the one medium lit through a dielectric). With every
/// medium guided (`refractedshare` 0, not the default) on one scene of each kind the guide
/// meets there — a gray homogeneous sphere, a grid cloud under a distant light, an emitting
/// grid (the VDB cloud, the second grid cloud, the fog under a spotlight and the chromatic
/// smoke took 70 s more; guided-everywhere on the grid cloud is in guided's results) — the
/// excess is averaged over three independent pairs of renders: one pair's excess spreads
/// widely on a cloud guided everywhere, with splitting or without (graph-cloud at 16 spp, six
/// pairs each: 0.90–2.13 and 1.09–2.08, mean 1.24 and 1.33; grid-cloud at 32 spp, eight
/// pairs: 0.58–1.35, where volpath's own spread 0.77–1.37).
#[test]
fn guided_media_scenes_match_pbrt_v4() {
    media_scenes_match_pbrt_v4_with(Some(""), 3, &[]);
    let everywhere = r#""float refractedshare" 0"#;
    media_scenes_match_pbrt_v4_with(Some(everywhere), 3, &["homogeneous-sphere", "graph-cloud", "emissive-grid"]);
}

/// The parity check with the scene's integrator (`None`) or `guided` with these parameters
/// (added to the scene's), over `pairs` independent pairs of renders (seeds 1 and 2, 3 and 4,
/// ...), on the scenes `only` names (every one when empty): every pair's mean within
/// tolerance, the pairs' mean excess below its tolerance.
fn media_scenes_match_pbrt_v4_with(guided: Option<&str>, pairs: i32, only: &[&str]) {
    let dir = reference_scenes_dir();
    let scenes: [(&str, u32, f64, f64); 8] = [
        ("homogeneous-sphere", 16, 0.01, 1.5),
        ("grid-cloud", 16, 0.01, 1.5),
        ("graph-cloud", 16, 0.01, 1.5),
        ("fog-spotlight", 16, 0.01, 1.5),
        // Emission inside the cloud is heavy-tailed: judged at the README's 32 spp. The
        // medium's box sits in the floor's plane (its bottom face at y = −1, as the floor):
        // ties that nimbus decides with pbrt-v4's own triangle arithmetic (`accel/tie.rs`).
        ("emissive-grid", 32, 0.01, 1.5),
        // The README's 32 spp (at 16 one pair read up to 1.79, above).
        ("vdb-cloud", 32, 0.01, 1.5),
        // Chromatic media: spectral transport in `auto` mode, judged like the others (RGB
        // transport was 2.5 % off on the wax and needed 3 %).
        ("rgbgrid-smoke", 16, 0.01, 1.5),
        ("wax-dielectric", 32, 0.01, 1.5),
    ];
    for (name, spp, mean_tol, excess_tol) in scenes {
        if !only.is_empty() && !only.contains(&name) {
            continue;
        }
        let path = dir.join(format!("{name}.pbrt"));
        let desc = match guided {
            None => nimbus::parser::load_file(&path).unwrap(),
            Some(params) => {
                let text = std::fs::read_to_string(&path).unwrap();
                assert!(text.contains("Integrator \"volpath\""), "{name}");
                let text = text.replace("Integrator \"volpath\"", &format!("Integrator \"guided\" {params}"));
                nimbus::parser::load_str(&text, path.to_str().unwrap()).unwrap()
            }
        };
        let reference = nimbus::imageio::read_exr(&dir.join(format!("../images/{name}.exr"))).unwrap();
        let render_seed = |seed| {
            let opts = BuildOptions { spp: Some(spp), seed: Some(seed), ..Default::default() };
            let scene = nimbus::setup::build(&desc, &opts).unwrap();
            render_with(&scene, scene.integrator.create(&scene).unwrap().as_ref())
        };
        let mut excess = Vec::new();
        for pair in 0..pairs {
            let (a, b) = (render_seed(2 * pair + 1), render_seed(2 * pair + 2));
            let p = nimbus::metrics::parity(&a, &b, &reference).unwrap();
            // Standard error of the image mean of M, from the pixels' (A − B)/2.
            let n = a.pixels.len() as f64;
            let ref_mean = reference.mean();
            for c in 0..3 {
                let var: f64 =
                    a.pixels.iter().zip(&b.pixels).map(|(x, y)| (0.5 * (x[c] - y[c]) as f64).powi(2)).sum::<f64>() / n;
                let se = (var / n).sqrt() / ref_mean[c] as f64;
                assert!(
                    p.mean_rel[c] < mean_tol + 4.0 * se,
                    "{guided:?} {name}: channel {c} mean_rel {} (tolerance {mean_tol} + 4 × {se})",
                    p.mean_rel[c]
                );
            }
            excess.push(p.excess);
        }
        let mean_excess = excess.iter().sum::<f64>() / excess.len() as f64;
        assert!(mean_excess < excess_tol, "{guided:?} {name}: excess {excess:?}");
    }
}
