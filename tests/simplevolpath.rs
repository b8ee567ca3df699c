//! `simplevolpath` (the simplified path-tracing architecture) checked against analytic answers
//! and against `volpath`: the two are different unbiased estimators of the same image.

use nimbus::imageio::Image;
use nimbus::integrators::simplevolpath::{SimpleVolPath, SimpleVolPathSettings};
use nimbus::integrators::volpath::{VolPath, VolPathSettings};
use nimbus::scene::{BuildOptions, Scene};
use nimbus::setup::Setup;

use crate::common::{
    Estimate, assert_agree, assert_channels, channel_stats, grid_values, load_scene, mean_difference, media_header,
    medium_cube, reference_scenes, render_scene, render_with, reversed_sphere_images, scratch_dir,
};

fn scene(text: &str) -> Setup {
    load_scene(text, &BuildOptions::default())
}

/// Renders with `simplevolpath` and with `volpath`, both with the scene's `maxdepth`.
fn render_both(s: &Scene, max_depth: u32) -> (Image, Image) {
    let simple = SimpleVolPath::new(&SimpleVolPathSettings { max_depth, ..Default::default() }, s);
    let volpath = VolPath::new(&VolPathSettings {
        max_depth,
        regularize: false,
        light_sampler: nimbus::integrators::volpath::LightSamplerKind::Bvh,
    });
    (render_with(s, &simple), render_with(s, &volpath))
}

/// pbrt-v4's analytic test: an emitting sphere (Le = 0.5) of albedo 0.5 seen from inside has
/// L = 0.5 + 0.5 L = 1. Here light is only found by hitting it: the mixture's luminaire
/// density samples the sphere from its own surface.
#[test]
fn emissive_sphere_gives_one_for_every_sampler() {
    let expected = 1.0 - 0.5f64.powi(31);
    for (sampler, img) in reversed_sphere_images("simplevolpath", r#"AreaLightSource "diffuse" "rgb L" [0.5 0.5 0.5]"#)
    {
        assert_channels(&img, [expected; 3], sampler);
    }
}

/// pbrt-v4's other analytic test: a point light of intensity π at the centre of a diffuse
/// sphere of albedo 0.5 gives L = 1 (through the deterministic delta-light connection).
#[test]
fn point_light_in_reversed_sphere_gives_one_for_every_sampler() {
    let light = r#"LightSource "point" "rgb I" [3.14159265 3.14159265 3.14159265]"#;
    for (sampler, img) in reversed_sphere_images("simplevolpath", light) {
        assert_channels(&img, [1.0 - 0.5f64.powi(30); 3], sampler);
    }
}

/// White furnace: a non-absorbing medium in a uniform environment of radiance L returns L:
/// media as probabilistic surfaces of albedo 1, for a homogeneous medium, a density grid and
/// a chromatic rgbgrid (σs differing per channel: spectral MIS keeps each channel exact).
#[test]
fn white_furnace_in_media_returns_the_environment() {
    let media = [
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0 0 0] "rgb sigma_s" [2 2 2] "float g" 0.4"#
            .to_string(),
        format!(
            r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 3 "integer ny" 3 "integer nz" 3 "float density" [{}]
    "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "rgb sigma_a" [0 0 0] "rgb sigma_s" [3 3 3] "float g" -0.3"#,
            (0..27).map(|k| format!("{}", 0.3 + (k % 5) as f32 * 0.2)).collect::<Vec<_>>().join(" ")
        ),
        format!(
            r#"MakeNamedMedium "m" "string type" "rgbgrid" "integer nx" 2 "integer ny" 2 "integer nz" 2
    "rgb sigma_a" [{}] "rgb sigma_s" [{}] "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "float g" 0.2"#,
            grid_values(2, "0 0 0"),
            grid_values(2, "0.5 2 4")
        ),
    ];
    for medium in media {
        let text = format!(
            "{}WorldBegin\nLightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\n{medium}\n{}\n",
            media_header("simplevolpath", 64, 200),
            medium_cube("m")
        );
        assert_channels(&render_scene(&scene(&text)), [0.5; 3], &medium);
    }
}

/// An infinite emissive medium (camera inside) is in equilibrium, L = Le, whatever σs: the
/// emission is found only where the medium is 'hit' (σa/σt·Le per hit).
#[test]
fn infinite_emissive_medium_radiance_equals_le() {
    let media = [
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [1 1 1] "rgb sigma_s" [2 2 2] "rgb Le" [0.5 0.25 0.125] "float g" 0.5"#,
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [1 0.5 2] "rgb sigma_s" [2 3 0.5] "rgb Le" [0.5 0.25 0.125] "float g" -0.2"#,
    ];
    for medium in media {
        let text =
            format!("MediumInterface \"m\" \"m\"\n{medium}\n{}WorldBegin\n", media_header("simplevolpath", 32, 400));
        assert_channels(&render_scene(&scene(&text)), [0.5, 0.25, 0.125], medium);
    }
}

