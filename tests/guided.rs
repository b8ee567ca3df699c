//! Path guiding in media: the same answer as volpath where it guides (a milky medium in a
//! glass sphere under a small light, in RGB and spectral transport, with and without
//! splitting), a white furnace through glass, lower noise there, the same image at any thread
//! count, and its guide cache reused and refused as it should be.

use nimbus::imageio::Image;
use nimbus::scene::BuildOptions;

use crate::common::{channel_stats, load_scene, nimbus, render_scene, scratch_dir, transport};

/// A forward-scattering medium (`sigma_s` as given, g = 0.85) inside a glass sphere over a
/// diffuse floor, lit by a small spherical light and a dim sky: light reaches the medium
/// through the glass only, the case guiding is for. `sigma_a` is chromatic, so `auto`
/// transport is spectral.
fn glass_scene(integrator: &str, params: &str) -> String {
    format!(
        r#"LookAt 0 0.7 3.6  0 0 0  0 1 0
Camera "perspective" "float fov" 38
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Sampler "zsobol" "integer pixelsamples" 16
Integrator "{integrator}" "integer maxdepth" 32 {params}
WorldBegin
LightSource "infinite" "rgb L" [0.05 0.05 0.06]
AttributeBegin
  Translate 1.4 1.8 0.9
  AreaLightSource "diffuse" "rgb L" [7.5 7 6]
  Material "diffuse" "rgb reflectance" [0 0 0]
  Shape "sphere" "float radius" 0.3
AttributeEnd
MakeNamedMedium "milk" "string type" "homogeneous" "rgb sigma_a" [0.02 0.03 0.08]
  "rgb sigma_s" [1.5 1.6 1.7] "float g" 0.85
AttributeBegin
  MediumInterface "milk" ""
  Material "dielectric" "float eta" 1.4
  Shape "sphere" "float radius" 0.9
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [0.45 0.45 0.45]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-8 -0.9 -8  8 -0.9 -8  8 -0.9 8  -8 -0.9 8]
AttributeEnd
"#
    )
}

/// Few photons: the tests check the method, not the guide's quality.
const SMALL: &str = r#""integer photons" 8192 "integer trainingiterations" 3"#;

/// Mean per-pixel difference a − b in channel `c` and its standard error.
fn paired_difference(a: &Image, b: &Image, c: usize) -> (f64, f64) {
    let d: Vec<f64> = a.pixels.iter().zip(&b.pixels).map(|(p, q)| f64::from(p[c] - q[c])).collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Guided and volpath estimate the same image, in both transports: with the paper's
/// resampling (g = 0.85 ≥ 0.5) and with one-sample MIS (`selectivethreshold` 2), with
/// splitting wherever a path's expected contribution grows at all (`splitthreshold` 1, up to
/// 16 copies) and without splitting, each against volpath at another seed, within four
/// standard errors of the pixels' differences.
#[test]
fn guided_and_volpath_agree() {
    for spectral in [false, true] {
        let opts = BuildOptions { spp: Some(64), seed: Some(3), ..transport(spectral) };
        let volpath = render_scene(&load_scene(&glass_scene("volpath", ""), &opts));
        let split_everywhere = r#""float splitthreshold" 1 "integer maxsplit" 16"#;
        for extra in ["", r#""float selectivethreshold" 2"#, split_everywhere, r#""integer maxsplit" 1"#] {
            let params = format!("{SMALL} {extra}");
            let guided = render_scene(&load_scene(
                &glass_scene("guided", &params),
                &BuildOptions { seed: Some(4), ..opts.clone() },
            ));
            for c in 0..3 {
                let (mean, se) = paired_difference(&guided, &volpath, c);
                let level = channel_stats(&volpath)[c].0;
                assert!(
                    mean.abs() <= 4.0 * se && level > 0.01,
                    "spectral {spectral} {extra}: channel {c}: difference {mean} ± {se} (level {level})"
                );
            }
        }
    }
}

/// A white furnace through glass: a medium that absorbs nothing, in a glass sphere under a
/// uniform sky of radiance 1, is invisible, so every pixel's expectation is 1. Guided paths
/// (resampled directions, split copies, next-event estimation by roulette inside the glass,
/// where it finds nothing) average to it within four standard errors, at g = 0.85 and 0.
#[test]
fn white_furnace_through_glass() {
    for g in ["0.85", "0"] {
        let text = format!(
            r#"LookAt 0 0 3  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Sampler "zsobol" "integer pixelsamples" 32
Integrator "guided" "integer maxdepth" 100000 {SMALL} "float splitthreshold" 1.5
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
MakeNamedMedium "white" "string type" "homogeneous" "rgb sigma_a" [0 0 0] "rgb sigma_s" [2 2 2] "float g" {g}
AttributeBegin
  MediumInterface "white" ""
  Material "dielectric" "float eta" 1.4
  Shape "sphere" "float radius" 0.9
AttributeEnd
"#
        );
        let scene = load_scene(&text, &BuildOptions { seed: Some(6), ..transport(false) });
        let report = scene.integrator.create(&scene).unwrap().report().join("\n");
        assert!(report.contains("white guided (100 % refracted)") && report.contains("split into up to 8"), "{report}");
        crate::common::assert_channels(&render_scene(&scene), [1.0; 3], &format!("furnace, g {g}"));
    }
}

/// Copies of a split path share its wavelengths, which a dispersive surface cuts down to the
/// hero for the whole path: with a dispersive glass, guided does not split.
#[test]
fn dispersive_glass_turns_splitting_off() {
    let text = glass_scene("guided", SMALL).replace(r#""float eta" 1.4"#, r#""spectrum eta" "glass-BK7""#);
    let scene = load_scene(&text, &BuildOptions { spp: Some(1), ..transport(true) });
    let report = scene.integrator.create(&scene).unwrap().report().join("\n");
    assert!(report.contains("guide split off"), "{report}");
}

/// Where the light comes through the glass, guiding lowers the noise at equal spp: the MSE
/// against a 1024-spp volpath reference, over the whole image, is lower than volpath's.
#[test]
fn guiding_lowers_the_noise_through_glass() {
    let opts = BuildOptions { spp: Some(32), seed: Some(1), ..transport(false) };
    let reference = render_scene(&load_scene(
        &glass_scene("volpath", ""),
        &BuildOptions { spp: Some(1024), seed: Some(9), ..opts.clone() },
    ));
    let volpath = render_scene(&load_scene(&glass_scene("volpath", ""), &opts));
    let guided = render_scene(&load_scene(&glass_scene("guided", SMALL), &opts));
    let mse = |a: &Image| {
        a.pixels.iter().zip(&reference.pixels).map(|(p, q)| f64::from((*p - *q).length_squared())).sum::<f64>()
            / a.pixels.len() as f64
    };
    let (g, v) = (mse(&guided), mse(&volpath));
    assert!(g < 0.8 * v, "guided MSE {g}, volpath MSE {v}");
}

/// Training and rendering are deterministic for a seed: one thread and two give the same
/// image, bit for bit.
#[test]
fn same_image_at_any_thread_count() {
    let scene =
        load_scene(&glass_scene("guided", SMALL), &BuildOptions { spp: Some(4), seed: Some(5), ..transport(true) });
    let render = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render_scene(&scene))
    };
    assert_eq!(render(1).pixels, render(2).pixels);
}

