//! Coverage of pbrt-v4's scene format: every entity type pbrt-v4 has, in a small scene of its
//! own, is either rendered, refused with an error that names it and its place, or replaced
//! with a warning that names it — never silently something else. `nimbus check` and scene
//! building agree on each, and the README's table lists each in the column it falls in.

use nimbus::scene::BuildOptions;
use nimbus::setup::check_scene;

/// What nimbus does with an entity type.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Outcome {
    /// Built without a warning that names it.
    Rendered,
    /// Refused: an error at the entity's line naming it.
    Refused,
    /// Built with a warning naming it (a stated replacement).
    Replaced,
}
use Outcome::*;

/// A small scene around one entity: `body` goes where the entity's directive belongs.
fn scene(kind: &str, name: &str) -> (String, &'static str) {
    let world = "WorldBegin\nLightSource \"distant\" \"rgb L\" [1 1 1]\n";
    let sphere = "Shape \"sphere\"";
    let header = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n";
    let text = match kind {
        "shape" => {
            let params = match name {
                "trianglemesh" => r#""integer indices" [0 1 2] "point3 P" [0 0 0 1 0 0 0 1 0]"#,
                "bilinearmesh" => r#""integer indices" [0 1 2 3] "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0]"#,
                "loopsubdiv" => r#""integer indices" [0 1 2] "point3 P" [0 0 0 1 0 0 0 1 0]"#,
                "curve" => r#""point3 P" [0 0 0 1 0 0 1 1 0 0 1 0]"#,
                _ => "",
            };
            format!("{header}{world}Shape \"{name}\" {params}\n")
        }
        "camera" => {
            let params = if name == "realistic" { r#""string lensfile" "lens.dat""# } else { "" };
            format!("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"{name}\" {params}\n{world}{sphere}\n")
        }
        "light" => {
            let params = match name {
                "goniometric" | "projection" => r#""string filename" "light.exr""#,
                _ => "",
            };
            format!("{header}WorldBegin\nLightSource \"{name}\" {params}\n{sphere}\n")
        }
        "area light" => format!("{header}WorldBegin\nAreaLightSource \"{name}\" \"rgb L\" [1 1 1]\n{sphere}\n"),
        "material" => {
            let params = match name {
                "mix" => r#""string materials" ["a" "b"]"#,
                "measured" => r#""string filename" "brdf.bsdf""#,
                _ => "",
            };
            format!(
                "{header}{world}MakeNamedMaterial \"a\" \"string type\" \"diffuse\"\nMakeNamedMaterial \"b\" \"string type\" \"conductor\"\nMaterial \"{name}\" {params}\n{sphere}\n"
            )
        }
        "texture" => {
            let params = match name {
                "imagemap" => r#""string filename" "tex.exr""#,
                "ptex" => r#""string filename" "tex.ptx""#,
                "directionmix" => r#""vector3 dir" [0 1 0]"#,
                _ => "",
            };
            if name == "marble" {
                format!(
                    "{header}{world}Texture \"t\" \"spectrum\" \"{name}\" {params}\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\n{sphere}\n"
                )
            } else {
                format!(
                    "{header}{world}Texture \"t\" \"float\" \"{name}\" {params}\nMaterial \"coateddiffuse\" \"texture roughness\" \"t\"\n{sphere}\n"
                )
            }
        }
        "medium" => {
            let params = match name {
                "uniformgrid" => r#""float density" [1]"#,
                "rgbgrid" => r#""rgb sigma_a" [1 1 1] "rgb sigma_s" [1 1 1]"#,
                "nanovdb" => r#""string filename" "cloud.nvdb""#,
                _ => "",
            };
            format!(
                "{header}{world}MakeNamedMedium \"m\" \"string type\" \"{name}\" {params}\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n{sphere}\n"
            )
        }
        "sampler" => format!("{header}Sampler \"{name}\"\n{world}{sphere}\n"),
        "film" => format!("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"{name}\"\n{world}{sphere}\n"),
        "filter" => format!("{header}PixelFilter \"{name}\"\n{world}{sphere}\n"),
        "integrator" => format!("{header}Integrator \"{name}\"\n{world}{sphere}\n"),
        "accelerator" => format!("{header}Accelerator \"{name}\"\n{world}{sphere}\n"),
        other => panic!("no scene for {other}"),
    };
    // The line of the entity's own directive.
    let directive = match kind {
        "shape" => "Shape \"",
        "camera" => "Camera \"",
        "light" => "LightSource \"",
        "area light" => "AreaLightSource \"",
        "material" => "Material \"",
        "texture" => "Texture \"",
        "medium" => "MakeNamedMedium \"",
        "sampler" => "Sampler \"",
        "film" => "Film \"",
        "filter" => "PixelFilter \"",
        "integrator" => "Integrator \"",
        _ => "Accelerator \"",
    };
    (text, directive)
}

/// Every entity type of pbrt-v4 (`src/pbrt/*.cpp`'s `Create` functions) and what nimbus does.
const ENTITIES: &[(&str, &str, Outcome)] = &[
    ("shape", "sphere", Rendered),
    ("shape", "disk", Rendered),
    ("shape", "cylinder", Rendered),
    ("shape", "trianglemesh", Rendered),
    ("shape", "bilinearmesh", Rendered),
    ("shape", "loopsubdiv", Rendered),
    ("shape", "curve", Rendered),
    ("camera", "perspective", Rendered),
    ("camera", "orthographic", Rendered),
    ("camera", "realistic", Rendered),
    ("camera", "spherical", Rendered),
    ("light", "point", Rendered),
    ("light", "spot", Rendered),
    ("light", "distant", Rendered),
    ("light", "infinite", Rendered),
    ("light", "goniometric", Rendered),
    ("light", "projection", Rendered),
    ("area light", "diffuse", Rendered),
    ("material", "diffuse", Rendered),
    ("material", "conductor", Rendered),
    ("material", "dielectric", Rendered),
    ("material", "thindielectric", Rendered),
    ("material", "coateddiffuse", Rendered),
    ("material", "coatedconductor", Rendered),
    ("material", "diffusetransmission", Rendered),
    ("material", "mix", Rendered),
    ("material", "interface", Rendered),
    ("material", "subsurface", Rendered),
    ("material", "measured", Rendered),
    ("material", "hair", Rendered),
    ("texture", "constant", Rendered),
    ("texture", "scale", Rendered),
    ("texture", "mix", Rendered),
    ("texture", "checkerboard", Rendered),
    ("texture", "bilerp", Rendered),
    ("texture", "directionmix", Rendered),
    ("texture", "dots", Rendered),
    ("texture", "fbm", Rendered),
    ("texture", "wrinkled", Rendered),
    ("texture", "windy", Rendered),
    ("texture", "marble", Rendered),
    ("texture", "ptex", Rendered),
    ("medium", "homogeneous", Rendered),
    ("medium", "uniformgrid", Rendered),
    ("medium", "rgbgrid", Rendered),
    ("medium", "cloud", Rendered),
    ("sampler", "independent", Rendered),
    ("sampler", "stratified", Rendered),
    ("sampler", "sobol", Rendered),
    ("sampler", "zsobol", Rendered),
    ("sampler", "halton", Rendered),
    ("sampler", "paddedsobol", Rendered),
    ("sampler", "pmj02bn", Rendered),
    ("film", "rgb", Rendered),
    ("film", "gbuffer", Rendered),
    ("film", "spectral", Rendered),
    ("filter", "box", Rendered),
    ("filter", "gaussian", Rendered),
    ("filter", "mitchell", Rendered),
    ("filter", "sinc", Rendered),
    ("filter", "triangle", Rendered),
    ("integrator", "volpath", Rendered),
    ("integrator", "simplevolpath", Rendered),
    ("integrator", "path", Replaced),
    ("integrator", "simplepath", Replaced),
    ("integrator", "randomwalk", Replaced),
    ("integrator", "bdpt", Refused),
    ("integrator", "mlt", Refused),
    ("integrator", "sppm", Refused),
    ("integrator", "lightpath", Refused),
    ("integrator", "ambientocclusion", Refused),
    ("integrator", "function", Refused),
    ("accelerator", "bvh", Rendered),
    ("accelerator", "kdtree", Rendered),
];

#[test]
fn every_pbrt_v4_entity_type_is_rendered_refused_or_replaced_by_name() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let opts = BuildOptions { spp: Some(1), ..Default::default() };
    let mut failures = Vec::new();
    // A measured material needs a .bsdf file: a small synthetic one.
    let dir = crate::common::scratch_dir("coverage-measured");
    let bsdf = dir.as_ref().join("brdf.bsdf");
    std::fs::write(&bsdf, nimbus::materials::measured::synthetic_bsdf(false)).unwrap();
    // A goniometric light needs a square image.
    let map = dir.as_ref().join("light.exr");
    let mut img = nimbus::imageio::Image::new(4, 4);
    img.pixels.iter_mut().for_each(|p| *p = glam::Vec3::ONE);
    nimbus::imageio::write_image(&map, &img).unwrap();
    // A realistic camera needs a lens file: a single thin glass element and a stop.
    let lens = dir.as_ref().join("lens.dat");
    std::fs::write(&lens, "50 3 1.5 20\n-50 5 1 20\n0 40 0 10\n").unwrap();
    for &(kind, name, expected) in ENTITIES {
        let (text, directive) = scene(kind, name);
        let text = text.replace("\"lens.dat\"", &format!("\"{}\"", lens.display()));
        let text = text.replace("\"brdf.bsdf\"", &format!("\"{}\"", bsdf.display()));
        let text = text.replace("\"light.exr\"", &format!("\"{}\"", map.display()));
        let ptex = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/ptex/grid-rgb8.ptx");
        let text = text.replace("\"tex.ptx\"", &format!("\"{ptex}\""));
        let line = text.lines().position(|l| l.starts_with(directive)).expect("the directive") + 1;
        let at = format!("coverage.pbrt:{line}:");
        let desc = match nimbus::parser::load_str(&text, "coverage.pbrt") {
            Ok(d) => d,
            Err(e) => {
                failures.push(format!("{kind} \"{name}\": does not parse: {e}"));
                continue;
            }
        };
        let built = nimbus::setup::build(&desc, &opts);
        let checked = check_scene(&desc);
        let named = |m: &str| m.contains(&format!("\"{name}\""));
        let outcome = match (&built, &checked) {
            (Err(e), Err(c)) => {
                let (e, c) = (e.to_string(), c.to_string());
                if !(named(&e) && e.contains(&at)) {
                    failures.push(format!("{kind} \"{name}\": error does not name it at {at}: {e}"));
                }
                if c != e {
                    // check may stop at the same problem with other words, but at the place.
                    if !c.contains(&at) {
                        failures.push(format!("{kind} \"{name}\": check and build disagree: {c} / {e}"));
                    }
                }
                Refused
            }
            (Ok(scene), Ok(check)) => {
                let warned = scene.warnings.iter().any(|w| named(&w.message));
                let check_warned = check.warnings.iter().any(|w| named(&w.message));
                if warned != check_warned {
                    failures.push(format!("{kind} \"{name}\": check and build disagree on the warning"));
                }
                if warned { Replaced } else { Rendered }
            }
            (Err(e), Ok(_)) => {
                failures.push(format!("{kind} \"{name}\": check passes what build refuses: {e}"));
                Refused
            }
            (Ok(_), Err(c)) => {
                failures.push(format!("{kind} \"{name}\": check refuses what build renders: {c}"));
                Rendered
            }
        };
        if outcome != expected {
            failures.push(format!("{kind} \"{name}\": expected {expected:?}, got {outcome:?}"));
        }
        // The README's table names it in the row of its kind.
        let row_name = match kind {
            "area light" => "lights",
            "medium" => "media",
            "film" | "filter" => "films, filters",
            "accelerator" => "accelerators",
            k => &format!("{k}s"),
        };
        let row = readme.lines().find(|l| l.starts_with(&format!("| {row_name} |")));
        match row {
            Some(row) if row.contains(&format!("`{name}`")) => {}
            _ => failures.push(format!("{kind} \"{name}\" is missing from the README's table")),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Every directive of pbrt-v4's format in one scene (with `Include` and `Import` of files
/// beside it) is read and built.
#[test]
fn every_directive_is_read() {
    let dir = crate::common::scratch_dir("coverage-directives");
    std::fs::write(dir.as_ref().join("inc.pbrt"), "Material \"diffuse\" \"rgb reflectance\" [0.2 0.3 0.4]\n").unwrap();
    std::fs::write(dir.as_ref().join("imp.pbrt"), "Shape \"disk\" \"float radius\" 0.5\n").unwrap();
    let text = r#"Option "bool disablepixeljitter" false
ColorSpace "srgb"
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Sampler "zsobol" "integer pixelsamples" 1
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
PixelFilter "gaussian"
Integrator "volpath" "integer maxdepth" 3
Accelerator "bvh"
TransformTimes 0 1
MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [0.1 0.1 0.1] "rgb sigma_s" [0.1 0.1 0.1]
WorldBegin
Attribute "shape" "float radius" 0.25
LightSource "point" "rgb I" [1 1 1]
Texture "checks" "spectrum" "checkerboard"
MakeNamedMaterial "named" "string type" "diffuse" "texture reflectance" "checks"
AttributeBegin
  Identity
  Translate 0 0 1
  Scale 1 1 1
  Rotate 10 0 1 0
  Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]
  ConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]
  CoordinateSystem "here"
  ActiveTransform All
  ReverseOrientation
  Include "inc.pbrt"
  Shape "sphere"
AttributeEnd
AttributeBegin
  ActiveTransform StartTime
  Translate -0.5 0 0
  ActiveTransform EndTime
  Translate 0.5 0 0
  ActiveTransform All
  Shape "sphere" "float radius" 0.1
AttributeEnd
AttributeBegin
  CoordSysTransform "here"
  NamedMaterial "named"
  Import "imp.pbrt"
  MediumInterface "fog" ""
  Material "interface"
  AreaLightSource "diffuse" "rgb L" [0.5 0.5 0.5]
  Shape "cylinder" "float radius" 0.2
AttributeEnd
ObjectBegin "thing"
  Shape "sphere" "float radius" 0.1
ObjectEnd
ObjectInstance "thing"
"#;
    let path = dir.as_ref().join("all.pbrt");
    std::fs::write(&path, text).unwrap();
    let desc = nimbus::parser::load_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let scene = nimbus::setup::build(&desc, &BuildOptions { spp: Some(1), ..Default::default() })
        .unwrap_or_else(|e| panic!("{e}"));
    check_scene(&desc).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.surfaces.top.is_some() && !scene.media.is_empty());
}
