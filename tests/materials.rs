//! pbrt-v4's materials, shading and shapes beyond the basics, checked end to end against
//! analytic answers: `mix`, `diffusetransmission`, `coatedconductor`, `subsurface`, bump and
//! normal maps, alpha, `loopsubdiv`, `curve`.

use crate::common::{Estimate, assert_agree, assert_channels, load_scene, render_scene, transport};

/// A plane at z = 0 of `material`, seen straight down by an orthographic camera, lit by a
/// distant light of radiance (2, 4, 6) from `from`; one bounce, 16×16 pixels at `spp`.
fn lit_plane(material: &str, from: &str, spp: u32) -> String {
    format!(
        r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "independent" "integer pixelsamples" {spp}
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "volpath" "integer maxdepth" 1
WorldBegin
LightSource "distant" "point3 from" [{from}] "point3 to" [0 0 0] "rgb L" [2 4 6]
MakeNamedMaterial "black" "string type" "diffuse" "rgb reflectance" [0 0 0]
MakeNamedMaterial "tinted" "string type" "diffuse" "rgb reflectance" [0.5 0.25 0.75]
{material}
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0]"#
    )
}

/// R·L·cos θ/π per channel for the plane of [`lit_plane`] lit at cos θ = 0.8.
fn lambert(r: [f64; 3]) -> [f64; 3] {
    let k = 0.8 / std::f64::consts::PI;
    [r[0] * 2.0 * k, r[1] * 4.0 * k, r[2] * 6.0 * k]
}

