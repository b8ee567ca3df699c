//! The stratified sampler: jittered strata, independently permuted per pixel and dimension.

use glam::{UVec2, Vec2};

use super::hash::{hashed_uniform, mix_bits, permutation_element, sample_key};
use crate::sampling::warp::ONE_MINUS_EPSILON;

/// pbrt-v4's `StratifiedSampler`: the `x`×`y` samples of a pixel cover the `x`×`y` strata of
/// every 2D dimension pair once (and the `x·y` strata of every 1D dimension once), in an
/// order shuffled per pixel and dimension so dimensions do not correlate.
///
/// The stratum of each sample is pbrt's exactly (same hash and permutation); the jitter
/// inside it comes from a counter-based hash rather than pbrt's PCG32 stream. Sample indices
/// past `x·y` start the strata over (pbrt leaves them unstratified).
#[derive(Clone, Debug)]
pub struct StratifiedSampler {
    x_samples: u32,
    y_samples: u32,
    jitter: bool,
    seed: i32,
    pixel: UVec2,
    sample_index: u32,
    dimension: u32,
    key: u64,
}

impl StratifiedSampler {
    /// A sampler with `x_samples`×`y_samples` strata per pixel; without `jitter` samples sit
    /// at the strata centres.
    pub fn new(x_samples: u32, y_samples: u32, jitter: bool, seed: i32) -> StratifiedSampler {
        StratifiedSampler {
            x_samples: x_samples.max(1),
            y_samples: y_samples.max(1),
            jitter,
            seed,
            pixel: UVec2::ZERO,
            sample_index: 0,
            dimension: 0,
            key: 0,
        }
    }

    /// Samples per pixel: one per stratum.
    pub fn samples_per_pixel(&self) -> u32 {
        self.x_samples * self.y_samples
    }

    /// Starts sample `sample_index` of `pixel` at `dimension`.
    pub fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32, dimension: u32) {
        self.pixel = pixel;
        self.sample_index = sample_index;
        self.dimension = dimension;
        self.key = sample_key(pixel, sample_index, self.seed);
    }

    /// The stratum of the current sample in the current dimension, as pbrt-v4 picks it.
    fn stratum(&self) -> u32 {
        let spp = self.samples_per_pixel();
        // pbrt widens the (signed) seed to 64 bits, so negative seeds sign-extend.
        let hash = mix_bits(
            ((self.pixel.x as u64) << 48)
                ^ ((self.pixel.y as u64) << 32)
                ^ ((self.dimension as u64) << 16)
                ^ self.seed as i64 as u64,
        );
        permutation_element(self.sample_index % spp, spp, hash as u32)
    }

    /// Offset inside a stratum for counter `c` of this pixel sample.
    fn delta(&self, c: u32) -> f32 {
        if self.jitter { hashed_uniform(self.key, c) } else { 0.5 }
    }

    /// The next value: one of `x·y` strata of [0, 1).
    pub fn get_1d(&mut self) -> f32 {
        let stratum = self.stratum();
        let d = self.delta(self.dimension);
        self.dimension += 1;
        // The division can round up to 1 in the last stratum.
        ((stratum as f32 + d) / self.samples_per_pixel() as f32).min(ONE_MINUS_EPSILON)
    }

    /// The next two values: one of the `x`×`y` strata of [0, 1)².
    pub fn get_2d(&mut self) -> Vec2 {
        let stratum = self.stratum();
        let (dx, dy) = (self.delta(self.dimension), self.delta(self.dimension + 1));
        self.dimension += 2;
        let (x, y) = (stratum % self.x_samples, stratum / self.x_samples);
        Vec2::new((x as f32 + dx) / self.x_samples as f32, (y as f32 + dy) / self.y_samples as f32)
            .min(Vec2::splat(ONE_MINUS_EPSILON))
    }
}
