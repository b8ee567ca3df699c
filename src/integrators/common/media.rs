//! Volume estimators shared by every integrator: majorant-based distance sampling
//! (pbrt-v4's SampleT_maj, §14.2.1) and ratio-tracking transmittance for shadow rays with
//! pbrt-v4's rescaled path probabilities, so chromatic media get spectral MIS over the RGB
//! channels (the channel `hero` plays the role of pbrt-v4's first wavelength).

use glam::Vec3;

use crate::channels::Channels;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::media::{Medium, MediumKind, MediumPoint, MediumView};
use crate::sampling::rng::Pcg32;

/// Walks `ray` (unit direction) through `medium` (as the path sees it) up to `t_max`, sampling tentative collisions
/// with density σmaj[hero]·exp(−σmaj[hero] t) in each majorant segment. At each collision
/// `callback(p, point, σmaj, T_maj, rng)` decides whether to go on (`true`); T_maj is the
/// majorant transmittance since the previous collision. Returns the majorant transmittance
/// from the last collision to the end (1 if the callback stopped the walk).
///
/// Both are known up to a positive factor common to all channels, which every estimator
/// cancels (it divides by the hero channel's T_maj, the sampling density): a segment whose
/// majorant is the same in every channel (any gray medium, a spectral `rgbgrid`) leaves
/// T_maj unchanged instead of taking e^(−σmaj t) per collision (3 % of a spectral `rgbgrid`
/// render). A collision-free infinite segment still makes it zero.
#[inline]
#[allow(clippy::too_many_arguments)] // pbrt-v4's SampleT_maj takes the same inputs
pub fn sample_t_maj<C: Channels, F>(
    medium: MediumView<'_, C>,
    ray: &Ray,
    t_max: f32,
    mut u: f32,
    rng: &mut Pcg32,
    hero: usize,
    lambda: &C::Lambda,
    mut callback: F,
) -> C
where
    F: FnMut(Vec3, &MediumPoint<C>, C, C, &mut Pcg32) -> bool,
{
    let mut t_maj = C::ONE;
    for seg in medium.segments(ray, t_max, lambda) {
        let sigma = seg.sigma_maj[hero];
        let gray = seg.sigma_maj.max_element() == seg.sigma_maj.min_element();
        if sigma == 0.0 {
            let dt = seg.t_max - seg.t_min;
            t_maj *= (seg.sigma_maj * dt).exp_neg();
            continue;
        }
        let mut t_min = seg.t_min;
        loop {
            let t = t_min - (1.0 - u).ln() / sigma;
            u = rng.uniform();
            if t < seg.t_max {
                if !gray {
                    t_maj *= (seg.sigma_maj * (t - t_min)).exp_neg();
                }
                let p = ray.at(t);
                let mp = medium.sample_point(p, lambda);
                if !callback(p, &mp, seg.sigma_maj, t_maj, rng) {
                    return C::ONE;
                }
                t_maj = C::ONE;
                t_min = t;
            } else {
                let dt = seg.t_max - t_min;
                // An infinite segment with σmaj > 0 has zero transmittance (avoid inf·0).
                t_maj *= match (dt.is_infinite(), gray) {
                    (true, _) => C::ZERO,
                    (false, true) => C::ONE,
                    (false, false) => (seg.sigma_maj * dt).exp_neg(),
                };
                break;
            }
        }
    }
    t_maj
}

/// A shadow ray's running transmittance estimate with pbrt-v4's rescaled probabilities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowEstimate<C = Rgb> {
    /// Transmittance estimate.
    pub t_ray: C,
    /// Rescaled unidirectional (delta-tracking) path probability.
    pub r_u: C,
    /// Rescaled light-sampling (ratio-tracking) path probability.
    pub r_l: C,
}

impl<C: Channels> Default for ShadowEstimate<C> {
    fn default() -> Self {
        ShadowEstimate { t_ray: C::ONE, r_u: C::ONE, r_l: C::ONE }
    }
}

/// Transmittance along a shadow-ray segment through `medium` by ratio tracking, folded into
/// `est` (unchanged for an empty segment). Russian roulette stops walks whose estimate has
/// fallen below 0.05.
#[inline]
pub fn ratio_tracking<C: Channels>(
    medium: MediumView<'_, C>,
    ray: &Ray,
    t_max: f32,
    rng: &mut Pcg32,
    hero: usize,
    lambda: &C::Lambda,
    est: &mut ShadowEstimate<C>,
) {
    let u = rng.uniform();
    let t_maj =
        sample_t_maj(medium, ray, t_max, u, rng, hero, lambda, |_, mp: &MediumPoint<C>, sigma_maj: C, t_maj: C, rr| {
            let sigma_n = (sigma_maj - mp.sigma_a - mp.sigma_s).max(C::ZERO);
            let pdf = t_maj[hero] * sigma_maj[hero];
            est.t_ray *= t_maj * sigma_n / pdf;
            est.r_l *= t_maj * sigma_maj / pdf;
            est.r_u *= t_maj * sigma_n / pdf;
            let tr = est.t_ray / (est.r_l + est.r_u).average();
            if tr.max_element() < 0.05 {
                let q = 0.75;
                if rr.uniform() < q {
                    est.t_ray = C::ZERO;
                } else {
                    est.t_ray /= 1.0 - q;
                }
            }
            !est.t_ray.is_zero()
        });
    let h = t_maj[hero];
    if h > 0.0 {
        est.t_ray *= t_maj / h;
        est.r_l *= t_maj / h;
        est.r_u *= t_maj / h;
    } else {
        est.t_ray = C::ZERO;
    }
}

