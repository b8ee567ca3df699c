//! Degenerate scenes, every integrator: each renders the exact answer or refuses naming the
//! documented constraint the scene breaks — never a panic, a NaN, a hang, or a refusal the
//! case does not expect.

use nimbus::integrators::INTEGRATOR_NAMES;
use nimbus::scene::BuildOptions;

/// The radiance graph's documented constraints (its README, thesis Sec. 4.8), as its
/// refusals name them.
const NO_MEDIUM: &str = "one medium (the scene has none)";
const BOUNDED: &str = "a medium bounded by `interface` surfaces (the scene has none)";
const ONE_BOUNDARY: &str = "surfaces that change the medium only as its boundary";
const NO_LIGHT: &str = "at least one light (the scene has none)";
const MILD_PHASE: &str = "a phase function with g in [−0.75, 0.95]";
const GRAY: &str = "gray coefficients";
const NON_EMISSIVE: &str = "a non-emissive medium";
const EMPTY_GRAPH: &str = "no light path scattered in the medium: the graph is empty";

/// A scene with a white sky (L = 1) unless `sky` is false, `film` pixels square, `world`
/// after WorldBegin and `header` before it.
fn scene(header: &str, film: u32, sky: bool, world: &str) -> String {
    format!(
        "{header}\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"rgb\" \"integer xresolution\" {film} \"integer yresolution\" {film}\nWorldBegin\n{}{world}\n",
        if sky { "LightSource \"infinite\" \"rgb L\" [1 1 1]\n" } else { "" }
    )
}

