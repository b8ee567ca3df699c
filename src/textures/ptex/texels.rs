//! Texels in their file's type (Ptex's half float among them) and the library's box
//! reductions of them, with its rounding.

use super::file::{DataType, Res};

/// Ptex's half float, kept as its bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Half(pub u16);

impl Half {
    /// The value (exact).
    #[inline]
    pub fn to_f32(self) -> f32 {
        let h = self.0 as u32;
        let sign = (h & 0x8000) << 16;
        let e = h & 0x7c00;
        let m = h & 0x03ff;
        if e == 0 {
            let v = m as f32 * 5.960_464_5e-8;
            if sign != 0 { -v } else { v }
        } else if e == 0x7c00 {
            f32::from_bits(sign | 0x7f80_0000 | (m << 13))
        } else {
            f32::from_bits(sign | ((e + 0x1_c000) | m) << 13)
        }
    }

    /// `v` rounded as Ptex rounds (`PtexHalf::fromFloat`: half-way cases up in magnitude).
    pub fn from_f32(v: f32) -> Half {
        if v == 0.0 {
            return Half(0);
        }
        let i = v.to_bits();
        let s = (i >> 16) & 0x8000;
        let exp = ((i >> 23) & 0xff) as i32 - 112;
        if (1..31).contains(&exp) {
            return Half((s + ((exp as u32) << 10) + (((i & 0x7f_ffff) + 0x1000) >> 13)) as u16);
        }
        if exp <= 0 {
            // Subnormal (or below): rounded to the nearest multiple of 2⁻²⁴.
            return Half((s | (v.abs() * 1.677_721_6e7 + 0.5) as u32) as u16);
        }
        if ((i >> 23) & 0xff) == 0xff {
            Half((s | 0x7c00 | ((i & 0x7f_ffff) >> 13)) as u16)
        } else {
            Half((s | 0x7c00) as u16)
        }
    }
}

/// Texels in their file's type.
#[derive(Clone, Debug, PartialEq)]
pub enum Texels {
    /// 8-bit.
    U8(Box<[u8]>),
    /// 16-bit.
    U16(Box<[u16]>),
    /// Half.
    Half(Box<[Half]>),
    /// Float.
    F32(Box<[f32]>),
}

/// A stored type that can be read as f32 (unscaled: 8-bit 255 reads 255).
pub trait Texel: Copy {
    /// The value.
    fn value(self) -> f32;
}

impl Texel for u8 {
    #[inline]
    fn value(self) -> f32 {
        self as f32
    }
}

impl Texel for u16 {
    #[inline]
    fn value(self) -> f32 {
        self as f32
    }
}

impl Texel for Half {
    #[inline]
    fn value(self) -> f32 {
        self.to_f32()
    }
}

impl Texel for f32 {
    #[inline]
    fn value(self) -> f32 {
        self
    }
}

/// `bytes` (little-endian, `dt`) as texels.
pub(super) fn texels_from(bytes: &[u8], dt: DataType) -> Texels {
    match dt {
        DataType::U8 => Texels::U8(bytes.into()),
        DataType::U16 => Texels::U16(bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect()),
        DataType::Half => Texels::Half(bytes.chunks_exact(2).map(|b| Half(u16::from_le_bytes([b[0], b[1]]))).collect()),
        DataType::F32 => {
            Texels::F32(bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect())
        }
    }
}

impl Texels {
    pub(super) fn len(&self) -> usize {
        match self {
            Texels::U8(t) => t.len(),
            Texels::U16(t) => t.len(),
            Texels::Half(t) => t.len(),
            Texels::F32(t) => t.len(),
        }
    }

    /// The first texel that is not a finite number (only float data can have one).
    pub(super) fn first_non_finite(&self) -> Option<usize> {
        match self {
            Texels::U8(_) | Texels::U16(_) => None,
            Texels::Half(t) => t.iter().position(|h| !h.to_f32().is_finite()),
            Texels::F32(t) => t.iter().position(|v| !v.is_finite()),
        }
    }

    /// Texel `i` as f32 (unscaled).
    pub fn value(&self, i: usize) -> f32 {
        match self {
            Texels::U8(t) => t[i].value(),
            Texels::U16(t) => t[i].value(),
            Texels::Half(t) => t[i].value(),
            Texels::F32(t) => t[i].value(),
        }
    }

    /// Premultiplies the colour channels by alpha as the library does on reading
    /// (`PtexUtils::multalpha`: in the stored type, truncating integers).
    pub(super) fn multiply_alpha(&mut self, channels: usize, alpha: usize, one: f32) {
        fn go<T: Copy>(t: &mut [T], channels: usize, alpha: usize, scale: f32, get: fn(T) -> f32, put: fn(f32) -> T) {
            let (first, n, a) = if alpha == 0 { (1, channels - 1, 0) } else { (0, alpha, alpha) };
            for px in t.chunks_exact_mut(channels) {
                let aval = scale * get(px[a]);
                for v in &mut px[first..first + n] {
                    *v = put(get(*v) * aval);
                }
            }
        }
        let scale = 1.0 / one;
        match self {
            Texels::U8(t) => go(t, channels, alpha, scale, |v| v as f32, |v| v as u8),
            Texels::U16(t) => go(t, channels, alpha, scale, |v| v as f32, |v| v as u16),
            Texels::Half(t) => go(t, channels, alpha, scale, Half::to_f32, Half::from_f32),
            Texels::F32(t) => go(t, channels, alpha, scale, |v| v, |v| v),
        }
    }
}

