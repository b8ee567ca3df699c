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
use crate::accel::{Accel, Geometry, Instance, NONE, Primitive, ShapeStore, Surfaces};
use crate::camera::Camera;
use crate::camera::settings::CameraSettings;
use crate::color::{Rgb, pack_voxel};
use crate::film::filter::Filter;
use crate::film::filter_settings::FilterSettings;
use crate::film::settings::{FilmKind, FilmSettings};
use crate::geometry::ply::read_ply;
use crate::geometry::{Bounds3, MotionTransform};
use crate::integrators::IntegratorSettings;
use crate::integrators::registry::MethodInputs;
use crate::lights::{EmissionImage, EnvironmentMap, Light, LightKind, LightSampler, PortalMap, SceneSphere};
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

mod lights;
mod materials;
mod media;
mod shapes;
mod textures;

use super::Scene;
use lights::*;
use materials::*;
use media::*;
use shapes::*;
use textures::*;

/// Command-line choices that override the scene file (pbrt-v4's flags).
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// `--integrator`: render with this method instead of the scene's.
    pub integrator: Option<String>,
    /// The scene file named on the command line (methods look for their own files beside
    /// it).
    pub scene_file: Option<std::path::PathBuf>,
    /// `--precomputed` (`--graph-data`, `--guide-cache`): what the method prepared before
    /// (see [`crate::integrators::registry::MethodInputs`]).
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

/// The first quantity of the scene that varies with wavelength, named with its location:
/// a material that a shape uses, or a medium the camera, a light or a boundary uses.
fn first_chromatic(
    desc: &SceneDescription,
    materials: &[Material],
    textures: &Textures,
    material_ids: &dyn Fn(&MaterialRef) -> u32,
    used_media: &std::collections::HashSet<&str>,
    spectra: &SpectrumResolver<'_>,
) -> Result<Option<String>, Error> {
    let shapes = desc.shapes.iter().chain(desc.instance_definitions.iter().flat_map(|d| d.shapes.iter()));
    for shape in shapes {
        let id = material_ids(&shape.material) as usize;
        if let Some(input) = materials.get(id).and_then(|m| m.chromatic_input(materials, textures)) {
            let loc = match &shape.material {
                MaterialRef::Index(i) => desc.materials.get(*i).map(|m| &m.loc),
                MaterialRef::Named(n) => desc.named_materials.iter().find(|m| &m.name == n).map(|m| &m.entity.loc),
            }
            .unwrap_or(&shape.entity.loc);
            return Ok(Some(format!("{loc}: material {input} varies with wavelength")));
        }
    }
    for m in desc.media.iter().filter(|m| used_media.contains(m.name.as_str())) {
        let settings = MediumSettings::from_entity(m)?;
        let cs = m.entity.color_space;
        let chromatic = match &settings.kind {
            MediumSpec::RgbGrid { sigma_a, sigma_s, .. } => [sigma_a, sigma_s]
                .iter()
                .filter_map(|g| g.as_ref())
                .any(|g| g.iter().any(|c| c[0] != c[1] || c[1] != c[2])),
            _ => {
                let unbounded =
                    |s: &SpectrumSpec| spectra.unbounded(s, cs).map_err(|x| err(&m.entity.loc, x.to_string()));
                !unbounded(&settings.sigma_a)?.is_constant() || !unbounded(&settings.sigma_s)?.is_constant()
            }
        };
        if chromatic {
            return Ok(Some(format!("{}: medium \"{}\" has chromatic sigma_a or sigma_s", m.entity.loc, m.name)));
        }
    }
    Ok(None)
}

fn err(loc: &FileLoc, message: impl Into<String>) -> Error {
    Error::new(loc, message)
}

fn fixed_transform(t: &AnimatedTransform, loc: &FileLoc, what: &str) -> Result<Affine3A, Error> {
    if t.is_animated() {
        return Err(err(
            loc,
            format!(
                "animated transforms ({what} with ActiveTransform/TransformTimes motion) are not supported by nimbus"
            ),
        ));
    }
    affine(&t.start, loc)
}

/// An animated transform's motion, both keyframes checked as [`affine`] checks them.
fn motion_transform(t: &AnimatedTransform, loc: &FileLoc) -> Result<MotionTransform, Error> {
    affine(&t.start, loc)?;
    affine(&t.end, loc)?;
    Ok(MotionTransform::new(&t.start, &t.end, t.start_time as f32, t.end_time as f32))
}

