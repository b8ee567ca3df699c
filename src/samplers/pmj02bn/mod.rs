//! pbrt-v4's `PMJ02BNSampler`: progressive multi-jittered (0,2) blue-noise points.
//!
//! Film positions come from one 65,536-point sequence spread over a tile of pixels (each
//! pixel's share is itself a (0,2)-net, and neighbouring pixels' points avoid each other);
//! every later dimension pair reads the same sample index of another sequence (the first
//! four pairs) or a per-pixel shuffle of it, and single dimensions are jittered strata in a
//! shuffled order. Each pixel's values are offset by per-pixel blue noise (a Cranley–Patterson
//! rotation), so the error left in an image is blue noise too.
//!
//! pbrt-v4 reads its five point sequences and 48 blue-noise textures from precomputed tables
//! that are not part of its published source snapshot; nimbus generates both with the
//! published algorithms ([`points`], [`blue_noise`]) once per process (the texture count and
//! the length of sets 1–4 are the deviations: see [`Pmj02bnSampler::blue_noise`] and
//! [`later_sets`]). The sample pattern
//! therefore has pbrt-v4's structure and properties but not its exact values: images agree
//! with pbrt-v4's in expectation, not pixel for pixel.

mod blue_noise;
mod points;

use std::sync::{Arc, Mutex, OnceLock};

use glam::{UVec2, Vec2};

use super::hash::{permutation_element, pixel_dimension_hash};
use crate::sampling::warp::ONE_MINUS_EPSILON;

/// Point sequences, as in pbrt-v4 (`nPMJ02bnSets`).
const SETS: usize = 5;
/// Points per sequence, as in pbrt-v4 (`nPMJ02bnSamples`); also the most samples per pixel.
pub const MAX_SAMPLES: u32 = 1 << 16;
/// Best-candidate tries per point: Christensen et al.'s choice for pmj02bn.
const CANDIDATES: usize = 10;
/// Blue-noise textures and their side, as in pbrt-v4 (`NumBlueNoiseTextures`,
/// `BlueNoiseResolution`).
const BLUE_NOISE_TEXTURES: usize = 48;
const BLUE_NOISE_SIZE: usize = 128;

/// Set 0 (film positions, and every fifth dimension pair past the fifth) and the blue noise,
/// generated once per process and shared by every pmj02bn sampler.
struct Tables {
    set0: Vec<[u32; 2]>,
    blue_noise: Vec<u16>,
    /// Where each of the 48 textures starts in `blue_noise` (see [`Pmj02bnSampler::blue_noise`]).
    offsets: [(usize, usize); BLUE_NOISE_TEXTURES],
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        // Fixed seeds: the same tables in every run, on any number of threads.
        let (set0, blue_noise) = rayon::join(
            || points::pmj02bn(MAX_SAMPLES as usize, CANDIDATES, 0),
            || blue_noise::void_and_cluster(BLUE_NOISE_SIZE, 0),
        );
        let mut offsets = [(0, 0); BLUE_NOISE_TEXTURES];
        for (t, o) in offsets.iter_mut().enumerate().skip(1) {
            let h = super::hash::mix_bits(t as u64);
            *o = (h as usize % BLUE_NOISE_SIZE, (h >> 32) as usize % BLUE_NOISE_SIZE);
        }
        Tables { set0, blue_noise, offsets }
    })
}

/// Sets 1–4 (32-bit fixed-point points), shared.
type LaterSets = Arc<Vec<Vec<[u32; 2]>>>;

/// Sets 1–4, which only ever serve sample indices below the sample count: generated up to
/// the largest count asked for so far (a longer generation has the shorter one as its prefix).
fn later_sets(count: usize) -> LaterSets {
    use rayon::prelude::*;
    static MEMO: Mutex<Option<LaterSets>> = Mutex::new(None);
    let mut memo = MEMO.lock().unwrap_or_else(|e| e.into_inner());
    match memo.as_ref() {
        Some(sets) if sets[0].len() >= count => sets.clone(),
        _ => {
            let sets: Arc<Vec<_>> =
                Arc::new((1..SETS).into_par_iter().map(|s| points::pmj02bn(count, CANDIDATES, s as u64)).collect());
            *memo = Some(sets.clone());
            sets
        }
    }
}

/// pbrt-v4's pmj02bn sampler.
#[derive(Clone)]
pub struct Pmj02bnSampler {
    samples_per_pixel: u32,
    seed: i32,
    tables: &'static Tables,
    later_sets: LaterSets,
    /// Pixels per side of the tile that set 0's points cover; `pixel_samples` holds each
    /// tile pixel's `samples_per_pixel` film positions.
    pixel_tile: u32,
    pixel_samples: Arc<[Vec2]>,
    pixel: UVec2,
    sample_index: u32,
    dimension: u32,
}

