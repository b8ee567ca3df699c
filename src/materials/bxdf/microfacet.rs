//! The anisotropic Trowbridge-Reitz (GGX) microfacet distribution with visible-normal
//! sampling (pbrt-v4 §9.6, `TrowbridgeReitzDistribution` in `util/scattering.h`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::math::{abs_cos_theta, sqr};

/// cos²θ of a local direction.
#[inline]
pub(super) fn cos2_theta(w: Vec3) -> f32 {
    w.z * w.z
}

/// sin²θ of a local direction.
#[inline]
pub(super) fn sin2_theta(w: Vec3) -> f32 {
    (1.0 - cos2_theta(w)).max(0.0)
}

/// tan²θ of a local direction (infinite at grazing angles).
#[inline]
pub(super) fn tan2_theta(w: Vec3) -> f32 {
    sin2_theta(w) / cos2_theta(w)
}

/// cos φ of a local direction (1 along the normal).
#[inline]
pub(super) fn cos_phi(w: Vec3) -> f32 {
    let sin_theta = sin2_theta(w).sqrt();
    if sin_theta == 0.0 { 1.0 } else { (w.x / sin_theta).clamp(-1.0, 1.0) }
}

/// sin φ of a local direction (0 along the normal).
#[inline]
pub(super) fn sin_phi(w: Vec3) -> f32 {
    let sin_theta = sin2_theta(w).sqrt();
    if sin_theta == 0.0 { 0.0 } else { (w.y / sin_theta).clamp(-1.0, 1.0) }
}

/// `v` flipped, if needed, into the hemisphere of `reference` (pbrt-v4's `FaceForward`).
#[inline]
pub(super) fn face_forward(v: Vec3, reference: Vec3) -> Vec3 {
    if v.dot(reference) < 0.0 { -v } else { v }
}

/// Uniform point on the unit disk by the polar mapping (pbrt-v4's `SampleUniformDiskPolar`).
#[inline]
fn uniform_disk_polar(u: Vec2) -> Vec2 {
    let r = u.x.sqrt();
    let theta = 2.0 * PI * u.y;
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Anisotropic Trowbridge-Reitz distribution of microfacet normals with roughness α along
/// the local x and y axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    alpha_x: f32,
    alpha_y: f32,
}

impl TrowbridgeReitz {
    /// A distribution with the given α. Unless the surface is effectively smooth, both α are
    /// kept ≥ 1e-4 so D's ellipse term stays finite (as pbrt-v4's constructor does).
    pub fn new(alpha_x: f32, alpha_y: f32) -> TrowbridgeReitz {
        let mut d = TrowbridgeReitz { alpha_x, alpha_y };
        if !d.effectively_smooth() {
            d.alpha_x = d.alpha_x.max(1e-4);
            d.alpha_y = d.alpha_y.max(1e-4);
        }
        d
    }

    /// A distribution from a material's `uroughness`/`vroughness`, mapped through
    /// [`TrowbridgeReitz::roughness_to_alpha`] when `remap` (pbrt-v4's `remaproughness`).
    pub fn from_roughness(u_roughness: f32, v_roughness: f32, remap: bool) -> TrowbridgeReitz {
        if remap {
            TrowbridgeReitz::new(Self::roughness_to_alpha(u_roughness), Self::roughness_to_alpha(v_roughness))
        } else {
            TrowbridgeReitz::new(u_roughness, v_roughness)
        }
    }

    /// pbrt-v4's perceptual roughness mapping, α = √roughness (kept as shipped; see
    /// pbrt-v4 issue #479).
    #[inline]
    pub fn roughness_to_alpha(roughness: f32) -> f32 {
        roughness.sqrt()
    }

    /// α along x.
    #[inline]
    pub fn alpha_x(&self) -> f32 {
        self.alpha_x
    }

    /// α along y.
    #[inline]
    pub fn alpha_y(&self) -> f32 {
        self.alpha_y
    }

    /// True when both α are below 1e-3: the surface is treated as a perfect specular one.
    #[inline]
    pub fn effectively_smooth(&self) -> bool {
        self.alpha_x.max(self.alpha_y) < 1e-3
    }

