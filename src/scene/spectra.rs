//! The spectra a scene gives, resolved into [`SpectrumValue`]s for its film and transport,
//! each with pbrt-v4's meaning for its role: reflectances and coefficients, lights
//! (photometrically normalised), unnormalised emission, indices of refraction and conductor
//! optical constants.

use nimbus_parser::ColorSpace;

use super::materials::Eta;
use super::values::SpectrumSpec;
use crate::color::Rgb;
use crate::spectra::{SpectrumError, SpectrumValue, conductor_rgb, dielectric_eta, illuminant_rgb, reflectance_rgb};

/// A conductor's optical constants ready for rendering.
pub(crate) struct ConductorValues {
    /// η.
    pub eta: SpectrumValue,
    /// k.
    pub k: SpectrumValue,
    /// Per-channel factor on the Fresnel term (1 except where an RGB fit needs it).
    pub scale: SpectrumValue,
}

/// Resolves scene spectra for a film in color space `film`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpectrumResolver {
    /// The film's color space.
    pub film: ColorSpace,
}

impl SpectrumResolver {
    /// A reflectance or albedo given in color space `cs`.
    pub fn albedo(&self, spec: &SpectrumSpec, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        Ok(SpectrumValue::from_rgb(reflectance_rgb(spec, cs, self.film)?))
    }

    /// An unbounded coefficient (σa, σs) given in color space `cs`.
    pub fn unbounded(&self, spec: &SpectrumSpec, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        Ok(SpectrumValue::from_rgb(reflectance_rgb(spec, cs, self.film)?))
    }

    /// A light's emission, normalised photometrically as pbrt-v4 normalises lights.
    pub fn illuminant(&self, spec: &SpectrumSpec, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        Ok(SpectrumValue::from_rgb(illuminant_rgb(spec, cs, self.film)?))
    }

    /// An index of refraction.
    pub fn eta(&self, eta: &Eta, cs: ColorSpace) -> Result<SpectrumValue, SpectrumError> {
        Ok(match eta {
            Eta::Constant(v) => SpectrumValue::constant(*v),
            Eta::Spectrum(s) => SpectrumValue::constant(dielectric_eta(s, cs)?),
        })
    }

    /// A conductor's η and k.
    pub fn conductor(
        &self,
        eta: &SpectrumSpec,
        k: &SpectrumSpec,
        cs: ColorSpace,
    ) -> Result<ConductorValues, SpectrumError> {
        let fit = conductor_rgb(eta, k, cs, self.film)?;
        Ok(ConductorValues {
            eta: SpectrumValue::from_rgb(fit.eta),
            k: SpectrumValue::from_rgb(fit.k),
            scale: SpectrumValue::from_rgb(fit.scale),
        })
    }

    /// A per-voxel σ of an `rgbgrid` given in color space `cs`, as the medium stores it.
    pub fn grid_coefficient(&self, rgb: Rgb, cs: ColorSpace) -> Rgb {
        crate::spectra::convert_reflectance_rgb(rgb, cs, self.film)
    }

    /// A per-voxel Le of an `rgbgrid` given in color space `cs`, as the medium stores it
    /// (pbrt-v4 does not normalise it).
    pub fn grid_emission(&self, rgb: Rgb, cs: ColorSpace) -> Rgb {
        crate::spectra::convert_rgb(rgb, cs, self.film) * crate::spectra::CIE_Y_INTEGRAL as f32
    }
}