/// `--guide-cache`: the first render trains and saves, the second loads the trees (another
/// camera) and its image is the one a fresh training gives; a changed light, other training
/// parameters or a damaged file are refused with a message naming the file and a non-zero
/// exit.
#[test]
fn guide_cache_is_reused_and_refused() {
    let dir = scratch_dir("guide-cache");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let scene = write("glass.pbrt", &glass_scene("guided", SMALL));
    let cache = dir.join("glass.guide").to_str().unwrap().to_string();
    let render = |scene: &str, out: &str, cache: Option<&str>| {
        let out = dir.join(out).to_str().unwrap().to_string();
        let mut args = vec!["render", scene, "--spp", "2", "--seed", "1", "--quiet", "--stats", "--outfile", &out];
        if let Some(c) = cache {
            args.extend(["--guide-cache", c]);
        }
        (nimbus(&args), out)
    };
    let (first, _) = render(&scene, "a.exr", Some(&cache));
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    assert!(String::from_utf8_lossy(&first.stdout).contains("saved to"));
    // Another camera, the same media and lights: loaded, and the same image as training anew.
    let moved = write("moved.pbrt", &glass_scene("guided", SMALL).replace("LookAt 0 0.7 3.6", "LookAt 0.5 0.9 3.4"));
    let (second, loaded) = render(&moved, "b.exr", Some(&cache));
    assert!(second.status.success(), "{}", String::from_utf8_lossy(&second.stderr));
    assert!(
        String::from_utf8_lossy(&second.stdout).contains("loaded from"),
        "{}",
        String::from_utf8_lossy(&second.stdout)
    );
    let (fresh, trained) = render(&moved, "c.exr", None);
    assert!(fresh.status.success());
    let read = |p: &str| nimbus::imageio::read_exr(std::path::Path::new(p)).unwrap().pixels;
    assert_eq!(read(&loaded), read(&trained));
    // Refusals.
    let brighter = write("brighter.pbrt", &glass_scene("guided", SMALL).replace("[7.5 7 6]", "[9 7 6]"));
    let more_photons = write("photons.pbrt", &glass_scene("guided", r#""integer photons" 4096"#));
    for (scene, says) in [(&brighter, "another scene"), (&more_photons, "other training parameters")] {
        let (out, _) = render(scene, "d.exr", Some(&cache));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("glass.guide") && err.contains(says), "{err}");
    }
    let bytes = std::fs::read(&cache).unwrap();
    std::fs::write(&cache, &bytes[..bytes.len() / 2]).unwrap();
    let (out, _) = render(&scene, "e.exr", Some(&cache));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("glass.guide"), "{err}");
}

