//! [`SpectrumValue`]: a spectral quantity of the scene (an albedo, a coefficient, an emitted
//! radiance), resolved once at scene building into what each transport evaluates: its RGB
//! for RGB transport and a [`Sampled`] form for spectral transport.

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use glam::Vec4;

use super::SampledWavelengths;
use super::blackbody::normalized_planck4;
use super::sigmoid::SigmoidPolynomial;
use crate::color::Rgb;

/// Values of a spectrum at every integer wavelength from 360 to 830 nm, looked up with linear
/// interpolation (exact for the piecewise-linear spectra of `.spd` files and named tables
/// whose samples sit at whole nanometres, as pbrt-v4's do).
#[derive(Debug, PartialEq)]
pub struct DenseSpectrum {
    values: [f32; DENSE_LEN],
    max: f32,
}

const DENSE_MIN: f32 = 360.0;
const DENSE_LEN: usize = 471;

impl DenseSpectrum {
    /// `f` sampled at 360, 361, …, 830 nm, interned: equal tables are stored once for the
    /// life of the program, so scene values can refer to them by `&'static`.
    pub fn intern(f: impl Fn(f64) -> f64) -> &'static DenseSpectrum {
        let mut values = [0.0f32; DENSE_LEN];
        for (i, v) in values.iter_mut().enumerate() {
            *v = f(f64::from(DENSE_MIN) + i as f64) as f32;
        }
        static TABLES: OnceLock<Mutex<HashMap<Vec<u32>, &'static DenseSpectrum>>> = OnceLock::new();
        let key: Vec<u32> = values.iter().map(|v| v.to_bits()).collect();
        let mut tables = TABLES.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
        tables.entry(key).or_insert_with(|| {
            let max = values.iter().copied().fold(0.0f32, f32::max);
            Box::leak(Box::new(DenseSpectrum { values, max }))
        })
    }

    /// The value at `lambda` nm (zero outside 360–830 nm).
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        let x = lambda - DENSE_MIN;
        if !(0.0..=(DENSE_LEN - 1) as f32).contains(&x) {
            return 0.0;
        }
        let i = (x as usize).min(DENSE_LEN - 2);
        let t = x - i as f32;
        self.values[i] * (1.0 - t) + self.values[i + 1] * t
    }

    /// The values at the four wavelengths of `lambda`.
    #[inline]
    pub fn sample(&self, lambda: Vec4) -> Vec4 {
        Vec4::new(self.eval(lambda.x), self.eval(lambda.y), self.eval(lambda.z), self.eval(lambda.w))
    }

    /// The largest value.
    pub fn max_value(&self) -> f32 {
        self.max
    }

    /// True when every value is the same.
    pub fn is_constant(&self) -> bool {
        self.values.iter().all(|v| *v == self.values[0])
    }
}

/// A spectrum as spectral transport evaluates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sampled {
    /// The same value at every wavelength.
    Constant(f32),
    /// `scale` × a sigmoid polynomial: pbrt-v4's `RGBAlbedoSpectrum` (scale 1) and
    /// `RGBUnboundedSpectrum`.
    Sigmoid {
        /// The smooth spectrum of the RGB's chromaticity.
        poly: SigmoidPolynomial,
        /// Its scale.
        scale: f32,
    },
    /// `scale` × a sigmoid polynomial × the color space's illuminant: pbrt-v4's
    /// `RGBIlluminantSpectrum`.
    Illuminant {
        /// The smooth spectrum of the RGB's chromaticity.
        poly: SigmoidPolynomial,
        /// Its scale.
        scale: f32,
        /// The color space's standard illuminant.
        illuminant: &'static DenseSpectrum,
    },
    /// `scale` × a tabulated spectrum (named spectra, `.spd` files, inline samples).
    Dense {
        /// The table.
        table: &'static DenseSpectrum,
        /// Its scale.
        scale: f32,
    },
    /// `scale` × pbrt-v4's peak-normalised blackbody.
    Blackbody {
        /// Temperature in Kelvin.
        t: f32,
        /// The multiplier (the blackbody's own peak is 1).
        scale: f32,
    },
}

impl Sampled {
    /// `scale` × `poly`'s spectrum: a constant when the polynomial is one (a gray RGB has
    /// c₀ = c₁ = 0), holding exactly the value [`Sampled::sample`] gives at every wavelength,
    /// so a gray medium's coefficients cost no sigmoid per lookup.
    pub fn sigmoid(poly: SigmoidPolynomial, scale: f32) -> Sampled {
        if poly.is_constant() {
            Sampled::Constant(poly.eval4(Vec4::splat(550.0)).x * scale)
        } else {
            Sampled::Sigmoid { poly, scale }
        }
    }

