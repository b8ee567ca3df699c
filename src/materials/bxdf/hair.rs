//! pbrt-v4's hair BSDF (pbrt-v4 §9.9, `HairBxDF`; Chiang et al. 2016, d'Eon et al. 2011):
//! scattering by a dielectric cylinder with an absorbing interior, as a sum over the number
//! p of internal path segments of a longitudinal lobe M_p, an attenuation A_p and an
//! azimuthal lobe N_p, with the cuticle scales' tilt α.
//!
//! The local frame is the curve's: x runs along the hair (sin θ = ω.x), and the azimuth φ is
//! measured in the yz plane. `h` ∈ [−1, 1] is where across its width the hair was hit.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::fresnel::fr_dielectric;
use super::{BsdfSample, BxdfFlags, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::color::Rgb;

/// Scattering orders modelled explicitly; the rest are lumped into one term.
const P_MAX: usize = 3;

/// The hair BSDF at one hit. Kept compact (every path vertex builds a [`super::Bxdf`], whose
/// size is its largest model's): the per-order variances and the tilt's multiple angles are
/// derived when used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairBxdf<C = Rgb> {
    h: f32,
    eta: f32,
    sigma_a: C,
    /// Longitudinal variance of order 0 (order 1 has a quarter, the others four times).
    v0: f32,
    /// Azimuthal logistic scale.
    s: f32,
    /// sin α and cos α of the cuticle tilt.
    sin_alpha: f32,
    cos_alpha: f32,
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

fn safe_asin(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).asin()
}

/// The modified Bessel function I₀ (series; pbrt-v4's `I0`).
fn i0(x: f32) -> f32 {
    let mut val = 0.0f32;
    let mut x2i = 1.0f32;
    let mut ifact = 1.0f64;
    let mut i4 = 1.0f32;
    for i in 0..10 {
        if i > 1 {
            ifact *= i as f64;
        }
        val += x2i / (i4 * (ifact * ifact) as f32);
        x2i *= x * x;
        i4 *= 4.0;
    }
    val
}

fn log_i0(x: f32) -> f32 {
    if x > 12.0 { x + 0.5 * (-(2.0 * PI).ln() + (1.0 / x).ln() + 1.0 / (8.0 * x)) } else { i0(x).ln() }
}

/// The longitudinal scattering function (d'Eon et al.). pbrt-v4 writes ln 2 as 0.6931; kept.
#[allow(clippy::approx_constant)]
fn mp(cos_theta_i: f32, cos_theta_o: f32, sin_theta_i: f32, sin_theta_o: f32, v: f32) -> f32 {
    let a = cos_theta_i * cos_theta_o / v;
    let b = sin_theta_i * sin_theta_o / v;
    if v <= 0.1 {
        (log_i0(a) - b - 1.0 / v + 0.6931 + (1.0 / (2.0 * v)).ln()).exp()
    } else {
        ((-b).exp() * i0(a)) / ((1.0 / v).sinh() * 2.0 * v)
    }
}

fn logistic(x: f32, s: f32) -> f32 {
    let x = x.abs();
    (-x / s).exp() / (s * (1.0 + (-x / s).exp()).powi(2))
}

fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

fn trimmed_logistic(x: f32, s: f32, a: f32, b: f32) -> f32 {
    logistic(x, s) / (logistic_cdf(b, s) - logistic_cdf(a, s))
}

fn sample_trimmed_logistic(u: f32, s: f32, a: f32, b: f32) -> f32 {
    let k = logistic_cdf(b, s) - logistic_cdf(a, s);
    let x = -s * (1.0 / (u * k + logistic_cdf(a, s)) - 1.0).ln();
    x.clamp(a, b)
}

/// The azimuthal offset of order p.
fn phi(p: usize, gamma_o: f32, gamma_t: f32) -> f32 {
    2.0 * p as f32 * gamma_t - 2.0 * gamma_o + p as f32 * PI
}

