//! Tabulated distributions: piecewise-constant densities in 1D and 2D (environment maps, pixel
//! filters) and Vose's alias table (lights by power).
//!
//! They follow pbrt-v4's `PiecewiseConstant1D`, `PiecewiseConstant2D` and `AliasTable`
//! (`util/sampling.h`, `util/sampling.cpp`; PBR 4th ed. §A.1 and §A.4), with two guarantees
//! pbrt leaves to its callers: an all-zero (or empty) function samples uniformly with a
//! matching density instead of a density of 0, and no input produces NaN.
//!
//! Inputs are weights, taken by absolute value as pbrt does; a non-finite weight counts as 0
//! so one bad texel cannot poison a whole table.

use glam::{UVec2, Vec2};

use super::warp::ONE_MINUS_EPSILON;

/// A sample of a continuous distribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContinuousSample {
    /// The sampled point of the domain.
    pub value: f32,
    /// Its density with respect to the domain's measure.
    pub pdf: f32,
    /// Index of the constant piece it fell in.
    pub offset: usize,
}

/// A sample of a discrete distribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscreteSample {
    /// The chosen outcome.
    pub index: usize,
    /// Its probability.
    pub pmf: f32,
    /// The part of `u` not used up by the choice, again uniform in [0, 1): lets one number
    /// pick a light and then a point on it.
    pub u_remapped: f32,
}

/// A sample of a 2D distribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample2D {
    /// The sampled point of the domain.
    pub point: Vec2,
    /// Its density with respect to area.
    pub pdf: f32,
    /// Column and row of the cell it fell in.
    pub cell: UVec2,
}

/// Weight as the tables use it: |w|, and 0 for NaN or infinity.
#[inline]
fn sanitize(w: f32) -> f32 {
    if w.is_finite() { w.abs() } else { 0.0 }
}

/// Clamps a sample to [0, 1); NaN becomes 0.
#[inline]
fn unit(u: f32) -> f32 {
    if u >= 0.0 { u.min(ONE_MINUS_EPSILON) } else { 0.0 }
}

/// A piecewise-constant density over `[min, max]` proportional to |f|, sampled by inverting
/// its CDF.
#[derive(Clone, Debug)]
pub struct PiecewiseConstant1D {
    /// |f| per piece.
    func: Vec<f32>,
    /// CDF at the piece boundaries: `func.len() + 1` entries from exactly 0 to exactly 1.
    cdf: Vec<f32>,
    min: f32,
    max: f32,
    /// ∫|f| over the domain.
    integral: f32,
    /// Σ|f|, for probabilities of whole pieces.
    sum: f32,
    /// Guide table (cut points): entry k is the last piece whose left boundary is at or below
    /// k/G, G = `guide.len() − 1` a power of two. [`Self::find`] searches only between two
    /// neighbouring entries; its answer is the full search's (a camera sample's Gaussian
    /// filter made two 48-piece binary searches 2 % of a grid-cloud render).
    guide: Vec<u32>,
}

/// The guide table of a CDF (`n + 1` boundaries from 0 to 1): about four pieces per entry, at
/// most 256 entries (1 KiB per distribution).
fn guide_table(cdf: &[f32]) -> Vec<u32> {
    let n = cdf.len() - 1;
    let g = (n / 4).next_power_of_two().clamp(1, 256);
    (0..=g)
        .map(|k| {
            let x = if k == g { 1.0 } else { k as f32 / g as f32 };
            // The last boundary below n at or below x (boundary 0 is 0: at least one).
            (cdf[..n].partition_point(|&c| c <= x) - 1) as u32
        })
        .collect()
}

impl PiecewiseConstant1D {
    /// The distribution of `f` over [0, 1].
    pub fn new(f: &[f32]) -> PiecewiseConstant1D {
        PiecewiseConstant1D::with_domain(f, 0.0, 1.0)
    }

