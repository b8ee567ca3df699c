//! Light selection: pbrt-v4's light BVH against sampling by power on a scene with many lights.

use nimbus::scene::BuildOptions;

use crate::common::{load_scene, render_scene};

fn many_lights(sampler: &str) -> String {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes");
    let text = std::fs::read_to_string(dir.join("many-lights.pbrt")).unwrap();
    text.replace(
        "\"integer maxdepth\" [ 8 ]",
        &format!("\"integer maxdepth\" [ 8 ] \"string lightsampler\" \"{sampler}\""),
    )
}

/// On the 70-light street the BVH's error at equal spp is a fraction of power sampling's
/// (measured: relMSE 0.13 vs 1.35 at 16 spp, 0.025 vs 0.33 in 4 s), and both estimate the
/// same image: their means agree within the noise they measure. Errors are the mean over
/// three seeds: one render's relMSE is heavy-tailed here (the BVH's 0.10–0.28 over 18 seeds).
/// Since medium walks draw their first collision and event from the sampler, power
/// sampling's MSE is lower (three seeds: 0.0150 against 0.0186 over six before), the BVH's
/// 0.0087: the MSE margin is 1.7×, the relMSE margin 4.4×.
#[test]
fn light_bvh_beats_power_sampling_with_many_lights() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes");
    let reference = nimbus::imageio::read_exr(&dir.join("references/many-lights.exr")).unwrap();
    let render = |sampler: &str, seed| {
        let opts = BuildOptions { spp: Some(16), seed: Some(seed), ..Default::default() };
        render_scene(&load_scene(&many_lights(sampler), &opts))
    };
    let errors = |sampler: &str| {
        let e: Vec<_> =
            (1..=3).map(|seed| nimbus::metrics::error_metrics(&render(sampler, seed), &reference).unwrap()).collect();
        (e.iter().map(|e| e.rel_mse).sum::<f64>() / 3.0, e.iter().map(|e| e.mse).sum::<f64>() / 3.0)
    };
    let ((bvh_rel, bvh_mse), (power_rel, power_mse)) = (errors("bvh"), errors("power"));
    assert!(
        bvh_rel * 4.0 < power_rel && bvh_mse * 1.5 < power_mse,
        "bvh relMSE {bvh_rel} MSE {bvh_mse}, power relMSE {power_rel} MSE {power_mse}"
    );
    let power = render("power", 1);
    // Power sampling estimates the same image as the BVH's reference: the mean of two seeds
    // within 4 standard errors (from the pixels' (A − B)/2) plus 0.5 %.
    let power2 = render("power", 2);
    let n = power.pixels.len() as f64;
    for c in 0..3 {
        let m = power.pixels.iter().zip(&power2.pixels).map(|(a, b)| 0.5 * (a[c] + b[c]) as f64).sum::<f64>() / n;
        let r = reference.pixels.iter().map(|x| x[c] as f64).sum::<f64>() / n;
        let var =
            power.pixels.iter().zip(&power2.pixels).map(|(a, b)| (0.5 * (a[c] - b[c]) as f64).powi(2)).sum::<f64>() / n;
        let se = (var / n).sqrt();
        assert!((m - r).abs() < 4.0 * se + 0.005 * r, "power: channel {c}: {m} vs reference {r} (se {se})");
    }
}

/// pbrt-v4's goniometric light: without an image it warns and emits nothing (the light is
/// left out, said by name); an image that is not square is no equal-area map and is refused,
/// naming the file. (Its picture is judged against pbrt-v4 in `pbrt_v4_parity.rs`.)
#[test]
fn goniometric_lights_need_a_square_image() {
    let dir = crate::common::scratch_dir("goniometric");
    let text = |light: &str| {
        format!(
            "LookAt 0 3 6  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
             WorldBegin\nShape \"sphere\"\n{light}\n"
        )
    };
    let path = dir.join("s.pbrt");
    std::fs::write(&path, text("LightSource \"goniometric\" \"rgb I\" [1 1 1]")).unwrap();
    let desc = nimbus::parser::load_file(&path).unwrap();
    let scene = nimbus::setup::build(&desc, &BuildOptions::default()).unwrap();
    assert!(scene.lights.is_empty());
    assert!(scene.warnings.iter().any(|w| w.message.contains("goniometric")), "{:?}", scene.warnings);
    let mut img = nimbus::imageio::Image::new(4, 2);
    img.pixels.iter_mut().for_each(|p| *p = glam::Vec3::ONE);
    nimbus::imageio::write_image(&dir.join("wide.exr"), &img).unwrap();
    std::fs::write(&path, text("LightSource \"goniometric\" \"string filename\" \"wide.exr\"")).unwrap();
    let desc = nimbus::parser::load_file(&path).unwrap();
    let e = nimbus::setup::build(&desc, &BuildOptions::default()).err().expect("a 4x2 map is refused");
    assert!(e.message.contains("wide.exr") && e.message.contains("not square"), "{}", e.message);
}

