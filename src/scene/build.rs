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
use crate::camera::settings::CameraSettings;
use crate::camera::{Camera, Differentials};
use crate::color::{Rgb, pack_voxel};
use crate::film::filter::Filter;
use crate::film::filter_settings::FilterSettings;
use crate::film::settings::{FilmKind, FilmSettings};
use crate::geometry::ply::read_ply;
use crate::geometry::{Bounds3, MotionTransform};
use crate::integrators::IntegratorSettings;
use crate::integrators::registry::MethodInputs;
use crate::lights::{EmissionImage, EnvironmentMap, Light, LightKind, LightSampler, PortalMap, SceneSphere};
use crate::materials::{ConductorInput, HairAbsorption, Material, RoughnessTex, ShadingPerturbation, resolve};
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

/// Everything needed to render.
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Film settings (output name, resolution, clamp, color space).
    pub film: FilmSettings,
    /// Pixels to render: [x0, y0, x1, y1), within the full resolution.
    pub pixel_bounds: [u32; 4],
    /// The film's own pixel bounds (its `cropwindow` or `pixelbounds`, not the command
    /// line's): the whole image that parts rendered with `--pixelbounds` make up.
    pub film_bounds: [u32; 4],
    /// Sampler settings (spp, seed, kind).
    pub sampler: SamplerSettings,
    /// The reconstruction filter.
    pub filter: Filter,
    /// The integrator to use and its parameters.
    pub integrator: IntegratorSettings,
    /// Surfaces and BVHs.
    pub surfaces: Surfaces,
    /// Materials, indexed by primitives.
    pub materials: Vec<Material>,
    /// Each material's bump or normal map, indexed like `materials`.
    pub shading: Vec<ShadingPerturbation>,
    /// Texture nodes.
    pub textures: Textures,
    /// The camera's footprint model, when a texture filters over it.
    pub footprint: Option<crate::camera::Footprint>,
    /// A texture also reads the footprint in (u, v) (MIP-mapped images).
    pub uv_footprint: bool,
    /// Lights (area lights first, one per emitting primitive).
    pub lights: Vec<Light>,
    /// Next-event light selection.
    pub light_sampler: LightSampler,
    /// Indices of lights at infinity.
    pub infinite_lights: Vec<u32>,
    /// Bounding sphere of the scene.
    pub sphere: SceneSphere,
    /// Whether any surface is an `interface` (shadow rays must pass through them).
    pub has_interfaces: bool,
    /// Media the scene uses (unused named media are not built).
    pub media: Vec<Medium>,
    /// (inside, outside) medium of each boundary surface; primitives index this.
    pub interfaces: Vec<[u32; 2]>,
    /// Medium around the camera, or [`NONE`].
    pub camera_medium: u32,
    /// Whether any medium is chromatic (paths then pick a hero channel).
    pub has_chromatic_media: bool,
    /// The film's sensor (its imaging ratio, response curves and output matrix).
    pub sensor: PixelSensor,
    /// RGB or spectral transport, and why.
    pub transport: TransportChoice,
    /// pbrt-v4's `Option "disablewavelengthjitter"`: every path gets the wavelengths of u = ½.
    pub disable_wavelength_jitter: bool,
    /// Build statistics.
    pub stats: BuildStats,
    /// Warnings found while building.
    pub warnings: Vec<Warning>,
}

impl Scene {
    /// True when shapes or the camera move over the shutter interval (motion blur).
    pub fn has_motion(&self) -> bool {
        self.camera.moves() || self.surfaces.instances.iter().any(|i| i.motion.is_some())
    }

    /// The material that scatters at `hit` seen from `wo` (`mix` resolved), with the hit's
    /// shading normal and tangents replaced by the material's bump or normal map, and the
    /// texture lookup there: its screen-space footprint when a texture or a bump needs one
    /// (computed once per hit, with the surface derivatives at most once), from the ray's
    /// differentials `diff` where it has them, else from the camera's smallest ones.
    #[inline]
    pub fn surface_material(
        &self,
        hit: &mut crate::accel::Hit,
        wo: Vec3,
        diff: Option<&Differentials>,
    ) -> (&Material, TexContext) {
        let s = &hit.surface;
        let mut ctx = TexContext::at(s.p, s.uv, s.n);
        ctx.face = self.surfaces.shapes.face_index(hit.prim.geometry);
        let mut derivatives = None;
        if let Some(f) = &self.footprint {
            (ctx.dpdx, ctx.dpdy) = diff.and_then(|d| d.dp_dxy(s.p, s.n)).unwrap_or_else(|| f.dp_dxy(s.p, s.n));
            if self.uv_footprint {
                let d = self.surfaces.derivatives(hit);
                (ctx.duvdx, ctx.duvdy) = uv_footprint(d.dpdu, d.dpdv, ctx.dpdx, ctx.dpdy);
                derivatives = Some(d);
            }
        }
        let id = resolve(&self.materials, hit.prim.material, &self.textures, &ctx, wo);
        let shading = &self.shading[id as usize];
        if !shading.is_none() {
            let d = derivatives.unwrap_or_else(|| self.surfaces.derivatives(hit));
            // A bump steps by the (u, v) footprint even where no texture reads it.
            if self.footprint.is_some() && !self.uv_footprint {
                (ctx.duvdx, ctx.duvdy) = uv_footprint(d.dpdu, d.dpdv, ctx.dpdx, ctx.dpdy);
            }
            shading.apply(&self.textures, &mut hit.surface, &d, &ctx);
        }
        (&self.materials[id as usize], ctx)
    }

    /// The differentials of the ray leaving `hit` (its material looked up in `ctx`) along `wi`
    /// after a perfectly specular reflection or transmission (relative index `eta`) of a ray
    /// that arrived along −`wo` with differentials `diff` (pbrt-v4's `SpawnRay` with specular
    /// flags; the shading normal's change across the footprint from the shape's ∂n/∂u, ∂n/∂v).
    #[allow(clippy::too_many_arguments)]
    pub fn specular_differentials(
        &self,
        hit: &crate::accel::Hit,
        ctx: &TexContext,
        diff: &Differentials,
        wo: Vec3,
        wi: Vec3,
        transmission: bool,
        eta: f32,
    ) -> Option<Differentials> {
        let d = self.surfaces.derivatives(hit);
        let (duvdx, duvdy) = uv_footprint(d.dpdu, d.dpdv, ctx.dpdx, ctx.dpdy);
        let dndx = d.dndu * duvdx.x + d.dndv * duvdx.y;
        let dndy = d.dndu * duvdy.x + d.dndv * duvdy.y;
        let s = &hit.surface;
        diff.specular(s.p, (ctx.dpdx, ctx.dpdy), s.ns, (dndx, dndy), wo, wi, transmission.then_some(eta))
    }

