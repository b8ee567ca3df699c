//! The biased estimate's bias, estimated from the neighbouring pixels and taken off before the
//! combination ([`super::combine`]).
//!
//! Where a path graph is biased, the bias b of its pixel estimate L varies slowly across the
//! image compared with the noise of the paths' unbiased estimate U (a dense cloud lit from
//! behind: −6 % on the bright rim, a little less beside it). Each pixel's own D̄ = L̄ − Ū
//! estimates b with U's noise, which takes many samples to fall below b; its neighbours' D̄s
//! estimate it with a fraction of that noise. So each half of the passes (even, odd) gets
//!
//!   L̃_h = L̄_h − κ · ring_r(D̄_o),
//!
//! ring_r the mean over the (2r + 1)² pixels around the pixel without the pixel itself, of the
//! other half's D̄ (independent of half h, so E[L̃_h] = μ + b − E[κ] ring_r(b)). κ and r are
//! each half's own regression of its D̄ on the ring mean of its own D̄, over a 33×33 window:
//! κ = Σ D̄·ring(D̄) / Σ ring(D̄)², which estimates b·ring(b) / (ring(b)² + Var(ring(D̄))) — the
//! κ that minimises E[(b − κ ring(D̄_o))²], the pixel's squared bias after the correction plus
//! the noise the correction adds. Leaving the pixel out of its own ring keeps the numerator free
//! of its noise (D̄(p) and D̄(q ≠ p) are independent), and keeps the correction of one half at
//! a pixel independent of the other half's own samples there, which set that half's weight in
//! the combination. Of the radii 1, 2 and 4 a window takes the one whose regression removes the
//! most squared error, num²/den: the narrow ring where the bias changes from pixel to pixel and
//! the samples are many, the wide ring where they are few.
//!
//! Where L is unbiased and far less noisy than U (the Disney cloud: its graph's bias is −0.34 %)
//! the ring only adds U's noise, the regression finds nothing (κ ≈ 0.04) and L stays as it is;
//! on the back-lit cloud at 36 spp the correction takes the graph's MSE from 7.1e-3 to 4.6e-3
//! (U alone: 1.7e-2), at 72 spp from 5.6e-3 to 2.4e-3 (prototype on two-seed image pairs).
//! The combination's weights then see the corrected D̄ (its bias left over, and the ring's
//! noise), and still tend to U as the samples grow: the image converges whatever is left.

use super::combine::window_sums;

/// Ring radii the regression chooses among.
const RADII: [usize; 3] = [1, 2, 4];

/// Half-width of the window over which κ and the radius are fitted (33×33, the combination's).
const FIT_RADIUS: usize = 16;

/// One half's correction at one pixel: −κ times the ring mean of radius `radius`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shift {
    kappa: f64,
    radius: usize,
}

/// Each pixel's correction of each half (even, odd), fitted to the halves' D̄ fields.
pub(super) struct Correction {
    width: usize,
    shifts: [Vec<Option<Shift>>; 2],
}

impl Correction {
    /// Fits each half's κ and radius to its own D̄ field (`fields[h]`, one value per pixel of a
    /// `width`-wide image, None where the half has no samples).
    pub fn fit(width: usize, fields: [&[Option<[f64; 1]>]; 2]) -> Correction {
        let shifts = fields.map(|field| {
            let mut best: Vec<(f64, Option<Shift>)> = vec![(0.0, None); field.len()];
            for radius in RADII {
                let ring = ring_means(width, field, radius);
                let terms: Vec<Option<[f64; 2]>> = field
                    .iter()
                    .zip(&ring)
                    .map(|(d, c)| Some([d.as_ref()?[0] * c.as_ref()?[0], c.as_ref()?[0].powi(2)]))
                    .collect();
                let sums = window_sums(width, &terms, FIT_RADIUS);
                for ((b, [num, den]), d) in best.iter_mut().zip(sums).zip(field) {
                    if d.is_none() || num <= 0.0 || den <= 0.0 {
                        continue;
                    }
                    let removed = num * num / den;
                    if removed > b.0 {
                        *b = (removed, Some(Shift { kappa: (num / den).min(1.0), radius }));
                    }
                }
            }
            best.into_iter().map(|(_, s)| s).collect()
        });
        Correction { width, shifts }
    }

