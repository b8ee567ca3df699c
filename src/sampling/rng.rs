//! The deterministic random numbers of pbrt-v4's stochastic BxDFs: its PCG32 generator
//! (`util/rng.h`, O'Neill 2014) seeded by MurmurHash64A of the directions involved
//! (`util/hash.h`), so that evaluating the same (ωo, ωi) twice gives the same estimate.

use glam::{Vec2, Vec3};

use crate::sampling::warp::ONE_MINUS_EPSILON;

const PCG32_DEFAULT_STATE: u64 = 0x853c_49e6_748f_ea9b;
const PCG32_DEFAULT_STREAM: u64 = 0xda3e_39cb_94b9_5bdb;
const PCG32_MULT: u64 = 0x5851_f42d_4c95_7f2d;

/// pbrt-v4's `RNG`: a PCG32 generator with a selectable sequence (stream).
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Default for Pcg32 {
    fn default() -> Pcg32 {
        Pcg32 { state: PCG32_DEFAULT_STATE, inc: PCG32_DEFAULT_STREAM }
    }
}

impl Pcg32 {
    /// pbrt-v4's `RNG(seqIndex, start)`, i.e. `SetSequence(sequence_index, seed)`.
    pub fn new(sequence_index: u64, seed: u64) -> Pcg32 {
        let mut rng = Pcg32 { state: 0, inc: (sequence_index << 1) | 1 };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// Next 32 random bits (PCG-XSH-RR).
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG32_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform float in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f32 {
        (self.next_u32() as f32 * (1.0 / 4_294_967_296.0)).min(ONE_MINUS_EPSILON)
    }
}

/// MurmurHash64A (Appleby) of `key`, as pbrt-v4 uses it for `Hash(...)`.
pub fn murmur_hash64a(key: &[u8], seed: u64) -> u64 {
    const M: u64 = 0xc6a4_a793_5bd1_e995;
    const R: u32 = 47;
    let mut h = seed ^ (key.len() as u64).wrapping_mul(M);
    let mut chunks = key.chunks_exact(8);
    for chunk in &mut chunks {
        let mut k = u64::from_le_bytes(chunk.try_into().expect("8-byte chunk"));
        k = k.wrapping_mul(M);
        k ^= k >> R;
        k = k.wrapping_mul(M);
        h ^= k;
        h = h.wrapping_mul(M);
    }
    let tail = chunks.remainder();
    if !tail.is_empty() {
        for (i, &b) in tail.iter().enumerate() {
            h ^= (b as u64) << (8 * i);
        }
        h = h.wrapping_mul(M);
    }
    h ^= h >> R;
    h = h.wrapping_mul(M);
    h ^= h >> R;
    h
}

/// pbrt-v4's `Hash(a, b, c, ...)` for up to four f32 values (their bytes, packed).
fn hash_f32s<const N: usize>(values: [f32; N]) -> u64 {
    let mut buf = [0u8; 16];
    for (i, v) in values.iter().enumerate() {
        buf[4 * i..4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
    murmur_hash64a(&buf[..4 * N], 0)
}

/// pbrt-v4's `Hash(seed, w)` for an `int` seed and a `Vector3f`.
pub fn hash_seed_vec3(seed: i32, w: Vec3) -> u64 {
    hash_f32s([f32::from_bits(seed as u32), w.x, w.y, w.z])
}

/// pbrt-v4's `Hash(w)` for a `Vector3f`.
pub fn hash_vec3(w: Vec3) -> u64 {
    hash_f32s([w.x, w.y, w.z])
}

/// pbrt-v4's `Hash(uc, u)` for a `Float` and a `Point2f`.
pub fn hash_sample(uc: f32, u: Vec2) -> u64 {
    hash_f32s([uc, u.x, u.y])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_matches_the_reference_generator() {
        // O'Neill's pcg32-demo: seed 42, sequence 54 gives these first outputs.
        let mut rng = Pcg32::new(54, 42);
        let expected = [0xa15c_02b7u32, 0x7b47_f409, 0xba1d_3330, 0x83d2_f293, 0xbfa4_784b, 0xcbed_606e];
        for e in expected {
            assert_eq!(rng.next_u32(), e);
        }
        let mut d = Pcg32::default();
        for _ in 0..1000 {
            let u = d.uniform();
            assert!((0.0..1.0).contains(&u));
        }
    }

    #[test]
    fn murmur_hash_is_stable_and_reads_tails() {
        // Reference values of MurmurHash64A with seed 0.
        assert_eq!(murmur_hash64a(b"", 0), 0);
        let a = murmur_hash64a(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12], 0);
        let b = murmur_hash64a(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 13], 0);
        assert_ne!(a, b, "the tail bytes must matter");
        assert_eq!(hash_vec3(Vec3::new(0.1, 0.2, 0.3)), hash_vec3(Vec3::new(0.1, 0.2, 0.3)));
        // Hash(uc, u) packs the same 12 bytes as Hash(Vector3f(uc, u.x, u.y)).
        assert_eq!(hash_vec3(Vec3::new(0.1, 0.2, 0.3)), hash_sample(0.1, Vec2::new(0.2, 0.3)));
        assert_ne!(hash_seed_vec3(0, Vec3::X), hash_seed_vec3(1, Vec3::X));
    }
}
