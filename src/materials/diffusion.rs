//! Scattering coefficients from a diffuse reflectance, as pbrt-v4's `subsurface` material
//! derives them (pbrt-v4 §11.4 of the 3rd edition, `bssrdf.cpp`): the photon beam diffusion
//! profile (d'Eon and Irving 2011; Habel et al. 2013) tabulated over single-scattering
//! albedo ρ and radius, its integral ρ_eff(ρ) (the total diffuse reflectance), and that
//! relation inverted for the ρ whose ρ_eff is the material's `reflectance`. nimbus then
//! renders the medium itself, exactly, instead of the diffusion profile.

use std::f32::consts::PI;

use super::bxdf::fr_dielectric;
use crate::media::phase::henyey_greenstein;

const N_RHO: usize = 100;
const N_RADIUS: usize = 64;

/// ρ_eff as a function of ρ, for one (g, η).
#[derive(Debug)]
pub struct DiffusionTable {
    rho: Vec<f32>,
    rho_eff: Vec<f32>,
}

/// ∫₀^{π/2} F(cos θ) cos θ sin θ dθ (pbrt-v4's polynomial fit `FresnelMoment1`).
fn fresnel_moment1(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta.powi(3), eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5
    } else {
        -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5
    }
}

/// ∫₀^{π/2} F(cos θ) cos² θ sin θ dθ (pbrt-v4's `FresnelMoment2`).
fn fresnel_moment2(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta.powi(3), eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.27614 - 0.87350 * eta + 1.12077 * e2 - 0.65095 * e3 + 0.07883 * e4 + 0.04860 * e5
    } else {
        let (r, r2, r3) = (1.0 / eta, 1.0 / e2, 1.0 / e3);
        -547.033 + 45.3087 * r3 - 218.725 * r2 + 458.843 * r + 404.557 * eta - 189.519 * e2 + 54.9327 * e3
            - 9.00603 * e4
            + 0.63942 * e5
    }
}

fn sample_exponential(u: f32, a: f32) -> f32 {
    -(1.0 - u).ln() / a
}

/// Multiple scattering of the photon beam diffusion profile at radius r.
fn beam_diffusion_ms(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    const N: usize = 100;
    let sigmap_s = sigma_s * (1.0 - g);
    let sigmap_t = sigma_a + sigmap_s;
    let rhop = sigmap_s / sigmap_t;
    let d_g = (2.0 * sigma_a + sigmap_s) / (3.0 * sigmap_t * sigmap_t);
    let sigma_tr = (sigma_a / d_g).max(0.0).sqrt();
    let (fm1, fm2) = (fresnel_moment1(eta), fresnel_moment2(eta));
    let ze = -2.0 * d_g * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1);
    let (c_phi, c_e) = (0.25 * (1.0 - 2.0 * fm1), 0.5 * (1.0 - 3.0 * fm2));
    let mut ed = 0.0;
    for i in 0..N {
        // A real source at depth zr and its virtual mirror image.
        let zr = sample_exponential((i as f32 + 0.5) / N as f32, sigmap_t);
        let zv = -zr + 2.0 * ze;
        let (dr, dv) = ((r * r + zr * zr).sqrt(), (r * r + zv * zv).sqrt());
        let phi_d = 1.0 / (4.0 * PI) / d_g * ((-sigma_tr * dr).exp() / dr - (-sigma_tr * dv).exp() / dv);
        let ed_n = 1.0 / (4.0 * PI)
            * (zr * (1.0 + sigma_tr * dr) * (-sigma_tr * dr).exp() / dr.powi(3)
                - zv * (1.0 + sigma_tr * dv) * (-sigma_tr * dv).exp() / dv.powi(3));
        let e = phi_d * c_phi + ed_n * c_e;
        let kappa = 1.0 - (-2.0 * sigmap_t * (dr + zr)).exp();
        ed += kappa * rhop * rhop * e;
    }
    ed / N as f32
}

/// Single scattering of the photon beam diffusion profile at radius r.
fn beam_diffusion_ss(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    const N: usize = 100;
    let sigma_t = sigma_a + sigma_s;
    let rho = sigma_s / sigma_t;
    let t_crit = r * (eta * eta - 1.0).max(0.0).sqrt();
    let mut ess = 0.0;
    for i in 0..N {
        let ti = t_crit + sample_exponential((i as f32 + 0.5) / N as f32, sigma_t);
        let d = (r * r + ti * ti).sqrt();
        let cos_o = ti / d;
        ess += rho * (-sigma_t * (d + t_crit)).exp() / (d * d)
            * henyey_greenstein(cos_o, g)
            * (1.0 - fr_dielectric(-cos_o, eta))
            * cos_o.abs();
    }
    ess / N as f32
}

/// ∫ of the Catmull-Rom spline through (x, f) (pbrt-v4's `IntegrateCatmullRom`).
fn integrate_catmull_rom(x: &[f32], f: &[f32]) -> f32 {
    let mut sum = 0.0;
    for i in 0..x.len() - 1 {
        let (x0, x1, f0, f1) = (x[i], x[i + 1], f[i], f[i + 1]);
        let width = x1 - x0;
        let d0 = if i > 0 { width * (f1 - f[i - 1]) / (x1 - x[i - 1]) } else { f1 - f0 };
        let d1 = if i + 2 < x.len() { width * (f[i + 2] - f0) / (x[i + 2] - x0) } else { f1 - f0 };
        sum += ((d0 - d1) * (1.0 / 12.0) + (f0 + f1) * 0.5) * width;
    }
    sum
}

