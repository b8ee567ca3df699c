//! Dielectric interfaces: specular or rough (Trowbridge-Reitz) reflection and transmission
//! at a real index of refraction (pbrt-v4 §9.5 and §9.7, `DielectricBxDF`).

use glam::{Vec2, Vec3};

use super::fresnel::fr_dielectric;
use super::microfacet::{TrowbridgeReitz, face_forward};
use super::{BsdfSample, BxdfFlags, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::math::{abs_cos_theta, cos_theta, reflect, refract, same_hemisphere, sqr};

/// An interface with relative index of refraction η = η_inside/η_outside, where the inside
/// is the −z side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricBxdf {
    eta: f32,
    distrib: TrowbridgeReitz,
}

/// The generalized half vector of (wo, wi), facing +z, and the relative η along the path
/// (1 for reflection), or `None` for degenerate or back-facing configurations (pbrt-v4
/// §9.7 and Walter et al. 2007, "Microfacet Models for Refraction through Rough Surfaces";
/// with the back-facing test of `DielectricBxDF::f`).
#[inline]
fn generalized_half_vector(eta: f32, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32, bool)> {
    let (cos_o, cos_i) = (cos_theta(wo), cos_theta(wi));
    let reflect = cos_i * cos_o > 0.0;
    let etap = if reflect {
        1.0
    } else if cos_o > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let wm = wi * etap + wo;
    if cos_i == 0.0 || cos_o == 0.0 || wm.length_squared() == 0.0 {
        return None;
    }
    let wm = face_forward(wm.normalize(), Vec3::Z);
    // Discard back-facing microfacets.
    if wm.dot(wi) * cos_i < 0.0 || wm.dot(wo) * cos_o < 0.0 {
        return None;
    }
    Some((wm, etap, reflect))
}

impl DielectricBxdf {
    /// An interface with index ratio `eta` and roughness `distrib`. pbrt-v4 replaces η = 0
    /// by 1 before creating it.
    pub fn new(eta: f32, distrib: TrowbridgeReitz) -> DielectricBxdf {
        DielectricBxdf { eta, distrib }
    }

    /// η = η_inside/η_outside.
    pub fn eta(&self) -> f32 {
        self.eta
    }

    /// The microfacet distribution.
    pub fn distribution(&self) -> &TrowbridgeReitz {
        &self.distrib
    }

    /// True when the interface is a perfect specular one (or index-matched, η = 1).
    #[inline]
    fn is_specular(&self) -> bool {
        self.eta == 1.0 || self.distrib.effectively_smooth()
    }

    /// Microfacet reflection and transmission (pbrt-v4 §9.7, Walter et al. 2007); zero when
    /// specular. Transmitted radiance is scaled by 1/η'² in radiance mode.
    pub fn f<C: Channels>(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        if self.is_specular() {
            return C::ZERO;
        }
        let Some((wm, etap, reflect)) = generalized_half_vector(self.eta, wo, wi) else {
            return C::ZERO;
        };
        let (cos_o, cos_i) = (cos_theta(wo), cos_theta(wi));
        let fresnel = fr_dielectric(wo.dot(wm), self.eta);
        let d = &self.distrib;
        if reflect {
            C::splat(d.d(wm) * d.g(wo, wi) * fresnel / (4.0 * cos_i * cos_o).abs())
        } else {
            let denom = sqr(wi.dot(wm) + wo.dot(wm) / etap) * cos_i * cos_o;
            let mut ft = d.d(wm) * (1.0 - fresnel) * d.g(wo, wi) * (wi.dot(wm) * wo.dot(wm) / denom).abs();
            if mode == TransportMode::Radiance {
                ft /= sqr(etap);
            }
            C::splat(ft)
        }
    }

    /// Chooses reflection or transmission with probability proportional to the Fresnel
    /// reflectance (of the macro surface when specular, of a visible microfacet when rough).
    pub fn sample_f<C: Channels>(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        if self.is_specular() {
            self.sample_specular(wo, uc, mode, sample_flags)
        } else {
            self.sample_rough(wo, uc, u, mode, sample_flags)
        }
    }

