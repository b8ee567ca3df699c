//! Motion blur: shapes, instances and the camera moving over the shutter interval
//! (`ActiveTransform` / `TransformTimes`), against the blur they must produce.

use nimbus::scene::BuildOptions;

use crate::common::{load_scene, render_scene};

/// A black slab 0.5 wide, seen by an orthographic camera over x in [-2, 2] against a white
/// environment; `motion` is what goes between `AttributeBegin` and the slab.
fn slab_scene(camera_motion: &str, slab_motion: &str, shutter: f32) -> String {
    format!(
        r#"TransformTimes 0 1
{camera_motion}
LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [ -2 2 -1 1 ] "float shutterclose" [ {shutter} ]
Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" [ 32 ]
Sampler "zsobol" "integer pixelsamples" [ 16 ]
Integrator "volpath"
WorldBegin
LightSource "infinite" "rgb L" [ 1 1 1 ]
AttributeBegin
{slab_motion}
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ -0.25 -2 0  0.25 -2 0  0.25 2 0  -0.25 2 0 ]
AttributeEnd
"#
    )
}

const MOVING: &str = "  ActiveTransform StartTime\n  Translate -1 0 0\n  ActiveTransform EndTime\n  Translate 1 0 0\n  ActiveTransform All";

/// Mean of the red channel over pixel columns `x0..x1` (all rows).
fn columns(img: &nimbus::imageio::Image, x0: usize, x1: usize) -> f64 {
    let mut sum = 0.0;
    for y in 0..img.height {
        for x in x0..x1 {
            sum += img.get(x, y)[0] as f64;
        }
    }
    sum / ((x1 - x0) * img.height) as f64
}

/// Pixel column x covers world x in [2 − (x+1)/16, 2 − x/16] (pbrt-v4's camera space is
/// left-handed: looking down −z, raster x runs along world −x). The slab's centre sweeps from
/// −1 to 1:
/// a point with |x| < 0.75 is covered for 0.5 of the 2 units, a quarter of the shutter, and
/// points beyond 1.25 never are. The tolerance is 4 standard errors of a Bernoulli mean
/// over the region's samples (16 per pixel), a bound the stratified time samples only beat.
fn check_blur(img: &nimbus::imageio::Image, what: &str) {
    let inner = columns(img, 22, 42);
    let n = (20 * img.height * 16) as f64;
    let se = (0.75 * 0.25 / n).sqrt();
    assert!((inner - 0.75).abs() < 4.0 * se, "{what}: covered a quarter of the time: {inner} vs 0.75 ± {se}");
    let outer = (columns(img, 0, 10) + columns(img, 54, 64)) / 2.0;
    assert!((outer - 1.0).abs() < 1e-4, "{what}: never covered: {outer}");
    // The whole image: 1.5 units at 1, 1.5 at 0.75 and 1 unit of linear ramps (mean 0.875).
    let all = columns(img, 0, 64);
    assert!((all - 0.875).abs() < 4.0 * (0.1875 / (64.0 * 32.0 * 16.0f64)).sqrt() + 2e-3, "{what}: mean {all}");
}

fn render(text: &str) -> nimbus::imageio::Image {
    render_scene(&load_scene(text, &BuildOptions { seed: Some(3), ..Default::default() }))
}

#[test]
fn a_moving_shape_blurs_over_the_shutter() {
    check_blur(&render(&slab_scene("", MOVING, 1.0)), "moving shape");
    // The same motion on an object instance.
    let instanced = slab_scene("", "", 1.0).replace("AttributeBegin\n\n  Material", "ObjectBegin \"slab\"\n  Material");
    let instanced = instanced.replace(
        "AttributeEnd\n",
        &format!("ObjectEnd\nAttributeBegin\n{MOVING}\n  ObjectInstance \"slab\"\nAttributeEnd\n"),
    );
    assert!(instanced.contains("ObjectInstance"), "{instanced}");
    check_blur(&render(&instanced), "moving instance");
    // A camera moving the other way sees the same blur of a still slab.
    let camera =
        "ActiveTransform StartTime\nTranslate -1 0 0\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All";
    check_blur(&render(&slab_scene(camera, "", 1.0)), "moving camera");
}

#[test]
fn the_shutter_interval_selects_the_motion_and_the_exposure() {
    // Open for [0, 0.5]: the slab's centre goes from −1 to 0, covering x in [−0.75, −0.25]
    // for half the exposure, and pbrt-v4's imaging ratio halves the image.
    let img = render(&slab_scene("", MOVING, 0.5));
    let covered = columns(&img, 36, 42);
    let se = 0.5 * (0.25 / (6.0 * 32.0 * 16.0f64)).sqrt();
    assert!((covered - 0.25).abs() < 4.0 * se, "{covered} vs 0.25 ± {se}");
    let clear = columns(&img, 0, 20);
    assert!((clear - 0.5).abs() < 1e-4, "{clear}");
}

#[test]
fn a_rotating_shape_stays_inside_its_motion_bounds() {
    // A slab turning a quarter turn about the view axis sweeps a disk of radius 2 (its
    // half-length): every pixel within 0.25 of the centre is always covered, and the BVH's
    // bounds must hold the slab at every time for that to be seen.
    let rotating = "  ActiveTransform EndTime\n  Rotate 90 0 0 1\n  ActiveTransform All";
    let img = render(&slab_scene("", rotating, 1.0));
    let centre = img.get(32, 16)[0];
    assert!(centre < 1e-6, "the centre is always covered: {centre}");
    // Along the horizontal axis at x = 1.5 the slab passes once, for a short while.
    let passing = img.get(56, 16)[0];
    assert!(passing > 0.7 && passing < 1.0, "{passing}");
}

#[test]
fn motion_pbrt_v4_does_not_support_is_refused_or_warned() {
    let area = slab_scene("", MOVING, 1.0).replace("  Material", "  AreaLightSource \"diffuse\"\n  Material");
    let desc = nimbus::parser::load_str(&area, "moving-light.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &BuildOptions::default()).err().expect("animated area light refused");
    assert!(e.to_string().contains("animated area lights") && e.to_string().contains("moving-light.pbrt"), "{e}");
    // A moving point light is used at its start, with pbrt-v4's warning.
    let light = slab_scene("", "", 1.0).replace(
        "LightSource \"infinite\"",
        "AttributeBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\nLightSource \"point\" \"rgb I\" [ 1 1 1 ]\nAttributeEnd\nLightSource \"infinite\"",
    );
    let scene = load_scene(&light, &BuildOptions::default());
    assert!(scene.warnings.iter().any(|w| w.message.contains("Animated lights")), "{:?}", scene.warnings);
    // The radiance graph is built for a static scene.
    let scene = load_scene(
        &slab_scene("", MOVING, 1.0),
        &BuildOptions { integrator: Some("radiancegraph".into()), ..Default::default() },
    );
    let e = scene.integrator.create(&scene).err().expect("radiancegraph refuses motion");
    assert!(e.to_string().contains("static scene"), "{e}");
}
