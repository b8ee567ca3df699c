//! The spectra a scene gives, resolved into [`SpectrumValue`]s for its film and transport,
//! each with pbrt-v4's meaning for its role: reflectances and coefficients, lights
//! (photometrically normalised), indices of refraction and conductor optical constants.
//! Every value carries both forms: the RGB that RGB transport multiplies and the spectrum
//! that spectral transport samples — pbrt-v4's `RGBAlbedoSpectrum`, `RGBUnboundedSpectrum`
//! and `RGBIlluminantSpectrum` for `rgb` inputs, the tabulated spectrum otherwise.

use nimbus_parser::ColorSpace;

use super::materials::Eta;
use crate::color::Rgb;
use crate::spectra::spec::SpectrumSpec;
use crate::spectra::{
    CIE_Y_INTEGRAL, DenseSpectrum, PixelSensor, ResolvedSpectrum, RgbRole, Sampled, SpectrumError, SpectrumValue,
    conductor_rgb, dielectric_eta, fit_sigmoid, illuminant_rgb, illuminant_table, reflectance_rgb, resolve,
    spectrum_to_photometric,
};

/// A conductor's optical constants ready for rendering.
pub(crate) struct ConductorValues {
    /// η.
    pub eta: SpectrumValue,
    /// k.
    pub k: SpectrumValue,
    /// Per-channel factor on the Fresnel term (1 except where an RGB fit needs it).
    pub scale: SpectrumValue,
}

/// Resolves scene spectra for a film in color space `film` with sensor `sensor`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpectrumResolver<'a> {
    /// The film's color space.
    pub film: ColorSpace,
    /// The film's sensor: RGB transport converts each emitted spectrum through it once.
    pub sensor: &'a PixelSensor,
}

/// pbrt-v4's `RGBUnboundedSpectrum`: the smooth spectrum of rgb / (2 max), scaled by 2 max.
fn unbounded_rgb(rgb: Rgb, cs: ColorSpace) -> (f32, crate::spectra::SigmoidPolynomial) {
    let m = rgb.max_element().max(0.0);
    let scale = 2.0 * m;
    let rel = if scale > 0.0 { (rgb / scale).max(Rgb::ZERO) } else { Rgb::ZERO };
    (scale, fit_sigmoid(cs, rel.to_array()))
}

/// The spectrum of a non-RGB input, tabulated.
fn dense(s: &crate::spectra::Spectrum, scale: f64) -> Sampled {
    Sampled::dense(DenseSpectrum::intern(|l| s.eval(l)), scale as f32)
}

