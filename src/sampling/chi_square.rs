//! Test support: Pearson's chi-square goodness-of-fit test and a small seeded RNG.
//!
//! Thresholds are set at significance 1e-4 and every test uses fixed seeds, so a correct
//! sampler fails with probability 1e-4 once, and then deterministically never again.

/// SplitMix64 (Steele et al. 2014): a tiny, well-mixed generator for tests.
pub(crate) struct TestRng(u64);

impl TestRng {
    /// A generator whose stream is fixed by `seed`.
    pub(crate) fn new(seed: u64) -> TestRng {
        TestRng(seed)
    }

    /// The next 64 random bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 24 random bits (every f32 value is exact).
    pub(crate) fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// Upper quantile of the chi-square distribution with `dof` degrees of freedom at
/// significance 1e-4, by the Wilson-Hilferty cube approximation (slightly conservative for
/// small `dof`).
fn chi_square_threshold(dof: usize) -> f64 {
    // Standard normal quantile for 1 - 1e-4.
    const Z: f64 = 3.719_016_5;
    let k = dof.max(1) as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + Z * a.sqrt()).powi(3)
}

/// Pearson's test of `observed` counts against `expected` counts (same total). Cells expected
/// to hold fewer than 5 samples are pooled, as the test requires; a sample in a cell of
/// expected count zero fails at once.
pub(crate) fn chi_square_test(observed: &[u64], expected: &[f64]) -> Result<(), String> {
    assert_eq!(observed.len(), expected.len());
    let mut stat = 0.0;
    let mut cells = 0usize;
    let (mut pooled_o, mut pooled_e) = (0.0, 0.0);
    for (i, (&o, &e)) in observed.iter().zip(expected).enumerate() {
        if e == 0.0 {
            if o > 0 {
                return Err(format!("cell {i}: {o} samples where none are expected"));
            }
        } else if e < 5.0 {
            pooled_o += o as f64;
            pooled_e += e;
        } else {
            stat += (o as f64 - e).powi(2) / e;
            cells += 1;
        }
    }
    if pooled_e > 0.0 {
        stat += (pooled_o - pooled_e).powi(2) / pooled_e;
        cells += 1;
    }
    let threshold = chi_square_threshold(cells.saturating_sub(1));
    if stat > threshold {
        Err(format!("chi-square {stat:.1} over {cells} cells exceeds {threshold:.1} (p = 1e-4)"))
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threshold_matches_tables() {
        // Exact 0.9999 quantiles: 1 dof 15.14, 10 dof 35.56, 100 dof 161.32.
        assert!((chi_square_threshold(1) - 15.14).abs() < 1.5);
        assert!((chi_square_threshold(10) - 35.56).abs() < 0.5);
        assert!((chi_square_threshold(100) - 161.32).abs() < 0.5);
    }

    #[test]
    fn rejects_a_wrong_distribution_and_accepts_the_right_one() {
        let mut rng = TestRng::new(7);
        let mut counts = [0u64; 10];
        for _ in 0..100_000 {
            counts[(rng.uniform() * 10.0) as usize] += 1;
        }
        assert!(chi_square_test(&counts, &[10_000.0; 10]).is_ok());
        let mut skewed = [10_000.0; 10];
        skewed[0] = 10_500.0;
        skewed[1] = 9_500.0;
        assert!(chi_square_test(&counts, &skewed).is_err());
    }
}
