//! pbrt-v4's `HaltonSampler` (pbrt-v4 §8.6): the Halton sequence over the whole image, the
//! first two dimensions scaled so that every pixel gets its own samples (the indices of a
//! pixel's samples found with the Chinese remainder theorem), randomized by random digit
//! permutations (pbrt-v4's default), Owen scrambling, or not at all. Dimensions 0 and 1 are
//! the film position ([`HaltonSampler::get_pixel_2d`]); `get_1d`/`get_2d` start at 2.

use std::sync::Arc;

use glam::{UVec2, Vec2};

use super::hash::{mix_bits, permutation_element};
use crate::sampling::rng::murmur_hash64a;
use crate::sampling::warp::ONE_MINUS_EPSILON;

/// Dimensions available (pbrt-v4's `PrimeTableSize`): the first 1000 primes are the bases.
const PRIME_TABLE_SIZE: usize = 1000;

/// pbrt-v4 scales the first two dimensions to at most 128 × 128 pixels, then repeats.
const MAX_RESOLUTION: u32 = 128;

/// pbrt-v4's Halton `randomization`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HaltonRandomization {
    /// `none`: the plain radical inverses.
    None,
    /// `permutedigits` (default): a random permutation of the digits per base and digit.
    PermuteDigits,
    /// `owen`: nested (Owen) scrambling, hashed per digit prefix.
    Owen,
}

/// The first `n` primes.
fn primes(n: usize) -> Vec<u32> {
    let mut p = Vec::with_capacity(n);
    let mut k = 2u32;
    while p.len() < n {
        if p.iter().take_while(|&&q| q * q <= k).all(|&q| !k.is_multiple_of(q)) {
            p.push(k);
        }
        k += 1;
    }
    p
}

/// pbrt-v4's `DigitPermutation`: for a base, one random permutation of the digits per digit
/// position, enough positions for a float's precision.
#[derive(Clone, Debug)]
struct DigitPermutation {
    base: u32,
    n_digits: u32,
    permutations: Vec<u16>,
}

impl DigitPermutation {
    fn new(base: u32, seed: u32) -> DigitPermutation {
        let inv_base = 1.0 / base as f32;
        let mut inv_base_m = 1.0f32;
        let mut n_digits = 0;
        while 1.0 - (base - 1) as f32 * inv_base_m < 1.0 {
            n_digits += 1;
            inv_base_m *= inv_base;
        }
        let mut permutations = Vec::with_capacity((n_digits * base) as usize);
        for digit_index in 0..n_digits {
            // pbrt-v4's Hash(base, digitIndex, seed): MurmurHash64A of the three ints' bytes.
            let mut bytes = [0u8; 12];
            bytes[0..4].copy_from_slice(&(base as i32).to_le_bytes());
            bytes[4..8].copy_from_slice(&(digit_index as i32).to_le_bytes());
            bytes[8..12].copy_from_slice(&seed.to_le_bytes());
            let dseed = murmur_hash64a(&bytes, 0);
            for digit_value in 0..base {
                permutations.push(permutation_element(digit_value, base, dseed as u32) as u16);
            }
        }
        DigitPermutation { base, n_digits, permutations }
    }

    #[inline]
    fn permute(&self, digit_index: u32, digit_value: u32) -> u32 {
        u32::from(self.permutations[(digit_index * self.base + digit_value) as usize])
    }
}

/// What every clone of a Halton sampler shares: the bases and their digit permutations.
#[derive(Debug)]
struct Tables {
    primes: Vec<u32>,
    permutations: Vec<DigitPermutation>,
}

/// pbrt-v4's Halton sampler.
#[derive(Clone, Debug)]
pub struct HaltonSampler {
    samples_per_pixel: u32,
    randomization: HaltonRandomization,
    tables: Arc<Tables>,
    base_scales: [u64; 2],
    base_exponents: [u32; 2],
    mult_inverse: [u64; 2],
    halton_index: u64,
    dimension: u32,
    seed: i32,
    /// The current pixel, for [`HaltonSampler::get_2d_shifted_y`].
    pixel_key: u64,
}

/// The radical inverse of `a` in base `primes[base_index]` (pbrt-v4's `RadicalInverse`).
pub(crate) fn radical_inverse(base: u32, mut a: u64) -> f32 {
    let base = u64::from(base);
    let limit = u64::MAX / base - base;
    let inv_base = 1.0 / base as f32;
    let mut inv_base_m = 1.0f32;
    let mut reversed = 0u64;
    while a != 0 && reversed < limit {
        let next = a / base;
        reversed = reversed * base + (a - next * base);
        inv_base_m *= inv_base;
        a = next;
    }
    (reversed as f32 * inv_base_m).min(ONE_MINUS_EPSILON)
}

