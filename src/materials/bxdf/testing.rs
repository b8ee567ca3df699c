//! Statistical checks shared by the BxDF tests. Everything is deterministic (fixed seeds,
//! stratified samples), so a test either always passes or always fails.
//!
//! - [`integrate_sphere`]: midpoint quadrature over (θ, φ), fine enough for lobes with α ≥ 0.1.
//! - [`sample_statistics`]: stratified estimates of the probability that `sample_f` succeeds
//!   and of the directional albedo ∫ f |cos θi| dωi = E[f |cos θi| / pdf].
//! - [`chi2_test`]: pbrt-v4's `bsdfs_test.cpp` χ² test of sampled directions against `pdf`,
//!   binned in (θ, φ), expected counts by Gauss-Legendre quadrature, low cells pooled.
//! - [`check_all`]: the properties every non-stochastic BxDF must have.

use std::f64::consts::PI;

use glam::{DVec3, Vec2, Vec3};

use super::{Bxdf, ReflTransFlags, TransportMode};
use crate::math::same_hemisphere;
use crate::sampling::rng::Pcg32;
use crate::sampling::warp::ONE_MINUS_EPSILON;

/// Outgoing directions used by the tests: normal, moderate, oblique and grazing incidence,
/// from above and from below the surface.
pub(crate) fn test_directions() -> [Vec3; 6] {
    [
        Vec3::Z,
        Vec3::new(0.3, 0.4, 0.85).normalize(),
        Vec3::new(-0.7, 0.5, 0.3).normalize(),
        Vec3::new(0.9, -0.2, 0.1).normalize(),
        Vec3::new(0.2, 0.3, -0.9).normalize(),
        Vec3::new(-0.6, -0.5, -0.4).normalize(),
    ]
}

/// The centres of an n × n grid over [0, 1)².
pub(crate) fn stratified_2d(n: usize) -> impl Iterator<Item = Vec2> {
    (0..n * n).map(move |k| Vec2::new(((k % n) as f32 + 0.5) / n as f32, ((k / n) as f32 + 0.5) / n as f32))
}

/// A BxDF that says it does not read its lobe sample `uc` (the path loop then skips that
/// dimension) samples the same directions whatever `uc` is.
pub(crate) fn check_ignores_uc(b: &Bxdf) {
    assert!(!b.reads_uc());
    for wo in test_directions() {
        for u in stratified_2d(8) {
            let at = |uc: f32| {
                b.sample_f(wo, uc, u, TransportMode::Radiance, ReflTransFlags::ALL).map(|s| (s.wi, s.pdf, s.flags))
            };
            let first = at(0.0);
            for uc in [0.3, 0.7, ONE_MINUS_EPSILON] {
                assert_eq!(at(uc), first, "wo {wo}, u {u}, uc {uc}");
            }
        }
    }
}

/// The unit vector with polar angle θ and azimuth φ.
fn spherical(theta: f64, phi: f64) -> Vec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new((st * cp) as f32, (st * sp) as f32, ct as f32)
}

/// ∫ f(ω) dω over the sphere by the midpoint rule on an n_theta × n_phi grid in (θ, φ).
pub(crate) fn integrate_sphere(n_theta: usize, n_phi: usize, mut f: impl FnMut(Vec3) -> f64) -> f64 {
    let (dt, dp) = (PI / n_theta as f64, 2.0 * PI / n_phi as f64);
    let mut sum = 0.0;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * dt;
        let mut row = 0.0;
        for j in 0..n_phi {
            row += f(spherical(theta, (j as f64 + 0.5) * dp));
        }
        sum += row * theta.sin();
    }
    sum * dt * dp
}

