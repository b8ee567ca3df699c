//! `guided`: path guiding in participating media (Deng, Wang, Wang and Holzschuch 2020). Before
//! rendering, photons from the lights train an SD-tree per medium ([`train`]); camera paths
//! then run the shared path loop, whose observer hook draws each medium scattering direction
//! from the product of phase function and learned radiance by resampling, or from their
//! mixture by MIS, depending on the medium's anisotropy ([`sampling`]). Next-event estimation
//! is MIS-weighted against the guided technique's density. A path whose expected contribution
//! grows along the way splits (README). Surfaces are not guided.

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

use std::path::Path;

use super::RayIntegrator;
use super::common::{GuidedSample, PathConfig, PathRecorder, PathStrategy, RayStats, trace_path};
use super::prepared::{Source, load_or_prepare};
use super::registry::{Method, MethodInputs, MethodSettings, Precompute};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::media::phase::HenyeyGreenstein;
use crate::samplers::Sampler;
use crate::sampling::rng::{Pcg32, hash_sample};
use crate::scene::Scene;
use sampling::Strategy;

/// The registry's entry.
pub const METHOD: Method = Method { name: "guided", aliases: &[], read };

fn read(e: &nimbus_parser::Entity) -> Result<Box<dyn MethodSettings>, nimbus_parser::Error> {
    Ok(Box::new(GuidedSettings::from_entity(e)?))
}

impl MethodSettings for GuidedSettings {
    fn method(&self) -> &'static Method {
        &METHOD
    }

    fn set_max_depth(&mut self, depth: u32) -> crate::Result<()> {
        self.max_depth = depth;
        Ok(())
    }

    fn prepares(&self) -> bool {
        true
    }

    /// The precomputed file is the guide cache: loaded when it matches, trained and saved
    /// when it is missing.
    fn set_inputs(&mut self, inputs: &MethodInputs<'_>) {
        self.cache = inputs.precomputed.map(Path::to_path_buf);
    }

    /// Training happens in the first render whose cache file is missing.
    fn precompute(&self, _scene_file: &Path) -> crate::Result<Option<Precompute>> {
        Ok(Some(Precompute::FirstRender { file: "guide.cache".into() }))
    }

    /// Training traces photons from the lights, which read a medium's own coefficients.
    fn check(&self, scene: &Scene) -> crate::Result<()> {
        if scene.entered_medium().is_some() {
            return Err(crate::Error::Unsupported(
                "guided trains on photons that read a medium's coefficients where they are, and this scene has a \
                 subsurface material with textured inputs (coefficients taken where a path enters): render it with \
                 volpath or pathgraph"
                    .into(),
            ));
        }
        Ok(())
    }

    fn create(&self, scene: &Scene) -> crate::Result<Box<dyn super::Integrator>> {
        self.check(scene)?;
        Ok(Box::new(create(self, scene)?))
    }
}

/// The guided path tracer.
pub struct Guided {
    config: PathConfig,
    strategy: Strategy,
    guide: Guide,
    /// Where the guide came from, for `--stats`.
    source: String,
    /// Which media are guided and why, for `--stats`.
    media: String,
    /// Splitting: (threshold, most copies); 1 copy where splitting is off.
    split: (f32, u32),
}