/// Renders `text` with `integrator` at `spp`: `Ok(image)` or the refusal's message. The
/// radiance graph gets a coarse graph (node radius 40× the default) so that it builds fast.
fn render(text: &str, integrator: &str, spp: u32) -> Result<nimbus::imageio::Image, String> {
    // `{integrator}` in the scene stands for the integrator's name (for its parameters).
    let text = &text.replace("{integrator}", integrator);
    let dir = crate::common::scratch_dir(&format!("robust-{integrator}-{spp}-{}", text.len()));
    let path = dir.as_ref().join("s.pbrt");
    std::fs::write(&path, text).unwrap();
    std::fs::write(dir.as_ref().join("s.json"), r#"{"graphBuilder": {"radiusModifier": 40.0}}"#).unwrap();
    let desc = nimbus::parser::load_file(&path).map_err(|e| e.to_string())?;
    let opts = BuildOptions {
        integrator: Some(integrator.into()),
        spp: Some(spp),
        seed: Some(5),
        scene_file: Some(path.clone()),
        ..Default::default()
    };
    let scene = nimbus::setup::build(&desc, &opts).map_err(|e| e.to_string())?;
    let i = scene.integrator.create(&scene)?;
    let options = nimbus::render::RenderOptions { time_budget: None, quiet: true };
    Ok(nimbus::render::render(&scene, i.as_ref(), &options).image)
}

/// What a render must show.
#[derive(Clone, Copy)]
enum Expect {
    /// Every pixel this value.
    All(f32),
    /// The four corner pixels this value (they see past the scene's middle).
    Corners(f32),
    /// Finite pixels, some of them lit.
    Lit,
}

/// Every integrator on `text`: finite pixels showing `expected`, or, for the integrators
/// `refusals` names, a refusal naming every constraint listed for it. An integrator not
/// named must render; one named must refuse.
fn check(what: &str, text: &str, spp: u32, expected: Expect, refusals: &[(&str, &[&str])]) {
    for integrator in INTEGRATOR_NAMES {
        let reasons = refusals.iter().find(|(name, _)| name == integrator).map(|(_, r)| *r);
        match (render(text, integrator, spp), reasons) {
            (Ok(img), None) => {
                assert!(img.pixels.iter().all(|p| p.is_finite()), "{what}/{integrator}: non-finite pixels");
                let (w, h) = (img.width - 1, img.height - 1);
                let (pixels, v): (Vec<_>, f32) = match expected {
                    Expect::All(v) => (img.pixels.clone(), v),
                    Expect::Corners(v) => ([(0, 0), (w, 0), (0, h), (w, h)].map(|(x, y)| img.get(x, y)).to_vec(), v),
                    Expect::Lit => {
                        assert!(img.pixels.iter().any(|p| p.max_element() > 0.0), "{what}/{integrator}: black");
                        continue;
                    }
                };
                let worst = pixels.iter().map(|p| (*p - v).abs().max_element()).fold(0.0, f32::max);
                assert!(worst < 1e-4, "{what}/{integrator}: a pixel is {worst} away from {v}");
            }
            (Ok(_), Some(reasons)) => panic!("{what}/{integrator}: rendered a scene that breaks {reasons:?}"),
            (Err(e), None) => panic!("{what}/{integrator}: refused a scene it supports: {e}"),
            (Err(e), Some(reasons)) => {
                for reason in reasons {
                    assert!(e.contains(reason), "{what}/{integrator}: the refusal does not name {reason:?}: {e}");
                }
            }
        }
    }
}

#[test]
fn degenerate_scenes_render_exactly_or_refuse() {
    let sphere_medium = |density: &str| {
        format!(
            "MakeNamedMedium \"m\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"integer ny\" 2 \"integer nz\" 2 \
             \"float density\" [{density}] \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [1 1 1]"
        )
    };
    let boundary = "AttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1\nAttributeEnd";
    // Nothing at all: black.
    check("empty world", &scene("", 8, false, ""), 2, Expect::All(0.0), &[("radiancegraph", &[NO_MEDIUM, NO_LIGHT])]);
    // Only the sky: every pixel sees L = 1, at 1 spp too and on a 1×1 film.
    check("sky only", &scene("", 8, true, ""), 1, Expect::All(1.0), &[("radiancegraph", &[NO_MEDIUM])]);
    check("1x1 film", &scene("", 1, true, ""), 3, Expect::All(1.0), &[("radiancegraph", &[NO_MEDIUM])]);
    // A medium of zero density is not there.
    let grid = scene(&sphere_medium("0 0 0 0 0 0 0 0"), 8, true, boundary);
    check("zero-density grid", &grid, 2, Expect::All(1.0), &[("radiancegraph", &[EMPTY_GRAPH])]);
    let homogeneous =
        "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [0 0 0]";
    let empty = scene(homogeneous, 8, true, boundary);
    check("zero-density homogeneous", &empty, 2, Expect::All(1.0), &[("radiancegraph", &[EMPTY_GRAPH])]);
    // A light inside an opaque box, seen from outside: black.
    let boxed = "LightSource \"point\" \"rgb I\" [5 5 5]\nMaterial \"diffuse\"\nShape \"sphere\" \"float radius\" 1";
    let graph = [NO_MEDIUM, BOUNDED];
    check("light inside an opaque box", &scene("", 8, false, boxed), 2, Expect::All(0.0), &[("radiancegraph", &graph)]);
    // The camera inside a closed diffuse sphere, the sky outside: black.
    let enclosing = "Material \"diffuse\"\nShape \"sphere\" \"float radius\" 8";
    let graph = [NO_MEDIUM, BOUNDED];
    check("camera inside a surface", &scene("", 8, true, enclosing), 2, Expect::All(0.0), &[("radiancegraph", &graph)]);
    // A dense medium in the sky, maxdepth 0 and 1 (each integrator's own parameter): the sky
    // around it is still seen directly.
    for depth in [0, 1] {
        let header =
            format!("{}\nIntegrator \"{{integrator}}\" \"integer maxdepth\" {depth}", sphere_medium("1 2 3 4 5 6 7 8"));
        check(&format!("maxdepth {depth}"), &scene(&header, 8, true, boundary), 2, Expect::Corners(1.0), &[]);
    }
}

/// The conditions the research methods were not all built for (issue 14's matrix, tiny):
/// a medium sphere over a ground plane varying one thing at a time. Every integrator renders
/// finite, lit images; the radiance graph renders those inside its constraints (the ground
/// beside the medium among them) and refuses the others, naming each constraint a condition
/// breaks.
#[test]
fn stress_conditions_render_finite_or_refuse() {
    let base = |sa: &str, ss: &str, g: f32, le: &str, lights: &str, boundary: &str| {
        format!(
            "LookAt 0 1 4  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
             Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
             MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [{sa}] \"rgb sigma_s\" [{ss}] \"float g\" {g} {le}\n\
             WorldBegin\n{lights}\nAttributeBegin\nMediumInterface \"m\" \"\"\n{boundary}\n\
             Shape \"sphere\" \"float radius\" 0.8\nAttributeEnd\n\
             Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n\
             Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-5 -0.8 -5 5 -0.8 -5 5 -0.8 5 -5 -0.8 5]\n"
        )
    };
    let sun_sky = "LightSource \"distant\" \"point3 from\" [1 3 2] \"rgb L\" [3 3 3]\nLightSource \"infinite\" \"rgb L\" [0.2 0.3 0.5]";
    let small = "AttributeBegin\nTranslate 1.5 1.5 1\nAreaLightSource \"diffuse\" \"rgb L\" [400 400 400]\nShape \"sphere\" \"float radius\" 0.02\nAttributeEnd";
    let point = "LightSource \"point\" \"point3 from\" [0 0.3 0] \"rgb I\" [2 2 2]";
    let all = format!("{sun_sky}\n{point}");
    let iface = "Material \"interface\"";
    let (a, s) = ("0.01 0.01 0.01", "2 2 2");
    // Each condition with the constraints the radiance graph must name (none: it renders).
    let conditions: [(&str, String, &[&str]); 14] = [
        ("albedo 0.5", base("2 2 2", s, 0.0, "", sun_sky, iface), &[]),
        ("albedo 0.999", base("0.002 0.002 0.002", s, 0.0, "", sun_sky, iface), &[]),
        ("g -0.5", base(a, s, -0.5, "", sun_sky, iface), &[]),
        ("g 0.95", base(a, s, 0.95, "", sun_sky, iface), &[]),
        ("g 0.98", base(a, s, 0.98, "", sun_sky, iface), &[MILD_PHASE]),
        ("optically thin", base(a, "0.1 0.1 0.1", 0.0, "", sun_sky, iface), &[]),
        ("optically thick", base("0.1 0.1 0.1", "100 100 100", 0.0, "", sun_sky, iface), &[]),
        ("small light", base(a, s, 0.0, "", small, iface), &[]),
        ("light inside the medium", base(a, s, 0.0, "", point, iface), &[]),
        ("sun, sky and an inner light", base(a, s, 0.0, "", &all, iface), &[]),
        ("chromatic", base(a, "1 2 4", 0.0, "", sun_sky, iface), &[GRAY]),
        ("emissive", base(a, s, 0.0, "\"rgb Le\" [1 0.5 0.2]", sun_sky, iface), &[NON_EMISSIVE]),
        (
            "dielectric boundary",
            base(a, s, 0.0, "", sun_sky, "Material \"dielectric\" \"float eta\" 1.5"),
            &[ONE_BOUNDARY],
        ),
        (
            "rough boundary",
            base(a, s, 0.0, "", sun_sky, "Material \"dielectric\" \"float eta\" 1.5 \"float roughness\" 0.3"),
            &[ONE_BOUNDARY],
        ),
    ];
    for (what, text, graph) in &conditions {
        let refusals: &[(&str, &[&str])] = if graph.is_empty() { &[] } else { &[("radiancegraph", *graph)] };
        check(what, text, 2, Expect::Lit, refusals);
    }
}
