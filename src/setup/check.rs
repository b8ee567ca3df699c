//! Reads every entity of a description through its settings reader without building
//! anything heavy: what `nimbus check` reports.

use std::collections::BTreeMap;

use nimbus_parser::{Entity, Error, ParameterDictionary, SceneDescription, ShapeEntity, Warning};

use crate::camera::settings::{CameraSettings, Projection};
use crate::film::filter_settings::FilterSettings;
use crate::film::settings::FilmSettings;
use crate::geometry::ply::read_ply;
use crate::integrators::IntegratorSettings;
use crate::samplers::settings::SamplerSettings;
use crate::scene::lights::{AreaLightSettings, LightSettings};
use crate::scene::materials::MaterialSettings;
use crate::scene::media::MediumSettings;
use crate::scene::shapes::{ShapeKind, ShapeSettings};
use crate::scene::textures::TextureSettings;

/// What `nimbus check` found.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCheck {
    /// Camera summary (`perspective, fov 45°`).
    pub camera: String,
    /// Film resolution.
    pub resolution: [u32; 2],
    /// Output file named by the film.
    pub filename: String,
    /// Sampler summary.
    pub sampler: String,
    /// Samples per pixel.
    pub spp: u32,
    /// Integrator name.
    pub integrator: String,
    /// The integrator's parameters as written (`maxdepth 20`).
    pub integrator_params: Vec<String>,
    /// Shapes by type (instanced object shapes included once).
    pub shapes: BTreeMap<String, usize>,
    /// Triangles in all meshes (each instanced mesh counted once; as built by `nimbus check`,
    /// displacement and subdivision included).
    pub triangles: u64,
    /// Object instances.
    pub instances: usize,
    /// Lights by type (area lights as `area (diffuse)`).
    pub lights: BTreeMap<String, usize>,
    /// Media by type.
    pub media: BTreeMap<String, usize>,
    /// Materials by type (named and anonymous that shapes use or define).
    pub materials: BTreeMap<String, usize>,
    /// Textures by class.
    pub textures: BTreeMap<String, usize>,
    /// Files read.
    pub files: Vec<String>,
    /// Everything suspicious: the parser's warnings, unsupported features that have a
    /// stand-in, and parameters nothing reads.
    pub warnings: Vec<Warning>,
}

fn unused(params: &ParameterDictionary, warnings: &mut Vec<Warning>) {
    warnings.extend(params.report_unused());
}

fn describe_param(p: &nimbus_parser::Param) -> String {
    use nimbus_parser::ParamValues::*;
    let values: Vec<String> = match &p.values {
        Ints(v) => v.iter().take(4).map(|x| x.to_string()).collect(),
        Floats(v) => v.iter().take(4).map(|x| x.to_string()).collect(),
        Strings(v) => v.iter().take(4).map(|x| format!("\"{x}\"")).collect(),
        Bools(v) => v.iter().take(4).map(|x| x.to_string()).collect(),
    };
    let more = if p.values.len() > 4 { " ..." } else { "" };
    format!("{} {}{more}", p.name, values.join(" "))
}

fn shape_triangles(shape: &ShapeEntity, settings: &ShapeSettings<'_>) -> Result<u64, Error> {
    Ok(match &settings.kind {
        ShapeKind::TriangleMesh(m) => m.indices.len() as u64 / 3,
        ShapeKind::BilinearMesh(m) => m.indices.len() as u64 / 2,
        ShapeKind::PlyMesh(path, _) => {
            let mesh = read_ply(path).map_err(|e| Error::new(&shape.entity.loc, format!("plymesh: {e}")))?;
            mesh.indices.len() as u64 / 3
        }
        _ => 0,
    })
}

/// Warnings for every parameter that no reader used, across all entities of `scene`. Call
/// after the entities were read (by [`check_scene`] or by building the scene).
pub fn unused_parameters(scene: &SceneDescription) -> Vec<Warning> {
    let mut w = Vec::new();
    let mut dicts: Vec<&ParameterDictionary> = vec![
        &scene.camera.entity.params,
        &scene.film.params,
        &scene.filter.params,
        &scene.sampler.params,
        &scene.integrator.params,
    ];
    dicts.extend(scene.shapes.iter().map(|s| &s.entity.params));
    dicts.extend(scene.instance_definitions.iter().flat_map(|d| d.shapes.iter().map(|s| &s.entity.params)));
    dicts.extend(scene.lights.iter().map(|l| &l.entity.params));
    dicts.extend(scene.area_lights.iter().map(|a| &a.params));
    dicts.extend(scene.media.iter().map(|m| &m.entity.params));
    for d in dicts {
        w.extend(d.report_unused());
    }
    // Materials and textures of types nimbus lacks were already reported as unsupported.
    for e in scene
        .materials
        .iter()
        .chain(scene.named_materials.iter().map(|m| &m.entity))
        .chain(scene.textures.iter().map(|t| &t.entity))
    {
        if e.params.iter().any(|p| p.is_used()) || e.params.is_empty() {
            w.extend(e.params.report_unused());
        }
    }
    w
}

