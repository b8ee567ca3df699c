//! `volpath`: pbrt-v4's volumetric path tracer, the reference every other method is checked
//! against. The loop itself lives in [`crate::integrators::common::path`].

mod settings;

pub use settings::{LightSamplerKind, VolPathSettings};

use super::RayIntegrator;
use super::common::{NoObserver, PathConfig, RayStats, trace_path};
use super::registry::{Method, MethodSettings};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::samplers::Sampler;
use crate::scene::Scene;

/// The registry's entry (`volpathcustom` is the radiance-graph thesis's name for it).
pub const METHOD: Method = Method { name: "volpath", aliases: &["volpathcustom"], read };

fn read(e: &nimbus_parser::Entity) -> Result<Box<dyn MethodSettings>, nimbus_parser::Error> {
    Ok(Box::new(VolPathSettings::from_entity(e)?))
}

impl MethodSettings for VolPathSettings {
    fn method(&self) -> &'static Method {
        &METHOD
    }

    fn set_max_depth(&mut self, depth: u32) -> crate::Result<()> {
        self.max_depth = depth;
        Ok(())
    }

    fn light_sampler(&self) -> LightSamplerKind {
        self.light_sampler
    }

    fn create(&self, _scene: &Scene) -> crate::Result<Box<dyn super::Integrator>> {
        Ok(Box::new(VolPath::new(self)))
    }
}

/// The volumetric path tracer.
pub struct VolPath {
    config: PathConfig,
}

impl VolPath {
    /// A tracer with the given settings.
    pub fn new(s: &VolPathSettings) -> VolPath {
        VolPath { config: PathConfig::volpath(s.max_depth, s.regularize) }
    }

    /// A tracer with an explicit loop configuration (tests switch next-event estimation off).
    pub fn with_config(config: PathConfig) -> VolPath {
        VolPath { config }
    }
}

impl RayIntegrator for VolPath {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn li<C: Channels>(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut C::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> C {
        trace_path(scene, ray, scene.camera_medium, lambda, sampler, &self.config, &mut NoObserver, stats)
    }
}
