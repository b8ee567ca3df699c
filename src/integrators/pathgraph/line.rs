//! How many extra first vertices a graph sample takes along each camera ray
//! ([`crate::integrators::common::PathConfig::line_direct`]) when the scene does not say
//! (`integer linesamples`).
//!
//! A pixel's direct light at its first vertex is not aggregated (Sec. 4), so where it is most
//! of the pixel (a cloud lit from behind, a bright rim) its noise is most of the graph's, and
//! more first collisions along the camera ray, each with a light sample, divide it. With n
//! such estimates the pixel's variance is V_D/n + V_I (V_D one estimate's, V_I the rest's)
//! at a cost C + (n − 1)c, which is least at n = √((C/c) V_D/V_I). The first two samples
//! take [`PROBE`] extra ones and measure V_D (the extra estimates' own spread) and the total
//! (the two samples' difference per pixel); the rest take the n that minimises the product.
//! The choice depends only on the samples, not on timing or the thread count, and each
//! sample's count is fixed before it is drawn, so every sample stays unbiased.
//!
//! The paths' own estimate U (the samples the graph no longer pays for, `unpaired.rs`) takes
//! its own count by the same rule: its rest is path-traced, far noisier than the graph's, so
//! it takes fewer (2 against 6 to 9 on the back-lit cloud), and C is a path's cost.

/// Extra first vertices in the two samples that measure.
pub(super) const PROBE: u32 = 2;
/// The most the rule takes.
const MAX: u32 = 16;
/// C/c: a graph sample's cost over one extra first vertex's (a delta-tracked collision and a
/// light sample). Measured: 24 on a back-lit dense cloud (128², 16 spp: 0.95 s without
/// extra vertices, +0.04 s per extra vertex), 16 on the Disney cloud (320×180, 4 spp: 3.72 s,
/// +0.23 s each). The optimum is flat: a factor of 2 in C/c moves n by √2.
const COST_RATIO: f64 = 16.0;
/// C/c for U alone: a path's cost over one extra first vertex's. Measured: 15 on the back-lit
/// cloud (128², 32 spp per camera ray: 0.033 s per sample without extra vertices, +0.0022 s
/// per extra vertex).
const OWN_COST_RATIO: f64 = 15.0;

/// The measurements and the choice.
#[derive(Debug, Default)]
pub(super) struct LineTuning {
    passes: u32,
    chosen: Option<u32>,
    /// The count for U alone, chosen with `chosen`.
    own: Option<u32>,
    /// The first sample's pixel values, L and U (means of the channels), by pixel index.
    first: Vec<[f32; 2]>,
    /// Σ of the extra estimates' sample variances (each sample's summed in tile order), and
    /// the number of paths.
    spread: f64,
    paths: f64,
    /// Σ over pixels of half the squared difference between the two samples, of L and of U,
    /// and their counts.
    diff: [f64; 2],
    pixels: [f64; 2],
    /// V_D and the total variance per sample, once measured (for `--stats`).
    pub(super) measured: Option<(f64, f64)>,
}

impl LineTuning {
    /// Extra first vertices for the next sample.
    pub(super) fn samples(&self) -> u32 {
        self.chosen.unwrap_or(PROBE)
    }

    /// Extra first vertices for a sample of the paths' own estimate alone.
    pub(super) fn own_samples(&self) -> u32 {
        self.own.unwrap_or(0)
    }

    /// Whether the count has been chosen.
    pub(super) fn chosen(&self) -> Option<u32> {
        self.chosen
    }

