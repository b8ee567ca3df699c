//! Conductors in RGB: per-channel complex indices of refraction (η, k) whose Fresnel
//! reflectance matches, channel by channel and across incidence angles, the spectral Fresnel
//! reflectance pbrt-v4 computes wavelength by wavelength.
//!
//! pbrt-v4 evaluates F(θ, λ) from the measured η(λ), k(λ) and the film integrates it against
//! the light. nimbus evaluates F(θ) per RGB channel, so for each channel c we want constants
//! (η_c, k_c) with F(θ; η_c, k_c) ≈ P_c(θ), where P(θ) = M·Σ F(θ,λ)I(λ)x̄ȳz̄(λ) / Σ I(λ)ȳ(λ)
//! is the spectral reflectance projected like any reflectance (I: the film space's
//! illuminant). Projecting η and k themselves would not do: F is far from linear in them.
//! The fit is least squares over cos θ samples, from a coarse grid to Levenberg–Marquardt.

use glam::DVec3;
use nimbus_parser::ColorSpace;

use super::SpectrumError;
use super::cie::{LAMBDA_MIN, integrate_y};
use super::colorspace::{convert_reflectance_rgb, rgb_color_space};
use super::convert::spectrum_reflectance_rgb;
use super::spectrum::{ResolvedSpectrum, Spectrum, resolve};
use crate::color::Rgb;
use crate::spectra::spec::SpectrumSpec;

/// A complex number, just enough for the Fresnel equations.
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f64,
    im: f64,
}

