//! Hashing helpers shared by the samplers: bit mixing, random permutations, Morton codes and
//! a counter-based uniform generator. Bit-exact with pbrt-v4 where pbrt has the function
//! (`util/hash.h`, `util/math.h`), so the samplers built on them reproduce pbrt's sequences.

use glam::UVec2;

use crate::sampling::warp::ONE_MINUS_EPSILON;

/// pbrt-v4's `MixBits`: a 64-bit finalizer (Stafford's "Mix04" variant of MurmurHash3's).
#[inline]
pub(crate) fn mix_bits(mut v: u64) -> u64 {
    v ^= v >> 31;
    v = v.wrapping_mul(0x7fb5_d329_728e_a185);
    v ^= v >> 27;
    v = v.wrapping_mul(0x81da_def4_bc2d_d44d);
    v ^= v >> 33;
    v
}

/// pbrt-v4's `PermutationElement` (Kensler, "Correlated Multi-Jittered Sampling", 2013): the
/// image of `i` under a random permutation of `0..l` chosen by `p`, without storing it.
#[inline]
pub(crate) fn permutation_element(mut i: u32, l: u32, p: u32) -> u32 {
    debug_assert!(l > 0);
    let mut w = l.wrapping_sub(1);
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    // Cycle-walk: a bijection on 0..=w, repeated until the image lands inside 0..l.
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    (i.wrapping_add(p)) % l
}

/// Spreads the bits of `x` to the even bit positions of a u64.
#[inline]
fn left_shift2(x: u32) -> u64 {
    let mut x = x as u64;
    x = (x ^ (x << 16)) & 0x0000_ffff_0000_ffff;
    x = (x ^ (x << 8)) & 0x00ff_00ff_00ff_00ff;
    x = (x ^ (x << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
    x = (x ^ (x << 2)) & 0x3333_3333_3333_3333;
    x = (x ^ (x << 1)) & 0x5555_5555_5555_5555;
    x
}

/// pbrt-v4's `EncodeMorton2`: x in the even bits, y in the odd ones.
#[inline]
pub(crate) fn encode_morton2(x: u32, y: u32) -> u64 {
    (left_shift2(y) << 1) | left_shift2(x)
}

/// A float in [0, 1) from the top 24 bits of `h` (every such float is exact).
#[inline]
pub(crate) fn unit_from_bits(h: u64) -> f32 {
    ((h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)).min(ONE_MINUS_EPSILON)
}

/// pbrt-v4's `Hash(pixel, dimension, seed)` (MurmurHash64A of the four 32-bit integers), the
/// key of the per-pixel, per-dimension shuffles of the padded samplers.
#[inline]
pub(crate) fn pixel_dimension_hash(pixel: UVec2, dimension: u32, seed: i32) -> u64 {
    let mut bytes = [0u8; 16];
    bytes[0..4].copy_from_slice(&(pixel.x as i32).to_le_bytes());
    bytes[4..8].copy_from_slice(&(pixel.y as i32).to_le_bytes());
    bytes[8..12].copy_from_slice(&(dimension as i32).to_le_bytes());
    bytes[12..16].copy_from_slice(&seed.to_le_bytes());
    crate::sampling::rng::murmur_hash64a(&bytes, 0)
}

/// Golden-ratio increment of SplitMix64 (Steele, Lea and Flood, OOPSLA 2014).
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// Key of the stream of one pixel sample: a hash of the pixel, the sample index and the seed.
#[inline]
pub(crate) fn sample_key(pixel: UVec2, sample_index: u32, seed: i32) -> u64 {
    let p = ((pixel.x as u64) << 32) | pixel.y as u64;
    let s = ((sample_index as u64) << 32) | seed as u32 as u64;
    mix_bits(p ^ mix_bits(s).wrapping_add(GOLDEN))
}

/// Counter-based uniform number: value `counter` of the stream `key`, SplitMix64-style. No
/// state is carried, so a value depends on its inputs alone and never on call order.
#[inline]
pub(crate) fn hashed_uniform(key: u64, counter: u32) -> f32 {
    unit_from_bits(mix_bits(key.wrapping_add((counter as u64 + 1).wrapping_mul(GOLDEN))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_element_is_a_permutation() {
        for l in [1u32, 2, 5, 16, 17, 100] {
            for p in [0u32, 1, 0xdead_beef, 12345] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permutation_element(i, l, p) as usize;
                    assert!(!seen[j], "l {l} p {p}: {j} twice");
                    seen[j] = true;
                }
            }
        }
    }

    #[test]
    fn morton_interleaves_x_low() {
        assert_eq!(encode_morton2(1, 0), 1);
        assert_eq!(encode_morton2(0, 1), 2);
        assert_eq!(encode_morton2(3, 5), 0b100111);
        assert_eq!(encode_morton2(u32::MAX, 0), 0x5555_5555_5555_5555);
    }

    #[test]
    fn mix_bits_matches_pbrt() {
        // Values of pbrt-v4's MixBits from an independent (Python) transcription.
        assert_eq!(mix_bits(0), 0);
        assert_eq!(mix_bits(1), 0xccde_22c1_faa4_d20f);
        assert_eq!(mix_bits(0x0123_4567_89ab_cdef), 0x0eb3_513c_40b1_1a29);
    }
}