    /// Microfacet normal density D(ωm) of the anisotropic Trowbridge-Reitz (GGX) model.
    #[inline]
    pub fn d(&self, wm: Vec3) -> f32 {
        let tan2 = tan2_theta(wm);
        if tan2.is_infinite() {
            return 0.0;
        }
        let cos4 = sqr(cos2_theta(wm));
        if cos4 < 1e-16 {
            return 0.0;
        }
        let e = tan2 * (sqr(cos_phi(wm) / self.alpha_x) + sqr(sin_phi(wm) / self.alpha_y));
        1.0 / (PI * self.alpha_x * self.alpha_y * cos4 * sqr(1.0 + e))
    }

    /// Smith's auxiliary function Λ(ω) = (√(1 + α(ω)² tan²θ) − 1)/2 with the anisotropic
    /// α(ω)² = α_x² cos²φ + α_y² sin²φ (Heitz 2014, "Understanding the Masking-Shadowing
    /// Function in Microfacet-Based BRDFs").
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let tan2 = tan2_theta(w);
        if tan2.is_infinite() {
            return 0.0;
        }
        let alpha2 = sqr(cos_phi(w) * self.alpha_x) + sqr(sin_phi(w) * self.alpha_y);
        ((1.0 + alpha2 * tan2).sqrt() - 1.0) / 2.0
    }

    /// Smith masking function G1(ω) = 1/(1 + Λ(ω)).
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G(ωo, ωi) = 1/(1 + Λ(ωo) + Λ(ωi)) (Heitz 2014).
    #[inline]
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Distribution of normals visible from `w`, D_ω(ωm) = G1(ω)/|cos θ| · D(ωm) · |ω·ωm|
    /// (pbrt-v4 §9.6; pbrt-v4's two-argument `D(w, wm)`).
    #[inline]
    pub fn d_visible(&self, w: Vec3, wm: Vec3) -> f32 {
        self.g1(w) / abs_cos_theta(w) * self.d(wm) * w.dot(wm).abs()
    }

    /// Density of [`TrowbridgeReitz::sample_wm`]: the visible-normal distribution.
    #[inline]
    pub fn pdf(&self, w: Vec3, wm: Vec3) -> f32 {
        self.d_visible(w, wm)
    }

    /// Samples a microfacet normal visible from `w` (Heitz 2018, "Sampling the GGX
    /// Distribution of Visible Normals"; pbrt-v4 §9.6). The normal is always in the +z
    /// hemisphere, and facing `w` when `w` is too, or facing −`w` when `w` is below.
    pub fn sample_wm(&self, w: Vec3, u: Vec2) -> Vec3 {
        // Stretch w to the hemispherical (α = 1) configuration.
        let mut wh = Vec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        // Orthonormal basis around wh.
        let t1 = if wh.z < 0.99999 { Vec3::Z.cross(wh).normalize() } else { Vec3::X };
        let t2 = wh.cross(t1);
        // Uniform disk point, warped to the projection of the visible hemisphere.
        let mut p = uniform_disk_polar(u);
        let h = (1.0 - sqr(p.x)).sqrt();
        let s = (1.0 + wh.z) / 2.0;
        p.y = (1.0 - s) * h + s * p.y;
        // Reproject onto the hemisphere and unstretch.
        let pz = (1.0 - p.length_squared()).max(0.0).sqrt();
        let nh = p.x * t1 + p.y * t2 + pz * wh;
        Vec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(1e-6)).normalize()
    }

    /// Roughens a near-specular distribution for path regularization: each α below 0.3
    /// becomes clamp(2α, 0.1, 0.3) (pbrt-v4's `Regularize`).
    pub fn regularize(&mut self) {
        if self.alpha_x < 0.3 {
            self.alpha_x = (2.0 * self.alpha_x).clamp(0.1, 0.3);
        }
        if self.alpha_y < 0.3 {
            self.alpha_y = (2.0 * self.alpha_y).clamp(0.1, 0.3);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::bxdf::testing::{integrate_sphere, stratified_2d};

    fn distributions() -> [TrowbridgeReitz; 4] {
        [
            TrowbridgeReitz::new(0.1, 0.1),
            TrowbridgeReitz::new(0.3, 0.3),
            TrowbridgeReitz::new(0.8, 0.8),
            TrowbridgeReitz::new(0.15, 0.6),
        ]
    }

    #[test]
    fn projected_normal_density_integrates_to_one() {
        // ∫ D(ωm) cos θm dωm = 1: the projected microfacet area is the macro surface's.
        for d in distributions() {
            let v = integrate_sphere(1024, 512, |wm| if wm.z > 0.0 { (d.d(wm) * wm.z) as f64 } else { 0.0 });
            assert!((v - 1.0).abs() < 2e-3, "{d:?}: {v}");
        }
    }

    #[test]
    fn visible_normals_integrate_to_one() {
        // ∫ D_ω(ωm) dωm = 1 for every ω, from above and below (the Smith G1 normalizes it).
        for d in distributions() {
            for w in [
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(0.5, 0.3, 0.81).normalize(),
                Vec3::new(-0.9, 0.2, 0.15).normalize(),
                Vec3::new(0.3, -0.6, -0.5).normalize(),
            ] {
                let v = integrate_sphere(1024, 512, |wm| {
                    if wm.z > 0.0 && wm.dot(w) * w.z > 0.0 { d.d_visible(w, wm) as f64 } else { 0.0 }
                });
                assert!((v - 1.0).abs() < 3e-3, "{d:?} {w}: {v}");
            }
        }
    }

    #[test]
    fn sampled_normals_have_the_visible_normal_mean() {
        // E[ωm] under sample_wm equals ∫ ωm D_ω(ωm) dωm, compared per component.
        for d in distributions() {
            let w = Vec3::new(0.6, -0.2, 0.5).normalize();
            let mut mean = Vec3::ZERO.as_dvec3();
            let n = 256;
            for u in stratified_2d(n) {
                let wm = d.sample_wm(w, u);
                assert!(wm.z > 0.0 && (wm.length() - 1.0).abs() < 1e-4);
                assert!(wm.dot(w) > -1e-4, "sampled a back-facing normal");
                mean += wm.as_dvec3();
            }
            mean /= (n * n) as f64;
            let expected = glam::DVec3::new(
                integrate_sphere(512, 512, |m| vis(&d, w, m) * m.x as f64),
                integrate_sphere(512, 512, |m| vis(&d, w, m) * m.y as f64),
                integrate_sphere(512, 512, |m| vis(&d, w, m) * m.z as f64),
            );
            assert!((mean - expected).abs().max_element() < 2e-3, "{d:?}: {mean} vs {expected}");
        }
    }

    fn vis(d: &TrowbridgeReitz, w: Vec3, m: Vec3) -> f64 {
        if m.z > 0.0 && m.dot(w) > 0.0 { d.d_visible(w, m) as f64 } else { 0.0 }
    }

    #[test]
    fn smoothness_regularization_and_remap() {
        assert!(TrowbridgeReitz::new(0.0, 0.0).effectively_smooth());
        assert!(TrowbridgeReitz::new(9e-4, 5e-4).effectively_smooth());
        let a = TrowbridgeReitz::new(0.0, 0.5);
        assert!(!a.effectively_smooth());
        assert_eq!((a.alpha_x(), a.alpha_y()), (1e-4, 0.5));
        let mut r = TrowbridgeReitz::new(0.0, 0.0);
        r.regularize();
        assert_eq!((r.alpha_x(), r.alpha_y()), (0.1, 0.1));
        let mut r = TrowbridgeReitz::new(0.12, 0.5);
        r.regularize();
        assert_eq!((r.alpha_x(), r.alpha_y()), (0.24, 0.5));
        let m = TrowbridgeReitz::from_roughness(0.04, 0.25, true);
        assert!((m.alpha_x() - 0.2).abs() < 1e-6 && (m.alpha_y() - 0.5).abs() < 1e-6);
        let m = TrowbridgeReitz::from_roughness(0.04, 0.25, false);
        assert_eq!((m.alpha_x(), m.alpha_y()), (0.04, 0.25));
    }

    #[test]
    fn masking_is_one_at_normal_incidence_and_g_is_symmetric() {
        let d = TrowbridgeReitz::new(0.3, 0.7);
        assert_eq!(d.g1(Vec3::Z), 1.0);
        let (a, b) = (Vec3::new(0.3, 0.4, 0.5).normalize(), Vec3::new(-0.7, 0.1, 0.2).normalize());
        assert_eq!(d.g(a, b), d.g(b, a));
        assert!(d.g(a, b) <= d.g1(a).min(d.g1(b)));
    }
}