impl std::fmt::Debug for Pmj02bnSampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pmj02bnSampler")
            .field("samples_per_pixel", &self.samples_per_pixel)
            .field("seed", &self.seed)
            .field("pixel", &self.pixel)
            .field("sample_index", &self.sample_index)
            .field("dimension", &self.dimension)
            .finish_non_exhaustive()
    }
}

impl Pmj02bnSampler {
    /// A sampler of `samples_per_pixel` (at most [`MAX_SAMPLES`]; best a power of 4, as
    /// pbrt-v4 warns) decorrelated by `seed`. The first sampler of a process generates the
    /// tables.
    pub fn new(samples_per_pixel: u32, seed: i32) -> Pmj02bnSampler {
        let spp = samples_per_pixel.clamp(1, MAX_SAMPLES);
        let tables = tables();
        // The tile: as many pixels as set 0 fills with `spp` points each, rounded so that a
        // pixel is an elementary square of the sequence (spp rounded up to a power of 4).
        let log4_spp = spp.next_power_of_two().trailing_zeros().div_ceil(2);
        let log2_tile = MAX_SAMPLES.trailing_zeros() / 2 - log4_spp;
        let tile = 1u32 << log2_tile;
        let mut pixel_samples = vec![Vec2::ZERO; (tile * tile * spp) as usize];
        let mut stored = vec![0u32; (tile * tile) as usize];
        for p in &tables.set0 {
            let (px, fx) = split(p[0], log2_tile);
            let (py, fy) = split(p[1], log2_tile);
            let pixel = (py * tile + px) as usize;
            // With spp not a power of 4 a pixel's square holds more points than it needs.
            if stored[pixel] == spp {
                continue;
            }
            pixel_samples[pixel * spp as usize + stored[pixel] as usize] = Vec2::new(fx, fy);
            stored[pixel] += 1;
        }
        Pmj02bnSampler {
            samples_per_pixel: spp,
            seed,
            tables,
            later_sets: later_sets(spp.next_power_of_two() as usize),
            pixel_tile: tile,
            pixel_samples: pixel_samples.into(),
            pixel: UVec2::ZERO,
            sample_index: 0,
            dimension: 0,
        }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.samples_per_pixel
    }

    /// Starts sample `sample_index` of `pixel` at `dimension` (dimensions 0 and 1 belong to
    /// the film position, so the others start at 2, as in pbrt-v4).
    pub fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32, dimension: u32) {
        self.pixel = pixel;
        self.sample_index = sample_index;
        self.dimension = dimension.max(2);
    }

    /// pbrt-v4's `BlueNoise(texture, pixel)`: this pixel's value of one of 48 textures.
    /// pbrt-v4's are 48 independent textures; nimbus's are one texture read from 48 toroidal
    /// offsets (each still blue noise; a pixel's values for different textures come from
    /// distant texels, which blue noise leaves uncorrelated), generated in a 48th of the time.
    fn blue_noise(&self, texture: u32) -> f32 {
        let (ox, oy) = self.tables.offsets[texture as usize % BLUE_NOISE_TEXTURES];
        let x = (self.pixel.x as usize + ox) % BLUE_NOISE_SIZE;
        let y = (self.pixel.y as usize + oy) % BLUE_NOISE_SIZE;
        f32::from(self.tables.blue_noise[y * BLUE_NOISE_SIZE + x]) * (1.0 / 65536.0)
    }

    /// The next value: a jittered stratum of [0, 1), strata shuffled per pixel and dimension.
    pub fn get_1d(&mut self) -> f32 {
        let hash = pixel_dimension_hash(self.pixel, self.dimension, self.seed);
        let index = permutation_element(self.sample_index, self.samples_per_pixel, hash as u32);
        let delta = self.blue_noise(self.dimension);
        self.dimension += 1;
        ((index as f32 + delta) / self.samples_per_pixel as f32).min(ONE_MINUS_EPSILON)
    }

    /// The next two values: a point of sequence `dimension / 2` (shuffled per pixel past the
    /// fifth pair), rotated by the pixel's blue noise.
    pub fn get_2d(&mut self) -> Vec2 {
        let instance = (self.dimension / 2) as usize;
        let mut index = self.sample_index;
        if instance >= SETS {
            let hash = pixel_dimension_hash(self.pixel, self.dimension, self.seed);
            index = permutation_element(self.sample_index, self.samples_per_pixel, hash as u32);
        }
        let p = match instance % SETS {
            0 => self.tables.set0[index as usize],
            set => self.later_sets[set - 1][index as usize],
        };
        let offset = Vec2::new(self.blue_noise(self.dimension), self.blue_noise(self.dimension + 1));
        self.dimension += 2;
        let wrap = |v: f32| (if v >= 1.0 { v - 1.0 } else { v }).min(ONE_MINUS_EPSILON);
        let u = Vec2::new(fixed_to_unit(p[0]), fixed_to_unit(p[1])) + offset;
        Vec2::new(wrap(u.x), wrap(u.y))
    }

    /// The film position within the pixel: this pixel's share of set 0. Consumes no
    /// dimension (`start_pixel_sample` already skipped 0 and 1).
    pub fn get_pixel_2d(&mut self) -> Vec2 {
        let x = self.pixel.x % self.pixel_tile;
        let y = self.pixel.y % self.pixel_tile;
        let offset = ((y * self.pixel_tile + x) * self.samples_per_pixel) as usize;
        self.pixel_samples[offset + self.sample_index as usize]
    }
}