impl SpectrumResolver<'_> {
    /// A reflectance or albedo given in color space `cs`.
    pub fn albedo(&self, spec: &SpectrumSpec, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        let rgb = reflectance_rgb(spec, cs, self.film)?;
        let sampled = match resolve(spec)? {
            ResolvedSpectrum::Rgb(c) => Sampled::sigmoid(fit_sigmoid(cs, c.clamp(Rgb::ZERO, Rgb::ONE).to_array()), 1.0),
            ResolvedSpectrum::Spectral(s) => dense(&s, 1.0),
        };
        Ok(SpectrumValue { rgb, sampled })
    }

    /// An unbounded coefficient (σa, σs, η, k) given in color space `cs`.
    pub fn unbounded(&self, spec: &SpectrumSpec, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        let rgb = reflectance_rgb(spec, cs, self.film)?;
        Ok(SpectrumValue { rgb, sampled: self.unbounded_sampled(spec, cs)? })
    }

    fn unbounded_sampled(&self, spec: &SpectrumSpec, cs: ColorSpace) -> Result<Sampled, SpectrumError> {
        Ok(match resolve(spec)? {
            ResolvedSpectrum::Rgb(c) => {
                let (scale, poly) = unbounded_rgb(c, cs);
                Sampled::sigmoid(poly, scale)
            }
            ResolvedSpectrum::Spectral(s) => dense(&s, 1.0),
        })
    }

    /// A light's emission, normalised photometrically as pbrt-v4 normalises lights (its
    /// `scale /= SpectrumToPhotometric(L)`): film RGB `rgb` for an `rgb` input, luminance 1
    /// for a spectrum.
    pub fn illuminant(&self, spec: &SpectrumSpec, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        let sampled = match resolve(spec)? {
            ResolvedSpectrum::Rgb(c) => {
                let (scale, poly) = unbounded_rgb(c, cs);
                // An RGB light's photometric normalisation is its illuminant's: ∫ȳ.
                Sampled::Illuminant { poly, scale: scale / CIE_Y_INTEGRAL as f32, illuminant: illuminant_table(cs) }
            }
            ResolvedSpectrum::Spectral(s) => {
                let y = spectrum_to_photometric(&s);
                if y.is_nan() || y <= 0.0 { Sampled::Constant(0.0) } else { dense(&s, 1.0 / y) }
            }
        };
        Ok(SpectrumValue { rgb: self.emission_rgb(spec, cs, &sampled)?, sampled })
    }

    /// The film RGB of emission `sampled` (given as `spec`) for RGB transport: exact for `rgb`
    /// and spectra under the `cie1931` sensor without white balance (the RGB passes through),
    /// and through the sensor's curves and matrix otherwise.
    fn emission_rgb(&self, spec: &SpectrumSpec, cs: ColorSpace, sampled: &Sampled) -> Result<Rgb, SpectrumError> {
        if self.sensor.is_passthrough() {
            illuminant_rgb(spec, cs, self.film)
        } else {
            Ok(self.sensor.film_rgb(|l| f64::from(sampled.eval(l as f32))))
        }
    }

    /// Film RGB of a per-texel or per-voxel emitted `rgb` in color space `cs` for RGB
    /// transport (through the sensor unless it passes RGB through).
    pub fn emitted_texel(&self, rgb: Rgb, cs: ColorSpace) -> Rgb {
        if self.sensor.is_passthrough() {
            crate::spectra::convert_rgb(rgb, cs, self.film)
        } else {
            let s = crate::channels::rgb_spectrum(rgb, RgbRole::Illuminant, cs);
            self.sensor.film_rgb(|l| f64::from(s.eval(l as f32)))
        }
    }

    /// An index of refraction: a constant, or a spectrum (dispersion; spectral transport
    /// follows the path's first wavelength, RGB reads it at 550 nm).
    pub fn eta(&self, eta: &Eta, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        Ok(match eta {
            Eta::Constant(v) => SpectrumValue::constant(*v),
            Eta::Spectrum(s) => {
                SpectrumValue { rgb: Rgb::splat(dielectric_eta(s, cs)?), sampled: self.unbounded_sampled(s, cs)? }
            }
        })
    }

    /// A conductor's η and k: for RGB the fit that reproduces the spectral Fresnel
    /// reflectance, for spectral transport the spectra themselves.
    pub fn conductor(
        &self,
        eta: &SpectrumSpec,
        k: &SpectrumSpec,
        cs: ColorSpace,
    ) -> Result<ConductorValues, SpectrumError> {
        let fit = conductor_rgb(eta, k, cs, self.film)?;
        Ok(ConductorValues {
            eta: SpectrumValue { rgb: fit.eta, sampled: self.unbounded_sampled(eta, cs)? },
            k: SpectrumValue { rgb: fit.k, sampled: self.unbounded_sampled(k, cs)? },
            scale: SpectrumValue { rgb: fit.scale, sampled: Sampled::Constant(1.0) },
        })
    }

    /// A per-voxel σ of an `rgbgrid` given in color space `cs`, as the medium stores it.
    pub fn grid_coefficient(&self, rgb: Rgb, cs: ColorSpace) -> Rgb {
        crate::spectra::convert_reflectance_rgb(rgb, cs, self.film)
    }
}
