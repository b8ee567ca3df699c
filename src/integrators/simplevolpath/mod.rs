//! `simplevolpath`: the simplified path-tracing architecture (Shirley, Wang, Zimmerman et al.,
//! "A Simplified Path Tracing Architecture", technical report): no shadow rays, no
//! direct/indirect split; at every scattering event one direction drawn from a mixture
//! density over the BSDF or phase function, the luminaires and the environment, weighted by
//! Equation 2 with the whole mixture density; participating media as probabilistic surfaces
//! found by the same intersection routine as surfaces.
//!
//! pbrt-v4 has an integrator of this name (a minimal reference volumetric path tracer); nimbus
//! keeps its name and its `maxdepth` parameter and implements the paper. The files follow the
//! paper (see README.md next to this file for the section and equation map and every
//! deviation):
//!
//! - `mixture.rs`: §3, the mixture density — sampling and evaluating p over its components;
//! - `intersection.rs`: §4, the probabilistic intersection — surfaces and media, one interface;
//! - `tracer.rs`: §2 and Eq. 2 and 5, the shading loop.

mod intersection;
mod mixture;
mod settings;
mod tracer;

pub use settings::SimpleVolPathSettings;

use super::RayIntegrator;
use super::common::RayStats;
use super::registry::{Method, MethodSettings};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::samplers::Sampler;
use crate::scene::Scene;
use mixture::Mixture;
use tracer::DeltaLights;

/// The registry's entry.
pub const METHOD: Method = Method { name: "simplevolpath", aliases: &[], read };

fn read(e: &nimbus_parser::Entity) -> Result<Box<dyn MethodSettings>, nimbus_parser::Error> {
    Ok(Box::new(SimpleVolPathSettings::from_entity(e)?))
}

impl MethodSettings for SimpleVolPathSettings {
    fn method(&self) -> &'static Method {
        &METHOD
    }

    fn set_max_depth(&mut self, depth: u32) -> crate::Result<()> {
        self.max_depth = depth;
        Ok(())
    }

    /// The mixture reaches a luminaire only by tracing the direction it sampled towards it,
    /// so a light no ray can hit (pbrt-v4's invisible alpha-0 area light) would add nothing:
    /// such a scene is refused by name rather than rendered without that light.
    fn check(&self, scene: &Scene) -> crate::Result<()> {
        let invisible =
            scene.lights.iter().any(|l| matches!(l.kind, crate::lights::LightKind::Area { invisible: true, .. }));
        if invisible {
            return Err(crate::Error::Unsupported(
                "simplevolpath reaches area lights by tracing towards them, and this scene has an invisible one \
                 (a shape of constant alpha 0, which no ray hits): render it with volpath"
                    .into(),
            ));
        }
        // Its probabilistic intersection reads a medium's own coefficients.
        if scene.entered_medium().is_some() {
            return Err(crate::Error::Unsupported(
                "simplevolpath reads a medium's coefficients where its rays are, and this scene has a subsurface \
                 material with textured inputs (coefficients taken where a path enters): render it with volpath"
                    .into(),
            ));
        }
        Ok(())
    }

    fn create(&self, scene: &Scene) -> crate::Result<Box<dyn super::Integrator>> {
        self.check(scene)?;
        Ok(Box::new(SimpleVolPath::new(self, scene)))
    }
}

/// The simplified path tracer, with the densities of one scene.
pub struct SimpleVolPath {
    max_depth: u32,
    mixture: Mixture,
    delta: DeltaLights,
}

impl SimpleVolPath {
    /// The tracer for `scene` with the given settings (builds the light and environment
    /// tables the mixture samples from).
    pub fn new(s: &SimpleVolPathSettings, scene: &Scene) -> SimpleVolPath {
        SimpleVolPath { max_depth: s.max_depth, mixture: Mixture::new(scene, s), delta: DeltaLights::new(scene) }
    }
}

impl RayIntegrator for SimpleVolPath {
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
        tracer::trace(scene, &self.mixture, &self.delta, self.max_depth, ray, lambda, sampler, stats)
    }
}