    /// The matrix from what the film accumulates to output RGB: for RGB transport samples are
    /// output RGB already and only the imaging ratio is left; for spectral transport they are
    /// sensor RGB (imaging ratio included), converted as pbrt-v4's RGB film does.
    pub fn film_output(&self) -> glam::DMat3 {
        match self.transport.transport {
            Transport::Rgb => glam::DMat3::from_diagonal(glam::DVec3::splat(f64::from(self.sensor.imaging_ratio()))),
            Transport::Spectral => self.sensor.output_rgb_from_sensor_rgb(),
        }
    }
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

/// Builds textures and remembers which name maps to which node.
struct TextureBuilder<'a> {
    textures: Textures,
    float_names: HashMap<String, u32>,
    spectrum_names: HashMap<String, u32>,
    spectra: SpectrumResolver<'a>,
}

impl TextureBuilder<'_> {
    fn float(&self, input: &FloatInput, loc: &FileLoc) -> Result<Tex, Error> {
        Ok(match input {
            FloatInput::Value(v) => Tex::Const(SpectrumValue::constant(*v)),
            FloatInput::Texture(name) => Tex::Node(
                *self
                    .float_names
                    .get(name)
                    .ok_or_else(|| err(loc, format!("float texture \"{name}\" is not defined")))?,
            ),
        })
    }

    /// A spectrum texture input; a constant is read as a reflectance, or as an unbounded
    /// coefficient with `unbounded`.
    fn spectrum(&self, input: &SpectrumInput, cs: ColorSpace, loc: &FileLoc) -> Result<Tex, Error> {
        self.spectrum_as(input, cs, loc, false)
    }

    fn spectrum_as(&self, input: &SpectrumInput, cs: ColorSpace, loc: &FileLoc, unbounded: bool) -> Result<Tex, Error> {
        Ok(match input {
            SpectrumInput::Value(spec) => {
                let v = if unbounded { self.spectra.unbounded(spec, cs) } else { self.spectra.albedo(spec, cs) };
                Tex::Const(v.map_err(|e| err(loc, e.to_string()))?)
            }
            SpectrumInput::Texture(name) => Tex::Node(
                *self
                    .spectrum_names
                    .get(name)
                    .ok_or_else(|| err(loc, format!("spectrum texture \"{name}\" is not defined")))?,
            ),
        })
    }

    fn input(&self, input: &TexInput, cs: ColorSpace, loc: &FileLoc) -> Result<Tex, Error> {
        match input {
            TexInput::Float(f) => self.float(f, loc),
            TexInput::Spectrum(s) => self.spectrum(s, cs, loc),
        }
    }

    fn add(&mut self, t: &nimbus_parser::TextureEntity) -> Result<(), Error> {
        let e = &t.entity;
        let settings = TextureSettings::from_entity(t)?;
        let texture_from_world = affine(&t.world_from_texture.start, &e.loc)?.inverse();
        let mapping = |m: &Mapping| match m {
            Mapping::Uv { su, sv, du, dv } => TexMapping::Uv { s: Vec2::new(*su, *sv), d: Vec2::new(*du, *dv) },
            Mapping::Spherical => TexMapping::Spherical { texture_from_world },
            Mapping::Cylindrical => TexMapping::Cylindrical { texture_from_world },
            Mapping::Planar { v1, v2, du, dv } => TexMapping::Planar {
                texture_from_world,
                vs: Vec3::from(*v1),
                vt: Vec3::from(*v2),
                d: Vec2::new(*du, *dv),
            },
        };
        let cs = e.color_space;
        let node = match &settings.kind {
            TextureKind::Constant(v) => {
                TexNode::Scale { tex: self.input(v, cs, &e.loc)?, scale: Tex::Const(SpectrumValue::constant(1.0)) }
            }
            TextureKind::Scale { tex, scale } => {
                TexNode::Scale { tex: self.input(tex, cs, &e.loc)?, scale: self.float(scale, &e.loc)? }
            }
            TextureKind::Mix { tex1, tex2, amount } => TexNode::Mix {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                amount: self.float(amount, &e.loc)?,
            },
            TextureKind::Checkerboard { tex1, tex2, mapping: m } => TexNode::Checkerboard {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                mapping: mapping(m),
            },
            TextureKind::Checkerboard3D { tex1, tex2 } => TexNode::Checkerboard3D {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                texture_from_world,
            },
            TextureKind::Bilerp { v, mapping: m } => TexNode::Bilerp {
                v: [
                    self.input(&v[0], cs, &e.loc)?,
                    self.input(&v[1], cs, &e.loc)?,
                    self.input(&v[2], cs, &e.loc)?,
                    self.input(&v[3], cs, &e.loc)?,
                ],
                mapping: mapping(m),
            },
            TextureKind::Fbm { octaves, roughness } => {
                TexNode::Fbm { texture_from_world, octaves: *octaves, omega: *roughness }
            }
            TextureKind::Wrinkled { octaves, roughness } => {
                TexNode::Wrinkled { texture_from_world, octaves: *octaves, omega: *roughness }
            }
            TextureKind::Windy => TexNode::Windy { texture_from_world },
            TextureKind::Marble { octaves, roughness, scale, variation } => TexNode::Marble {
                texture_from_world,
                octaves: *octaves,
                omega: *roughness,
                scale: *scale,
                variation: *variation,
            },
            TextureKind::Dots { inside, outside, mapping: m } => TexNode::Dots {
                inside: self.input(inside, cs, &e.loc)?,
                outside: self.input(outside, cs, &e.loc)?,
                mapping: mapping(m),
            },
            TextureKind::DirectionMix { tex1, tex2, dir } => TexNode::DirectionMix {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                // A texture-space direction, taken to world space (pbrt-v4's renderFromTexture).
                dir: texture_from_world.inverse().transform_vector3(Vec3::from(*dir)).normalize_or_zero(),
            },
            TextureKind::ImageMap { filename, filter, max_anisotropy, scale, invert, wrap, encoding, mapping: m } => {
                let image = load_texture_image(filename, encoding).map_err(|m| err(&e.loc, m))?;
                let wrap = match wrap.as_str() {
                    "repeat" => Wrap::Repeat,
                    "black" => Wrap::Black,
                    "clamp" => Wrap::Clamp,
                    other => {
                        return Err(err(
                            &e.loc,
                            format!("imagemap: unknown wrap mode \"{other}\" (repeat, black or clamp)"),
                        ));
                    }
                };
                let gray = image.pixels.iter().all(|p| p.x == p.y && p.y == p.z);
                let filter = match filter.as_str() {
                    "point" => MipFilter::Point,
                    "bilinear" => MipFilter::Bilinear,
                    "trilinear" => MipFilter::Trilinear,
                    "ewa" | "EWA" => MipFilter::Ewa,
                    other => {
                        return Err(err(
                            &e.loc,
                            format!("imagemap: unknown filter \"{other}\" (point, bilinear, trilinear or ewa)"),
                        ));
                    }
                };
                TexNode::Image {
                    image: Arc::new(MipMap::new(image, wrap, filter).with_max_anisotropy(*max_anisotropy)),
                    mapping: mapping(m),
                    scale: *scale,
                    invert: *invert,
                    space: cs,
                    gray,
                    float: t.value == TextureValue::Float,
                }
            }
            TextureKind::Ptex { filename, encoding, scale } => {
                let encoding = PtexEncoding::parse(encoding)
                    .map_err(|m| err(t.entity.params.loc("encoding").unwrap_or(&e.loc), format!("ptex: {m}")))?;
                let texture =
                    PtexTexture::open(filename, encoding, *scale).map_err(|m| err(&e.loc, format!("ptex: {m}")))?;
                TexNode::Ptex { texture: Arc::new(texture), float: t.value == TextureValue::Float }
            }
        };
        let id = self.textures.nodes.len() as u32;
        self.textures.nodes.push(node);
        match t.value {
            TextureValue::Float => self.float_names.insert(t.name.clone(), id),
            TextureValue::Spectrum => self.spectrum_names.insert(t.name.clone(), id),
        };
        Ok(())
    }
}

