//! Material settings with pbrt-v4's parameter names and defaults. Materials nimbus lacks are
//! reported by name and stand in as gray diffuse.

use nimbus_parser::{Entity, Error, Warning};

use crate::params::{FloatInput, checked_float, checked_int, float_input};
use crate::spectra::spec::{SpectrumInput, SpectrumSpec, spectrum, spectrum_input};

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

/// How a `hair` material gives its absorption (pbrt-v4's three ways, in priority order).
#[derive(Clone, Debug, PartialEq)]
pub enum HairAbsorptionSpec {
    /// `sigma_a` directly.
    SigmaA(SpectrumInput),
    /// `reflectance` (or `color`), inverted to σa.
    Reflectance(SpectrumInput),
    /// Melanin concentrations (default: eumelanin 1.3, brown hair).
    Melanin {
        /// `eumelanin`.
        eumelanin: FloatInput,
        /// `pheomelanin`.
        pheomelanin: FloatInput,
    },
}

/// How a `subsurface` material gives its medium. Any input may be a texture: pbrt-v4 evaluates
/// them where a path enters the surface (its BSSRDF's coefficients are the entry point's).
#[derive(Clone, Debug, PartialEq)]
pub enum SubsurfaceCoefficients {
    /// σa and σs (named, given, or pbrt-v4's defaults).
    Sigma {
        /// Absorption.
        sigma_a: SpectrumInput,
        /// Scattering.
        sigma_s: SpectrumInput,
    },
    /// A total diffuse reflectance and a mean free path, inverted through the photon beam
    /// diffusion profile as pbrt-v4 does.
    Reflectance {
        /// `reflectance`.
        reflectance: SpectrumInput,
        /// `mfp`.
        mfp: SpectrumInput,
    },
}

impl SubsurfaceCoefficients {
    /// True when some input is a texture, so the coefficients vary over the surface.
    pub fn textured(&self) -> bool {
        let t = |i: &SpectrumInput| matches!(i, SpectrumInput::Texture(_));
        match self {
            SubsurfaceCoefficients::Sigma { sigma_a, sigma_s } => t(sigma_a) || t(sigma_s),
            SubsurfaceCoefficients::Reflectance { reflectance, mfp } => t(reflectance) || t(mfp),
        }
    }
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
    /// `coatedconductor`: a dielectric coating over a conductor.
    CoatedConductor {
        /// Coating roughness (`interface.roughness`, ...).
        interface_roughness: Roughness,
        /// Coating thickness.
        thickness: FloatInput,
        /// Coating index of refraction (`interface.eta`).
        interface_eta: Eta,
        /// The conductor's optical constants (`conductor.eta`/`conductor.k` or `reflectance`).
        conductor: ConductorSpec,
        /// The conductor's roughness (`conductor.roughness`, ...).
        conductor_roughness: Roughness,
        /// Albedo of the medium between coating and base.
        albedo: SpectrumInput,
        /// Asymmetry of that medium.
        g: FloatInput,
        /// Random-walk depth of the layered evaluation.
        max_depth: u32,
        /// Samples per evaluation.
        n_samples: u32,
    },
    /// `diffusetransmission`: Lambertian reflection and transmission.
    DiffuseTransmission {
        /// Reflectance.
        reflectance: SpectrumInput,
        /// Transmittance.
        transmittance: SpectrumInput,
        /// Factor on both.
        scale: f32,
    },
    /// `mix`: one of two named materials, chosen per hit.
    Mix {
        /// The two named materials.
        materials: [String; 2],
        /// Probability of the second (float texture).
        amount: FloatInput,
    },
    /// `subsurface`: rendered as what its BSSRDF approximates, a dielectric boundary around a
    /// homogeneous medium with the material's coefficients.
    Subsurface {
        /// Index of refraction of the boundary.
        eta: f32,
        /// Roughness of the boundary.
        roughness: Roughness,
        /// The medium's coefficients, or what they are derived from.
        coefficients: SubsurfaceCoefficients,
        /// Multiplier on the coefficients (pbrt-v4's unit conversion: named ones are per mm)
        /// and on `mfp`.
        scale: f32,
        /// Henyey-Greenstein asymmetry of the medium.
        g: f32,
    },
    /// `hair`: pbrt-v4's hair BSDF.
    Hair {
        /// What absorbs inside the fibre.
        absorption: HairAbsorptionSpec,
        /// Index of refraction.
        eta: FloatInput,
        /// Longitudinal roughness.
        beta_m: FloatInput,
        /// Azimuthal roughness.
        beta_n: FloatInput,
        /// Cuticle scale tilt (degrees).
        alpha: FloatInput,
    },
    /// pbrt-v4's measured BRDF from a `.bsdf` tensor file.
    Measured {
        /// The file (resolved, existing).
        filename: std::path::PathBuf,
    },
    /// A material nimbus lacks, rendered as gray diffuse.
    Unsupported(String),
}

