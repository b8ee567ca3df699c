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
//!
//! Before it, each half's L̄ is corrected by the bias that the neighbouring pixels' D̄ of the
//! other half show ([`super::correction`]): the weights then weigh what that leaves, which at
//! few samples is far less than the bias itself (a dense cloud lit from behind at 3 s: MSE
//! 2.5× below volpath's with it, 1.6× without).

use super::correction::Correction;
use super::window::Table;
use crate::color::Rgb;
use crate::integrators::Outlook;
use rayon::prelude::*;

/// Half-width of the square window of pixels whose statistics set a pixel's ω (33×33): on
/// the Disney cloud at 10 s (6 spp) the relMSE was 6.0e-2 with 7×7, 4.1e-2 with 17×17 and
/// 3.9e-2 with 33×33 (the graph alone: 3.7e-2); on cloud-sun-sky at 1.5 s 6.1e-4, 5.7e-4,
/// 5.3e-4 (alone: 5.5e-4); on the back-lit cloud the same within noise.
const RADIUS: usize = 16;

/// Unweighted moments of one half's samples: x = U's channel mean, y = D's channel mean.
/// Single precision: they only set ω and the [`Outlook`] (a relative error of 1e-5 in a sum
/// moves ω by as much), and the film's pixel grows by 16 bytes less per half than in double.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    n: u32,
    x: f32,
    y: f32,
    xy: f32,
    xx: f32,
    yy: f32,
}

impl Moments {
    /// Per-sample estimates from this half, or None below two samples: −Cov(U, D) = A,
    /// Var(U) and Var(D) (its D̄ is [`gray_fields`]'s).
    fn estimate(&self) -> Option<Estimates> {
        if self.n < 2 {
            return None;
        }
        let (n, x, y) = (self.n as f64, self.x as f64, self.y as f64);
        let var = |sq: f32, a: f64, b: f64| (sq as f64 - a * b / n) / (n - 1.0);
        Some(Estimates {
            a: -var(self.xy, x, y),
            var_u: var(self.xx, x, x).max(0.0),
            var_d: var(self.yy, y, y).max(0.0),
        })
    }
}

/// One half's per-sample estimates at a pixel (see [`Moments::estimate`]).
#[derive(Clone, Copy, Debug, Default)]
struct Estimates {
    a: f64,
    var_u: f64,
    var_d: f64,
}

/// One pixel's sums over its paired samples (the film keeps Σ w·L and Σ w of all of them),
/// and over its unpaired ones: samples that carry U alone (a method that stopped paying for
/// L where it no longer pays, [`Outlook`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PairSums {
    /// Σ w·U, weighted by the filter as the film weighs L (double precision, as the film's
    /// sums: where L is biased, the image tends to this mean), over all paired samples and
    /// over the even passes' ones, with their Σ w.
    unbiased: [f64; 3],
    unbiased_even: [f64; 3],
    weight_even: f64,
    /// Σ w·U and Σ w of the unpaired samples, and their count.
    alone: [f64; 3],
    alone_weight: f64,
    alone_n: u32,
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
                self.unbiased_even[c] += w as f64 * u[c] as f64;
                self.diff_even[c] += w * (l[c] - u[c]);
            }
        }
        if even {
            self.weight_even += w as f64;
        }
        let x = (u[0] + u[1] + u[2]) / 3.0;
        let y = (l[0] + l[1] + l[2]) / 3.0 - x;
        let m = &mut self.halves[(pass % 2) as usize];
        m.n += 1;
        m.x += x;
        m.y += y;
        m.xy += x * y;
        m.xx += x * x;
        m.yy += y * y;
    }

    /// Adds `count` unpaired samples: Σ w·U of an unbiased estimate and Σ w, with no L.
    pub fn add_unpaired(&mut self, sum: [f64; 3], weight: f64, count: u32) {
        for (a, s) in self.alone.iter_mut().zip(sum) {
            *a += s;
        }
        self.alone_weight += weight;
        self.alone_n += count;
    }

    /// Paired samples, n, and all samples, N.
    fn counts(&self) -> (f64, f64) {
        let n = (self.halves[0].n + self.halves[1].n) as f64;
        (n, n + self.alone_n as f64)
    }
}

