//! Lambertian reflection and transmission (pbrt-v4's `DiffuseTransmissionBxDF`).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::{BsdfSample, BxdfFlags, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::color::Rgb;
use crate::math::{abs_cos_theta, same_hemisphere};
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};

/// f = R/π on the side of `wo`, T/π on the other.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseTransmissionBxdf<C = Rgb> {
    r: C,
    t: C,
}

impl<C: Channels> DiffuseTransmissionBxdf<C> {
    /// Reflectance `r` and transmittance `t` (pbrt-v4 clamps both to [0, 1] first).
    pub fn new(r: C, t: C) -> DiffuseTransmissionBxdf<C> {
        DiffuseTransmissionBxdf { r, t }
    }

    /// The probabilities of sampling reflection and transmission: pbrt-v4 weighs the two
    /// lobes by their largest channel.
    #[inline]
    fn lobe_weights(&self, sample_flags: ReflTransFlags) -> (f32, f32) {
        let pr = if sample_flags.reflection() { self.r.max_element() } else { 0.0 };
        let pt = if sample_flags.transmission() { self.t.max_element() } else { 0.0 };
        (pr, pt)
    }

    /// R/π for `wi` on `wo`'s side, else T/π.
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if same_hemisphere(wo, wi) { self.r * FRAC_1_PI } else { self.t * FRAC_1_PI }
    }

    /// Chooses a lobe with probability proportional to its weight, then samples the cosine
    /// on that side.
    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        let (pr, pt) = self.lobe_weights(sample_flags);
        if pr == 0.0 && pt == 0.0 {
            return None;
        }
        let mut wi = cosine_hemisphere(u);
        let reflect = uc < pr / (pr + pt);
        // Reflection stays on wo's side, transmission goes to the other.
        if (wo.z < 0.0) == reflect {
            wi.z = -wi.z;
        }
        let (share, flags) = if reflect {
            (pr / (pr + pt), BxdfFlags::DIFFUSE_REFLECTION)
        } else {
            (pt / (pr + pt), BxdfFlags::DIFFUSE_TRANSMISSION)
        };
        let pdf = cosine_hemisphere_pdf(abs_cos_theta(wi)) * share;
        Some(BsdfSample::new(self.f(wo, wi, mode), wi, pdf, flags))
    }

    /// Density of [`DiffuseTransmissionBxdf::sample_f`].
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode, sample_flags: ReflTransFlags) -> f32 {
        let (pr, pt) = self.lobe_weights(sample_flags);
        if pr == 0.0 && pt == 0.0 {
            return 0.0;
        }
        let share = if same_hemisphere(wo, wi) { pr } else { pt } / (pr + pt);
        cosine_hemisphere_pdf(abs_cos_theta(wi)) * share
    }

    /// Diffuse reflection if R ≠ 0, diffuse transmission if T ≠ 0.
    #[inline]
    pub fn flags(&self) -> BxdfFlags {
        let mut flags = BxdfFlags::UNSET;
        if !self.r.is_zero() {
            flags |= BxdfFlags::DIFFUSE_REFLECTION;
        }
        if !self.t.is_zero() {
            flags |= BxdfFlags::DIFFUSE_TRANSMISSION;
        }
        flags
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::Bxdf;
    use crate::materials::bxdf::testing::{self, Check, test_directions};

    #[test]
    fn diffuse_transmission_passes_the_common_checks() {
        for (r, t) in [(Rgb::new(0.2, 0.5, 0.9), Rgb::new(0.6, 0.3, 0.05)), (Rgb::splat(0.25), Rgb::splat(0.25))] {
            let b = Bxdf::from(DiffuseTransmissionBxdf::new(r, t));
            // pbrt-v4 picks the lobe by its largest channel, so a sample's weight is
            // R·(pr + pt)/pr in the channels below that maximum: up to 1.5 here.
            let bound = f64::from((r / (r.max_element() / (r.max_element() + t.max_element()))).max_element());
            let bound =
                bound.max(f64::from((t / (t.max_element() / (r.max_element() + t.max_element()))).max_element()));
            for wo in test_directions() {
                testing::check_all(&b, wo, Check { max_weight: bound, ..Check::default() });
            }
        }
    }

    #[test]
    fn albedo_is_r_plus_t_and_lobes_sample_their_side() {
        let (r, t) = (Rgb::new(0.2, 0.5, 0.3), Rgb::new(0.6, 0.3, 0.1));
        let b = Bxdf::from(DiffuseTransmissionBxdf::new(r, t));
        for wo in test_directions() {
            let s = testing::sample_statistics(&b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 256);
            let expected = glam::DVec3::new(0.8, 0.8, 0.4);
            assert!((s.albedo - expected).abs().max_element() < 2e-3, "{wo}: {:?}", s.albedo);
            testing::chi2_test(&b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 200_000, 1).unwrap();
            // Only one lobe asked for: only its side, with all of the probability.
            for (flags, same_side) in [(ReflTransFlags::REFLECTION, true), (ReflTransFlags::TRANSMISSION, false)] {
                let s = b.sample_f(wo, 0.3, Vec2::new(0.4, 0.7), TransportMode::Radiance, flags).unwrap();
                assert_eq!(same_hemisphere(wo, s.wi), same_side);
                let full = cosine_hemisphere_pdf(abs_cos_theta(s.wi));
                assert!((s.pdf - full).abs() < 1e-6 * full);
            }
        }
        assert_eq!(b.flags(), BxdfFlags::DIFFUSE_REFLECTION | BxdfFlags::DIFFUSE_TRANSMISSION);
        let only_t = Bxdf::from(DiffuseTransmissionBxdf::new(Rgb::ZERO, t));
        assert_eq!(only_t.flags(), BxdfFlags::DIFFUSE_TRANSMISSION);
        assert!(
            only_t
                .sample_f(Vec3::Z, 0.5, Vec2::splat(0.5), TransportMode::Radiance, ReflTransFlags::REFLECTION)
                .is_none()
        );
    }
}
