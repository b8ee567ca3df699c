//! Directional radiance per node for anisotropic media (beyond the thesis, its Sec. 6.1): real
//! spherical harmonics up to band 2, and the Henyey–Greenstein phase function in them.
//!
//! HG's Legendre expansion is p(μ) = Σ_l (2l + 1)/4π g^l P_l(μ) (μ the cosine between the
//! light's direction of travel and the scattered direction), and the addition theorem gives
//! P_l(d·ω) = 4π/(2l + 1) Σ_m Y_lm(d) Y_lm(ω). So light arriving along d and scattered at a
//! point has, as a function of the outgoing ω, the coefficients 4π g^l Y_lm(d) per unit of
//! arriving radiance (truncated at band 2): transport through an edge is a scale of the
//! basis at the edge's direction, with no quadrature.

use glam::Vec3;

/// Coefficients per node: bands 0, 1 and 2.
pub const COEFFS: usize = 9;

/// The real SH basis up to band 2 at unit direction `d` (order: l = 0; l = 1, m = −1, 0, 1;
/// l = 2, m = −2 … 2).
#[inline]
pub fn basis(d: Vec3) -> [f32; COEFFS] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        0.282_094_8,
        0.488_602_5 * y,
        0.488_602_5 * z,
        0.488_602_5 * x,
        1.092_548_4 * x * y,
        1.092_548_4 * y * z,
        0.315_391_57 * (3.0 * z * z - 1.0),
        1.092_548_4 * x * z,
        0.546_274_2 * (x * x - y * y),
    ]
}

/// 4π g^l per coefficient: HG's scattering of radiance arriving along d is
/// `band[k] · basis(d)[k]` in coefficient k.
pub fn bands(g: f32) -> [f32; COEFFS] {
    let four_pi = 4.0 * std::f32::consts::PI;
    let (g1, g2) = (four_pi * g, four_pi * g * g);
    [four_pi, g1, g1, g1, g2, g2, g2, g2, g2]
}

/// The SH function with coefficients `c` at direction `d`.
#[inline]
pub fn eval(c: &[f32], d: Vec3) -> f32 {
    c.iter().zip(basis(d)).map(|(a, b)| a * b).sum()
}

/// Henyey–Greenstein's density for scattering by angle θ, μ = cos θ between the direction
/// light travelled in and the one it leaves in (g > 0 scatters forward): pbrt-v4's phase
/// function, whose argument is the cosine between the outgoing direction and the one back
/// toward the light, −μ.
#[inline]
pub fn hg(mu: f32, g: f32) -> f32 {
    crate::media::phase::henyey_greenstein(-mu, g)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn directions() -> Vec<Vec3> {
        (0..40)
            .map(|i| {
                let (a, b) = (i as f32 * 0.731, i as f32 * 1.913);
                Vec3::new(a.sin() * b.cos(), a.sin() * b.sin(), a.cos()).normalize()
            })
            .collect()
    }

    /// The addition theorem: Σ_m Y_lm(d) Y_lm(ω) summed with 4π g^l is the truncated Legendre
    /// series Σ_l (2l + 1) g^l P_l(d·ω), for any pair of directions.
    #[test]
    fn coefficients_give_the_truncated_legendre_series() {
        let g = 0.6;
        for d in directions() {
            for w in directions() {
                let c: Vec<f32> = bands(g).iter().zip(basis(d)).map(|(b, y)| b * y).collect();
                let mu = d.dot(w);
                let want = 1.0 + 3.0 * g * mu + 5.0 * g * g * 0.5 * (3.0 * mu * mu - 1.0);
                assert!((eval(&c, w) - want).abs() < 1e-4, "{d} {w}");
            }
        }
    }

    /// In this convention HG integrates to 1 and its mean cosine is +g (forward scattering
    /// for g > 0; a midpoint rule over μ).
    #[test]
    fn hg_is_a_density_with_mean_cosine_g() {
        for g in [-0.5, 0.0, 0.6, 0.877] {
            let n = 200_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let mu = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                let p = f64::from(hg(mu as f32, g)) * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                total += p;
                mean += p * mu;
            }
            assert!((total - 1.0).abs() < 1e-3 && (mean - f64::from(g)).abs() < 1e-3, "{g}: {total} {mean}");
        }
    }
}