/// Everything a material entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSettings {
    /// The material.
    pub kind: MaterialKind,
    /// Bump map: displacement along the shading normal (float texture).
    pub displacement: Option<FloatInput>,
    /// Normal map image (resolved path).
    pub normal_map: Option<std::path::PathBuf>,
}

fn roughness(e: &Entity) -> Result<Roughness, Error> {
    prefixed_roughness(e, "")
}

/// `{prefix}roughness`, `{prefix}uroughness`, `{prefix}vroughness` (coatedconductor's
/// `interface.` and `conductor.` parameters).
fn prefixed_roughness(e: &Entity, prefix: &str) -> Result<Roughness, Error> {
    let p = &e.params;
    let (rn, un, vn) = (format!("{prefix}roughness"), format!("{prefix}uroughness"), format!("{prefix}vroughness"));
    let r = float_input(p, &rn)?.unwrap_or(FloatInput::Value(0.0));
    let u = float_input(p, &un)?.unwrap_or_else(|| r.clone());
    let v = float_input(p, &vn)?.unwrap_or_else(|| r.clone());
    for (name, x) in [(&un, &u), (&vn, &v)] {
        if let FloatInput::Value(x) = x
            && *x < 0.0
        {
            return Err(Error::new(p.loc(name).or(p.loc(&rn)).unwrap_or(&e.loc), "roughness cannot be negative"));
        }
    }
    Ok(Roughness { u, v, remap: p.get_one_bool("remaproughness", true)? })
}

fn eta(e: &Entity, default: f32) -> Result<Eta, Error> {
    named_eta(e, "eta", default)
}

fn named_eta(e: &Entity, name: &str, default: f32) -> Result<Eta, Error> {
    let p = &e.params;
    // pbrt-v4 accepts "float eta" or "spectrum eta".
    if let Some(peek) = p.peek(name)
        && peek.ty != nimbus_parser::ParamType::Float
    {
        return Ok(Eta::Spectrum(spectrum(p, name)?.expect("peeked")));
    }
    let v = checked_float(p, name, default, |v| v > 0.0, "the index of refraction must be positive")?;
    Ok(Eta::Constant(v))
}

/// pbrt-v4's four mutually exclusive ways to give a subsurface material's coefficients: a
/// named measured medium, `sigma_a` with `sigma_s`, `reflectance` (with `mfp`), or its
/// defaults (whole milk's, per mm).
fn subsurface(e: &Entity, warnings: &mut Vec<Warning>) -> Result<MaterialKind, Error> {
    let p = &e.params;
    let mut g = p.get_one_float("g", 0.0)?;
    let sigma = |a: [f32; 3], s: [f32; 3]| SubsurfaceCoefficients::Sigma {
        sigma_a: SpectrumInput::Value(SpectrumSpec::Rgb(a)),
        sigma_s: SpectrumInput::Value(SpectrumSpec::Rgb(s)),
    };
    let coefficients = if let Some(name) = p.get_opt_string("name")? {
        let Some((_, ss, sa)) = super::media::MEDIUM_PRESETS.iter().find(|(n, _, _)| *n == name) else {
            return Err(Error::new(
                p.loc("name").unwrap_or(&e.loc),
                format!("subsurface: named medium \"{name}\" not found"),
            ));
        };
        if g != 0.0 {
            warnings.push(Warning::new(
                p.loc("g").unwrap_or(&e.loc),
                "subsurface: non-zero \"g\" ignored with named scattering coefficients (they are reduced coefficients, for g = 0)",
            ));
        }
        g = 0.0;
        sigma(*sa, *ss)
    } else {
        match (spectrum_input(p, "sigma_a")?, spectrum_input(p, "sigma_s")?) {
            (Some(sigma_a), Some(sigma_s)) => SubsurfaceCoefficients::Sigma { sigma_a, sigma_s },
            (Some(_), None) => {
                return Err(Error::new(
                    p.loc("sigma_a").unwrap_or(&e.loc),
                    "subsurface: \"sigma_a\" given without \"sigma_s\"",
                ));
            }
            (None, Some(_)) => {
                return Err(Error::new(
                    p.loc("sigma_s").unwrap_or(&e.loc),
                    "subsurface: \"sigma_s\" given without \"sigma_a\"",
                ));
            }
            (None, None) => match spectrum_input(p, "reflectance")? {
                Some(reflectance) => SubsurfaceCoefficients::Reflectance {
                    reflectance,
                    mfp: spectrum_input(p, "mfp")?.unwrap_or(SpectrumInput::Value(SpectrumSpec::Rgb([1.0; 3]))),
                },
                // pbrt-v4's defaults (whole milk, per mm).
                None => sigma([0.0011, 0.0024, 0.014], [2.55, 3.21, 3.77]),
            },
        }
    };
    Ok(MaterialKind::Subsurface {
        eta: checked_float(p, "eta", 1.33, |v| v > 0.0, "the index of refraction must be positive")?,
        roughness: roughness(e)?,
        coefficients,
        scale: checked_float(p, "scale", 1.0, |v| v >= 0.0 && v.is_finite(), "must be finite and not negative")?,
        g: if g > -1.0 && g < 1.0 {
            g
        } else {
            return Err(Error::new(p.loc("g").unwrap_or(&e.loc), "subsurface: \"g\" must be in (-1, 1)"));
        },
    })
}