fn load_texture_image(path: &Path, encoding: &str) -> Result<crate::imageio::Image, String> {
    let is_png = path.extension().is_some_and(|x| x.eq_ignore_ascii_case("png"));
    let mut image = crate::imageio::read_image(path)?;
    if is_png && encoding != "sRGB" {
        // read_image decoded sRGB; re-encode and apply the requested encoding instead.
        let gamma = match encoding {
            "linear" => 1.0,
            e if e.starts_with("gamma ") => {
                e[6..].trim().parse::<f32>().map_err(|_| format!("imagemap: bad encoding \"{e}\""))?
            }
            other => {
                return Err(format!("imagemap: unknown encoding \"{other}\" (sRGB, linear or \"gamma g\")"));
            }
        };
        let enc = |v: f32| {
            if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
        };
        for p in &mut image.pixels {
            *p = Rgb::new(enc(p.x).powf(gamma), enc(p.y).powf(gamma), enc(p.z).powf(gamma));
        }
        // pbrt-v4 decodes an 8-bit image's alpha with the same encoding.
        for (_, values) in image.channels.iter_mut().filter(|(n, _)| n == "A") {
            for a in values.iter_mut() {
                *a = enc(*a).powf(gamma);
            }
        }
    }
    Ok(image)
}

fn roughness(r: &Roughness, tb: &TextureBuilder, loc: &FileLoc) -> Result<RoughnessTex, Error> {
    Ok(RoughnessTex { u: tb.float(&r.u, loc)?, v: tb.float(&r.v, loc)?, remap: r.remap })
}

fn eta_value(eta: &Eta, tb: &TextureBuilder, cs: ColorSpace, loc: &FileLoc) -> Result<SpectrumValue, Error> {
    tb.spectra.eta(eta, cs).map_err(|e| err(loc, e.to_string()))
}

fn conductor_input(
    spec: &ConductorSpec,
    tb: &TextureBuilder,
    cs: ColorSpace,
    loc: &FileLoc,
) -> Result<ConductorInput, Error> {
    Ok(match spec {
        ConductorSpec::Reflectance(r) => ConductorInput::Reflectance(tb.spectrum(r, cs, loc)?),
        ConductorSpec::EtaK { eta: SpectrumInput::Value(eta), k: SpectrumInput::Value(k) } => {
            let c = tb.spectra.conductor(eta, k, cs).map_err(|m| err(loc, m.to_string()))?;
            ConductorInput::EtaK { eta: Tex::Const(c.eta), k: Tex::Const(c.k), scale: c.scale }
        }
        ConductorSpec::EtaK { eta, k } => {
            // Textured optical constants: used per channel as given.
            let as_tex = |s: &SpectrumInput| -> Result<Tex, Error> {
                Ok(match s {
                    SpectrumInput::Value(v) => {
                        let c = tb.spectra.conductor(v, v, cs).map_err(|m| err(loc, m.to_string()))?;
                        Tex::Const(c.eta)
                    }
                    t => tb.spectrum_as(t, cs, loc, true)?,
                })
            };
            ConductorInput::EtaK { eta: as_tex(eta)?, k: as_tex(k)?, scale: SpectrumValue::constant(1.0) }
        }
    })
}

/// Points each `mix` material at its two named parts: pbrt-v4 requires them to exist and
/// not be `interface`; nimbus also refuses a mix that contains itself.
fn resolve_mixes(
    desc: &SceneDescription,
    materials: &mut [Material],
    named: &HashMap<String, u32>,
) -> Result<(), Error> {
    let entities = desc.materials.iter().chain(desc.named_materials.iter().map(|m| &m.entity));
    let mut parts = Vec::new();
    for (i, e) in entities.enumerate() {
        if e.name != "mix" {
            continue;
        }
        let names = e.params.get_strings("materials")?;
        let loc = e.params.loc("materials").unwrap_or(&e.loc);
        let mut pair = [0u32; 2];
        for (slot, name) in pair.iter_mut().zip(names) {
            let Some(&id) = named.get(name) else {
                return Err(err(loc, format!("mix: named material \"{name}\" not found")));
            };
            if materials[id as usize].is_interface() {
                return Err(err(
                    loc,
                    format!("mix: \"{name}\" is an \"interface\" material, which cannot be part of a mix"),
                ));
            }
            *slot = id;
        }
        parts.push((i, pair, loc));
    }
    for &(i, pair, _) in &parts {
        if let Material::Mix { materials: p, .. } = &mut materials[i] {
            *p = pair;
        }
    }
    // A mix reachable from itself would never resolve.
    for &(i, _, loc) in &parts {
        let mut stack = vec![(i as u32, 0usize)];
        while let Some((m, depth)) = stack.pop() {
            if let Material::Mix { materials: pair, .. } = &materials[m as usize] {
                for &p in pair {
                    if p as usize == i || depth > materials.len() {
                        return Err(err(loc, "mix: the material contains itself"));
                    }
                    stack.push((p, depth + 1));
                }
            }
        }
    }
    Ok(())
}

/// The homogeneous medium inside a `subsurface` material's boundary.
struct SubsurfaceMedium {
    sigma_a: SpectrumValue,
    sigma_s: SpectrumValue,
    g: f32,
    loc: FileLoc,
}

/// A material as the scene uses it: what scatters at its surface, how it perturbs the
/// shading geometry, and the medium behind it for `subsurface`.
struct BuiltMaterial {
    material: Material,
    shading: ShadingPerturbation,
    subsurface: Option<SubsurfaceMedium>,
}

/// Measured BRDFs read so far, by file: materials naming the same file share its tables.
type MeasuredCache =
    std::cell::RefCell<HashMap<std::path::PathBuf, std::sync::Arc<crate::materials::measured::MeasuredData>>>;

