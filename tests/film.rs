//! pbrt-v4's `gbuffer` and `spectral` films: their extra channels against scenes whose answers are known.

use nimbus::scene::BuildOptions;

use crate::common::{load_scene, render_scene};

/// A camera at the origin looking down +z at a plane z = 3 (+ `tilt` x) covering the right
/// half of the view (x > 0), a uniform sky, optionally fog of extinction `sigma` around it.
fn scene(tilt: f32, sigma: f32, system: &str) -> String {
    let fog = if sigma > 0.0 {
        format!(
            "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [{sigma} {sigma} {sigma}] \"rgb sigma_s\" [0 0 0]\nMediumInterface \"fog\" \"fog\"\n"
        )
    } else {
        String::new()
    };
    let boundary = if sigma > 0.0 {
        "AttributeBegin\n  MediumInterface \"fog\" \"\"\n  Material \"interface\"\n  Shape \"sphere\" \"float radius\" 50\nAttributeEnd\n"
    } else {
        ""
    };
    let z = |x: f32| 3.0 + tilt * x;
    format!(
        r#"{fog}LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "gbuffer" "integer xresolution" [ 32 ] "integer yresolution" [ 32 ] "string filename" "g.exr" "string coordinatesystem" "{system}"
Sampler "zsobol" "integer pixelsamples" [ 16 ]
Integrator "volpath"
WorldBegin
LightSource "infinite" "rgb L" [ 1 1 1 ]
{boundary}Material "diffuse" "rgb reflectance" [ 0.2 0.4 0.6 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ]
  "point3 P" [ 0 -5 {z0}  10 -5 {z1}  10 5 {z1}  0 5 {z0} ] "point2 uv" [ 0 0  1 0  1 1  0 1 ]
"#,
        z0 = z(0.0),
        z1 = z(10.0)
    )
}

fn channel<'a>(img: &'a nimbus::imageio::Image, name: &str) -> &'a [f32] {
    &img.channels.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no channel {name}")).1
}

/// The pixel columns looking at the plane and at the sky (the camera's +x is raster left
/// here: pbrt-v4's LookAt makes camera space left-handed).
fn plane_and_sky(img: &nimbus::imageio::Image) -> (usize, usize) {
    let p_z = channel(img, "P.Z");
    let row = 16 * img.width;
    let plane = (0..img.width).find(|&x| p_z[row + x] > 0.0).expect("the plane is seen");
    let sky = (0..img.width).find(|&x| p_z[row + x] == 0.0).expect("the sky is seen");
    (if plane < sky { 4 } else { img.width - 5 }, if plane < sky { img.width - 5 } else { 4 })
}

#[test]
fn gbuffer_channels_describe_the_visible_surface() {
    let img = render_scene(&load_scene(&scene(0.0, 0.0, "camera"), &BuildOptions::default()));
    let names: Vec<&str> = img.channels.iter().map(|(n, _)| n.as_str()).collect();
    for n in ["Albedo.R", "P.X", "dzdx", "dzdy", "N.Z", "Ns.Z", "u", "v", "Variance.G", "RelativeVariance.B"] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
    let (plane, sky) = plane_and_sky(&img);
    for y in [4, 16, 27] {
        let i = y * img.width + plane;
        // A Lambertian's albedo is its reflectance (every cosine-weighted sample gives it).
        for (c, want) in ["Albedo.R", "Albedo.G", "Albedo.B"].iter().zip([0.2, 0.4, 0.6]) {
            assert!((channel(&img, c)[i] - want).abs() < 1e-5, "{c} {}", channel(&img, c)[i]);
        }
        assert!((channel(&img, "P.Z")[i] - 3.0).abs() < 1e-4, "camera-space depth {}", channel(&img, "P.Z")[i]);
        // The plane's winding points its normal away from the camera (+z); pbrt-v4 turns the
        // normals to face the viewer (camera space: −z).
        for n in ["N", "Ns"] {
            let z = channel(&img, &format!("{n}.Z"))[i];
            assert!((z + 1.0).abs() < 1e-5, "{n} faces the camera: {z}");
        }
        assert!(channel(&img, "dzdx")[i] < 1e-5 && channel(&img, "dzdy")[i] < 1e-5, "fronto-parallel");
        assert!(channel(&img, "Variance.R")[i] > 0.0, "a diffuse plane under a sky is noisy");
        // Nothing on the sky; a constant sky has no variance.
        let j = y * img.width + sky;
        for c in ["Albedo.G", "P.Z", "N.Z", "u", "Variance.G", "RelativeVariance.G"] {
            assert_eq!(channel(&img, c)[j], 0.0, "{c} on the sky");
        }
    }
    // uv is the mesh's: u = world x / 10 on this plane, and camera x is ±world x.
    for y in [4, 16, 27] {
        let i = y * img.width + plane;
        let (u, x) = (channel(&img, "u")[i], channel(&img, "P.X")[i]);
        assert!((u - x.abs() / 10.0).abs() < 1e-4, "u {u} at x {x}");
    }
}