/// Small scenes that exercise each density of the mixture and each kind of medium, rendered by
/// `simplevolpath` and `volpath`: the per-pixel differences average to 0 within 4σ.
#[test]
fn agrees_with_volpath_on_small_scenes() {
    let dir = scratch_dir("simplevolpath-env");
    let mut sky = Image::new(32, 32);
    for (k, p) in sky.pixels.iter_mut().enumerate() {
        let (x, y) = (k % 32, k / 32);
        *p = if (10..14).contains(&x) && (4..8).contains(&y) {
            glam::Vec3::new(60.0, 50.0, 40.0)
        } else {
            glam::Vec3::new(0.2, 0.3, 0.5) * (1.0 + y as f32 / 32.0)
        };
    }
    let sky_path = dir.join("sky.exr");
    nimbus::imageio::write_image(&sky_path, &sky).unwrap();
    let camera = |spp: u32| {
        format!(
            r#"LookAt 0 1 3.4  0 0.8 0  0 1 0
Camera "perspective" "float fov" 45
Sampler "zsobol" "integer pixelsamples" {spp}
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
WorldBegin
"#
        )
    };
    let room = r#"Material "diffuse" "rgb reflectance" [0.7 0.6 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3  4 5 6 4 6 7  8 9 10 8 10 11]
  "point3 P" [-1 0 -1  1 0 -1  1 0 1  -1 0 1   -1 2 -1  -1 2 1  1 2 1  1 2 -1   -1 0 -1  -1 2 -1  1 2 -1  1 0 -1]"#;
    let area_light = r#"AttributeBegin
  AreaLightSource "diffuse" "rgb L" [6 6 6]
  Material "diffuse" "rgb reflectance" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-0.4 1.98 -0.4  0.4 1.98 -0.4  0.4 1.98 0.4  -0.4 1.98 0.4]
AttributeEnd"#;
    let ground = r#"Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-8 -0.2 -8  8 -0.2 -8  8 -0.2 8  -8 -0.2 8]"#;
    let spheres = r#"AttributeBegin
  Translate -0.45 0.4 -0.2
  Material "conductor" "float roughness" 0.2
  Shape "sphere" "float radius" 0.35
AttributeEnd
AttributeBegin
  Translate 0.45 0.4 0.2
  Material "dielectric" "float eta" 1.5
  Shape "sphere" "float radius" 0.35
AttributeEnd"#;
    let cube = |medium: &str| {
        format!("{medium}\nAttributeBegin\nTranslate 0 0.8 0\nScale 0.6 0.6 0.6\n{}\nAttributeEnd", medium_cube("m"))
    };
    let homogeneous = cube(
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.2 0.2 0.2] "rgb sigma_s" [2 2 2] "float g" 0.5"#,
    );
    let grid = cube(&format!(
        r#"MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 3 "integer ny" 3 "integer nz" 3 "float density" [{}]
    "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "rgb sigma_a" [0.3 0.3 0.3] "rgb sigma_s" [3 3 3] "float g" -0.4"#,
        (0..27).map(|k| format!("{}", (k * 5 % 9) as f32 * 0.25)).collect::<Vec<_>>().join(" ")
    ));
    let chromatic = cube(
        r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.05 0.2 0.6] "rgb sigma_s" [3 1.5 0.6] "float g" 0.3
  "rgb Le" [0.3 0.2 0.1]"#,
    );
    let image_env = format!(r#"LightSource "infinite" "string filename" "{}""#, sky_path.display());
    let sky_and_sun = r#"LightSource "infinite" "rgb L" [0.4 0.5 0.6]
LightSource "distant" "point3 from" [1 3 2] "rgb L" [2 2 2]"#;
    let spot = r#"LightSource "spot" "point3 from" [0 1.9 0.5] "point3 to" [0 0 0] "rgb I" [5 5 5]"#;
    // (what, spp, scene): in the first, luminaire samples blocked by lit surfaces are common:
    // counting them (instead of giving them weight 0) is a bias of about 3 % that this rejects.
    let scenes: [(&str, u32, String); 6] = [
        ("surfaces, area light", 256, format!("{area_light}\n{room}\n{spheres}")),
        ("image environment", 64, format!("{image_env}\n{ground}\n{spheres}")),
        ("uniform environment and sun", 64, format!("{sky_and_sun}\n{ground}\n{spheres}")),
        ("homogeneous medium, area light", 64, format!("{area_light}\n{room}\n{homogeneous}")),
        ("grid medium, image environment", 64, format!("{image_env}\n{ground}\n{grid}")),
        ("chromatic emissive medium, spot light", 64, format!("{spot}\n{room}\n{chromatic}")),
    ];
    for (what, spp, body) in scenes {
        let s = scene(&format!("{}{body}", camera(spp)));
        let (simple, volpath) = render_both(&s, 8);
        let (md, sd) = mean_difference(&simple, &volpath);
        let (mean, _) = channel_stats(&volpath)[1];
        assert!(mean > 0.01, "{what}: the scene is lit ({mean})");
        assert!(md.abs() < 4.0 * sd, "{what}: simplevolpath − volpath = {md} ± {sd} (image mean {mean})");
    }
}

