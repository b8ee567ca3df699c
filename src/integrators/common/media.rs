//! Volume estimators shared by every integrator: majorant-based distance sampling
//! (pbrt-v4's SampleT_maj, §14.2.1) and residual-ratio-tracking transmittance for shadow
//! rays with pbrt-v4's rescaled path probabilities, so chromatic media get spectral MIS over
//! the RGB channels (the channel `hero` plays the role of pbrt-v4's first wavelength).

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
    u: f32,
    rng: &mut Pcg32,
    hero: usize,
    lambda: &C::Lambda,
    mut callback: F,
) -> C
where
    F: FnMut(Vec3, &MediumPoint<C>, C, C, &mut Pcg32) -> bool,
{
    let walk = Tracking { medium, ray, t_max, hero, lambda, residual: false };
    walk.run(u, rng, |c: &Collision<C>, rng| callback(c.p, &c.mp, c.sigma_maj, c.t_s, rng)).t_s
}

/// A walk along a ray through a medium's majorant segments, sampling tentative collisions
/// with the hero channel's density of a sampling majorant per segment: σmaj (delta tracking,
/// pbrt-v4's SampleT_maj) or, `residual`, σmaj − σc, σc the segment's minorant (residual
/// ratio tracking, Novák et al. 2014: the control σc's share e^(−∫σc) is known in
/// closed form, and only the residual is tracked).
pub(crate) struct Tracking<'a, 'r, C: Channels> {
    pub medium: MediumView<'a, C>,
    pub ray: &'r Ray,
    pub t_max: f32,
    pub hero: usize,
    pub lambda: &'r C::Lambda,
    pub residual: bool,
}

/// A tentative collision of a [`Tracking`].
pub(crate) struct Collision<C> {
    pub p: Vec3,
    pub mp: MediumPoint<C>,
    /// The segment's majorant and minorant.
    pub sigma_maj: C,
    pub sigma_c: C,
    /// The sampling majorant's transmittance since the previous collision (up to a factor
    /// common to all channels, as [`sample_t_maj`]'s T_maj).
    pub t_s: C,
    /// ∫σc since the previous collision.
    pub tau_c: C,
}

/// What is left when a [`Tracking`] walk reaches its end: the sampling majorant's transmittance and
/// ∫σc since the last collision (1 and 0 if the callback stopped the walk).
pub(crate) struct Tail<C> {
    pub t_s: C,
    pub tau_c: C,
}

/// σ·dt, with no light through an infinite stretch where σ > 0 and none lost where σ = 0.
#[inline(always)]
fn optical_depth<C: Channels>(sigma: C, dt: f32) -> C {
    if dt.is_finite() { sigma * dt } else { sigma.map(|s| if s > 0.0 { f32::INFINITY } else { 0.0 }) }
}

impl<C: Channels> Tracking<'_, '_, C> {
    /// Walks the ray, handing each tentative collision to `callback` until it returns `false`.
    #[inline(always)]
    pub fn run<F>(&self, u: f32, rng: &mut Pcg32, callback: F) -> Tail<C>
    where
        F: FnMut(&Collision<C>, &mut Pcg32) -> bool,
    {
        self.run_with_segment_ends(u, rng, callback, |_, _| true)
    }