/// Estimates from stratified calls of `sample_f`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SampleStatistics {
    /// Fraction of calls that returned a non-specular sample.
    pub p_non_specular: f64,
    /// Fraction of calls that returned a sample.
    pub p_any: f64,
    /// E[f |cos θi| / pdf]: the directional albedo.
    pub albedo: DVec3,
    /// The albedo with the 1/η² radiance scaling of transmission undone (equal to `albedo`
    /// in importance mode): the fraction of energy that is not absorbed.
    pub energy: DVec3,
    /// Largest single-sample weight f |cos θi| / pdf over channels (radiance scaling undone).
    pub max_weight: f64,
}

/// Runs `sample_f` with n × n jittered stratified `u` and Latin-hypercube `uc`.
pub(crate) fn sample_statistics(
    bxdf: &Bxdf,
    wo: Vec3,
    mode: TransportMode,
    flags: ReflTransFlags,
    n: usize,
) -> SampleStatistics {
    let count = n * n;
    // A random permutation stratifies uc too.
    let mut perm: Vec<usize> = (0..count).collect();
    let mut rng = Pcg32::new(7, 11);
    for i in (1..count).rev() {
        let j = (rng.next_u32() as usize) % (i + 1);
        perm.swap(i, j);
    }
    let mut stats =
        SampleStatistics { p_non_specular: 0.0, p_any: 0.0, albedo: DVec3::ZERO, energy: DVec3::ZERO, max_weight: 0.0 };
    for (k, cell) in stratified_2d(n).enumerate() {
        // Jittered within the cell: a regular grid would quantize the success probability.
        let jitter = Vec2::new(rng.uniform(), rng.uniform()) - Vec2::splat(0.5);
        let u = (cell + jitter / n as f32).clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON));
        let uc = (perm[k] as f32 + rng.uniform()) / count as f32;
        let Some(s) = bxdf.sample_f(wo, uc, u, mode, flags) else {
            continue;
        };
        stats.p_any += 1.0;
        if !s.is_specular() {
            stats.p_non_specular += 1.0;
        }
        assert!(s.pdf > 0.0, "sample with pdf {}: {s:?}", s.pdf);
        assert!(s.f.is_finite() && s.f.min_element() >= 0.0, "bad f: {s:?}");
        assert!((s.wi.length() - 1.0).abs() < 1e-4, "wi not normalized: {s:?}");
        assert_eq!(s.is_reflection(), same_hemisphere(wo, s.wi), "flags disagree with the hemisphere: {s:?}");
        let weight = (s.f * s.wi.z.abs() / s.pdf).as_dvec3();
        let unscaled = if s.is_transmission() && mode == TransportMode::Radiance {
            weight * (s.eta as f64).powi(2)
        } else {
            weight
        };
        stats.albedo += weight;
        stats.energy += unscaled;
        stats.max_weight = stats.max_weight.max(unscaled.max_element());
    }
    let c = count as f64;
    stats.p_non_specular /= c;
    stats.p_any /= c;
    stats.albedo /= c;
    stats.energy /= c;
    stats
}

/// ∫ pdf(wo, ω) dω over the sphere, by adaptive quadrature over the χ² bins.
pub(crate) fn pdf_integral(bxdf: &Bxdf, wo: Vec3, mode: TransportMode, flags: ReflTransFlags) -> f64 {
    let pdf = |wi: Vec3| bxdf.pdf(wo, wi, mode, flags) as f64;
    adaptive_bin_integrals(&pdf, |v| 1e-7 + 1e-5 * v).iter().sum()
}

/// Regularized upper incomplete gamma function Q(a, x) = Γ(a, x)/Γ(a): the χ² tail
/// probability is Q(dof/2, χ²/2). Series for x < a + 1, continued fraction otherwise.
pub(crate) fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let log_prefactor = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut del) = (a, 1.0 / a);
        let mut sum = del;
        for _ in 0..100_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * log_prefactor.exp()
    } else {
        // Modified Lentz evaluation of the continued fraction for Γ(a, x).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        log_prefactor.exp() * h
    }
}

/// ln Γ(x) for x > 0 by the Lanczos approximation (g = 7, nine terms).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    let t = x + 7.5;
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