/// A 32-bit fixed-point coordinate as a value in [0, 1).
fn fixed_to_unit(v: u32) -> f32 {
    (v as f32 * (1.0 / 4_294_967_296.0)).min(ONE_MINUS_EPSILON)
}

/// A fixed-point coordinate scaled by 2^`bits`: its integer part and its fraction in [0, 1).
/// Exact in integers (pbrt-v4 needs double precision for the same split).
fn split(v: u32, bits: u32) -> (u32, f32) {
    if bits == 0 {
        return (0, fixed_to_unit(v));
    }
    (v >> (32 - bits), fixed_to_unit(v << bits))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pixel_gets_a_02_net_of_film_positions() {
        // pbrt-v4's test (samplers_test.cpp, "ElementaryIntervals"): each pixel's film
        // positions put one point in every elementary interval, for spp = 4^k.
        for spp in [4u32, 16, 64, 256, 1024] {
            let mut s = Pmj02bnSampler::new(spp, 0);
            let k = spp.trailing_zeros();
            for pixel in [UVec2::ZERO, UVec2::new(3, 1), UVec2::new(200, 77)] {
                let points: Vec<Vec2> = (0..spp)
                    .map(|i| {
                        s.start_pixel_sample(pixel, i, 0);
                        s.get_pixel_2d()
                    })
                    .collect();
                for a in 0..=k {
                    let (cols, rows) = (1u32 << a, 1u32 << (k - a));
                    let mut seen = vec![false; spp as usize];
                    for p in &points {
                        let cell = (p.y * rows as f32) as u32 * cols + (p.x * cols as f32) as u32;
                        assert!(!std::mem::replace(&mut seen[cell as usize], true), "spp {spp} {pixel} {cols}×{rows}");
                    }
                }
            }
        }
    }

    #[test]
    fn other_spp_fill_their_pixels() {
        // Not a power of 4: each pixel keeps the first spp of its square's points.
        for spp in [1u32, 2, 8, 12, 100] {
            let mut s = Pmj02bnSampler::new(spp, 3);
            for i in 0..spp {
                s.start_pixel_sample(UVec2::new(5, 9), i, 0);
                let p = s.get_pixel_2d();
                assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y), "spp {spp}: {p}");
            }
        }
    }

    #[test]
    fn first_dimension_pairs_are_02_nets_too() {
        // Dimension pairs 2–9 read sets 1–4 at the sample index: a toroidal shift of a
        // (0,2)-net, so every 4×4 square of 16 samples holds one point of each elementary
        // column and row strip (the shift moves strata but keeps one point per stratum).
        let mut s = Pmj02bnSampler::new(16, 1);
        let pixel = UVec2::new(7, 4);
        for pair in 0..4u32 {
            let mut cols = [0u32; 16];
            let mut rows = [0u32; 16];
            for i in 0..16 {
                s.start_pixel_sample(pixel, i, 2 + 2 * pair);
                let u = s.get_2d();
                // A rotation of a 1D stratification by 1/16-strata keeps one point per 1/16
                // strip only up to the offset's sub-stratum part; count in shifted strips.
                let off = Vec2::new(s.blue_noise(2 + 2 * pair), s.blue_noise(3 + 2 * pair));
                let back = (u - off + Vec2::ONE).fract();
                cols[(back.x * 16.0) as usize] += 1;
                rows[(back.y * 16.0) as usize] += 1;
            }
            assert!(cols.iter().chain(&rows).all(|&c| c == 1), "pair {pair}: {cols:?} {rows:?}");
        }
    }
}