fn np(phi_: f32, p: usize, s: f32, gamma_o: f32, gamma_t: f32) -> f32 {
    let mut dphi = phi_ - phi(p, gamma_o, gamma_t);
    while dphi > PI {
        dphi -= 2.0 * PI;
    }
    while dphi < -PI {
        dphi += 2.0 * PI;
    }
    trimmed_logistic(dphi, s, -PI, PI)
}

impl<C: Channels> HairBxdf<C> {
    /// Hair hit at offset `h`, index of refraction `eta`, absorption `sigma_a` (per unit
    /// diameter), longitudinal and azimuthal roughness `beta_m`, `beta_n` and scale tilt
    /// `alpha` (degrees).
    pub fn new(h: f32, eta: f32, sigma_a: C, beta_m: f32, beta_n: f32, alpha: f32) -> HairBxdf<C> {
        let h = h.clamp(-1.0, 1.0);
        let (beta_m, beta_n) = (beta_m.clamp(0.0, 1.0), beta_n.clamp(0.0, 1.0));
        let v0 = (0.726 * beta_m + 0.812 * beta_m * beta_m + 3.7 * beta_m.powi(20)).powi(2);
        const SQRT_PI_OVER_8: f32 = 0.626_657_07;
        let s = SQRT_PI_OVER_8 * (0.265 * beta_n + 1.194 * beta_n * beta_n + 5.372 * beta_n.powi(22));
        let sin_alpha = alpha.to_radians().sin();
        HairBxdf { h, eta, sigma_a, v0, s, sin_alpha, cos_alpha: safe_sqrt(1.0 - sin_alpha * sin_alpha) }
    }

    /// The longitudinal variance of order p (pbrt-v4's v[p]).
    #[inline]
    fn v(&self, p: usize) -> f32 {
        match p {
            0 => self.v0,
            1 => 0.25 * self.v0,
            _ => 4.0 * self.v0,
        }
    }

    /// sin and cos of 2^k·α for k = 0, 1, 2 (pbrt-v4's sin2kAlpha, cos2kAlpha).
    #[inline]
    fn alpha_k(&self) -> ([f32; 3], [f32; 3]) {
        let (mut s, mut c) = ([self.sin_alpha, 0.0, 0.0], [self.cos_alpha, 0.0, 0.0]);
        for i in 1..3 {
            s[i] = 2.0 * c[i - 1] * s[i - 1];
            c[i] = c[i - 1] * c[i - 1] - s[i - 1] * s[i - 1];
        }
        (s, c)
    }

    #[inline]
    fn gamma_o(&self) -> f32 {
        safe_asin(self.h)
    }

    /// pbrt-v4's `SigmaAFromReflectance`: the absorption that gives roughly the diffuse
    /// reflectance `c` for azimuthal roughness `beta_n`.
    pub fn sigma_a_from_reflectance(c: C, beta_n: f32) -> C {
        let d = 5.969 - 0.215 * beta_n + 2.532 * beta_n.powi(2) - 10.73 * beta_n.powi(3)
            + 5.574 * beta_n.powi(4)
            + 0.245 * beta_n.powi(5);
        c.map(|c| (c.ln() / d).powi(2))
    }

    /// pbrt-v4's `SigmaAFromConcentration`: linear sRGB absorption of eumelanin and pheomelanin
    /// concentrations.
    pub fn sigma_a_from_concentration(ce: f32, cp: f32) -> Rgb {
        ce * Rgb::new(0.419, 0.697, 1.37) + cp * Rgb::new(0.187, 0.4, 1.05)
    }

    /// sin θ′ₒ, |cos θ′ₒ| for order p: θₒ tilted by the cuticle scales.
    #[inline]
    fn tilted(&self, p: usize, sin_o: f32, cos_o: f32) -> (f32, f32) {
        let (sa, ca) = self.alpha_k();
        let (s, c) = match p {
            0 => (sin_o * ca[1] - cos_o * sa[1], cos_o * ca[1] + sin_o * sa[1]),
            1 => (sin_o * ca[0] + cos_o * sa[0], cos_o * ca[0] - sin_o * sa[0]),
            2 => (sin_o * ca[2] + cos_o * sa[2], cos_o * ca[2] - sin_o * sa[2]),
            _ => (sin_o, cos_o),
        };
        (s, c.abs())
    }