const CHI2_THETA_RES: usize = 40;
const CHI2_PHI_RES: usize = 2 * CHI2_THETA_RES;
const CHI2_MIN_EXPECTED: f64 = 5.0;
/// Reject when the χ² tail probability is below this.
const CHI2_SIGNIFICANCE: f64 = 1e-4;

/// ∫ pdf over the (θ, φ) rectangle [t0, t0 + dt] × [p0, p0 + dp] by 4-point Gauss-Legendre
/// on a `sub` × `sub` subdivision.
fn integrate_bin(pdf: &impl Fn(Vec3) -> f64, (t0, dt): (f64, f64), (p0, dp): (f64, f64), sub: usize) -> f64 {
    const X: [f64; 4] =
        [-0.861_136_311_594_052_6, -0.339_981_043_584_856_3, 0.339_981_043_584_856_3, 0.861_136_311_594_052_6];
    const W: [f64; 4] =
        [0.347_854_845_137_453_8, 0.652_145_154_862_546_1, 0.652_145_154_862_546_1, 0.347_854_845_137_453_8];
    let (ht, hp) = (dt / (2 * sub) as f64, dp / (2 * sub) as f64);
    let mut sum = 0.0;
    for si in 0..sub {
        for sj in 0..sub {
            let tc = t0 + (2 * si + 1) as f64 * ht;
            let pc = p0 + (2 * sj + 1) as f64 * hp;
            for (xa, wa) in X.iter().zip(W) {
                let theta = tc + ht * xa;
                for (xb, wb) in X.iter().zip(W) {
                    sum += wa * wb * pdf(spherical(theta, pc + hp * xb)) * theta.sin();
                }
            }
        }
    }
    sum * ht * hp
}

/// ∫ f over each (θ, φ) bin of the χ² grid. Each bin's subdivision is doubled until the
/// integral changes by less than `tolerance(integral)`.
fn adaptive_bin_integrals(f: &impl Fn(Vec3) -> f64, tolerance: impl Fn(f64) -> f64) -> Vec<f64> {
    let (dt, dp) = (PI / CHI2_THETA_RES as f64, 2.0 * PI / CHI2_PHI_RES as f64);
    let mut out = vec![0.0; CHI2_THETA_RES * CHI2_PHI_RES];
    for i in 0..CHI2_THETA_RES {
        for j in 0..CHI2_PHI_RES {
            let (t, p) = ((i as f64 * dt, dt), (j as f64 * dp, dp));
            let mut value = integrate_bin(f, t, p, 1);
            let mut sub = 2;
            loop {
                let finer = integrate_bin(f, t, p, sub);
                let converged = (finer - value).abs() < tolerance(finer);
                value = finer;
                if converged || sub >= 32 {
                    break;
                }
                sub *= 2;
            }
            out[i * CHI2_PHI_RES + j] = value;
        }
    }
    out
}

/// Expected bin counts: `n` times ∫ pdf over each (θ, φ) bin, refined until a count changes
/// by less than a twentieth of its Poisson deviation, so that quadrature error cannot
/// masquerade as a sampling error at sharp lobe features.
fn expected_frequencies(bxdf: &Bxdf, wo: Vec3, mode: TransportMode, flags: ReflTransFlags, n: usize) -> Vec<f64> {
    let pdf = |wi: Vec3| bxdf.pdf(wo, wi, mode, flags) as f64;
    let n = n as f64;
    let mut counts = adaptive_bin_integrals(&pdf, |v| 0.05 * (v * n).max(1.0).sqrt() / n);
    for c in &mut counts {
        *c *= n;
    }
    counts
}