    /// Half `h`'s correction at every pixel, −κ · ring_r(`other`), `other` being the other
    /// half's field (any channels; its gray D̄ or its per-channel one); 0 where there is none.
    pub fn apply<const K: usize>(&self, h: usize, other: &[Option<[f64; K]>]) -> Vec<[f64; K]> {
        let rings = RADII.map(|r| {
            let used = self.shifts[h].iter().any(|s| s.is_some_and(|s| s.radius == r));
            if used { ring_means(self.width, other, r) } else { Vec::new() }
        });
        self.shifts[h]
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let Some(s) = s else { return [0.0; K] };
                let k = RADII.iter().position(|&r| r == s.radius).expect("a radius of RADII");
                match rings[k][i] {
                    Some(c) => c.map(|c| -s.kappa * c),
                    None => [0.0; K],
                }
            })
            .collect()
    }
}

/// The mean of `values` (a `width`-wide image; None counts as nothing) over the (2r + 1)²
/// pixels around each pixel, the pixel itself left out; None where none of them has a value.
fn ring_means<const K: usize>(width: usize, values: &[Option<[f64; K]>], r: usize) -> Vec<Option<[f64; K]>> {
    let ones: Vec<Option<[f64; 1]>> = values.iter().map(|v| v.map(|_| [1.0])).collect();
    let counts = window_sums(width, &ones, r);
    let sums = window_sums(width, values, r);
    values
        .iter()
        .zip(counts)
        .zip(sums)
        .map(|((v, [count]), sum)| {
            let own = v.unwrap_or([0.0; K]);
            let n = count - if v.is_some() { 1.0 } else { 0.0 };
            (n > 0.5).then(|| std::array::from_fn(|k| (sum[k] - own[k]) / n))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ring_leaves_out_its_centre_and_the_missing() {
        // 3×3: the centre's ring is the mean of the other eight, one of them missing.
        let mut v: Vec<Option<[f64; 1]>> = (0..9).map(|i| Some([i as f64])).collect();
        v[0] = None;
        let ring = ring_means(3, &v, 1);
        assert_eq!(ring[4], Some([(1.0 + 2.0 + 3.0 + 5.0 + 6.0 + 7.0 + 8.0) / 7.0]));
        // The corner (0, 0) has no value of its own: its ring is its three neighbours.
        assert_eq!(ring[0], Some([(1.0 + 3.0 + 4.0) / 3.0]));
    }

    /// A uniform bias is fitted with κ near 1 at the widest ring; a bias alternating from
    /// pixel to pixel (a checkerboard, whose rings average out) gets no correction.
    #[test]
    fn the_fit_takes_a_smooth_bias_and_leaves_a_rough_one() {
        let side = 24;
        let mut state = 3u64;
        let mut noise = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.1
        };
        let smooth: Vec<Option<[f64; 1]>> = (0..side * side).map(|_| Some([0.05 + noise()])).collect();
        let c = Correction::fit(side, [&smooth, &smooth]);
        let s = c.shifts[0][side * side / 2 + side / 2].unwrap();
        assert!(s.kappa > 0.9 && s.radius == 4, "{s:?}");
        let shift = c.apply(0, &smooth)[side * side / 2 + side / 2][0];
        assert!((shift + 0.05).abs() < 0.01, "{shift}");

        let rough: Vec<Option<[f64; 1]>> =
            (0..side * side).map(|i| Some([if (i % side + i / side) % 2 == 0 { 0.05 } else { -0.05 }])).collect();
        let c = Correction::fit(side, [&rough, &rough]);
        assert!(c.apply(0, &rough).iter().all(|v| v[0].abs() < 0.01));
    }
}
