//! `guided`: path guiding in participating media (Deng, Wang, Wang and Holzschuch 2020). Before
//! rendering, photons from the lights train an SD-tree per medium ([`train`]); camera paths
//! then run the shared path loop, whose observer hook draws each medium scattering direction
//! from the product of phase function and learned radiance by resampling, or from their
//! mixture by MIS, depending on the medium's anisotropy ([`sampling`]). Next-event estimation
//! is MIS-weighted against the guided technique's density. Surfaces are not guided.

mod cache;
mod dtree;
mod photons;
mod sampling;
mod sdtree;
mod settings;
mod train;

pub use settings::GuidedSettings;
pub use train::Guide;

use glam::{Vec2, Vec3};

use super::RayIntegrator;
use super::common::{GuidedSample, PathConfig, PathObserver, RayStats, trace_path};
use crate::color::Channels;
use crate::geometry::Ray;
use crate::media::phase::HenyeyGreenstein;
use crate::samplers::Sampler;
use crate::sampling::rng::{Pcg32, hash_sample};
use crate::scene::Scene;
use sampling::Strategy;

/// The guided path tracer.
pub struct Guided {
    config: PathConfig,
    strategy: Strategy,
    guide: Guide,
    /// Where the guide came from, for `--stats`.
    source: String,
    /// Which media are guided and why, for `--stats`.
    media: String,
}

/// Trains the guide (or loads it from the cache file) and creates the integrator.
pub fn create(settings: &GuidedSettings, scene: &Scene) -> Result<Guided, String> {
    let (mut guide, source) = match &settings.cache {
        Some(path) if path.exists() => {
            let g = cache::load(path, scene, settings)?;
            (g, format!("loaded from {}", path.display()))
        }
        Some(path) => {
            let g = train::train(scene, settings);
            cache::save(path, scene, settings, &g)?;
            (g, format!("trained, saved to {}", path.display()))
        }
        None => (train::train(scene, settings), "trained".to_string()),
    };
    guide.activate(settings.refracted_share);
    let media = guide
        .trees
        .iter()
        .enumerate()
        .filter(|(_, t)| t.is_some())
        .map(|(m, _)| {
            let verdict = if guide.active[m] { "guided" } else { "not guided" };
            format!("{} {verdict} ({:.0} % refracted)", scene.media[m].name, 100.0 * guide.refracted[m])
        })
        .collect::<Vec<_>>()
        .join(", ");
    Ok(Guided {
        config: PathConfig::volpath(settings.max_depth, settings.regularize),
        strategy: settings.strategy,
        guide,
        source,
        media,
    })
}

impl Guided {
    /// The trained trees.
    pub fn guide(&self) -> &Guide {
        &self.guide
    }
}

/// The path loop's observer: guides scattering in media, records nothing.
struct GuidingObserver<'a> {
    guide: &'a Guide,
    /// Whether any medium is guided.
    any_active: bool,
    scene: &'a Scene,
    strategy: &'a Strategy,
}

impl<C: Channels> PathObserver<C> for GuidingObserver<'_> {
    /// Only where a medium is guided: otherwise the path is volpath's, sample for sample.
    #[inline]
    fn guides(&self) -> bool {
        self.any_active
    }

    fn guide_medium(
        &mut self,
        medium: u32,
        p: Vec3,
        wo: Vec3,
        phase: &HenyeyGreenstein,
        u: f32,
    ) -> Option<GuidedSample> {
        let tree = self.guide.dtree(medium, p)?;
        let g = self.scene.media[medium as usize].g;
        // The guide draws a variable count of numbers: its own stream, seeded by the sampler.
        let mut rng = Pcg32::new(hash_sample(u, Vec2::new(0.5, 0.25)), 0x6775_6964);
        sampling::sample(tree, phase, g, wo, self.strategy, &mut rng)
    }

    fn guide_medium_pdf(&self, medium: u32, p: Vec3, wo: Vec3, phase: &HenyeyGreenstein, wi: Vec3) -> Option<f32> {
        let tree = self.guide.dtree(medium, p)?;
        let g = self.scene.media[medium as usize].g;
        Some(sampling::mis_pdf(tree, phase, g, wo, wi, self.strategy))
    }
}

impl RayIntegrator for Guided {
    fn name(&self) -> &'static str {
        "guided"
    }

    fn li<C: Channels>(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut C::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> C {
        let mut observer = GuidingObserver {
            guide: &self.guide,
            any_active: self.guide.active.iter().any(|&a| a),
            scene,
            strategy: &self.strategy,
        };
        trace_path(scene, ray, scene.camera_medium, lambda, sampler, &self.config, &mut observer, stats)
    }

    fn report(&self) -> Vec<String> {
        let s = &self.guide.stats;
        let (snodes, dtrees, dnodes) = self.guide.sizes();
        let bytes = self.guide.memory_bytes();
        vec![
            format!(
                "guide       {} ({} photons in {} rounds, {} deposits, {:.3} s training)",
                self.source, s.photons, s.rounds, s.deposits, s.seconds
            ),
            format!(
                "guide media {}",
                if self.media.is_empty() { "none (no photon scattered in a medium)" } else { &self.media }
            ),
            format!(
                "guide size  {snodes} spatial nodes, {dtrees} directional trees, {dnodes} directional nodes, \
                 {:.2} MiB ({} B per directional node)",
                bytes as f64 / (1 << 20) as f64,
                bytes.checked_div(dnodes).unwrap_or(0)
            ),
        ]
    }
}