/// The x where the Catmull-Rom spline through (nodes, f) — increasing — reaches u (pbrt-v4's
/// `InvertCatmullRom`, solved here by bisection on the segment).
fn invert_catmull_rom(nodes: &[f32], f: &[f32], u: f32) -> f32 {
    if u <= f[0] {
        return nodes[0];
    }
    if u >= f[f.len() - 1] {
        return nodes[nodes.len() - 1];
    }
    let i = f.partition_point(|&v| v <= u).saturating_sub(1).min(f.len() - 2);
    let (x0, x1, f0, f1) = (nodes[i], nodes[i + 1], f[i], f[i + 1]);
    let width = x1 - x0;
    let d0 = if i > 0 { width * (f1 - f[i - 1]) / (x1 - nodes[i - 1]) } else { f1 - f0 };
    let d1 = if i + 2 < nodes.len() { width * (f[i + 2] - f0) / (nodes[i + 2] - x0) } else { f1 - f0 };
    let spline = |t: f32| {
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * f0 + (-2.0 * t3 + 3.0 * t2) * f1 + (t3 - 2.0 * t2 + t) * d0 + (t3 - t2) * d1
    };
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if spline(mid) < u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    x0 + 0.5 * (lo + hi) * width
}

impl DiffusionTable {
    /// pbrt-v4's `ComputeBeamDiffusionBSSRDF` for asymmetry `g` and index of refraction `eta`
    /// (unit extinction; the radii scale with the mean free path).
    pub fn new(g: f32, eta: f32) -> DiffusionTable {
        let mut radius = vec![0.0f32; N_RADIUS];
        radius[1] = 2.5e-3;
        for i in 2..N_RADIUS {
            radius[i] = radius[i - 1] * 1.2;
        }
        let rho: Vec<f32> = (0..N_RHO)
            .map(|i| (1.0 - (-8.0 * i as f32 / (N_RHO - 1) as f32).exp()) / (1.0 - (-8.0f32).exp()))
            .collect();
        let rho_eff = rho
            .iter()
            .map(|&r| {
                let profile: Vec<f32> = radius
                    .iter()
                    .map(|&x| {
                        2.0 * PI
                            * x
                            * (beam_diffusion_ss(r, 1.0 - r, g, eta, x) + beam_diffusion_ms(r, 1.0 - r, g, eta, x))
                    })
                    .collect();
                integrate_catmull_rom(&radius, &profile)
            })
            .collect();
        DiffusionTable { rho, rho_eff }
    }

    /// The total diffuse reflectance of single-scattering albedo `rho`.
    pub fn rho_eff(&self, rho: f32) -> f32 {
        // The table is fine enough that a linear lookup serves the tests that use it.
        let i = self.rho.partition_point(|&r| r <= rho).clamp(1, N_RHO - 1);
        let t = (rho - self.rho[i - 1]) / (self.rho[i] - self.rho[i - 1]);
        self.rho_eff[i - 1] + t * (self.rho_eff[i] - self.rho_eff[i - 1])
    }

    /// pbrt-v4's `SubsurfaceFromDiffuse` for one channel: (σa, σs) with total diffuse
    /// reflectance `reflectance` and mean free path `mfp` (σt = 1/mfp).
    pub fn coefficients(&self, reflectance: f32, mfp: f32) -> (f32, f32) {
        let rho = self.albedo(reflectance);
        ((1.0 - rho) / mfp, rho / mfp)
    }

    /// The single-scattering albedo ρ whose total diffuse reflectance ρ_eff is `reflectance`.
    #[inline]
    pub fn albedo(&self, reflectance: f32) -> f32 {
        invert_catmull_rom(&self.rho, &self.rho_eff, reflectance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effective_albedo_rises_with_albedo_and_inverts() {
        let t = DiffusionTable::new(0.0, 1.33);
        assert!(t.rho_eff.windows(2).all(|w| w[1] >= w[0]), "ρ_eff increases with ρ");
        // ρ_eff(0) = 0; at ρ = 1 the diffusion approximation overshoots 1 a little (1.02 for
        // η = 1.33), as pbrt-v4's table does.
        assert!(t.rho_eff[0].abs() < 1e-6 && t.rho_eff[N_RHO - 1] < 1.05 && t.rho_eff[N_RHO - 1] > 0.9);
        for target in [0.05f32, 0.2, 0.5, 0.8] {
            let (sa, ss) = t.coefficients(target, 2.0);
            assert!(((sa + ss) - 0.5).abs() < 1e-6, "σt = 1/mfp");
            let rho = ss / (sa + ss);
            assert!((t.rho_eff(rho) - target).abs() < 0.01, "ρ_eff({rho}) = {} vs {target}", t.rho_eff(rho));
        }
        // Out of range: the ends of the table.
        assert_eq!(t.coefficients(0.0, 1.0), (1.0, 0.0));
    }

    #[test]
    fn catmull_rom_integrates_and_inverts_a_line_exactly() {
        let x = [0.0, 0.5, 1.0, 2.0];
        let f = [0.0, 1.0, 2.0, 4.0];
        assert!((integrate_catmull_rom(&x, &f) - 4.0).abs() < 1e-5);
        assert!((invert_catmull_rom(&x, &f, 3.0) - 1.5).abs() < 1e-4);
    }
}