    /// [`Tracking::run`], also asking `segment_end(∫σc since the last collision, rng)` at the
    /// end of each majorant segment whether to go on (`false` stops the walk, as a collision's
    /// `false` does).
    #[inline(always)]
    pub fn run_with_segment_ends<F, E>(&self, u: f32, rng: &mut Pcg32, mut callback: F, mut segment_end: E) -> Tail<C>
    where
        F: FnMut(&Collision<C>, &mut Pcg32) -> bool,
        E: FnMut(C, &mut Pcg32) -> bool,
    {
        // The optical depth to the next tentative collision, Exp(1)-distributed. A sample that
        // passes a segment's end carries what is left of it into the next segment instead of
        // being drawn anew: by the exponential's memorylessness the excess is Exp(1) and
        // independent of the segment, so the distances are distributed as pbrt-v4's, and the
        // first collision stays a monotone function of the sampler's `u` across segments
        // (stratified as the sampler stratifies `u`) at one logarithm per collision.
        let mut tau = -(1.0 - u).ln();
        let mut t_s = C::ONE;
        let mut tau_c = C::ZERO;
        for seg in self.medium.segments(self.ray, self.t_max, self.lambda) {
            let sigma_s = if self.residual { (seg.sigma_maj - seg.sigma_c).max(C::ZERO) } else { seg.sigma_maj };
            let sigma = sigma_s[self.hero];
            let gray = sigma_s.max_element() == sigma_s.min_element();
            if sigma == 0.0 {
                let dt = seg.t_max - seg.t_min;
                t_s *= optical_depth(sigma_s, dt).exp_neg();
                tau_c += optical_depth(seg.sigma_c, dt);
                if !segment_end(tau_c, rng) {
                    return Tail { t_s: C::ONE, tau_c: C::ZERO };
                }
                continue;
            }
            let mut t_min = seg.t_min;
            loop {
                let t = t_min + tau / sigma;
                if t < seg.t_max {
                    tau = -(1.0 - rng.uniform()).ln();
                    if !gray {
                        t_s *= (sigma_s * (t - t_min)).exp_neg();
                    }
                    let p = self.ray.at(t);
                    let mp = self.medium.sample_point(p, self.lambda);
                    let c = Collision {
                        p,
                        mp,
                        sigma_maj: seg.sigma_maj,
                        sigma_c: seg.sigma_c,
                        t_s,
                        tau_c: tau_c + seg.sigma_c * (t - t_min),
                    };
                    if !callback(&c, rng) {
                        return Tail { t_s: C::ONE, tau_c: C::ZERO };
                    }
                    t_s = C::ONE;
                    tau_c = C::ZERO;
                    t_min = t;
                } else {
                    let dt = seg.t_max - t_min;
                    tau = (tau - sigma * dt).max(0.0);
                    // An infinite segment with σ > 0 has zero transmittance (avoid inf·0).
                    t_s *= match (dt.is_infinite(), gray) {
                        (true, _) => C::ZERO,
                        (false, true) => C::ONE,
                        (false, false) => (sigma_s * dt).exp_neg(),
                    };
                    tau_c += optical_depth(seg.sigma_c, dt);
                    if !segment_end(tau_c, rng) {
                        return Tail { t_s: C::ONE, tau_c: C::ZERO };
                    }
                    break;
                }
            }
        }
        Tail { t_s, tau_c }
    }
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

/// Transmittance along a shadow-ray segment through `medium` by residual ratio tracking,
/// folded into `est` (unchanged for an empty segment). Russian roulette stops walks whose
/// estimate has fallen below 0.05.
///
/// Tentative collisions are sampled with the residual majorant σr = σmaj − σc of each
/// segment (σc its minorant), and each weighs σn/σr = (σmaj − σt)/(σmaj − σc) instead of
/// ratio tracking's σn/σmaj, times the control's e^(−σc Δt) (Novák et al. 2014). In a
/// null-scattering path space (Miller, Georgiev and Jarosz, "A Null-Scattering Path Integral
/// Formulation of Light Transport", SIGGRAPH 2019) this only changes how the light-sampling
/// technique samples its null vertices: with density σr e^(−∫σr) instead of σmaj e^(−∫σmaj).
/// So its rescaled probability `r_l` takes σr and T_r, and delta tracking's `r_l` (in
/// `path.rs`, `track_medium`) the same, which keeps the MIS weights those of one path space.
/// With no minorant (σc = 0) this is ratio tracking, number for number; in a homogeneous
/// medium (σc = σmaj) it is e^(−σt d) without a step.
///
/// The first tentative collision is at optical depth −ln(1 − u) for `first_u` (a sampler's
/// value, so that a pixel's shadow rays are stratified as its paths are), else for a value of
/// `rng`.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn ratio_tracking<C: Channels>(
    first_u: Option<f32>,
    medium: MediumView<'_, C>,
    ray: &Ray,
    t_max: f32,
    rng: &mut Pcg32,
    hero: usize,
    lambda: &C::Lambda,
    est: &mut ShadowEstimate<C>,
) {
    let u = first_u.unwrap_or_else(|| rng.uniform());
    let walk = Tracking { medium, ray, t_max, hero, lambda, residual: true };
    // e^(−∫σc), 1 without evaluating the exponential where there is no control.
    let control = |tau_c: C| if tau_c.is_zero() { C::ONE } else { tau_c.exp_neg() };
    // Russian roulette where the estimate's largest channel `tr` is below 0.05.
    let roulette = |tr: f32, t_ray: &mut C, rr: &mut Pcg32| {
        const Q: f32 = 0.75;
        if tr < 0.05 {
            if rr.uniform() < Q {
                *t_ray = C::ZERO;
            } else {
                *t_ray /= 1.0 - Q;
            }
        }
        !t_ray.is_zero()
    };
    let est = std::cell::RefCell::new(est);
    let tail = walk.run_with_segment_ends(
        u,
        rng,
        |c: &Collision<C>, rr| {
            let mut guard = est.borrow_mut();
            let est = &mut **guard;
            let sigma_n = (c.sigma_maj - c.mp.sigma_a - c.mp.sigma_s).max(C::ZERO);
            let sigma_r = (c.sigma_maj - c.sigma_c).max(C::ZERO);
            let pdf = c.t_s[hero] * sigma_r[hero];
            let t_ray = control(c.tau_c) * c.t_s * sigma_n / pdf;
            est.t_ray *= t_ray;
            est.r_l *= c.t_s * sigma_r / pdf;
            est.r_u *= t_ray;
            let tr = (est.t_ray / (est.r_l + est.r_u).average()).max_element();
            roulette(tr, &mut est.t_ray, rr)
        },
        // Where the control alone has taken the estimate below 0.05 (e^-3), roulette at
        // segment ends too: with few residual collisions, a shadow ray deep in a dense cloud
        // otherwise walks every cell to the boundary for a negligible estimate.
        |tau_c: C, rr| {
            if tau_c.min_element() <= 3.0 {
                return true;
            }
            let mut guard = est.borrow_mut();
            let est = &mut **guard;
            let c = tau_c.exp_neg();
            let tr = (est.t_ray * c / (est.r_l + est.r_u * c).average()).max_element();
            roulette(tr, &mut est.t_ray, rr)
        },
    );
    let est = est.into_inner();
    let h = tail.t_s[hero];
    if h > 0.0 {
        let t_ray = control(tail.tau_c) * tail.t_s / h;
        est.t_ray *= t_ray;
        est.r_l *= tail.t_s / h;
        est.r_u *= t_ray;
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

    /// Residual ratio tracking through a homogeneous slab gives exp(−σt d) every time: σt is
    /// its own minorant, so no residual is left to track. Per channel in a chromatic one, with
    /// r_l = 1 (the light technique's null vertices: none) and r_u = T (delta tracking's
    /// chance to pass).
    #[test]
    fn homogeneous_transmittance_is_exponential() {
        // RGB transport reads only the `rgb` part.
        let rgb = |r, g, b| SpectrumValue { rgb: Rgb::new(r, g, b), ..SpectrumValue::ZERO };
        let (sa, ss) = (rgb(0.5, 0.2, 0.1), rgb(1.5, 0.3, 0.0));
        let m = Medium::homogeneous("m".into(), sa, ss, SpectrumValue::ZERO, 0.0);
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let exact = Rgb::new((-2.0f32 * 0.7).exp(), (-0.5f32 * 0.7).exp(), (-0.1f32 * 0.7).exp());
        let mut rng = Pcg32::new(1, 2);
        for hero in [0, 1, 2] {
            let mut est = ShadowEstimate::default();
            ratio_tracking(None, (&m).into(), &ray, 0.7, &mut rng, hero, &(), &mut est);
            let t = est.t_ray / crate::color::average(est.r_l);
            assert!((t - exact).abs().max_element() < 1e-6, "hero {hero}: {t} vs {exact}");
            assert_eq!(est.r_l, Rgb::ONE);
            assert!((est.r_u - est.t_ray).abs().max_element() < 1e-7);
        }
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

    /// Delta tracking (probability of no real collision), residual ratio tracking and
    /// quadrature agree on the transmittance through a heterogeneous grid.
    #[test]
    fn delta_and_ratio_tracking_match_quadrature() {
        let m = grid_medium();
        let ray = Ray::new(Vec3::new(-1.5, -0.3, 0.2), Vec3::new(1.0, 0.35, -0.2).normalize());
        let t_max = 3.0;
        let exact = analytic(&m, &ray, t_max);
        let mut rng = Pcg32::new(7, 11);
        let n = 40000;
        let (mut ratio, mut delta) = (0.0f64, 0.0f64);
        // Every collision lies between its segment's minorant and majorant, and some segments
        // have a minorant (else residual ratio tracking is plain ratio tracking here).
        let mut controlled = 0;
        let walk = Tracking { medium: (&m).into(), ray: &ray, t_max, hero: 0, lambda: &(), residual: false };
        walk.run(0.5, &mut rng, |c: &Collision<Rgb>, _| {
            let sigma_t = (c.mp.sigma_a + c.mp.sigma_s).x;
            assert!(c.sigma_c.x <= sigma_t * 1.0001 && sigma_t <= c.sigma_maj.x * 1.0001, "{sigma_t} at {}", c.p);
            controlled += (c.sigma_c.x > 0.0) as u32;
            true
        });
        assert!(controlled > 0);
        for _ in 0..n {
            let mut est = ShadowEstimate::default();
            ratio_tracking(None, (&m).into(), &ray, t_max, &mut rng, 0, &(), &mut est);
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

    /// A sparse grid's majorant cells bound every lookup a collision in them makes, from
    /// above and below, though they reach only the voxels a lookup interpolates (not
    /// pbrt-v4's extra voxel on each side): a grid of random densities under a rotation and
    /// a non-uniform scale, walked along random rays.
    #[test]
    fn sparse_majorant_cells_bound_their_lookups() {
        use crate::media::grid::SparseGrid;
        let dims = UVec3::new(23, 17, 29);
        let mut state = 0x1234_5678u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        let values: Vec<f32> = (0..dims.x * dims.y * dims.z).map(|_| 0.2 + next()).collect();
        let world_from_index = glam::DAffine3::from_scale_rotation_translation(
            glam::DVec3::new(0.1, 0.13, 0.07),
            glam::DQuat::from_rotation_y(0.4),
            glam::DVec3::new(-1.0, -1.2, -0.9),
        );
        let g = SparseGrid::from_dense(glam::IVec3::new(-3, 2, 0), dims, &values, 0.0).with_transform(world_from_index);
        let bounds = g.world_bounds();
        let density = Density::Field(Field::Sparse(Box::new(g)));
        let m = Medium::grid(
            "s".into(),
            Affine3A::IDENTITY,
            bounds,
            density,
            SpectrumValue::constant(0.5),
            SpectrumValue::constant(1.5),
            Emission::None,
            0.0,
        );
        let mut rng = Pcg32::new(3, 5);
        let (mut collisions, mut controlled) = (0, 0);
        for _ in 0..300 {
            let o = bounds.min + (bounds.max - bounds.min) * Vec3::new(next(), next(), next());
            let d = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let ray = Ray::new(o - 5.0 * d, d);
            let walk = Tracking { medium: (&m).into(), ray: &ray, t_max: 10.0, hero: 0, lambda: &(), residual: false };
            walk.run(next(), &mut rng, |c: &Collision<Rgb>, _| {
                let sigma_t = (c.mp.sigma_a + c.mp.sigma_s).x;
                assert!(
                    sigma_t <= c.sigma_maj.x * 1.0001 + 1e-6,
                    "σt {sigma_t} above σmaj {} at {}",
                    c.sigma_maj.x,
                    c.p
                );
                assert!(c.sigma_c.x <= sigma_t * 1.0001 + 1e-6, "σc {} above σt {sigma_t} at {}", c.sigma_c.x, c.p);
                collisions += 1;
                controlled += (c.sigma_c.x > 0.0) as u32;
                true
            });
        }
        assert!(collisions > 1000 && controlled > collisions / 4, "{controlled} of {collisions} collisions controlled");
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
