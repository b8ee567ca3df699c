//! Choosing one light for next-event estimation: uniformly, in proportion to power, or with
//! pbrt-v4's light BVH (by each light's importance for the shading point).

use glam::Vec3;

use super::bvh::LightBvh;
use super::{Light, SceneSphere};
use crate::accel::ShapeStore;
use crate::sampling::distribution::AliasTable;

/// How lights are chosen for next-event estimation (pbrt-v4's `lightsampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSamplerKind {
    /// Every light equally likely.
    Uniform,
    /// Proportional to emitted power.
    Power,
    /// pbrt-v4's light BVH: spatially varying, by importance at the shading point (pbrt-v4's
    /// default for every integrator).
    #[default]
    Bvh,
}

/// Picks lights for next-event estimation. Lights that are not sampled directly (a uniform
/// environment) have probability 0.
#[derive(Clone, Debug)]
pub enum LightSampler {
    /// A fixed distribution (uniform or by power); `None` when no light is sampled.
    Table(Option<AliasTable>),
    /// pbrt-v4's light BVH.
    Bvh(LightBvh),
}

impl LightSampler {
    /// A sampler over `lights` of the given kind.
    pub fn new(lights: &[Light], shapes: &ShapeStore, scene: &SceneSphere, kind: LightSamplerKind) -> LightSampler {
        if kind == LightSamplerKind::Bvh {
            return LightSampler::Bvh(LightBvh::new(lights, shapes));
        }
        let by_power = kind == LightSamplerKind::Power;
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
        LightSampler::Table(weights.iter().any(|w| *w > 0.0).then(|| AliasTable::new(&weights)))
    }

    /// Picks a light for a point `p` with shading normal `n` (zero in media): (index,
    /// probability), or `None` when no light is sampled there.
    #[inline]
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(usize, f32)> {
        match self {
            LightSampler::Table(t) => {
                let s = t.as_ref()?.sample(u)?;
                (s.pmf > 0.0).then_some((s.index, s.pmf))
            }
            LightSampler::Bvh(bvh) => bvh.sample(p, n, u),
        }
    }

    /// Whether [`Self::sample`] reads its `u`: not when there is one light or none to pick.
    pub fn reads_sample(&self) -> bool {
        match self {
            LightSampler::Table(t) => t.as_ref().is_some_and(|t| t.len() > 1),
            LightSampler::Bvh(bvh) => bvh.reads_sample(),
        }
    }

    /// Probability of picking light `index` for a point `p` with shading normal `n`.
    #[inline]
    pub fn pmf(&self, p: Vec3, n: Vec3, index: usize) -> f32 {
        match self {
            LightSampler::Table(t) => t.as_ref().map_or(0.0, |t| t.pmf(index)),
            LightSampler::Bvh(bvh) => bvh.pmf(p, n, index),
        }
    }
}