#[test]
fn gbuffer_depth_derivatives_follow_the_tilt_and_fog_dims_the_albedo() {
    // z = 3 + 0.5 x: the ray with x/z = s meets it at z = 3/(1 − s/2), and the next pixel's
    // ray has s + 2 tan 20°/32; pbrt-v4 scales differentials by max(1/8, 1/√spp) = 1/4 at 16 spp.
    let img = render_scene(&load_scene(&scene(0.5, 0.0, "camera"), &BuildOptions::default()));
    let (plane, _) = plane_and_sky(&img);
    let i = 16 * img.width + plane;
    let s = channel(&img, "P.X")[i].abs() as f64 / channel(&img, "P.Z")[i] as f64;
    let ds = 2.0 * (20.0f64).to_radians().tan() / 32.0;
    let expected = 0.25 * (3.0 / (1.0 - 0.5 * (s + ds)) - 3.0 / (1.0 - 0.5 * s));
    let got = channel(&img, "dzdx")[i] as f64;
    assert!((got / expected - 1.0).abs() < 0.02, "dzdx {got} vs {expected}");
    assert!((channel(&img, "dzdy")[i] as f64) < 0.1 * got, "no slope along y");
    // World coordinates: the plane's points satisfy z = 3 + 0.5 x.
    let w = render_scene(&load_scene(&scene(0.5, 0.0, "world"), &BuildOptions::default()));
    let (px, pz) = (channel(&w, "P.X")[i], channel(&w, "P.Z")[i]);
    assert!((pz - (3.0 + 0.5 * px)).abs() < 1e-3, "({px}, {pz}) on the plane");
    // Fog of extinction 0.1: pbrt-v4's albedo is averaged over all samples and only those
    // that reach the plane (probability T = e^{−0.1 d}) count, so it is T·ρ; depth is not.
    let fog = render_scene(&load_scene(&scene(0.0, 0.1, "camera"), &BuildOptions::default()));
    let (plane, _) = plane_and_sky(&fog);
    for y in [14, 16, 18] {
        let i = y * fog.width + plane;
        let p = glam::Vec3::new(channel(&fog, "P.X")[i], channel(&fog, "P.Y")[i], channel(&fog, "P.Z")[i]);
        let t = (-0.1 * p.length()).exp();
        let a = channel(&fog, "Albedo.B")[i];
        assert!((a / (0.6 * t) - 1.0).abs() < 0.01, "albedo {a} vs T·ρ {}", 0.6 * t);
        assert!((p.z - 3.0).abs() < 1e-3, "depth {}", p.z);
    }
}

