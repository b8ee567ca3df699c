//! Integrators: one folder per method, each with its settings and its entry in the
//! [`registry`], which maps the names scenes and `--integrator` use to them; the traits every
//! method implements to render.

pub mod common;
pub mod guided;
pub mod image_pass;
pub mod pathgraph;
pub mod prepared;
pub mod radiancegraph;
pub mod registry;
pub mod simplevolpath;
pub mod volpath;

pub use registry::{INTEGRATOR_NAMES, MethodSettings, REFERENCE, canonical_name, pbrt_v4_substitute};

use nimbus_parser::{Entity, Error};

use crate::channels::Channels;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::samplers::Sampler;
use crate::scene::Scene;
use crate::spectra::{SampledSpectrum, SampledWavelengths};
use common::RayStats;

/// Settings of the integrator a scene asks for: the method's own (see [`registry`]), read by
/// the method's entry in [`registry::METHODS`].
#[derive(Debug)]
pub struct IntegratorSettings(Box<dyn MethodSettings>);

impl Clone for IntegratorSettings {
    fn clone(&self) -> IntegratorSettings {
        IntegratorSettings(self.0.clone_box())
    }
}

impl std::ops::Deref for IntegratorSettings {
    type Target = dyn MethodSettings;
    fn deref(&self) -> &(dyn MethodSettings + 'static) {
        self.0.as_ref()
    }
}

impl std::ops::DerefMut for IntegratorSettings {
    fn deref_mut(&mut self) -> &mut (dyn MethodSettings + 'static) {
        self.0.as_mut()
    }
}

impl IntegratorSettings {
    /// Reads the integrator entity; `name_override` replaces the scene's choice (the
    /// parameters that method shares with the scene's, such as `maxdepth`, are kept).
    pub fn from_entity(e: &Entity, name_override: Option<&str>) -> Result<IntegratorSettings, Error> {
        let name = name_override.unwrap_or(&e.name);
        if let Some(method) = registry::find(name) {
            return Ok(IntegratorSettings((method.read)(e)?));
        }
        match pbrt_v4_substitute(name) {
            Some(Ok(_)) => Ok(IntegratorSettings((registry::METHODS[0].read)(e)?)),
            Some(Err(reason)) => Err(Error::new(
                &e.loc,
                format!(
                    "integrator \"{name}\": {reason} (use `Integrator \"{REFERENCE}\"` or `--integrator {REFERENCE}`)"
                ),
            )),
            None => Err(Error::new(
                &e.loc,
                format!("integrator \"{name}\" is not available in nimbus (it has: {})", INTEGRATOR_NAMES.join(", ")),
            )),
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

    /// The method's name.
    pub fn name(&self) -> &'static str {
        self.0.method().name
    }

    /// The method's own settings, if they are of type `T`.
    pub fn settings<T: 'static>(&self) -> Option<&T> {
        self.0.as_any().downcast_ref()
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
/// camera rays (see [`image_pass::ImagePass`]).
pub trait ImageIntegrator: Sync {
    /// One sample of every pixel: (accumulator index, filter weight, RGB radiance) for each
    /// camera ray of `pass`, handed to `out` in any order (no image-sized list of them is
    /// needed); returns the rays traced.
    fn sample_image(
        &self,
        scene: &Scene,
        pass: &image_pass::ImagePass<'_>,
        out: &mut dyn FnMut(PixelValue),
    ) -> RayStats;

    /// Whether the next sample, the render's `sample_index`th (paired and unpaired samples
    /// counted), should be a whole-image one, for a method that pairs a biased
    /// estimate with an unbiased one ([`PixelValue::unbiased`]), given the film's [`Outlook`]
    /// (computed only when `outlook` is called; None until it can tell). False: the renderer
    /// takes them per camera ray from `li`,
    /// which must then be the same unbiased estimate, and the film pools them with the
    /// unbiased side of its combination. Other methods keep the default.
    fn image_sample_pays(&self, _sample_index: u32, _outlook: &dyn Fn() -> Option<Outlook>) -> bool {
        true
    }
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
    /// An unbiased estimate of the same pixel from the same sample, for a method whose `l`
    /// is biased (a graph's aggregate): the film then combines the two per pixel, trusting
    /// `l` as far as its measured disagreement with this estimate allows, so that the image
    /// converges whatever `l`'s bias (`render/combine.rs`). None: `l` is the estimate.
    pub unbiased: Option<Rgb>,
}

/// For a method that hands the film a biased estimate beside an unbiased one
/// ([`PixelValue::unbiased`]): what one more sample of each kind would take off the film's
/// combined image's squared error, summed over the pixels from the samples so far
/// (`render/combine.rs`). A method whose paired sample costs k times an unbiased one alone
/// pays for the pair while `paired > (k − 1) · unpaired`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outlook {
    /// One more sample of the unbiased estimate alone.
    pub unpaired: f64,
    /// What a paired sample takes off beyond that: the biased estimate's share.
    pub paired: f64,
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
