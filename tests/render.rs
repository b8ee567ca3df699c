//! Rendering checked against analytic answers (pbrt-v4's own integrator tests), against
//! itself (MIS vs no next-event estimation, thread counts) and against pbrt-v4.

use nimbus::imageio::Image;
use nimbus::integrators::common::PathConfig;
use nimbus::integrators::volpath::VolPath;
use nimbus::scene::BuildOptions;
use nimbus::setup::Setup;

use nimbus::lights::LightKind;
use nimbus::materials::Material;
use nimbus::textures::Tex;

use crate::common::{
    assert_channels, film_rgb, load_scene, mean_difference, reference_scenes_dir, render_scene, render_with,
    reversed_sphere_images, transport,
};

fn scene(text: &str, opts: &BuildOptions) -> Setup {
    load_scene(text, opts)
}

/// Mean of all pixels and channels, and the standard error of that mean estimated from the
/// spread of per-pixel values (pixels are independent estimates of the same quantity in
/// these scenes).
fn mean_and_stderr(img: &Image) -> (f64, f64) {
    let v: Vec<f64> = img.pixels.iter().map(|p| (p.x + p.y + p.z) as f64 / 3.0).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Renders the inside of a reversed unit sphere with diffuse albedo 0.5 and `light` with every
/// sampler, and checks each image's mean against `expected`.
fn reversed_sphere_gives(light: &str, expected: f64) {
    for (sampler, img) in reversed_sphere_images("volpath", light) {
        let (mean, se) = mean_and_stderr(&img);
        assert!((mean - expected).abs() < 4.0 * se + 1e-3, "{sampler}: mean {mean} ± {se}, expected {expected}");
    }
}

/// pbrt-v4's analytic test: inside a unit sphere with diffuse albedo 0.5 lit by a point light
/// of intensity π at its centre, every point receives E = π (direct) and the interreflections
/// sum to L = 0.5 / (1 − 0.5) = 1 (up to 0.5^maxdepth).
#[test]
fn point_light_in_reversed_sphere_gives_one_for_every_sampler() {
    reversed_sphere_gives(r#"LightSource "point" "rgb I" [3.14159265 3.14159265 3.14159265]"#, 1.0 - 0.5f64.powi(30));
}

/// pbrt-v4's second analytic test: an emitting sphere (Le = 0.5) with albedo 0.5 seen from
/// inside: L = 0.5 + 0.5 L, so L = 1.
#[test]
fn emissive_sphere_gives_one_for_every_sampler() {
    reversed_sphere_gives(r#"AreaLightSource "diffuse" "rgb L" [0.5 0.5 0.5]"#, 1.0 - 0.5f64.powi(31));
}

/// A Lambertian plane of albedo R under a distant light of radiance L at angle θ reflects
/// R·L·cos θ / π everywhere: a deterministic estimate (delta light, maxdepth 1).
#[test]
fn lambertian_plane_under_distant_light() {
    let text = r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "independent" "integer pixelsamples" 4
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "volpath" "integer maxdepth" 1
WorldBegin
LightSource "distant" "point3 from" [0 3 4] "point3 to" [0 0 0] "rgb L" [2 4 6]
Material "diffuse" "rgb reflectance" [0.5 0.25 0.75]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0]"#;
    let img = render_scene(&scene(text, &transport(false)));
    let cos = 4.0 / 5.0;
    let expected = glam::Vec3::new(0.5 * 2.0, 0.25 * 4.0, 0.75 * 6.0) * cos / std::f32::consts::PI;
    for p in &img.pixels {
        assert!((*p - expected).abs().max_element() < 1e-4, "{p:?} vs {expected:?}");
    }
    // Spectrally, the film sees R(λ)·L(λ)·cos θ/π; only the wavelengths are random.
    let s = scene(text, &transport(true));
    let LightKind::Distant { l, .. } = &s.lights[0].kind else { panic!("a distant light") };
    let Some(Material::Diffuse { reflectance: Tex::Const(r) }) = s.materials.last() else {
        panic!("a diffuse material")
    };
    let k = cos / std::f32::consts::PI;
    let expected = film_rgb(|lambda| r.sampled.eval(lambda) * l.sampled.eval(lambda) * k);
    assert_channels(&render_scene(&s), expected, "spectral Lambertian plane");
}

/// Next-event estimation with MIS and pure BSDF sampling are different unbiased estimators of
/// the same image: their means agree within their combined noise.
#[test]
fn mis_and_bsdf_sampling_only_agree() {
    let text = r#"LookAt 0 1 3.4  0 1 0  0 1 0
Camera "perspective" "float fov" 45
Sampler "sobol" "integer pixelsamples" 64
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Integrator "volpath" "integer maxdepth" 5
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4]
  Material "diffuse" "rgb reflectance" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-0.6 1.98 -0.6  0.6 1.98 -0.6  0.6 1.98 0.6  -0.6 1.98 0.6]
AttributeEnd
Material "diffuse" "rgb reflectance" [0.7 0.6 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3  4 5 6 4 6 7  8 9 10 8 10 11]
  "point3 P" [-1 0 -1  1 0 -1  1 0 1  -1 0 1   -1 2 -1  -1 2 1  1 2 1  1 2 -1   -1 0 -1  -1 2 -1  1 2 -1  1 0 -1]
Material "conductor" "float roughness" 0.3
Shape "sphere" "float radius" 0.4"#;
    let s = scene(text, &BuildOptions::default());
    let mis = render_with(&s, &VolPath::with_config(PathConfig::volpath(5, false)));
    let bsdf =
        render_with(&s, &VolPath::with_config(PathConfig { next_event: false, ..PathConfig::volpath(5, false) }));
    let (m1, e1) = mean_and_stderr(&mis);
    let (m2, e2) = mean_and_stderr(&bsdf);
    // Pixels differ in expectation here, so the per-pixel spread overstates the noise of the
    // mean; compare the per-pixel differences instead, whose expectation is zero everywhere.
    let (md, sd) = mean_difference(&mis, &bsdf);
    assert!(md.abs() < 4.0 * sd, "MIS {m1} ± {e1}, BSDF-only {m2} ± {e2}: difference {md} ± {sd}");
    assert!(m1 > 0.05, "the scene is lit: {m1}");
}

