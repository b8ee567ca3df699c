//! Metals: perfect specular or Torrance-Sparrow microfacet reflection with the conductor
//! Fresnel term (pbrt-v4 §9.4 and §9.6, `ConductorBxDF`).

use glam::{Vec2, Vec3};

use super::fresnel::fr_complex_channels;
use super::microfacet::{TrowbridgeReitz, face_forward};
use super::{BsdfSample, BxdfFlags, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::color::Rgb;
use crate::math::{abs_cos_theta, reflect, same_hemisphere};

/// A conductor with complex index of refraction η + i·k per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorBxdf<C = Rgb> {
    distrib: TrowbridgeReitz,
    eta: C,
    k: C,
    /// Per-channel factor on the Fresnel term: 1 except where an RGB fit of spectral optical
    /// constants needs it (a projected reflectance above 1, e.g. gold's red channel in sRGB).
    fresnel_scale: C,
}

impl<C: Channels> ConductorBxdf<C> {
    /// A conductor with the given microfacet distribution and optical constants.
    pub fn new(distrib: TrowbridgeReitz, eta: C, k: C) -> ConductorBxdf<C> {
        ConductorBxdf { distrib, eta, k, fresnel_scale: C::ONE }
    }

    /// The same conductor with its Fresnel reflectance multiplied by `scale` per channel
    /// (see [`crate::spectra::ConductorFit`]).
    pub fn with_fresnel_scale(mut self, scale: C) -> ConductorBxdf<C> {
        self.fresnel_scale = scale;
        self
    }

    /// A conductor specified by its normal-incidence reflectance `r`, as pbrt-v4's
    /// `ConductorMaterial` does without `eta`/`k`: r is clamped to [0, 0.9999], η = 1 and
    /// k = 2√r / √(1 − r), which reflects exactly r at normal incidence.
    pub fn from_reflectance(distrib: TrowbridgeReitz, r: C) -> ConductorBxdf<C> {
        let r = r.clamp(0.0, 0.9999);
        let k = r.map(|r| 2.0 * r.sqrt() / (1.0 - r).max(0.0).sqrt());
        ConductorBxdf::new(distrib, C::ONE, k)
    }

    /// The same conductor under a dielectric of index `eta_outside` instead of vacuum: η and
    /// k relative to it (pbrt-v4's `CoatedConductorMaterial` divides both by the coating's η).
    pub fn relative_to(mut self, eta_outside: f32) -> ConductorBxdf<C> {
        self.eta *= 1.0 / eta_outside;
        self.k *= 1.0 / eta_outside;
        self
    }

    /// The distribution, η and k (without the Fresnel scale).
    pub fn constants(&self) -> (TrowbridgeReitz, C, C) {
        (self.distrib, self.eta, self.k)
    }

    /// The microfacet distribution.
    pub fn distribution(&self) -> &TrowbridgeReitz {
        &self.distrib
    }