/// `illuminance` on an infinite light, as pbrt-v4 applies it: a uniform `L` is divided by π
/// (the illuminance of a unit sky), an image by pbrt-v4's upper-hemisphere sum, which counts
/// 2π/N steradians per texel where each covers 4π/N: asking for E, a uniform sky shines E/π
/// and a unit image map 2E/π, twice as bright; and an OpenEXR map's channels are weighed in
/// the file's order.
#[test]
fn illuminance_scales_infinite_lights_as_pbrt_v4_does() {
    let dir = crate::common::scratch_dir("illuminance");
    let mut img = nimbus::imageio::Image::new(16, 16);
    img.pixels.iter_mut().for_each(|p| *p = glam::Vec3::ONE);
    nimbus::imageio::write_image(&dir.join("white.exr"), &img).unwrap();
    let sky = |light: &str| {
        let text = format!(
            "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nSampler \"independent\" \"integer pixelsamples\" 4\n\
             Film \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\n{light}\n"
        );
        let path = dir.join("s.pbrt");
        std::fs::write(&path, text).unwrap();
        let desc = nimbus::parser::load_file(&path).unwrap();
        let opts = crate::common::transport(false);
        let image = render_scene(&nimbus::setup::build(&desc, &opts).unwrap());
        image.pixels.iter().map(|p| p.x as f64).sum::<f64>() / image.pixels.len() as f64
    };
    let pi = std::f64::consts::PI;
    let uniform = sky("LightSource \"infinite\" \"rgb L\" [1 1 1] \"float illuminance\" 2");
    assert!((uniform - 2.0 / pi).abs() < 1e-4, "{uniform}");
    let map = sky("LightSource \"infinite\" \"string filename\" \"white.exr\" \"float illuminance\" 2");
    assert!((map - 4.0 / pi).abs() < 0.02 * 4.0 / pi, "{map}");
    // pbrt-v4 weighs an OpenEXR map's channels in the file's (alphabetical) order, B, G, R,
    // with the luminance weights of R, G, B; the light's `scale` multiplies on top.
    img.pixels.iter_mut().for_each(|p| *p = glam::Vec3::new(0.2, 0.5, 1.0));
    nimbus::imageio::write_image(&dir.join("blue.exr"), &img).unwrap();
    let blue =
        sky("LightSource \"infinite\" \"string filename\" \"blue.exr\" \"float illuminance\" 2 \"float scale\" 3");
    let k_e = pi / 2.0 * (0.2126 * 1.0 + 0.7152 * 0.5 + 0.0722 * 0.2);
    let expected = 3.0 * 0.2 * 2.0 / k_e;
    assert!((blue - expected).abs() < 0.02 * expected, "{blue} vs {expected}");
}

