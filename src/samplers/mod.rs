//! Sample generators: the numbers in [0, 1) that drive every random decision of a path.
//!
//! A [`Sampler`] is started at a pixel sample with [`Sampler::start_pixel_sample`] and then
//! hands out consecutive dimensions with [`Sampler::get_1d`], [`Sampler::get_2d`] and
//! [`Sampler::get_pixel_2d`]. Every value is a pure function of (pixel, sample index,
//! dimension, seed) and the sampler's settings, so images do not depend on how threads share
//! the work; each thread clones its own sampler (a few words; Halton's digit permutations
//! are shared behind an `Arc`).
//!
//! The camera ray consumes dimensions as pbrt-v4's `GetCameraSample` does: film position
//! (2D), time (1D), lens (2D); see [`get_camera_sample`].

mod camera_sample;
mod halton;
mod hash;
mod independent;
mod padded_sobol;
mod pmj02bn;
pub mod settings;
mod sobol;
mod stratified;
mod zsobol;

use glam::{UVec2, Vec2};

use crate::samplers::settings::{SamplerKind, SamplerSettings};
use crate::sampling::rng::hash_sample;

pub use camera_sample::{CameraSample, CameraSampleUse, get_camera_sample};
pub(crate) use halton::radical_inverse;
pub use halton::{HaltonRandomization, HaltonSampler};
pub use independent::IndependentSampler;
pub use padded_sobol::PaddedSobolSampler;
pub use pmj02bn::{MAX_SAMPLES as PMJ02BN_MAX_SAMPLES, Pmj02bnSampler};
pub use sobol::SobolSampler;
pub use stratified::StratifiedSampler;
pub use zsobol::ZSobolSampler;
pub(crate) use zsobol::sobol_bits;

/// One of nimbus's sample generators (a closed set: dispatch is a `match`).
#[derive(Clone, Debug)]
pub enum Sampler {
    /// Uniform random values.
    Independent(IndependentSampler),
    /// Jittered strata.
    Stratified(StratifiedSampler),
    /// Owen-scrambled Sobol' points per pixel.
    Sobol(SobolSampler),
    /// pbrt-v4's Morton-ordered Sobol' sampler (its default).
    ZSobol(ZSobolSampler),
    /// The Halton sequence over the image.
    Halton(HaltonSampler),
    /// Independently scrambled 2D Sobol' sets per dimension pair.
    PaddedSobol(PaddedSobolSampler),
    /// Progressive multi-jittered (0,2) blue-noise points.
    Pmj02bn(Pmj02bnSampler),
}

impl Sampler {
    /// The sampler `settings` describe, for a film of `full_resolution` pixels (ZSobol orders
    /// pixels along a Morton curve over the whole image; the others ignore it).
    pub fn new(settings: &SamplerSettings, full_resolution: UVec2) -> Sampler {
        let spp = settings.pixel_samples.max(1);
        let seed = settings.seed;
        match settings.kind {
            SamplerKind::Independent => Sampler::Independent(IndependentSampler::new(spp, seed)),
            SamplerKind::Stratified { x, y, jitter } => Sampler::Stratified(StratifiedSampler::new(x, y, jitter, seed)),
            SamplerKind::Sobol => Sampler::Sobol(SobolSampler::new(spp, seed)),
            SamplerKind::ZSobol => {
                Sampler::ZSobol(ZSobolSampler::new(spp, full_resolution, settings.randomization, seed))
            }
            SamplerKind::Halton(r) => Sampler::Halton(HaltonSampler::new(spp, full_resolution, r, seed)),
            SamplerKind::PaddedSobol => {
                Sampler::PaddedSobol(PaddedSobolSampler::new(spp, settings.randomization, seed))
            }
            SamplerKind::Pmj02bn => Sampler::Pmj02bn(Pmj02bnSampler::new(spp, seed)),
        }
    }

    /// Samples to take per pixel (ZSobol rounds the requested count down to a power of two,
    /// as pbrt-v4 does).
    pub fn samples_per_pixel(&self) -> u32 {
        match self {
            Sampler::Independent(s) => s.samples_per_pixel(),
            Sampler::Stratified(s) => s.samples_per_pixel(),
            Sampler::Sobol(s) => s.samples_per_pixel(),
            Sampler::ZSobol(s) => s.samples_per_pixel(),
            Sampler::Halton(s) => s.samples_per_pixel(),
            Sampler::PaddedSobol(s) => s.samples_per_pixel(),
            Sampler::Pmj02bn(s) => s.samples_per_pixel(),
        }
    }