    /// The distribution of `f`, whose pieces evenly split `[min, max]`. An empty `f` counts
    /// as one zero piece.
    ///
    /// # Panics
    /// If `min < max` does not hold.
    pub fn with_domain(f: &[f32], min: f32, max: f32) -> PiecewiseConstant1D {
        assert!(min < max, "empty domain [{min}, {max}]");
        let mut func: Vec<f32> = f.iter().map(|&w| sanitize(w)).collect();
        if func.is_empty() {
            func.push(0.0);
        }
        let n = func.len();
        // Accumulate in f64: environment maps have millions of pieces, and f32 running sums
        // would lose the small ones entirely.
        let mut cdf = Vec::with_capacity(n + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0f64);
        for &w in &func {
            acc += w as f64;
            cdf.push(acc);
        }
        let cdf: Vec<f32> = if acc > 0.0 {
            cdf.iter().map(|&c| (c / acc) as f32).collect()
        } else {
            // All zero: fall back to uniform.
            (0..=n).map(|i| i as f32 / n as f32).collect()
        };
        let guide = guide_table(&cdf);
        PiecewiseConstant1D {
            integral: (acc * (max - min) as f64 / n as f64) as f32,
            sum: acc as f32,
            func,
            cdf,
            min,
            max,
            guide,
        }
    }

    /// ∫|f| over the domain (0 for an all-zero function, which samples uniformly).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Number of pieces.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Whether there are no pieces (never: an empty input becomes one zero piece).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// The domain `[min, max]`.
    pub fn domain(&self) -> (f32, f32) {
        (self.min, self.max)
    }

    /// |f| of piece `offset`.
    pub fn value(&self, offset: usize) -> f32 {
        self.func.get(offset).copied().unwrap_or(0.0)
    }

    /// Piece containing `u` and how far through it `u` lies, in [0, 1).
    fn find(&self, u: f32) -> (usize, f32) {
        let u = unit(u);
        let n = self.func.len();
        // The last boundary at or below u. It skips zero pieces: their right boundary equals
        // their left one, so it is also at or below u.
        // The last boundary at or below u lies between the guide's entries around u (k/G is
        // exact in f32 for a power-of-two G).
        let g = self.guide.len() - 1;
        let k = ((u * g as f32) as usize).min(g - 1);
        let (lo, hi) = (self.guide[k] as usize, self.guide[k + 1] as usize);
        let o = lo + self.cdf[lo + 1..=hi].partition_point(|&c| c <= u);
        debug_assert_eq!(o, self.cdf[..n].partition_point(|&c| c <= u) - 1);
        let width = self.cdf[o + 1] - self.cdf[o];
        let du = if width > 0.0 { ((u - self.cdf[o]) / width).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 };
        (o, du)
    }

    /// Density of piece `o`.
    #[inline]
    fn piece_pdf(&self, o: usize) -> f32 {
        if self.integral > 0.0 { self.func[o] / self.integral } else { 1.0 / (self.max - self.min) }
    }

    /// A point distributed proportionally to |f|, from `u` in [0, 1).
    pub fn sample_continuous(&self, u: f32) -> ContinuousSample {
        let (o, du) = self.find(u);
        let t = (o as f32 + du) / self.func.len() as f32;
        ContinuousSample {
            value: (self.min + t * (self.max - self.min)).min(self.max),
            pdf: self.piece_pdf(o),
            offset: o,
        }
    }

    /// A piece chosen with probability proportional to its |f|, from `u` in [0, 1).
    pub fn sample_discrete(&self, u: f32) -> DiscreteSample {
        let (o, du) = self.find(u);
        DiscreteSample { index: o, pmf: self.pmf(o), u_remapped: du }
    }

    /// Density of [`Self::sample_continuous`] at `x` (0 outside the domain).
    pub fn pdf(&self, x: f32) -> f32 {
        if !(x >= self.min && x <= self.max) {
            return 0.0;
        }
        let n = self.func.len();
        let o = ((x - self.min) / (self.max - self.min) * n as f32) as usize;
        self.piece_pdf(o.min(n - 1))
    }

    /// Probability that [`Self::sample_discrete`] picks `index` (0 past the end).
    pub fn pmf(&self, index: usize) -> f32 {
        match self.func.get(index) {
            None => 0.0,
            Some(&w) if self.sum > 0.0 => w / self.sum,
            Some(_) => 1.0 / self.func.len() as f32,
        }
    }
}

