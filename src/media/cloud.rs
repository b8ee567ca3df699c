//! pbrt-v4's procedural `cloud` medium density: Perlin noise turbulence, perturbed for
//! wisps, falling off with height (Pharr et al., PBR 4th ed., §11.4.2).

use glam::Vec3;

/// Ken Perlin's reference permutation for improved noise (SIGGRAPH 2002).
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37, 240,
    21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88,
    237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83,
    111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216,
    80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186,
    3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17,
    182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129,
    22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238,
    210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184,
    84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195,
    78, 66, 215, 61, 156, 180,
];

#[inline]
fn perm(i: i32) -> i32 {
    PERM[(i & 255) as usize] as i32
}

#[inline]
fn grad(x: i32, y: i32, z: i32, d: Vec3) -> f32 {
    let h = perm(perm(perm(x) + y) + z) & 15;
    let u = if h < 8 || h == 12 || h == 13 { d.x } else { d.y };
    let v = if h < 4 || h == 12 || h == 13 { d.y } else { d.z };
    (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
}

#[inline]
fn weight(t: f32) -> f32 {
    let t3 = t * t * t;
    6.0 * t3 * t * t - 15.0 * t3 * t + 10.0 * t3
}

/// Perlin's improved gradient noise, in [-1, 1].
pub fn noise(p: Vec3) -> f32 {
    let f = p.floor();
    let d = p - f;
    let (ix, iy, iz) = (f.x as i32, f.y as i32, f.z as i32);
    let w = |x: i32, y: i32, z: i32| grad(ix + x, iy + y, iz + z, d - Vec3::new(x as f32, y as f32, z as f32));
    let (wx, wy, wz) = (weight(d.x), weight(d.y), weight(d.z));
    let lerp = |t: f32, a: f32, b: f32| (1.0 - t) * a + t * b;
    let x00 = lerp(wx, w(0, 0, 0), w(1, 0, 0));
    let x10 = lerp(wx, w(0, 1, 0), w(1, 1, 0));
    let x01 = lerp(wx, w(0, 0, 1), w(1, 0, 1));
    let x11 = lerp(wx, w(0, 1, 1), w(1, 1, 1));
    lerp(wz, lerp(wy, x00, x10), lerp(wy, x01, x11))
}

/// Gradient of [`noise`] by forward differences.
fn dnoise(p: Vec3) -> Vec3 {
    const DELTA: f32 = 0.01;
    let n = noise(p);
    Vec3::new(noise(p + Vec3::X * DELTA) - n, noise(p + Vec3::Y * DELTA) - n, noise(p + Vec3::Z * DELTA) - n) / DELTA
}

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
    /// Density at `p` in [0, 1]³ of the medium's box, in [0, 1].
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
    fn noise_is_zero_on_lattice_points_and_bounded() {
        assert_eq!(noise(Vec3::new(1.0, 2.0, 3.0)), 0.0);
        for i in 0..1000 {
            let p = Vec3::new(i as f32 * 0.137, i as f32 * 0.071, i as f32 * 0.029);
            assert!(noise(p).abs() <= 1.0);
        }
        let c = Cloud { density: 1.0, wispiness: 1.0, frequency: 5.0 };
        for i in 0..100 {
            let d = c.density_at(Vec3::new(0.5, i as f32 / 100.0, 0.3));
            assert!((0.0..=1.0).contains(&d));
        }
        // Below half height the cloud is dense by construction.
        assert!(c.density_at(Vec3::new(0.5, 0.0, 0.5)) == 1.0);
    }
}
