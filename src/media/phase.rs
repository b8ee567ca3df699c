//! The Henyey-Greenstein phase function, for participating media and for the medium between
//! the layers of a layered BxDF (pbrt-v4 §11.3, `HGPhaseFunction`, `HenyeyGreenstein` and `SampleHenyeyGreenstein`).
//!
//! pbrt-v4's convention: both directions point away from the scattering point, so
//! p(ωo, ωi) = HG(ωo·ωi, g) with the sign of the cosine term flipped relative to the
//! textbook formula; g > 0 scatters forward, i.e. ωi ≈ −ωo.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::math::{Frame, safe_sqrt, sqr};

/// The Henyey-Greenstein function (1 − g²)/(4π (1 + g² + 2g cos θ)^(3/2)) of
/// cos θ = ωo·ωi. |g| is clamped to
/// 0.99, where the function is still numerically stable.
#[inline]
pub fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let g = g.clamp(-0.99, 0.99);
    let denom = 1.0 + sqr(g) + 2.0 * g * cos_theta;
    (1.0 - sqr(g)) / (4.0 * PI * denom * safe_sqrt(denom))
}

/// A sampled direction of a phase function.
#[derive(Clone, Copy, Debug)]
pub struct PhaseSample {
    /// Phase function value.
    pub p: f32,
    /// Sampled direction, pointing away from the scattering point.
    pub wi: Vec3,
    /// Density of `wi` (equal to `p`: HG is sampled exactly).
    pub pdf: f32,
}

/// The Henyey-Greenstein phase function with asymmetry `g`.
#[derive(Clone, Copy, Debug)]
pub struct HenyeyGreenstein {
    g: f32,
}

impl HenyeyGreenstein {
    /// A phase function with asymmetry `g` ∈ [−1, 1].
    #[inline]
    pub fn new(g: f32) -> HenyeyGreenstein {
        HenyeyGreenstein { g }
    }

    /// p(ωo, ωi).
    #[inline]
    pub fn p(&self, wo: Vec3, wi: Vec3) -> f32 {
        henyey_greenstein(wo.dot(wi), self.g)
    }

    /// Density of [`HenyeyGreenstein::sample_p`], equal to p.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.p(wo, wi)
    }

    /// Samples ωi by inverting the CDF of cos θ (pbrt-v4 §11.3); never fails.
    pub fn sample_p(&self, wo: Vec3, u: Vec2) -> Option<PhaseSample> {
        let g = self.g.clamp(-0.99, 0.99);
        let cos_theta = if g.abs() < 1e-3 {
            1.0 - 2.0 * u.x
        } else {
            -1.0 / (2.0 * g) * (1.0 + sqr(g) - sqr((1.0 - sqr(g)) / (1.0 + g - 2.0 * g * u.x)))
        };
        let sin_theta = safe_sqrt(1.0 - sqr(cos_theta));
        let phi = 2.0 * PI * u.y;
        let local = Vec3::new(
            sin_theta.clamp(-1.0, 1.0) * phi.cos(),
            sin_theta.clamp(-1.0, 1.0) * phi.sin(),
            cos_theta.clamp(-1.0, 1.0),
        );
        let wi = Frame::from_z(wo).to_world(local);
        let pdf = henyey_greenstein(cos_theta, g);
        Some(PhaseSample { p: pdf, wi, pdf })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::testing::{integrate_sphere, stratified_2d};

    #[test]
    fn henyey_greenstein_is_normalized_with_mean_cosine_minus_g() {
        // ∫ p dω = 1 and, in pbrt's convention, ∫ p (ωo·ωi) dω = −g.
        let wo = Vec3::new(0.2, -0.4, 0.7).normalize();
        for g in [-0.7f32, -0.2, 0.0, 0.5, 0.9] {
            let hg = HenyeyGreenstein::new(g);
            let norm = integrate_sphere(1024, 256, |wi| hg.p(wo, wi) as f64);
            let mean = integrate_sphere(1024, 256, |wi| (hg.p(wo, wi) * wo.dot(wi)) as f64);
            assert!((norm - 1.0).abs() < 2e-3, "g {g}: {norm}");
            assert!((mean + g as f64).abs() < 2e-3, "g {g}: {mean}");
        }
    }

    #[test]
    fn sampling_matches_the_mean_cosine_and_pdf() {
        let wo = Vec3::new(-0.5, 0.1, 0.3).normalize();
        for g in [-0.6f32, 0.0, 0.3, 0.95] {
            let hg = HenyeyGreenstein::new(g);
            let n = 128;
            let mut mean = 0.0f64;
            for u in stratified_2d(n) {
                let s = hg.sample_p(wo, u).expect("HG sampling never fails");
                assert!((s.wi.length() - 1.0).abs() < 1e-4);
                assert!((s.pdf - hg.pdf(wo, s.wi)).abs() <= 2e-3 * s.pdf.max(1.0), "g {g}");
                mean += wo.dot(s.wi) as f64;
            }
            mean /= (n * n) as f64;
            assert!((mean + g.clamp(-0.99, 0.99) as f64).abs() < 2e-3, "g {g}: {mean}");
        }
    }
}