    /// A sample is done: `spread` is its paths' Σ of sample variances (over `paths` paths),
    /// `pixels` its pixel values (index, means of the channels of L and of U, U NaN when
    /// there is none), in any order.
    pub(super) fn observe(&mut self, spread: f64, paths: usize, pixels: impl Iterator<Item = (u32, [f32; 2])>) {
        if self.chosen.is_some() {
            return;
        }
        self.spread += spread;
        self.paths += paths as f64;
        if self.passes == 0 {
            for (i, v) in pixels {
                let i = i as usize;
                if i >= self.first.len() {
                    self.first.resize(i + 1, [f32::NAN; 2]);
                }
                self.first[i] = v;
            }
        } else {
            // Summed in pixel order, whatever order the pixels came in (tiles finish in any
            // order): the choice does not depend on the thread count.
            let mut second = vec![[f32::NAN; 2]; self.first.len()];
            for (i, v) in pixels {
                if let Some(s) = second.get_mut(i as usize) {
                    *s = v;
                }
            }
            for (a, b) in self.first.iter().zip(&second) {
                for k in 0..2 {
                    if a[k].is_finite() && b[k].is_finite() {
                        self.diff[k] += 0.5 * f64::from(b[k] - a[k]).powi(2);
                        self.pixels[k] += 1.0;
                    }
                }
            }
            let v_d = if self.paths > 0.0 { self.spread / self.paths } else { 0.0 };
            let [total, own] = [0, 1].map(|k| if self.pixels[k] > 0.0 { self.diff[k] / self.pixels[k] } else { 0.0 });
            self.measured = Some((v_d, total));
            self.chosen = Some(choose(v_d, total, COST_RATIO));
            self.own = Some(if self.pixels[1] > 0.0 { choose(v_d, own, OWN_COST_RATIO) } else { 0 });
            self.first = Vec::new();
        }
        self.passes += 1;
    }
}

/// The extra first vertices that minimise variance × cost, from one estimate's variance `v_d`
/// and the pixels' total variance `total` measured with [`PROBE`] extra ones, for a sample
/// `cost_ratio` times as costly as one extra vertex.
fn choose(v_d: f64, total: f64, cost_ratio: f64) -> u32 {
    if v_d <= 0.0 || !v_d.is_finite() || !total.is_finite() {
        return 0;
    }
    // The rest's variance: what the measured total leaves once the direct light's share is
    // taken out (kept above a twentieth of the total, the measurements being noisy).
    let rest = (total - v_d / f64::from(PROBE + 1)).max(0.05 * total).max(1e-30);
    let n = (cost_ratio * v_d / rest).sqrt();
    (n.round() - 1.0).clamp(0.0, f64::from(MAX)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_takes_more_where_direct_light_is_the_noise() {
        // No direct-light noise: none; as much as the rest: about √16 = 4 estimates.
        assert_eq!(choose(0.0, 1.0, COST_RATIO), 0);
        assert_eq!(choose(1.0, 1.0 + 1.0 / 3.0, COST_RATIO), 3);
        // Direct light a tenth of the rest: √1.6 ≈ 1 estimate, the path's own.
        assert_eq!(choose(0.1, 1.0, COST_RATIO), 0);
        // Direct light all of it: the most.
        assert_eq!(choose(3.0, 1.0, COST_RATIO), MAX);
    }

    #[test]
    fn the_count_is_chosen_after_two_samples_from_their_difference() {
        let mut t = LineTuning::default();
        assert_eq!(t.samples(), PROBE);
        // Two samples of 4 pixels whose L differs by 2 (total variance 2 per pixel) and U by 6
        // (18), one estimate's direct-light variance 3 (spread summed over 4 paths per sample).
        t.observe(12.0, 4, (0..4).map(|i| (i, [1.0, 1.0])));
        assert_eq!(t.chosen(), None);
        t.observe(12.0, 4, (0..4).map(|i| (i, [3.0, 7.0])));
        let (v_d, total) = t.measured.unwrap();
        assert_eq!((v_d, total), (3.0, 2.0));
        // rest = 2 − 3/3 = 1: n = √(16·3) ≈ 6.9, so 6 extra.
        assert_eq!(t.chosen(), Some(6));
        // U's rest is 18 − 1 = 17: n = √(15·3/17) ≈ 1.6, so 1 extra.
        assert_eq!(t.own_samples(), 1);
        t.observe(1e9, 4, (0..4).map(|i| (i, [1e9, 1e9])));
        assert_eq!(t.samples(), 6);
    }
}
