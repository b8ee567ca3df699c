//! The Sobol' sampler: an Owen-scrambled Sobol' sequence per pixel.

use glam::{UVec2, Vec2};

use super::hash::{hashed_uniform, mix_bits, sample_key};

/// Largest sample index `sobol_burley` supports, plus one.
const MAX_SAMPLES: u32 = 1 << 16;

/// Owen-scrambled Sobol' points (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020,
/// via the `sobol_burley` crate with Joe and Kuo's direction numbers), one sequence per
/// pixel: the seed of each pixel's scramble and index shuffle is a hash of the pixel and the
/// scene seed, so neighbouring pixels' errors are independent.
///
/// Consecutive dimensions are consecutive Sobol' dimensions, so a pixel's samples are
/// stratified jointly across all 256 dimensions the crate has. Past dimension 256 or sample
/// 2^16 values come from the counter-based hash instead (uniform, unstratified).
///
/// Deviation from pbrt-v4's `SobolSampler`, which spreads one global sequence over the image
/// (`SobolIntervalToIndex`): this is pbrt's per-pixel scheme instead, and it uses Burley's
/// hash scramble whether the scene asks for `owen` or `fastowen`. The expected image is the
/// same.
#[derive(Clone, Debug)]
pub struct SobolSampler {
    samples_per_pixel: u32,
    seed: i32,
    pixel_seed: u32,
    key: u64,
    sample_index: u32,
    dimension: u32,
    /// The last set of four dimensions computed (`u32::MAX`: none) and its values: the
    /// crate computes four at once in SIMD for about the price of one, and paths ask for
    /// consecutive dimensions (the Disney cloud's paths take hundreds).
    cached_set: u32,
    cached: [f32; 4],
}

impl SobolSampler {
    /// A sampler taking `samples_per_pixel` samples, decorrelated across scenes by `seed`.
    pub fn new(samples_per_pixel: u32, seed: i32) -> SobolSampler {
        SobolSampler {
            samples_per_pixel,
            seed,
            pixel_seed: 0,
            key: 0,
            sample_index: 0,
            dimension: 0,
            cached_set: u32::MAX,
            cached: [0.0; 4],
        }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.samples_per_pixel
    }

    /// Starts sample `sample_index` of `pixel` at `dimension`.
    pub fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32, dimension: u32) {
        let p = ((pixel.x as u64) << 32) | pixel.y as u64;
        self.pixel_seed = mix_bits(p ^ mix_bits(self.seed as u32 as u64 ^ 0x5eed)) as u32;
        self.key = sample_key(pixel, sample_index, self.seed);
        self.sample_index = sample_index;
        self.dimension = dimension;
        self.cached_set = u32::MAX;
    }

    /// Value of dimension `d` of the current sample (`sobol_burley::sample_4d` gives the
    /// same values as `sample`).
    fn sample_dimension(&mut self, d: u32) -> f32 {
        if d < sobol_burley::NUM_DIMENSIONS && self.sample_index < MAX_SAMPLES {
            let set = d >> 2;
            if set != self.cached_set {
                self.cached = sobol_burley::sample_4d(self.sample_index, set, self.pixel_seed);
                self.cached_set = set;
            }
            self.cached[(d & 3) as usize]
        } else {
            hashed_uniform(self.key, d)
        }
    }

    /// The next value.
    pub fn get_1d(&mut self) -> f32 {
        let u = self.sample_dimension(self.dimension);
        self.dimension += 1;
        u
    }

    /// The next two values.
    pub fn get_2d(&mut self) -> Vec2 {
        let d = self.dimension;
        self.dimension += 2;
        Vec2::new(self.sample_dimension(d), self.sample_dimension(d + 1))
    }
}