/// pbrt-v4's `HairMaterial::Create`.
fn hair(e: &Entity, warnings: &mut Vec<Warning>) -> Result<MaterialKind, Error> {
    let p = &e.params;
    let sigma_a = spectrum_input(p, "sigma_a")?;
    let reflectance = match spectrum_input(p, "reflectance")? {
        Some(r) => Some(r),
        None => spectrum_input(p, "color")?,
    };
    let eumelanin = float_input(p, "eumelanin")?;
    let pheomelanin = float_input(p, "pheomelanin")?;
    let mut ignore = |name: &str, because: &str| {
        warnings.push(Warning::new(
            p.loc(name).unwrap_or(&e.loc),
            format!("hair: \"{name}\" ignored since \"{because}\" was given"),
        ))
    };
    let absorption = if let Some(s) = sigma_a {
        for (name, given) in [
            ("reflectance", reflectance.is_some()),
            ("eumelanin", eumelanin.is_some()),
            ("pheomelanin", pheomelanin.is_some()),
        ] {
            if given {
                ignore(name, "sigma_a");
            }
        }
        HairAbsorptionSpec::SigmaA(s)
    } else if let Some(r) = reflectance {
        for (name, given) in [("eumelanin", eumelanin.is_some()), ("pheomelanin", pheomelanin.is_some())] {
            if given {
                ignore(name, "reflectance");
            }
        }
        HairAbsorptionSpec::Reflectance(r)
    } else if eumelanin.is_some() || pheomelanin.is_some() {
        HairAbsorptionSpec::Melanin {
            eumelanin: eumelanin.unwrap_or(FloatInput::Value(0.0)),
            pheomelanin: pheomelanin.unwrap_or(FloatInput::Value(0.0)),
        }
    } else {
        HairAbsorptionSpec::Melanin { eumelanin: FloatInput::Value(1.3), pheomelanin: FloatInput::Value(0.0) }
    };
    let f = |name: &str, default: f32| -> Result<FloatInput, Error> {
        Ok(float_input(p, name)?.unwrap_or(FloatInput::Value(default)))
    };
    Ok(MaterialKind::Hair {
        absorption,
        eta: f("eta", 1.55)?,
        beta_m: f("beta_m", 0.3)?,
        beta_n: f("beta_n", 0.3)?,
        alpha: f("alpha", 2.0)?,
    })
}

/// A conductor's optical constants from `{prefix}eta`/`{prefix}k` or `reflectance`, copper by
/// default (pbrt-v4's conductor and coatedconductor materials).
fn conductor_spec(e: &Entity, prefix: &str) -> Result<ConductorSpec, Error> {
    let p = &e.params;
    let (eta_name, k_name) = (format!("{prefix}eta"), format!("{prefix}k"));
    Ok(match spectrum_input(p, "reflectance")? {
        Some(r) => {
            if !prefix.is_empty() && (p.peek(&eta_name).is_some() || p.peek(&k_name).is_some()) {
                return Err(Error::new(
                    p.loc("reflectance").unwrap_or(&e.loc),
                    format!("\"reflectance\" and \"{eta_name}\"/\"{k_name}\" cannot both be given"),
                ));
            }
            ConductorSpec::Reflectance(r)
        }
        None => ConductorSpec::EtaK {
            eta: spectrum_input(p, &eta_name)?
                .unwrap_or_else(|| SpectrumInput::Value(SpectrumSpec::Named("metal-Cu-eta".into()))),
            k: spectrum_input(p, &k_name)?
                .unwrap_or_else(|| SpectrumInput::Value(SpectrumSpec::Named("metal-Cu-k".into()))),
        },
    })
}

