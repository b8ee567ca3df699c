//! Errors against a reference with the reference's own noise taken out.
//!
//! A Monte Carlo reference R = (A + B) / 2, rendered as two independent halves A and B, is
//! noisy itself, and that noise adds to every error measured against it: a method whose
//! error approaches the reference's looks no better than the reference, whatever it does.
//! Each error E(X, ·) is extrapolated to a noiseless reference from its value against R
//! and against each half (whose noise variance is twice R's):
//!
//! E₀ = 2·E(X, R) − (E(X, A) + E(X, B)) / 2.
//!
//! For the squared errors this is exact, pixel by pixel: with d = X − R and h = (A − B)/2,
//! ((d − h)² + (d + h)²)/2 = d² + h², so E₀ = d² − h² = (X − R)² − (A − B)²/4, whose
//! expectation is the error against the true image (relMSE − relMSE(A, B)/4). An absolute
//! error (MAE, MPE, MNE) grows with the noise variance as √(σ² + v) does, not linearly, so it
//! is extrapolated in its square: E₀² = 2·E(X, R)² − ((E(X, A) + E(X, B))/2)², exact for
//! errors of one spread, approximate when pixels' spreads differ. relMSE's weight
//! 1/(R² + 0.01) is noisy too, which no removal undoes: it leaves a bias of the order of the
//! reference's relative noise squared (1–2 % of the error for a reference 4 % noisy per
//! half, smaller for references of thousands of spp). Squared errors can come out
//! below zero when the method's error is within the reference's noise; absolute ones then
//! come out 0.

use super::ErrorMetrics;
use crate::error::{Error, Result};
use crate::imageio::Image;

fn same_size(images: &[(&str, &Image)]) -> Result<()> {
    let (_, first) = images[0];
    for (name, img) in &images[1..] {
        if (img.width, img.height) != (first.width, first.height) {
            return Err(Error::Invalid(format!(
                "image sizes differ: {name} is {}x{}, the test image {}x{}",
                img.width, img.height, first.width, first.height
            )));
        }
    }
    Ok(())
}

/// The errors of `test` against the reference R = (a + b)/2 with R's noise removed (see the
/// module's comment). The relative error's denominator is R's for all three terms, so the
/// squared errors are exact; `mean_reference` is R's mean.
pub fn error_metrics_noise_removed(test: &Image, a: &Image, b: &Image) -> Result<ErrorMetrics> {
    same_size(&[("test", test), ("first reference half", a), ("second reference half", b)])?;
    let (mut se, mut rel, mut st, mut sr) = (0.0f64, 0.0, 0.0, 0.0);
    // Absolute, positive and negative error against R, A and B.
    let mut abs = [[0.0f64; 3]; 3];
    for ((pt, pa), pb) in test.pixels.iter().zip(&a.pixels).zip(&b.pixels) {
        for c in 0..3 {
            let (x, ya, yb) = (pt[c] as f64, pa[c] as f64, pb[c] as f64);
            let r = 0.5 * (ya + yb);
            let (d, h) = (x - r, 0.5 * (ya - yb));
            let sq = d * d - h * h;
            se += sq;
            rel += sq / (r * r + 0.01);
            for (k, e) in [d, d - h, d + h].into_iter().enumerate() {
                abs[0][k] += e.abs();
                abs[1][k] += e.max(0.0);
                abs[2][k] += (-e).max(0.0);
            }
            st += x;
            sr += r;
        }
    }
    let n = (test.pixels.len() * 3).max(1) as f64;
    let extrapolate = |[r, ea, eb]: [f64; 3]| {
        let (r, half) = (r / n, 0.5 * (ea + eb) / n);
        (2.0 * r * r - half * half).max(0.0).sqrt()
    };
    Ok(ErrorMetrics {
        mse: se / n,
        rmse: (se / n).max(0.0).sqrt(),
        rel_mse: rel / n,
        mae: extrapolate(abs[0]),
        mpe: extrapolate(abs[1]),
        mne: extrapolate(abs[2]),
        mean_test: st / n,
        mean_reference: sr / n,
    })
}

/// What R = (a + b)/2's own noise adds to each error measured against it: the difference
/// between an error against R and the same error with the noise removed, in expectation
/// for a test image equal to the true image. For the squared errors it is (A − B)²/4
/// averaged (relMSE(A, B)/4); `mean_test` is unused (0).
pub fn reference_noise(a: &Image, b: &Image) -> Result<ErrorMetrics> {
    same_size(&[("first reference half", a), ("second reference half", b)])?;
    let r = average(a, b);
    let raw = super::error_metrics(&r, &r)?;
    let removed = error_metrics_noise_removed(&r, a, b)?;
    Ok(ErrorMetrics {
        mse: raw.mse - removed.mse,
        rmse: (raw.mse - removed.mse).max(0.0).sqrt(),
        rel_mse: raw.rel_mse - removed.rel_mse,
        mae: raw.mae - removed.mae,
        mpe: raw.mpe - removed.mpe,
        mne: raw.mne - removed.mne,
        mean_test: 0.0,
        mean_reference: raw.mean_reference,
    })
}

/// The standard error of the mean of R = (a + b)/2 over pixels and channels, from the halves'
/// per-pixel differences: var(R_p) ≈ ((A_p − B_p)/2)² for each pixel's channel mean, and
/// pixels are independent (a reference is rendered by a method without shared state).
pub fn mean_standard_error(a: &Image, b: &Image) -> Result<f64> {
    same_size(&[("first reference half", a), ("second reference half", b)])?;
    let var: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(pa, pb)| {
            let d = (*pa - *pb).to_array().iter().map(|v| *v as f64).sum::<f64>() / 3.0;
            0.25 * d * d
        })
        .sum();
    let n = a.pixels.len().max(1) as f64;
    Ok(var.sqrt() / n)
}

