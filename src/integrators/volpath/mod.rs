//! `volpath`: pbrt-v4's volumetric path tracer, the reference every other method is checked
//! against. The loop itself lives in [`crate::integrators::common::path`].

mod settings;

pub use settings::{LightSamplerKind, VolPathSettings};

use super::RayIntegrator;
use super::common::{NoObserver, PathConfig, RayStats, trace_path};
use crate::color::Channels;
use crate::geometry::Ray;
use crate::samplers::Sampler;
use crate::scene::Scene;

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
        "volpath"
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
