//! The independent sampler: uniform random values with no stratification.

use glam::{UVec2, Vec2};

use super::hash::{hashed_uniform, sample_key};

/// Uniform random values from a counter-based hash of (pixel, sample index, dimension, seed).
///
/// pbrt-v4's `IndependentSampler` draws from a PCG32 stream advanced to the pixel sample; the
/// hash gives the same statistics without state, so a value never depends on call order.
#[derive(Clone, Debug)]
pub struct IndependentSampler {
    samples_per_pixel: u32,
    seed: i32,
    key: u64,
    dimension: u32,
}

impl IndependentSampler {
    /// A sampler taking `samples_per_pixel` samples, decorrelated across scenes by `seed`.
    pub fn new(samples_per_pixel: u32, seed: i32) -> IndependentSampler {
        IndependentSampler { samples_per_pixel, seed, key: 0, dimension: 0 }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.samples_per_pixel
    }

    /// Starts sample `sample_index` of `pixel` at `dimension`.
    pub fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32, dimension: u32) {
        self.key = sample_key(pixel, sample_index, self.seed);
        self.dimension = dimension;
    }

    /// The next value.
    pub fn get_1d(&mut self) -> f32 {
        let u = hashed_uniform(self.key, self.dimension);
        self.dimension += 1;
        u
    }

    /// The next two values.
    pub fn get_2d(&mut self) -> Vec2 {
        let u = Vec2::new(hashed_uniform(self.key, self.dimension), hashed_uniform(self.key, self.dimension + 1));
        self.dimension += 2;
        u
    }
}