/// A parameter out of range or of the wrong type is an error naming the file, line and
/// parameter, with a non-zero exit.
#[test]
fn bad_parameters_name_the_place() {
    let dir = scratch_dir("guided-params");
    for (params, name) in [
        (r#""float lambda" 1.5"#, "lambda"),
        (r#""integer candidates" 0"#, "candidates"),
        (r#""float defensive" 0"#, "defensive"),
        (r#""string photons" "many""#, "photons"),
    ] {
        let path = dir.join("bad.pbrt");
        std::fs::write(&path, glass_scene("guided", params)).unwrap();
        let out =
            nimbus(&["render", path.to_str().unwrap(), "--quiet", "--outfile", dir.join("x.exr").to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("bad.pbrt:5") && err.contains(name), "{params}: {err}");
    }
}

/// A medium lit directly (no refractive boundary) is not guided by default: the image is
/// volpath's bit for bit (the training costs, the render does not). With `refractedshare 0`
/// it is guided, and photons find it from an area light inside it whose shape names the
/// medium on both sides (`MediumInterface "fog" "fog"`), as well as from one with no
/// interface of its own.
#[test]
fn unguided_media_render_volpath_and_lights_inside_media_are_found() {
    let scene = |integrator: &str, params: &str, light_interface: &str| {
        format!(
            r#"LookAt 0 1 4  0 0.5 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Sampler "zsobol" "integer pixelsamples" 4
Integrator "{integrator}" "integer maxdepth" 8 {params}
MediumInterface "fog" "fog"
WorldBegin
MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [0.02 0.02 0.02] "rgb sigma_s" [0.3 0.3 0.3]
AttributeBegin
  MediumInterface "fog" ""
  Material "interface"
  Shape "sphere" "float radius" 10
AttributeEnd
AttributeBegin
  {light_interface}
  Translate 0.5 1 0
  AreaLightSource "diffuse" "rgb L" [5 5 5]
  Shape "sphere" "float radius" 0.2
AttributeEnd
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-4 0 -4  4 0 -4  4 0 4  -4 0 4]
"#
        )
    };
    let opts = BuildOptions { seed: Some(2), ..Default::default() };
    let fog = r#"MediumInterface "fog" "fog""#;
    let guided = load_scene(&scene("guided", SMALL, fog), &opts);
    let volpath = load_scene(&scene("volpath", "", fog), &opts);
    assert_eq!(render_scene(&guided).pixels, render_scene(&volpath).pixels);
    for light_interface in [fog, ""] {
        let all = load_scene(&scene("guided", &format!(r#"{SMALL} "float refractedshare" 0"#), light_interface), &opts);
        let report = all.integrator.create(&all).unwrap().report().join("\n");
        assert!(report.contains("fog guided (0 % refracted)"), "{light_interface:?}: {report}");
    }
}

/// The README's equal-spp claim on the candle (pbrt-scenes/wax-small-light.pbrt, its results'
/// first case: 4.07× lower relMSE than volpath at 64 spp): on the candle's middle (32×32
/// pixels through the glass) at 64 spp, two seeds each, guided's MSE against the shipped
/// 4096-spp reference is lower than volpath's by at least CANDLE_AT_EQUAL_SPP.
#[test]
fn the_candle_at_equal_spp() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/wax-small-light.pbrt");
    let desc = nimbus::parser::load_file(&path).unwrap();
    let reference = nimbus::imageio::read_exr(&path.with_file_name("references/wax-small-light.exr")).unwrap();
    let bounds = [40usize, 72, 32, 64];
    let mse = |integrator: &str| {
        [1, 2]
            .map(|seed| {
                let opts = BuildOptions {
                    integrator: Some(integrator.into()),
                    spp: Some(64),
                    seed: Some(seed),
                    pixel_bounds: Some(bounds.map(|b| b as i32)),
                    ..Default::default()
                };
                let img = render_scene(&nimbus::setup::build(&desc, &opts).unwrap());
                assert_eq!((img.width, img.height), (32, 32));
                let mut sum = 0.0;
                for y in 0..32 {
                    for x in 0..32 {
                        let r = reference.get(bounds[0] + x, bounds[2] + y);
                        sum += f64::from((img.get(x, y) - r).length_squared());
                    }
                }
                sum / 1024.0
            })
            .iter()
            .sum::<f64>()
            / 2.0
    };
    let (v, g) = (mse("volpath"), mse("guided"));
    eprintln!("candle middle at 64 spp: MSE volpath {v:.3e}, guided {g:.3e}: {:.2}x", v / g);
    assert!(
        v / g >= CANDLE_AT_EQUAL_SPP,
        "volpath MSE {v:.3e} / guided MSE {g:.3e} = {:.2} (README: at least {CANDLE_AT_EQUAL_SPP})",
        v / g
    );
}

/// The factor the README states as the test's lower bound.
const CANDLE_AT_EQUAL_SPP: f64 = 2.5;