    /// γt and the attenuations A_p for θₒ.
    fn attenuation(&self, sin_o: f32, cos_o: f32) -> (f32, [C; P_MAX + 1]) {
        let sin_t = sin_o / self.eta;
        let cos_t = safe_sqrt(1.0 - sin_t * sin_t);
        let etap = safe_sqrt(self.eta * self.eta - sin_o * sin_o) / cos_o;
        let sin_gamma_t = self.h / etap;
        let cos_gamma_t = safe_sqrt(1.0 - sin_gamma_t * sin_gamma_t);
        let gamma_t = safe_asin(sin_gamma_t);
        // Transmittance of one crossing of the cylinder.
        let t = (self.sigma_a * (2.0 * cos_gamma_t / cos_t)).map(|x| (-x).exp());
        let cos_gamma_o = safe_sqrt(1.0 - self.h * self.h);
        let f = fr_dielectric(cos_o * cos_gamma_o, self.eta);
        let mut ap = [C::ZERO; P_MAX + 1];
        ap[0] = C::splat(f);
        ap[1] = t * ((1.0 - f) * (1.0 - f));
        for p in 2..P_MAX {
            ap[p] = ap[p - 1] * t * f;
        }
        ap[P_MAX] = (ap[P_MAX - 1] * t * f).zip_map(t, |a, t| a / (1.0 - t * f));
        (gamma_t, ap)
    }

    fn ap_pdf(ap: &[C; P_MAX + 1]) -> [f32; P_MAX + 1] {
        let sum: f32 = ap.iter().map(|a| a.average()).sum();
        let mut pdf = [0.0; P_MAX + 1];
        for (p, a) in pdf.iter_mut().zip(ap) {
            *p = if sum > 0.0 { a.average() / sum } else { 0.0 };
        }
        pdf
    }

    /// f(wo, wi) (pbrt-v4's `HairBxDF::f`, divided by |cos θi| as pbrt-v4 does so that the
    /// integrator's cosine factor cancels).
    // The hair model's methods stay out of line: inlined into `Bxdf`'s dispatch they crowded
    // the path loop's hot code (wax-dielectric, which has no hair, ran 8 % slower).
    #[inline(never)]
    pub fn f(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        let (sin_o, cos_o) = (wo.x, safe_sqrt(1.0 - wo.x * wo.x));
        let phi_o = wo.z.atan2(wo.y);
        let (sin_i, cos_i) = (wi.x, safe_sqrt(1.0 - wi.x * wi.x));
        let phi_i = wi.z.atan2(wi.y);
        let (gamma_t, ap) = self.attenuation(sin_o, cos_o);
        let dphi = phi_i - phi_o;
        let mut sum = C::ZERO;
        for (p, a) in ap.iter().enumerate().take(P_MAX) {
            let (s, c) = self.tilted(p, sin_o, cos_o);
            sum += *a * (mp(cos_i, c, sin_i, s, self.v(p)) * np(dphi, p, self.s, self.gamma_o(), gamma_t));
        }
        sum += ap[P_MAX] * (mp(cos_i, cos_o, sin_i, sin_o, self.v(P_MAX)) / (2.0 * PI));
        if wi.z.abs() > 0.0 {
            sum *= 1.0 / wi.z.abs();
        }
        sum
    }