/// pbrt-v4's `mix` picks the second material with probability `amount` per hit, so a mix of
/// black and a Lambertian plane reflects `amount` times the plane; 0 and 1 pick one material.
#[test]
fn mix_material_picks_its_parts_with_probability_amount() {
    let tinted = [0.5, 0.25, 0.75];
    for amount in [0.0, 0.3, 1.0] {
        let m = format!(r#"Material "mix" "string materials" ["black" "tinted"] "float amount" {amount}"#);
        let img = render_scene(&load_scene(&lit_plane(&m, "0 3 4", 64), &transport(false)));
        let expected = lambert(tinted.map(|r| r * amount));
        if amount == 0.0 || amount == 1.0 {
            for p in &img.pixels {
                let e = glam::DVec3::from(expected).as_vec3();
                assert!((*p - e).abs().max_element() < 1e-4, "amount {amount}: {p:?} vs {e:?}");
            }
        } else {
            assert_channels(&img, expected, &format!("mix with amount {amount}"));
        }
    }
}

/// Bad mixes are refused by name: a missing part, an `interface` part, a mix of itself.
#[test]
fn mix_material_refuses_bad_parts() {
    let cases = [
        (r#"Material "mix" "string materials" ["black" "nowhere"]"#, "\"nowhere\" not found"),
        (r#"Material "mix" "string materials" ["black"]"#, "two values"),
        (
            r#"MakeNamedMaterial "glassless" "string type" "interface"
Material "mix" "string materials" ["black" "glassless"]"#,
            "\"interface\" material",
        ),
        (
            r#"MakeNamedMaterial "loop" "string type" "mix" "string materials" ["black" "loop"]
NamedMaterial "loop""#,
            "contains itself",
        ),
    ];
    for (material, message) in cases {
        let desc = nimbus::parser::load_str(&lit_plane(material, "0 3 4", 1), "mix.pbrt").unwrap();
        let e = nimbus::setup::build(&desc, &transport(false)).err().expect("refused");
        let text = e.to_string();
        assert!(text.contains(message) && text.contains("mix.pbrt:"), "{material}: {text}");
    }
}

/// `diffusetransmission` reflects R·scale/π on the lit side and transmits T·scale/π to the
/// other: the plane seen from the camera above is lit from above, then from below.
#[test]
fn diffuse_transmission_reflects_r_and_transmits_t() {
    let m = r#"Material "diffusetransmission" "rgb reflectance" [0.5 0.25 0.75] "rgb transmittance" [0.1 0.6 0.3] "float scale" 0.8"#;
    for (from, r) in [("0 3 4", [0.5, 0.25, 0.75]), ("0 3 -4", [0.1, 0.6, 0.3])] {
        let img = render_scene(&load_scene(&lit_plane(m, from, 4), &transport(false)));
        let e = glam::DVec3::from(lambert(r.map(|x| x * 0.8))).as_vec3();
        for p in &img.pixels {
            assert!((*p - e).abs().max_element() < 1e-4, "light from {from}: {p:?} vs {e:?}");
        }
    }
    // pbrt-v4's defaults: R = T = 0.25.
    let img =
        render_scene(&load_scene(&lit_plane(r#"Material "diffusetransmission""#, "0 3 -4", 4), &transport(false)));
    let e = glam::DVec3::from(lambert([0.25; 3])).as_vec3();
    assert!(img.pixels.iter().all(|p| (*p - e).abs().max_element() < 1e-4), "defaults: {:?}", img.pixels[0]);
}

/// A `coatedconductor` with an index-matched (η = 1), smooth, clear coating over a smooth
/// conductor, under a uniform sky seen head-on, reflects the conductor's Fresnel term at
/// normal incidence attenuated by the clear slab both ways: F(1)·e^(−2t)·L exactly.
#[test]
fn index_matched_coated_conductor_is_a_mirror_under_a_clear_slab() {
    let (eta, k, t) = (0.2f64, 3.0f64, 0.15f64);
    let text = format!(
        r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "independent" "integer pixelsamples" 4
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "volpath" "integer maxdepth" 2
WorldBegin
LightSource "infinite" "rgb L" [1 2 3]
Material "coatedconductor" "float interface.eta" 1 "float thickness" {t}
  "rgb conductor.eta" [{eta} {eta} {eta}] "rgb conductor.k" [{k} {k} {k}]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0]"#
    );
    let img = render_scene(&load_scene(&text, &transport(false)));
    // Normal-incidence conductor Fresnel: ((η−1)² + k²) / ((η+1)² + k²).
    let f = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
    let r = (f * (-2.0 * t).exp()) as f32;
    let e = glam::Vec3::new(r, 2.0 * r, 3.0 * r);
    for p in &img.pixels {
        assert!((*p - e).abs().max_element() < 2e-4 * 3.0, "{p:?} vs {e:?}");
    }
    // "reflectance" and "conductor.eta" together are refused, as pbrt-v4 refuses them.
    let both = text.replace("\"rgb conductor.k\"", "\"rgb reflectance\" [0.5 0.5 0.5] \"rgb conductor.k\"");
    let desc = nimbus::parser::load_str(&both, "cc.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &transport(false)).err().expect("refused");
    assert!(e.to_string().contains("cannot both be given"), "{e}");
}

/// A Lambertian plane (R = (0.5, 0.25, 0.75), uv over [−10, 10]², so ∂p/∂u = (20, 0, 0)) with
/// `perturb` in its material, lit by a distant light from `from` and seen head-on: each pixel
/// is R·L·|ωl·ns|/π with the perturbed shading normal ns, exactly (one bounce).
fn perturbed_plane(perturb: &str, textures: &str, from: [f32; 3]) -> Vec<glam::Vec3> {
    let text = format!(
        r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "independent" "integer pixelsamples" 2
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Integrator "volpath" "integer maxdepth" 1
WorldBegin
LightSource "distant" "point3 from" [{} {} {}] "point3 to" [0 0 0] "rgb L" [2 4 6]
{textures}
Material "diffuse" "rgb reflectance" [0.5 0.25 0.75] {perturb}
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0]
  "point2 uv" [0 0  1 0  1 1  0 1]"#,
        from[0], from[1], from[2]
    );
    render_scene(&load_scene(&text, &transport(false))).pixels
}

fn lambert_with_normal(ns: glam::Vec3, from: [f32; 3]) -> glam::Vec3 {
    let wl = glam::Vec3::from(from).normalize();
    glam::Vec3::new(0.5 * 2.0, 0.25 * 4.0, 0.75 * 6.0) * ns.normalize().dot(wl).abs() / std::f32::consts::PI
}

/// Bump mapping by pbrt-v4's `bilerp` texture d = 10·u: the surface z = 10·u = x/2 + 5 has
/// normal (−1/2, 0, 1)/|·| (forward differences of a linear displacement are exact).
#[test]
fn bump_map_tilts_the_shading_normal_by_the_displacement_slope() {
    let ramp = r#"Texture "ramp" "float" "bilerp" "float v00" 0 "float v10" 10 "float v01" 0 "float v11" 10"#;
    for from in [[-3.0, 0.0, 4.0], [3.0, 0.0, 4.0], [0.0, 3.0, 4.0]] {
        let pixels = perturbed_plane(r#""texture displacement" "ramp""#, ramp, from);
        let e = lambert_with_normal(glam::Vec3::new(-0.5, 0.0, 1.0), from);
        for p in &pixels {
            assert!((*p - e).abs().max_element() < 2e-3 * e.max_element(), "light from {from:?}: {p:?} vs {e:?}");
        }
    }
    // A constant displacement of a plane changes nothing.
    let pixels = perturbed_plane(r#""float displacement" 0.3"#, "", [-3.0, 0.0, 4.0]);
    let e = lambert_with_normal(glam::Vec3::Z, [-3.0, 0.0, 4.0]);
    assert!(pixels.iter().all(|p| (*p - e).abs().max_element() < 1e-4), "{:?} vs {e:?}", pixels[0]);
}

/// A one-texel normal map holding (n + 1)/2 makes n the shading normal in the tangent frame
/// (∂p/∂u, ∂p/∂v, n) = (x, y, z) of the plane; a missing map is refused by name.
#[test]
fn normal_map_sets_the_shading_normal() {
    let dir = crate::common::scratch_dir("normalmap");
    let tilt = glam::Vec3::new(0.6, 0.0, 0.8);
    let mut img = nimbus::imageio::Image::new(1, 1);
    img.pixels[0] = (tilt + glam::Vec3::ONE) * 0.5;
    let path = dir.as_ref().join("tilt.exr");
    nimbus::imageio::write_image(&path, &img).unwrap();
    for from in [[3.0, 0.0, 4.0], [-3.0, 0.0, 4.0]] {
        let pixels = perturbed_plane(&format!(r#""string normalmap" "{}""#, path.display()), "", from);
        let e = lambert_with_normal(tilt, from);
        for p in &pixels {
            assert!((*p - e).abs().max_element() < 2e-3 * e.max_element(), "light from {from:?}: {p:?} vs {e:?}");
        }
    }
    let text = r#"WorldBegin
Material "diffuse" "string normalmap" "nowhere.exr"
Shape "sphere""#;
    let desc = nimbus::parser::load_str(text, "nm.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &transport(false)).err().expect("refused");
    assert!(e.to_string().contains("nm.pbrt:2") && e.to_string().contains("nowhere.exr"), "{e}");
}

/// `loopsubdiv` renders the refined limit mesh: a two-sided emitting octahedron refined four
/// times is seen head-on as its limit surface's silhouette (L = 1 inside, 0 outside, the
/// covered share of the film within a pixel row of the mesh's projected area).
#[test]
fn loop_subdivision_surfaces_render_their_limit_mesh() {
    let p =
        [[1.0f32, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    let i = [0u32, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5];
    let fmt = |v: &[String]| v.join(" ");
    let text = format!(
        r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-1 1 -1 1]
Sampler "independent" "integer pixelsamples" 16
Film "rgb" "integer xresolution" 48 "integer yresolution" 48
Integrator "volpath" "integer maxdepth" 1
WorldBegin
AreaLightSource "diffuse" "rgb L" [1 1 1] "bool twosided" true
Shape "loopsubdiv" "integer levels" 4 "integer indices" [{}] "point3 P" [{}]"#,
        fmt(&i.iter().map(|x| x.to_string()).collect::<Vec<_>>()),
        fmt(&p.iter().flatten().map(|x| x.to_string()).collect::<Vec<_>>())
    );
    let img = render_scene(&load_scene(&text, &transport(false)));
    let px = |x: usize, y: usize| img.pixels[y * 48 + x];
    assert!((px(24, 24) - glam::Vec3::ONE).abs().max_element() < 1e-5, "{:?}", px(24, 24));
    assert_eq!(px(0, 0), glam::Vec3::ZERO);
    // The limit mesh's area projected on z = 0 (its triangles' |n_z| areas, half of them
    // facing the camera).
    let sub = nimbus::geometry::loop_subdiv::loop_subdivide(&p, &i, 4).unwrap();
    let mut area = 0.0f64;
    for t in sub.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| glam::Vec3::from(sub.positions[t[k] as usize]).as_dvec3());
        area += 0.5 * (b - a).cross(c - a).z.abs();
    }
    let expected = area / 2.0 / 4.0;
    let covered = img.pixels.iter().map(|p| f64::from(p.x)).sum::<f64>() / img.pixels.len() as f64;
    // The silhouette's edge pixels are partly covered: a perimeter of at most 2π·r film
    // units is at most that many pixel widths (2/48) of error, times one half.
    assert!(
        (covered - expected).abs() < 0.5 * 2.0 * std::f64::consts::PI * (2.0 / 48.0) / 4.0 + 0.01,
        "covered {covered}, expected {expected}"
    );
    assert!(expected > 0.1 && expected < 0.5, "{expected}");
    // Its normals face out of the counter-clockwise mesh, so a medium interface (or a
    // subsurface material) puts the medium inside.
    let scene = load_scene(&text, &transport(false));
    let ray = nimbus::geometry::Ray::new(glam::Vec3::new(0.0, 0.0, 5.0), -glam::Vec3::Z);
    let hit = scene.surfaces.intersect(&ray, f32::INFINITY).expect("the surface");
    assert!(hit.surface.n.dot(ray.d) < 0.0 && hit.surface.ns.dot(ray.d) < 0.0, "{:?}", hit.surface);
}

/// `subsurface` is rendered as what its BSSRDF approximates: a dielectric boundary around a
/// homogeneous medium. The same scene written that way explicitly renders the same image,
/// sample for sample, where `maxdepth` ends no path (events inside a subsurface medium do not
/// count towards it, see `subsurface_is_one_event_for_maxdepth`); named coefficients are
/// pbrt-v4's (scaled), and the ways pbrt-v4 refuses are errors naming the place.
#[test]
fn subsurface_is_a_dielectric_around_its_medium() {
    let scene = |shape_block: &str| {
        format!(
            r#"LookAt 0 0.5 4  0 0 0  0 1 0
Camera "perspective" "float fov" 35
Sampler "zsobol" "integer pixelsamples" 8
Film "rgb" "integer xresolution" 24 "integer yresolution" 24
Integrator "volpath" "integer maxdepth" 3000
WorldBegin
LightSource "distant" "point3 from" [1 3 2] "point3 to" [0 0 0] "rgb L" [3 3 3]
LightSource "infinite" "rgb L" [0.2 0.25 0.3]
{shape_block}"#
        )
    };
    let sss = scene(
        r#"Material "subsurface" "rgb sigma_a" [0.05 0.1 0.2] "rgb sigma_s" [2 2.5 3] "float scale" 2 "float eta" 1.4 "float g" 0.3
Shape "sphere" "float radius" 0.8"#,
    );
    let explicit = scene(
        r#"MakeNamedMedium "inner" "string type" "homogeneous" "rgb sigma_a" [0.1 0.2 0.4] "rgb sigma_s" [4 5 6] "float g" 0.3
AttributeBegin
MediumInterface "inner" ""
Material "dielectric" "float eta" 1.4
Shape "sphere" "float radius" 0.8
AttributeEnd"#,
    );
    let a = render_scene(&load_scene(&sss, &transport(false)));
    let b = render_scene(&load_scene(&explicit, &transport(false)));
    let mean = |img: &nimbus::imageio::Image| img.pixels.iter().map(|p| p.x + p.y + p.z).sum::<f32>();
    assert!(mean(&a) > 0.1, "the sphere is lit");
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        assert!((*p - *q).abs().max_element() < 1e-5, "{p:?} vs {q:?}");
    }

    // Named coefficients (pbrt-v4's measured media, per mm): the medium is the preset scaled.
    let named = load_scene(
        &scene(
            r#"Material "subsurface" "string name" "Skimmilk" "float scale" 10
Shape "sphere" "float radius" 0.8"#,
        ),
        &transport(false),
    );
    let nimbus::media::MediumKind::Homogeneous { sigma_a, sigma_s, .. } = &named.media[0].kind else {
        panic!("a homogeneous medium")
    };
    // Skimmilk: σ's = (0.70, 1.22, 1.90), σa = (0.0014, 0.0025, 0.0142) per mm; g forced to 0.
    let close = |a: glam::Vec3, b: glam::Vec3| (a - b).abs().max_element() < 1e-4 * b.max_element();
    assert!(close(sigma_s.rgb, glam::Vec3::new(7.0, 12.2, 19.0)), "{:?}", sigma_s.rgb);
    assert!(close(sigma_a.rgb, glam::Vec3::new(0.014, 0.025, 0.142)), "{:?}", sigma_a.rgb);
    assert_eq!((named.media.len(), named.media[0].g), (1, 0.0));

    // A reflectance and mean free path become σt = 1/mfp and the albedo whose diffusion
    // profile reflects that much (pbrt-v4's SubsurfaceFromDiffuse): more reflectance, more
    // albedo.
    let from_r = load_scene(
        &scene(
            r#"Material "subsurface" "rgb reflectance" [0.2 0.5 0.8] "rgb mfp" [0.5 0.5 0.5] "float eta" 1.33
Shape "sphere" "float radius" 0.8"#,
        ),
        &transport(false),
    );
    let nimbus::media::MediumKind::Homogeneous { sigma_a, sigma_s, .. } = &from_r.media[0].kind else {
        panic!("a homogeneous medium")
    };
    let (a, s) = (sigma_a.rgb, sigma_s.rgb);
    assert!(((a + s) - glam::Vec3::splat(2.0)).abs().max_element() < 1e-3, "σt = 1/mfp: {a} + {s}");
    let albedo = s / (a + s);
    assert!(albedo.x < albedo.y && albedo.y < albedo.z && albedo.z < 1.0, "{albedo}");
    let table = nimbus::materials::diffusion::DiffusionTable::new(0.0, 1.33);
    for (rho, r) in [(albedo.x, 0.2), (albedo.y, 0.5), (albedo.z, 0.8)] {
        assert!((table.rho_eff(rho) - r).abs() < 0.01, "ρ {rho}: ρ_eff {} vs {r}", table.rho_eff(rho));
    }

    for (material, message) in [
        (r#"Material "subsurface" "rgb sigma_a" [1 1 1]"#, "without \"sigma_s\""),
        (r#"Material "subsurface" "string name" "Moonrock""#, "\"Moonrock\" not found"),
    ] {
        let text = scene(&format!("{material}\nShape \"sphere\""));
        let desc = nimbus::parser::load_str(&text, "sss.pbrt").unwrap();
        let e = nimbus::setup::build(&desc, &transport(false)).err().expect("refused");
        assert!(e.to_string().contains("sss.pbrt:") && e.to_string().contains(message), "{material}: {e}");
    }
}

/// pbrt-v4's BSSRDF is one scattering event, counted at the entry vertex, and nimbus's medium
/// stands for it: the events inside a subsurface medium (and at its boundary from inside) do
/// not count towards `maxdepth`. A convex subsurface sphere under a sky, which no light leaves
/// to come back, then renders the same at `maxdepth` 1 as at 64, sample for sample; the same
/// medium declared explicitly (where every event counts) is far darker at 1.
#[test]
fn subsurface_is_one_event_for_maxdepth() {
    let scene = |depth: u32, shape_block: &str| {
        format!(
            r#"LookAt 0 0.5 4  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Sampler "zsobol" "integer pixelsamples" 8
Film "rgb" "integer xresolution" 24 "integer yresolution" 24
Integrator "volpath" "integer maxdepth" {depth}
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
{shape_block}"#
        )
    };
    let sss = r#"Material "subsurface" "rgb reflectance" [0.7 0.5 0.3] "rgb mfp" [0.05 0.05 0.05]
Shape "sphere" "float radius" 0.8"#;
    let render = |text: String| render_scene(&load_scene(&text, &transport(false)));
    let (one, many) = (render(scene(1, sss)), render(scene(64, sss)));
    assert!(one.pixels == many.pixels, "maxdepth 1 and 64 differ");
    // The centre: the reflectance's colour, most of it through the medium.
    let c = one.get(12, 12);
    assert!(c.x > 0.3 && c.x > c.y && c.y > c.z, "{c:?}");
    // The same medium, explicit: one event only, the rest cut off.
    let from_r = load_scene(&scene(1, sss), &transport(false));
    let nimbus::media::MediumKind::Homogeneous { sigma_a, sigma_s, .. } = &from_r.media[0].kind else {
        panic!("a homogeneous medium")
    };
    let (a, s) = (sigma_a.rgb, sigma_s.rgb);
    let explicit = render(scene(
        1,
        &format!(
            r#"MakeNamedMedium "inner" "string type" "homogeneous" "rgb sigma_a" [{} {} {}] "rgb sigma_s" [{} {} {}]
MediumInterface "inner" ""
Material "dielectric" "float eta" 1.33
Shape "sphere" "float radius" 0.8"#,
            a.x, a.y, a.z, s.x, s.y, s.z
        ),
    ));
    let e = explicit.get(12, 12);
    assert!(e.x < 0.5 * c.x, "explicit medium at maxdepth 1: {e:?} against {c:?}");
}

/// pbrt-v4 evaluates a subsurface material's textured inputs where a path enters (its
/// BSSRDF's coefficients are the entry point's), and nimbus's medium takes them there. A
/// `constant` texture renders as the value does, sample for sample (for `reflectance`, `mfp`
/// and `sigma_a`); a sphere whose lower half has one reflectance and upper half another shows,
/// away from the seam (many diffusion lengths), what each reflectance alone gives there.
#[test]
fn subsurface_takes_textured_inputs_where_paths_enter() {
    let scene = |seed: u32, block: &str| {
        format!(
            r#"LookAt 0 0 4  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Sampler "zsobol" "integer pixelsamples" 16 "integer seed" {seed}
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
{block}
AttributeBegin
Rotate -90 1 0 0
Shape "sphere" "float radius" 0.8
AttributeEnd"#
        )
    };
    let render = |text: String| render_scene(&load_scene(&text, &transport(false)));
    let value = |r: &str| format!(r#"Material "subsurface" "rgb reflectance" [{r}] "rgb mfp" [0.01 0.01 0.01]"#);
    let (lower, upper) = ("0.5 0.2 0.1", "0.1 0.2 0.5");
    let reference = render(scene(1, &value(lower)));
    for textured in [
        format!(
            r#"Texture "r" "spectrum" "constant" "rgb value" [{lower}]
Material "subsurface" "texture reflectance" "r" "rgb mfp" [0.01 0.01 0.01]"#
        ),
        format!(
            r#"Texture "m" "spectrum" "constant" "rgb value" [0.01 0.01 0.01]
Material "subsurface" "rgb reflectance" [{lower}] "texture mfp" "m""#
        ),
    ] {
        assert!(render(scene(1, &textured)).pixels == reference.pixels, "{textured}: not the value's image");
    }
    let sigma = r#"Material "subsurface" "rgb sigma_a" [0.1 0.2 0.3] "rgb sigma_s" [20 25 30]"#;
    let sigma_textured = r#"Texture "a" "spectrum" "constant" "rgb value" [0.1 0.2 0.3]
Material "subsurface" "texture sigma_a" "a" "rgb sigma_s" [20 25 30]"#;
    assert!(render(scene(1, sigma)).pixels == render(scene(1, sigma_textured)).pixels, "textured sigma_a");

    // The halves: pbrt-v4's sphere has v = 0 at the bottom (its -z pole, here rotated to -y),
    // so a checkerboard with vscale 2 gives tex1 to the lower half.
    let checker = format!(
        r#"Texture "r" "spectrum" "checkerboard" "float vscale" 2 "rgb tex1" [{lower}] "rgb tex2" [{upper}]
Material "subsurface" "texture reflectance" "r" "rgb mfp" [0.01 0.01 0.01]"#
    );
    // Rows 5-10 and 21-26 are 0.3 to 0.65 from the equator (the sphere spans rows 4-27);
    // the diffusion length is at most 0.03 there.
    let crop = |img: &nimbus::imageio::Image, rows: std::ops::Range<usize>| {
        let mut out = nimbus::imageio::Image::new(8, rows.len());
        out.pixels = rows.flat_map(|y| (12..20).map(move |x| img.get(x, y))).collect();
        out
    };
    let seeds = 1..5u32;
    let renders = |block: &str| seeds.clone().map(|s| render(scene(s, block))).collect::<Vec<_>>();
    let (mixed, low, up) = (renders(&checker), renders(&value(lower)), renders(&value(upper)));
    for (rows, name, alone, other) in [(21..27, "lower", &low, &up), (5..11, "upper", &up, &low)] {
        let est = |imgs: &[nimbus::imageio::Image]| {
            Estimate::from_seeds(&imgs.iter().map(|i| crop(i, rows.clone())).collect::<Vec<_>>())
        };
        let (m, a, o) = (est(&mixed), est(alone), est(other));
        assert_agree(&format!("{name} half"), &m, &a, 0.0, "none: the other half's light does not reach");
        // And the test can tell the halves apart.
        assert!((a.mean[0] - o.mean[0]).abs() > 20.0 * a.se[0], "{name}: {a:?} against {o:?}");
    }
}

/// pbrt-v4's stochastic alpha test: a black plane of alpha a in front of a uniform sky lets
/// 1 − a of the camera rays through, and of the shadow rays towards a sun; alpha 0 and 1 are
/// exact, and a texture decides per point.
#[test]
fn alpha_tested_shapes_let_rays_through_with_probability_one_minus_alpha() {
    let quad = |z: f32| {
        format!(
            r#"Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-10 -10 {z}  10 -10 {z}  10 10 {z}  -10 10 {z}] "point2 uv" [0 0 1 0 1 1 0 1]"#
        )
    };
    let header = |spp: u32| {
        format!(
            r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "independent" "integer pixelsamples" {spp}
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "volpath" "integer maxdepth" 1
WorldBegin
"#
        )
    };
    // Camera rays through a black plane in front of the sky.
    for (alpha, exact) in [("0.3", false), ("0", true), ("1", true)] {
        let text = format!(
            "{}LightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\n{} \"float alpha\" {alpha}",
            header(64),
            quad(1.0)
        );
        let img = render_scene(&load_scene(&text, &transport(false)));
        let through = 1.0 - alpha.parse::<f64>().unwrap();
        if exact {
            assert!(
                img.pixels.iter().all(|p| (p.x as f64 - through).abs() < 1e-6),
                "alpha {alpha}: {:?}",
                img.pixels[0]
            );
        } else {
            assert_channels(&img, [through; 3], &format!("alpha {alpha}"));
        }
    }
    // Shadow rays: a white Lambertian floor under a sun, behind an alpha 0.5 black plane that
    // the camera also looks through: (1 − a)² of R·L·cos θ/π on average.
    let text = format!(
        "{}LightSource \"distant\" \"point3 from\" [0 3 4] \"point3 to\" [0 0 0] \"rgb L\" [1 1 1]\nAttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\n{} \"float alpha\" 0.5\nAttributeEnd\nMaterial \"diffuse\" \"rgb reflectance\" [1 1 1]\n{}",
        header(256),
        quad(1.0),
        quad(0.0)
    );
    let img = render_scene(&load_scene(&text, &transport(false)));
    let lit = 0.8 / std::f64::consts::PI;
    assert_channels(&img, [0.25 * lit; 3], "alpha-tested occluder");
    // A checkerboard alpha (u, v in 2×2 squares: alternately 0 and 1) shows the sky through
    // exactly half of the plane.
    let text = format!(
        "{}Texture \"holes\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 2 \"float tex1\" 1 \"float tex2\" 0\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\n{} \"texture alpha\" \"holes\"",
        header(4),
        quad(1.0)
    );
    let img = render_scene(&load_scene(&text, &transport(false)));
    let mean = img.pixels.iter().map(|p| f64::from(p.x)).sum::<f64>() / img.pixels.len() as f64;
    assert!((mean - 0.5).abs() < 0.05, "{mean}");
    assert!(
        img.pixels.iter().filter(|p| p.x > 0.99).count() > 64 && img.pixels.iter().filter(|p| p.x < 0.01).count() > 64
    );
}

/// `curve`: a black curve of width 0.5 across a white sky (orthographic view of [−1, 1]²)
/// hides a quarter of the film, for every curve type and basis; ribbons need their normals.
#[test]
fn curves_hide_their_width_times_their_length() {
    let scene = |shape: &str| {
        format!(
            r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "stratified" "integer xsamples" 4 "integer ysamples" 4 "bool jitter" false
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Integrator "volpath" "integer maxdepth" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "diffuse" "rgb reflectance" [0 0 0]
{shape}"#
        )
    };
    for shape in [
        r#"Shape "curve" "point3 P" [-2 0 0  -0.7 0.05 0  0.7 -0.05 0  2 0 0] "float width" 0.5"#,
        r#"Shape "curve" "string type" "cylinder" "point3 P" [-2 0 0  -0.7 0.05 0  0.7 -0.05 0  2 0 0] "float width" 0.5"#,
        r#"Shape "curve" "string type" "ribbon" "normal N" [0 0 1  0 0.2 1] "point3 P" [-2 0 0  -0.7 0.05 0  0.7 -0.05 0  2 0 0] "float width" 0.5"#,
        r#"Shape "curve" "string basis" "bspline" "point3 P" [-4 0 0  -2 0 0  0 0 0  2 0 0  4 0 0] "float width" 0.5"#,
        r#"Shape "curve" "integer degree" 2 "point3 P" [-2 0 0  -1 0 0  0 0 0  1 0 0  2 0 0] "float width0" 0.5 "float width1" 0.5"#,
    ] {
        let img = render_scene(&load_scene(&scene(shape), &transport(false)));
        let sky = img.pixels.iter().map(|p| f64::from(p.x)).sum::<f64>() / img.pixels.len() as f64;
        // Two pixel rows straddle the curve's edges (1/32 of the film each, at most).
        assert!((sky - 0.75).abs() < 2.0 / 32.0, "{shape}: sky {sky}");
        assert!(img.pixels[16 * 32 + 16].x < 1e-6 && img.pixels[0].x > 0.999, "{shape}");
    }
    for (shape, message) in [
        (r#"Shape "curve" "string type" "ribbon" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "needs 2 normals"),
        (r#"Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0]"#, "3 control points"),
        (r#"Shape "curve" "string basis" "nurbs" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0]"#, "unknown basis"),
    ] {
        let desc = nimbus::parser::load_str(&scene(shape), "curve.pbrt").unwrap();
        let e = nimbus::setup::build(&desc, &transport(false)).err().expect("refused");
        assert!(e.to_string().contains("curve.pbrt:9") && e.to_string().contains(message), "{shape}: {e}");
    }
}

/// pbrt-v4's hair BSDF in a white furnace: a non-absorbing hair fibre under a uniform sky
/// reflects exactly the sky (its BSDF conserves energy), so the whole image averages 1 within
/// its noise; with melanin it is darker and browner (blue absorbed most).
#[test]
fn hair_is_white_in_a_white_furnace_and_brown_with_melanin() {
    let scene = |material: &str| {
        format!(
            r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-1 1 -0.3 0.3]
Sampler "independent" "integer pixelsamples" 64
Film "rgb" "integer xresolution" 32 "integer yresolution" 10
Integrator "volpath" "integer maxdepth" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "hair" {material}
Shape "curve" "string type" "cylinder" "point3 P" [-2 0 0  -0.7 0 0  0.7 0 0  2 0 0] "float width" 0.4"#
        )
    };
    let white = render_scene(&load_scene(
        &scene(r#""rgb sigma_a" [0 0 0] "float beta_m" 0.4 "float beta_n" 0.4"#),
        &transport(false),
    ));
    assert_channels(&white, [1.0; 3], "white hair in a white furnace");
    let brown = render_scene(&load_scene(&scene(r#""float eumelanin" 1.3"#), &transport(false)));
    let centre = brown.pixels[5 * 32 + 16];
    assert!(centre.x < 0.9 && centre.z < centre.x, "{centre:?}");
}

/// pbrt-v4's procedural textures: `directionmix` blends by |n · dir| (exact on a plane),
/// `dots` shows only its two values, and the noise textures (`fbm`, `wrinkled`, `windy`,
/// `marble`) vary over the surface, finite, within their ranges.
#[test]
fn procedural_textures_evaluate_as_pbrt_v4_defines_them() {
    let plane = |textures: &str, material: &str| {
        let text = format!(
            r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic"
Sampler "independent" "integer pixelsamples" 1
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Integrator "volpath" "integer maxdepth" 1
WorldBegin
LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0] "rgb L" [3.14159265 3.14159265 3.14159265]
{textures}
Material {material}
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0] "point2 uv" [0 0 20 0 20 20 0 20]"#
        );
        // Lit head-on by π: each pixel is the reflectance.
        render_scene(&load_scene(&text, &transport(false))).pixels
    };
    for (dir, r) in [("0 0 1", 0.2f32), ("1 0 0", 0.8), ("0 0.6 0.8", 0.8 * 0.2 + 0.2 * 0.8)] {
        let px = plane(
            &format!(
                r#"Texture "t" "spectrum" "directionmix" "rgb tex1" [0.2 0.2 0.2] "rgb tex2" [0.8 0.8 0.8] "vector3 dir" [{dir}]"#
            ),
            r#""diffuse" "texture reflectance" "t""#,
        );
        assert!(px.iter().all(|p| (p.x - r).abs() < 1e-4), "dir {dir}: {:?} vs {r}", px[0]);
    }
    let px = plane(
        r#"Texture "t" "spectrum" "dots" "rgb inside" [0.9 0.9 0.9] "rgb outside" [0.1 0.1 0.1]"#,
        r#""diffuse" "texture reflectance" "t""#,
    );
    assert!(px.iter().all(|p| (p.x - 0.9).abs() < 1e-4 || (p.x - 0.1).abs() < 1e-4));
    // Dots (radius 0.35 in half of the unit cells) cover about a fifth of the plane, and
    // pbrt-v4 shows `outside` in them and `inside` around them (its constructor swaps the two).
    let background = px.iter().filter(|p| p.x > 0.5).count() as f32 / px.len() as f32;
    assert!((0.65..0.95).contains(&background), "{background} of the plane shows \"inside\"");
    for texture in [
        r#"Texture "t" "float" "wrinkled" "float roughness" 0.5"#,
        r#"Texture "t" "float" "windy""#,
        r#"Texture "s" "float" "fbm" Texture "t" "float" "scale" "texture tex" "s" "float scale" 0.5"#,
    ] {
        let px = plane(
            &format!(
                "{texture}\nTexture \"u\" \"spectrum\" \"mix\" \"rgb tex1\" [0 0 0] \"rgb tex2\" [1 1 1] \"texture amount\" \"t\""
            ),
            r#""diffuse" "texture reflectance" "u""#,
        );
        let (min, max) = px.iter().fold((f32::MAX, f32::MIN), |(a, b), p| (a.min(p.x), b.max(p.x)));
        assert!(px.iter().all(|p| p.is_finite()) && max > min + 0.01, "{texture}: {min}..{max}");
    }
    let px = plane(r#"Texture "t" "spectrum" "marble" "float scale" 4"#, r#""diffuse" "texture reflectance" "t""#);
    assert!(px.iter().all(|p| p.min_element() >= 0.0 && p.max_element() <= 1.0));
    assert!(px.iter().any(|p| p.z > p.x + 0.01), "marble's veins are bluish");
    let desc = nimbus::parser::load_str("WorldBegin\nTexture \"t\" \"spectrum\" \"fbm\"\n", "fbm.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &transport(false)).err().expect("refused");
    assert!(e.to_string().contains("fbm.pbrt:2") && e.to_string().contains("float texture"), "{e}");
}

/// pbrt-v4's measured BRDF (a synthetic gray `.bsdf` file): a plane lit and seen straight
/// down reflects f(z, z)·L, with f from the tables, in RGB and spectral transport alike.
#[test]
fn measured_brdf_reflects_its_tabulated_value() {
    use nimbus::materials::bxdf::{MeasuredBxdf, TransportMode};
    use nimbus::materials::measured::{MeasuredData, synthetic_bsdf};
    let dir = crate::common::scratch_dir("measured-plane");
    let path = dir.as_ref().join("gray.bsdf");
    std::fs::write(&path, synthetic_bsdf(true)).unwrap();
    let data = MeasuredData::read(&path, nimbus::parser::ColorSpace::Srgb).unwrap();
    let f = MeasuredBxdf::<glam::Vec3>::new(std::sync::Arc::new(data), &()).f(
        glam::Vec3::Z,
        glam::Vec3::Z,
        TransportMode::Radiance,
    );
    assert!(f.x > 0.0 && (f.x - f.y).abs() < 1e-3 * f.x && (f.x - f.z).abs() < 1e-3 * f.x, "gray tables: {f}");
    let material = format!("Material \"measured\" \"string filename\" \"{}\"", path.display());
    for spectral in [false, true] {
        let img = render_scene(&load_scene(&lit_plane(&material, "0 0 1", 8), &transport(spectral)));
        let expected = [f.x as f64 * 2.0, f.y as f64 * 4.0, f.z as f64 * 6.0];
        assert_channels(&img, expected, &format!("measured, spectral {spectral}"));
    }
    // A file that is not a tensor file is refused at the parameter.
    let bad = dir.as_ref().join("bad.bsdf");
    std::fs::write(&bad, b"tensor_file\0\x01\x00").unwrap();
    let text = lit_plane(&format!("Material \"measured\" \"string filename\" \"{}\"", bad.display()), "0 0 1", 1);
    let desc = nimbus::parser::load_str(&text, "m.pbrt").unwrap();
    let e = nimbus::setup::build(&desc, &Default::default()).err().expect("refused");
    assert!(e.to_string().contains("m.pbrt:") && e.to_string().contains("bad.bsdf"), "{e}");
}

/// The `ewa` filter's `maxanisotropy` must be positive (pbrt-v4 would divide by it); the
/// error names the parameter's place.
#[test]
fn ewa_max_anisotropy_must_be_positive() {
    let dir = crate::common::scratch_dir("ewa-anisotropy");
    let path = dir.as_ref().join("t.exr");
    nimbus::imageio::write_image(&path, &nimbus::imageio::Image::new(2, 2)).unwrap();
    for (v, ok) in [("0.5", true), ("0", false), ("-2", false)] {
        let text = format!(
            "WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"{}\" \"string filter\" \"ewa\" \"float maxanisotropy\" {v}\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\nShape \"sphere\"",
            path.display()
        );
        let desc = nimbus::parser::load_str(&text, "ewa.pbrt").unwrap();
        match nimbus::setup::build(&desc, &transport(false)) {
            Ok(_) => assert!(ok, "maxanisotropy {v} accepted"),
            Err(e) => {
                let e = e.to_string();
                assert!(!ok && e.contains("ewa.pbrt:2:") && e.contains("maxanisotropy"), "{v}: {e}");
            }
        }
    }
}