/// pbrt-v4's χ² test of `sample_f` against `pdf` for `n` random samples. Specular samples
/// are skipped, as they are by pbrt-v4.
pub(crate) fn chi2_test(
    bxdf: &Bxdf,
    wo: Vec3,
    mode: TransportMode,
    flags: ReflTransFlags,
    n: usize,
    seed: u64,
) -> Result<(), String> {
    let mut observed = vec![0.0f64; CHI2_THETA_RES * CHI2_PHI_RES];
    let mut rng = Pcg32::new(seed, 0x5eed);
    for _ in 0..n {
        let uc = rng.uniform();
        let u = Vec2::new(rng.uniform(), rng.uniform());
        let Some(s) = bxdf.sample_f(wo, uc, u, mode, flags) else {
            continue;
        };
        if s.is_specular() {
            continue;
        }
        let theta = (s.wi.z as f64).clamp(-1.0, 1.0).acos();
        let mut phi = (s.wi.y as f64).atan2(s.wi.x as f64);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let ti = ((theta / PI * CHI2_THETA_RES as f64) as usize).min(CHI2_THETA_RES - 1);
        let pj = ((phi / (2.0 * PI) * CHI2_PHI_RES as f64) as usize).min(CHI2_PHI_RES - 1);
        observed[ti * CHI2_PHI_RES + pj] += 1.0;
    }
    let expected = expected_frequencies(bxdf, wo, mode, flags, n);

    // Pool the cells with low expected counts, smallest first.
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pooled_obs, mut pooled_exp) = (0.0, 0.0);
    let (mut chi2, mut dof) = (0.0, 0i64);
    for &c in &order {
        let (o, e) = (observed[c], expected[c]);
        if e == 0.0 {
            if o > n as f64 * 1e-5 {
                return Err(format!("{o} samples in a cell with expected count 0 (wo {wo})"));
            }
        } else if e < CHI2_MIN_EXPECTED || (pooled_exp > 0.0 && pooled_exp < CHI2_MIN_EXPECTED) {
            pooled_obs += o;
            pooled_exp += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pooled_exp > 0.0 || pooled_obs > 0.0 {
        chi2 += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        dof += 1;
    }
    dof -= 1;
    if dof <= 0 {
        return Err(format!("too few degrees of freedom ({dof}) for wo {wo}"));
    }
    let p = gamma_q(dof as f64 / 2.0, chi2 / 2.0);
    if p < CHI2_SIGNIFICANCE || !p.is_finite() {
        return Err(format!("χ² test rejected sampling for wo {wo}: χ² = {chi2:.1}, dof = {dof}, p = {p:.3e}"));
    }
    Ok(())
}

/// The transport mode and sample flags [`check_all`] uses.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Check {
    /// Transport mode.
    pub mode: TransportMode,
    /// Sample flags.
    pub flags: ReflTransFlags,
    /// Bound on a single sample's weight f·|cos|/pdf.
    pub max_weight: f64,
}

impl Default for Check {
    fn default() -> Check {
        Check { mode: TransportMode::Radiance, flags: ReflTransFlags::ALL, max_weight: 1.0 }
    }
}

/// Tolerance of ∫ pdf against the sampling probability; the largest deviation seen over all
/// configurations is 5.5e-4.
const INTEGRAL_TOLERANCE: f64 = 2e-3;