fn material(
    e: &nimbus_parser::Entity,
    tb: &TextureBuilder,
    measured: &MeasuredCache,
    warnings: &mut Vec<Warning>,
) -> Result<BuiltMaterial, Error> {
    let settings = MaterialSettings::from_entity(e, warnings)?;
    let cs = e.color_space;
    let loc = &e.loc;
    // pbrt-v4 applies the normal map when a material has both.
    let shading = if let Some(path) = &settings.normal_map {
        let image = load_texture_image(path, "linear").map_err(|m| err(e.params.loc("normalmap").unwrap_or(loc), m))?;
        ShadingPerturbation::NormalMap(Arc::new(image))
    } else if let Some(d) = &settings.displacement {
        ShadingPerturbation::Bump(tb.float(d, loc)?)
    } else {
        ShadingPerturbation::None
    };
    let mut subsurface = None;
    let material = match &settings.kind {
        MaterialKind::Diffuse { reflectance } => Material::Diffuse { reflectance: tb.spectrum(reflectance, cs, loc)? },
        MaterialKind::Conductor { spec, roughness: r } => {
            Material::Conductor { input: conductor_input(spec, tb, cs, loc)?, roughness: roughness(r, tb, loc)? }
        }
        MaterialKind::CoatedConductor {
            interface_roughness,
            thickness,
            interface_eta,
            conductor,
            conductor_roughness,
            albedo,
            g,
            max_depth,
            n_samples,
        } => Material::CoatedConductor {
            interface_roughness: roughness(interface_roughness, tb, loc)?,
            thickness: tb.float(thickness, loc)?,
            interface_eta: eta_value(interface_eta, tb, cs, loc)?,
            conductor: conductor_input(conductor, tb, cs, loc)?,
            conductor_roughness: roughness(conductor_roughness, tb, loc)?,
            albedo: tb.spectrum(albedo, cs, loc)?,
            g: tb.float(g, loc)?,
            max_depth: *max_depth,
            n_samples: *n_samples,
        },
        MaterialKind::DiffuseTransmission { reflectance, transmittance, scale } => Material::DiffuseTransmission {
            reflectance: tb.spectrum(reflectance, cs, loc)?,
            transmittance: tb.spectrum(transmittance, cs, loc)?,
            scale: *scale,
        },
        // The parts are named materials, some perhaps defined later: `resolve_mixes` sets
        // them once every material exists.
        MaterialKind::Mix { amount, .. } => Material::Mix { materials: [0, 0], amount: tb.float(amount, loc)? },
        MaterialKind::Dielectric { eta, roughness: r } => {
            Material::Dielectric { eta: eta_value(eta, tb, cs, loc)?, roughness: roughness(r, tb, loc)? }
        }
        MaterialKind::ThinDielectric { eta } => Material::ThinDielectric { eta: eta_value(eta, tb, cs, loc)? },
        MaterialKind::Interface => Material::Interface,
        MaterialKind::CoatedDiffuse { reflectance, roughness: r, thickness, eta, albedo, g, max_depth, n_samples } => {
            Material::CoatedDiffuse {
                reflectance: tb.spectrum(reflectance, cs, loc)?,
                roughness: roughness(r, tb, loc)?,
                thickness: tb.float(thickness, loc)?,
                eta: eta_value(eta, tb, cs, loc)?,
                albedo: tb.spectrum(albedo, cs, loc)?,
                g: tb.float(g, loc)?,
                max_depth: *max_depth,
                n_samples: *n_samples,
            }
        }
        MaterialKind::Subsurface { eta, roughness: r, coefficients, scale, g } => {
            let unbounded = |s: &SpectrumSpec| tb.spectra.unbounded(s, cs).map_err(|x| err(loc, x.to_string()));
            let (sigma_a, sigma_s) = match coefficients {
                SubsurfaceCoefficients::Sigma { sigma_a, sigma_s } => {
                    (unbounded(sigma_a)?.scaled(*scale), unbounded(sigma_s)?.scaled(*scale))
                }
                SubsurfaceCoefficients::Reflectance { reflectance, mfp } => {
                    // pbrt-v4 inverts per sampled wavelength; nimbus per RGB channel of the
                    // reflectance, the coefficients then upsampled as unbounded RGB.
                    let r = tb.spectra.albedo(reflectance, cs).map_err(|x| err(loc, x.to_string()))?.rgb;
                    let mfp = unbounded(mfp)?.rgb * *scale;
                    let table = crate::media::diffusion::DiffusionTable::new(*g, *eta);
                    let (mut a, mut s) = ([0.0f32; 3], [0.0f32; 3]);
                    for c in 0..3 {
                        (a[c], s[c]) = table.coefficients(r[c].clamp(0.0, 1.0), mfp[c].max(f32::MIN_POSITIVE));
                    }
                    (unbounded(&SpectrumSpec::Rgb(a))?, unbounded(&SpectrumSpec::Rgb(s))?)
                }
            };
            subsurface = Some(SubsurfaceMedium { sigma_a, sigma_s, g: *g, loc: loc.clone() });
            Material::Dielectric { eta: SpectrumValue::constant(*eta), roughness: roughness(r, tb, loc)? }
        }
        MaterialKind::Hair { absorption, eta, beta_m, beta_n, alpha } => Material::Hair {
            absorption: match absorption {
                HairAbsorptionSpec::SigmaA(s) => HairAbsorption::SigmaA(tb.spectrum_as(s, cs, loc, true)?),
                HairAbsorptionSpec::Reflectance(r) => HairAbsorption::Reflectance(tb.spectrum(r, cs, loc)?),
                HairAbsorptionSpec::Melanin { eumelanin, pheomelanin } => HairAbsorption::Melanin {
                    eumelanin: tb.float(eumelanin, loc)?,
                    pheomelanin: tb.float(pheomelanin, loc)?,
                },
            },
            eta: tb.float(eta, loc)?,
            beta_m: tb.float(beta_m, loc)?,
            beta_n: tb.float(beta_n, loc)?,
            alpha: tb.float(alpha, loc)?,
        },
        MaterialKind::Measured { filename } => {
            let mut cache = measured.borrow_mut();
            let data = match cache.get(filename) {
                Some(d) => d.clone(),
                None => {
                    let d = std::sync::Arc::new(
                        crate::materials::measured::MeasuredData::read(filename, tb.spectra.film)
                            .map_err(|m| err(e.params.loc("filename").unwrap_or(loc), format!("measured: {m}")))?,
                    );
                    cache.insert(filename.clone(), d.clone());
                    d
                }
            };
            Material::Measured { data: crate::materials::measured::SharedMeasured(data) }
        }
        MaterialKind::Unsupported(_) => Material::Diffuse { reflectance: Tex::Const(SpectrumValue::constant(0.5)) },
    };
    Ok(BuiltMaterial { material, shading, subsurface })
}

/// Emission of an area light: pbrt-v4's photometric normalisation and `power`.
/// ∂(u, v)/∂x and ∂(u, v)/∂y from the screen-space footprint (`dpdx`, `dpdy`) and the
/// surface's ∂p/∂u, ∂p/∂v, by least squares as pbrt-v4's `ComputeDifferentials` does
/// (clamped to ±10⁸; zero where the parameterisation degenerates).
fn uv_footprint(dpdu: Vec3, dpdv: Vec3, dpdx: Vec3, dpdy: Vec3) -> (Vec2, Vec2) {
    let (a00, a01, a11) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let inv_det = 1.0 / (a00 * a11 - a01 * a01);
    let inv_det = if inv_det.is_finite() { inv_det } else { 0.0 };
    let solve = |d: Vec3| {
        let (b0, b1) = (dpdu.dot(d), dpdv.dot(d));
        let du = (a11 * b0 - a01 * b1) * inv_det;
        let dv = (a00 * b1 - a01 * b0) * inv_det;
        let clamp = |v: f32| if v.is_finite() { v.clamp(-1e8, 1e8) } else { 0.0 };
        Vec2::new(clamp(du), clamp(dv))
    };
    (solve(dpdx), solve(dpdy))
}

