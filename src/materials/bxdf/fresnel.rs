//! Fresnel reflectance of dielectric and conducting interfaces (pbrt-v4 §9.3,
//! `util/scattering.h`: `FrDielectric`, `FrComplex`).

use crate::channels::Channels;
use crate::math::{safe_sqrt, sqr};

/// Unpolarized Fresnel reflectance of a dielectric interface: the mean of the squared
/// parallel and perpendicular amplitude coefficients (pbrt-v4 §9.3, `FrDielectric`).
///
/// `eta` is η_t/η_i for light arriving from the +z side; a negative `cos_theta_i` means the
/// direction is on the −z side, so the interface is flipped (η → 1/η). Returns 1 under total
/// internal reflection.
#[inline]
pub fn fr_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    // Snell's law for cos θt.
    let sin2_i = 1.0 - sqr(cos_i);
    let sin2_t = sin2_i / sqr(eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (sqr(r_parl) + sqr(r_perp)) / 2.0
}

/// A complex number, just enough for the conductor Fresnel equations (pbrt-v4's
/// `pstd::complex`, whose `sqrt` branch choice this follows).
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    #[inline]
    fn new(re: f32, im: f32) -> Complex {
        Complex { re, im }
    }

    #[inline]
    fn real(re: f32) -> Complex {
        Complex { re, im: 0.0 }
    }

    #[inline]
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }

    #[inline]
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }

    #[inline]
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }

    #[inline]
    fn scale(self, s: f32) -> Complex {
        Complex::new(self.re * s, self.im * s)
    }

    #[inline]
    fn div(self, o: Complex) -> Complex {
        let scale = 1.0 / (o.re * o.re + o.im * o.im);
        Complex::new(scale * (self.re * o.re + self.im * o.im), scale * (self.im * o.re - self.re * o.im))
    }

    /// |z|².
    #[inline]
    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }

    /// Principal square root.
    #[inline]
    fn sqrt(self) -> Complex {
        let n = self.norm().sqrt();
        if n == 0.0 {
            return Complex::real(0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 { Complex::new(t1, t2) } else { Complex::new(t2.abs(), t1.copysign(self.im)) }
    }
}

/// Fresnel reflectance of a conductor with complex index of refraction η + i·k, for light
/// arriving from outside: the dielectric equations with a complex η and complex Snell's
/// law (pbrt-v4 §9.3, `FrComplex`). `cos_theta_i` is
/// clamped to [0, 1]. With k = 0 and η > 1 this equals [`fr_dielectric`].
#[inline]
pub fn fr_complex(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let eta = Complex::new(eta, k);
    let cos_i = cos_theta_i.clamp(0.0, 1.0);
    let sin2_i = 1.0 - sqr(cos_i);
    let sin2_t = Complex::real(sin2_i).div(eta.mul(eta));
    let cos_t = Complex::real(1.0).sub(sin2_t).sqrt();
    let eta_cos_i = eta.scale(cos_i);
    let r_parl = eta_cos_i.sub(cos_t).div(eta_cos_i.add(cos_t));
    let eta_cos_t = eta.mul(cos_t);
    let ci = Complex::real(cos_i);
    let r_perp = ci.sub(eta_cos_t).div(ci.add(eta_cos_t));
    (r_parl.norm() + r_perp.norm()) / 2.0
}

/// [`fr_complex`] per channel (RGB channel or wavelength).
#[inline]
pub fn fr_complex_channels<C: Channels>(cos_theta_i: f32, eta: C, k: C) -> C {
    eta.zip_map(k, |eta, k| fr_complex(cos_theta_i, eta, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_matches_known_values() {
        // Normal incidence: ((η-1)/(η+1))².
        assert!((fr_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fr_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything.
        assert!((fr_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        // Brewster's angle: the parallel component vanishes, R = r_perp²/2.
        let theta_b = 1.5f32.atan();
        let r = fr_dielectric(theta_b.cos(), 1.5);
        let (ci, ct) = (theta_b.cos(), (1.0 - theta_b.sin().powi(2) / 2.25).sqrt());
        let r_perp = (ci - 1.5 * ct) / (ci + 1.5 * ct);
        assert!((r - r_perp * r_perp / 2.0).abs() < 1e-6, "{r}");
        // Total internal reflection from inside beyond the critical angle (sin θc = 1/1.5).
        assert_eq!(fr_dielectric(-0.5, 1.5), 1.0);
        // Index matching: no reflection.
        assert!(fr_dielectric(0.3, 1.0).abs() < 1e-12);
    }

    #[test]
    fn complex_fresnel_reduces_to_dielectric_for_zero_k() {
        for eta in [1.2f32, 1.5, 2.4, 0.8, 0.5] {
            // cos θ at the critical angle (η < 1), where both have infinite slope.
            let critical = (1.0 - eta * eta).max(0.0).sqrt();
            for i in 0..=100 {
                let c = i as f32 / 100.0;
                if (c - critical).abs() < 0.02 {
                    continue;
                }
                let a = fr_complex(c, eta, 0.0);
                let b = fr_dielectric(c, eta);
                assert!((a - b).abs() < 2e-5, "eta {eta} cos {c}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn complex_fresnel_of_a_metal() {
        // Normal incidence: ((η-1)² + k²)/((η+1)² + k²). Gold-ish at 600 nm.
        let (eta, k) = (0.25f32, 3.0f32);
        let expected = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
        assert!((fr_complex(1.0, eta, k) - expected).abs() < 1e-5);
        assert!((fr_complex(0.0, eta, k) - 1.0).abs() < 1e-5);
        let rgb = fr_complex_channels(1.0, glam::Vec3::new(eta, 1.0, 1.5), glam::Vec3::new(k, 0.0, 0.0));
        assert!((rgb.x - expected).abs() < 1e-5 && rgb.y.abs() < 1e-6);
        assert!((rgb.z - 0.04).abs() < 1e-5);
    }
}
