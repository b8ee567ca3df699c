//! A biased estimate combined per pixel with the unbiased estimate its own samples carry.
//!
//! A method whose samples give both a low-variance but biased value L (a path graph's
//! aggregate) and an unbiased value U of the same pixel (the path-traced estimate the same
//! paths carry) hands both to the film. The film keeps, besides the means L̄ and Ū, the
//! moments that say how much each can be trusted, and the image is
//!
//!   C = Ū + ω (L̄ − Ū),   ω = −Cov(Ū, D̄) / E[D̄²],   D = L − U,
//!
//! the ω that minimises E[(C − μ)²] when ω is known (E[(Ū − μ) D̄] = Cov(Ū, D̄) because Ū is
//! unbiased; E[D̄²] = b² + Var(D̄) with b the bias of L). Both are estimated from the samples:
//! Cov(Ū, D̄) = Cov(U, D)/n by the sample covariance, E[D̄²] by D̄² itself (its unbiased
//! estimate), each summed over a window of pixels around the pixel (the bias and the noise
//! vary smoothly across the image; one pixel's few samples say little about either).
//!
//! The weight must not be estimated from the samples it weighs. Where U is heavy-tailed (a
//! caustic's rare bright paths), a window without a bright path has a low Ū, a small sample
//! covariance and a large D̄², so ω picks the low Ū; a window with one has a large
//! covariance, so ω drops the bright path: both pull the image down (wax-small-light: −6.9 %
//! at 8 spp). So the samples are split by pass into two halves, even and odd, and each
//! half's D̄ is weighted by the ω of the other half: E[ω_odd · D̄_even] = E[ω_odd] · b, and
//! the combination's bias is b times the mean weight, which tends to 0.
//!
//! When L is unbiased, E[D̄²] = Var(D)/n and ω stays near its n-independent optimum (near 1
//! when L's noise is much lower than U's). When it is biased, Cov(Ū, D̄) falls as 1/n while
//! D̄² tends to b², so ω → 0 and C tends to Ū: the image converges to the right answer
//! whatever the bias, which L alone does not. At n = 1 nothing can be estimated and C = L̄.
//! The idea is the James-Stein-style combination of a biased and an unbiased rendering
//! (Gu, Iglesias-Guitian and Moon, "Neural James-Stein Combiner for Unbiased and Biased
//! Renderings", ACM TOG 41(6), 2022), here with the closed-form weight and no network.

use crate::color::Rgb;

/// Half-width of the square window of pixels whose statistics set a pixel's ω (33×33): on
/// the Disney cloud at 10 s (6 spp) the relMSE was 6.0e-2 with 7×7, 4.1e-2 with 17×17 and
/// 3.9e-2 with 33×33 (the graph alone: 3.7e-2); on cloud-sun-sky at 1.5 s 6.1e-4, 5.7e-4,
/// 5.3e-4 (alone: 5.5e-4); on the back-lit cloud the same within noise.
const RADIUS: usize = 16;

/// Unweighted moments of one half's samples: x = U's channel mean, y = D's channel mean.
/// Single precision: they only set ω (a relative error of 1e-5 in a sum moves ω by as much),
/// and the film's pixel grows by 72 bytes instead of 112.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    n: u32,
    x: f32,
    y: f32,
    xy: f32,
}

impl Moments {
    /// −Cov(Ū, D̄) and D̄² of this half, or None below two samples.
    fn estimate(&self) -> Option<(f64, f64)> {
        if self.n < 2 {
            return None;
        }
        let (n, x, y, xy) = (self.n as f64, self.x as f64, self.y as f64, self.xy as f64);
        let cov = (xy - x * y / n) / (n - 1.0);
        let d = y / n;
        Some((-cov / n, d * d))
    }
}

/// One pixel's sums over its paired samples (the film keeps Σ w·L and Σ w of all of them).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PairSums {
    /// Σ w·U, weighted by the filter as the film weighs L (double precision, as the film's
    /// sums: where L is biased, the image tends to this mean).
    unbiased: [f64; 3],
    /// Σ w·(L − U) over the even passes' samples (the odd ones' is the rest of the total).
    diff_even: [f32; 3],
    /// The even and the odd passes' moments.
    halves: [Moments; 2],
}

impl PairSums {
    /// Adds one sample of pass `pass`: its (clamped) estimates `l` and `u` with filter
    /// weight `w`.
    #[inline]
    pub fn add(&mut self, l: Rgb, u: Rgb, w: f32, pass: u32) {
        let even = pass.is_multiple_of(2);
        for c in 0..3 {
            self.unbiased[c] += w as f64 * u[c] as f64;
            if even {
                self.diff_even[c] += w * (l[c] - u[c]);
            }
        }
        let x = (u[0] + u[1] + u[2]) / 3.0;
        let y = (l[0] + l[1] + l[2]) / 3.0 - x;
        let m = &mut self.halves[(pass % 2) as usize];
        m.n += 1;
        m.x += x;
        m.y += y;
        m.xy += x * y;
    }
}

/// Each pixel's ω from the even passes' and from the odd passes' samples, in a
/// `width`-wide image (row-major `pairs`); 1 where a half has fewer than two samples.
fn weights(width: usize, pairs: &[PairSums]) -> Vec<[f64; 2]> {
    let [even, odd] = [0, 1].map(|h| half_weights(width, pairs, h));
    even.into_iter().zip(odd).map(|(e, o)| [e, o]).collect()
}