/// Transmittance along `ray` up to `t_max` through `medium`, for an estimate that is added
/// whatever the path does ([`super::PathConfig::camera_line`]), so its variance is all there
/// is: exact in a homogeneous medium; elsewhere ratio tracking against twice the majorant,
/// each collision keeping 1 − σt/(2 σmaj) ≥ 1/2 of the estimate in every channel (relative
/// variance e^{τ/2} − 1 against e^τ − 1 for reaching the end by delta tracking), with
/// Russian roulette below 0.05. Channels share the collisions, so no spectral MIS is needed.
pub fn line_transmittance<C: Channels>(
    medium: &Medium,
    ray: &Ray,
    t_max: f32,
    rng: &mut Pcg32,
    lambda: &C::Lambda,
) -> C {
    if let MediumKind::Homogeneous { .. } = medium.kind {
        // One segment, σmaj = σt: e^{-σt d}, and no light through an infinite one.
        return medium.segments::<C>(ray, t_max, lambda).next().map_or(C::ONE, |seg| {
            let dt = seg.t_max - seg.t_min;
            if dt.is_infinite() {
                seg.sigma_maj.map(|s| if s > 0.0 { 0.0 } else { 1.0 })
            } else {
                (seg.sigma_maj * dt).exp_neg()
            }
        });
    }
    let mut tr = C::ONE;
    for seg in medium.segments::<C>(ray, t_max, lambda) {
        let sigma = 2.0 * seg.sigma_maj.max_element();
        if sigma <= 0.0 {
            continue;
        }
        let mut t = seg.t_min;
        loop {
            t -= (1.0 - rng.uniform()).ln() / sigma;
            if t >= seg.t_max {
                break;
            }
            let mp = medium.sample_point::<C>(ray.at(t), lambda);
            tr *= C::ONE - (mp.sigma_a + mp.sigma_s) * (1.0 / sigma);
            if tr.max_element() < 0.05 {
                if rng.uniform() < 0.75 {
                    return C::ZERO;
                }
                tr *= 4.0;
            }
        }
    }
    tr
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::Medium;
    use crate::spectra::SpectrumValue;

    /// Ratio tracking through a homogeneous slab estimates exp(−σt d) (exactly, since
    /// σmaj = σt leaves no null collisions to weigh).
    #[test]
    fn homogeneous_transmittance_is_exponential() {
        let (sa, ss) = (SpectrumValue::constant(0.5), SpectrumValue::constant(1.5));
        let m = Medium::homogeneous("m".into(), sa, ss, SpectrumValue::ZERO, 0.0);
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let mut rng = Pcg32::new(1, 2);
        let n = 20000;
        let mut sum = 0.0;
        for _ in 0..n {
            let mut est = ShadowEstimate::default();
            ratio_tracking((&m).into(), &ray, 0.7, &mut rng, 0, &(), &mut est);
            sum += (est.t_ray / crate::color::average(est.r_l)).x as f64;
        }
        let est = sum / n as f64;
        let exact = (-2.0f64 * 0.7).exp();
        // Each estimate is 0 or exp(-σt d)/(P(no collision)) = 1 ... with variance ≤ 1/4n.
        assert!((est - exact).abs() < 4.0 * (0.25 / n as f64).sqrt(), "{est} vs {exact}");
    }
}

#[cfg(test)]
mod heterogeneous_tests {
    use super::*;
    use crate::geometry::Bounds3;
    use crate::media::dense::DenseGrid;
    use crate::media::{Density, Emission, Field, Medium};
    use crate::spectra::SpectrumValue;
    use glam::{Affine3A, UVec3};

    fn grid_medium() -> Medium {
        // A 4×4×4 grid whose density varies along every axis.
        let mut values = Vec::new();
        for z in 0..4 {
            for y in 0..4 {
                for x in 0..4 {
                    values.push(0.2 + 0.3 * x as f32 + 0.15 * y as f32 + 0.1 * ((x + z) % 3) as f32);
                }
            }
        }
        let density = Density::Field(Field::Dense(DenseGrid::new(UVec3::splat(4), values).unwrap()));
        let bounds = Bounds3::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        Medium::grid(
            "g".into(),
            Affine3A::IDENTITY,
            bounds,
            density,
            SpectrumValue::constant(0.4),
            SpectrumValue::constant(0.8),
            Emission::None,
            0.0,
        )
    }

