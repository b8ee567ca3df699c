//! Material settings with pbrt-v4's parameter names and defaults. Materials nimbus lacks are
//! reported by name and stand in as gray diffuse.

use nimbus_parser::{Entity, Error, Warning};

use super::values::{
    FloatInput, SpectrumInput, SpectrumSpec, checked_float, checked_int, float_input, spectrum, spectrum_input,
};

/// Microfacet roughness along u and v, possibly textured.
#[derive(Clone, Debug, PartialEq)]
pub struct Roughness {
    /// Roughness along u.
    pub u: FloatInput,
    /// Roughness along v.
    pub v: FloatInput,
    /// Map perceptual roughness to the Trowbridge-Reitz alpha (pbrt-v4's `remaproughness`).
    pub remap: bool,
}

/// A conductor's optical constants.
#[derive(Clone, Debug, PartialEq)]
pub enum ConductorSpec {
    /// Complex index of refraction.
    EtaK {
        /// Real part.
        eta: SpectrumInput,
        /// Imaginary part (absorption).
        k: SpectrumInput,
    },
    /// Reflectance at normal incidence (eta/k derived from it).
    Reflectance(SpectrumInput),
}

/// A dielectric's index of refraction.
#[derive(Clone, Debug, PartialEq)]
pub enum Eta {
    /// A constant index.
    Constant(f32),
    /// A spectrally varying index (named glass or samples).
    Spectrum(SpectrumSpec),
}

/// What a material is.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// `diffuse`
    Diffuse {
        /// Albedo.
        reflectance: SpectrumInput,
    },
    /// `conductor`
    Conductor {
        /// Optical constants.
        spec: ConductorSpec,
        /// Roughness.
        roughness: Roughness,
    },
    /// `dielectric`
    Dielectric {
        /// Index of refraction.
        eta: Eta,
        /// Roughness.
        roughness: Roughness,
    },
    /// `thindielectric`
    ThinDielectric {
        /// Index of refraction.
        eta: Eta,
    },
    /// `interface`: marks a medium boundary; scatters nothing.
    Interface,
    /// `coateddiffuse`: a dielectric coating over a diffuse base.
    CoatedDiffuse {
        /// Base albedo.
        reflectance: SpectrumInput,
        /// Coating roughness.
        roughness: Roughness,
        /// Coating thickness.
        thickness: FloatInput,
        /// Coating index of refraction.
        eta: Eta,
        /// Albedo of the medium between coating and base.
        albedo: SpectrumInput,
        /// Asymmetry of that medium.
        g: FloatInput,
        /// Random-walk depth of the layered evaluation.
        max_depth: u32,
        /// Samples per evaluation.
        n_samples: u32,
    },
    /// A material nimbus lacks, rendered as gray diffuse.
    Unsupported(String),
}

/// Everything a material entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSettings {
    /// The material.
    pub kind: MaterialKind,
}

fn roughness(e: &Entity) -> Result<Roughness, Error> {
    let p = &e.params;
    let r = float_input(p, "roughness")?.unwrap_or(FloatInput::Value(0.0));
    let u = float_input(p, "uroughness")?.unwrap_or_else(|| r.clone());
    let v = float_input(p, "vroughness")?.unwrap_or_else(|| r.clone());
    for (name, x) in [("uroughness", &u), ("vroughness", &v)] {
        if let FloatInput::Value(x) = x
            && *x < 0.0
        {
            return Err(Error::new(
                p.loc(name).or(p.loc("roughness")).unwrap_or(&e.loc),
                "roughness cannot be negative",
            ));
        }
    }
    Ok(Roughness { u, v, remap: p.get_one_bool("remaproughness", true)? })
}

fn eta(e: &Entity, default: f32) -> Result<Eta, Error> {
    let p = &e.params;
    // pbrt-v4 accepts "float eta" or "spectrum eta".
    if let Some(peek) = p.peek("eta")
        && peek.ty != nimbus_parser::ParamType::Float
    {
        return Ok(Eta::Spectrum(spectrum(p, "eta")?.expect("peeked")));
    }
    let v = checked_float(p, "eta", default, |v| v > 0.0, "the index of refraction must be positive")?;
    Ok(Eta::Constant(v))
}

fn gray(v: f32) -> SpectrumInput {
    SpectrumInput::Value(SpectrumSpec::Rgb([v, v, v]))
}

impl MaterialSettings {
    /// Reads a material entity. Unknown types give a warning naming them and gray diffuse.
    pub fn from_entity(e: &Entity, warnings: &mut Vec<Warning>) -> Result<MaterialSettings, Error> {
        let p = &e.params;
        if let Some(d) = p.get_texture("displacement")? {
            return Err(Error::new(
                p.loc("displacement").unwrap_or(&e.loc),
                format!("displacement (texture \"{d}\") is not supported by nimbus"),
            ));
        }
        if let Some(n) = p.get_opt_string("normalmap")? {
            return Err(Error::new(
                p.loc("normalmap").unwrap_or(&e.loc),
                format!("normal maps (\"{n}\") are not supported by nimbus"),
            ));
        }
        let kind = match e.name.as_str() {
            "diffuse" => {
                MaterialKind::Diffuse { reflectance: spectrum_input(p, "reflectance")?.unwrap_or_else(|| gray(0.5)) }
            }
            "conductor" => {
                let spec = match spectrum_input(p, "reflectance")? {
                    Some(r) => ConductorSpec::Reflectance(r),
                    None => ConductorSpec::EtaK {
                        eta: spectrum_input(p, "eta")?
                            .unwrap_or_else(|| SpectrumInput::Value(SpectrumSpec::Named("metal-Cu-eta".into()))),
                        k: spectrum_input(p, "k")?
                            .unwrap_or_else(|| SpectrumInput::Value(SpectrumSpec::Named("metal-Cu-k".into()))),
                    },
                };
                MaterialKind::Conductor { spec, roughness: roughness(e)? }
            }
            "dielectric" => MaterialKind::Dielectric { eta: eta(e, 1.5)?, roughness: roughness(e)? },
            "thindielectric" => MaterialKind::ThinDielectric { eta: eta(e, 1.5)? },
            "interface" | "" | "none" => MaterialKind::Interface,
            "coateddiffuse" => MaterialKind::CoatedDiffuse {
                reflectance: spectrum_input(p, "reflectance")?.unwrap_or_else(|| gray(0.5)),
                roughness: roughness(e)?,
                thickness: float_input(p, "thickness")?.unwrap_or(FloatInput::Value(0.01)),
                eta: eta(e, 1.5)?,
                albedo: spectrum_input(p, "albedo")?.unwrap_or_else(|| gray(0.0)),
                g: float_input(p, "g")?.unwrap_or(FloatInput::Value(0.0)),
                max_depth: checked_int(p, "maxdepth", 10, |v| v > 0, "must be positive")? as u32,
                n_samples: checked_int(p, "nsamples", 1, |v| v > 0, "must be positive")? as u32,
            },
            other => {
                warnings.push(Warning::new(
                    &e.loc,
                    format!("material \"{other}\" is not supported by nimbus; rendering it as gray diffuse"),
                ));
                MaterialKind::Unsupported(other.to_string())
            }
        };
        Ok(MaterialSettings { kind })
    }
}