/// (a + b)/2, pixel by pixel (same sizes; the metadata is a's).
pub fn average(a: &Image, b: &Image) -> Image {
    let mut out = a.clone();
    for (o, pb) in out.pixels.iter_mut().zip(&b.pixels) {
        *o = 0.5 * (*o + *pb);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::error_metrics;
    use crate::sampling::rng::Pcg32;

    fn noisy(truth: &[f32], sigma: f32, rng: &mut Pcg32) -> Image {
        let mut img = Image::new(truth.len(), 1);
        for (p, t) in img.pixels.iter_mut().zip(truth) {
            let mut g = || {
                // A sum of uniforms: zero mean, variance sigma².
                let u: f32 = (0..12).map(|_| rng.uniform()).sum::<f32>() - 6.0;
                t + sigma * u
            };
            *p = glam::Vec3::new(g(), g(), g());
        }
        img
    }

    #[test]
    fn squared_errors_lose_exactly_the_halves_difference() {
        let mut rng = Pcg32::new(0, 7);
        let truth: Vec<f32> = (0..64).map(|i| 0.2 + 0.01 * i as f32).collect();
        let (a, b, x) = (noisy(&truth, 0.1, &mut rng), noisy(&truth, 0.1, &mut rng), noisy(&truth, 0.05, &mut rng));
        let r = average(&a, &b);
        let raw = error_metrics(&x, &r).unwrap();
        let removed = error_metrics_noise_removed(&x, &a, &b).unwrap();
        let mut h2 = 0.0f64;
        for (pa, pb) in a.pixels.iter().zip(&b.pixels) {
            for c in 0..3 {
                h2 += (0.5 * (pa[c] as f64 - pb[c] as f64)).powi(2);
            }
        }
        let h2 = h2 / (64.0 * 3.0);
        assert!((raw.mse - removed.mse - h2).abs() < 1e-9, "{} {} {h2}", raw.mse, removed.mse);
        assert!((reference_noise(&a, &b).unwrap().mse - h2).abs() < 1e-9);
        assert!((raw.mean_reference - removed.mean_reference).abs() < 1e-6);
    }

    /// Over `trials` draws: (raw, noise removed, against the truth) for `get`.
    fn trial_means(sigma_half: f32, sigma_test: f32, get: fn(&ErrorMetrics) -> f64) -> (f64, f64, f64) {
        let mut rng = Pcg32::new(0, 11);
        let truth: Vec<f32> = (0..4096).map(|i| 0.5 + 0.3 * ((i as f32) * 0.37).sin()).collect();
        let mut t = Image::new(truth.len(), 1);
        for (p, v) in t.pixels.iter_mut().zip(&truth) {
            *p = glam::Vec3::splat(*v);
        }
        let (mut raw, mut removed, mut exact) = (0.0, 0.0, 0.0);
        for _ in 0..20 {
            let (a, b) = (noisy(&truth, sigma_half, &mut rng), noisy(&truth, sigma_half, &mut rng));
            let x = noisy(&truth, sigma_test, &mut rng);
            raw += get(&error_metrics(&x, &average(&a, &b)).unwrap());
            removed += get(&error_metrics_noise_removed(&x, &a, &b).unwrap());
            exact += get(&error_metrics(&x, &t).unwrap());
        }
        (raw, removed, exact)
    }

    #[test]
    fn noise_removal_recovers_the_error_against_the_truth_on_average() {
        // Reference noise (σ 0.1 per half, 0.0707 for R) twice the test image's (σ 0.035):
        // against R the MSE is 5× the true one; removed, it is the true one within its noise.
        let (raw, removed, exact) = trial_means(0.1, 0.035, |m| m.mse);
        assert!(raw > 4.0 * exact, "{raw} {exact}");
        assert!((removed / exact - 1.0).abs() < 0.05, "{removed} {exact}");
        // Errors of one spread: the MAE's extrapolation in its square is exact too (the raw
        // MAE is 2.25× the true one).
        let (raw, removed, exact) = trial_means(0.1, 0.035, |m| m.mae);
        assert!(raw > 2.0 * exact, "{raw} {exact}");
        assert!((removed / exact - 1.0).abs() < 0.05, "{removed} {exact}");
        // relMSE's weight 1/(R² + 0.01) is noisy too, which the removal cannot undo: with a
        // reference 4 % noisy per half it is left within a few percent.
        let (raw, removed, exact) = trial_means(0.02, 0.01, |m| m.rel_mse);
        assert!(raw > 2.5 * exact, "{raw} {exact}");
        assert!((removed / exact - 1.0).abs() < 0.05, "{removed} {exact}");
    }

    #[test]
    fn the_mean_standard_error_matches_the_spread_of_means() {
        let mut rng = Pcg32::new(0, 3);
        let truth = vec![1.0f32; 1024];
        let (a, b) = (noisy(&truth, 0.2, &mut rng), noisy(&truth, 0.2, &mut rng));
        // Channels are independent here, so a pixel's channel mean has σ 0.2/√3 and R's
        // 0.2/√6; its mean over 1024 pixels 0.2/√6/32.
        let se = mean_standard_error(&a, &b).unwrap();
        let expected = 0.2 / 6f64.sqrt() / 32.0;
        assert!((se / expected - 1.0).abs() < 0.1, "{se} {expected}");
        assert!(error_metrics_noise_removed(&Image::new(3, 1), &a, &b).is_err());
    }
}