/// The same seed gives the same image at any thread count.
#[test]
fn image_does_not_depend_on_thread_count() {
    let text = r#"LookAt 0 1 3.4  0 1 0  0 1 0
Camera "perspective" "float fov" 45
Sampler "zsobol" "integer pixelsamples" 4
Film "rgb" "integer xresolution" 40 "integer yresolution" 24
WorldBegin
LightSource "infinite" "rgb L" [0.5 0.6 0.7]
Material "dielectric"
Shape "sphere" "float radius" 0.5
Material "diffuse"
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-5 -0.5 -5  5 -0.5 -5  5 -0.5 5  -5 -0.5 5]"#;
    let s = scene(text, &BuildOptions::default());
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| render_scene(&s));
    let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| render_scene(&s));
    assert_eq!(one.pixels, three.pixels);
}

/// Parity with pbrt-v4 on the surface-only reference scene and the two camera-sensor scenes
/// (a Canon sensor over the colored box, spectral; a Nikon sensor with 5000 K white balance
/// and ISO 90 over a gray cloud, RGB through the sensor), judged as the references' README
/// judges it: two seeds at 32 spp, mean within 1 %, block excess at most 1.5.
#[test]
fn surfaces_and_sensors_match_pbrt_v4() {
    let dir = reference_scenes_dir();
    for name in ["cornell-surfaces", "sensor-cornell", "sensor-grid-cloud"] {
        let desc = nimbus::parser::load_file(&dir.join(format!("{name}.pbrt"))).unwrap();
        let reference = nimbus::imageio::read_exr(&dir.join(format!("../images/{name}.exr"))).unwrap();
        let render_seed = |seed| {
            let s =
                nimbus::setup::build(&desc, &BuildOptions { spp: Some(32), seed: Some(seed), ..Default::default() })
                    .unwrap();
            render_scene(&s)
        };
        let (a, b) = (render_seed(11), render_seed(12));
        let p = nimbus::metrics::parity(&a, &b, &reference).unwrap();
        assert!(p.worst_mean_rel() < 0.01, "{name}: {p:?}");
        assert!(p.excess < 1.5, "{name}: {p:?}");
    }
}

/// On a scene where everything that scatters or absorbs is gray, RGB transport is exact, and
/// spectral transport follows exactly the same paths (both draw the same samples): pixel by
/// pixel the two differ only by the wavelength sampling of the lights' spectra, whose mean is
/// zero. Checked paired, pixel against pixel, so the bound is far tighter than either image's
/// own noise; and `auto` picks RGB here.
#[test]
fn spectral_and_rgb_agree_on_a_gray_scene() {
    let text = r#"LookAt 0 1 3.4  0 1 0  0 1 0
Camera "perspective" "float fov" 45
Sampler "zsobol" "integer pixelsamples" 16
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Integrator "volpath" "integer maxdepth" 8
WorldBegin
LightSource "distant" "point3 from" [1 4 2] "point3 to" [0 0 0] "blackbody L" 3200
LightSource "infinite" "rgb L" [0.2 0.3 0.5]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 3 2]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-0.3 1.98 -0.3  0.3 1.98 -0.3  0.3 1.98 0.3  -0.3 1.98 0.3]
AttributeEnd
MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [0.1 0.1 0.1] "rgb sigma_s" [0.6 0.6 0.6] "float g" 0.4
Material "diffuse" "rgb reflectance" [0.6 0.6 0.6]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-4 0 -4  4 0 -4  4 0 4  -4 0 4]
AttributeBegin
  Translate 0 0.6 0
  MediumInterface "fog" ""
  Material "interface"
  Shape "sphere" "float radius" 0.5