impl Complex {
    fn new(re: f64, im: f64) -> Complex {
        Complex { re, im }
    }
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    fn scale(self, s: f64) -> Complex {
        Complex::new(self.re * s, self.im * s)
    }
    fn norm(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    fn div(self, o: Complex) -> Complex {
        let d = o.norm();
        Complex::new((self.re * o.re + self.im * o.im) / d, (self.im * o.re - self.re * o.im) / d)
    }
    /// Principal square root (as `pstd::sqrt` in pbrt-v4).
    fn sqrt(self) -> Complex {
        let n = self.norm().sqrt();
        if n == 0.0 {
            return Complex::new(0.0, 0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 { Complex::new(t1, t2) } else { Complex::new(t2.abs(), t1.copysign(self.im)) }
    }
}

/// Unpolarised Fresnel reflectance of a conductor with complex index η + ik at incidence
/// cosine `cos_theta_i` (pbrt-v4's `FrComplex`).
pub fn conductor_fresnel(cos_theta_i: f64, eta: f64, k: f64) -> f64 {
    let cos_i = cos_theta_i.clamp(0.0, 1.0);
    let n = Complex::new(eta, k);
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = Complex::new(sin2_i, 0.0).div(n.mul(n));
    let cos_t = Complex::new(1.0, 0.0).sub(sin2_t).sqrt();
    let ci = Complex::new(cos_i, 0.0);
    let r_parl = n.scale(cos_i).sub(cos_t).div(n.scale(cos_i).add(cos_t));
    let r_perp = ci.sub(n.mul(cos_t)).div(ci.add(n.mul(cos_t)));
    (r_parl.norm() + r_perp.norm()) / 2.0
}

/// [`conductor_fresnel`] per RGB channel: what nimbus's conductors evaluate with the
/// constants from [`conductor_rgb`].
pub fn conductor_fresnel_rgb(cos_theta_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let c = f64::from(cos_theta_i);
    Rgb::new(
        conductor_fresnel(c, eta.x.into(), k.x.into()) as f32,
        conductor_fresnel(c, eta.y.into(), k.y.into()) as f32,
        conductor_fresnel(c, eta.z.into(), k.z.into()) as f32,
    )
}

/// Incidence cosines the fit samples: midpoints of 64 equal steps of cos θ in (0, 1].
fn fit_cosines() -> Vec<f64> {
    const N: usize = 64;
    (0..N).map(|i| (i as f64 + 0.5) / N as f64).collect()
}

/// The spectral Fresnel reflectance at incidence cosine `cos_theta_i`, projected onto the
/// RGB channels of `film` under its illuminant, as [`spectrum_reflectance_rgb`] would.
pub fn projected_conductor_fresnel(eta: &Spectrum, k: &Spectrum, cos_theta_i: f64, film: ColorSpace) -> DVec3 {
    ProjectionWeights::new(eta, k, film).reflectance(cos_theta_i)
}

/// Per-wavelength weights w(λ) = M·I(λ)x̄ȳz̄(λ) / Σ Iȳ, with η(λ) and k(λ) at the same
/// wavelengths, so projecting F is one weighted sum.
struct ProjectionWeights {
    weights: Vec<DVec3>,
    eta: Vec<f64>,
    k: Vec<f64>,
}

impl ProjectionWeights {
    fn new(eta: &Spectrum, k: &Spectrum, film: ColorSpace) -> ProjectionWeights {
        let cs = rgb_color_space(film);
        let illum = cs.illuminant;
        let norm = integrate_y(|l| illum.eval(l));
        let (mut weights, mut etas, mut ks) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..471 {
            let l = LAMBDA_MIN + i as f64;
            let bar = super::cie::cie_xyz_bar(l);
            weights.push(cs.rgb_from_xyz(bar * illum.eval(l) / norm));
            etas.push(eta.eval(l));
            ks.push(k.eval(l));
        }
        ProjectionWeights { weights, eta: etas, k: ks }
    }

    fn reflectance(&self, cos_theta_i: f64) -> DVec3 {
        self.weights
            .iter()
            .zip(self.eta.iter().zip(&self.k))
            .map(|(w, (&eta, &k))| *w * conductor_fresnel(cos_theta_i, eta, k))
            .sum()
    }
}

/// RGB conductor constants: F_c(θ) = `scale`_c · FrComplex(cos θ; `eta`_c, `k`_c).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorFit {
    /// Per-channel real part of the index of refraction.
    pub eta: Rgb,
    /// Per-channel extinction coefficient.
    pub k: Rgb,
    /// Per-channel factor on the Fresnel reflectance: 1 except in channels where the
    /// projected spectral reflectance exceeds 1, which no conductor reaches (gold's red
    /// channel in sRGB peaks at 1.022: gold lies outside the sRGB gamut).
    pub scale: Rgb,
    /// Largest |F_c − P_c| over the fit's incidence samples and channels.
    pub max_error: f32,
}

impl ConductorFit {
    /// The fitted RGB Fresnel reflectance at incidence cosine `cos_theta_i`.
    pub fn fresnel(&self, cos_theta_i: f32) -> Rgb {
        self.scale * conductor_fresnel_rgb(cos_theta_i, self.eta, self.k)
    }
}

/// Fits RGB conductor constants to the spectral conductor `eta`, `k` for a film in `film`.
pub fn fit_conductor(eta: &Spectrum, k: &Spectrum, film: ColorSpace) -> ConductorFit {
    let weights = ProjectionWeights::new(eta, k, film);
    let cosines = fit_cosines();
    let targets: Vec<DVec3> = cosines.iter().map(|&c| weights.reflectance(c)).collect();
    let mut fit = ConductorFit { eta: Rgb::ZERO, k: Rgb::ZERO, scale: Rgb::ONE, max_error: 0.0 };
    for c in 0..3 {
        let target: Vec<f64> = targets.iter().map(|t| t[c]).collect();
        let (e, kk, s) = fit_channel(&cosines, &target);
        fit.eta[c] = e as f32;
        fit.k[c] = kk as f32;
        fit.scale[c] = s as f32;
        let err = cosines
            .iter()
            .zip(&target)
            .map(|(&mu, t)| (s * conductor_fresnel(mu, e, kk) - t).abs())
            .fold(0.0, f64::max);
        fit.max_error = fit.max_error.max(err as f32);
    }
    fit
}

/// Least-squares (η, k, scale) for one channel. Parameters are ln η, ln(k + 0.01) and ln
/// scale so all stay positive; the scale is only freed when the target exceeds 1
/// somewhere. A coarse grid over (η, k) finds the basin, Levenberg–Marquardt polishes.
fn fit_channel(cosines: &[f64], target: &[f64]) -> (f64, f64, f64) {
    let peak = target.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let free_scale = peak > 1.0;
    let to_params = |p: DVec3| {
        let s = if free_scale { p.z.exp() } else { 1.0 };
        (p.x.exp(), (p.y.exp() - 0.01).max(0.0), s)
    };
    let residuals = |p: DVec3| -> Vec<f64> {
        let (e, k, s) = to_params(p);
        cosines.iter().zip(target).map(|(&mu, t)| s * conductor_fresnel(mu, e, k) - t).collect()
    };
    let cost = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();

    // Coarse grid: η in [0.02, 12], k in [0, 15], both log-spaced; scale starts at the peak.
    let ln_s = if free_scale { peak.ln() } else { 0.0 };
    let mut best = (DVec3::ZERO, f64::INFINITY);
    const G: usize = 48;
    for i in 0..G {
        for j in 0..G {
            let p = DVec3::new(
                0.02f64.ln() + 600.0f64.ln() * i as f64 / (G - 1) as f64,
                0.01f64.ln() + 1501.0f64.ln() * j as f64 / (G - 1) as f64,
                ln_s,
            );
            let c = cost(&residuals(p));
            if c < best.1 {
                best = (p, c);
            }
        }
    }

    // Levenberg–Marquardt with a forward-difference Jacobian.
    let n_params = if free_scale { 3 } else { 2 };
    let (mut p, mut c) = best;
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let r = residuals(p);
        let h = 1e-7;
        let cols: Vec<Vec<f64>> = (0..n_params)
            .map(|u| {
                let mut q = p;
                q[u] += h;
                let rq = residuals(q);
                rq.iter().zip(&r).map(|(a, b)| (a - b) / h).collect()
            })
            .collect();
        // Normal equations JᵀJ δ = −Jᵀr; unused parameters get an identity row.
        let mut a = glam::DMat3::IDENTITY;
        let mut g = DVec3::ZERO;
        for u in 0..n_params {
            g[u] = cols[u].iter().zip(&r).map(|(j, r)| j * r).sum();
            for v in 0..n_params {
                a.col_mut(v)[u] = cols[u].iter().zip(&cols[v]).map(|(x, y)| x * y).sum();
            }
        }
        // Additive (Levenberg) damping: multiplicative damping cannot help where a parameter
        // has no influence, e.g. k at 0 for a dielectric-like channel.
        let mean_diag = (0..n_params).map(|u| a.col(u)[u]).sum::<f64>() / n_params as f64;
        let mut improved = false;
        for _ in 0..12 {
            let mut damped = a;
            for u in 0..n_params {
                damped.col_mut(u)[u] += lambda * mean_diag.max(1e-12);
            }
            if damped.determinant().abs() < 1e-300 {
                lambda *= 10.0;
                continue;
            }
            let q = p - damped.inverse() * g;
            let cq = cost(&residuals(q));
            if cq < c {
                (p, c) = (q, cq);
                lambda = (lambda * 0.3).max(1e-12);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved || c < 1e-14 {
            break;
        }
    }
    to_params(p)
}

/// RGB constants for a conductor given by the scene's `eta` and `k`, for a film in `film`;
/// render with [`ConductorFit::fresnel`] (per-channel `scale` × FrComplex(η, k)).
/// Spectral inputs are fitted with [`fit_conductor`]. RGB inputs pass through (adapted like
/// reflectances if the entity's space `entity` differs) with scale 1 — pbrt-v4 upsamples them
/// to smooth spectra, for which per-channel constants are the natural RGB reading. When only
/// one of the two is RGB, the spectral one is projected like a reflectance.
pub fn conductor_rgb(
    eta: &SpectrumSpec,
    k: &SpectrumSpec,
    entity: ColorSpace,
    film: ColorSpace,
) -> Result<ConductorFit, SpectrumError> {
    Ok(match (resolve(eta)?, resolve(k)?) {
        (ResolvedSpectrum::Spectral(e), ResolvedSpectrum::Spectral(k)) => fit_conductor(&e, &k, film),
        (e, k) => {
            let as_rgb = |s: ResolvedSpectrum| match s {
                ResolvedSpectrum::Rgb(rgb) => convert_reflectance_rgb(rgb, entity, film),
                ResolvedSpectrum::Spectral(s) => spectrum_reflectance_rgb(&s, film),
            };
            ConductorFit { eta: as_rgb(e), k: as_rgb(k), scale: Rgb::ONE, max_error: 0.0 }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::named_spectrum;

    fn metal(name: &str) -> (Spectrum, Spectrum) {
        let get = |q: &str| Spectrum::PiecewiseLinear(named_spectrum(&format!("metal-{name}-{q}")).unwrap().clone());
        (get("eta"), get("k"))
    }

    #[test]
    fn fresnel_limits() {
        // Normal incidence: ((n−1)² + k²) / ((n+1)² + k²).
        let (n, k) = (0.2, 3.0);
        let r0 = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        assert!((conductor_fresnel(1.0, n, k) - r0).abs() < 1e-12);
        assert!((conductor_fresnel(0.0, n, k) - 1.0).abs() < 1e-12);
        // k = 0 is a dielectric: glass reflects 4% at normal incidence.
        assert!((conductor_fresnel(1.0, 1.5, 0.0) - 0.04).abs() < 1e-12);
    }

    /// Largest |F_rgb − P| over 0°..=85° in 1° steps, per channel.
    fn fit_error(name: &str, film: ColorSpace) -> (ConductorFit, f64) {
        let (eta, k) = metal(name);
        let fit = fit_conductor(&eta, &k, film);
        let weights = ProjectionWeights::new(&eta, &k, film);
        let mut worst: f64 = 0.0;
        for deg in 0..=85 {
            let mu = f64::from(deg).to_radians().cos();
            let p = weights.reflectance(mu);
            let f = fit.fresnel(mu as f32).as_dvec3();
            worst = worst.max((f - p).abs().max_element());
        }
        (fit, worst)
    }

    #[test]
    fn gold_and_copper_fits_reproduce_spectral_fresnel() {
        for name in ["Au", "Cu"] {
            let (fit, worst) = fit_error(name, ColorSpace::Srgb);
            assert!(worst < 0.01, "{name}: {worst} {fit:?}");
        }
    }

    #[test]
    fn gold_looks_gold() {
        let (fit, _) = fit_error("Au", ColorSpace::Srgb);
        let r0 = fit.fresnel(1.0);
        assert!(r0.x > r0.y && r0.y > r0.z, "{r0}");
        // Gold's red channel is the one outside the sRGB gamut; copper needs no scale.
        assert!(fit.scale.x > 1.0 && fit.scale.y == 1.0 && fit.scale.z == 1.0);
        assert!(r0.x > 0.9 && r0.z < 0.5, "{r0}");
    }

    #[test]
    fn every_metal_fits_in_every_space() {
        for name in ["Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"] {
            for space in [ColorSpace::Srgb, ColorSpace::Rec2020, ColorSpace::Aces2065_1] {
                let (fit, worst) = fit_error(name, space);
                assert!(worst < 0.01, "{name} {space:?}: {worst} {fit:?}");
            }
        }
    }

    #[test]
    fn dielectric_like_channels_leave_the_grid_point() {
        // MgO has k = 0: with multiplicative damping the fit stuck at a grid η (error 0.0075).
        for space in [ColorSpace::Srgb, ColorSpace::Aces2065_1] {
            let (fit, worst) = fit_error("MgO", space);
            assert!(worst < 1e-3, "{space:?}: {worst} {fit:?}");
            assert!(fit.eta.x < fit.eta.z, "{fit:?}");
        }
    }

    #[test]
    fn rgb_inputs_pass_through() {
        let s = ColorSpace::Srgb;
        let fit =
            conductor_rgb(&SpectrumSpec::Rgb([0.2, 0.9, 1.1]), &SpectrumSpec::Rgb([3.9, 2.4, 2.2]), s, s).unwrap();
        assert_eq!(fit.eta, Rgb::new(0.2, 0.9, 1.1));
        assert_eq!(fit.k, Rgb::new(3.9, 2.4, 2.2));
        assert_eq!(fit.scale, Rgb::ONE);
        let named = |n: &str| SpectrumSpec::Named(n.to_string());
        let fit = conductor_rgb(&named("metal-Au-eta"), &named("metal-Au-k"), s, s).unwrap();
        assert!(fit.eta.x < fit.eta.z && fit.k.x > fit.k.z, "{fit:?}");
    }
}