#[test]
fn gbuffer_film_is_written_with_its_channels() {
    let dir = crate::common::scratch_dir("gbuffer-cli");
    let scene_path = dir.as_ref().join("g.pbrt");
    std::fs::write(&scene_path, scene(0.0, 0.0, "camera")).unwrap();
    let out = dir.as_ref().join("g.exr");
    let o =
        crate::common::nimbus(&["render", scene_path.to_str().unwrap(), "--outfile", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let channels = nimbus::imageio::read_exr_channels(&out).unwrap();
    assert_eq!(channels.len(), 22, "{:?}", channels.iter().map(|c| &c.0).collect::<Vec<_>>());
    // pbrt-v4 writes only EXR from this film.
    let png = scene(0.0, 0.0, "camera").replace("g.exr", "g.png");
    let desc = nimbus::parser::load_str(&png, "png.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &BuildOptions::default()).err().expect("png refused");
    assert!(e.to_string().contains("EXR"), "{e}");
}

/// pbrt-v4's spectral film: a light of constant spectrum seen directly reads 1 in every band
/// (pbrt-v4 normalises the light to unit luminance and the film multiplies by ∫ȳ), and a
/// surface's band values follow its reflectance spectrum.
#[test]
fn spectral_film_bands_hold_the_spectrum() {
    let text = |filename: &str| {
        format!(
            r#"LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "spectral" "integer xresolution" [ 16 ] "integer yresolution" [ 16 ] "string filename" "{filename}" "integer nbuckets" [ 8 ] "float lambdamin" [ 400 ] "float lambdamax" [ 720 ]
Sampler "zsobol" "integer pixelsamples" [ 64 ]
Integrator "volpath" "integer maxdepth" [ 1 ]
WorldBegin
LightSource "infinite" "spectrum L" [ 300 1  900 1 ]
Material "diffuse" "spectrum reflectance" [ 400 0.1  720 0.9 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ 0 -5 3  10 -5 3  10 5 3  0 5 3 ]
"#
        )
    };
    let img = render_scene(&load_scene(&text("s.exr"), &BuildOptions::default()));
    let names: Vec<&str> = img.channels.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 8, "{names:?}");
    assert_eq!(names[0], "S0.420,000nm");
    assert_eq!(names[7], "S0.700,000nm");
    assert_eq!(img.metadata.get("spectralLayoutVersion").map(String::as_str), Some("1.0"));
    // The sky: exactly 1 in every band. The plane (ρ ramps from 0.1 to 0.9 over the range)
    // under a unit sky with one bounce: its band means ρ(centre) (maxdepth 1: direct light
    // only, by MIS over the sky; noisy, so judged over a block of pixels).
    let sky_col = (0..16).find(|&x| {
        img.get(x, 8).x > 0.0 && {
            let v = channel(&img, "S0.420,000nm")[8 * 16 + x];
            (v - 1.0).abs() < 1e-5
        }
    });
    let sky_col = sky_col.expect("a pixel sees only the sky");
    for (name, values) in &img.channels {
        assert!((values[8 * 16 + sky_col] - 1.0).abs() < 1e-4, "{name}: {}", values[8 * 16 + sky_col]);
    }
    let plane_col = if sky_col < 8 { 13 } else { 2 };
    for (b, (name, values)) in img.channels.iter().enumerate() {
        let rho = 0.1 + 0.8 * (b as f32 + 0.5) / 8.0;
        let mean: f32 = (4..12).map(|y| values[y * 16 + plane_col]).sum::<f32>() / 8.0;
        assert!((mean / rho - 1.0).abs() < 0.02, "{name}: {mean} vs ρ {rho}");
    }
    // EXR only, and only with spectral transport.
    let desc = nimbus::parser::load_str(&text("s.png"), "s.pbrt").unwrap();
    assert!(nimbus::setup::build(&desc, &BuildOptions::default()).is_err());
    let desc = nimbus::parser::load_str(&text("s.exr"), "s.pbrt").unwrap();
    let off = BuildOptions { spectral: Some(nimbus::scene::transport::SpectralMode::Off), ..Default::default() };
    let e = nimbus::setup::build(&desc, &off).err().expect("spectral off refused");
    assert!(e.to_string().contains("spectral transport"), "{e}");
}