/// λ of C = Ū_N + λ (L̄ − Ū_N) for one pixel, from per-sample quantities: `e_d` = E[D̄²] =
/// b² + σ²_D/n, `a_n` = A/n with A = −Cov(U, D), `c_n` = (2A − σ²_U)/n, and the paired share
/// r = n/N.
///
/// Ū_N is the mean of all N samples' U, paired and unpaired, D̄ = L̄ − Ū_n over the n paired
/// ones. With E[(Ū_N − μ)(L̄ − Ū_N)] = −A/N and E[(L̄ − Ū_N)²] = E[D̄²] − (2A − σ²_U)(1/n −
/// 1/N), the optimum is λ = (A/N) / E[(L̄ − Ū_N)²] = r a_n / (e_d − (1 − r) c_n); at N = n it
/// is ω = −Cov(Ū, D̄)/E[D̄²]. Where L is exact λ = 1 whatever the unpaired samples (C = L̄);
/// as L's bias dominates λ → 0 (C = Ū_N). Ū_N keeps every U at the same weight, so no few
/// paired samples' outlier weighs more than its share. The error at the optimum is
/// σ²_U/N − (A/N) λ ([`error`]).
fn optimum(e_d: f64, a_n: f64, c_n: f64, r: f64) -> f64 {
    let den = e_d - (1.0 - r) * c_n;
    // den ≤ 0: the two estimates agree within what the samples can tell (a cluster of one
    // gives exactly 0); λ does not matter.
    if den > 0.0 { (r * a_n / den).clamp(0.0, 1.0) } else { 1.0 }
}

/// A pixel's expected squared error at the optimum of [`optimum`], after n paired samples of
/// N, from per-sample σ²_U, A, σ²_D and b².
fn error(var_u: f64, a: f64, var_d: f64, b2: f64, n: f64, all: f64) -> f64 {
    let base = var_u / all;
    let den = b2 + var_d / n + (var_u - 2.0 * a) * (1.0 / n - 1.0 / all);
    if den <= 0.0 {
        return 0.0;
    }
    (base - (a / all).powi(2) / den).max(0.0)
}

/// Each half's gray D̄ per pixel: its samples' unweighted mean of L − U, as its moments take
/// it; None where the half has no samples.
fn gray_fields(pairs: &[PairSums]) -> [Vec<Option<[f64; 1]>>; 2] {
    [0, 1].map(|h| {
        pairs
            .iter()
            .map(|p| {
                let m = &p.halves[h];
                (m.n > 0).then(|| [m.y as f64 / m.n as f64])
            })
            .collect()
    })
}

/// The bias correction fitted to the halves' gray D̄ ([`Correction`]), and each half's gray
/// correction per pixel.
fn corrections(width: usize, pairs: &[PairSums]) -> (Correction, [Vec<[f64; 1]>; 2]) {
    let [even, odd] = gray_fields(pairs);
    Correction::fit(width, [&even, &odd])
}

