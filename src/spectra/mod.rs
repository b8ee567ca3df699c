//! Spectral data and the conversions from pbrt-v4's spectral inputs to the RGB nimbus
//! renders with.
//!
//! pbrt-v4 is spectral; nimbus transports linear RGB in the film's color space. Each
//! spectral input a scene can hold — `rgb`, `blackbody`, inline `spectrum` samples, named
//! spectra and `.spd` files — is converted once, with pbrt-v4's meaning for its role:
//! [`reflectance_rgb`] for albedos and coefficients, [`illuminant_rgb`] for photometrically
//! normalised lights, [`emission_rgb`] / [`BlackbodyRgbTable`] for emission pbrt-v4 leaves
//! unnormalised, [`conductor_rgb`] for metals and [`dielectric_eta`] for glass. The measured
//! tables live in `data/` (provenance in `data/README.md`).

mod blackbody;
mod cie;
mod colorspace;
mod conductor;
mod convert;
mod error;
mod named;
mod piecewise;
mod sampled;
mod sensor;
mod sigmoid;
pub mod spec;
mod spectrum;
mod value;

pub use blackbody::{BlackbodyRgbTable, BlackbodySpectrum, blackbody_emission_rgb, planck};
pub use cie::{CIE_Y_INTEGRAL, LAMBDA_MAX, LAMBDA_MIN, cie_xyz_bar, integrate_xyz, integrate_y};
pub use colorspace::{RgbColorSpace, convert_reflectance_rgb, convert_rgb, rgb_color_space};
pub use conductor::{
    ConductorFit, conductor_fresnel, conductor_fresnel_rgb, conductor_rgb, fit_conductor, projected_conductor_fresnel,
};
pub use convert::{
    DIELECTRIC_ETA_WAVELENGTH, dielectric_eta, emission_rgb, illuminant_rgb, reflectance_rgb, spectrum_emission_rgb,
    spectrum_illuminant_rgb, spectrum_reflectance_rgb, spectrum_to_photometric, srgb_of_spectrum,
};
pub use error::SpectrumError;
pub use named::{is_named_spectrum, named_spectrum, named_spectrum_names};
pub use piecewise::PiecewiseLinearSpectrum;
pub use sampled::{
    N_SPECTRUM_SAMPLES, SampledSpectrum, SampledWavelengths, sample_visible_wavelength, visible_wavelength_pdf,
};
pub use sensor::{PixelSensor, camera_sensors, daylight_spectrum, white_balance};
pub use sigmoid::{SigmoidPolynomial, SigmoidTable, fit_sigmoid};
pub use spectrum::{ResolvedSpectrum, Spectrum, resolve, resolve_spectral};
pub use value::{DenseSpectrum, RgbRole, Sampled, SpectrumValue, illuminant_table};