fn affine(m: &DMat4, loc: &FileLoc) -> Result<Affine3A, Error> {
    let row3 = m.row(3);
    if (row3.x, row3.y, row3.z, row3.w) != (0.0, 0.0, 0.0, 1.0) {
        return Err(err(loc, "projective transforms are not supported (the last row must be 0 0 0 1)"));
    }
    let a = Affine3A::from_mat4(m.as_mat4());
    if !a.is_finite() || a.matrix3.determinant() == 0.0 {
        return Err(err(loc, "the transform is singular or not finite"));
    }
    Ok(a)
}

fn pixel_bounds(film: &FilmSettings, opts: &BuildOptions, loc: &FileLoc) -> Result<[u32; 4], Error> {
    let [w, h] = film.resolution;
    let from_crop = |c: [f32; 4]| -> [i64; 4] {
        [
            (w as f32 * c[0]).ceil() as i64,
            (h as f32 * c[2]).ceil() as i64,
            (w as f32 * c[1]).ceil() as i64,
            (h as f32 * c[3]).ceil() as i64,
        ]
    };
    let b: [i64; 4] = if let Some([x0, x1, y0, y1]) = opts.pixel_bounds.or(film.pixel_bounds) {
        [x0 as i64, y0 as i64, x1 as i64, y1 as i64]
    } else if let Some(c) = opts.crop_window.or(film.crop_window) {
        from_crop(c)
    } else {
        [0, 0, w as i64, h as i64]
    };
    let clamped = [b[0].clamp(0, w as i64), b[1].clamp(0, h as i64), b[2].clamp(0, w as i64), b[3].clamp(0, h as i64)];
    if clamped[0] >= clamped[2] || clamped[1] >= clamped[3] {
        return Err(err(loc, format!("the pixel bounds {b:?} select no pixels of the {w}x{h} image")));
    }
    Ok([clamped[0] as u32, clamped[1] as u32, clamped[2] as u32, clamped[3] as u32])
}