/// The factor pbrt-v4 scales an image infinite light by for an `illuminance` of `ev`: `ev`
/// over its reference illuminance of the image as read from `path` (the light's own `scale`
/// multiplies on top, as in pbrt-v4).
fn illuminance_factor(ev: f32, path: Option<&std::path::Path>, image: &crate::imageio::Image) -> Result<f32, String> {
    let ordered = match path {
        Some(p) => crate::imageio::pbrt_channel_order(p)?,
        None => None,
    };
    let values = ordered.as_deref().unwrap_or(&image.pixels);
    let k_e = crate::lights::reference_illuminance(values, image.width, image.height);
    Ok(if k_e > 0.0 { ev / k_e } else { 1.0 })
}

/// An area light's radiance `L` (with an image, the factor its texels are scaled by) for a
/// primitive of `area`: pbrt-v4's `power` makes the primitive emit that many watts, counting
/// an image by its mean luminance.
fn area_light_radiance(
    settings: &AreaLightSettings,
    image: Option<&EmissionImage>,
    e: &nimbus_parser::Entity,
    area: f32,
    spectra: &SpectrumResolver<'_>,
) -> Result<SpectrumValue, Error> {
    let l = match image {
        Some(_) => SpectrumValue::constant(1.0),
        None => spectra.illuminant(&settings.radiance, e.color_space).map_err(|m| err(&e.loc, m.to_string()))?,
    };
    let mut scale = settings.scale;
    if let Some(phi) = settings.power {
        let mean = image.map_or(1.0, |i| i.mean_luminance());
        let k_e = mean * if settings.two_sided { 2.0 } else { 1.0 } * area * std::f32::consts::PI;
        if k_e > 0.0 {
            scale *= phi / k_e;
        }
    }
    Ok(l.scaled(scale))
}

/// An area light's emission image, read once for all of a shape's primitives. RGB transport
/// converts each texel into the film's RGB (through its sensor) once, as it does for `L`.
fn emission_image(
    settings: &AreaLightSettings,
    e: &nimbus_parser::Entity,
    spectra: &SpectrumResolver<'_>,
    rgb_transport: bool,
) -> Result<Option<Arc<EmissionImage>>, Error> {
    let Some(path) = &settings.image else { return Ok(None) };
    let loc = e.params.loc("filename").unwrap_or(&e.loc);
    let what = |m: String| err(loc, format!("area light image {}: {m}", nimbus_parser::loc_shown(path)));
    let image = crate::imageio::read_image(path).map_err(what)?;
    let mut image = EmissionImage::new(&image, e.color_space).map_err(what)?;
    if rgb_transport {
        image.map_pixels(|p| spectra.emitted_texel(p, e.color_space));
    }
    Ok(Some(Arc::new(image)))
}

/// A shape's boundary index from its `MediumInterface` and its material.
type InterfaceIds<'a> = dyn Fn(Option<&nimbus_parser::MediumInterface>, u32) -> Result<u32, Error> + 'a;

struct ShapeBuilder<'a> {
    store: ShapeStore,
    textures: &'a TextureBuilder<'a>,
    alphas: Vec<Tex>,
    spectra: SpectrumResolver<'a>,
    material_ids: &'a dyn Fn(&MaterialRef) -> u32,
    interface_ids: &'a InterfaceIds<'a>,
    lights: Vec<Light>,
    triangles: usize,
    mesh_bytes: usize,
    /// The render's transport is RGB (emission images are converted to film RGB once).
    rgb_transport: bool,
}