    /// Reflection and transmission probabilities for Fresnel reflectance `r`, restricted to
    /// `sample_flags`; `None` when neither may be sampled.
    #[inline]
    fn lobe_probabilities(r: f32, sample_flags: ReflTransFlags) -> Option<(f32, f32)> {
        let pr = if sample_flags.reflection() { r } else { 0.0 };
        let pt = if sample_flags.transmission() { 1.0 - r } else { 0.0 };
        if pr == 0.0 && pt == 0.0 { None } else { Some((pr, pt)) }
    }

    /// Perfect specular reflection or refraction (pbrt-v4 §9.5).
    fn sample_specular<C: Channels>(
        &self,
        wo: Vec3,
        uc: f32,
        mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        let r = fr_dielectric(cos_theta(wo), self.eta);
        let t = 1.0 - r;
        let (pr, pt) = Self::lobe_probabilities(r, sample_flags)?;
        if uc < pr / (pr + pt) {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let f = C::splat(r / abs_cos_theta(wi));
            Some(BsdfSample::new(f, wi, pr / (pr + pt), BxdfFlags::SPECULAR_REFLECTION))
        } else {
            let (wi, etap) = refract(wo, Vec3::Z, self.eta)?;
            let mut ft = t / abs_cos_theta(wi);
            // Radiance is compressed into a smaller solid angle when entering a denser medium.
            if mode == TransportMode::Radiance {
                ft /= sqr(etap);
            }
            Some(BsdfSample::with_eta(C::splat(ft), wi, pt / (pr + pt), BxdfFlags::SPECULAR_TRANSMISSION, etap))
        }
    }