/// A piecewise-constant density over a rectangle proportional to |f| on a grid of cells:
/// a marginal distribution over rows, then a conditional one within the chosen row.
#[derive(Clone, Debug)]
pub struct PiecewiseConstant2D {
    min: Vec2,
    max: Vec2,
    /// One distribution along x per row.
    conditional: Vec<PiecewiseConstant1D>,
    /// Distribution of rows, by their integrals.
    marginal: PiecewiseConstant1D,
}

impl PiecewiseConstant2D {
    /// The distribution of `f`, given row by row (`nu` values per row, `nv` rows), over the
    /// rectangle from `min` to `max`. Missing values count as 0.
    ///
    /// # Panics
    /// If `min` is not below `max` in both coordinates.
    pub fn new(f: &[f32], nu: usize, nv: usize, min: Vec2, max: Vec2) -> PiecewiseConstant2D {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let conditional: Vec<PiecewiseConstant1D> = (0..nv)
            .map(|v| {
                let row = f.get(v * nu..).unwrap_or(&[]);
                let mut row: Vec<f32> = row.iter().take(nu).copied().collect();
                row.resize(nu, 0.0);
                PiecewiseConstant1D::with_domain(&row, min.x, max.x)
            })
            .collect();
        let row_integrals: Vec<f32> = conditional.iter().map(|c| c.integral()).collect();
        let marginal = PiecewiseConstant1D::with_domain(&row_integrals, min.y, max.y);
        PiecewiseConstant2D { min, max, conditional, marginal }
    }

    /// ∫|f| over the domain.
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// Number of cells along x and y.
    pub fn resolution(&self) -> UVec2 {
        UVec2::new(self.conditional[0].len() as u32, self.marginal.len() as u32)
    }

    /// The domain's corners.
    pub fn domain(&self) -> (Vec2, Vec2) {
        (self.min, self.max)
    }

    /// A point distributed proportionally to |f|: `u.y` picks the row, `u.x` the point in it.
    pub fn sample(&self, u: Vec2) -> Sample2D {
        let y = self.marginal.sample_continuous(u.y);
        let x = self.conditional[y.offset].sample_continuous(u.x);
        Sample2D {
            point: Vec2::new(x.value, y.value),
            pdf: x.pdf * y.pdf,
            cell: UVec2::new(x.offset as u32, y.offset as u32),
        }
    }

    /// Density of [`Self::sample`] at `p` (0 outside the domain).
    pub fn pdf(&self, p: Vec2) -> f32 {
        if !(p.cmpge(self.min).all() && p.cmple(self.max).all()) {
            return 0.0;
        }
        let t = (p - self.min) / (self.max - self.min);
        let res = self.resolution();
        let iu = ((t.x * res.x as f32) as u32).min(res.x - 1) as usize;
        let iv = ((t.y * res.y as f32) as u32).min(res.y - 1) as usize;
        let integral = self.integral();
        if integral > 0.0 {
            self.conditional[iv].value(iu) / integral
        } else {
            let size = self.max - self.min;
            1.0 / (size.x * size.y)
        }
    }
}

/// One bin of an alias table: keep its own outcome with probability `q`, else take `alias`.
#[derive(Clone, Copy, Debug)]
struct Bin {
    q: f32,
    pmf: f32,
    alias: u32,
}

/// Constant-time discrete sampling by Walker's alias method, built by Vose's algorithm
/// ("A linear algorithm for generating random numbers with a given distribution", IEEE TSE
/// 1991) as in pbrt-v4's `AliasTable`. For choosing lights by power.
#[derive(Clone, Debug)]
pub struct AliasTable {
    bins: Vec<Bin>,
}