/// ω at every pixel from half `h`'s moments, summed over the window around it.
fn half_weights(width: usize, pairs: &[PairSums], h: usize) -> Vec<f64> {
    let height = pairs.len().checked_div(width).unwrap_or(0);
    // Summed-area table of the two moments.
    let stride = width + 1;
    let mut sat = vec![[0.0f64; 2]; stride * (height + 1)];
    for y in 0..height {
        let mut row = [0.0f64; 2];
        for x in 0..width {
            if let Some((a, b)) = pairs[y * width + x].halves[h].estimate() {
                row[0] += a;
                row[1] += b;
            }
            let above = sat[y * stride + x + 1];
            sat[(y + 1) * stride + x + 1] = [above[0] + row[0], above[1] + row[1]];
        }
    }
    let mut out = vec![1.0; pairs.len()];
    for y in 0..height {
        let (y0, y1) = (y.saturating_sub(RADIUS), (y + RADIUS + 1).min(height));
        for x in 0..width {
            if pairs[y * width + x].halves[h].n < 2 {
                continue;
            }
            let (x0, x1) = (x.saturating_sub(RADIUS), (x + RADIUS + 1).min(width));
            let s = |k: usize| {
                sat[y1 * stride + x1][k] - sat[y0 * stride + x1][k] - sat[y1 * stride + x0][k]
                    + sat[y0 * stride + x0][k]
            };
            let (a, b) = (s(0), s(1));
            // b = 0: the two estimates agree exactly (a cluster of one); ω does not matter.
            out[y * width + x] = if b > 0.0 { (a / b).clamp(0.0, 1.0) } else { 1.0 };
        }
    }
    out
}

/// The combined mean of every pixel of a `width`-wide image: `totals` are the film's Σ w·L
/// and Σ w per pixel, `pairs` the same pixels' paired sums.
pub(super) fn combine(
    width: usize,
    totals: impl Iterator<Item = ([f64; 3], f64)>,
    pairs: &[PairSums],
) -> Vec<[f64; 3]> {
    let omega = weights(width, pairs);
    totals
        .zip(pairs.iter().zip(&omega))
        .map(|((l, w), (p, &[even, odd]))| {
            if w == 0.0 {
                return [0.0; 3];
            }
            // Each half's L − U, weighted by the other half's ω.
            std::array::from_fn(|c| {
                let diff_even = p.diff_even[c] as f64;
                let diff_odd = l[c] - p.unbiased[c] - diff_even;
                (p.unbiased[c] + odd * diff_even + even * diff_odd) / w
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tiny generator for the tests (SplitMix64).
    fn uniform(state: &mut u64) -> f64 {
        *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A `side`² image of `n` samples per pixel whose L is `l()` and U `u()` (gray), combined:
    /// the images' mean and the weight at its centre from the even passes.
    fn render(
        side: usize,
        n: u32,
        mut l: impl FnMut(&mut u64) -> f64,
        mut u: impl FnMut(&mut u64) -> f64,
    ) -> (f64, f64) {
        let mut state = 7;
        let mut pairs = vec![PairSums::default(); side * side];
        let mut totals = vec![([0.0; 3], 0.0); side * side];
        for (p, t) in pairs.iter_mut().zip(totals.iter_mut()) {
            for pass in 0..n {
                let (lv, uv) = (l(&mut state) as f32, u(&mut state) as f32);
                p.add(Rgb::splat(lv), Rgb::splat(uv), 1.0, pass);
                for c in 0..3 {
                    t.0[c] += lv as f64;
                }
                t.1 += 1.0;
            }
        }
        let image = combine(side, totals.iter().copied(), &pairs);
        let mean = image.iter().map(|c| c[0]).sum::<f64>() / image.len() as f64;
        (mean, weights(side, &pairs)[side * side / 2 + side / 2][0])
    }

    /// L = 1 + `bias` exactly, U = 1 ± 0.5 (uniform): Var(Ū) = 1/12n, Cov(Ū, D̄) = −Var(Ū).
    fn biased(bias: f64, n: u32) -> (f64, f64) {
        render(16, n, |_| 1.0 + bias, |s| 0.5 + uniform(s))
    }

    #[test]
    fn an_unbiased_noiseless_estimate_takes_all_the_weight() {
        let (mean, omega) = biased(0.0, 16);
        assert!(omega > 0.9, "{omega}");
        assert!((mean - 1.0).abs() < 1e-3, "{mean}");
    }

    #[test]
    fn a_biased_estimate_loses_its_weight_as_samples_grow() {
        // b = 0.05; each half holds n/2 samples, so the optimum Var/(b² + Var) with Var =
        // 1/(12 · n/2) is 0.50 at n = 66 and 0.024 at n = 2666; the bias left is b·ω.
        let (few_mean, few) = biased(0.05, 66);
        let (many_mean, many) = biased(0.05, 2666);
        assert!((0.4..0.6).contains(&few), "{few}");
        assert!((0.015..0.035).contains(&many), "{many}");
        assert!((few_mean - 1.025).abs() < 0.005, "{few_mean}");
        assert!((many_mean - 1.0).abs() < 0.002, "{many_mean}");
    }

    #[test]
    fn a_pixel_grows_by_72_bytes() {
        assert_eq!(std::mem::size_of::<PairSums>(), 72);
    }

    #[test]
    fn one_sample_is_the_biased_estimate() {
        assert!((biased(0.3, 1).0 - 1.3).abs() < 1e-6);
    }

    /// A heavy-tailed U (0, or 250 one time in 250: a caustic) beside an exact L. Weights
    /// taken from the samples they weigh pull such an image down: a window whose samples saw
    /// no bright one trusts its low Ū. Taken from the other half's, the image keeps its mean.
    #[test]
    fn a_heavy_tailed_unbiased_estimate_keeps_the_mean() {
        let (mean, _) = render(128, 8, |_| 1.0, |s| if uniform(s) < 0.004 { 250.0 } else { 0.0 });
        assert!((mean - 1.0).abs() < 0.1, "{mean}");
    }
}