/// The deterministic properties of a (non-stochastic) BxDF for one `wo`:
/// (a) ∫ pdf equals the probability that `sample_f` returns a non-specular sample;
/// (c) a sample's f and pdf equal `f()` and `pdf()` at its direction (specular samples: those
///     are zero instead);
/// (d) the energy E[f |cos| / pdf] (radiance scaling undone) is at most 1, and so is every
///     single sample's weight;
/// (e) reciprocity: f(wo, wi, mode) = f(wi, wo, !mode), which is f(wo, wi) = f(wi, wo) for
///     reflection and the adjoint relation f*(wo, wi) = f(wi, wo) of radiance and importance
///     transport for transmission (pbrt-v4 §9.5, non-symmetric scattering).
pub(crate) fn check_all(bxdf: &Bxdf, wo: Vec3, check: Check) -> SampleStatistics {
    let Check { mode, flags, max_weight } = check;
    let stats = sample_statistics(bxdf, wo, mode, flags, 256);

    // (a)
    let integral = pdf_integral(bxdf, wo, mode, flags);
    assert!(
        (integral - stats.p_non_specular).abs() < INTEGRAL_TOLERANCE,
        "∫pdf = {integral} but sample_f gives a non-specular sample with probability {} \
         (wo {wo}, {bxdf:?})",
        stats.p_non_specular
    );

    // (c)
    for (k, u) in stratified_2d(48).enumerate() {
        let uc = ((k as f32 + 0.5) * 0.618_034).fract();
        let Some(s) = bxdf.sample_f(wo, uc, u, mode, flags) else {
            continue;
        };
        let f = bxdf.f(wo, s.wi, mode);
        let pdf = bxdf.pdf(wo, s.wi, mode, flags);
        if s.is_specular() {
            if !bxdf.flags().is_non_specular() {
                assert_eq!((f, pdf), (Vec3::ZERO, 0.0), "delta lobe evaluated: {s:?}");
            }
            continue;
        }
        let tol = |a: f32| 2e-3 * a.abs() + 1e-6;
        assert!(
            (s.f - f).abs().max_element() <= tol(s.f.max_element()),
            "sample f {} but f() {f} (wo {wo}, {s:?})",
            s.f
        );
        assert!((s.pdf - pdf).abs() <= tol(s.pdf), "sample pdf {} but pdf() {pdf} (wo {wo}, {s:?})", s.pdf);
    }

    // (d)
    assert!(stats.energy.max_element() <= 1.0 + 1e-3, "energy {} > 1 (wo {wo}, {bxdf:?})", stats.energy);
    // Most models have single-sample weights of at most 1 (F·G/G1 for the microfacet models,
    // Fresnel-weighted lobe choices for the specular ones); lobes chosen by their largest
    // channel exceed it in the others (`max_weight`).
    assert!(stats.max_weight <= max_weight + 1e-3, "weight {} > {max_weight} (wo {wo})", stats.max_weight);

    // (e)
    let mut n = 0;
    integrate_sphere(24, 48, |wi| {
        let a = bxdf.f(wo, wi, mode);
        let b = bxdf.f(wi, wo, !mode);
        let scale = a.max_element().max(b.max_element());
        assert!(
            (a - b).abs().max_element() <= 2e-3 * scale + 1e-5,
            "not reciprocal: f(wo, wi) = {a}, f(wi, wo) = {b} (wo {wo}, wi {wi}, {mode:?}, {bxdf:?})"
        );
        n += 1;
        0.0
    });
    assert_eq!(n, 24 * 48);
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_tail_probabilities_are_right() {
        // Q(k/2, x/2) for known χ² quantiles: P(χ²₁ > 3.841) = 0.05, P(χ²₁₀ > 23.209) = 0.01,
        // P(χ²₁₀₀ > 135.807) = 0.01, and Q(1, x) = e^(−x).
        assert!((gamma_q(0.5, 3.841_459 / 2.0) - 0.05).abs() < 1e-5);
        assert!((gamma_q(5.0, 23.209_25 / 2.0) - 0.01).abs() < 1e-5);
        assert!((gamma_q(50.0, 135.806_7 / 2.0) - 0.01).abs() < 1e-5);
        assert!((gamma_q(1.0, 2.5) - (-2.5f64).exp()).abs() < 1e-12);
        assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-10);
    }

    #[test]
    fn sphere_quadrature_is_accurate() {
        assert!((integrate_sphere(64, 128, |_| 1.0) - 4.0 * PI).abs() < 2e-3);
        let v = integrate_sphere(64, 128, |w| (w.z.max(0.0) as f64) / PI);
        assert!((v - 1.0).abs() < 1e-3, "{v}");
    }
}
