//! e^x and ln x on four lanes at once. Transmittance takes e^(−σt·d) of every channel on
//! every path segment and pbrt-v4's visible-wavelength sampling an inverse hyperbolic tangent
//! per wavelength; as one libm call per lane these were 10–13 % of a spectral render of a
//! chromatic medium (perf, rgbgrid-smoke). On x86-64 (SSE2, always present) the four lanes
//! are one polynomial (Cephes' `expf`/`logf`, within 2 ulp of libm); elsewhere they are four
//! libm calls.

use glam::Vec4;

/// e^x per lane: 0 below the smallest normal result, +∞ above the largest, NaN kept.
#[inline]
pub fn exp4(x: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE2 is part of the x86-64 baseline.
        unsafe { sse2::exp4(x) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec4::from_array(x.to_array().map(f32::exp))
    }
}

/// ln x per lane for positive normal x; other lanes (zero, negative, subnormal, ∞, NaN) get
/// libm's answer.
#[inline]
pub fn ln4(x: Vec4) -> Vec4 {
    let normal = x.cmpge(Vec4::splat(f32::MIN_POSITIVE)) & x.cmple(Vec4::splat(f32::MAX));
    if !normal.all() {
        return Vec4::from_array(x.to_array().map(f32::ln));
    }
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE2 is part of the x86-64 baseline.
        unsafe { sse2::ln4(x) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec4::from_array(x.to_array().map(f32::ln))
    }
}

#[cfg(target_arch = "x86_64")]
mod sse2 {
    use core::arch::x86_64::*;
    use glam::Vec4;

    /// ln 2 split in a part exact in few bits and the rest (Cody–Waite), so n·ln 2 is
    /// subtracted without rounding error.
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;

