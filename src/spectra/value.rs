//! [`SpectrumValue`]: a spectral quantity of the scene (an albedo, a coefficient, an emitted
//! radiance), resolved once at scene building into what each transport evaluates.

use crate::color::Rgb;

/// A scene spectrum ready for rendering: its RGB in the film's color space, as RGB transport
/// multiplies it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectrumValue {
    /// The value for RGB transport.
    pub rgb: Rgb,
}

impl SpectrumValue {
    /// Zero at every wavelength.
    pub const ZERO: SpectrumValue = SpectrumValue { rgb: Rgb::ZERO };

    /// The constant spectrum `v`.
    pub fn constant(v: f32) -> SpectrumValue {
        SpectrumValue { rgb: Rgb::splat(v) }
    }

    /// A value given by its RGB.
    pub fn from_rgb(rgb: Rgb) -> SpectrumValue {
        SpectrumValue { rgb }
    }

    /// The value times `s`.
    pub fn scaled(self, s: f32) -> SpectrumValue {
        SpectrumValue { rgb: self.rgb * s }
    }

    /// True when the spectrum is the same at every wavelength.
    pub fn is_constant(&self) -> bool {
        crate::color::is_gray(self.rgb)
    }

    /// True when the spectrum is zero everywhere.
    pub fn is_zero(&self) -> bool {
        self.rgb == Rgb::ZERO
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