    /// Samples an order p ∝ A_p, then θi from M_p and Δφ from N_p (pbrt-v4's
    /// `HairBxDF::Sample_f`), with the density of the whole mixture.
    #[inline(never)]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        _flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        let (sin_o, cos_o) = (wo.x, safe_sqrt(1.0 - wo.x * wo.x));
        let phi_o = wo.z.atan2(wo.y);
        let (gamma_t, ap) = self.attenuation(sin_o, cos_o);
        let ap_pdf = Self::ap_pdf(&ap);
        // Choose p and remap uc for reuse (pbrt-v4's SampleDiscrete with uRemapped).
        let mut p = 0;
        let mut cdf = 0.0;
        let mut uc = uc;
        while p < P_MAX && uc >= cdf + ap_pdf[p] {
            cdf += ap_pdf[p];
            p += 1;
        }
        if ap_pdf[p] > 0.0 {
            uc = ((uc - cdf) / ap_pdf[p]).min(1.0 - f32::EPSILON);
        }
        let (sin_po, cos_po) = self.tilted(p, sin_o, cos_o);
        // θi from M_p.
        let vp = self.v(p);
        let cos_theta = 1.0 + vp * (u.x.max(1e-5) + (1.0 - u.x) * (-2.0 / vp).exp()).ln();
        let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
        let cos_phi = (2.0 * PI * u.y).cos();
        let sin_i = -cos_theta * sin_po + sin_theta * cos_phi * cos_po;
        let cos_i = safe_sqrt(1.0 - sin_i * sin_i);
        // Δφ from N_p.
        let dphi = if p < P_MAX {
            phi(p, self.gamma_o(), gamma_t) + sample_trimmed_logistic(uc, self.s, -PI, PI)
        } else {
            2.0 * PI * uc
        };
        let phi_i = phi_o + dphi;
        let wi = Vec3::new(sin_i, cos_i * phi_i.cos(), cos_i * phi_i.sin());
        let pdf = self.pdf_with(sin_o, cos_o, sin_i, cos_i, dphi, gamma_t, &ap_pdf);
        Some(BsdfSample::new(self.f(wo, wi, mode), wi, pdf, BxdfFlags::GLOSSY_REFLECTION))
    }

    #[allow(clippy::too_many_arguments)]
    fn pdf_with(
        &self,
        sin_o: f32,
        cos_o: f32,
        sin_i: f32,
        cos_i: f32,
        dphi: f32,
        gamma_t: f32,
        ap_pdf: &[f32; P_MAX + 1],
    ) -> f32 {
        let mut pdf = 0.0;
        for (p, a) in ap_pdf.iter().enumerate().take(P_MAX) {
            let (s, c) = self.tilted(p, sin_o, cos_o);
            pdf += mp(cos_i, c, sin_i, s, self.v(p)) * a * np(dphi, p, self.s, self.gamma_o(), gamma_t);
        }
        pdf + mp(cos_i, cos_o, sin_i, sin_o, self.v(P_MAX)) * ap_pdf[P_MAX] / (2.0 * PI)
    }

    /// Density of [`HairBxdf::sample_f`].
    #[inline(never)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode, _flags: ReflTransFlags) -> f32 {
        let (sin_o, cos_o) = (wo.x, safe_sqrt(1.0 - wo.x * wo.x));
        let (sin_i, cos_i) = (wi.x, safe_sqrt(1.0 - wi.x * wi.x));
        let (gamma_t, ap) = self.attenuation(sin_o, cos_o);
        let dphi = wi.z.atan2(wi.y) - wo.z.atan2(wo.y);
        self.pdf_with(sin_o, cos_o, sin_i, cos_i, dphi, gamma_t, &Self::ap_pdf(&ap))
    }

    /// pbrt-v4 reports glossy reflection: hair transmits, but one scattering event does not
    /// change the medium a ray is in.
    pub fn flags(&self) -> BxdfFlags {
        BxdfFlags::GLOSSY_REFLECTION
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;
    use crate::sampling::warp::uniform_sphere;

    fn random_dir(rng: &mut Pcg32) -> Vec3 {
        uniform_sphere(Vec2::new(rng.uniform(), rng.uniform()))
    }

    /// Directions of a stratified uniform grid over the sphere (n² of them, jittered).
    fn sphere_grid(n: usize, rng: &mut Pcg32) -> impl Iterator<Item = Vec3> + '_ {
        (0..n * n).map(move |k| {
            let u = Vec2::new(((k % n) as f32 + rng.uniform()) / n as f32, ((k / n) as f32 + rng.uniform()) / n as f32);
            uniform_sphere(u)
        })
    }

    /// pbrt-v4's `HairBxDF.WhiteFurnace`: without absorption a hair scatters all the light
    /// (here with stratified directions, so that the test needs fewer of them).
    #[test]
    fn white_hair_scatters_everything() {
        let mut rng = Pcg32::new(0, 7);
        let wo = random_dir(&mut rng);
        for beta_m in [0.1f32, 0.4, 0.7, 1.0] {
            for beta_n in [0.1f32, 0.4, 0.7, 1.0] {
                let n = 400;
                let mut sum = 0.0f64;
                let mut hrng = Pcg32::new(2, 3);
                for wi in sphere_grid(n, &mut rng) {
                    let h = -1.0 + 2.0 * hrng.uniform();
                    let hair = HairBxdf::new(h, 1.55, Rgb::ZERO, beta_m, beta_n, 0.0);
                    sum += f64::from(hair.f(wo, wi, TransportMode::Radiance).y * wi.z.abs());
                }
                let albedo = sum * 4.0 * std::f64::consts::PI / (n * n) as f64;
                assert!((0.95..=1.05).contains(&albedo), "β_m {beta_m}, β_n {beta_n}: {albedo}");
            }
        }
    }

    /// pbrt-v4's `HairBxDF.SamplingWeights`: white hair's importance sampling is exact, every
    /// sample's weight is 1; `pdf` agrees with the sample's density, and integrates to 1.
    #[test]
    fn white_hair_samples_with_unit_weight_and_a_normalized_density() {
        let mut rng = Pcg32::new(1, 9);
        for beta_m in [0.1f32, 0.4, 0.7] {
            for beta_n in [0.1f32, 0.4, 0.7] {
                let hair = HairBxdf::new(-1.0 + 2.0 * rng.uniform(), 1.55, Rgb::ZERO, beta_m, beta_n, 2.0);
                for _ in 0..200 {
                    let wo = random_dir(&mut rng);
                    let u = Vec2::new(rng.uniform(), rng.uniform());
                    let Some(s) = hair.sample_f(wo, rng.uniform(), u, TransportMode::Radiance, ReflTransFlags::ALL)
                    else {
                        continue;
                    };
                    if s.pdf > 0.0 {
                        let w = s.f.y * s.wi.z.abs() / s.pdf;
                        assert!((w - 1.0).abs() < 1e-2, "β {beta_m}/{beta_n}: weight {w}");
                        let pdf = hair.pdf(wo, s.wi, TransportMode::Radiance, ReflTransFlags::ALL);
                        assert!((pdf - s.pdf).abs() <= 1e-3 * s.pdf.max(1.0), "{pdf} vs {}", s.pdf);
                    }
                }
                let wo = random_dir(&mut rng);
                let n = 400;
                let integral: f64 = sphere_grid(n, &mut rng)
                    .map(|wi| f64::from(hair.pdf(wo, wi, TransportMode::Radiance, ReflTransFlags::ALL)))
                    .sum::<f64>()
                    * 4.0
                    * std::f64::consts::PI
                    / (n * n) as f64;
                assert!((integral - 1.0).abs() < 0.05, "β {beta_m}/{beta_n}: ∫pdf = {integral}");
            }
        }
    }

    #[test]
    fn absorption_darkens_and_colors_hair() {
        let sigma = HairBxdf::<Rgb>::sigma_a_from_concentration(1.3, 0.0);
        let hair = HairBxdf::new(0.3, 1.55, sigma, 0.3, 0.3, 2.0);
        let white = HairBxdf::new(0.3, 1.55, Rgb::ZERO, 0.3, 0.3, 2.0);
        let (wo, wi) = (Vec3::new(0.2, 0.6, 0.77).normalize(), Vec3::new(-0.1, -0.7, 0.7).normalize());
        let (f, fw) = (hair.f(wo, wi, TransportMode::Radiance), white.f(wo, wi, TransportMode::Radiance));
        assert!(f.x < fw.x && f.z < f.x, "brown hair absorbs blue most: {f} vs {fw}");
        // The reflectance inversion recovers σa that the forward fit maps back near c.
        let c = Rgb::new(0.6, 0.4, 0.2);
        let s = HairBxdf::<Rgb>::sigma_a_from_reflectance(c, 0.3);
        assert!(s.x < s.y && s.y < s.z && s.min_element() > 0.0, "{s}");
    }
}