impl ShapeBuilder<'_> {
    /// Adds a shape's primitives (and their area lights) to `prims`/`bounds`.
    fn add(
        &mut self,
        shape: &ShapeEntity,
        area_lights: &[nimbus_parser::Entity],
        instanced: bool,
        world: Affine3A,
        prims: &mut Vec<Primitive>,
        bounds: &mut Vec<Bounds3>,
    ) -> Result<(), Error> {
        let e = &shape.entity;
        let settings = ShapeSettings::from_entity(shape)?;
        let rev = shape.reverse_orientation;
        let material = (self.material_ids)(&shape.material);
        let interface = (self.interface_ids)(shape.medium_interface.as_ref(), material)?;
        // pbrt-v4 alpha-tests a shape whose "alpha" is a texture or a constant below 1.
        let alpha = match &settings.alpha {
            FloatInput::Value(a) if *a >= 1.0 => NONE,
            a => {
                self.alphas.push(self.textures.float(a, &e.loc)?);
                self.alphas.len() as u32 - 1
            }
        };
        let first = prims.len();
        let mut push = |g: Geometry, store: &ShapeStore| {
            bounds.push(store.bounds(g));
            prims.push(Primitive { geometry: g, material, area_light: NONE, interface, alpha });
        };
        match &settings.kind {
            ShapeKind::Sphere { radius, zmin, zmax, phimax } => {
                self.store.spheres.push(Sphere::new(world, rev, *radius, *zmin, *zmax, *phimax));
                push(Geometry::Sphere(self.store.spheres.len() as u32 - 1), &self.store);
            }
            ShapeKind::Disk { height, radius, inner_radius, phimax } => {
                self.store.disks.push(Disk::new(world, rev, *height, *radius, *inner_radius, *phimax));
                push(Geometry::Disk(self.store.disks.len() as u32 - 1), &self.store);
            }
            ShapeKind::Cylinder { radius, zmin, zmax, phimax } => {
                self.store.cylinders.push(Cylinder::new(world, rev, *radius, *zmin, *zmax, *phimax));
                push(Geometry::Cylinder(self.store.cylinders.len() as u32 - 1), &self.store);
            }
            ShapeKind::TriangleMesh(m) => {
                let mesh = Mesh::new(&world, rev, m.positions, m.normals, m.uvs, m.indices.clone())
                    .with_face_indices(m.face_indices.clone());
                self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
            }
            ShapeKind::BilinearMesh(m) => {
                let mesh = BilinearMesh::new(&world, rev, m.positions, m.normals, m.uvs, m.indices.clone())
                    .with_face_indices(m.face_indices.clone());
                self.add_bilinear(mesh, [material, interface, alpha], prims, bounds);
            }
            ShapeKind::Curve { segments, widths, normals, kind, split_depth } => {
                if shape.area_light.is_some() {
                    return Err(err(&e.loc, "curves cannot be area lights (pbrt-v4 cannot sample them either)"));
                }
                let pieces = 1u32 << split_depth;
                for (k, (cp, w)) in segments.iter().zip(widths).enumerate() {
                    let n = normals.get(k).map(|n| n.map(Vec3::from));
                    let common = self.store.curve_segments.len() as u32;
                    self.store.curve_segments.push(CurveCommon::new(cp.map(Vec3::from), *w, *kind, n, world, rev));
                    for i in 0..pieces {
                        let (u0, u1) = (i as f32 / pieces as f32, (i + 1) as f32 / pieces as f32);
                        self.store.curves.push(Curve::new(common, u0, u1));
                        push(Geometry::Curve(self.store.curves.len() as u32 - 1), &self.store);
                    }
                }
            }
            ShapeKind::LoopSubdiv { mesh: m, levels } => {
                let sub = crate::geometry::loop_subdiv::loop_subdivide(m.positions, &m.indices, *levels)
                    .map_err(|m| err(&e.loc, format!("loopsubdiv: {m}")))?;
                let mesh = Mesh::new(&world, rev, &sub.positions, &sub.normals, &[], sub.indices);
                self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
            }
            ShapeKind::PlyMesh(path, displacement) => {
                let mut ply = read_ply(path).map_err(|m| err(&e.loc, format!("plymesh: {m}")))?;
                if let Some((name, edge)) = displacement {
                    // pbrt-v4 evaluates the texture at the mesh's own (p, uv), nothing else.
                    let tex = self.textures.float(&FloatInput::Texture(name.clone()), &e.loc)?;
                    let textures = &self.textures.textures;
                    ply = crate::geometry::displace::displace(&ply, &world, *edge, |p, uv| {
                        textures.eval_float(tex, &TexContext::at(p, uv, Vec3::ZERO))
                    })
                    .map_err(|m| err(&e.loc, format!("plymesh \"{}\": {m}", path.display())))?;
                }
                if !ply.quads.is_empty() {
                    let quads = BilinearMesh::new(&world, rev, &ply.positions, &ply.normals, &ply.uvs, ply.quads)
                        .with_face_indices(ply.quad_faces);
                    self.add_bilinear(quads, [material, interface, alpha], prims, bounds);
                }
                if !ply.indices.is_empty() {
                    let mesh = Mesh::new(&world, rev, &ply.positions, &ply.normals, &ply.uvs, ply.indices)
                        .with_face_indices(ply.triangle_faces);
                    self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
                }
            }
            ShapeKind::ObjMesh(path) | ShapeKind::GltfMesh(path) => {
                let meshes = if matches!(settings.kind, ShapeKind::ObjMesh(_)) {
                    crate::geometry::obj::read_obj(path)
                } else {
                    crate::geometry::gltf::read_gltf(path)
                }
                .map_err(|m| err(&e.loc, m))?;
                for m in meshes {
                    let mesh = Mesh::new(&world, rev, &m.positions, &m.normals, &m.uvs, m.indices);
                    self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
                }
            }
        }
        if let Some(al) = shape.area_light {
            if instanced {
                return Ok(());
            }
            let al_entity = &area_lights[al];
            let settings = AreaLightSettings::from_entity(al_entity)?;
            let image = emission_image(&settings, al_entity, &self.spectra, self.rgb_transport)?;
            for prim in &mut prims[first..] {
                let area = match prim.geometry {
                    Geometry::Triangle { mesh, tri } => self.store.meshes[mesh as usize].triangle_area(tri),
                    Geometry::Sphere(i) => {
                        let s = &self.store.spheres[i as usize];
                        let scale = uniform_scale(&world)
                            .ok_or_else(|| err(&e.loc, "an emitting sphere must not be scaled non-uniformly"))?;
                        s.area() * scale * scale
                    }
                    Geometry::Disk(i) => self.store.disks[i as usize]
                        .world_area()
                        .ok_or_else(|| err(&e.loc, "an emitting disk must not be scaled non-uniformly"))?,
                    Geometry::Cylinder(i) => self.store.cylinders[i as usize]
                        .world_area()
                        .ok_or_else(|| err(&e.loc, "an emitting cylinder must not be scaled non-uniformly"))?,
                    Geometry::Bilinear { mesh, patch } => self.store.bilinear_meshes[mesh as usize].area(patch),
                    Geometry::Curve(_) | Geometry::Instance(_) => continue,
                };
                let l = area_light_radiance(&settings, image.as_deref(), al_entity, area, &self.spectra)?;
                prim.area_light = self.lights.len() as u32;
                self.lights.push(Light {
                    kind: LightKind::Area {
                        geometry: prim.geometry,
                        l,
                        image: image.clone(),
                        two_sided: settings.two_sided,
                        area,
                        interface: prim.interface,
                        alpha: prim.alpha,
                    },
                    medium: NONE,
                });
            }
        }
        Ok(())
    }

    fn add_bilinear(
        &mut self,
        mesh: BilinearMesh,
        attrs: [u32; 3],
        prims: &mut Vec<Primitive>,
        bounds: &mut Vec<Bounds3>,
    ) {
        let id = self.store.bilinear_meshes.len() as u32;
        self.mesh_bytes += mesh_bytes(mesh.positions.len(), mesh.normals.len(), mesh.uvs.len(), mesh.indices.len());
        let piece = |patch| (Geometry::Bilinear { mesh: id, patch }, mesh.bounds(patch));
        push_pieces(mesh.patch_count(), piece, attrs, prims, bounds);
        self.store.bilinear_meshes.push(mesh);
    }

    fn add_mesh(&mut self, mesh: Mesh, attrs: [u32; 3], prims: &mut Vec<Primitive>, bounds: &mut Vec<Bounds3>) {
        let id = self.store.meshes.len() as u32;
        self.triangles += mesh.triangle_count();
        self.mesh_bytes += mesh_bytes(mesh.positions.len(), mesh.normals.len(), mesh.uvs.len(), mesh.indices.len());
        let piece = |tri| (Geometry::Triangle { mesh: id, tri }, mesh.triangle_bounds(tri));
        push_pieces(mesh.triangle_count(), piece, attrs, prims, bounds);
        self.store.meshes.push(mesh);
    }
}

/// Bytes of a mesh's vertex arrays (positions, normals, uvs) and indices.
fn mesh_bytes(positions: usize, normals: usize, uvs: usize, indices: usize) -> usize {
    positions * 12 + normals * 12 + uvs * 8 + indices * 4
}

/// Adds `n` primitives of one mesh, piece k's geometry and bounds from `piece(k)`, all with
/// the shape's [material, interface, alpha].
fn push_pieces(
    n: usize,
    piece: impl Fn(u32) -> (Geometry, Bounds3),
    [material, interface, alpha]: [u32; 3],
    prims: &mut Vec<Primitive>,
    bounds: &mut Vec<Bounds3>,
) {
    for k in 0..n as u32 {
        let (geometry, b) = piece(k);
        bounds.push(b);
        prims.push(Primitive { geometry, material, area_light: NONE, interface, alpha });
    }
}

