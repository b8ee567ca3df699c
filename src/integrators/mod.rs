//! Integrators: one folder per method, each with its settings. The registry maps the names
//! scenes and `--integrator` use to settings readers and implementations.

pub mod common;
pub mod guided;
pub mod pathgraph;
pub mod radiancegraph;
pub mod simplevolpath;
pub mod volpath;

use nimbus_parser::{Entity, Error};

use crate::color::{Channels, Rgb};
use crate::geometry::Ray;
use crate::samplers::Sampler;
use crate::scene::Scene;
use crate::spectra::{SampledSpectrum, SampledWavelengths};
use common::RayStats;

/// Settings of the integrator a scene asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum IntegratorSettings {
    /// `volpath`
    VolPath(volpath::VolPathSettings),
    /// `simplevolpath`
    SimpleVolPath(simplevolpath::SimpleVolPathSettings),
    /// `radiancegraph` (`graph` in the thesis's scenes)
    RadianceGraph(radiancegraph::RadianceGraphSettings),
    /// `pathgraph`
    PathGraph(pathgraph::PathGraphSettings),
    /// `guided`
    Guided(guided::GuidedSettings),
}

/// The integrator a scene's name stands for: the radiance-graph thesis's scenes name their
/// VolPath reference `volpathcustom` (pbrt-v4's volpath with the thesis's analysis hooks and
/// the same parameters) and its method `graph`.
pub fn canonical_name(name: &str) -> &str {
    match name {
        "volpathcustom" => "volpath",
        "graph" => "radiancegraph",
        other => other,
    }
}

/// What nimbus says about a pbrt-v4 integrator it does not have: `Ok(note)` when the scene
/// renders with `volpath` instead (the note says why that is the same image), `Err(reason)`
/// when it is refused (the reason names the nimbus integrator that computes its image).
/// `None` for names nimbus has or does not know.
pub fn pbrt_v4_substitute(name: &str) -> Option<Result<&'static str, &'static str>> {
    Some(match name {
        "path" | "simplepath" => {
            Ok("pbrt-v4's surface path tracer runs as \"volpath\", which computes the same image for surfaces \
             (and, unlike it, also renders the scene's participating media)")
        }
        "randomwalk" => Ok("pbrt-v4's random-walk integrator runs as \"volpath\": the same image (the random walk's \
             expectation) with next-event estimation and far less noise"),
        "bdpt" => Err("bidirectional path tracing is not in nimbus; \"volpath\" converges to the same image"),
        "mlt" => Err("Metropolis light transport is not in nimbus; \"volpath\" converges to the same image"),
        "sppm" => {
            Err("stochastic progressive photon mapping is not in nimbus; \"volpath\" converges to the same image")
        }
        "lightpath" => Err("light tracing is not in nimbus; \"volpath\" converges to the same image"),
        "ambientocclusion" => {
            Err("ambient occlusion is not light transport and nimbus has no integrator that computes it")
        }
        "function" => Err("pbrt-v4's function-integration test harness is not a renderer; nimbus has none"),
        _ => return None,
    })
}

/// Names of the integrators nimbus has.
pub const INTEGRATOR_NAMES: &[&str] = &["volpath", "simplevolpath", "radiancegraph", "pathgraph", "guided"];

impl IntegratorSettings {
    /// Reads the integrator entity; `name_override` replaces the scene's choice (the
    /// parameters that method shares with the scene's, such as `maxdepth`, are kept).
    pub fn from_entity(e: &Entity, name_override: Option<&str>) -> Result<IntegratorSettings, Error> {
        match canonical_name(name_override.unwrap_or(&e.name)) {
            "volpath" => Ok(IntegratorSettings::VolPath(volpath::VolPathSettings::from_entity(e)?)),
            "simplevolpath" => {
                Ok(IntegratorSettings::SimpleVolPath(simplevolpath::SimpleVolPathSettings::from_entity(e)?))
            }
            "radiancegraph" => {
                Ok(IntegratorSettings::RadianceGraph(radiancegraph::RadianceGraphSettings::from_entity(e)?))
            }
            "pathgraph" => Ok(IntegratorSettings::PathGraph(pathgraph::PathGraphSettings::from_entity(e)?)),
            "guided" => Ok(IntegratorSettings::Guided(guided::GuidedSettings::from_entity(e)?)),
            other => match pbrt_v4_substitute(other) {
                Some(Ok(_)) => Ok(IntegratorSettings::VolPath(volpath::VolPathSettings::from_entity(e)?)),
                Some(Err(reason)) => Err(Error::new(
                    &e.loc,
                    format!(
                        "integrator \"{other}\": {reason} (use `Integrator \"volpath\"` or `--integrator volpath`)"
                    ),
                )),
                None => Err(Error::new(
                    &e.loc,
                    format!(
                        "integrator \"{other}\" is not available in nimbus (it has: {})",
                        INTEGRATOR_NAMES.join(", ")
                    ),
                )),
            },
        }
    }

    /// The note for a scene whose integrator runs as another (pbrt-v4's `path` as
    /// `volpath`), unless `name_override` chose the method.
    pub fn substitution_note(e: &Entity, name_override: Option<&str>) -> Option<nimbus_parser::Warning> {
        if name_override.is_some() {
            return None;
        }
        match pbrt_v4_substitute(&e.name) {
            Some(Ok(note)) => Some(nimbus_parser::Warning::new(&e.loc, format!("integrator \"{}\": {note}", e.name))),
            _ => None,
        }
    }

