//! Builds the render-time [`Scene`] from a description: reads every entity's settings,
//! converts spectra to the film's RGB, creates shapes, BVHs, materials, textures and lights.
//! Only what the scene uses is built: no BVH without surfaces, no grid for homogeneous media.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glam::{Affine3A, DMat4, Vec2, Vec3, Vec4};
use nimbus_parser::{
    AnimatedTransform, ColorSpace, Error, FileLoc, MaterialRef, SceneDescription, ShapeEntity, TextureValue, Warning,
};

use super::lights::{AreaLightSettings, LightKind as LightSpec, LightSettings};
use super::materials::{
    ConductorSpec, Eta, HairAbsorptionSpec, MaterialKind, MaterialSettings, Roughness, SubsurfaceCoefficients,
};
use super::media::{MediumKind as MediumSpec, MediumSettings};
use super::shapes::{ShapeKind, ShapeSettings};
use super::spectra::SpectrumResolver;
use super::textures::{Mapping, TexInput, TextureKind, TextureSettings};
use super::transport::{SpectralMode, Transport, TransportChoice};
use crate::accel::{
    Accel, Geometry, Hulls, Instance, NONE, Primitive, ShapeStore, Surfaces, gather_hulls, lone_spheres,
};
use crate::camera::Camera;
use crate::camera::settings::CameraSettings;
use crate::channels::pack_voxel;
use crate::color::Rgb;
use crate::film::filter::Filter;
use crate::film::filter_settings::FilterSettings;
use crate::film::settings::{FilmKind, FilmSettings};
use crate::geometry::ply::read_ply;
use crate::geometry::{Bounds3, MotionTransform};
use crate::lights::{
    EmissionImage, EnvironmentMap, Light, LightKind, LightSampler, LightSamplerKind, PortalMap, SceneSphere,
};
use crate::materials::subsurface::{EntryCoefficients, SubsurfaceInputs};
use crate::materials::{ConductorInput, HairAbsorption, Material, RoughnessTex, ShadingPerturbation};
use crate::math::Frame;
use crate::media::dense::DenseGrid;
use crate::media::grid::VdbFile;
use crate::media::{Density, Emission, Field, Medium};
use crate::params::FloatInput;
use crate::samplers::settings::SamplerSettings;
use crate::shapes::{BilinearMesh, Curve, CurveCommon, Cylinder, Disk, Mesh, Sphere, uniform_scale};
use crate::spectra::RgbRole;
use crate::spectra::spec::{SpectrumInput, SpectrumSpec};
use crate::spectra::{BlackbodyRgbTable, PixelSensor, SpectrumValue};
use crate::textures::{
    MipFilter, MipMap, PtexEncoding, PtexTexture, Tex, TexContext, TexMapping, TexNode, Textures, Wrap,
};

mod chromatic;
mod lights;
mod materials;
mod media;
mod shapes;
mod textures;
mod transforms;
mod view;

use super::Scene;
use chromatic::*;
use lights::*;
use materials::*;
use media::*;
use shapes::*;
use textures::*;
use transforms::*;
use view::*;

/// Command-line choices that override the scene file (pbrt-v4's flags).
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// `--integrator`: render with this method instead of the scene's.
    pub integrator: Option<String>,
    /// The scene file named on the command line (methods look for their own files beside
    /// it).
    pub scene_file: Option<std::path::PathBuf>,
    /// `--precomputed` (`--graph-data`, `--guide-cache`): what the method prepared before
    /// (the method reads it; the scene does not).
    pub precomputed: Option<std::path::PathBuf>,
    /// `--maxdepth`: the longest path, overriding the integrator's `maxdepth`.
    pub max_depth: Option<u32>,
    /// `--spp`
    pub spp: Option<u32>,
    /// `--seed`
    pub seed: Option<i32>,
    /// `--quick`: a quarter of the resolution in each axis and a quarter of the samples.
    pub quick: bool,
    /// `--cropwindow x0 x1 y0 y1`
    pub crop_window: Option<[f32; 4]>,
    /// `--pixelbounds x0 x1 y0 y1`
    pub pixel_bounds: Option<[i32; 4]>,
    /// `--spectral auto|on|off`: overrides the scene's `Option "spectral"`.
    pub spectral: Option<SpectralMode>,
}

