//! A thin dielectric slab with parallel faces, such as a window pane: specular reflection and
//! straight-through transmission, summed over all internal reflections (pbrt-v4 §9.5,
//! `ThinDielectricBxDF`).

use glam::{Vec2, Vec3};

use super::fresnel::fr_dielectric;
use super::{BsdfSample, BxdfFlags, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::math::{abs_cos_theta, sqr};

/// A thin slab with index of refraction η relative to its surroundings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectricBxdf {
    eta: f32,
}

impl ThinDielectricBxdf {
    /// A slab with index ratio `eta`.
    pub fn new(eta: f32) -> ThinDielectricBxdf {
        ThinDielectricBxdf { eta }
    }

    /// η of the slab.
    pub fn eta(&self) -> f32 {
        self.eta
    }

    /// Always zero: both lobes are Dirac deltas.
    pub fn f<C: Channels>(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> C {
        C::ZERO
    }

    /// Mirror reflection or pass-through, chosen in proportion to the slab's total reflectance
    /// R' = R + T²R/(1 − R²) (the geometric series of the internal reflections).
    pub fn sample_f<C: Channels>(
        &self,
        wo: Vec3,
        uc: f32,
        _u: Vec2,
        _mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        let mut r = fr_dielectric(abs_cos_theta(wo), self.eta);
        let mut t = 1.0 - r;
        if r < 1.0 {
            r += sqr(t) * r / (1.0 - sqr(r));
            t = 1.0 - r;
        }
        let pr = if sample_flags.reflection() { r } else { 0.0 };
        let pt = if sample_flags.transmission() { t } else { 0.0 };
        if pr == 0.0 && pt == 0.0 {
            return None;
        }
        if uc < pr / (pr + pt) {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let f = C::splat(r / abs_cos_theta(wi));
            Some(BsdfSample::new(f, wi, pr / (pr + pt), BxdfFlags::SPECULAR_REFLECTION))
        } else {
            let wi = -wo;
            let f = C::splat(t / abs_cos_theta(wi));
            Some(BsdfSample::new(f, wi, pt / (pr + pt), BxdfFlags::SPECULAR_TRANSMISSION))
        }
    }

    /// Always zero: both lobes are Dirac deltas.
    pub fn pdf(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode, _flags: ReflTransFlags) -> f32 {
        0.0
    }

    /// Specular reflection and transmission.
    pub fn flags(&self) -> BxdfFlags {
        BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION | BxdfFlags::SPECULAR
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::Bxdf;
    use crate::materials::bxdf::testing::{self, Check, test_directions};

    #[test]
    fn thin_dielectric_conserves_energy_and_passes_straight_through() {
        let b = Bxdf::from(ThinDielectricBxdf::new(1.5));
        for wo in test_directions() {
            testing::check_all(&b, wo, Check::default());
            let s = testing::sample_statistics(&b, wo, TransportMode::Radiance, ReflTransFlags::ALL, 64);
            assert!((s.albedo - glam::DVec3::ONE).abs().max_element() < 1e-5, "{:?}", s.albedo);
            let t = b.sample_f(wo, 0.999_99, Vec2::ZERO, TransportMode::Radiance, ReflTransFlags::ALL).unwrap();
            assert_eq!(t.wi, -wo);
            assert_eq!(t.eta, 1.0, "no net refraction through a thin slab");
        }
    }

    #[test]
    fn thin_slab_reflects_more_than_one_interface() {
        // Normal incidence at η = 1.5: R = 0.04, R' = R + T²R/(1 − R²) = 2R/(1 + R).
        let b = ThinDielectricBxdf::new(1.5);
        let s = b
            .sample_f::<crate::color::Rgb>(Vec3::Z, 0.0, Vec2::ZERO, TransportMode::Radiance, ReflTransFlags::ALL)
            .unwrap();
        let expected = 2.0 * 0.04 / 1.04;
        assert!(s.is_reflection() && (s.pdf - expected).abs() < 1e-6, "{}", s.pdf);
        let only_t = b
            .sample_f::<crate::color::Rgb>(
                Vec3::Z,
                0.0,
                Vec2::ZERO,
                TransportMode::Radiance,
                ReflTransFlags::TRANSMISSION,
            )
            .unwrap();
        assert!(only_t.is_transmission() && only_t.pdf == 1.0);
        assert!((only_t.f.x - (1.0 - expected)).abs() < 1e-6);
    }
}