/// Halves a face along u (`half_u`) or v, averaging texel pairs in the stored type as the
/// library does (`PtexUtils::reduceu`/`reducev`: integers truncate, halves round).
pub(super) fn reduce(src: &Texels, res: Res, channels: usize, half_u: bool) -> Texels {
    fn go<T: Copy>(src: &[T], res: Res, channels: usize, half_u: bool, avg: fn(T, T) -> T) -> Box<[T]> {
        let (uw, vw) = (res.u() as usize, res.v() as usize);
        let (nu, nv) = if half_u { (uw / 2, vw) } else { (uw, vw / 2) };
        let mut out = Vec::with_capacity(nu * nv * channels);
        for y in 0..nv {
            for x in 0..nu {
                for c in 0..channels {
                    let (a, b) = if half_u {
                        ((y * uw + 2 * x) * channels + c, (y * uw + 2 * x + 1) * channels + c)
                    } else {
                        ((2 * y * uw + x) * channels + c, ((2 * y + 1) * uw + x) * channels + c)
                    };
                    out.push(avg(src[a], src[b]));
                }
            }
        }
        out.into()
    }
    match src {
        Texels::U8(t) => Texels::U8(go(t, res, channels, half_u, |a, b| ((a as u32 + b as u32) >> 1) as u8)),
        Texels::U16(t) => Texels::U16(go(t, res, channels, half_u, |a, b| ((a as u32 + b as u32) >> 1) as u16)),
        Texels::Half(t) => {
            Texels::Half(go(t, res, channels, half_u, |a, b| Half::from_f32(0.5 * (a.to_f32() + b.to_f32()))))
        }
        Texels::F32(t) => Texels::F32(go(t, res, channels, half_u, |a, b| 0.5 * (a + b))),
    }
}

/// Halves a triangle face of `w`×`w` texels (the library's `PtexUtils::reduceTri`): each new
/// texel averages the even texels (2y, 2x), (2y, 2x + 1), (2y + 1, 2x) and the odd one
/// stored at (w − 1 − 2x, w − 1 − 2y), in the stored type.
pub(super) fn reduce_triangle(src: &Texels, w: usize, channels: usize) -> Texels {
    fn go<T: Copy>(src: &[T], w: usize, channels: usize, avg: fn(T, T, T, T) -> T) -> Box<[T]> {
        let h = w / 2;
        let at = |row: usize, col: usize, c: usize| src[(row * w + col) * channels + c];
        let mut out = Vec::with_capacity(h * h * channels);
        for y in 0..h {
            for x in 0..h {
                for c in 0..channels {
                    out.push(avg(
                        at(2 * y, 2 * x, c),
                        at(2 * y, 2 * x + 1, c),
                        at(2 * y + 1, 2 * x, c),
                        at(w - 1 - 2 * x, w - 1 - 2 * y, c),
                    ));
                }
            }
        }
        out.into()
    }
    match src {
        Texels::U8(t) => {
            Texels::U8(go(t, w, channels, |a, b, c, d| ((a as u32 + b as u32 + c as u32 + d as u32) >> 2) as u8))
        }
        Texels::U16(t) => {
            Texels::U16(go(t, w, channels, |a, b, c, d| ((a as u32 + b as u32 + c as u32 + d as u32) >> 2) as u16))
        }
        Texels::Half(t) => Texels::Half(go(t, w, channels, |a, b, c, d| {
            Half::from_f32(0.25 * (a.to_f32() + b.to_f32() + c.to_f32() + d.to_f32()))
        })),
        Texels::F32(t) => Texels::F32(go(t, w, channels, |a, b, c, d| 0.25 * (a + b + c + d))),
    }
}

/// Planar channels (each a plane of `n` texels) to interleaved texels.
pub(super) fn interleave<T: Copy>(planar: &[T], n: usize, channels: usize) -> Box<[T]> {
    (0..n * channels).map(|i| planar[(i % channels) * n + i / channels]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Half conversions as the library makes them: exact to f32, and back rounding half-way
    /// cases up in magnitude; subnormals, infinities and overflow included.
    #[test]
    fn half_floats_round_as_ptex_rounds() {
        for bits in (0u16..0x7c00).step_by(7).chain([0x0001, 0x03ff, 0x0400, 0x7bff]) {
            let v = Half(bits).to_f32();
            assert_eq!(Half::from_f32(v), Half(bits), "{bits:#x}");
            assert_eq!(Half::from_f32(-v), Half(bits | if v == 0.0 { 0 } else { 0x8000 }));
        }
        assert_eq!(Half(0x3c00).to_f32(), 1.0);
        // 1 + 2⁻¹¹ lies half-way between 1 and the next half: up.
        assert_eq!(Half::from_f32(1.0 + 2f32.powi(-11)), Half(0x3c01));
        assert_eq!(Half::from_f32(1e6), Half(0x7c00));
        assert_eq!(Half(0x7c00).to_f32(), f32::INFINITY);
    }
}
