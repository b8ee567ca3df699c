//! pbrt-v4's `PaddedSobolSampler`: every dimension pair an independently scrambled 2D Sobol'
//! point set, its samples shuffled per pixel and dimension ("padding" 2D sets rather than
//! using one high-dimensional sequence).

use glam::{UVec2, Vec2};

use super::hash::{permutation_element, pixel_dimension_hash};
use super::zsobol::{fast_owen_scramble, owen_scramble, sobol_bits};
use crate::samplers::settings::Randomization;
use crate::sampling::warp::ONE_MINUS_EPSILON;

/// pbrt-v4's padded Sobol' sampler.
#[derive(Clone, Debug)]
pub struct PaddedSobolSampler {
    samples_per_pixel: u32,
    seed: i32,
    randomization: Randomization,
    pixel: UVec2,
    sample_index: u32,
    dimension: u32,
}

impl PaddedSobolSampler {
    /// A sampler of `samples_per_pixel` (best a power of two), scrambled as `randomization`
    /// says and decorrelated by `seed`.
    pub fn new(samples_per_pixel: u32, randomization: Randomization, seed: i32) -> PaddedSobolSampler {
        PaddedSobolSampler { samples_per_pixel, seed, randomization, pixel: UVec2::ZERO, sample_index: 0, dimension: 0 }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.samples_per_pixel
    }

    /// Starts sample `sample_index` of `pixel` at `dimension`.
    pub fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32, dimension: u32) {
        self.pixel = pixel;
        self.sample_index = sample_index;
        self.dimension = dimension;
    }

    /// pbrt-v4's `Hash(pixel, dimension, seed)` and the sample's shuffled index.
    fn hash_and_index(&self) -> (u64, u64) {
        let hash = pixel_dimension_hash(self.pixel, self.dimension, self.seed);
        let index = permutation_element(self.sample_index, self.samples_per_pixel, hash as u32);
        (hash, u64::from(index))
    }

    fn sample(&self, dimension: usize, a: u64, seed: u32) -> f32 {
        let v = sobol_bits(a, dimension);
        let v = match self.randomization {
            Randomization::Owen => owen_scramble(v, seed),
            Randomization::FastOwen => fast_owen_scramble(v, seed),
        };
        (v as f32 * (1.0 / 4_294_967_296.0)).min(ONE_MINUS_EPSILON)
    }

    /// The next value.
    pub fn get_1d(&mut self) -> f32 {
        let (hash, index) = self.hash_and_index();
        self.dimension += 1;
        self.sample(0, index, (hash >> 32) as u32)
    }

    /// The next two values: one scrambled 2D Sobol' point.
    pub fn get_2d(&mut self) -> Vec2 {
        let (hash, index) = self.hash_and_index();
        self.dimension += 2;
        Vec2::new(self.sample(0, index, hash as u32), self.sample(1, index, (hash >> 32) as u32))
    }
}