impl AliasTable {
    /// The table for outcomes with the given weights (all zero: uniform).
    pub fn new(weights: &[f32]) -> AliasTable {
        let n = weights.len();
        let w: Vec<f64> = weights.iter().map(|&w| sanitize(w) as f64).collect();
        let sum: f64 = w.iter().sum();
        // Probabilities in f64, as pbrt does: with many outcomes of very different weights,
        // f32 round-off leaves bins unfilled.
        let p: Vec<f64> = if sum > 0.0 { w.iter().map(|&w| w / sum).collect() } else { vec![1.0 / n as f64; n] };
        let mut bins: Vec<Bin> = (0..n).map(|i| Bin { q: 1.0, pmf: p[i] as f32, alias: i as u32 }).collect();
        // Scaled probabilities: bin i must hold n * p[i] of the unit mass of one bin.
        let mut scaled: Vec<f64> = p.iter().map(|&p| p * n as f64).collect();
        let (mut under, mut over): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(&un), Some(&ov)) = (under.last(), over.last()) {
            under.pop();
            over.pop();
            // The under-full bin keeps its own mass and borrows the rest from `ov`.
            bins[un].q = scaled[un] as f32;
            bins[un].alias = ov as u32;
            scaled[ov] += scaled[un] - 1.0;
            if scaled[ov] < 1.0 {
                under.push(ov);
            } else {
                over.push(ov);
            }
        }
        // What is left is 1 up to round-off: those bins keep themselves (q = 1, set above).
        AliasTable { bins }
    }

    /// Number of outcomes.
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    /// Whether there are no outcomes.
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// An outcome with probability proportional to its weight, from `u` in [0, 1); `None` for
    /// a table without outcomes.
    pub fn sample(&self, u: f32) -> Option<DiscreteSample> {
        let n = self.bins.len();
        if n == 0 {
            return None;
        }
        // Pick a bin uniformly; what is left of u decides between the bin and its alias.
        // In f64 so that u_remapped keeps its resolution when there are many outcomes.
        let un = unit(u) as f64 * n as f64;
        let offset = (un as usize).min(n - 1);
        let up = ((un - offset as f64) as f32).clamp(0.0, ONE_MINUS_EPSILON);
        let bin = self.bins[offset];
        let (index, u_remapped) =
            if up < bin.q { (offset, up / bin.q) } else { (bin.alias as usize, (up - bin.q) / (1.0 - bin.q)) };
        Some(DiscreteSample { index, pmf: self.bins[index].pmf, u_remapped: u_remapped.clamp(0.0, ONE_MINUS_EPSILON) })
    }

    /// Probability of outcome `index` (0 past the end).
    pub fn pmf(&self, index: usize) -> f32 {
        self.bins.get(index).map_or(0.0, |b| b.pmf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi_square::{TestRng, chi_square_test};

    const N: usize = 200_000;

    /// Weights with zero runs at both ends and inside, and a wide range.
    const WEIGHTS: [f32; 12] = [0.0, 1.0, 3.0, 0.0, 0.0, 2.0, 5.0, 0.25, 0.0, 7.0, 1.5, 0.0];

    /// The guide table's search finds the piece a full binary search finds, at boundaries,
    /// inside zero runs and for spiky weights, for every table size.
    #[test]
    fn guided_search_is_the_full_search() {
        let mut rng = TestRng::new(7);
        for n in [1usize, 2, 3, 12, 48, 100, 1000, 5000] {
            let f: Vec<f32> = (0..n)
                .map(|i| {
                    if n == 12 {
                        WEIGHTS[i]
                    } else if rng.uniform() < 0.3 {
                        0.0
                    } else {
                        rng.uniform().powi(8)
                    }
                })
                .collect();
            let d = PiecewiseConstant1D::new(&f);
            let mut us: Vec<f32> = d.cdf.clone();
            us.extend((0..4000).map(|_| rng.uniform()));
            us.extend([0.0, ONE_MINUS_EPSILON, 1.0, -0.5, 0.5, 0.25]);
            for u in us {
                let v = unit(u);
                let full = d.cdf[..n].partition_point(|&c| c <= v) - 1;
                assert_eq!(d.find(u).0, full, "n {n}, u {u}");
            }
        }
    }

    #[test]
    fn piecewise_1d_continuous_matches_density() {
        let d = PiecewiseConstant1D::with_domain(&WEIGHTS, -1.0, 2.0);
        let total: f32 = WEIGHTS.iter().sum();
        assert!((d.integral() - total * 3.0 / 12.0).abs() < 1e-5);
        // Four sub-bins per piece: checks where inside a piece points land, too.
        let bins = WEIGHTS.len() * 4;
        let mut counts = vec![0u64; bins];
        let mut rng = TestRng::new(1);
        for _ in 0..N {
            let s = d.sample_continuous(rng.uniform());
            assert!((-1.0..=2.0).contains(&s.value));
            assert!(WEIGHTS[s.offset] > 0.0);
            assert_eq!(s.pdf, WEIGHTS[s.offset] / d.integral());
            let b = (((s.value + 1.0) / 3.0 * bins as f32) as usize).min(bins - 1);
            counts[b] += 1;
        }
        let expected: Vec<f64> = (0..bins).map(|b| N as f64 * WEIGHTS[b / 4] as f64 / (4.0 * total as f64)).collect();
        chi_square_test(&counts, &expected).unwrap();
    }

    #[test]
    fn piecewise_1d_discrete_matches_pmf_and_remaps_uniformly() {
        let d = PiecewiseConstant1D::new(&WEIGHTS);
        let mut counts = vec![0u64; WEIGHTS.len()];
        let mut remapped = vec![0u64; 16];
        let mut rng = TestRng::new(2);
        for _ in 0..N {
            let s = d.sample_discrete(rng.uniform());
            assert_eq!(s.pmf, d.pmf(s.index));
            counts[s.index] += 1;
            remapped[(s.u_remapped * 16.0) as usize] += 1;
        }
        let expected: Vec<f64> = (0..WEIGHTS.len()).map(|i| N as f64 * d.pmf(i) as f64).collect();
        chi_square_test(&counts, &expected).unwrap();
        chi_square_test(&remapped, &[N as f64 / 16.0; 16]).unwrap();
        assert!(((0..WEIGHTS.len()).map(|i| d.pmf(i)).sum::<f32>() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn piecewise_1d_zero_empty_and_bad_inputs_fall_back_to_uniform() {
        for f in [&[0.0f32; 5][..], &[], &[f32::NAN, 0.0, f32::INFINITY]] {
            let d = PiecewiseConstant1D::with_domain(f, 2.0, 4.0);
            assert_eq!(d.integral(), 0.0);
            for i in 0..=100 {
                let u = i as f32 / 100.0;
                let s = d.sample_continuous(u);
                assert!(s.value >= 2.0 && s.value <= 4.0);
                assert_eq!(s.pdf, 0.5);
                assert!((s.value - (2.0 + 2.0 * u)).abs() < 1e-5 || u == 1.0);
                let s = d.sample_discrete(u);
                assert_eq!(s.pmf, 1.0 / d.len() as f32);
            }
        }
        // Negative weights count by magnitude; NaN samples are clamped.
        let d = PiecewiseConstant1D::new(&[-1.0, 3.0]);
        assert_eq!(d.pmf(0), 0.25);
        let s = d.sample_continuous(f32::NAN);
        assert!(s.value == 0.0 && s.pdf.is_finite());
        assert_eq!(d.pdf(-0.5), 0.0);
        assert_eq!(d.sample_continuous(1.0).offset, 1);
    }

    /// A 7×5 grid with zero rows and columns, over [-2, 3]×[1, 2].
    fn grid() -> (Vec<f32>, usize, usize) {
        let (nu, nv) = (7, 5);
        let f = (0..nu * nv)
            .map(|i| {
                let (x, y) = (i % nu, i / nu);
                if y == 2 || x == 0 { 0.0 } else { ((x * 3 + y * 5) % 7) as f32 + 0.5 }
            })
            .collect();
        (f, nu, nv)
    }

    #[test]
    fn piecewise_2d_matches_density() {
        let (f, nu, nv) = grid();
        let (min, max) = (Vec2::new(-2.0, 1.0), Vec2::new(3.0, 2.0));
        let d = PiecewiseConstant2D::new(&f, nu, nv, min, max);
        let total: f32 = f.iter().sum();
        let cell_area = 5.0 / nu as f32 * (1.0 / nv as f32);
        assert!((d.integral() - total * cell_area).abs() < 1e-4);
        // 2×2 sub-cells per cell.
        let (bu, bv) = (nu * 2, nv * 2);
        let mut counts = vec![0u64; bu * bv];
        let mut rng = TestRng::new(3);
        for _ in 0..N {
            let s = d.sample(Vec2::new(rng.uniform(), rng.uniform()));
            assert!(s.point.cmpge(min).all() && s.point.cmple(max).all());
            assert!(f[s.cell.y as usize * nu + s.cell.x as usize] > 0.0);
            assert!((s.pdf - d.pdf(s.point)).abs() <= 1e-5 * s.pdf);
            let t = (s.point - min) / (max - min);
            let x = ((t.x * bu as f32) as usize).min(bu - 1);
            let y = ((t.y * bv as f32) as usize).min(bv - 1);
            counts[y * bu + x] += 1;
        }
        let expected: Vec<f64> = (0..bu * bv)
            .map(|i| {
                let (x, y) = (i % bu / 2, i / bu / 2);
                N as f64 * f[y * nu + x] as f64 / (4.0 * total as f64)
            })
            .collect();
        chi_square_test(&counts, &expected).unwrap();
        assert_eq!(d.pdf(Vec2::new(-2.5, 1.5)), 0.0);
    }

    #[test]
    fn piecewise_2d_all_zero_is_uniform() {
        let d = PiecewiseConstant2D::new(&[0.0; 6], 3, 2, Vec2::ZERO, Vec2::new(2.0, 4.0));
        let mut rng = TestRng::new(4);
        for _ in 0..1000 {
            let s = d.sample(Vec2::new(rng.uniform(), rng.uniform()));
            assert_eq!(s.pdf, 0.125);
            assert_eq!(d.pdf(s.point), 0.125);
        }
        // Too few values: the rest are zero.
        let d = PiecewiseConstant2D::new(&[1.0], 2, 2, Vec2::ZERO, Vec2::ONE);
        assert_eq!(d.pdf(Vec2::new(0.25, 0.25)), 4.0);
        assert_eq!(d.pdf(Vec2::new(0.75, 0.75)), 0.0);
    }

    #[test]
    fn alias_table_matches_pmf_and_remaps_uniformly() {
        let weights = [0.0, 1e-3, 10.0, 0.5, 0.0, 3.0, 3.0, 100.0, 0.25, 7.0];
        let t = AliasTable::new(&weights);
        let total: f32 = weights.iter().sum();
        for (i, &w) in weights.iter().enumerate() {
            assert!((t.pmf(i) - w / total).abs() < 1e-7);
        }
        let mut counts = vec![0u64; weights.len()];
        let mut remapped = vec![0u64; 16];
        let mut rng = TestRng::new(5);
        for _ in 0..N {
            let s = t.sample(rng.uniform()).unwrap();
            assert_eq!(s.pmf, t.pmf(s.index));
            counts[s.index] += 1;
            remapped[(s.u_remapped * 16.0) as usize] += 1;
        }
        let expected: Vec<f64> = weights.iter().map(|&w| N as f64 * (w / total) as f64).collect();
        chi_square_test(&counts, &expected).unwrap();
        chi_square_test(&remapped, &[N as f64 / 16.0; 16]).unwrap();
    }

    #[test]
    fn alias_table_many_outcomes_cover_their_mass() {
        // Many outcomes with weights spanning 12 orders of magnitude: every bin's q and alias
        // must add up to the pmfs exactly (the invariant pbrt's f64 sum protects).
        let weights: Vec<f32> = (0..10_000).map(|i| 10f32.powi(i % 13 - 6)).collect();
        let t = AliasTable::new(&weights);
        let n = weights.len();
        let mut mass = vec![0.0f64; n];
        for (i, b) in t.bins.iter().enumerate() {
            mass[i] += b.q as f64 / n as f64;
            mass[b.alias as usize] += (1.0 - b.q as f64) / n as f64;
        }
        for (i, m) in mass.into_iter().enumerate() {
            let pmf = t.pmf(i) as f64;
            assert!((m - pmf).abs() <= 1e-5 * pmf + 1e-15, "{i}: {m} vs {pmf}");
        }
    }

    #[test]
    fn alias_table_zero_and_empty() {
        let t = AliasTable::new(&[0.0, 0.0, 0.0, 0.0]);
        for i in 0..4 {
            assert_eq!(t.pmf(i), 0.25);
        }
        let s = t.sample(0.6).unwrap();
        assert_eq!((s.index, s.pmf), (2, 0.25));
        assert!((s.u_remapped - 0.4).abs() < 1e-5);
        assert!(AliasTable::new(&[]).sample(0.5).is_none());
        assert_eq!(t.pmf(9), 0.0);
        let one = AliasTable::new(&[f32::NAN, 2.0]);
        assert_eq!(one.sample(0.1).unwrap().index, 1);
        assert_eq!(one.sample(1.0).unwrap().index, 1);
    }
}
