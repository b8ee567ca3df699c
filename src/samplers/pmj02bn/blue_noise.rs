//! Blue-noise dither textures by the void-and-cluster method (Ulichney, "The void-and-cluster
//! method for dither array generation", 1993).
//!
//! pbrt-v4's pmj02bn sampler offsets each pixel's points by values from 48 precomputed
//! 128 × 128 blue-noise textures; nimbus generates its own. A texture is a ranking of its
//! pixels: ranks that are close in value are far apart in space, at every threshold.

use crate::sampling::rng::Pcg32;

/// Gaussian filter width of the energy, in pixels (Ulichney's σ = 1.5).
const SIGMA: f32 = 1.5;
/// Half-width of the truncated filter: the Gaussian is 1.8·10⁻⁵ of its peak there.
const REACH: isize = 7;

/// A `size`×`size` (a power of two) void-and-cluster texture from `seed`: the rank of each
/// pixel (row-major), scaled to 16 bits (`rank · 65536 / size²`).
pub(super) fn void_and_cluster(size: usize, seed: u64) -> Vec<u16> {
    let n = size * size;
    let mut field = Energy::new(size);
    let mut rng = Pcg32::new(seed, 0x766f_6964);
    // An initial pattern of a tenth of the pixels, at random.
    let ones = n / 10;
    while field.count < ones {
        let i = (rng.next_u32() as usize) % n;
        if !field.on[i] {
            field.set(i, true);
        }
    }
    // Move the tightest cluster into the largest void until that changes nothing.
    for _ in 0..n {
        let cluster = field.extreme(true);
        field.set(cluster, false);
        let void = field.extreme(false);
        if void == cluster {
            field.set(cluster, true);
            break;
        }
        field.set(void, true);
    }
    let mut rank = vec![0usize; n];
    // Phase 1: remove the tightest cluster repeatedly; the pattern's pixels get ranks ones-1..0.
    let mut removing = field.clone();
    for r in (0..ones).rev() {
        let cluster = removing.extreme(true);
        removing.set(cluster, false);
        rank[cluster] = r;
    }
    // Phases 2 and 3: fill the largest void repeatedly. With a normalised filter the largest
    // void of the ones is the tightest cluster of the zeros, so one rule serves both halves.
    for r in ones..n {
        let void = field.extreme(false);
        field.set(void, true);
        rank[void] = r;
    }
    rank.into_iter().map(|r| (r * 65536 / n) as u16).collect()
}

/// The filtered pattern: which pixels are set, and the Gaussian-weighted sum of set pixels
/// around each (toroidal). Minima and maxima are found through per-row summaries, so each
/// change costs the filter's rows, not a scan of the texture.
#[derive(Clone)]
struct Energy {
    size: usize,
    on: Vec<bool>,
    energy: Vec<f32>,
    count: usize,
    kernel: Vec<f32>,
    /// Per row: (max energy among set pixels, its index), (min among unset, its index).
    rows: Vec<[(f32, usize); 2]>,
}

impl Energy {
    fn new(size: usize) -> Energy {
        let width = 2 * REACH + 1;
        let mut kernel = Vec::with_capacity((width * width) as usize);
        for dy in -REACH..=REACH {
            for dx in -REACH..=REACH {
                kernel.push((-((dx * dx + dy * dy) as f32) / (2.0 * SIGMA * SIGMA)).exp());
            }
        }
        let mut e = Energy {
            size,
            on: vec![false; size * size],
            energy: vec![0.0; size * size],
            count: 0,
            kernel,
            rows: vec![[(0.0, 0); 2]; size],
        };
        for y in 0..size {
            e.summarise(y);
        }
        e
    }

    fn set(&mut self, i: usize, on: bool) {
        if self.on[i] == on {
            return;
        }
        self.on[i] = on;
        self.count = if on { self.count + 1 } else { self.count - 1 };
        let sign = if on { 1.0 } else { -1.0 };
        let s = self.size as isize;
        let (x, y) = ((i % self.size) as isize, (i / self.size) as isize);
        let width = (2 * REACH + 1) as usize;
        for dy in -REACH..=REACH {
            let row = (y + dy).rem_euclid(s) as usize;
            let weights = &self.kernel[(dy + REACH) as usize * width..][..width];
            for (dx, w) in (-REACH..=REACH).zip(weights) {
                let col = (x + dx).rem_euclid(s) as usize;
                self.energy[row * self.size + col] += sign * w;
            }
        }
        for dy in -REACH..=REACH {
            self.summarise((y + dy).rem_euclid(s) as usize);
        }
    }

    fn summarise(&mut self, y: usize) {
        let mut cluster = (f32::NEG_INFINITY, usize::MAX);
        let mut void = (f32::INFINITY, usize::MAX);
        for i in y * self.size..(y + 1) * self.size {
            let e = self.energy[i];
            if self.on[i] {
                if e > cluster.0 {
                    cluster = (e, i);
                }
            } else if e < void.0 {
                void = (e, i);
            }
        }
        self.rows[y] = [cluster, void];
    }

    /// The set pixel of highest energy (`on`: the tightest cluster) or the unset one of
    /// lowest energy (the largest void). Ties go to the lowest index.
    fn extreme(&self, on: bool) -> usize {
        let mut best = self.rows[0][usize::from(!on)];
        for row in &self.rows[1..] {
            let c = row[usize::from(!on)];
            let better = if on { c.0 > best.0 } else { c.0 < best.0 };
            if better {
                best = c;
            }
        }
        best.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rank_appears_once() {
        let t = void_and_cluster(32, 1);
        let mut seen = [false; 1024];
        for v in t {
            let r = v as usize * 1024 / 65536;
            assert!(!std::mem::replace(&mut seen[r], true), "rank {r} twice");
        }
    }

    #[test]
    fn thresholds_spread_evenly() {
        // Blue noise: the pixels below any threshold are spread out, so no 4×4 block holds far
        // more or fewer of them than its share. White noise at 1/4 density puts 4 ± 1.7 in a
        // block (binomial); void-and-cluster keeps every block within ±2 of 4.
        let size = 64;
        let t = void_and_cluster(size, 2);
        let threshold: u16 = 16384;
        for by in 0..size / 4 {
            for bx in 0..size / 4 {
                let count = (0..16).filter(|k| t[(by * 4 + k / 4) * size + bx * 4 + k % 4] < threshold).count();
                assert!((2..=6).contains(&count), "block ({bx}, {by}) holds {count}");
            }
        }
    }
}