    /// `scale` × `table`: a [`Sampled::Constant`] when the table holds one value (a spectrum
    /// given as `[200 1 900 1]`, as the published Disney cloud gives its σs), so that a lookup
    /// costs no interpolation at four wavelengths.
    pub fn dense(table: &'static DenseSpectrum, scale: f32) -> Sampled {
        if table.is_constant() { Sampled::Constant(table.values[0] * scale) } else { Sampled::Dense { table, scale } }
    }

    /// pbrt-v4's peak-normalised blackbody at `t` K (zero for non-positive temperatures).
    pub fn blackbody(t: f32) -> Sampled {
        Sampled::Blackbody { t, scale: if t > 0.0 { 1.0 } else { 0.0 } }
    }

    /// The values at the path's wavelengths.
    #[inline]
    pub fn sample(&self, lambda: &SampledWavelengths) -> Vec4 {
        match self {
            Sampled::Constant(c) => Vec4::splat(*c),
            Sampled::Sigmoid { poly, scale } => poly.eval4(lambda.lambda) * *scale,
            Sampled::Illuminant { poly, scale, illuminant } => {
                poly.eval4(lambda.lambda) * illuminant.sample(lambda.lambda) * *scale
            }
            Sampled::Dense { table, scale } => table.sample(lambda.lambda) * *scale,
            Sampled::Blackbody { t, scale } => normalized_planck4(lambda.lambda, *t) * *scale,
        }
    }

    /// The value at one wavelength.
    pub fn eval(&self, lambda: f32) -> f32 {
        let l = SampledWavelengths { lambda: Vec4::splat(lambda), pdf: Vec4::ONE };
        self.sample(&l).x
    }

    /// The spectrum times `s`.
    pub fn scaled(self, s: f32) -> Sampled {
        match self {
            Sampled::Constant(c) => Sampled::Constant(c * s),
            Sampled::Sigmoid { poly, scale } => Sampled::Sigmoid { poly, scale: scale * s },
            Sampled::Illuminant { poly, scale, illuminant } => {
                Sampled::Illuminant { poly, scale: scale * s, illuminant }
            }
            Sampled::Dense { table, scale } => Sampled::Dense { table, scale: scale * s },
            Sampled::Blackbody { t, scale } => Sampled::Blackbody { t, scale: scale * s },
        }
    }

    /// True when the spectrum has the same value at every wavelength.
    pub fn is_constant(&self) -> bool {
        match self {
            Sampled::Constant(_) => true,
            Sampled::Sigmoid { poly, scale } => *scale == 0.0 || poly.is_constant(),
            Sampled::Illuminant { scale, .. } | Sampled::Blackbody { scale, .. } => *scale == 0.0,
            Sampled::Dense { table, scale } => *scale == 0.0 || table.is_constant(),
        }
    }

    /// An upper bound on the spectrum's values (pbrt-v4's `MaxValue`).
    pub fn max_value(&self) -> f32 {
        match self {
            Sampled::Constant(c) => *c,
            Sampled::Sigmoid { poly, scale } => poly.max_value() * scale,
            Sampled::Illuminant { poly, scale, illuminant } => poly.max_value() * scale * illuminant.max_value(),
            Sampled::Dense { table, scale } => table.max_value() * scale,
            // The peak, at Wien's wavelength, is 1.
            Sampled::Blackbody { scale, .. } => *scale,
        }
    }
}

/// A scene spectrum ready for rendering: its RGB in the film's color space, as RGB transport
/// multiplies it, and its spectral form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectrumValue {
    /// The value for RGB transport.
    pub rgb: Rgb,
    /// The value for spectral transport.
    pub sampled: Sampled,
}

impl SpectrumValue {
    /// Zero at every wavelength.
    pub const ZERO: SpectrumValue = SpectrumValue { rgb: Rgb::ZERO, sampled: Sampled::Constant(0.0) };

    /// The constant spectrum `v`.
    pub fn constant(v: f32) -> SpectrumValue {
        SpectrumValue { rgb: Rgb::splat(v), sampled: Sampled::Constant(v) }
    }

    /// The value times `s`.
    pub fn scaled(self, s: f32) -> SpectrumValue {
        SpectrumValue { rgb: self.rgb * s, sampled: self.sampled.scaled(s) }
    }