    #[inline]
    #[target_feature(enable = "sse2")]
    pub fn exp4(x: Vec4) -> Vec4 {
        // Below −103.97 every result rounds to 0 (so an opaque medium transmits exactly 0, as
        // with libm's e^(−∞)); above 88.72, +∞.
        let under = x.cmplt(Vec4::splat(-103.97));
        let over = x.cmpgt(Vec4::splat(88.722_84));
        let nan = x.is_nan_mask();
        let xc = x.clamp(Vec4::splat(-103.97), Vec4::splat(88.722_84));
        // x = n ln 2 + r with |r| ≤ ln 2 / 2: e^x = 2^n e^r.
        let n = _mm_cvtps_epi32((xc * std::f32::consts::LOG2_E).into());
        let nf = Vec4::from(_mm_cvtepi32_ps(n));
        let r = xc - nf * LN2_HI - nf * LN2_LO;
        let p = ((((Vec4::splat(1.987_569_2e-4) * r + 1.398_199_9e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
            + 0.166_666_65)
            * r
            + 0.5;
        let er = p * (r * r) + r + 1.0;
        // 2^n as 2^⌊n/2⌋ 2^(n − ⌊n/2⌋), each built from its exponent bits: n ∈ [−150, 128]
        // after the clamp, beyond one float's exponent range, while either half is within it
        // (and the product rounds into the subnormals as libm's result does).
        let pow2 =
            |k: __m128i| Vec4::from(_mm_castsi128_ps(_mm_slli_epi32::<23>(_mm_add_epi32(k, _mm_set1_epi32(127)))));
        let half = _mm_srai_epi32::<1>(n);
        let y = er * pow2(half) * pow2(_mm_sub_epi32(n, half));
        let y = Vec4::select(under, Vec4::ZERO, y);
        let y = Vec4::select(over, Vec4::INFINITY, y);
        Vec4::select(nan, x, y)
    }

    /// ln x for positive normal x (the caller checks).
    #[inline]
    #[target_feature(enable = "sse2")]
    pub fn ln4(x: Vec4) -> Vec4 {
        // x = m 2^e with m ∈ [√½, √2): ln x = e ln 2 + ln m, ln m by a polynomial in m − 1.
        let bits = _mm_castps_si128(x.into());
        let e = _mm_sub_epi32(_mm_srli_epi32::<23>(bits), _mm_set1_epi32(126));
        let m = Vec4::from(_mm_castsi128_ps(_mm_or_si128(
            _mm_and_si128(bits, _mm_set1_epi32(0x007f_ffff)),
            _mm_set1_epi32(0x3f00_0000),
        )));
        let mut e = Vec4::from(_mm_cvtepi32_ps(e));
        // m ∈ [½, 1) now; below √½ take 2m and one less in the exponent.
        let low = m.cmplt(Vec4::splat(std::f32::consts::FRAC_1_SQRT_2));
        e -= Vec4::select(low, Vec4::ONE, Vec4::ZERO);
        let t = m - 1.0 + Vec4::select(low, m, Vec4::ZERO);
        let z = t * t;
        let p = ((((((((Vec4::splat(7.037_683_6e-2) * t - 1.151_461e-1) * t + 1.167_699_9e-1) * t
            - 1.242_014_1e-1)
            * t
            + 1.424_932_3e-1)
            * t
            - 1.666_805_8e-1)
            * t
            + 2.000_071_4e-1)
            * t
            - 2.499_999_4e-1)
            * t
            + 3.333_333e-1)
            * t
            * z;
        let y = p + e * LN2_LO - z * 0.5;
        t + y + e * LN2_HI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place.
    fn ulps(a: f32, b: f32) -> u32 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs() as u32
    }

    #[test]
    fn exp4_matches_libm_within_two_ulp() {
        let mut worst = 0;
        for i in 0..200_000 {
            let x = -87.3 + 176.0 * i as f32 / 200_000.0;
            let got = exp4(Vec4::new(x, -x * 0.5, x * 1e-3, x * 1e-7));
            for (g, xi) in got.to_array().into_iter().zip([x, -x * 0.5, x * 1e-3, x * 1e-7]) {
                let want = xi.exp();
                if want >= f32::MIN_POSITIVE && want.is_finite() {
                    worst = worst.max(ulps(g, want));
                }
            }
        }
        assert!(worst <= 2, "worst {worst} ulp");
    }

    #[test]
    fn exp4_edges() {
        let got = exp4(Vec4::new(f32::NEG_INFINITY, -200.0, 0.0, 100.0));
        assert_eq!(got.to_array(), [0.0, 0.0, 1.0, f32::INFINITY]);
        let got = exp4(Vec4::new(f32::NAN, f32::INFINITY, -0.0, 1.0));
        assert!(got.x.is_nan());
        assert_eq!([got.y, got.z], [f32::INFINITY, 1.0]);
        assert!(ulps(got.w, std::f32::consts::E) <= 1);
    }

    #[test]
    fn ln4_matches_libm_within_two_ulp() {
        let mut worst = 0;
        for i in 0..200_000 {
            let x = 1e-3 + 20.0 * i as f32 / 200_000.0;
            let xs = [x, 1.0 / x, x * 1e30, x * 1e-30];
            let got = ln4(Vec4::from_array(xs));
            for (g, xi) in got.to_array().into_iter().zip(xs) {
                let want = xi.ln();
                // Relative to the result's size, or to ln's own rounding near x = 1.
                if want.abs() > 1e-3 {
                    worst = worst.max(ulps(g, want));
                } else {
                    assert!((g - want).abs() < 1e-9, "ln {xi}: {g} vs {want}");
                }
            }
        }
        assert!(worst <= 2, "worst {worst} ulp");
    }

    #[test]
    fn ln4_outside_its_polynomial_domain_is_libm() {
        let got = ln4(Vec4::new(0.0, -1.0, 1e-40, 2.0));
        assert_eq!(got.x, f32::NEG_INFINITY);
        assert!(got.y.is_nan());
        assert_eq!(got.z, 1e-40f32.ln());
        assert_eq!(got.w, 2.0f32.ln());
    }
}