/// pbrt-v4's `ScrambledRadicalInverse`: every digit through its position's permutation (the
/// leading zeros included, which is what randomizes them).
fn scrambled_radical_inverse(perm: &DigitPermutation, mut a: u64) -> f32 {
    let base = u64::from(perm.base);
    let inv_base = 1.0 / base as f32;
    let mut inv_base_m = 1.0f32;
    let mut reversed = 0u64;
    for digit_index in 0..perm.n_digits {
        let next = a / base;
        let digit = (a - next * base) as u32;
        reversed = reversed * base + u64::from(perm.permute(digit_index, digit));
        inv_base_m *= inv_base;
        a = next;
    }
    (inv_base_m * reversed as f32).min(ONE_MINUS_EPSILON)
}

/// pbrt-v4's `OwenScrambledRadicalInverse`: each digit permuted by a hash of the digits
/// before it.
fn owen_scrambled_radical_inverse(base: u32, mut a: u64, hash: u32) -> f32 {
    let b = u64::from(base);
    let inv_base = 1.0 / base as f32;
    let mut inv_base_m = 1.0f32;
    let mut reversed = 0u64;
    while 1.0 - inv_base_m < 1.0 {
        let next = a / b;
        let digit = (a - next * b) as u32;
        let digit_hash = mix_bits(u64::from(hash) ^ reversed) as u32;
        let digit = permutation_element(digit, base, digit_hash);
        reversed = reversed * b + u64::from(digit);
        inv_base_m *= inv_base;
        a = next;
    }
    (inv_base_m * reversed as f32).min(ONE_MINUS_EPSILON)
}

/// pbrt-v4's `InverseRadicalInverse`: the index whose first `n_digits` reversed digits are
/// `inverse`.
fn inverse_radical_inverse(mut inverse: u64, base: u64, n_digits: u32) -> u64 {
    let mut index = 0;
    for _ in 0..n_digits {
        let digit = inverse % base;
        inverse /= base;
        index = index * base + digit;
    }
    index
}

/// x with a·x ≡ 1 (mod n) (pbrt-v4's `multiplicativeInverse`, by the extended Euclid).
fn multiplicative_inverse(a: i64, n: i64) -> u64 {
    let (mut old_r, mut r) = (a, n);
    let (mut old_s, mut s) = (1i64, 0i64);
    while r != 0 {
        let q = old_r / r;
        (old_r, r) = (r, old_r - q * r);
        (old_s, s) = (s, old_s - q * s);
    }
    old_s.rem_euclid(n) as u64
}

impl HaltonSampler {
    /// A sampler of `samples_per_pixel` for an image of `full_resolution` pixels.
    pub fn new(
        samples_per_pixel: u32,
        full_resolution: UVec2,
        randomization: HaltonRandomization,
        seed: i32,
    ) -> HaltonSampler {
        let primes = primes(PRIME_TABLE_SIZE);
        let permutations = if randomization == HaltonRandomization::PermuteDigits {
            primes.iter().map(|&b| DigitPermutation::new(b, seed as u32)).collect()
        } else {
            Vec::new()
        };
        let mut base_scales = [1u64; 2];
        let mut base_exponents = [0u32; 2];
        for (i, base) in [2u64, 3].into_iter().enumerate() {
            let target = u64::from(full_resolution[i].min(MAX_RESOLUTION));
            while base_scales[i] < target {
                base_scales[i] *= base;
                base_exponents[i] += 1;
            }
        }
        let mult_inverse = [
            multiplicative_inverse(base_scales[1] as i64, base_scales[0] as i64),
            multiplicative_inverse(base_scales[0] as i64, base_scales[1] as i64),
        ];
        HaltonSampler {
            samples_per_pixel,
            randomization,
            tables: Arc::new(Tables { primes, permutations }),
            base_scales,
            base_exponents,
            mult_inverse,
            halton_index: 0,
            dimension: 0,
            seed,
            pixel_key: 0,
        }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.samples_per_pixel
    }

