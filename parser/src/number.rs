//! Number parsing tuned for big meshes and grids: most tokens are short decimals, which a
//! fast path converts exactly (Clinger's algorithm: an integer mantissa below 2^53 scaled by
//! an exactly representable power of ten). Anything else goes through the standard library.

/// Powers of ten that are exact in an `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20,
    1e21, 1e22,
];

/// Parses a decimal floating-point number (`-1`, `2.5`, `.5`, `1e-3`, `+4.`). Rejects
/// infinities, NaN, hex and anything with trailing junk.
#[inline]
pub(crate) fn parse_f64(s: &[u8]) -> Option<f64> {
    let mut i = 0;
    let neg = match s.first()? {
        b'-' => {
            i = 1;
            true
        }
        b'+' => {
            i = 1;
            false
        }
        _ => false,
    };
    let mut mantissa: u64 = 0;
    let mut digits = 0u32; // significant digits accumulated into `mantissa`
    let mut any_digit = false;
    let mut exp10: i32 = 0;
    let mut exact = true;
    while i < s.len() && s[i].is_ascii_digit() {
        any_digit = true;
        if mantissa == 0 && s[i] == b'0' {
            // leading zeros are not significant
        } else if digits < 19 {
            mantissa = mantissa * 10 + u64::from(s[i] - b'0');
            digits += 1;
        } else {
            exact = false;
            exp10 += 1;
        }
        i += 1;
    }
    if i < s.len() && s[i] == b'.' {
        i += 1;
        while i < s.len() && s[i].is_ascii_digit() {
            any_digit = true;
            if mantissa == 0 && s[i] == b'0' {
                exp10 -= 1;
            } else if digits < 19 {
                mantissa = mantissa * 10 + u64::from(s[i] - b'0');
                digits += 1;
                exp10 -= 1;
            } else {
                exact = false;
            }
            i += 1;
        }
    }
    if !any_digit {
        return None;
    }
    if i < s.len() && (s[i] == b'e' || s[i] == b'E') {
        i += 1;
        let mut eneg = false;
        if i < s.len() && (s[i] == b'-' || s[i] == b'+') {
            eneg = s[i] == b'-';
            i += 1;
        }
        let mut e: i32 = 0;
        let mut any = false;
        while i < s.len() && s[i].is_ascii_digit() {
            any = true;
            e = e.saturating_mul(10).saturating_add(i32::from(s[i] - b'0'));
            i += 1;
        }
        if !any {
            return None;
        }
        exp10 = exp10.saturating_add(if eneg { -e } else { e });
    }
    if i != s.len() {
        return None;
    }
    let value = if exact && mantissa < (1u64 << 53) && (-22..=22).contains(&exp10) {
        let m = mantissa as f64;
        if exp10 >= 0 { m * POW10[exp10 as usize] } else { m / POW10[(-exp10) as usize] }
    } else {
        // Rare: long mantissas or large exponents. The syntax is already validated, so the
        // standard library's correctly rounded parser accepts it.
        std::str::from_utf8(s).ok()?.parse::<f64>().ok()?.abs()
    };
    Some(if neg { -value } else { value })
}

/// Why a token is not a 32-bit integer.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum IntError {
    /// Not of the form `[+-]digits`.
    NotInteger,
    /// Does not fit in 32 bits.
    Overflow,
}

/// Parses `[+-]digits` into an `i32`.
#[inline]
pub(crate) fn parse_i32(s: &[u8]) -> Result<i32, IntError> {
    let (neg, digits) = match s.first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    if digits.is_empty() {
        return Err(IntError::NotInteger);
    }
    let mut v: i64 = 0;
    for &c in digits {
        if !c.is_ascii_digit() {
            return Err(IntError::NotInteger);
        }
        v = v * 10 + i64::from(c - b'0');
        if v > i64::from(i32::MAX) + 1 {
            return Err(IntError::Overflow);
        }
    }
    let v = if neg { -v } else { v };
    i32::try_from(v).map_err(|_| IntError::Overflow)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_match_the_standard_library() {
        for s in [
            "0",
            "1",
            "-1",
            "+2",
            "0.5",
            ".5",
            "5.",
            "-0.25",
            "1e3",
            "1E-3",
            "2.5e+10",
            "123456789012345678901234",
            "0.000000000000000000000000001",
            "3.14159265358979323846264338327950288",
            "1e-400",
            "1e308",
            "00012.5000",
            "-0",
            "7e22",
            "7e23",
            "9007199254740993",
        ] {
            let expected: f64 = s.parse().unwrap();
            assert_eq!(parse_f64(s.as_bytes()), Some(expected), "{s}");
        }
    }

    #[test]
    fn rejects_non_numbers() {
        for s in ["", "-", ".", "e5", "1e", "1.2.3", "inf", "nan", "NaN", "0x10", "1,5", "--1", "1e+"] {
            assert_eq!(parse_f64(s.as_bytes()), None, "{s}");
        }
    }

    #[test]
    fn integers() {
        assert_eq!(parse_i32(b"42"), Ok(42));
        assert_eq!(parse_i32(b"-2147483648"), Ok(i32::MIN));
        assert_eq!(parse_i32(b"2147483648"), Err(IntError::Overflow));
        assert_eq!(parse_i32(b"1.5"), Err(IntError::NotInteger));
        assert_eq!(parse_i32(b"-"), Err(IntError::NotInteger));
    }
}