/// Trains the guide (or loads it from the cache file, [`load_or_prepare`]) and creates the
/// integrator.
pub fn create(settings: &GuidedSettings, scene: &Scene) -> crate::Result<Guided> {
    let (mut guide, source) = load_or_prepare(
        settings.cache.as_deref(),
        |path| cache::load(path, scene, settings),
        || Ok(train::train(scene, settings)),
        |path, guide| cache::save(path, scene, settings, guide),
    )?;
    let source = match source {
        Source::Prepared => "trained".to_string(),
        Source::Saved(path) => format!("trained, saved to {}", path.display()),
        Source::Loaded(path) => format!("loaded from {}", path.display()),
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
    // Copies of a path share its wavelengths: a dispersive surface that one copy meets
    // would cut them down to the hero for all of them, so such scenes do not split.
    let dispersive = scene.materials.iter().any(|m| m.is_dispersive(&scene.materials));
    let max_split = if dispersive { 1 } else { settings.max_split };
    Ok(Guided {
        config: PathConfig::volpath(settings.max_depth, settings.regularize),
        strategy: settings.strategy,
        guide,
        source,
        media,
        split: (settings.split_threshold, max_split),
    })
}

impl Guided {
    /// The trained trees.
    pub fn guide(&self) -> &Guide {
        &self.guide
    }
}

/// Probability of next-event estimation in a guided medium that photons reached only
/// through refractive boundaries (README: 10 % less time per sample on the candle, the same
/// error).
const NEE_INSIDE_DIELECTRIC: f32 = 0.125;

/// The path loop's observer: guides scattering in media, records nothing.
struct GuidingObserver<'a> {
    guide: &'a Guide,
    /// Whether any medium is guided.
    any_active: bool,
    scene: &'a Scene,
    strategy: &'a Strategy,
    /// Splitting's threshold and most copies.
    split: (f32, u32),
    /// The path's expected contribution at its first guided vertex, once there.
    reference: Option<f32>,
}

impl<C: Channels> PathRecorder<C> for GuidingObserver<'_> {}

impl PathStrategy for GuidingObserver<'_> {
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

    /// Splitting by expected contribution (after Vorba and Křivánek 2016's adjoint-driven
    /// splitting, with the guide's learned fluence as the adjoint and the path's own first
    /// guided vertex as the reference): where β·fluence has grown to r times the reference,
    /// r ≥ the threshold, the path continues in round(r) copies. The split is decided before
    /// the directions are drawn, so each copy is an independent continuation and the
    /// estimator stays unbiased whatever the guide's accuracy.
    fn split_medium(&mut self, medium: u32, p: Vec3, beta: f32) -> u32 {
        let (threshold, max_copies) = self.split;
        if max_copies <= 1 {
            return 1;
        }
        let Some(fluence) = self.guide.fluence(medium, p) else { return 1 };
        let c = beta * fluence;
        if !(c > 0.0 && c.is_finite()) {
            return 1;
        }
        let Some(reference) = self.reference else {
            self.reference = Some(c);
            return 1;
        };
        let r = c / reference;
        if r >= threshold { (r.round() as u32).clamp(2, max_copies) } else { 1 }
    }

    /// Next-event estimation cannot see a light through a dielectric (its shadow rays stop
    /// at every surface but `interface` ones), so in a guided medium whose learned light all
    /// came in through refractive boundaries it only costs: it runs with probability
    /// [`NEE_INSIDE_DIELECTRIC`] there (roulette, so whatever it still finds is counted).
    fn nee_medium_probability(&self, medium: u32, _p: Vec3) -> f32 {
        if self.guide.active.get(medium as usize) == Some(&true) && self.guide.refracted[medium as usize] >= 1.0 {
            NEE_INSIDE_DIELECTRIC
        } else {
            1.0
        }
    }

    fn guide_medium_pdf(&self, medium: u32, p: Vec3, wo: Vec3, phase: &HenyeyGreenstein, wi: Vec3) -> Option<f32> {
        let tree = self.guide.dtree(medium, p)?;
        let g = self.scene.media[medium as usize].g;
        Some(sampling::mis_pdf(tree, phase, g, wo, wi, self.strategy))
    }
}

impl RayIntegrator for Guided {
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
        let mut observer = GuidingObserver {
            guide: &self.guide,
            any_active: self.guide.active.iter().any(|&a| a),
            scene,
            strategy: &self.strategy,
            split: self.split,
            reference: None,
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
            match self.split {
                (_, 1) => "guide split off".to_string(),
                (t, n) => format!("guide split into up to {n} copies at {t}x a path's first expected contribution"),
            },
            format!(
                "guide size  {snodes} spatial nodes, {dtrees} directional trees, {dnodes} directional nodes, \
                 {:.2} MiB ({} B per directional node)",
                bytes as f64 / (1 << 20) as f64,
                bytes.checked_div(dnodes).unwrap_or(0)
            ),
        ]
    }
}