/// Each pixel's λ from the even passes' and from the odd passes' samples, in a `width`-wide
/// image (row-major `pairs`): [`optimum`] with each half's estimates summed over the window,
/// E[D̄²] taken from its corrected D̄ (`shifts`, [`corrections`]), the half taken as if it were
/// all the paired samples there are (n_h of N_h = n_h / r); 1 where a half has fewer than two
/// samples.
fn weights(width: usize, pairs: &[PairSums], shifts: &[Vec<[f64; 1]>; 2]) -> Vec<[f64; 2]> {
    let [even, odd] = [0, 1].map(|h| {
        let term = |i: usize| {
            let p = &pairs[i];
            let e = p.halves[h].estimate()?;
            let n = p.halves[h].n as f64;
            let d = p.halves[h].y as f64 / n + shifts[h][i][0];
            Some([d * d, e.a / n, (2.0 * e.a - e.var_u) / n])
        };
        let sums = Table::from_fn(width, pairs.len(), term);
        (0..pairs.len())
            .into_par_iter()
            .map(|i| {
                if pairs[i].halves[h].n < 2 {
                    return 1.0;
                }
                let [e_d, a_n, c_n] = sums.window(i, RADIUS);
                let (n, all) = pairs[i].counts();
                optimum(e_d, a_n, c_n, n / all)
            })
            .collect::<Vec<_>>()
    });
    even.into_iter().zip(odd).map(|(e, o)| [e, o]).collect()
}

/// The combined mean of every pixel of a `width`-wide image: `totals` are the film's Σ w·L
/// and Σ w per pixel (over the paired samples), `pairs` the same pixels' paired and unpaired
/// sums. C = Ū_N + Σ_h w_h λ_h' (L̃_h − Ū_N), w_h half h's share of the paired weight, L̃_h
/// half h's mean of L with its bias correction ([`Correction`], fitted to the gray D̄ and
/// applied to each channel's), each half's term weighted by the other half's λ. The term is
/// written D̄_h + shift_h + (1 − r)(Ū_h − Ū_m) (Ū_m the unpaired samples' mean; the other
/// half's Ū in Ū_N replaced by this half's, which has its expectation), so that no λ weighs
/// the samples it was estimated from.
pub(super) fn combine(
    width: usize,
    totals: impl Iterator<Item = ([f64; 3], f64)>,
    pairs: &[PairSums],
) -> Vec<[f64; 3]> {
    let totals: Vec<([f64; 3], f64)> = totals.collect();
    let (fit, gray) = corrections(width, pairs);
    let lambda = weights(width, pairs, &gray);
    // Each half's Σ w·(L − U) per channel, and its weighted mean D̄ (the field the correction
    // reads).
    let diffs: Vec<[[f64; 3]; 2]> = totals
        .iter()
        .zip(pairs)
        .map(|((l, _), p)| {
            let even = p.diff_even.map(|d| d as f64);
            [even, std::array::from_fn(|c| l[c] - p.unbiased[c] - even[c])]
        })
        .collect();
    let [even_d, odd_d]: [Vec<Option<[f64; 3]>>; 2] = [0, 1].map(|h| {
        diffs
            .iter()
            .zip(totals.iter().zip(pairs))
            .map(|(d, ((_, w), p))| {
                let wh = if h == 0 { p.weight_even } else { w - p.weight_even };
                (wh > 0.0).then(|| d[h].map(|x| x / wh))
            })
            .collect()
    });
    let shifts = [fit.apply(0, &odd_d), fit.apply(1, &even_d)];
    totals
        .iter()
        .zip(pairs.iter().zip(&lambda))
        .zip(&diffs)
        .enumerate()
        .map(|(i, ((&(_, w), (p, &[even, odd])), &[diff_even, diff_odd]))| {
            let all = w + p.alone_weight;
            if all == 0.0 {
                return [0.0; 3];
            }
            let r = w / all;
            let (w_even, w_odd) = (p.weight_even, w - p.weight_even);
            std::array::from_fn(|c| {
                let pooled = (p.unbiased[c] + p.alone[c]) / all;
                if w == 0.0 {
                    return pooled;
                }
                let alone_mean = if p.alone_weight > 0.0 { p.alone[c] / p.alone_weight } else { 0.0 };
                let (u_even, u_odd) = (p.unbiased_even[c], p.unbiased[c] - p.unbiased_even[c]);
                // Half h's Σ w·(L̃ − U) + (1 − r) Σ w·(U − Ū_m).
                let term =
                    |diff: f64, shift: f64, u: f64, wh: f64| diff + wh * shift + (1.0 - r) * (u - wh * alone_mean);
                let even_term = term(diff_even[c], shifts[0][i][c], u_even, w_even);
                let odd_term = term(diff_odd[c], shifts[1][i][c], u_odd, w_odd);
                pooled + (odd * even_term + even * odd_term) / w
            })
        })
        .collect()
}