AttributeEnd
AttributeBegin
  Translate 0.8 0.3 0.4
  Material "conductor" "rgb eta" [0.2 0.2 0.2] "rgb k" [3 3 3] "float roughness" 0.2
  Shape "sphere" "float radius" 0.3
AttributeEnd"#;
    let auto = scene(text, &BuildOptions::default());
    assert_eq!(auto.transport.transport, nimbus::scene::transport::Transport::Rgb, "{}", auto.transport.reason);
    let rgb = render_scene(&scene(text, &transport(false)));
    let spectral = render_scene(&scene(text, &transport(true)));
    let n = rgb.pixels.len() as f64;
    for c in 0..3 {
        let d: Vec<f64> = spectral.pixels.iter().zip(&rgb.pixels).map(|(s, r)| (s[c] - r[c]) as f64).collect();
        let mean_d = d.iter().sum::<f64>() / n;
        let se = (d.iter().map(|x| (x - mean_d).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let mean_rgb = rgb.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        assert!(mean_d.abs() < 4.0 * se, "channel {c}: spectral − rgb = {mean_d} ± {se}");
        assert!(mean_d.abs() < 0.01 * mean_rgb, "channel {c}: spectral − rgb = {mean_d} of {mean_rgb}");
    }
}

/// An environment image of constant radiance renders like the uniform environment light of
/// that radiance (importance sampling and MIS of the image light are unbiased).
#[test]
fn constant_environment_image_matches_uniform_environment() {
    let dir = crate::common::scratch_dir("envmap");
    let mut img = Image::new(32, 32);
    for p in &mut img.pixels {
        *p = glam::Vec3::new(0.8, 0.6, 0.4);
    }
    let path = dir.join("sky.exr");
    nimbus::imageio::write_image(&path, &img).unwrap();
    let body = r#"LookAt 0 1 4  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Sampler "sobol" "integer pixelsamples" 32
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Integrator "volpath" "integer maxdepth" 4
WorldBegin
LIGHT
Material "diffuse" "rgb reflectance" [0.7 0.7 0.7]
Shape "sphere" "float radius" 1
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-5 -1 -5  5 -1 -5  5 -1 5  -5 -1 5]"#;
    let uniform =
        scene(&body.replace("LIGHT", r#"LightSource "infinite" "rgb L" [0.8 0.6 0.4]"#), &BuildOptions::default());
    let image = scene(
        &body.replace("LIGHT", &format!(r#"LightSource "infinite" "string filename" "{}""#, path.display())),
        &BuildOptions::default(),
    );
    let (a, b) = (render_scene(&uniform), render_scene(&image));
    let (md, sd) = mean_difference(&a, &b);
    assert!(md.abs() < 4.0 * sd + 1e-4, "difference {md} ± {sd}");
}

/// An unknown camera sensor is an error at its parameter, listing pbrt-v4's sensors; a known
/// one sets the imaging ratio from ISO and the shutter interval.
#[test]
fn film_sensors_are_read_with_their_parameters() {
    let film = |params: &str| {
        format!(
            "Camera \"perspective\" \"float shutterclose\" 0.5\nFilm \"rgb\" {params}\nWorldBegin\nShape \"sphere\""
        )
    };
    let desc = nimbus::parser::load_str(&film(r#""string sensor" "leica_m11""#), "s.pbrt").unwrap();
    let e =
        nimbus::setup::build(&desc, &BuildOptions::default()).err().expect("an unknown sensor is refused").to_string();
    assert!(
        e.starts_with("s.pbrt:2:12:") && e.contains("unknown sensor \"leica_m11\"") && e.contains("nikon_d850"),
        "{e}"
    );
    let s = scene(&film(r#""string sensor" "nikon_d850" "float iso" 400"#), &BuildOptions::default());
    assert_eq!(s.sensor.name(), "nikon_d850");
    assert_eq!(s.sensor.imaging_ratio(), 2.0);
}

/// An orthographic camera inside `medium` looking at an emitting wall 2 units away that fills
/// the view: every camera ray crosses exactly 2 units of medium to the light.
fn wall_through_medium(medium: &str) -> String {
    format!(
        r#"{medium}
MediumInterface "m" "m"
LookAt 0 0 0  0 0 -1  0 1 0
Camera "orthographic"
Sampler "zsobol" "integer pixelsamples" 8
Film "rgb" "integer xresolution" 24 "integer yresolution" 24
Integrator "volpath" "integer maxdepth" 8
WorldBegin
AttributeBegin
  MediumInterface "m" "m"
  AreaLightSource "diffuse" "rgb L" [1 1 1]
  Material "diffuse" "rgb reflectance" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-4 -4 -2  4 -4 -2  4 4 -2  -4 4 -2]
AttributeEnd"#
    )
}

/// `PathConfig::camera_line` estimates the light at the end of the camera line as Le times the
/// transmittance instead of by delta tracking's all-or-nothing arrival: in an absorbing
/// homogeneous medium every pixel is then exactly e^{-σa d} times the light (pbrt-v4's
/// estimator gets it right only on average), in a grid medium (ratio tracking against twice
/// the majorant) it keeps the mean with far less spread, and with scattering it agrees with
/// pbrt-v4's estimator in expectation.
#[test]
fn camera_line_estimates_lights_seen_through_media() {
    let config = |camera_line| VolPath::with_config(PathConfig { camera_line, ..PathConfig::volpath(8, false) });
    let opts = BuildOptions { seed: Some(2), ..Default::default() };
    let vacuum = render_scene(&scene(
        &wall_through_medium(
            r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0 0 0] "rgb sigma_s" [0 0 0]"#,
        ),
        &opts,
    ));
    let le = vacuum.pixels[0];
    assert!(le.min_element() > 0.5 && vacuum.pixels.iter().all(|p| *p == le), "the wall fills the view: {le}");
    let t = (-0.5f32 * 2.0).exp();

    let absorbing = scene(
        &wall_through_medium(
            r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.5 0.5 0.5] "rgb sigma_s" [0 0 0]"#,
        ),
        &opts,
    );
    let line = render_with(&absorbing, &config(true));
    let worst = line.pixels.iter().map(|p| ((*p - le * t).abs() / (le * t)).max_element()).fold(0.0, f32::max);
    assert!(worst < 1e-4, "every pixel is Le e^-1: worst relative error {worst}");
    let tracked = render_with(&absorbing, &config(false));
    let (m, se) = mean_and_stderr(&tracked);
    let want = f64::from((le * t).element_sum() / 3.0);
    assert!((m - want).abs() < 4.0 * se && se > 1e-3, "delta tracking: {m} ± {se} (Le e^-1 = {want})");

    // A grid of constant density 0.5: ratio tracking, unbiased, and a fraction of the spread
    // of arriving by independent delta tracking (whose per-pixel variance at 8 spp is
    // T (1 − T) Le² / 8). The path's own delta tracking has less than either: its first
    // collision and event come from the sampler, stratified over a pixel's samples, so about
    // 8T of a pixel's 8 paths arrive (measured: 0.0008 against the line's 0.010).
    let grid = scene(
        &wall_through_medium(
            r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 2 "integer ny" 2 "integer nz" 2
  "float density" [0.5 0.5 0.5 0.5 0.5 0.5 0.5 0.5] "rgb sigma_a" [1 1 1] "rgb sigma_s" [0 0 0]
  "point3 p0" [-5 -5 -3] "point3 p1" [5 5 1]"#,
        ),
        &opts,
    );
    let (line, tracked) = (render_with(&grid, &config(true)), render_with(&grid, &config(false)));
    let spread = |img: &Image| {
        let (m, _) = mean_and_stderr(img);
        let v: f64 = img.pixels.iter().map(|p| (f64::from(p.element_sum() / 3.0) - m).powi(2)).sum::<f64>();
        v / (img.pixels.len() - 1) as f64
    };
    let (m, se) = mean_and_stderr(&line);
    assert!((m - want).abs() < 4.0 * se.max(1e-4), "grid, camera line: {m} ± {se} (Le e^-1 = {want})");
    let independent = f64::from(t * (1.0 - t) * (le.element_sum() / 3.0).powi(2)) / 8.0;
    assert!(spread(&line) < 0.5 * independent, "variance {} against {independent}", spread(&line));
    assert!(spread(&tracked) < 0.5 * independent, "variance {} against {independent}", spread(&tracked));

    // With scattering the two estimators differ in every pixel but agree in expectation.
    let fog = scene(
        &wall_through_medium(
            r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.1 0.1 0.1] "rgb sigma_s" [0.6 0.6 0.6] "float g" 0.3"#,
        ),
        &opts,
    );
    let (a, b) = (render_with(&fog, &config(true)), render_with(&fog, &config(false)));
    let (md, sd) = mean_difference(&a, &b);
    assert!(md.abs() < 4.0 * sd, "scattering fog: camera line - delta tracking = {md} ± {sd}");
    // No variance claim here: arriving at the wall excludes scattered light, so delta
    // tracking's arrival anti-correlates with the rest of the path, Var(tracked) − Var(line) =
    // Le T (1 − T) (Le − 2 E[scattered light | scattered]) per sample, which is near zero in this
    // fog (seeds 1–7 at 8 spp, since residual ratio tracking: the line's 5 % above to 2 % below).
}