fn gray(v: f32) -> SpectrumInput {
    SpectrumInput::Value(SpectrumSpec::Rgb([v, v, v]))
}

impl MaterialSettings {
    /// Reads a material entity. Unknown types give a warning naming them and gray diffuse.
    pub fn from_entity(e: &Entity, warnings: &mut Vec<Warning>) -> Result<MaterialSettings, Error> {
        let p = &e.params;
        let displacement = float_input(p, "displacement")?;
        let normal_map = match p.get_opt_string("normalmap")? {
            Some(name) => {
                let loc = p.loc("normalmap").unwrap_or(&e.loc);
                let path = loc.resolve(name);
                if !path.is_file() {
                    return Err(Error::new(
                        loc,
                        format!("normal map \"{name}\" not found (tried {})", nimbus_parser::loc_shown(&path)),
                    ));
                }
                Some(path)
            }
            None => None,
        };
        let kind = match e.name.as_str() {
            "diffuse" => {
                MaterialKind::Diffuse { reflectance: spectrum_input(p, "reflectance")?.unwrap_or_else(|| gray(0.5)) }
            }
            "conductor" => MaterialKind::Conductor { spec: conductor_spec(e, "")?, roughness: roughness(e)? },
            "coatedconductor" => MaterialKind::CoatedConductor {
                interface_roughness: prefixed_roughness(e, "interface.")?,
                thickness: float_input(p, "thickness")?.unwrap_or(FloatInput::Value(0.01)),
                interface_eta: named_eta(e, "interface.eta", 1.5)?,
                conductor: conductor_spec(e, "conductor.")?,
                conductor_roughness: prefixed_roughness(e, "conductor.")?,
                albedo: spectrum_input(p, "albedo")?.unwrap_or_else(|| gray(0.0)),
                g: float_input(p, "g")?.unwrap_or(FloatInput::Value(0.0)),
                max_depth: checked_int(p, "maxdepth", 10, |v| v > 0, "must be positive")? as u32,
                n_samples: checked_int(p, "nsamples", 1, |v| v > 0, "must be positive")? as u32,
            },
            "diffusetransmission" => MaterialKind::DiffuseTransmission {
                reflectance: spectrum_input(p, "reflectance")?.unwrap_or_else(|| gray(0.25)),
                transmittance: spectrum_input(p, "transmittance")?.unwrap_or_else(|| gray(0.25)),
                scale: checked_float(
                    p,
                    "scale",
                    1.0,
                    |v| v >= 0.0 && v.is_finite(),
                    "must be finite and not negative",
                )?,
            },
            "subsurface" => subsurface(e, warnings)?,
            "hair" => hair(e, warnings)?,
            "measured" => {
                let Some(name) = p.get_opt_string("filename")? else {
                    return Err(Error::new(&e.loc, "measured: missing \"string filename\" (a .bsdf file)"));
                };
                let loc = p.loc("filename").unwrap_or(&e.loc);
                let filename = loc.resolve(name);
                if !filename.is_file() {
                    return Err(Error::new(
                        loc,
                        format!("measured: cannot find \"{name}\" (tried {})", nimbus_parser::loc_shown(&filename)),
                    ));
                }
                MaterialKind::Measured { filename }
            }
            "mix" => {
                let names = p.get_strings("materials")?;
                let [a, b] = <[String; 2]>::try_from(names.to_vec()).map_err(|_| {
                    Error::new(
                        p.loc("materials").unwrap_or(&e.loc),
                        "the mix material needs two values for \"string materials\"",
                    )
                })?;
                MaterialKind::Mix {
                    materials: [a, b],
                    amount: float_input(p, "amount")?.unwrap_or(FloatInput::Value(0.5)),
                }
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
        Ok(MaterialSettings { kind, displacement, normal_map })
    }
}