fn light(
    l: &nimbus_parser::LightEntity,
    spectra: &SpectrumResolver<'_>,
    transport: Transport,
    medium: u32,
) -> Result<Option<Light>, Error> {
    let e = &l.entity;
    let settings = LightSettings::from_entity(l)?;
    let world = affine(&l.world_from_light.start, &e.loc)?;
    let rgb = |s: &SpectrumSpec| spectra.illuminant(s, e.color_space).map_err(|m| err(&e.loc, m.to_string()));
    let kind = match &settings.kind {
        LightSpec::Point { intensity, from, power } => {
            let mut scale = settings.scale;
            if let Some(phi) = power {
                scale *= phi / (4.0 * std::f32::consts::PI);
            }
            LightKind::Point { p: world.transform_point3(Vec3::from(*from)), i: rgb(intensity)?.scaled(scale) }
        }
        LightSpec::Goniometric { intensity, filename, power } => {
            let Some(path) = filename else {
                // pbrt-v4 warns and the light emits nothing; nimbus says so and leaves it out.
                return Ok(None);
            };
            let image = crate::lights::goniometric::GoniometricImage::read(path, &world)
                .map_err(|m| err(&e.loc, format!("goniometric light: {m}")))?;
            let mut scale = settings.scale;
            if let Some(phi) = power {
                let k_e = 4.0 * std::f32::consts::PI * image.mean();
                if k_e <= 0.0 {
                    return Err(err(&e.loc, "goniometric light: \"power\" is given but its image is black"));
                }
                scale *= phi / k_e;
            }
            LightKind::Goniometric {
                p: world.transform_point3(Vec3::ZERO),
                i: rgb(intensity)?.scaled(scale),
                image: std::sync::Arc::new(image),
            }
        }
        LightSpec::Projection { filename, fov, power } => {
            let image = crate::lights::projection::ProjectionImage::read(filename, *fov, &world)
                .map_err(|m| err(&e.loc, format!("projection light: {m}")))?;
            let mut scale = settings.scale;
            if let Some(phi) = power {
                // pbrt-v4's k_e: the image's luminance over the frustum's solid angle.
                let k_e = crate::color::luminance(image.power_rgb());
                if k_e <= 0.0 {
                    return Err(err(&e.loc, "projection light: \"power\" is given but its image is black"));
                }
                scale *= phi / k_e;
            }
            LightKind::Projection { p: world.transform_point3(Vec3::ZERO), scale, image: std::sync::Arc::new(image) }
        }
        LightSpec::Spot { intensity, from, to, cone_angle, cone_delta_angle, power } => {
            let cos_end = cone_angle.to_radians().cos();
            let cos_start = (cone_angle - cone_delta_angle).to_radians().cos();
            let mut scale = settings.scale;
            if let Some(phi) = power {
                let k_e = 2.0 * std::f32::consts::PI * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0);
                scale *= phi / k_e;
            }
            let p = world.transform_point3(Vec3::from(*from));
            let dir = world.transform_vector3(Vec3::from(*to) - Vec3::from(*from));
            if dir.length_squared() == 0.0 {
                return Err(err(&e.loc, "spot light: \"from\" and \"to\" are the same point"));
            }
            LightKind::Spot {
                p,
                frame: Frame::from_z(dir.normalize()),
                i: rgb(intensity)?.scaled(scale),
                cos_falloff_start: cos_start,
                cos_falloff_end: cos_end,
            }
        }
        LightSpec::Distant { radiance, from, to, illuminance } => {
            let w = world.transform_vector3(Vec3::from(*from) - Vec3::from(*to)).normalize();
            let scale = settings.scale * illuminance.unwrap_or(1.0);
            LightKind::Distant { w, l: rgb(radiance)?.scaled(scale) }
        }
        LightSpec::Infinite { radiance, filename, illuminance, portal: Some(corners) } => {
            // pbrt-v4 renders `L` with a portal as a 1×1 image of its RGB.
            let cs = e.color_space;
            let image = match (radiance, filename) {
                (_, Some(path)) => crate::imageio::read_image(path).map_err(|m| err(&e.loc, m))?,
                (Some(SpectrumSpec::Rgb(c)), None) => {
                    let mut image = crate::imageio::Image::new(1, 1);
                    image.pixels[0] = Rgb::from(*c);
                    image
                }
                (Some(_), None) => {
                    return Err(err(
                        &e.loc,
                        "infinite light with a portal: give \"rgb L\" or an image (nimbus does not turn other spectra \
                         into the RGB image pbrt-v4 makes of them)",
                    ));
                }
                (None, None) => return Err(err(&e.loc, "infinite light without radiance or image")),
            };
            let mut scale = settings.scale;
            if let Some(ev) = illuminance {
                scale *= illuminance_factor(*ev, filename.as_deref(), &image).map_err(|m| err(&e.loc, m))?;
            }
            // The corners are world-space points (pbrt-v4 does not apply the light's transform
            // to them), the image is oriented by the light's transform.
            let loc = e.params.loc("portal").unwrap_or(&e.loc);
            let mut map = PortalMap::new(&image, cs, world, scale, corners.map(Vec3::from))
                .map_err(|m| err(loc, format!("infinite light: {m}")))?;
            if transport == Transport::Rgb && !spectra.sensor.is_passthrough() {
                map.map_pixels(|p| spectra.emitted_texel(p, cs));
            }
            LightKind::PortalInfinite(Box::new(map))
        }
        LightSpec::Infinite { radiance: Some(r), illuminance, .. } => {
            let scale = settings.scale * illuminance.map_or(1.0, |ev| ev / std::f32::consts::PI);
            LightKind::UniformInfinite { l: rgb(r)?.scaled(scale) }
        }
        LightSpec::Infinite { radiance: None, filename: Some(path), illuminance, .. } => {
            let cs = e.color_space;
            let image = crate::imageio::read_image(path).map_err(|m| err(&e.loc, m))?;
            let mut scale = settings.scale;
            if let Some(ev) = illuminance {
                scale *= illuminance_factor(*ev, Some(path), &image).map_err(|m| err(&e.loc, m))?;
            }
            let mut map = EnvironmentMap::new(&image, cs, world, scale).map_err(|m| err(&e.loc, m))?;
            // RGB transport sees each texel's film RGB; through a camera sensor that is the
            // texel's illuminant spectrum seen by the sensor (spectral transport converts at
            // lookup).
            if transport == Transport::Rgb && !spectra.sensor.is_passthrough() {
                map.map_pixels(|p| spectra.emitted_texel(p, cs));
            }
            LightKind::ImageInfinite(Box::new(map))
        }
        LightSpec::Infinite { .. } => {
            return Err(err(&e.loc, "infinite light without radiance or image"));
        }
    };
    Ok(Some(Light { kind, medium }))
}

/// Names of the media that the camera, lights or boundary surfaces refer to.
fn used_media(desc: &SceneDescription) -> std::collections::HashSet<&str> {
    let shapes = desc.shapes.iter().chain(desc.instance_definitions.iter().flat_map(|d| d.shapes.iter()));
    let from_shapes = shapes.filter_map(|s| s.medium_interface.as_ref()).flat_map(|mi| [&mi.inside, &mi.outside]);
    std::iter::once(&desc.camera.medium)
        .chain(desc.lights.iter().map(|l| &l.medium))
        .chain(from_shapes)
        .filter_map(|n| n.as_deref())
        .collect()
}

