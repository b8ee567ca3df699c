//! pbrt-v4's procedural noise (pbrt-v4 §10.6): Perlin's gradient noise, its gradient, and the
//! fractional Brownian motion and turbulence sums the procedural textures and the `cloud`
//! medium are built from.

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
pub fn dnoise(p: Vec3) -> Vec3 {
    const DELTA: f32 = 0.01;
    let n = noise(p);
    Vec3::new(noise(p + Vec3::X * DELTA) - n, noise(p + Vec3::Y * DELTA) - n, noise(p + Vec3::Z * DELTA) - n) / DELTA
}

/// pbrt-v4's `SmoothStep`.
fn smooth_step(x: f32, a: f32, b: f32) -> f32 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Octaves to sum for a lookup whose footprint has squared size `len2` (pbrt-v4 fades the
/// last octave in); with no footprint (nimbus traces no ray differentials) every octave.
fn octaves(len2: f32, max_octaves: u32) -> f32 {
    if len2 <= 0.0 {
        return max_octaves as f32;
    }
    (-1.0 - len2.log2() / 2.0).clamp(0.0, max_octaves as f32)
}

/// pbrt-v4's `FBm`: Σ ωⁱ·noise(1.99ⁱ·p) over the octaves the footprint allows.
pub fn fbm(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, max_octaves: u32) -> f32 {
    let n = octaves(dpdx.length_squared().max(dpdy.length_squared()), max_octaves);
    let n_int = n.floor() as u32;
    let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
    for _ in 0..n_int {
        sum += o * noise(lambda * p);
        lambda *= 1.99;
        o *= omega;
    }
    sum + o * smooth_step(n - n_int as f32, 0.3, 0.7) * noise(lambda * p)
}

/// pbrt-v4's `Turbulence`: Σ ωⁱ·|noise(1.99ⁱ·p)|, the unsummed octaves standing in by their
/// mean 0.2.
pub fn turbulence(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, max_octaves: u32) -> f32 {
    let n = octaves(dpdx.length_squared().max(dpdy.length_squared()), max_octaves);
    let n_int = n.floor() as u32;
    let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
    for _ in 0..n_int {
        sum += o * noise(lambda * p).abs();
        lambda *= 1.99;
        o *= omega;
    }
    // Fade the partial octave towards the average absolute noise.
    let n_partial = n - n_int as f32;
    sum += o * (0.2f32 + (noise(lambda * p).abs() - 0.2) * smooth_step(n_partial, 0.3, 0.7));
    for _ in n_int..max_octaves {
        sum += o * 0.2;
        o *= omega;
    }
    sum
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
    }

    #[test]
    fn fbm_and_turbulence_sum_their_octaves() {
        let p = Vec3::new(0.3, 1.7, -2.2);
        // Two full octaves of FBm are noise(p) + ω·noise(1.99 p) when the footprint allows
        // exactly two (log2 of its size −3, so n = 2: the third octave's share is 0).
        let d = Vec3::new(0.125, 0.0, 0.0);
        let two = fbm(p, d, d, 0.5, 8);
        assert!((two - (noise(p) + 0.5 * noise(1.99 * p))).abs() < 1e-6, "{two}");
        // Without a footprint every octave counts; turbulence is never negative.
        let all = fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 3);
        let by_hand = noise(p) + 0.5 * noise(1.99 * p) + 0.25 * noise(1.99 * 1.99 * p);
        assert!((all - by_hand).abs() < 1e-6);
        for i in 0..100 {
            assert!(turbulence(Vec3::splat(i as f32 * 0.31), Vec3::ZERO, Vec3::ZERO, 0.5, 6) >= 0.0);
        }
    }
}
