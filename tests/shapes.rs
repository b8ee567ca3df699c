//! Shapes end to end: pbrt-v4's bilinear patches are the curved surfaces they describe, for
//! camera rays and as area lights.

use nimbus::scene::BuildOptions;

use crate::common::{load_scene, render_scene};

fn channel<'a>(img: &'a nimbus::imageio::Image, name: &str) -> &'a [f32] {
    &img.channels.iter().find(|(n, _)| n == name).unwrap().1
}

/// The saddle z = x y over the unit square as one bilinear patch, seen from above by an
/// orthographic camera: the G-buffer's world positions lie on it (two triangles would put the
/// centre at z = 0.5 instead of 0.25).
#[test]
fn a_bilinear_patch_is_its_saddle_not_two_triangles() {
    let text = r#"LookAt 0.5 0.5 5  0.5 0.5 0  0 1 0
Camera "orthographic" "float screenwindow" [ -0.5 0.5 -0.5 0.5 ]
Film "gbuffer" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ] "string filename" "s.exr" "string coordinatesystem" "world"
Sampler "zsobol" "integer pixelsamples" [ 4 ]
WorldBegin
LightSource "infinite" "rgb L" [ 1 1 1 ]
Material "diffuse"
Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 1 ] "integer indices" [ 0 1 2 3 ]
"#;
    let img = render_scene(&load_scene(text, &BuildOptions::default()));
    let (px, py, pz) = (channel(&img, "P.X"), channel(&img, "P.Y"), channel(&img, "P.Z"));
    let mut worst = 0.0f32;
    // Interior pixels (the filter reaches past the patch's edge at the border). Each pixel
    // averages its samples' points; x and y jitter independently, so the mean of x y is the
    // product of the means.
    for y in 3..29 {
        for x in 3..29 {
            let i = y * 32 + x;
            worst = worst.max((pz[i] - px[i] * py[i]).abs());
        }
    }
    assert!(worst < 2e-3, "largest distance from z = x y: {worst}");
    let centre = 16 * 32 + 16;
    assert!((pz[centre] - 0.25).abs() < 0.02, "z at the centre {}", pz[centre]);
}

/// An emitting saddle lights a floor as a finely tessellated copy of it does: light sampling
/// (pbrt-v4's approximately area-uniform patch sampling, with the exact density) and its MIS
/// weights are right.
#[test]
fn an_emitting_bilinear_patch_matches_its_tessellation() {
    let header = r#"LookAt 0.5 -2.5 3  0.5 0.5 -1  0 0 1
Camera "perspective" "float fov" [ 50 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ]
Sampler "zsobol" "integer pixelsamples" [ 64 ]
Integrator "volpath" "integer maxdepth" [ 3 ]
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -3 -3 -1  4 -3 -1  4 4 -1  -3 4 -1 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 2 2 2 ] "bool twosided" true
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
"#;
    let patch = format!(
        "{header}  Shape \"bilinearmesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0  1 1 1 ] \"integer indices\" [ 0 1 2 3 ]\nAttributeEnd\n"
    );
    // 48 × 48 quads of the saddle, two triangles each.
    const N: usize = 48;
    let mut p = String::new();
    let mut idx = String::new();
    for j in 0..=N {
        for i in 0..=N {
            let (x, y) = (i as f32 / N as f32, j as f32 / N as f32);
            p += &format!("{x} {y} {} ", x * y);
        }
    }
    for j in 0..N {
        for i in 0..N {
            let a = j * (N + 1) + i;
            idx += &format!("{} {} {} {} {} {} ", a, a + 1, a + N + 2, a, a + N + 2, a + N + 1);
        }
    }
    let mesh =
        format!("{header}  Shape \"trianglemesh\" \"point3 P\" [ {p} ] \"integer indices\" [ {idx} ]\nAttributeEnd\n");
    let render =
        |text: &str, seed| render_scene(&load_scene(text, &BuildOptions { seed: Some(seed), ..Default::default() }));
    let (a1, a2) = (render(&patch, 1), render(&patch, 2));
    let (b1, b2) = (render(&mesh, 3), render(&mesh, 4));
    let n = (32 * 32) as f64;
    let mean = |x: &nimbus::imageio::Image, y: &nimbus::imageio::Image| {
        x.pixels.iter().zip(&y.pixels).map(|(p, q)| 0.5 * (p.x + q.x) as f64).sum::<f64>() / n
    };
    let var = |x: &nimbus::imageio::Image, y: &nimbus::imageio::Image| {
        x.pixels.iter().zip(&y.pixels).map(|(p, q)| (0.5 * (p.x - q.x) as f64).powi(2)).sum::<f64>() / n
    };
    let (ma, mb) = (mean(&a1, &a2), mean(&b1, &b2));
    let se = ((var(&a1, &a2) + var(&b1, &b2)) / n).sqrt();
    assert!(ma > 0.05, "the floor is lit: {ma}");
    // The tessellation differs by O(1/N²). The tolerance catches a wrong light density in
    // the MIS weights (tried: a density off by a factor varying over the patch gives +0.6 %).
    assert!((ma - mb).abs() < 4.0 * se + 5e-4 * mb, "patch {ma} vs tessellation {mb} (se {se})");
}
