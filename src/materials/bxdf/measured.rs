//! pbrt-v4's `MeasuredBxDF`: evaluation and sampling of a measured BRDF's tables
//! ([`MeasuredData`]) in Dupuy and Jakob's parameterisation. A direction maps to the unit
//! square by u = sqrt(2θ/π), v = φ/2π + 1/2 (θ, φ of the half vector, φ relative to the
//! outgoing direction for isotropic materials); sampling warps the uniform sample by the
//! luminance table, then by the visible-NDF table, and reflects the outgoing direction about
//! the resulting microfacet normal.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::{BsdfSample, BxdfFlags, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::color::Rgb;
use crate::materials::measured::MeasuredData;
use crate::math::same_hemisphere;

fn theta2u(theta: f32) -> f32 {
    (theta * (2.0 / PI)).max(0.0).sqrt()
}

fn phi2u(phi: f32) -> f32 {
    phi * (0.5 / PI) + 0.5
}

fn u2theta(u: f32) -> f32 {
    u * u * (PI / 2.0)
}

fn u2phi(u: f32) -> f32 {
    (2.0 * u - 1.0) * PI
}

fn spherical_theta(v: Vec3) -> f32 {
    v.z.clamp(-1.0, 1.0).acos()
}

/// A measured BRDF at one hit, for the path's wavelengths (or RGB channels).
#[derive(Clone, Debug)]
pub struct MeasuredBxdf<C = Rgb> {
    data: Arc<MeasuredData>,
    /// The path's wavelengths, or `None` for RGB.
    wavelengths: Option<Vec4>,
    _channels: std::marker::PhantomData<C>,
}

impl<C> PartialEq for MeasuredBxdf<C> {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.data, &o.data) && self.wavelengths == o.wavelengths
    }
}

impl<C: Channels> MeasuredBxdf<C> {
    /// The BRDF of `data` at the wavelengths `lambda`.
    pub fn new(data: Arc<MeasuredData>, lambda: &C::Lambda) -> MeasuredBxdf<C> {
        MeasuredBxdf { data, wavelengths: C::wavelengths(lambda), _channels: std::marker::PhantomData }
    }

    /// The tabulated BRDF factor at warped coordinates `p` for the outgoing (φ, θ), per channel.
    #[inline]
    fn values(&self, p: Vec2, phi_o: f32, theta_o: f32) -> C {
        let d = &self.data;
        let lanes = match self.wavelengths {
            Some(l) => Vec4::from_array(l.to_array().map(|l| d.spectra.evaluate(p, &[phi_o, theta_o, l]).max(0.0))),
            None => {
                let c = |k: f32| d.rgb.evaluate(p, &[phi_o, theta_o, k]).max(0.0);
                Vec4::new(c(0.0), c(1.0), c(2.0), 0.0)
            }
        };
        C::from_lanes(lanes)
    }

    /// (u, v) of the half vector `wm` for the outgoing azimuth `phi_o`.
    #[inline]
    fn u_wm(&self, wm: Vec3, phi_o: f32) -> Vec2 {
        let phi_m = wm.y.atan2(wm.x);
        let v = phi2u(if self.data.isotropic { phi_m - phi_o } else { phi_m });
        Vec2::new(theta2u(spherical_theta(wm)), v - v.floor())
    }

    /// The BRDF value (pbrt-v4's `MeasuredBxDF::f`): the tabulated factor at the inverse of
    /// the VNDF warp, times D(wm) / (4 σ(wo) cos θi).
    pub fn f(&self, mut wo: Vec3, mut wi: Vec3, _mode: TransportMode) -> C {
        if !same_hemisphere(wo, wi) {
            return C::ZERO;
        }
        if wo.z < 0.0 {
            wo = -wo;
            wi = -wi;
        }
        let wm = (wi + wo).normalize_or_zero();
        if wm == Vec3::ZERO {
            return C::ZERO;
        }
        let (theta_o, phi_o) = (spherical_theta(wo), wo.y.atan2(wo.x));
        let u_wo = Vec2::new(theta2u(theta_o), phi2u(phi_o));
        let u_wm = self.u_wm(wm, phi_o);
        let ui = self.data.vndf.invert(u_wm, &[phi_o, theta_o]);
        let d = self.data.ndf.evaluate(u_wm, &[]);
        let sigma = self.data.sigma.evaluate(u_wo, &[]);
        let denom = 4.0 * sigma * wi.z;
        if denom <= 0.0 || !denom.is_finite() {
            return C::ZERO;
        }
        self.values(ui.p, phi_o, theta_o) * (d / denom)
    }