    /// Rough reflection or transmission through a visible microfacet (pbrt-v4 §9.7).
    fn sample_rough<C: Channels>(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        let d = &self.distrib;
        let wm = d.sample_wm(wo, u);
        let r = fr_dielectric(wo.dot(wm), self.eta);
        let t = 1.0 - r;
        let (pr, pt) = Self::lobe_probabilities(r, sample_flags)?;
        if uc < pr / (pr + pt) {
            let wi = reflect(wo, wm);
            if !same_hemisphere(wo, wi) {
                return None;
            }
            let pdf = d.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt);
            let f = d.d(wm) * d.g(wo, wi) * r / (4.0 * cos_theta(wi) * cos_theta(wo));
            Some(BsdfSample::new(C::splat(f), wi, pdf, BxdfFlags::GLOSSY_REFLECTION))
        } else {
            let (wi, etap) = refract(wo, wm, self.eta)?;
            if same_hemisphere(wo, wi) || wi.z == 0.0 {
                return None;
            }
            // dωm/dωi for refraction through ωm (pbrt-v4 §9.7; Walter et al. 2007).
            let denom = sqr(wi.dot(wm) + wo.dot(wm) / etap);
            let dwm_dwi = wi.dot(wm).abs() / denom;
            let pdf = d.pdf(wo, wm) * dwm_dwi * pt / (pr + pt);
            let mut ft =
                t * d.d(wm) * d.g(wo, wi) * (wi.dot(wm) * wo.dot(wm) / (cos_theta(wi) * cos_theta(wo) * denom)).abs();
            if mode == TransportMode::Radiance {
                ft /= sqr(etap);
            }
            Some(BsdfSample::with_eta(C::splat(ft), wi, pdf, BxdfFlags::GLOSSY_TRANSMISSION, etap))
        }
    }

    /// Density of [`DielectricBxdf::sample_f`]; zero when specular.
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode, sample_flags: ReflTransFlags) -> f32 {
        if self.is_specular() {
            return 0.0;
        }
        let Some((wm, etap, reflect)) = generalized_half_vector(self.eta, wo, wi) else {
            return 0.0;
        };
        let r = fr_dielectric(wo.dot(wm), self.eta);
        let Some((pr, pt)) = Self::lobe_probabilities(r, sample_flags) else {
            return 0.0;
        };
        let d = &self.distrib;
        if reflect {
            d.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt)
        } else {
            let denom = sqr(wi.dot(wm) + wo.dot(wm) / etap);
            let dwm_dwi = wi.dot(wm).abs() / denom;
            d.pdf(wo, wm) * dwm_dwi * pt / (pr + pt)
        }
    }

    /// Reflection (unless η = 1) and transmission, specular or glossy.
    pub fn flags(&self) -> BxdfFlags {
        let lobes =
            if self.eta == 1.0 { BxdfFlags::TRANSMISSION } else { BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION };
        lobes | if self.distrib.effectively_smooth() { BxdfFlags::SPECULAR } else { BxdfFlags::GLOSSY }
    }

    /// Roughens the distribution (pbrt-v4's `Regularize`).
    pub fn regularize(&mut self) {
        self.distrib.regularize();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::Bxdf;
    use crate::materials::bxdf::testing::{self, Check, test_directions};

    fn rough_dielectrics() -> Vec<Bxdf> {
        vec![
            DielectricBxdf::new(1.5, TrowbridgeReitz::new(0.3, 0.3)).into(),
            DielectricBxdf::new(1.5, TrowbridgeReitz::new(0.12, 0.12)).into(),
            DielectricBxdf::new(1.0 / 1.33, TrowbridgeReitz::new(0.4, 0.4)).into(),
            DielectricBxdf::new(2.2, TrowbridgeReitz::new(0.1, 0.5)).into(),
        ]
    }

    #[test]
    fn rough_dielectric_common_checks() {
        for b in rough_dielectrics() {
            for wo in test_directions() {
                for mode in [TransportMode::Radiance, TransportMode::Importance] {
                    testing::check_all(&b, wo, Check { mode, ..Check::default() });
                }
            }
        }
    }

    #[test]
    fn rough_dielectric_common_checks_for_one_lobe() {
        for b in rough_dielectrics() {
            for wo in test_directions() {
                for flags in [ReflTransFlags::REFLECTION, ReflTransFlags::TRANSMISSION] {
                    testing::check_all(&b, wo, Check { flags, ..Check::default() });
                }
            }
        }
    }

    #[test]
    fn rough_dielectric_chi2() {
        for (i, b) in rough_dielectrics().iter().enumerate() {
            for (j, wo) in test_directions().into_iter().enumerate().skip(1) {
                testing::chi2_test(b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 200_000, (10 * i + j) as u64)
                    .unwrap_or_else(|e| panic!("{b:?}: {e}"));
            }
        }
    }

    #[test]
    fn rough_dielectric_chi2_one_lobe() {
        let b = &rough_dielectrics()[0];
        let wo = Vec3::new(-0.7, 0.5, 0.3).normalize();
        for (k, flags) in [ReflTransFlags::REFLECTION, ReflTransFlags::TRANSMISSION].into_iter().enumerate() {
            testing::chi2_test(b, wo, TransportMode::Importance, flags, 200_000, 100 + k as u64).unwrap();
            testing::chi2_test(b, -wo, TransportMode::Importance, flags, 200_000, 200 + k as u64).unwrap();
        }
    }

    #[test]
    fn smooth_dielectric_conserves_energy() {
        // (d) R + T = 1: every sample's weight is 1 once the 1/η'² radiance scaling is undone.
        for eta in [1.5f32, 1.0 / 1.5] {
            let b = Bxdf::from(DielectricBxdf::new(eta, TrowbridgeReitz::new(0.0, 0.0)));
            assert_eq!(b.flags(), BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION | BxdfFlags::SPECULAR);
            for wo in test_directions() {
                let s = testing::sample_statistics(&b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 64);
                assert_eq!(s.p_any, 1.0);
                assert!((s.energy - glam::DVec3::ONE).abs().max_element() < 1e-5, "{wo}: {:?}", s.energy);
                let s = testing::sample_statistics(&b, wo, TransportMode::Importance, ReflTransFlags::ALL, 64);
                assert!((s.albedo - glam::DVec3::ONE).abs().max_element() < 1e-5, "{wo}: {:?}", s.albedo);
                testing::check_all(&b, wo, Check::default());
            }
        }
    }

    #[test]
    fn smooth_dielectric_samples() {
        let b = DielectricBxdf::new(1.5, TrowbridgeReitz::new(0.0, 0.0));
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let r = fr_dielectric(0.8, 1.5);
        let refl =
            b.sample_f::<crate::color::Rgb>(wo, 0.0, Vec2::ZERO, TransportMode::Radiance, ReflTransFlags::ALL).unwrap();
        assert_eq!(refl.wi, Vec3::new(-0.6, 0.0, 0.8));
        assert!((refl.pdf - r).abs() < 1e-6 && refl.flags == BxdfFlags::SPECULAR_REFLECTION);
        let tr = b
            .sample_f::<crate::color::Rgb>(wo, 0.99, Vec2::ZERO, TransportMode::Radiance, ReflTransFlags::ALL)
            .unwrap();
        // Snell: sin θt = 0.6/1.5 = 0.4.
        assert!((tr.wi - Vec3::new(-0.4, 0.0, -(1.0f32 - 0.16).sqrt())).length() < 1e-6);
        assert_eq!((tr.eta, tr.flags), (1.5, BxdfFlags::SPECULAR_TRANSMISSION));
        assert!((tr.f.x * tr.wi.z.abs() * 2.25 - (1.0 - r)).abs() < 1e-6);
        let imp = b
            .sample_f::<crate::color::Rgb>(wo, 0.99, Vec2::ZERO, TransportMode::Importance, ReflTransFlags::ALL)
            .unwrap();
        assert!((imp.f.x * imp.wi.z.abs() - (1.0 - r)).abs() < 1e-6);
        // Only transmission requested: always transmits, with probability 1.
        let t = b
            .sample_f::<crate::color::Rgb>(wo, 0.0, Vec2::ZERO, TransportMode::Radiance, ReflTransFlags::TRANSMISSION)
            .unwrap();
        assert!(t.is_transmission() && t.pdf == 1.0);
        // Total internal reflection from inside beyond the critical angle.
        let inside = Vec3::new(0.9, 0.0, -(1.0f32 - 0.81).sqrt());
        let s = b
            .sample_f::<crate::color::Rgb>(inside, 0.999, Vec2::ZERO, TransportMode::Radiance, ReflTransFlags::ALL)
            .unwrap();
        assert!(s.is_reflection() && s.pdf == 1.0);
        assert!(
            b.sample_f::<crate::color::Rgb>(
                inside,
                0.5,
                Vec2::ZERO,
                TransportMode::Radiance,
                ReflTransFlags::TRANSMISSION
            )
            .is_none()
        );
        // Exiting: η' = 1/1.5 and radiance grows by 2.25.
        let out = b
            .sample_f::<crate::color::Rgb>(
                Vec3::new(0.3, 0.0, -(0.91f32).sqrt()),
                0.999,
                Vec2::ZERO,
                TransportMode::Radiance,
                ReflTransFlags::ALL,
            )
            .unwrap();
        assert!(out.is_transmission() && (out.eta - 1.0 / 1.5).abs() < 1e-6);
    }

    #[test]
    fn index_matched_dielectric_passes_light_through() {
        for alpha in [0.0f32, 0.3] {
            let b: Bxdf = Bxdf::from(DielectricBxdf::new(1.0, TrowbridgeReitz::new(alpha, alpha)));
            assert!(b.flags().is_transmissive() && !b.flags().is_reflective());
            for wo in test_directions() {
                let s = b.sample_f(wo, 0.2, Vec2::new(0.3, 0.7), TransportMode::Radiance, ReflTransFlags::ALL).unwrap();
                assert!((s.wi + wo).length() < 1e-6, "{} vs {}", s.wi, -wo);
                assert!(s.is_specular() && s.is_transmission() && s.pdf == 1.0 && s.eta == 1.0);
                assert!((s.f.x * wo.z.abs() - 1.0).abs() < 1e-6);
                assert_eq!(b.f(wo, -wo, TransportMode::Radiance), crate::color::Rgb::ZERO);
                assert_eq!(b.pdf(wo, -wo, TransportMode::Radiance, ReflTransFlags::ALL), 0.0);
                // Reflection only: the Fresnel term is zero up to rounding (pbrt-v4 computes it
                // the same way), so at most a negligible reflection is sampled.
                let r = b.sample_f(wo, 0.2, Vec2::ZERO, TransportMode::Radiance, ReflTransFlags::REFLECTION);
                assert!(r.is_none_or(|r| r.f.x * wo.z.abs() < 1e-6), "{r:?}");
            }
        }
    }

    #[test]
    fn rough_dielectric_energy_is_close_to_one_when_fairly_smooth() {
        // Single-scattering microfacet models lose a little energy; at α = 0.12 and normal
        // incidence the loss is small.
        let b = &rough_dielectrics()[1];
        let s = testing::sample_statistics(b, Vec3::Z, TransportMode::Importance, ReflTransFlags::ALL, 256);
        assert!(s.energy.x > 0.97 && s.energy.x <= 1.0 + 1e-6, "{:?}", s.energy);
    }
}