/// Reads every entity of `scene` through its settings reader. Errors stop at the first;
/// the result lists warnings, including every parameter no reader used.
pub fn check_scene(scene: &SceneDescription) -> Result<SceneCheck, Error> {
    let mut errors = Vec::new();
    match read_all(scene, &mut errors) {
        Some(check) if errors.is_empty() => Ok(check),
        _ => Err(errors.swap_remove(0)),
    }
}

/// What `nimbus check` reports: the summary of what the readers found, and every error.
pub struct FullCheck {
    /// The summary (`None` when the camera or film could not be read).
    pub summary: Option<SceneCheck>,
    /// Every problem found. The first is the one rendering the scene stops at.
    pub errors: Vec<Error>,
}

/// Everything `nimbus render` does short of tracing rays: every entity read (every problem
/// the readers find, not only the first), then the scene built as `render` builds it for the
/// scene's method (lights, media, textures and their images, displacement, the BVH), and the
/// method's constraints on the scene checked. The first error is the build's or the method's
/// when there is one, so `check` and `render` stop at the same first error.
pub fn check_scene_full(scene: &SceneDescription, opts: &crate::scene::BuildOptions) -> FullCheck {
    let mut errors = Vec::new();
    let mut summary = read_all(scene, &mut errors);
    let first = match super::build(scene, opts) {
        Err(e) => Some(e),
        Ok(setup) => {
            // What building says besides (conversions pbrt-v4 warns of, notes).
            if let Some(summary) = &mut summary {
                // As built: displaced and subdivided meshes refined, each object once.
                summary.triangles = setup.scene.stats.triangles as u64;
                for w in setup.scene.warnings.iter() {
                    if !summary.warnings.contains(w) {
                        summary.warnings.push(w.clone());
                    }
                }
            }
            setup.integrator.check(&setup.scene).err().map(|e| super::method_error(scene, &e))
        }
    };
    if let Some(e) = first {
        errors.retain(|x| x.message != e.message || x.loc != e.loc);
        errors.insert(0, e);
    }
    FullCheck { summary, errors }
}

