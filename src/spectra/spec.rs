//! Spectrum parameters as entities give them: inline, by name or from a file, or a named
//! spectrum texture; checked, not yet converted to the film's color space.

use std::path::PathBuf;

use nimbus_parser::{Error, ParameterDictionary, SpectrumOrTexture, SpectrumParam, SpectrumValue};

use super::is_named_spectrum;

/// A spectrum as the scene gives it, checked but not yet converted to the film's color space.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumSpec {
    /// RGB in the entity's color space.
    Rgb([f32; 3]),
    /// Normalised blackbody at a temperature in Kelvin.
    Blackbody(f32),
    /// Piecewise-linear (wavelength nm, value) samples.
    Samples(Vec<[f32; 2]>),
    /// One of pbrt-v4's named spectra.
    Named(String),
    /// A file of (wavelength, value) samples.
    File(PathBuf),
}

impl SpectrumSpec {
    /// Checks a spectrum parameter: values are non-negative, names are known or files exist.
    pub fn from_param(p: SpectrumParam<'_>, name: &str) -> Result<SpectrumSpec, Error> {
        Ok(match p.value {
            SpectrumValue::Rgb(rgb) => {
                if rgb.iter().any(|c| *c < 0.0) {
                    return Err(Error::new(p.loc, format!("rgb \"{name}\" has a negative component")));
                }
                SpectrumSpec::Rgb(rgb)
            }
            SpectrumValue::Blackbody(t) => {
                if t <= 0.0 {
                    return Err(Error::new(
                        p.loc,
                        format!("blackbody \"{name}\": temperature must be positive, not {t}"),
                    ));
                }
                SpectrumSpec::Blackbody(t)
            }
            SpectrumValue::Samples(v) => SpectrumSpec::Samples(v.as_chunks::<2>().0.to_vec()),
            SpectrumValue::Named(s) if is_named_spectrum(s) => SpectrumSpec::Named(s.to_string()),
            SpectrumValue::Named(s) => {
                let path = p.loc.resolve(s);
                if !path.is_file() {
                    return Err(Error::new(
                        p.loc,
                        format!(
                            "spectrum \"{name}\": \"{s}\" is neither a named spectrum nor a readable file (tried {})",
                            nimbus_parser::loc_shown(&path)
                        ),
                    ));
                }
                SpectrumSpec::File(path)
            }
        })
    }

    /// True for a spectrum that is the same at every wavelength (a gray RGB).
    pub fn is_constant(&self) -> bool {
        matches!(self, SpectrumSpec::Rgb([r, g, b]) if r == g && g == b)
    }
}

/// A spectrum that may come from a texture.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumInput {
    /// A constant spectrum.
    Value(SpectrumSpec),
    /// The named spectrum texture.
    Texture(String),
}

/// Reads an optional spectrum parameter.
pub fn spectrum(params: &ParameterDictionary, name: &str) -> Result<Option<SpectrumSpec>, Error> {
    params.get_one_spectrum(name)?.map(|p| SpectrumSpec::from_param(p, name)).transpose()
}

/// Reads an optional spectrum-or-texture parameter.
pub fn spectrum_input(params: &ParameterDictionary, name: &str) -> Result<Option<SpectrumInput>, Error> {
    params
        .get_spectrum_or_texture(name)?
        .map(|s| match s {
            SpectrumOrTexture::Value(p) => SpectrumSpec::from_param(p, name).map(SpectrumInput::Value),
            SpectrumOrTexture::Texture(t, _) => Ok(SpectrumInput::Texture(t.to_string())),
        })
        .transpose()
}
