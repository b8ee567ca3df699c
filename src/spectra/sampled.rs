//! Sampled spectra: pbrt-v4's `SampledSpectrum` and `SampledWavelengths` — four wavelengths
//! per camera path, drawn from its visible-wavelength density, with their probabilities.

use glam::Vec4;

use crate::math::ln4;

/// Wavelengths per path.
pub const N_SPECTRUM_SAMPLES: usize = 4;

/// Values of a spectrum at the four wavelengths of a path.
pub type SampledSpectrum = Vec4;

/// Shortest wavelength sampled (nm).
const LAMBDA_MIN: f32 = 360.0;
/// Longest wavelength sampled (nm).
const LAMBDA_MAX: f32 = 830.0;

/// The wavelengths a path carries and the density each was drawn with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    /// Wavelengths in nm.
    pub lambda: Vec4,
    /// Their densities; zero for wavelengths a path has dropped.
    pub pdf: Vec4,
}

impl SampledWavelengths {
    /// pbrt-v4's `SampleVisible`: four wavelengths from one uniform sample, stratified by
    /// offsetting it by quarters, each drawn from the visible-wavelength density.
    pub fn sample_visible(u: f32) -> SampledWavelengths {
        // The four lanes at once: `sample_visible_wavelength` with ln x on lanes (atanh y =
        // ½ ln((1 + y)/(1 − y))), and its density without a cosh: λ − 538 = −138.88889 atanh y
        // makes cosh(0.0072 (λ − 538)) = cosh(atanh y) = 1/√(1 − y²) (0.0072 · 138.88889 = 1
        // to 1e-8), so `visible_wavelength_pdf(λ)` = 0.003939804 (1 − y²).
        let up = Vec4::splat(u) + Vec4::new(0.0, 0.25, 0.5, 0.75);
        let up = Vec4::select(up.cmpgt(Vec4::ONE), up - 1.0, up);
        let y = Vec4::splat(0.856_910_6) - up * 1.827_502;
        let lambda = Vec4::splat(538.0) - 69.444_44 * ln4((1.0 + y) / (1.0 - y));
        let inside = lambda.cmpge(Vec4::splat(LAMBDA_MIN)) & lambda.cmple(Vec4::splat(LAMBDA_MAX));
        let pdf = Vec4::select(inside, 0.003_939_804 * (1.0 - y * y), Vec4::ZERO);
        SampledWavelengths { lambda, pdf }
    }

    /// pbrt-v4's `SampleUniform`: evenly spaced wavelengths over 360–830 nm from `u`.
    pub fn sample_uniform(u: f32) -> SampledWavelengths {
        SampledWavelengths::sample_uniform_in(u, LAMBDA_MIN, LAMBDA_MAX)
    }

    /// pbrt-v4's `SampleUniform(u, min, max)`: wavelengths evenly spaced over [min, max]
    /// (wrapping), the first at `u`, each with density 1/(max − min).
    pub fn sample_uniform_in(u: f32, min: f32, max: f32) -> SampledWavelengths {
        let delta = (max - min) / N_SPECTRUM_SAMPLES as f32;
        let mut lambda = [0.0; N_SPECTRUM_SAMPLES];
        lambda[0] = min + u * (max - min);
        for i in 1..N_SPECTRUM_SAMPLES {
            lambda[i] = lambda[i - 1] + delta;
            if lambda[i] > max {
                lambda[i] = min + (lambda[i] - max);
            }
        }
        SampledWavelengths { lambda: Vec4::from_array(lambda), pdf: Vec4::splat(1.0 / (max - min)) }
    }

    /// Keeps only the first wavelength (pbrt-v4's `TerminateSecondary`), for paths whose
    /// direction depends on the wavelength (dispersion): its density becomes that of picking
    /// it among four, the others' zero.
    pub fn terminate_secondary(&mut self) {
        if self.secondary_terminated() {
            return;
        }
        self.pdf = Vec4::new(self.pdf.x / N_SPECTRUM_SAMPLES as f32, 0.0, 0.0, 0.0);
    }

    /// True once only the first wavelength is left.
    pub fn secondary_terminated(&self) -> bool {
        self.pdf.y == 0.0 && self.pdf.z == 0.0 && self.pdf.w == 0.0
    }
}

/// pbrt-v4's `VisibleWavelengthsPDF`: a density over 360–830 nm shaped like the eye's
/// response, so sampled spectra put their samples where the film sees them.
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let c = (0.0072 * (lambda - 538.0)).cosh();
    0.003_939_804 / (c * c)
}

/// pbrt-v4's `SampleVisibleWavelengths`: inverts the CDF of [`visible_wavelength_pdf`].
pub fn sample_visible_wavelength(u: f32) -> f32 {
    538.0 - 138.888_89 * (0.856_910_6 - 1.827_502 * u).atanh()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visible_density_integrates_to_one_and_inverts_its_cdf() {
        let n = 47_000;
        let dl = (LAMBDA_MAX - LAMBDA_MIN) as f64 / n as f64;
        let total: f64 =
            (0..n).map(|i| visible_wavelength_pdf(LAMBDA_MIN + ((i as f64 + 0.5) * dl) as f32) as f64).sum();
        assert!((total * dl - 1.0).abs() < 1e-3, "{}", total * dl);
        // The sampled wavelength at u has CDF u.
        for k in 1..20 {
            let u = k as f32 / 20.0;
            let l = sample_visible_wavelength(u);
            let m = 4000;
            let dl = (l - LAMBDA_MIN) as f64 / m as f64;
            let cdf: f64 =
                (0..m).map(|i| visible_wavelength_pdf(LAMBDA_MIN + ((i as f64 + 0.5) * dl) as f32) as f64).sum::<f64>()
                    * dl;
            assert!((cdf - u as f64).abs() < 2e-3, "u {u}: cdf {cdf}");
        }
        assert!((sample_visible_wavelength(0.0) - LAMBDA_MIN).abs() < 0.5);
        assert!((sample_visible_wavelength(1.0) - LAMBDA_MAX).abs() < 0.5);
    }

    /// The four-lane sampling is the scalar formulas, lane by lane.
    #[test]
    fn lanes_match_the_scalar_formulas() {
        for k in 0..10_000 {
            let u = k as f32 / 10_000.0;
            let l = SampledWavelengths::sample_visible(u);
            for i in 0..N_SPECTRUM_SAMPLES {
                let mut up = u + i as f32 / N_SPECTRUM_SAMPLES as f32;
                if up > 1.0 {
                    up -= 1.0;
                }
                let lambda = sample_visible_wavelength(up);
                assert!((l.lambda[i] - lambda).abs() < 2e-3, "u {up}: {} vs {lambda}", l.lambda[i]);
                let pdf = visible_wavelength_pdf(l.lambda[i]);
                assert!((l.pdf[i] - pdf).abs() <= 1e-5 * pdf, "u {up}: pdf {} vs {pdf}", l.pdf[i]);
            }
        }
    }

    #[test]
    fn termination_keeps_the_first_wavelength() {
        let mut l = SampledWavelengths::sample_visible(0.3);
        let first = l.pdf.x;
        assert!(!l.secondary_terminated());
        l.terminate_secondary();
        assert!(l.secondary_terminated());
        assert_eq!(l.pdf, Vec4::new(first / 4.0, 0.0, 0.0, 0.0));
        l.terminate_secondary();
        assert_eq!(l.pdf.x, first / 4.0);
    }
}