    /// Starts sample `sample_index` of `pixel`; the next value returned is dimension
    /// `dimension` (0 for a camera path; integrators that restart mid-path pass more).
    pub fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32, dimension: u32) {
        match self {
            Sampler::Independent(s) => s.start_pixel_sample(pixel, sample_index, dimension),
            Sampler::Stratified(s) => s.start_pixel_sample(pixel, sample_index, dimension),
            Sampler::Sobol(s) => s.start_pixel_sample(pixel, sample_index, dimension),
            Sampler::ZSobol(s) => s.start_pixel_sample(pixel, sample_index, dimension),
            Sampler::Halton(s) => s.start_pixel_sample(pixel, sample_index, dimension),
            Sampler::PaddedSobol(s) => s.start_pixel_sample(pixel, sample_index, dimension),
            Sampler::Pmj02bn(s) => s.start_pixel_sample(pixel, sample_index, dimension),
        }
    }

    /// The next dimension, in [0, 1).
    #[inline]
    pub fn get_1d(&mut self) -> f32 {
        match self {
            Sampler::Independent(s) => s.get_1d(),
            Sampler::Stratified(s) => s.get_1d(),
            Sampler::Sobol(s) => s.get_1d(),
            Sampler::ZSobol(s) => s.get_1d(),
            Sampler::Halton(s) => s.get_1d(),
            Sampler::PaddedSobol(s) => s.get_1d(),
            Sampler::Pmj02bn(s) => s.get_1d(),
        }
    }

    /// The next two dimensions, in [0, 1)², stratified jointly.
    #[inline]
    pub fn get_2d(&mut self) -> Vec2 {
        match self {
            Sampler::Independent(s) => s.get_2d(),
            Sampler::Stratified(s) => s.get_2d(),
            Sampler::Sobol(s) => s.get_2d(),
            Sampler::ZSobol(s) => s.get_2d(),
            Sampler::Halton(s) => s.get_2d(),
            Sampler::PaddedSobol(s) => s.get_2d(),
            Sampler::Pmj02bn(s) => s.get_2d(),
        }
    }

    /// Passes over the next dimension whose value would go unused: the dimensions after it
    /// are the ones [`Self::get_1d`] would have left (pbrt-v4 draws such values anyway, e.g.
    /// a pinhole camera's lens sample, so that every path sees the same dimensions).
    /// Generating a ZSobol value (its digit permutations and scramble) costs about as much as
    /// a grid lookup; skipping it is free.
    #[inline]
    pub fn skip_1d(&mut self) {
        match self {
            Sampler::ZSobol(s) => s.skip(1),
            // Halton wraps its dimension inside `get_*`: skip by drawing.
            _ => {
                self.get_1d();
            }
        }
    }

    /// A 64-bit seed for a random stream of the path's own (a medium walk's later tentative
    /// collisions), in place of the next dimension. pbrt-v4 hashes two sampled values into
    /// its stream's seeds; a seed gains nothing from stratification, so ZSobol hashes the
    /// pixel sample's index and the dimension instead of generating a value (digit
    /// permutations and scrambles were a third of the sampler's work on graph-cloud). The
    /// other samplers hash their value, as pbrt-v4 does.
    #[inline]
    pub fn stream_seed(&mut self) -> u64 {
        match self {
            Sampler::ZSobol(s) => s.seed(),
            _ => hash_sample(self.get_1d(), Vec2::ZERO),
        }
    }

    /// The next two dimensions, the second for decisions whose images must be independent
    /// between seeds (a medium walk's first event choice): ZSobol's and Halton's values,
    /// randomized once per dimension for the whole image, moved per pixel as well
    /// ([`ZSobolSampler::get_2d_shifted_y`], [`HaltonSampler::get_2d_shifted_y`]); the other
    /// samplers' as they are (they randomize per pixel and seed, or are random).
    #[inline]
    pub fn get_2d_shifted_y(&mut self) -> Vec2 {
        match self {
            Sampler::ZSobol(s) => s.get_2d_shifted_y(),
            Sampler::Halton(s) => s.get_2d_shifted_y(),
            _ => self.get_2d(),
        }
    }

    /// The next dimension, moved per pixel as [`Self::get_2d_shifted_y`]'s second.
    #[inline]
    pub fn get_1d_shifted(&mut self) -> f32 {
        match self {
            Sampler::ZSobol(s) => s.get_1d_shifted(),
            Sampler::Halton(s) => s.get_1d_shifted(),
            _ => self.get_1d(),
        }
    }

    /// Passes over the next two dimensions, as [`Self::get_2d`] would (see [`Self::skip_1d`]).
    #[inline]
    pub fn skip_2d(&mut self) {
        match self {
            Sampler::ZSobol(s) => s.skip(2),
            _ => {
                self.get_2d();
            }
        }
    }

    /// The film-position sample within the pixel: the next two dimensions, except for Halton,
    /// whose first two dimensions are scaled over the image, and pmj02bn, whose film
    /// positions tile the image (as in pbrt-v4).
    #[inline]
    pub fn get_pixel_2d(&mut self) -> Vec2 {
        match self {
            Sampler::Halton(s) => s.get_pixel_2d(),
            Sampler::Pmj02bn(s) => s.get_pixel_2d(),
            _ => self.get_2d(),
        }
    }
}

#[cfg(test)]
mod tests;