/// Creates a render-time medium from its settings.
fn build_medium(
    m: &nimbus_parser::MediumEntity,
    settings: &MediumSettings<'_>,
    spectra: &SpectrumResolver<'_>,
    transport: Transport,
) -> Result<Medium, Error> {
    let e = &m.entity;
    let cs = e.color_space;
    let unbounded = |s: &SpectrumSpec| spectra.unbounded(s, cs).map_err(|x| err(&e.loc, x.to_string()));
    let sigma_a = unbounded(&settings.sigma_a)?.scaled(settings.scale);
    let sigma_s = unbounded(&settings.sigma_s)?.scaled(settings.scale);
    let le = match &settings.le {
        Some(s) => spectra.illuminant(s, cs).map_err(|x| err(&e.loc, x.to_string()))?.scaled(settings.le_scale),
        None => SpectrumValue::ZERO,
    };
    let world = affine(&m.world_from_medium.start, &e.loc)?;
    let g = settings.g;
    let dense = |n: [u32; 3], v: &[f32]| {
        DenseGrid::new(glam::UVec3::from(n), v.to_vec()).ok_or_else(|| err(&e.loc, "grid size mismatch"))
    };
    Ok(match &settings.kind {
        MediumSpec::Homogeneous => Medium::homogeneous(m.name.clone(), sigma_a, sigma_s, le, g),
        MediumSpec::UniformGrid { n, bounds, density, temperature, le_scale_grid } => {
            // pbrt-v4 keeps `Lescale` as a grid; without one it is a single sample of 1.
            let scale_grid = || match le_scale_grid {
                Some(v) => dense(*n, v),
                None => dense([1, 1, 1], &[1.0]),
            };
            let emission = match temperature {
                Some(t) => Emission::Temperature {
                    grid: Field::Dense(dense(*n, t.values.unwrap_or(&[]))?),
                    offset: t.offset,
                    scale: t.scale,
                    le_scale: settings.le_scale,
                    scale_grid: Some(scale_grid()?),
                    table: Box::new(BlackbodyRgbTable::for_sensor(spectra.sensor)),
                },
                None if !le.is_zero() => Emission::Radiance { le, scale: scale_grid()? },
                None => Emission::None,
            };
            let b = Bounds3::new(Vec3::from(bounds[0]), Vec3::from(bounds[1]));
            Medium::grid(
                m.name.clone(),
                world,
                b,
                Density::Field(Field::Dense(dense(*n, density)?)),
                sigma_a,
                sigma_s,
                emission,
                g,
            )
        }
        MediumSpec::Cloud { bounds, density, wispiness, frequency } => {
            let b = Bounds3::new(Vec3::from(bounds[0]), Vec3::from(bounds[1]));
            let cloud = crate::media::cloud::Cloud { density: *density, wispiness: *wispiness, frequency: *frequency };
            // pbrt-v4's procedural cloud does not emit.
            let emission = Emission::None;
            Medium::grid(m.name.clone(), world, b, Density::Cloud(cloud), sigma_a, sigma_s, emission, g)
        }
        MediumSpec::RgbGrid { n, bounds, sigma_a: ga, sigma_s: gs, le: gl } => {
            let scale = settings.scale;
            // Voxels packed for the transport: film RGB, or the sigmoid polynomial and scale of
            // the scene's RGB as a spectrum (pbrt-v4's SampledGrid of RGB spectra).
            let spectral = transport == Transport::Spectral;
            let rgb_grid = |v: &[[f32; 3]], f: &(dyn Fn(Rgb) -> Vec4 + Sync)| {
                use rayon::prelude::*;
                DenseGrid::new(glam::UVec3::from(*n), v.par_iter().map(|c| f(Rgb::from(*c))).collect())
                    .ok_or_else(|| err(&e.loc, "grid size mismatch"))
            };
            let coefficient = |c: Rgb| {
                let c = if spectral { c } else { spectra.grid_coefficient(c, cs) };
                pack_voxel(c * scale, RgbRole::Unbounded, cs, spectral)
            };
            let emitted = |c: Rgb| {
                let c = if spectral { c } else { spectra.emitted_texel(c, cs) };
                pack_voxel(c, RgbRole::Illuminant, cs, spectral)
            };
            let chromatic =
                [ga, gs].iter().filter_map(|g| g.as_ref()).any(|g| g.iter().any(|c| c[0] != c[1] || c[1] != c[2]));
            let sa = ga.map(|v| rgb_grid(v, &coefficient)).transpose()?;
            let ss = gs.map(|v| rgb_grid(v, &coefficient)).transpose()?;
            let le_grid = gl.map(|v| rgb_grid(v, &emitted)).transpose()?;
            let b = Bounds3::new(Vec3::from(bounds[0]), Vec3::from(bounds[1]));
            // pbrt-v4 does not normalise rgbgrid emission: an RGB illuminant spectrum whose film
            // RGB is ∫ȳ times the voxel's.
            let le_scale = settings.le_scale * crate::spectra::CIE_Y_INTEGRAL as f32;
            Medium::rgb_grid(m.name.clone(), world, b, sa, ss, le_grid, le_scale, cs, g, chromatic, spectral)
        }
        MediumSpec::Vdb { openvdb, filename, grid_name, temperature_name, temperature } => {
            let loc = e.params.loc("filename").unwrap_or(&e.loc);
            let file = VdbFile::open(filename, *openvdb).map_err(|x| err(loc, x.to_string()))?;
            let density = file.read_grid(grid_name).map_err(|x| err(loc, x.to_string()))?;
            // pbrt-v4 reads the temperature grid when the file has one.
            let emission = if file.has_grid(temperature_name) {
                let t = file.read_grid(temperature_name).map_err(|x| err(loc, x.to_string()))?;
                Emission::Temperature {
                    grid: Field::Sparse(Box::new(t)),
                    offset: temperature.offset,
                    scale: temperature.scale,
                    le_scale: settings.le_scale,
                    scale_grid: None,
                    table: Box::new(BlackbodyRgbTable::for_sensor(spectra.sensor)),
                }
            } else {
                Emission::None
            };
            let b = density.world_bounds();
            Medium::grid(
                m.name.clone(),
                world,
                b,
                Density::Field(Field::Sparse(Box::new(density))),
                sigma_a,
                sigma_s,
                emission,
                g,
            )
        }
    })
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

#[cfg(test)]
mod footprint_tests {
    use super::*;

    #[test]
    fn uv_footprints_solve_the_tangent_plane() {
        // p = (2u, 3v, 0): a step (0.2, 0.3, 0) is (du, dv) = (0.1, 0.1); one along the
        // normal has no (u, v) component; a degenerate parameterisation gives zero.
        let (dx, dy) =
            uv_footprint(Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0), Vec3::new(0.2, 0.3, 0.0), Vec3::Z);
        assert!((dx - Vec2::new(0.1, 0.1)).length() < 1e-6 && dy.length() < 1e-6, "{dx} {dy}");
        // A sheared parameterisation: p = u·(1, 0, 0) + v·(1, 1, 0).
        let (dx, _) = uv_footprint(Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 0.5, 0.0), Vec3::ZERO);
        assert!((dx - Vec2::new(-0.5, 0.5)).length() < 1e-6, "{dx}");
        let (dx, dy) = uv_footprint(Vec3::X, Vec3::X, Vec3::ONE, Vec3::ONE);
        assert!(dx == Vec2::ZERO && dy == Vec2::ZERO);
    }
}