    /// exp(−∫σt) along the ray by fine midpoint quadrature of the interpolated density,
    /// inside the medium's box (the density exists only there).
    fn analytic(m: &Medium, ray: &Ray, t_max: f32) -> f64 {
        let n = 20000;
        let dt = t_max as f64 / n as f64;
        let mut tau = 0.0;
        for i in 0..n {
            let p = ray.at(((i as f64 + 0.5) * dt) as f32);
            if p.abs().max_element() > 1.0 {
                continue;
            }
            let mp = m.sample_point::<Rgb>(p, &());
            tau += (mp.sigma_a + mp.sigma_s).x as f64 * dt;
        }
        (-tau).exp()
    }

    /// Delta tracking (probability of no real collision), ratio tracking and quadrature agree
    /// on the transmittance through a heterogeneous grid.
    #[test]
    fn delta_and_ratio_tracking_match_quadrature() {
        let m = grid_medium();
        let ray = Ray::new(Vec3::new(-1.5, -0.3, 0.2), Vec3::new(1.0, 0.35, -0.2).normalize());
        let t_max = 3.0;
        let exact = analytic(&m, &ray, t_max);
        let mut rng = Pcg32::new(7, 11);
        let n = 40000;
        let (mut ratio, mut delta) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let mut est = ShadowEstimate::default();
            ratio_tracking((&m).into(), &ray, t_max, &mut rng, 0, &(), &mut est);
            ratio += (est.t_ray / crate::color::average(est.r_l)).x as f64;
            let u = rng.uniform();
            let mut escaped = true;
            sample_t_maj(
                (&m).into(),
                &ray,
                t_max,
                u,
                &mut rng,
                0,
                &(),
                |p, mp: &MediumPoint<Rgb>, sigma_maj: Rgb, _, r| {
                    assert!((mp.sigma_a + mp.sigma_s).x <= sigma_maj.x * 1.0001, "majorant below σt at {p:?}");
                    if r.uniform() < (mp.sigma_a + mp.sigma_s).x / sigma_maj.x {
                        escaped = false;
                        return false;
                    }
                    true
                },
            );
            delta += escaped as u8 as f64;
        }
        let (ratio, delta) = (ratio / n as f64, delta / n as f64);
        // Binomial noise of the delta-tracking estimate; ratio tracking has less.
        let se = (exact * (1.0 - exact) / n as f64).sqrt();
        assert!((delta - exact).abs() < 4.0 * se, "delta tracking {delta} vs {exact} ± {se}");
        assert!((ratio - exact).abs() < 4.0 * se, "ratio tracking {ratio} vs {exact} ± {se}");
    }

    /// Lookups at voxel centres return the voxel data times σ.
    #[test]
    fn grid_lookup_at_voxel_centres_equals_the_data() {
        let m = grid_medium();
        for (x, y, z) in [(0, 0, 0), (3, 1, 2), (1, 2, 3)] {
            let p =
                Vec3::new(-1.0 + (x as f32 + 0.5) * 0.5, -1.0 + (y as f32 + 0.5) * 0.5, -1.0 + (z as f32 + 0.5) * 0.5);
            let d = 0.2 + 0.3 * x as f32 + 0.15 * y as f32 + 0.1 * ((x + z) % 3) as f32;
            let mp = m.sample_point::<Rgb>(p, &());
            assert!((mp.sigma_s.x - 0.8 * d).abs() < 1e-5 && (mp.sigma_a.y - 0.4 * d).abs() < 1e-5, "{x},{y},{z}");
        }
        // An rgbgrid returns its per-voxel RGB coefficients.
        // Spectrally, each voxel's packed sigmoid spectrum is evaluated at the wavelengths.
        let space = nimbus_parser::ColorSpace::Srgb;
        let (c0, c1) = (Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.4, 0.5, 0.6));
        let grid = |spectral| {
            let v =
                [c0, c1].map(|c| crate::channels::pack_voxel(c, crate::spectra::RgbRole::Unbounded, space, spectral));
            let sa = DenseGrid::new(UVec3::new(2, 1, 1), v.to_vec()).unwrap();
            let bounds = Bounds3::new(Vec3::ZERO, Vec3::ONE);
            Medium::rgb_grid(
                "r".into(),
                Affine3A::IDENTITY,
                bounds,
                Some(sa),
                None,
                None,
                1.0,
                space,
                0.0,
                true,
                spectral,
            )
        };
        let p = Vec3::new(0.75, 0.5, 0.5);
        let mp = grid(false).sample_point::<Rgb>(p, &());
        assert!((mp.sigma_a - c1).abs().max_element() < 1e-6);
        assert_eq!(mp.sigma_s, Rgb::ONE);
        let lambda = crate::spectra::SampledWavelengths::sample_visible(0.3);
        let mp = grid(true).sample_point::<crate::spectra::SampledSpectrum>(p, &lambda);
        let want = crate::channels::rgb_spectrum(c1, crate::spectra::RgbRole::Unbounded, space).sample(&lambda);
        assert!((mp.sigma_a - want).abs().max_element() < 1e-6, "{} vs {want}", mp.sigma_a);
    }
}