    /// The Torrance-Sparrow BRDF D(ωm) F(ωo·ωm) G(ωo, ωi) / (4 |cos θo| |cos θi|)
    /// (pbrt-v4 §9.6, Torrance-Sparrow model); zero when smooth.
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if !same_hemisphere(wo, wi) || self.distrib.effectively_smooth() {
            return C::ZERO;
        }
        let (cos_o, cos_i) = (abs_cos_theta(wo), abs_cos_theta(wi));
        if cos_i == 0.0 || cos_o == 0.0 {
            return C::ZERO;
        }
        let wm = wi + wo;
        if wm.length_squared() == 0.0 {
            return C::ZERO;
        }
        let wm = wm.normalize();
        let fresnel = fr_complex_channels(wo.dot(wm).abs(), self.eta, self.k) * self.fresnel_scale;
        fresnel * (self.distrib.d(wm) * self.distrib.g(wo, wi) / (4.0 * cos_i * cos_o))
    }

    /// Mirror reflection when smooth, else visible-normal sampling of the microfacets and
    /// mirror reflection about the sampled normal.
    pub fn sample_f(
        &self,
        wo: Vec3,
        _uc: f32,
        u: Vec2,
        _mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        if !sample_flags.reflection() {
            return None;
        }
        if self.distrib.effectively_smooth() {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let cos_i = abs_cos_theta(wi);
            let f = fr_complex_channels(cos_i, self.eta, self.k) * self.fresnel_scale / cos_i;
            return Some(BsdfSample::new(f, wi, 1.0, BxdfFlags::SPECULAR_REFLECTION));
        }
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.distrib.sample_wm(wo, u);
        let wi = reflect(wo, wm);
        if !same_hemisphere(wo, wi) {
            return None;
        }
        // Change of variables from ωm to ωi for mirror reflection: dωm/dωi = 1/(4 |ωo·ωm|)
        // (pbrt-v4 §9.6, Torrance-Sparrow sampling).
        let pdf = self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
        let (cos_o, cos_i) = (abs_cos_theta(wo), abs_cos_theta(wi));
        if cos_i == 0.0 || cos_o == 0.0 {
            return None;
        }
        let fresnel = fr_complex_channels(wo.dot(wm).abs(), self.eta, self.k) * self.fresnel_scale;
        let f = fresnel * (self.distrib.d(wm) * self.distrib.g(wo, wi) / (4.0 * cos_i * cos_o));
        Some(BsdfSample::new(f, wi, pdf, BxdfFlags::GLOSSY_REFLECTION))
    }

    /// Density of [`ConductorBxdf::sample_f`]; zero when smooth.
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode, sample_flags: ReflTransFlags) -> f32 {
        if !sample_flags.reflection() || !same_hemisphere(wo, wi) || self.distrib.effectively_smooth() {
            return 0.0;
        }
        let wm = wo + wi;
        if wm.length_squared() == 0.0 {
            return 0.0;
        }
        let wm = face_forward(wm.normalize(), Vec3::Z);
        self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
    }

    /// Specular or glossy reflection.
    pub fn flags(&self) -> BxdfFlags {
        if self.distrib.effectively_smooth() { BxdfFlags::SPECULAR_REFLECTION } else { BxdfFlags::GLOSSY_REFLECTION }
    }

    /// Roughens the distribution (pbrt-v4's `Regularize`).
    pub fn regularize(&mut self) {
        self.distrib.regularize();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::testing::{self, Check, test_directions};
    use crate::materials::bxdf::{Bxdf, DielectricBxdf, fr_dielectric};

    // Copper-like optical constants (R, G, B).
    fn copper() -> (Rgb, Rgb) {
        (Rgb::new(0.2, 0.92, 1.1), Rgb::new(3.9, 2.45, 2.14))
    }

    fn rough_conductors() -> Vec<Bxdf> {
        let (eta, k) = copper();
        vec![
            ConductorBxdf::new(TrowbridgeReitz::new(0.3, 0.3), eta, k).into(),
            ConductorBxdf::new(TrowbridgeReitz::new(0.12, 0.12), eta, k).into(),
            ConductorBxdf::new(TrowbridgeReitz::new(0.7, 0.7), eta, k).into(),
            ConductorBxdf::new(TrowbridgeReitz::new(0.1, 0.45), eta, k).into(),
        ]
    }

    #[test]
    fn rough_conductor_common_checks() {
        for b in rough_conductors() {
            for wo in test_directions() {
                let s = testing::check_all(&b, wo, Check::default());
                assert!(s.p_any > 0.5, "most samples succeed: {}", s.p_any);
            }
        }
    }

    #[test]
    fn rough_conductor_chi2() {
        for (i, b) in rough_conductors().iter().enumerate() {
            for (j, wo) in test_directions().into_iter().enumerate().skip(1).step_by(2) {
                testing::chi2_test(b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 200_000, (10 * i + j) as u64)
                    .unwrap_or_else(|e| panic!("{b:?}: {e}"));
            }
        }
    }

    #[test]
    fn smooth_conductor_reflects_the_fresnel_term() {
        let (eta, k) = copper();
        let b = Bxdf::from(ConductorBxdf::new(TrowbridgeReitz::new(0.0, 0.0), eta, k));
        assert_eq!(b.flags(), BxdfFlags::SPECULAR_REFLECTION);
        for wo in test_directions() {
            let s = b.sample_f(wo, 0.3, Vec2::new(0.2, 0.9), TransportMode::Radiance, ReflTransFlags::ALL).unwrap();
            assert_eq!(s.wi, Vec3::new(-wo.x, -wo.y, wo.z));
            assert_eq!((s.pdf, s.flags), (1.0, BxdfFlags::SPECULAR_REFLECTION));
            let albedo = s.f * s.wi.z.abs() / s.pdf;
            let expected = fr_complex_channels(wo.z.abs(), eta, k);
            assert!((albedo - expected).abs().max_element() < 1e-6);
            testing::check_all(&b, wo, Check::default());
        }
        let wo = Vec3::new(0.1, 0.2, 0.9).normalize();
        assert!(b.sample_f(wo, 0.3, Vec2::splat(0.5), TransportMode::Radiance, ReflTransFlags::TRANSMISSION).is_none());
    }

    #[test]
    fn conductor_with_zero_k_is_a_dielectric_reflector() {
        // (f) Smooth: the mirror sample carries fr_dielectric. Rough: f equals the rough
        // dielectric's reflection lobe for directions above the surface.
        for eta in [1.5f32, 1.33, 2.4] {
            let smooth = ConductorBxdf::new(TrowbridgeReitz::new(0.0, 0.0), Rgb::splat(eta), Rgb::ZERO);
            let rough = ConductorBxdf::new(TrowbridgeReitz::new(0.25, 0.4), Rgb::splat(eta), Rgb::ZERO);
            let glass = DielectricBxdf::new(eta, TrowbridgeReitz::new(0.25, 0.4));
            for wo in test_directions().into_iter().filter(|w| w.z > 0.0) {
                let s =
                    smooth.sample_f(wo, 0.5, Vec2::splat(0.5), TransportMode::Radiance, ReflTransFlags::ALL).unwrap();
                let r = s.f * s.wi.z;
                assert!((r - Rgb::splat(fr_dielectric(wo.z, eta))).abs().max_element() < 2e-5);
                testing::integrate_sphere(16, 32, |wi| {
                    if wi.z > 0.0 {
                        let a = rough.f(wo, wi, TransportMode::Radiance);
                        let b = glass.f::<Rgb>(wo, wi, TransportMode::Radiance);
                        assert!((a - b).abs().max_element() <= 1e-4 * b.x + 1e-7, "{a} vs {b}");
                    }
                    0.0
                });
            }
        }
    }

    #[test]
    fn reflectance_parameterization_reflects_r_at_normal_incidence() {
        let r = Rgb::new(0.9, 0.5, 0.05);
        let b = ConductorBxdf::from_reflectance(TrowbridgeReitz::new(0.0, 0.0), r);
        let s = b.sample_f(Vec3::Z, 0.5, Vec2::splat(0.5), TransportMode::Radiance, ReflTransFlags::ALL).unwrap();
        assert!((s.f - r).abs().max_element() < 1e-5, "{}", s.f);
    }

    #[test]
    fn regularize_roughens_a_mirror() {
        let (eta, k) = copper();
        let mut b = Bxdf::from(ConductorBxdf::new(TrowbridgeReitz::new(0.0, 0.0), eta, k));
        b.regularize();
        assert_eq!(b.flags(), BxdfFlags::GLOSSY_REFLECTION);
        let Bxdf::Conductor(c) = &b else { unreachable!() };
        assert_eq!(c.distribution().alpha_x(), 0.1);
        testing::check_all(&b, Vec3::new(0.3, 0.4, 0.85).normalize(), Check::default());
        testing::check_ignores_uc(&b);
        testing::check_ignores_uc(&Bxdf::from(ConductorBxdf::new(TrowbridgeReitz::new(0.0, 0.0), eta, k)));
    }
}