    /// Samples wi (pbrt-v4's `MeasuredBxDF::Sample_f`).
    pub fn sample_f(
        &self,
        mut wo: Vec3,
        _uc: f32,
        u: Vec2,
        _mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        if !sample_flags.reflection() {
            return None;
        }
        let flip = wo.z <= 0.0;
        if flip {
            wo = -wo;
        }
        let (theta_o, phi_o) = (spherical_theta(wo), wo.y.atan2(wo.x));
        let s = self.data.luminance.sample(u, &[phi_o, theta_o]);
        let (u, lum_pdf) = (s.p, s.pdf);
        let s = self.data.vndf.sample(u, &[phi_o, theta_o]);
        let (u_wm, mut pdf) = (s.p, s.pdf);
        let mut phi_m = u2phi(u_wm.y);
        let theta_m = u2theta(u_wm.x);
        if self.data.isotropic {
            phi_m += phi_o;
        }
        let (sin_m, cos_m) = theta_m.sin_cos();
        let wm = Vec3::new(sin_m * phi_m.cos(), sin_m * phi_m.sin(), cos_m);
        let mut wi = -wo + 2.0 * wo.dot(wm) * wm;
        if wi.z <= 0.0 {
            return None;
        }
        let u_wo = Vec2::new(theta2u(theta_o), phi2u(phi_o));
        let denom = 4.0 * self.data.sigma.evaluate(u_wo, &[]) * wi.z.abs();
        if denom <= 0.0 {
            return None;
        }
        let f = self.values(u, phi_o, theta_o) * (self.data.ndf.evaluate(u_wm, &[]) / denom);
        pdf /= 4.0 * wo.dot(wm) * (2.0 * PI * PI * u_wm.x * sin_m).max(1e-6);
        if flip {
            wi = -wi;
        }
        let pdf = pdf * lum_pdf;
        (pdf.is_finite() && pdf > 0.0).then(|| BsdfSample::new(f, wi, pdf, BxdfFlags::GLOSSY_REFLECTION))
    }

    /// The density of [`MeasuredBxdf::sample_f`] (pbrt-v4's `MeasuredBxDF::PDF`).
    pub fn pdf(&self, mut wo: Vec3, mut wi: Vec3, _mode: TransportMode, sample_flags: ReflTransFlags) -> f32 {
        if !sample_flags.reflection() || !same_hemisphere(wo, wi) {
            return 0.0;
        }
        if wo.z < 0.0 {
            wo = -wo;
            wi = -wi;
        }
        let wm = (wi + wo).normalize_or_zero();
        if wm == Vec3::ZERO {
            return 0.0;
        }
        let (theta_o, phi_o) = (spherical_theta(wo), wo.y.atan2(wo.x));
        let u_wm = self.u_wm(wm, phi_o);
        let ui = self.data.vndf.invert(u_wm, &[phi_o, theta_o]);
        let pdf = self.data.luminance.evaluate(ui.p, &[phi_o, theta_o]);
        let sin_m = (wm.x * wm.x + wm.y * wm.y).sqrt();
        let jacobian = 4.0 * wo.dot(wm) * (2.0 * PI * PI * u_wm.x * sin_m).max(1e-6);
        let p = ui.pdf * pdf / jacobian;
        if p.is_finite() { p.max(0.0) } else { 0.0 }
    }

    /// Glossy reflection.
    pub fn flags(&self) -> BxdfFlags {
        BxdfFlags::GLOSSY_REFLECTION
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::Bxdf;
    use crate::materials::bxdf::testing::{stratified_2d, test_directions};
    use crate::materials::measured::synthetic_bsdf;
    use nimbus_parser::ColorSpace;

    fn bxdf() -> Bxdf {
        let data = Arc::new(MeasuredData::from_bytes(&synthetic_bsdf(false), ColorSpace::Srgb).unwrap());
        Bxdf::Measured(MeasuredBxdf::new(data, &()))
    }

    /// Whatever the tables hold, sampling, its density and evaluation must agree: each
    /// sample's f and pdf are `f()` and `pdf()` at its direction, and the density is a true
    /// density of the samples: E[1/pdf] over them, times the chance that a sample is returned,
    /// is the solid angle they cover, the whole hemisphere (a quadrature of ∫pdf would not
    /// do: the parameterisation's density is singular, like θ^−3/2, at the mirror direction).
    #[test]
    fn sampling_density_and_evaluation_agree() {
        let b = bxdf();
        crate::materials::bxdf::testing::check_ignores_uc(&b);
        let (mode, flags) = (TransportMode::Radiance, ReflTransFlags::ALL);
        for wo in test_directions() {
            let n = 512;
            let (mut ok, mut inv) = (0usize, 0.0f64);
            for u in stratified_2d(n) {
                if let Some(s) = b.sample_f(wo, 0.5, u, mode, flags) {
                    ok += 1;
                    inv += 1.0 / s.pdf as f64;
                }
            }
            let p_ok = ok as f64 / (n * n) as f64;
            assert!(p_ok > 0.3, "wo {wo}: samples succeed with p {p_ok}");
            let covered = p_ok * inv / ok as f64;
            assert!(
                (covered / (2.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
                "wo {wo}: E[1/pdf] covers {covered} sr"
            );
            for (k, u) in stratified_2d(32).enumerate() {
                let Some(s) = b.sample_f(wo, (k as f32 * 0.618).fract(), u, mode, flags) else { continue };
                assert!(same_hemisphere(wo, s.wi), "reflection only");
                // Within 0.1 rad of the mirror direction θm comes from acos of a number near
                // 1, whose rounding the singular density magnifies (as in pbrt-v4).
                let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
                if s.wi.dot(mirror) > 0.1f32.cos() {
                    continue;
                }
                let (f, pdf) = (b.f(wo, s.wi, mode), b.pdf(wo, s.wi, mode, flags));
                assert!((s.pdf - pdf).abs() <= 2e-3 * s.pdf + 1e-6, "wo {wo}: sample pdf {} vs pdf() {pdf}", s.pdf);
                assert!((s.f - f).abs().max_element() <= 2e-3 * s.f.max_element() + 1e-6, "wo {wo}: {} vs {f}", s.f);
            }
            // Nothing is transmitted.
            assert_eq!(b.f(wo, Vec3::new(wo.x, wo.y, -wo.z), mode), Vec3::ZERO);
        }
        assert!(b.sample_f(Vec3::Z, 0.5, Vec2::splat(0.5), mode, ReflTransFlags::TRANSMISSION).is_none());
    }
}