/// What one more sample of each kind would take off the combined image's squared error,
/// summed over its pixels, from the moments so far (over the window, as the weights take
/// them): with [`error`] e(n, N) after n paired samples of N, one more unpaired sample takes
/// e(n, N) − e(n, N + 1) off, a paired one e(n, N) − e(n + 1, N + 1). Pixels with fewer than
/// two samples in a half are left out; None when that is every pixel.
pub(super) fn outlook(width: usize, pairs: &[PairSums]) -> Option<Outlook> {
    // Per pixel, both halves' per-sample estimates pooled, and the bias² their corrected D̄²
    // shows (what the correction leaves, with the noise it adds).
    let (_, [shift_even, shift_odd]) = corrections(width, pairs);
    let term = |i: usize| {
        let p = &pairs[i];
        let [e, o] = [0, 1].map(|h| p.halves[h].estimate());
        let (e, o) = (e?, o?);
        let (ne, no) = (p.halves[0].n as f64, p.halves[1].n as f64);
        let mean = |f: fn(&Estimates) -> f64| (f(&e) * ne + f(&o) * no) / (ne + no);
        // Each half's corrected D̄² estimates b̃² + σ²_D/n_h.
        let (de, d_o) = (p.halves[0].y as f64 / ne + shift_even[i][0], p.halves[1].y as f64 / no + shift_odd[i][0]);
        let b2 = (de * de - e.var_d / ne + d_o * d_o - o.var_d / no) / 2.0;
        Some([mean(|x| x.a), mean(|x| x.var_u), mean(|x| x.var_d), b2, 1.0])
    };
    let sums = Table::from_fn(width, pairs.len(), term);
    let mut o = Outlook::default();
    let mut counted = false;
    for (i, p) in pairs.iter().enumerate() {
        if p.halves.iter().any(|m| m.n < 2) {
            continue;
        }
        let s = sums.window(i, RADIUS);
        if s[4] == 0.0 {
            continue;
        }
        let [a, var_u, var_d, b2] = std::array::from_fn(|k| s[k] / s[4]);
        let e = |n: f64, all: f64| error(var_u, a, var_d, b2.max(0.0), n, all);
        let (n, all) = p.counts();
        let now = e(n, all);
        let unpaired = now - e(n, all + 1.0);
        o.unpaired += unpaired;
        o.paired += now - e(n + 1.0, all + 1.0) - unpaired;
        counted = true;
    }
    counted.then_some(o)
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

    /// The sign of a checkerboard's pixel `i` in a `side`-wide image: a bias that alternates
    /// from pixel to pixel, which the neighbours' D̄ cannot estimate ([`Correction`] leaves it),
    /// so that the tests of the weights see the bias whole.
    fn checker(i: usize, side: usize) -> f64 {
        if (i % side + i / side).is_multiple_of(2) { 1.0 } else { -1.0 }
    }

    /// A `side`² image of `n` samples per pixel whose L at pixel i is `l(i)` and U `u()`
    /// (gray), combined: the image, and the weight at its centre from the even passes.
    fn render(
        side: usize,
        n: u32,
        mut l: impl FnMut(&mut u64, usize) -> f64,
        mut u: impl FnMut(&mut u64) -> f64,
    ) -> (Vec<[f64; 3]>, f64) {
        let mut state = 7;
        let mut pairs = vec![PairSums::default(); side * side];
        let mut totals = vec![([0.0; 3], 0.0); side * side];
        for (i, (p, t)) in pairs.iter_mut().zip(totals.iter_mut()).enumerate() {
            for pass in 0..n {
                let (lv, uv) = (l(&mut state, i) as f32, u(&mut state) as f32);
                p.add(Rgb::splat(lv), Rgb::splat(uv), 1.0, pass);
                for c in 0..3 {
                    t.0[c] += lv as f64;
                }
                t.1 += 1.0;
            }
        }
        let image = combine(side, totals.iter().copied(), &pairs);
        let (_, shifts) = corrections(side, &pairs);
        (image, weights(side, &pairs, &shifts)[side * side / 2 + side / 2][0])
    }

    /// L = 1 ± `bias` exactly (a checkerboard), U = 1 ± 0.5 (uniform): Var(Ū) = 1/12n,
    /// Cov(Ū, D̄) = −Var(Ū). Returns 1 + the bias left in the image (along the checkerboard's
    /// sign) and ω at the centre.
    fn biased(bias: f64, n: u32) -> (f64, f64) {
        let side = 16;
        let (image, omega) = render(side, n, |_, i| 1.0 + bias * checker(i, side), |s| 0.5 + uniform(s));
        let left = image.iter().enumerate().map(|(i, c)| checker(i, side) * (c[0] - 1.0)).sum::<f64>();
        (1.0 + left / image.len() as f64, omega)
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

    /// A bias the same over the image is taken off before the combination, long before the
    /// weights could drop it: at n = 66, where a checkerboard's keeps half its bias (above),
    /// the image is within its noise of 1 (each pixel's σ: √(1/12/66) = 0.036 before the
    /// graph's; the image mean's 0.0022), and the weight stays with L.
    #[test]
    fn a_smooth_bias_is_taken_off_before_the_combination() {
        let (image, omega) = render(16, 66, |_, _| 1.05, |s| 0.5 + uniform(s));
        let mean = image.iter().map(|c| c[0]).sum::<f64>() / image.len() as f64;
        assert!((mean - 1.0).abs() < 0.005, "{mean}");
        assert!(omega > 0.8, "{omega}");
    }

    #[test]
    fn a_pixel_grows_by_152_bytes() {
        assert_eq!(std::mem::size_of::<PairSums>(), 152);
    }

    /// `side`² pixels of `n` paired samples (L = 1 ± `bias` in a checkerboard, ± `noise`/2,
    /// U = 1 ± 0.5, both uniform and independent) and then `m` unpaired ones (U alone): 1 +
    /// the bias left in the combined image (along the checkerboard's sign), its pixels' RMS
    /// distance from 1 (the truth without bias) and the outlook before the unpaired ones.
    fn with_unpaired(bias: f64, noise: f64, n: u32, m: u32) -> (f64, f64, Option<Outlook>) {
        let side = 16;
        let mut state = 11;
        let mut pairs = vec![PairSums::default(); side * side];
        let mut totals = vec![([0.0; 3], 0.0); side * side];
        for (i, (p, t)) in pairs.iter_mut().zip(totals.iter_mut()).enumerate() {
            for pass in 0..n {
                let l = (1.0 + bias * checker(i, side) + noise * (uniform(&mut state) - 0.5)) as f32;
                let u = (0.5 + uniform(&mut state)) as f32;
                p.add(Rgb::splat(l), Rgb::splat(u), 1.0, pass);
                t.0 = t.0.map(|x| x + l as f64);
                t.1 += 1.0;
            }
        }
        let outlook = outlook(side, &pairs);
        for p in pairs.iter_mut() {
            let sum: f64 = (0..m).map(|_| 0.5 + uniform(&mut state)).sum();
            p.add_unpaired([sum; 3], m as f64, m);
        }
        let image = combine(side, totals.iter().copied(), &pairs);
        let k = image.len() as f64;
        let rms = (image.iter().map(|c| (c[0] - 1.0).powi(2)).sum::<f64>() / k).sqrt();
        let left = image.iter().enumerate().map(|(i, c)| checker(i, side) * (c[0] - 1.0)).sum::<f64>();
        (1.0 + left / k, rms, outlook)
    }

    /// Unpaired samples join the unbiased mean, and the biased estimate's weight falls with
    /// its share of the samples: b = 0.05 at n = 66 keeps 0.025 of bias (ω ≈ ½); with 2000
    /// unpaired samples more (r = 0.032), α = r (A/n) / (b² + r σ²/n) ≈ 0.03 leaves 0.0016.
    #[test]
    fn unpaired_samples_dilute_the_bias() {
        let (paired, ..) = with_unpaired(0.05, 0.0, 66, 0);
        let (pooled, ..) = with_unpaired(0.05, 0.0, 66, 2000);
        assert!((paired - 1.025).abs() < 0.005, "{paired}");
        assert!((pooled - 1.0).abs() < 0.004, "{pooled}");
    }

    /// An unbiased L with a tenth of U's noise keeps its weight among unpaired samples: the
    /// pixels stay L̄ (σ = 0.029/√66 = 0.0036 each) instead of becoming Ū_N (0.29/√666 =
    /// 0.011).
    #[test]
    fn unpaired_samples_leave_a_good_estimate_its_weight() {
        let (_, rms, _) = with_unpaired(0.0, 0.1, 66, 600);
        assert!(rms < 0.006, "{rms}");
    }

    /// Only unpaired samples: the image is their mean.
    #[test]
    fn unpaired_samples_alone_are_the_image() {
        let mut pairs = vec![PairSums::default(); 4];
        for p in pairs.iter_mut() {
            p.add_unpaired([6.0, 3.0, 1.5], 3.0, 3);
        }
        let image = combine(2, std::iter::repeat_n(([0.0; 3], 0.0), 4), &pairs);
        assert_eq!(image[0], [2.0, 1.0, 0.5]);
    }

    /// The outlook: an unbiased L with a tenth of U's noise is worth its pairing, a biased
    /// one at many samples is not, and a biased but noisy one at few samples still is to a
    /// graph costing up to 1.3 times its paths (more of its samples take its noise off; a
    /// noiseless L would gain nothing from them).
    #[test]
    fn the_outlook_weighs_what_the_biased_estimate_still_gives() {
        let good = with_unpaired(0.0, 0.1, 32, 0).2.unwrap();
        assert!(good.paired > 2.0 * good.unpaired, "{good:?}");
        let late = with_unpaired(0.05, 0.0, 2000, 0).2.unwrap();
        assert!(late.paired < 0.1 * late.unpaired, "{late:?}");
        let early = with_unpaired(0.05, 0.3, 8, 0).2.unwrap();
        assert!(early.paired > 0.3 * early.unpaired, "{early:?}");
    }

    /// At the optimum no sample of either kind adds error.
    #[test]
    fn no_sample_adds_error() {
        for &(var_u, a, var_d, b2) in &[(1.0, 1.0, 1.01, 0.0), (1.0, 0.9, 1.2, 0.05), (1.0, 1.0, 1.0, 0.01)] {
            for n in [2.0, 8.0, 64.0] {
                for all in [n, 2.0 * n, 10.0 * n] {
                    let now = error(var_u, a, var_d, b2, n, all);
                    assert!(error(var_u, a, var_d, b2, n + 1.0, all + 1.0) <= now * (1.0 + 1e-12), "{n} {all}");
                    assert!(error(var_u, a, var_d, b2, n, all + 1.0) <= now * (1.0 + 1e-12), "{n} {all}");
                }
            }
        }
    }

    /// An exact L: λ = 1 whatever the unpaired samples.
    #[test]
    fn an_exact_estimate_is_the_image() {
        // σ²_U = 1, A = 1, b = 0, σ²_L = 0 (σ²_D = 1): E[D̄²] = 1/n, c = (2 − 1)/n.
        let lambda = optimum(1.0 / 8.0, 1.0 / 8.0, 1.0 / 8.0 * (1.0 - 1e-9), 0.25);
        assert!((lambda - 1.0).abs() < 1e-6, "{lambda}");
    }
}