/// pbrt-v4's image-textured area lights: a quad whose emission image is constant renders
/// exactly as the same RGB given as `L`, lit surfaces included, with `power` and in both
/// transports; a two-texel image shows each texel on its half (v runs up the image); `L` and
/// `filename` together are refused.
#[test]
fn image_area_lights_emit_their_texels() {
    let dir = crate::common::scratch_dir("image-area-light");
    let write = |name: &str, w: usize, texels: &[[f32; 3]]| {
        let mut img = nimbus::imageio::Image::new(w, texels.len() / w);
        for (p, t) in img.pixels.iter_mut().zip(texels) {
            *p = glam::Vec3::from(*t);
        }
        nimbus::imageio::write_image(&dir.join(name), &img).unwrap();
    };
    write("flat.exr", 2, &[[0.8, 0.5, 0.2]; 4]);
    write("halves.exr", 1, &[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    let render = |emission: &str, spectral: bool| {
        let text = format!(
            "LookAt 0 0 4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
             Sampler \"zsobol\" \"integer pixelsamples\" 16\n\
             Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nWorldBegin\n\
             AttributeBegin\nAreaLightSource \"diffuse\" {emission}\n\
             Shape \"bilinearmesh\" \"point3 P\" [-1 -1 0 1 -1 0 -1 1 0 1 1 0] \"point2 uv\" [0 0 1 0 0 1 1 1]\n\
             AttributeEnd\nTranslate 0 0 -1\nMaterial \"diffuse\"\nShape \"sphere\" \"float radius\" 0.3\n"
        );
        let path = dir.join("s.pbrt");
        std::fs::write(&path, text).unwrap();
        let desc = nimbus::parser::load_file(&path).unwrap();
        let opts = crate::common::transport(spectral);
        nimbus::setup::build(&desc, &opts).map(|scene| render_scene(&scene))
    };
    // With `power`, pbrt-v4 normalises an RGB `L` by its illuminant alone but an image by its
    // texels' mean luminance too, so the image then shines 1/Y(0.8, 0.5, 0.2) times brighter.
    let y = 0.2126 * 0.8 + 0.7152 * 0.5 + 0.0722 * 0.2;
    for spectral in [false, true] {
        for (extra, ratio) in [("", 1.0), ("\"float power\" 3", 1.0 / y)] {
            let a = render(&format!("\"rgb L\" [0.8 0.5 0.2] {extra}"), spectral).unwrap();
            let b = render(&format!("\"string filename\" \"flat.exr\" {extra}"), spectral).unwrap();
            let worst =
                a.pixels.iter().zip(&b.pixels).map(|(p, q)| (*p * ratio - *q).abs().max_element()).fold(0.0, f32::max);
            // Identical paths: only the RGB→spectrum round trip of the texels (and the digits of
            // the luminance weights) may differ.
            let tolerance = if spectral { 2e-3 } else { 1e-4 };
            assert!(worst <= tolerance, "spectral {spectral} {extra}: {worst}");
        }
    }
    // The top of the quad (v near 1) shows the image's first row, the bottom its second, and
    // between the texel centres (v = 0.75 and 0.25) the two blend bilinearly.
    let img = render("\"string filename\" \"halves.exr\"", false).unwrap();
    let (top, middle, bottom) = (img.get(8, 4), img.get(8, 8) + img.get(8, 7), img.get(8, 12));
    assert!(top.x > 0.95 && top.z < 0.05 && bottom.z > 0.95 && bottom.x < 0.05, "{top} {bottom}");
    assert!((middle.x - 1.0).abs() < 0.05 && (middle.z - 1.0).abs() < 0.05, "{middle}");
    let e = render("\"string filename\" \"flat.exr\" \"rgb L\" [1 1 1]", false).expect_err("refused");
    assert!(e.message.contains("both \"L\" and \"filename\""), "{}", e.message);
}

/// pbrt-v4 stops when a projection light has no image; so does nimbus, saying so.
#[test]
fn projection_lights_need_an_image() {
    let text = "LookAt 0 3 6  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
                WorldBegin\nShape \"sphere\"\nLightSource \"projection\" \"float fov\" 30\n";
    let desc = nimbus::parser::load_str(text, "p.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &BuildOptions::default()).err().expect("refused");
    assert!(e.message.contains("projection light") && e.message.contains("filename"), "{}", e.message);
    assert!(e.to_string().contains("p.pbrt:6"), "{e}");
}

/// A closed room whose only opening is a window, under a uniform sky: every ray that leaves
/// the room leaves through the window, so the sky seen through a portal over the window
/// (pbrt-v4's portal light: `rgb L` as a 1×1 image, sampled through the window) and the plain
/// uniform sky are the same image. Their means agree within four standard errors of the
/// difference (estimated from 4 seeds each), and the portal's samples, which all go through
/// the window, are less noisy.
#[test]
fn a_portal_over_the_only_window_changes_the_noise_not_the_image() {
    let room = |portal: &str| {
        format!(
            r#"LookAt 0.3 1.3 -1.7  0 0.9 2  0 1 0
Camera "perspective" "float fov" 70
Sampler "zsobol" "integer pixelsamples" 16
Integrator "volpath" "integer maxdepth" 3
Film "rgb" "integer xresolution" 32 "integer yresolution" 24
WorldBegin
LightSource "infinite" "rgb L" [0.8 0.9 1.0] {portal}
Material "diffuse" "rgb reflectance" [0.6 0.6 0.6]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 2.5 -2  -2 2.5 2  2 2.5 2  2 2.5 -2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 0 -2  -2 2.5 -2  2 2.5 -2  2 0 -2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 0 -2  -2 0 2  -2 2.5 2  -2 2.5 -2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [2 0 -2  2 2.5 -2  2 2.5 2  2 0 2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 0 2  -0.8 0 2  -0.8 2.5 2  -2 2.5 2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [0.8 0 2  2 0 2  2 2.5 2  0.8 2.5 2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-0.8 0 2  0.8 0 2  0.8 0.8 2  -0.8 0.8 2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-0.8 1.8 2  0.8 1.8 2  0.8 2.5 2  -0.8 2.5 2]
"#
        )
    };
    let with = room(r#""point3 portal" [-0.8 0.8 2  -0.8 1.8 2  0.8 1.8 2  0.8 0.8 2]"#);
    let without = room("");
    let (a, b) = (seed_renders(&with), seed_renders(&without));
    let ((ma, va), (mb, vb)) = (mean_and_variance(&a), mean_and_variance(&b));
    assert!(ma > 0.0 && (ma - mb).abs() <= 4.0 * (va + vb).sqrt() + 1e-3 * mb, "portal {ma} ± {va}, sky {mb} ± {vb}");
    // Per-pixel noise: the spread between two seeds' images.
    let spread = |r: &[Vec<f32>]| r[0].iter().zip(&r[1]).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>();
    assert!(spread(&a) < spread(&b), "portal {} vs sky {}", spread(&a), spread(&b));
}

/// A portal light's `L` may be any spectrum: pbrt-v4 turns it into the sRGB of its XYZ for
/// the 1×1 image a portal light needs, and says so; nimbus does both, `check` as `render`.
#[test]
fn portal_lights_take_any_spectrum_with_pbrt_v4s_warning() {
    let text = r#"LookAt 0 3 6  0 0 0  0 1 0
Camera "perspective"
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Sampler "independent" "integer pixelsamples" 4
WorldBegin
LightSource "infinite" "blackbody L" [5000] "point3 portal" [-1 0 2  -1 1 2  1 1 2  1 0 2]
Shape "sphere"
"#;
    let desc = nimbus::parser::load_str(text, "s.pbrt").unwrap();
    let setup = nimbus::setup::build(&desc, &BuildOptions::default()).expect("a blackbody portal light renders");
    let warned = |w: &[nimbus::parser::Warning]| {
        w.iter().any(|w| {
            w.message.contains("Converting non-RGB \"L\" parameter to RGB") && w.to_string().starts_with("s.pbrt:6:")
        })
    };
    assert!(warned(&setup.scene.warnings), "{:?}", setup.scene.warnings);
    assert!(render_scene(&setup).mean().x > 0.0);
    nimbus::setup::check_scene(&desc).expect("check passes it too");
}

/// A portal is four corners of a rectangle: another count, or corners that are not at right
/// angles, is refused at the `portal` parameter, by `check` as by rendering.
#[test]
fn portals_must_be_rectangles() {
    let text = |portal: &str| {
        format!(
            "LookAt 0 3 6  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
             WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1] \"point3 portal\" [{portal}]\nShape \"sphere\"\n"
        )
    };
    for (portal, expected) in
        [("-1 0 2  -1 1 2  1 1 2", "4 corners"), ("-1 0 2  -1 1 2  1 1.5 2  1 0 2", "not a rectangle")]
    {
        let desc = nimbus::parser::load_str(&text(portal), "s.pbrt").unwrap();
        let e = nimbus::setup::build(&desc, &BuildOptions::default()).err().expect("refused");
        assert!(e.to_string().contains(expected) && e.to_string().contains("s.pbrt:5:"), "{e}");
        let c = nimbus::setup::check_scene(&desc).expect_err("check refuses it too");
        assert_eq!(c.to_string(), e.to_string());
    }
}

/// An area light cut by an alpha texture emits only where the texture is 1 (pbrt-v4's
/// `AlphaMasked`, in light sampling and where rays hit it): a quad emitter with a 2×2
/// checkerboard alpha lights the room as the two squares it keeps do as emitters of their own.
/// Means over 4 seeds agree within four standard errors of the difference.
#[test]
fn alpha_cut_area_lights_emit_only_where_they_are_kept() {
    let scene = |lights: &str| {
        format!(
            r#"LookAt 0 2 -3  0 0.3 0  0 1 0
Camera "perspective" "float fov" 60
Sampler "zsobol" "integer pixelsamples" 16
Integrator "volpath" "integer maxdepth" 3
Film "rgb" "integer xresolution" 32 "integer yresolution" 24
WorldBegin
Texture "half" "float" "checkerboard" "float uscale" 2 "float vscale" 2 "float tex1" 1 "float tex2" 0
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-3 0 -3  3 0 -3  3 0 3  -3 0 3]
Shape "sphere" "float radius" 0.3
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" true
  Material "diffuse" "rgb reflectance" [0 0 0]
{lights}
AttributeEnd
"#
        )
    };
    // The quad [-1, 1] × [-1, 1] at y = 1.5 with uv = ((x + 1)/2, (z + 1)/2): the checkerboard
    // keeps the squares whose ⌊2u⌋ + ⌊2v⌋ is even, x < 0 with z < 0 and x > 0 with z > 0.
    let cut = scene(
        r#"  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-1 1.5 -1  1 1.5 -1  1 1.5 1  -1 1.5 1]
    "point2 uv" [0 0  1 0  1 1  0 1] "texture alpha" "half""#,
    );
    let squares = scene(
        r#"  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-1 1.5 -1  0 1.5 -1  0 1.5 0  -1 1.5 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [0 1.5 0  1 1.5 0  1 1.5 1  0 1.5 1]"#,
    );
    let ((a, va), (b, vb)) = (mean_and_variance(&seed_renders(&cut)), mean_and_variance(&seed_renders(&squares)));
    assert!(a > 0.0 && (a - b).abs() <= 4.0 * (va + vb).sqrt() + 1e-3 * b, "cut {a} ± {va}, squares {b} ± {vb}");
}

/// pbrt-v4's invisible area light: a shape of constant alpha 0 (a value or a `constant`
/// texture) is never hit by any ray, yet its light emits unmasked and is sampled without MIS.
/// The room it lights (the light out of view) renders as with the same light visible; looking
/// at it, the camera sees through it to the black world behind.
#[test]
fn alpha_zero_area_lights_are_invisible_but_emit() {
    let scene = |camera: &str, alpha: &str| {
        format!(
            r#"{camera}
Camera "perspective" "float fov" 40
Sampler "zsobol" "integer pixelsamples" 16
Integrator "volpath" "integer maxdepth" 3
Film "rgb" "integer xresolution" 32 "integer yresolution" 24
WorldBegin
Texture "zero" "float" "constant" "float value" 0
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-3 0 -3  3 0 -3  3 0 3  -3 0 3]
Shape "sphere" "float radius" 0.3
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" true
  Material "diffuse" "rgb reflectance" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-1 1.5 -1  1 1.5 -1  1 1.5 1  -1 1.5 1] {alpha}
AttributeEnd
"#
        )
    };
    // From below the light, looking down at the floor: the light is out of view.
    let room = "LookAt 0 1.2 -2.5  0 0 0  0 1 0";
    let visible = mean_and_variance(&seed_renders(&scene(room, "")));
    for alpha in [r#""float alpha" 0"#, r#""texture alpha" "zero""#] {
        let invisible = mean_and_variance(&seed_renders(&scene(room, alpha)));
        let ((a, va), (b, vb)) = (invisible, visible);
        assert!(
            a > 0.0 && (a - b).abs() <= 4.0 * (va + vb).sqrt() + 1e-3 * b,
            "{alpha}: {a} ± {va}, visible {b} ± {vb}"
        );
    }
    // From the floor, looking up at the light's emitting side with nothing else in view.
    let up = "LookAt 0 0.5 0  0 1.5 0  0 0 1";
    let seen = |alpha: &str| render_scene(&load_scene(&scene(up, alpha), &BuildOptions::default())).mean();
    assert!(seen("")[0] > 1.0, "the visible light fills the view");
    assert_eq!(seen(r#""float alpha" 0"#).to_array(), [0.0; 3], "the invisible light is seen through");
    // simplevolpath reaches lights only by tracing towards them: it refuses such a scene.
    let setup = load_scene(
        &scene(room, r#""float alpha" 0"#),
        &BuildOptions { integrator: Some("simplevolpath".into()), ..Default::default() },
    );
    let e = setup.prepare().err().expect("refused").to_string();
    assert!(e.contains("invisible") && e.contains("volpath"), "{e}");
}

/// `text` rendered at seeds 1–4: each image's pixels as R + G + B.
fn seed_renders(text: &str) -> Vec<Vec<f32>> {
    (1..5)
        .map(|seed| {
            let img = render_scene(&load_scene(text, &BuildOptions { seed: Some(seed), ..Default::default() }));
            img.pixels.iter().map(|p| p.x + p.y + p.z).collect()
        })
        .collect()
}

/// The mean over renders of their image means, and that mean's variance estimated from their
/// spread.
fn mean_and_variance(renders: &[Vec<f32>]) -> (f64, f64) {
    let means: Vec<f64> =
        renders.iter().map(|px| px.iter().map(|&v| f64::from(v)).sum::<f64>() / px.len() as f64).collect();
    let k = means.len() as f64;
    let m = means.iter().sum::<f64>() / k;
    (m, means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (k - 1.0) / k)
}