/// Reads every entity, pushing each error to `errors` and going on; the summary when the
/// camera and film could be read.
fn read_all(scene: &SceneDescription, errors: &mut Vec<Error>) -> Option<SceneCheck> {
    let mut warnings = scene.warnings.clone();
    let ok = |r: Result<(), Error>, errors: &mut Vec<Error>| {
        if let Err(e) = r {
            errors.push(e);
        }
    };

    let camera = CameraSettings::from_entity(&scene.camera).map_err(|e| errors.push(e)).ok();
    unused(&scene.camera.entity.params, &mut warnings);
    if let Some(camera) = &camera {
        warnings.extend(camera.aperture_warning(&scene.camera));
    }
    let film = FilmSettings::from_entity(&scene.film).map_err(|e| errors.push(e)).ok();
    unused(&scene.film.params, &mut warnings);
    // A lens that cannot focus or lets no light through is refused here as rendering refuses it.
    if let (Some(camera), Some(film)) = (&camera, &film)
        && let Projection::Realistic(r) = &camera.projection
    {
        let lens = crate::camera::RealisticLens::validate(r, film.resolution, film.diagonal)
            .map_err(|m| Error::new(&scene.camera.entity.loc, format!("realistic camera: {m}")));
        ok(lens.map(|_| ()), errors);
    }
    ok(FilterSettings::from_entity(&scene.filter).map(|_| ()), errors);
    unused(&scene.filter.params, &mut warnings);
    let sampler = SamplerSettings::from_entity(&scene.sampler, scene.options.seed, &mut warnings)
        .map_err(|e| errors.push(e))
        .ok();
    unused(&scene.sampler.params, &mut warnings);
    ok(IntegratorSettings::from_entity(&scene.integrator, None).map(|_| ()), errors);
    warnings.extend(IntegratorSettings::substitution_note(&scene.integrator, None));
    unused(&scene.integrator.params, &mut warnings);
    if scene.accelerator.name != "bvh" && scene.accelerator.name != "kdtree" {
        errors.push(Error::new(
            &scene.accelerator.loc,
            format!("unknown accelerator \"{}\" (bvh or kdtree)", scene.accelerator.name),
        ));
    }
    // nimbus always builds a BVH; the accelerator's tuning parameters have no counterpart.
    for p in scene.accelerator.params.iter() {
        warnings.push(Warning::new(
            &p.loc,
            format!("accelerator parameter \"{}\" is ignored (nimbus builds its own BVH)", p.name),
        ));
    }

    let mut shapes = BTreeMap::new();
    let mut triangles = 0;
    let object_shapes = scene.instance_definitions.iter().flat_map(|d| d.shapes.iter());
    for shape in scene.shapes.iter().chain(object_shapes) {
        match ShapeSettings::from_entity(shape).and_then(|settings| shape_triangles(shape, &settings)) {
            Ok(n) => triangles += n,
            Err(e) => errors.push(e),
        }
        unused(&shape.entity.params, &mut warnings);
        *shapes.entry(shape.entity.name.clone()).or_insert(0) += 1;
    }

    let mut lights = BTreeMap::new();
    for light in &scene.lights {
        ok(LightSettings::from_entity(light).map(|_| ()), errors);
        unused(&light.entity.params, &mut warnings);
        *lights.entry(light.entity.name.clone()).or_insert(0) += 1;
    }
    for area in &scene.area_lights {
        ok(AreaLightSettings::from_entity(area).map(|_| ()), errors);
        unused(&area.params, &mut warnings);
        *lights.entry(format!("area ({})", area.name)).or_insert(0) += 1;
    }

    let mut materials = BTreeMap::new();
    let mut material = |e: &Entity, warnings: &mut Vec<Warning>| -> Result<(), Error> {
        let before = warnings.len();
        MaterialSettings::from_entity(e, warnings)?;
        // A material reported as unsupported has no reader for its parameters.
        if warnings.len() == before {
            unused(&e.params, warnings);
        }
        *materials.entry(e.name.clone()).or_insert(0) += 1;
        Ok(())
    };
    // Material 0 is pbrt-v4's implicit default; count it only if a shape uses it.
    let uses_default = scene.shapes.iter().any(|s| s.material == nimbus_parser::MaterialRef::Index(0));
    for (i, m) in scene.materials.iter().enumerate() {
        if i > 0 || uses_default {
            ok(material(m, &mut warnings), errors);
        }
    }
    for m in &scene.named_materials {
        ok(material(&m.entity, &mut warnings), errors);
    }

    let mut textures = BTreeMap::new();
    for t in &scene.textures {
        ok(TextureSettings::from_entity(t).map(|_| ()), errors);
        unused(&t.entity.params, &mut warnings);
        *textures.entry(t.entity.name.clone()).or_insert(0) += 1;
    }

    let mut media = BTreeMap::new();
    for m in &scene.media {
        ok(MediumSettings::from_entity(m).map(|_| ()), errors);
        unused(&m.entity.params, &mut warnings);
        *media.entry(m.entity.name.clone()).or_insert(0) += 1;
    }
    let (camera, film, sampler) = (camera?, film?, sampler?);

    let camera_text = match &camera.projection {
        Projection::Perspective { fov } => format!("{}, fov {fov}°", scene.camera.entity.name),
        Projection::Orthographic => scene.camera.entity.name.clone(),
        Projection::Spherical { equal_area } => {
            format!("{}, {}", scene.camera.entity.name, if *equal_area { "equal-area" } else { "equirectangular" })
        }
        Projection::Realistic(r) => format!(
            "{}, {} lens interfaces, aperture {} mm, focus at {}",
            scene.camera.entity.name,
            r.elements.len(),
            r.aperture_diameter,
            r.focus_distance
        ),
    };
    let camera_text = match &scene.camera.medium {
        Some(m) => format!("{camera_text}, inside medium \"{m}\""),
        None => camera_text,
    };
    Some(SceneCheck {
        camera: camera_text,
        resolution: film.resolution,
        filename: film.filename,
        sampler: scene.sampler.name.clone(),
        spp: sampler.pixel_samples,
        integrator: match crate::integrators::canonical_name(&scene.integrator.name) {
            name if name == scene.integrator.name => name.to_string(),
            name => format!("{name} (as \"{}\")", scene.integrator.name),
        },
        // Only what the method reads: the rest is warned about as unused.
        integrator_params: scene.integrator.params.iter().filter(|p| p.is_used()).map(describe_param).collect(),
        shapes,
        triangles,
        instances: scene.instances.len(),
        lights,
        media,
        materials,
        textures,
        files: scene.files.clone(),
        warnings,
    })
}
