//! atan2 as Cephes' atanf computes it: one reduction to |x| ≤ tan(π/8) and a degree-9 odd
//! polynomial, within 2.4e-7 rad (an ulp of π) of libm, without libm's call and special-case handling. The
//! guide's directional trees map every candidate direction to the square by its azimuth,
//! where glibc's atanf was 9 % of a guided render.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// atan(x) for x ≥ 0 (Cephes atanf).
#[inline]
fn atan_pos(x: f32) -> f32 {
    let (base, x) = if x > 2.414_213_6 {
        (FRAC_PI_2, -1.0 / x)
    } else if x > 0.414_213_57 {
        (FRAC_PI_4, (x - 1.0) / (x + 1.0))
    } else {
        (0.0, x)
    };
    let z = x * x;
    base + ((((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * x + x)
}

/// The angle of (x, y) in (−π, π], as `f32::atan2` (0 for the origin).
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    if x == 0.0 {
        return if y > 0.0 {
            FRAC_PI_2
        } else if y < 0.0 {
            -FRAC_PI_2
        } else {
            0.0
        };
    }
    let a = atan_pos((y / x).abs());
    match (x > 0.0, y >= 0.0) {
        (true, true) => a,
        (true, false) => -a,
        (false, true) => PI - a,
        (false, false) => a - PI,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within an ulp of π (2.4e-7 rad) of libm's atan2 all around the circle and at many radii, with libm's
    /// values on the axes.
    #[test]
    fn matches_libm() {
        let mut worst = 0.0f32;
        for i in 0..200_000 {
            let t = i as f32 / 200_000.0 * 2.0 * PI - PI;
            for r in [1e-6f32, 0.3, 1.0, 7.0, 1e5] {
                let (y, x) = (r * t.sin(), r * t.cos());
                let (got, want) = (atan2(y, x), y.atan2(x));
                let d = (got - want).abs();
                // ±π are the same angle.
                worst = worst.max(d.min((d - 2.0 * PI).abs()));
            }
        }
        assert!(worst <= 2.5e-7, "worst difference {worst}");
        for (y, x) in [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0), (0.0, 0.0), (-0.0, 1.0)] {
            assert_eq!(atan2(y, x), f32::atan2(y, x), "({y}, {x})");
        }
    }
}