/// Builds the render-time scene.
pub fn build_scene(desc: &SceneDescription, opts: &BuildOptions) -> Result<Scene, Error> {
    let t0 = Instant::now();
    let mut warnings = desc.warnings.clone();
    // What pbrt-v4 does not animate it uses at the start of the motion, with these warnings.
    for l in desc.lights.iter().filter(|l| l.world_from_light.is_animated()) {
        warnings.push(Warning::new(&l.entity.loc, "Animated lights aren't supported. Using the start transform."));
    }
    for m in desc.media.iter().filter(|m| m.world_from_medium.is_animated()) {
        warnings.push(Warning::new(
            &m.entity.loc,
            "Animated transformation provided for medium. Only the start transform will be used.",
        ));
    }
    for t in desc.textures.iter().filter(|t| t.world_from_texture.is_animated()) {
        warnings.push(Warning::new(
            &t.entity.loc,
            "Animated world to texture transforms are not supported. Using the start transform.",
        ));
    }
    let mut film = FilmSettings::from_entity(&desc.film)?;
    if opts.quick {
        film.resolution = [(film.resolution[0] / 4).max(1), (film.resolution[1] / 4).max(1)];
    }
    let film_cs = film.color_space;
    let camera_settings = CameraSettings::from_entity(&desc.camera)?;
    let world_from_camera = &desc.camera.world_from_camera;
    warnings.extend(camera_settings.aperture_warning(&desc.camera));
    let mut camera = Camera::new(&camera_settings, &world_from_camera.start, film.resolution, film.diagonal)
        .map_err(|m| err(&desc.camera.entity.loc, format!("realistic camera: {m}")))?;
    if world_from_camera.is_animated() {
        camera = camera.with_motion(motion_transform(world_from_camera, &desc.camera.entity.loc)?);
    }
    let pixel_bounds = pixel_bounds(&film, opts, &desc.film.loc)?;
    let film_opts = BuildOptions { pixel_bounds: None, crop_window: None, ..Default::default() };
    let film_bounds = self::pixel_bounds(&film, &film_opts, &desc.film.loc)?;
    let mut sampler = SamplerSettings::from_entity(&desc.sampler, desc.options.seed, &mut warnings)?;
    // An explicit --spp is what the user asked for: --quick only quarters the scene's count.
    if let Some(spp) = opts.spp {
        sampler.pixel_samples = spp.max(1);
    } else if opts.quick {
        sampler.pixel_samples = (sampler.pixel_samples / 4).max(1);
    }
    if sampler.kind == crate::samplers::settings::SamplerKind::Pmj02bn {
        crate::samplers::settings::check_pmj02bn_samples(sampler.pixel_samples, &desc.sampler.loc)?;
    }
    if let Some(seed) = opts.seed {
        sampler.seed = seed;
    }
    let filter = Filter::new(&FilterSettings::from_entity(&desc.filter)?);
    let mut integrator = IntegratorSettings::from_entity(&desc.integrator, opts.integrator.as_deref())?;
    warnings.extend(IntegratorSettings::substitution_note(&desc.integrator, opts.integrator.as_deref()));
    integrator
        .set_inputs(&MethodInputs { scene_file: opts.scene_file.as_deref(), precomputed: opts.precomputed.as_deref() });
    if let Some(depth) = opts.max_depth {
        integrator.set_max_depth(depth).map_err(|m| err(&desc.integrator.loc, m))?;
    }

    // The film's sensor (pbrt-v4's imaging ratio: exposure time × ISO / 100).
    let exposure = camera_settings.shutter_close - camera_settings.shutter_open;
    let sensor = PixelSensor::new(&film.sensor, film.white_balance, film.iso, exposure, film_cs)
        .map_err(|m| err(desc.film.params.loc("sensor").unwrap_or(&desc.film.loc), m))?;

    // Textures, in definition order (a texture may use those defined before it).
    let spectra = SpectrumResolver { film: film_cs, sensor: &sensor };
    let mut tb = TextureBuilder {
        textures: Textures::default(),
        float_names: HashMap::new(),
        spectrum_names: HashMap::new(),
        spectra,
    };
    for t in &desc.textures {
        tb.add(t)?;
    }

    // Materials: anonymous ones by index, then named ones.
    let mut materials = Vec::with_capacity(desc.materials.len() + desc.named_materials.len());
    let mut shading = Vec::with_capacity(materials.capacity());
    let mut subsurface = Vec::with_capacity(materials.capacity());
    let mut named = HashMap::new();
    let entities =
        desc.materials.iter().map(|m| (None, m)).chain(desc.named_materials.iter().map(|m| (Some(&m.name), &m.entity)));
    let measured = MeasuredCache::default();
    for (name, e) in entities {
        if let Some(name) = name {
            named.insert(name.clone(), materials.len() as u32);
        }
        let built = material(e, &tb, &measured, &mut warnings)?;
        materials.push(built.material);
        shading.push(built.shading);
        subsurface.push(built.subsurface);
    }
    resolve_mixes(desc, &mut materials, &named)?;
    for m in &materials {
        if let Material::Mix { materials: pair, .. } = m
            && let Some(part) = pair.iter().find_map(|&i| subsurface[i as usize].as_ref())
        {
            return Err(err(
                &part.loc,
                "a subsurface material cannot be part of a mix in nimbus (its medium boundary belongs to the shape)",
            ));
        }
    }
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
    let mode = match (&opts.spectral, &desc.options.spectral) {
        (Some(m), _) => *m,
        (None, Some(s)) => s.parse().map_err(|m: String| err(&desc.film.loc, m))?,
        (None, None) => SpectralMode::Auto,
    };
    let mut chromatic = first_chromatic(desc, &materials, &tb.textures, &material_ids, &used, &spectra)?;
    if chromatic.is_none() {
        let shapes = desc.shapes.iter().chain(desc.instance_definitions.iter().flat_map(|d| d.shapes.iter()));
        chromatic = shapes
            .filter_map(|shape| subsurface[material_ids(&shape.material) as usize].as_ref())
            .find(|m| !m.sigma_a.is_constant() || !m.sigma_s.is_constant())
            .map(|m| format!("{}: subsurface material's sigma_a or sigma_s varies with wavelength", m.loc));
    }
    let mut transport = TransportChoice::new(mode, chromatic.as_deref());
    // The spectral film records spectra, which only spectral transport has.
    if let FilmKind::Spectral { .. } = film.kind {
        if mode == SpectralMode::Off {
            return Err(err(
                &desc.film.loc,
                "the spectral film records spectra: it needs spectral transport, not --spectral off",
            ));
        }
        if let Some(why) = integrator.spectral_film_refusal() {
            return Err(err(&desc.film.loc, why));
        }
        transport =
            TransportChoice { transport: Transport::Spectral, reason: "the spectral film records spectra".into() };
    }

    // Media: only those the camera, lights or boundary surfaces use are built.
    let mut media = Vec::new();
    let mut media_ids: HashMap<String, u32> = HashMap::new();
    for m in &desc.media {
        let settings = MediumSettings::from_entity(m)?;
        if used.contains(m.name.as_str()) {
            media_ids.insert(m.name.clone(), media.len() as u32);
            media.push(build_medium(m, &settings, &spectra, transport.transport)?);
        }
    }
    // A subsurface material's medium, one per material (shapes sharing it share it).
    let subsurface_media: Vec<u32> = subsurface
        .iter()
        .enumerate()
        .map(|(i, m)| match m {
            Some(m) => {
                let name = format!("subsurface material {i}");
                media.push(Medium::homogeneous(name, m.sigma_a, m.sigma_s, SpectrumValue::ZERO, m.g));
                media.len() as u32 - 1
            }
            None => NONE,
        })
        .collect();
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
    let mut prims = Vec::new();
    let mut bounds = Vec::new();
    let mut blas = Vec::new();
    let mut instances = Vec::new();
    for shape in &desc.shapes {
        let t = &shape.world_from_object;
        if !t.is_animated() {
            sb.add(shape, &desc.area_lights, false, affine(&t.start, &shape.entity.loc)?, &mut prims, &mut bounds)?;
            continue;
        }
        // A moving shape: built in its own space as a BVH of its own, placed by its motion at
        // each ray's time (pbrt-v4's AnimatedPrimitive).
        if shape.area_light.is_some() {
            return Err(err(&shape.entity.loc, "animated area lights are not supported (nor are they by pbrt-v4)"));
        }
        let motion = motion_transform(t, &shape.entity.loc)?;
        let (mut p, mut b) = (Vec::new(), Vec::new());
        sb.add(shape, &desc.area_lights, false, Affine3A::IDENTITY, &mut p, &mut b)?;
        if let Some(accel) = Accel::build(p, &b) {
            bounds.push(motion.bounds(&accel.bounds()));
            blas.push(accel);
            instances.push(Instance::moving(blas.len() as u32 - 1, motion));
            prims.push(Primitive::instance(instances.len() as u32 - 1));
        }
    }
    let mut blas_of: HashMap<&str, Option<u32>> = HashMap::new();
    for def in &desc.instance_definitions {
        let mut p = Vec::new();
        let mut b = Vec::new();
        for shape in &def.shapes {
            let world = fixed_transform(&shape.world_from_object, &shape.entity.loc, "a shape inside ObjectBegin")?;
            sb.add(shape, &desc.area_lights, true, world, &mut p, &mut b)?;
        }
        let accel = Accel::build(p, &b);
        blas_of.insert(def.name.as_str(), accel.as_ref().map(|_| blas.len() as u32));
        if let Some(a) = accel {
            blas.push(a);
        }
    }
    for u in &desc.instances {
        let Some(Some(accel)) = blas_of.get(u.name.as_str()).copied() else {
            continue;
        };
        let object_bounds = blas[accel as usize].bounds();
        let t = &u.world_from_instance;
        if t.is_animated() {
            let motion = motion_transform(t, &u.loc)?;
            bounds.push(motion.bounds(&object_bounds));
            instances.push(Instance::moving(accel, motion));
        } else {
            let world = affine(&t.start, &u.loc)?;
            bounds.push(object_bounds.transformed(&world));
            instances.push(Instance::fixed(accel, world));
        }
        prims.push(Primitive::instance(instances.len() as u32 - 1));
    }
    let primitives = prims.len();
    let top = Accel::build(prims, &bounds);
    let triangles = sb.triangles;
    let mesh_bytes = sb.mesh_bytes;
    let mut lights = std::mem::take(&mut sb.lights);
    let surfaces = Surfaces {
        shapes: sb.store,
        top,
        blas,
        instances,
        pass_through: materials.iter().map(Material::is_interface).collect(),
        alphas: std::mem::take(&mut sb.alphas),
        textures: tb.textures.clone(),
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
        match light(l, &spectra, transport.transport, medium)? {
            Some(light) => lights.push(light),
            None => warnings.push(Warning::new(
                &l.entity.loc,
                "No \"filename\" parameter provided for goniometric light (it emits nothing).",
            )),
        }
    }
    let infinite_lights = lights.iter().enumerate().filter(|(_, l)| l.is_infinite()).map(|(i, _)| i as u32).collect();
    // pbrt-v4's default for every integrator is the light BVH.
    let kind = integrator.light_sampler();
    let light_sampler = LightSampler::new(&lights, &surfaces.shapes, &sphere, kind);
    let bumps = shading.iter().any(|s| matches!(s, ShadingPerturbation::Bump(_)));
    let footprint = (tb.textures.uses_footprint() || bumps)
        .then(|| crate::camera::Footprint::new(&camera, film.resolution, sampler.pixel_samples));
    Ok(Scene {
        camera,
        film,
        pixel_bounds,
        film_bounds,
        sampler,
        filter,
        integrator,
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
        interfaces,
        camera_medium,
        has_chromatic_media,
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