/// The RMS of the 8×8 block z-scores of the difference between two estimators, from several
/// renders each (different seeds, same spp): each block's noise is estimated from the renders'
/// spread. With n renders a side the z-scores follow about a t distribution of 2(n − 1)
/// degrees of freedom, whose RMS is 1.12 for n = 6 (with two renders, z² would have no finite
/// mean: a heavy-tailed estimator then fails by chance).
fn block_z_rms(a: &[Image], b: &[Image]) -> f64 {
    let (w, h) = (a[0].width, a[0].height);
    // Channels of a pixel are correlated: their sum is one noisy quantity.
    let block = |img: &Image, bx: usize, by: usize| -> f64 {
        (by * 8..by * 8 + 8)
            .flat_map(|y| (bx * 8..bx * 8 + 8).map(move |x| (x, y)))
            .map(|(x, y)| {
                let p = img.get(x, y);
                (p.x + p.y + p.z) as f64
            })
            .sum()
    };
    // Mean and variance of the mean over renders.
    let stats = |v: &[f64]| {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        (m, v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n)
    };
    let (mut z2, mut blocks) = (0.0, 0.0);
    for by in 0..h / 8 {
        for bx in 0..w / 8 {
            let (ma, va) = stats(&a.iter().map(|i| block(i, bx, by)).collect::<Vec<_>>());
            let (mb, vb) = stats(&b.iter().map(|i| block(i, bx, by)).collect::<Vec<_>>());
            if va + vb > 0.0 {
                z2 += (ma - mb).powi(2) / (va + vb);
                blocks += 1.0;
            }
        }
    }
    if blocks > 0.0 { (z2 / blocks).sqrt() } else { 0.0 }
}

/// Every pbrt-v4 reference scene, and the one scene of pbrt-scenes/ the suite leaves to this
/// test (`wax-small-light`, light only through glass: heavy-tailed without shadow rays until a
/// few hundred samples), at a quarter of the resolution, six seeds each: simplevolpath's and
/// volpath's image means agree within 4 standard errors (it is unbiased: no bias allowance),
/// and the block z-scores of their difference are noise. The other pbrt-scenes scenes are
/// judged against their references by `suite.rs`. (README.md in src/integrators/simplevolpath
/// has the full-resolution table.)
#[test]
fn converges_to_volpath_on_every_shipped_scene() {
    let wax = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/wax-small-light.pbrt");
    let mut scenes = reference_scenes();
    scenes.push(wax);
    assert!(scenes.len() >= 10, "{scenes:?}");
    for path in scenes {
        let desc = nimbus::parser::load_file(&path).unwrap();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        // Light reaches the wax only through refraction: without shadow rays simplevolpath finds
        // it by chance, and its noise is heavy-tailed below a few hundred samples.
        let spp = if name.starts_with("wax") { 192 } else { 48 };
        let build = |integrator: &str, seed| {
            let opts = BuildOptions {
                integrator: Some(integrator.into()),
                spp: Some(spp),
                seed: Some(seed),
                quick: true,
                ..Default::default()
            };
            render_scene(&nimbus::setup::build(&desc, &opts).unwrap())
        };
        // Six renders each: their spread is the standard error's estimate, which two renders
        // of a heavy-tailed estimator make too uncertain for a 4-SE test.
        let simple: Vec<Image> = (1..7).map(|seed| build("simplevolpath", seed)).collect();
        let volpath: Vec<Image> = (7..13).map(|seed| build("volpath", seed)).collect();
        let (se, ve) = (Estimate::from_seeds(&simple), Estimate::from_seeds(&volpath));
        assert_agree(&format!("{name}: simplevolpath against volpath"), &se, &ve, 0.0, "none: both unbiased");
        // 16 to 60 blocks of 64 pixels: about 1.1 ± 0.3 by chance.
        let z_rms = block_z_rms(&simple, &volpath);
        assert!(z_rms < 1.75, "{name}: block z-scores rms {z_rms:.2}");
    }
}

/// `--integrator simplevolpath` renders a volpath scene, keeping its `maxdepth`; bad mixture
/// weights are errors that name the parameter.
#[test]
fn selected_by_name_with_validated_parameters() {
    let text = r#"Camera "perspective"
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Integrator "volpath" "integer maxdepth" 7
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]"#;
    let desc = nimbus::parser::load_str(text, "t.pbrt").unwrap();
    let s =
        nimbus::setup::build(&desc, &BuildOptions { integrator: Some("simplevolpath".into()), ..Default::default() })
            .unwrap();
    assert_eq!(s.integrator.name(), "simplevolpath");
    let p = s.integrator.settings::<SimpleVolPathSettings>().expect("simplevolpath's settings");
    assert_eq!(p.max_depth, 7);
    assert!(nimbus::integrators::INTEGRATOR_NAMES.contains(&"simplevolpath"));
    assert_eq!(s.integrator.create(&s).unwrap().name(), "simplevolpath");
    let bad = text.replace(r#""volpath" "integer maxdepth" 7"#, r#""simplevolpath" "float envfraction" -1"#);
    let desc = nimbus::parser::load_str(&bad, "t.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &BuildOptions::default()).err().expect("a negative weight is an error");
    assert!(e.to_string().contains("envfraction"), "{e}");
}
