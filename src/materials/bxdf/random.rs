//! pbrt-v4's PCG32 generator (`util/rng.h`, O'Neill 2014), used by the BxDF tests.

use crate::sampling::warp::ONE_MINUS_EPSILON;

const PCG32_DEFAULT_STATE: u64 = 0x853c_49e6_748f_ea9b;
const PCG32_DEFAULT_STREAM: u64 = 0xda3e_39cb_94b9_5bdb;
const PCG32_MULT: u64 = 0x5851_f42d_4c95_7f2d;

/// pbrt-v4's `RNG`: a PCG32 generator with a selectable sequence (stream).
#[derive(Clone, Debug)]
pub(crate) struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Default for Pcg32 {
    fn default() -> Pcg32 {
        Pcg32 {
            state: PCG32_DEFAULT_STATE,
            inc: PCG32_DEFAULT_STREAM,
        }
    }
}

impl Pcg32 {
    /// pbrt-v4's `RNG(seqIndex, start)`, i.e. `SetSequence(sequence_index, seed)`.
    pub(crate) fn new(sequence_index: u64, seed: u64) -> Pcg32 {
        let mut rng = Pcg32 {
            state: 0,
            inc: (sequence_index << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// Next 32 random bits (PCG-XSH-RR).
    #[inline]
    pub(crate) fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG32_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform float in [0, 1).
    #[inline]
    pub(crate) fn uniform(&mut self) -> f32 {
        (self.next_u32() as f32 * (1.0 / 4_294_967_296.0)).min(ONE_MINUS_EPSILON)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_matches_the_reference_generator() {
        // O'Neill's pcg32-demo: seed 42, sequence 54 gives these first outputs.
        let mut rng = Pcg32::new(54, 42);
        let expected = [
            0xa15c_02b7u32,
            0x7b47_f409,
            0xba1d_3330,
            0x83d2_f293,
            0xbfa4_784b,
            0xcbed_606e,
        ];
        for e in expected {
            assert_eq!(rng.next_u32(), e);
        }
        let mut d = Pcg32::default();
        for _ in 0..1000 {
            let u = d.uniform();
            assert!((0.0..1.0).contains(&u));
        }
    }
}