    /// True when the spectrum is the same at every wavelength (and so RGB transport carries
    /// it exactly).
    pub fn is_constant(&self) -> bool {
        self.sampled.is_constant()
    }

    /// True when the spectrum is zero everywhere.
    pub fn is_zero(&self) -> bool {
        self.rgb == Rgb::ZERO && self.sampled.max_value() == 0.0
    }
}

/// The standard illuminant of color space `space` as a dense table (normalised as pbrt-v4's
/// named illuminants: Σ s(λ)ȳ(λ) = ∫ȳ).
pub fn illuminant_table(space: nimbus_parser::ColorSpace) -> &'static DenseSpectrum {
    static TABLES: OnceLock<[&'static DenseSpectrum; 4]> = OnceLock::new();
    let t = TABLES.get_or_init(|| {
        [
            nimbus_parser::ColorSpace::Srgb,
            nimbus_parser::ColorSpace::Rec2020,
            nimbus_parser::ColorSpace::Aces2065_1,
            nimbus_parser::ColorSpace::DciP3,
        ]
        .map(|s| {
            let cs = super::rgb_color_space(s);
            DenseSpectrum::intern(|l| cs.illuminant.eval(l))
        })
    });
    match space {
        nimbus_parser::ColorSpace::Srgb => t[0],
        nimbus_parser::ColorSpace::Rec2020 => t[1],
        nimbus_parser::ColorSpace::Aces2065_1 => t[2],
        nimbus_parser::ColorSpace::DciP3 => t[3],
    }
}

/// What an RGB triple stands for as a spectrum (pbrt-v4's `SpectrumType`): a reflectance in
/// [0, 1], an unbounded coefficient, or an emitted radiance relative to the color space's
/// illuminant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RgbRole {
    /// A reflectance or albedo (pbrt-v4's `RGBAlbedoSpectrum`).
    Albedo,
    /// A coefficient without bound, such as σa or η (pbrt-v4's `RGBUnboundedSpectrum`).
    Unbounded,
    /// Emitted radiance (pbrt-v4's `RGBIlluminantSpectrum`).
    Illuminant,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::sigmoid::fit_sigmoid;
    use nimbus_parser::ColorSpace;

    /// A gray RGB's spectrum becomes a constant with, at every wavelength, the very value the
    /// sigmoid gives; a colored one stays a sigmoid.
    #[test]
    fn gray_sigmoids_are_constants_with_the_same_values() {
        let lambda = SampledWavelengths { lambda: Vec4::new(360.0, 471.3, 612.9, 830.0), pdf: Vec4::ONE };
        for v in [0.0, 0.18, 0.5, 0.73, 1.0] {
            for scale in [1.0, 0.4, 24.0] {
                let poly = fit_sigmoid(ColorSpace::Srgb, [v; 3]);
                let s = Sampled::sigmoid(poly, scale);
                assert!(matches!(s, Sampled::Constant(_)), "{v}");
                assert_eq!(s.sample(&lambda), Sampled::Sigmoid { poly, scale }.sample(&lambda), "{v} × {scale}");
            }
        }
        let poly = fit_sigmoid(ColorSpace::Srgb, [0.2, 0.5, 0.7]);
        assert!(matches!(Sampled::sigmoid(poly, 2.0), Sampled::Sigmoid { .. }));
    }

    /// A flat tabulated spectrum becomes a constant equal, within an ulp of interpolation, to
    /// the table's value at every wavelength; a sloped one stays a table.
    #[test]
    fn flat_tables_are_constants() {
        let lambda = SampledWavelengths { lambda: Vec4::new(360.0, 471.3, 612.9, 830.0), pdf: Vec4::ONE };
        for v in [0.0, 0.2, 1.0, 7.5] {
            let table = DenseSpectrum::intern(|_| v);
            let s = Sampled::dense(table, 4.0);
            assert_eq!(s, Sampled::Constant(v as f32 * 4.0));
            let tabled = Sampled::Dense { table, scale: 4.0 }.sample(&lambda);
            for (a, b) in s.sample(&lambda).to_array().into_iter().zip(tabled.to_array()) {
                assert!((a - b).abs() <= f32::EPSILON * b.abs(), "{a} {b}");
            }
        }
        assert!(matches!(Sampled::dense(DenseSpectrum::intern(|l| l / 830.0), 1.0), Sampled::Dense { .. }));
    }
}
