//! Lambertian reflection (pbrt-v4 §9.2, `DiffuseBxDF`).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::{BsdfSample, BxdfFlags, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::color::Rgb;
use crate::math::{abs_cos_theta, same_hemisphere};
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};

/// Lambertian reflection with albedo `r`: f = R/π on both sides of the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseBxdf<C = Rgb> {
    r: C,
}

impl<C: Channels> DiffuseBxdf<C> {
    /// A diffuse reflector with albedo `r` (pbrt-v4 clamps material reflectances to [0, 1]
    /// before creating it).
    pub fn new(r: C) -> DiffuseBxdf<C> {
        DiffuseBxdf { r }
    }

    /// The albedo.
    pub fn reflectance(&self) -> C {
        self.r
    }

    /// f(wo, wi) = R/π in the same hemisphere, else 0.
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if !same_hemisphere(wo, wi) {
            return C::ZERO;
        }
        self.r * FRAC_1_PI
    }

    /// Cosine-weighted sampling of the hemisphere of `wo`.
    #[inline]
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
        let mut wi = cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf = cosine_hemisphere_pdf(abs_cos_theta(wi));
        Some(BsdfSample::new(self.r * FRAC_1_PI, wi, pdf, BxdfFlags::DIFFUSE_REFLECTION))
    }

    /// Density of [`DiffuseBxdf::sample_f`]: |cos θi|/π in the hemisphere of `wo`.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode, sample_flags: ReflTransFlags) -> f32 {
        if !sample_flags.reflection() || !same_hemisphere(wo, wi) {
            return 0.0;
        }
        cosine_hemisphere_pdf(abs_cos_theta(wi))
    }

    /// Diffuse reflection, or nothing when R = 0.
    #[inline]
    pub fn flags(&self) -> BxdfFlags {
        if !self.r.is_zero() { BxdfFlags::DIFFUSE_REFLECTION } else { BxdfFlags::UNSET }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::Bxdf;
    use crate::materials::bxdf::testing::{self, Check, test_directions};

    #[test]
    fn diffuse_passes_the_common_checks() {
        let b = Bxdf::from(DiffuseBxdf::new(Rgb::new(0.2, 0.5, 0.9)));
        for wo in test_directions() {
            testing::check_all(&b, wo, Check::default());
        }
        testing::check_ignores_uc(&b);
    }

    #[test]
    fn white_diffuse_has_unit_albedo_and_the_cosine_density() {
        let b = Bxdf::from(DiffuseBxdf::new(Rgb::ONE));
        for wo in test_directions() {
            let s = testing::sample_statistics(&b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 256);
            assert!((s.albedo - glam::DVec3::ONE).abs().max_element() < 1e-6, "{wo}: {:?}", s.albedo);
            testing::chi2_test(&b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 200_000, 1).unwrap();
        }
        assert_eq!(b.flags(), BxdfFlags::DIFFUSE_REFLECTION);
        assert_eq!(Bxdf::from(DiffuseBxdf::new(Rgb::ZERO)).flags(), BxdfFlags::UNSET);
        let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
        assert!(b.sample_f(wo, 0.5, Vec2::splat(0.5), TransportMode::Radiance, ReflTransFlags::TRANSMISSION).is_none());
        assert_eq!(b.pdf(wo, Vec3::Z, TransportMode::Radiance, ReflTransFlags::TRANSMISSION), 0.0);
        assert_eq!(b.f(wo, -Vec3::Z, TransportMode::Radiance), Rgb::ZERO);
    }
}