    /// Sets the longest path (`--maxdepth`, the radiance-graph thesis's pbrt-v4 flag, which
    /// overrides the scene's `maxdepth`). The radiance graph has no such parameter: its light
    /// paths' depth is the graph config's, and saying so beats ignoring the flag.
    pub fn set_max_depth(&mut self, depth: u32) -> Result<(), String> {
        match self {
            IntegratorSettings::VolPath(s) => s.max_depth = depth,
            IntegratorSettings::SimpleVolPath(s) => s.max_depth = depth,
            IntegratorSettings::PathGraph(s) => s.max_depth = depth,
            IntegratorSettings::Guided(s) => s.max_depth = depth,
            IntegratorSettings::RadianceGraph(_) => {
                return Err("--maxdepth: radiancegraph has no maxdepth; its light paths' depth is the graph \
                            config's graphBuilder.maxDepth"
                    .into());
            }
        }
        Ok(())
    }

    /// The method's name.
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorSettings::VolPath(_) => "volpath",
            IntegratorSettings::SimpleVolPath(_) => "simplevolpath",
            IntegratorSettings::RadianceGraph(_) => "radiancegraph",
            IntegratorSettings::PathGraph(_) => "pathgraph",
            IntegratorSettings::Guided(_) => "guided",
        }
    }

    /// Creates the integrator for `scene` (as pbrt-v4's `Integrator::Create` receives the
    /// scene's lights: methods may build per-scene tables here, and methods that precompute
    /// do it here: the radiance graph loads or builds its graph). Fails with a message for
    /// the user when the precomputation cannot run.
    pub fn create(&self, scene: &Scene) -> Result<Box<dyn Integrator>, String> {
        Ok(match self {
            IntegratorSettings::VolPath(s) => Box::new(volpath::VolPath::new(s)),
            IntegratorSettings::SimpleVolPath(s) => Box::new(simplevolpath::SimpleVolPath::new(s, scene)),
            IntegratorSettings::RadianceGraph(s) => Box::new(radiancegraph::create(s, scene)?),
            IntegratorSettings::PathGraph(s) => Box::new(pathgraph::create(s, scene)?),
            IntegratorSettings::Guided(s) => Box::new(guided::create(s, scene)?),
        })
    }
}

/// A light transport method: radiance along camera rays, in each representation nimbus
/// transports. Per-ray methods implement [`RayIntegrator`] once, generic over the channels,
/// and get this trait from it.
pub trait Integrator: Sync {
    /// The method's name (as in scene files).
    fn name(&self) -> &'static str;

    /// Radiance arriving at the camera along `ray` as RGB, one sample.
    fn li_rgb(&self, scene: &Scene, ray: Ray, lambda: &mut (), sampler: &mut Sampler, stats: &mut RayStats) -> Rgb;

    /// Radiance arriving at the camera along `ray` at the wavelengths `lambda`, one sample.
    fn li_spectral(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> SampledSpectrum;

    /// Methods that work on the whole image (record every pixel's path → solve → write)
    /// return themselves here; the renderer then asks them for whole-image samples instead
    /// of calling `li` per camera ray. Per-ray methods keep the default and pay nothing.
    fn whole_image(&self) -> Option<&dyn ImageIntegrator> {
        None
    }

    /// Lines for `--stats` about the method's own work (memory, stage times), after a render.
    fn report(&self) -> Vec<String> {
        Vec::new()
    }

    /// Bytes of a scene-wide structure the method precomputed before rendering, at its
    /// largest (the radiance graph while it was built or loaded): reported apart from the
    /// render's memory, since it is the method's trade of memory for time. 0 for methods
    /// that precompute nothing.
    fn precomputed_bytes(&self) -> usize {
        0
    }
}

/// A method that estimates every pixel at once: one sample of the image from one pass of
/// camera rays (see [`crate::render::ImagePass`]).
pub trait ImageIntegrator: Sync {
    /// One sample of every pixel: (accumulator index, filter weight, RGB radiance) for each
    /// camera ray of `pass`, handed to `out` in any order (no image-sized list of them is
    /// needed); returns the rays traced.
    fn sample_image(
        &self,
        scene: &Scene,
        pass: &crate::render::ImagePass<'_>,
        out: &mut dyn FnMut(PixelValue),
    ) -> RayStats;
}

/// One camera sample's value for the film, from an [`ImageIntegrator`].
#[derive(Clone, Copy, Debug)]
pub struct PixelValue {
    /// The pixel's index in the film (row-major within the pixel bounds).
    pub index: u32,
    /// The filter weight of the camera sample.
    pub weight: f32,
    /// RGB radiance.
    pub l: Rgb,
}

/// A method that estimates radiance one camera ray at a time, written once for every
/// representation of light (monomorphised for each).
pub trait RayIntegrator: Sync {
    /// The method's name (as in scene files).
    fn name(&self) -> &'static str;

    /// Radiance arriving at the camera along `ray` at the wavelengths `lambda`, one sample.
    fn li<C: Channels>(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut C::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> C;

    /// Lines for `--stats` about the method's own work (see [`Integrator::report`]).
    fn report(&self) -> Vec<String> {
        Vec::new()
    }

    /// See [`Integrator::precomputed_bytes`].
    fn precomputed_bytes(&self) -> usize {
        0
    }
}

impl<T: RayIntegrator> Integrator for T {
    fn name(&self) -> &'static str {
        RayIntegrator::name(self)
    }

    fn li_rgb(&self, scene: &Scene, ray: Ray, lambda: &mut (), sampler: &mut Sampler, stats: &mut RayStats) -> Rgb {
        self.li::<Rgb>(scene, ray, lambda, sampler, stats)
    }

    fn li_spectral(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> SampledSpectrum {
        self.li::<SampledSpectrum>(scene, ray, lambda, sampler, stats)
    }

    fn report(&self) -> Vec<String> {
        RayIntegrator::report(self)
    }

    fn precomputed_bytes(&self) -> usize {
        RayIntegrator::precomputed_bytes(self)
    }
}