/// What the method that renders the scene asks of it. The scene knows no method: whoever
/// pairs the two (`nimbus::setup`) asks the method's settings and passes this.
#[derive(Clone, Copy, Debug, Default)]
pub struct SceneNeeds {
    /// How next-event estimation picks a light (pbrt-v4's default, the light BVH).
    pub light_sampler: LightSamplerKind,
    /// Why the method cannot render a spectral film, when it cannot.
    pub spectral_film_refusal: Option<&'static str>,
}

/// Time and memory spent building, for `--stats`.
#[derive(Clone, Debug, Default)]
pub struct BuildStats {
    /// Seconds to build shapes and the BVH.
    pub geometry_seconds: f64,
    /// Seconds for everything else.
    pub other_seconds: f64,
    /// Triangles.
    pub triangles: usize,
    /// Primitives in BVHs.
    pub primitives: usize,
    /// Bytes of mesh data.
    pub mesh_bytes: usize,
}

fn err(loc: &FileLoc, message: impl Into<String>) -> Error {
    Error::new(loc, message)
}

/// Builds the render-time scene for a method that asks `needs` of it.
pub fn build_scene(desc: &SceneDescription, opts: &BuildOptions, needs: &SceneNeeds) -> Result<Scene, Error> {
    let t0 = Instant::now();
    let mut warnings = desc.warnings.clone();
    animation_warnings(desc, &mut warnings);
    let View { film, camera, pixel_bounds, film_bounds, sampler, filter, sensor } = view(desc, opts, &mut warnings)?;
    let film_cs = film.color_space;

    // Textures, in definition order (a texture may use those defined before it).
    let spectra = SpectrumResolver { film: film_cs, sensor: &sensor };
    let mut tb = TextureBuilder {
        textures: Textures::default(),
        float_names: HashMap::new(),
        float_constants: HashMap::new(),
        spectrum_names: HashMap::new(),
        spectra,
    };
    for t in &desc.textures {
        tb.add(t)?;
    }

    let Materials { materials, shading, subsurface, named } = build_materials(desc, &tb, &mut warnings)?;
    let has_interfaces = materials.iter().any(Material::is_interface);
    let material_ids = |r: &MaterialRef| -> u32 {
        match r {
            MaterialRef::Index(i) => *i as u32,
            // The parser checked that every named material exists.
            MaterialRef::Named(n) => named.get(n).copied().unwrap_or(0),
        }
    };

    // RGB or spectral transport: the first quantity of the scene that varies with
    // wavelength, among the materials shapes use and the media, decides `auto`.
    let used = used_media(desc);
    let ctx = Chromatic {
        materials: &materials,
        textures: &tb.textures,
        material_ids: &material_ids,
        used_media: &used,
        spectra: &spectra,
    };
    let transport = choose_transport(desc, opts, &film, needs, &ctx, &subsurface)?;

    let Media { media, ids: media_ids, subsurface: subsurface_media, entry_coefficients } =
        build_media(desc, &used, &spectra, transport.transport, &subsurface)?;
    old_spellings(desc, &mut warnings);
    let interfaces = std::cell::RefCell::new(Vec::<[u32; 2]>::new());
    let medium_id = |name: &Option<String>| name.as_deref().map_or(NONE, |n| media_ids.get(n).copied().unwrap_or(NONE));
    // A shape's boundary: its MediumInterface, with the inside replaced by the material's
    // medium for subsurface materials.
    let interface_ids = |mi: Option<&nimbus_parser::MediumInterface>, material: u32| -> Result<u32, Error> {
        let sub = subsurface_media.get(material as usize).copied().unwrap_or(NONE);
        let pair = match mi {
            None if sub == NONE => return Ok(NONE),
            None => [sub, NONE],
            Some(mi) if sub == NONE => [medium_id(&mi.inside), medium_id(&mi.outside)],
            Some(mi) => [sub, medium_id(&mi.outside)],
        };
        let mut list = interfaces.borrow_mut();
        Ok(match list.iter().position(|p| *p == pair) {
            Some(i) => i as u32,
            None => {
                list.push(pair);
                list.len() as u32 - 1
            }
        })
    };
    let camera_medium = medium_id(&desc.camera.medium);

    // Shapes, object definitions and instances.
    let tg = Instant::now();
    let mut sb = ShapeBuilder {
        store: ShapeStore::default(),
        textures: &tb,
        alphas: Vec::new(),
        spectra,
        material_ids: &material_ids,
        interface_ids: &interface_ids,
        lights: Vec::new(),
        triangles: 0,
        mesh_bytes: 0,
        rgb_transport: transport.transport == Transport::Rgb,
    };
    let Placed { top, blas, instances, primitives, hulls } = sb.place_all(desc)?;
    let triangles = sb.triangles;
    let mesh_bytes = sb.mesh_bytes;
    let mut lights = std::mem::take(&mut sb.lights);
    // pbrt-v4's render space (`Option "rendercoordsys"`): world space moved to the camera by
    // default. Surfaces decide coplanar ties in it, and infinite lights' projective transforms
    // depend on it.
    let render_from_world = match desc.options.render_coord_sys.as_deref() {
        Some("world") => glam::Affine3A::IDENTITY,
        Some("camera") => camera.camera_from_world(),
        _ => glam::Affine3A::from_translation(-camera.position()),
    };
    let surfaces = Surfaces {
        shapes: sb.store,
        top,
        blas,
        instances,
        pass_through: materials.iter().map(Material::is_interface).collect(),
        alphas: std::mem::take(&mut sb.alphas),
        textures: tb.textures.clone(),
        hulls,
        render_from_world,
    };
    let interfaces = interfaces.into_inner();
    let has_chromatic_media = media.iter().any(|m| m.chromatic);
    let geometry_seconds = tg.elapsed().as_secs_f64();

    let sb_bounds = surfaces.bounds();
    let sphere = if sb_bounds.is_empty() {
        SceneSphere { center: camera.position(), radius: 1.0 }
    } else {
        let (center, radius) = sb_bounds.bounding_sphere();
        SceneSphere { center, radius: radius.max(1e-3) }
    };
    for l in &desc.lights {
        let medium = l.medium.as_deref().map_or(NONE, |n| media_ids.get(n).copied().unwrap_or(NONE));
        // An infinite light's projective transform depends on where render space is.
        if let Some(light) = light(l, &spectra, transport.transport, medium, &render_from_world, &mut warnings)? {
            lights.push(light);
        }
    }
    let infinite_lights = lights.iter().enumerate().filter(|(_, l)| l.is_infinite()).map(|(i, _)| i as u32).collect();
    let light_sampler = LightSampler::new(&lights, &surfaces.shapes, &sphere, needs.light_sampler);
    let has_tracked_media = media.iter().any(|m| !matches!(m.kind, crate::media::MediumKind::Homogeneous { .. }));
    let continues_past_max_depth = lights.iter().any(|l| l.is_infinite())
        || lights.iter().any(|l| matches!(l.kind, LightKind::Area { .. }))
        || media.iter().any(|m| m.subsurface);
    let bumps = shading.iter().any(|s| matches!(s, ShadingPerturbation::Bump(_)));
    let footprint = (tb.textures.uses_footprint() || bumps)
        .then(|| crate::camera::Footprint::new(&camera, film.resolution, sampler.pixel_samples));
    let camera_sample_use = crate::samplers::CameraSampleUse {
        time: camera.moves() || surfaces.instances.iter().any(|i| i.motion.is_some()),
        lens: camera.samples_lens(),
    };
    Ok(Scene {
        camera_sample_use,
        camera,
        film,
        pixel_bounds,
        film_bounds,
        sampler,
        filter,
        surfaces,
        materials,
        shading,
        footprint,
        uv_footprint: tb.textures.uses_uv_footprint(),
        textures: tb.textures,
        lights,
        light_sampler,
        infinite_lights,
        sphere,
        has_interfaces,
        media,
        entry_coefficients,
        interfaces,
        camera_medium,
        has_chromatic_media,
        has_tracked_media,
        continues_past_max_depth,
        sensor,
        transport,
        disable_wavelength_jitter: desc.options.disable_wavelength_jitter,
        stats: BuildStats {
            geometry_seconds,
            other_seconds: t0.elapsed().as_secs_f64() - geometry_seconds,
            triangles,
            primitives,
            mesh_bytes,
        },
        warnings,
    })
}

/// Parameters published scenes spell as an older pbrt-v4 did, which nimbus reads under their
/// new names: one note per spelling, at its first use.
fn old_spellings(desc: &SceneDescription, warnings: &mut Vec<Warning>) {
    let old = desc
        .media
        .iter()
        .find(|m| m.entity.params.peek("LeScale").is_some() && m.entity.params.peek("Lescale").is_none());
    if let Some(m) = old {
        let loc = m.entity.params.loc("LeScale").unwrap_or(&m.entity.loc);
        warnings.push(Warning::new(
            loc,
            "\"LeScale\" is read as \"Lescale\", as pbrt-v4 spells it now (noted once for the scene)",
        ));
    }
}