    /// Starts sample `sample_index` of `pixel` at `dimension` (at least 2: the first two
    /// dimensions are the pixel's own).
    pub fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32, dimension: u32) {
        let stride = self.base_scales[0] * self.base_scales[1];
        let mut index = 0u64;
        if stride > 1 {
            let pm = [u64::from(pixel.x % MAX_RESOLUTION), u64::from(pixel.y % MAX_RESOLUTION)];
            for (i, (p, base)) in pm.into_iter().zip([2, 3]).enumerate() {
                let offset = inverse_radical_inverse(p, base, self.base_exponents[i]);
                index += offset * (stride / self.base_scales[i]) * self.mult_inverse[i];
            }
            index %= stride;
        }
        self.halton_index = index + u64::from(sample_index) * stride;
        self.dimension = dimension.max(2);
        self.pixel_key = (u64::from(pixel.x) << 32) | u64::from(pixel.y);
    }

    fn sample_dimension(&self, dimension: u32) -> f32 {
        let base = self.tables.primes[dimension as usize];
        match self.randomization {
            HaltonRandomization::None => radical_inverse(base, self.halton_index),
            HaltonRandomization::PermuteDigits => {
                scrambled_radical_inverse(&self.tables.permutations[dimension as usize], self.halton_index)
            }
            HaltonRandomization::Owen => owen_scrambled_radical_inverse(
                base,
                self.halton_index,
                mix_bits(1 + (u64::from(dimension) << 4)) as u32,
            ),
        }
    }

    /// The next dimension.
    pub fn get_1d(&mut self) -> f32 {
        if self.dimension as usize >= PRIME_TABLE_SIZE {
            self.dimension = 2;
        }
        let d = self.dimension;
        self.dimension += 1;
        self.sample_dimension(d)
    }

    /// The next two dimensions.
    pub fn get_2d(&mut self) -> Vec2 {
        if self.dimension as usize + 1 >= PRIME_TABLE_SIZE {
            self.dimension = 2;
        }
        let d = self.dimension;
        self.dimension += 2;
        Vec2::new(self.sample_dimension(d), self.sample_dimension(d + 1))
    }

    /// The next two dimensions, the second rotated (Cranley–Patterson, modulo 1) per pixel by
    /// a hash of the pixel, the dimension and the seed: a pixel's samples stay stratified,
    /// and two seeds' values no longer share one relation over the whole image (see
    /// `ZSobolSampler::get_2d_shifted_y`; the digit permutations are the seed's, global).
    pub fn get_2d_shifted_y(&mut self) -> Vec2 {
        let v = self.get_2d();
        let h = self.rotation(self.dimension - 2);
        Vec2::new(v.x, rotate(v.y, (h >> 32) as u32))
    }

    /// The next dimension, rotated per pixel as [`Self::get_2d_shifted_y`]'s second.
    pub fn get_1d_shifted(&mut self) -> f32 {
        let v = self.get_1d();
        rotate(v, self.rotation(self.dimension - 1) as u32)
    }

    /// Hash bits of the current pixel, dimension `d` and the seed.
    fn rotation(&self, d: u32) -> u64 {
        let key = (u64::from(d) << 32) | self.seed as u32 as u64;
        mix_bits(self.pixel_key ^ mix_bits(key ^ 0x2545_f491_4f6c_dd1d))
    }

    /// The film position within the pixel: the first two (pixel-scaled) dimensions.
    pub fn get_pixel_2d(&mut self) -> Vec2 {
        Vec2::new(
            radical_inverse(2, self.halton_index >> self.base_exponents[0]),
            radical_inverse(3, self.halton_index / self.base_scales[1]),
        )
    }
}

/// `v` + `bits` / 2^32, modulo 1.
fn rotate(v: f32, bits: u32) -> f32 {
    let r = v + bits as f32 * (1.0 / 4_294_967_296.0);
    (if r >= 1.0 { r - 1.0 } else { r }).min(ONE_MINUS_EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radical_inverses_and_their_inverse() {
        assert_eq!(radical_inverse(2, 1), 0.5);
        assert_eq!(radical_inverse(2, 6), 0.375); // 110₂ → 0.011₂
        assert!((radical_inverse(3, 5) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-6); // 12₃ → 0.21₃
        assert_eq!(inverse_radical_inverse(3, 2, 3), 6); // 011 reversed over 3 digits: 110
        assert_eq!(multiplicative_inverse(3, 7), 5);
        assert_eq!(&primes(6), &[2, 3, 5, 7, 11, 13]);
        // A digit permutation permutes.
        let p = DigitPermutation::new(5, 7);
        for d in 0..p.n_digits {
            let mut seen: Vec<u32> = (0..5).map(|v| p.permute(d, v)).collect();
            seen.sort();
            assert_eq!(seen, vec![0, 1, 2, 3, 4]);
        }
    }

    #[test]
    fn each_pixel_gets_the_halton_points_that_fall_in_it() {
        // With the plain sequence, the pixel sample's film position lies in the pixel's cell
        // of the 2^a × 3^b grid the first two dimensions are scaled to.
        let res = UVec2::new(8, 9);
        let mut s = HaltonSampler::new(16, res, HaltonRandomization::None, 0);
        for pixel in [UVec2::new(0, 0), UVec2::new(5, 7), UVec2::new(7, 8)] {
            for i in 0..16 {
                s.start_pixel_sample(pixel, i, 0);
                let x = radical_inverse(2, s.halton_index) * 8.0;
                let y = radical_inverse(3, s.halton_index) * 9.0;
                assert_eq!((x.floor() as u32, y.floor() as u32), (pixel.x, pixel.y), "{pixel} sample {i}");
            }
        }
    }
}
