//! pbrt-v4's procedural `cloud` medium density: Perlin noise turbulence, perturbed for
//! wisps, falling off with height (Pharr et al., PBR 4th ed., §11.4.2).

use glam::Vec3;

use crate::math::noise::{dnoise, noise};

/// Parameters of the procedural cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cloud {
    /// Overall density.
    pub density: f32,
    /// Strength of the wisps.
    pub wispiness: f32,
    /// Noise frequency.
    pub frequency: f32,
}

impl Cloud {
    /// Density at the medium-space point `p`, in [0, 1] (pbrt-v4's default box is the unit
    /// cube, where the cloud thins out above y = 0.5).
    pub fn density_at(&self, p: Vec3) -> f32 {
        let mut pp = self.frequency * p;
        if self.wispiness > 0.0 {
            let (mut omega, mut lambda) = (0.05 * self.wispiness, 10.0);
            for _ in 0..2 {
                pp += omega * dnoise(lambda * pp);
                omega *= 0.5;
                lambda *= 1.99;
            }
        }
        let mut d = 0.0;
        let (mut omega, mut lambda) = (0.5, 1.0);
        for _ in 0..5 {
            d += omega * noise(lambda * pp);
            omega *= 0.5;
            lambda *= 1.99;
        }
        let d = ((1.0 - p.y) * 4.5 * self.density * d).clamp(0.0, 1.0) + 2.0 * (0.5 - p.y).max(0.0);
        d.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cloud_density_is_bounded() {
        let c = Cloud { density: 1.0, wispiness: 1.0, frequency: 5.0 };
        for i in 0..100 {
            let d = c.density_at(Vec3::new(0.5, i as f32 / 100.0, 0.3));
            assert!((0.0..=1.0).contains(&d));
        }
        // Below half height the cloud is dense by construction.
        assert!(c.density_at(Vec3::new(0.5, 0.0, 0.5)) == 1.0);
    }
}
