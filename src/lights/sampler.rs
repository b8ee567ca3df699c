//! Choosing one light for next-event estimation: uniformly or in proportion to power.

use super::{Light, SceneSphere};
use crate::sampling::distribution::AliasTable;

/// Picks lights for next-event estimation. Lights that are not sampled directly (a uniform
/// environment) have probability 0.
#[derive(Clone, Debug)]
pub struct LightSampler {
    table: Option<AliasTable>,
}

impl LightSampler {
    /// A sampler over `lights`, by power when `by_power` and uniformly otherwise.
    pub fn new(lights: &[Light], scene: &SceneSphere, by_power: bool) -> LightSampler {
        let weights: Vec<f32> = lights
            .iter()
            .map(|l| {
                if !l.samples_directly() {
                    0.0
                } else if by_power {
                    l.power(scene)
                } else {
                    1.0
                }
            })
            .collect();
        let any = weights.iter().any(|w| *w > 0.0);
        // All-zero power with lights present (e.g. black lights): fall back to uniform over
        // the sampleable ones, so an all-black scene still samples consistently.
        let weights = if !any && by_power {
            lights.iter().map(|l| if l.samples_directly() { 1.0 } else { 0.0 }).collect()
        } else {
            weights
        };
        let table = weights.iter().any(|w| *w > 0.0).then(|| AliasTable::new(&weights));
        LightSampler { table }
    }

    /// Picks a light: (index, probability), or `None` when no light is sampled directly.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        let t = self.table.as_ref()?;
        let s = t.sample(u)?;
        (s.pmf > 0.0).then_some((s.index, s.pmf))
    }

    /// Probability of picking light `index`.
    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        self.table.as_ref().map_or(0.0, |t| t.pmf(index))
    }
}
