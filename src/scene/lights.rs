//! Light settings with pbrt-v4's parameter names and defaults. Radiometric quantities stay
//! as spectra; pbrt-v4's photometric normalisation (`power`, `illuminance`) is applied when
//! the light is built.

use std::path::PathBuf;

use nimbus_parser::loc_shown as shown;
use nimbus_parser::{Entity, Error, LightEntity};

use crate::params::checked_float;
use crate::spectra::spec::{SpectrumSpec, spectrum};

/// What a light is.
#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    /// `point`: intensity `I` at `from`.
    Point {
        /// Intensity.
        intensity: SpectrumSpec,
        /// Position (light space).
        from: [f32; 3],
        /// Total emitted power, if given (overrides the intensity's scale).
        power: Option<f32>,
    },
    /// `goniometric`: a point light at the light's origin whose intensity varies with
    /// direction by an equal-area image (its channels averaged).
    Goniometric {
        /// Intensity.
        intensity: SpectrumSpec,
        /// The image, if a file was given (pbrt-v4 warns without one; the light is then dark).
        filename: Option<PathBuf>,
        /// Total emitted power, if given.
        power: Option<f32>,
    },
    /// `projection`: an RGB image projected from the light's origin along its +z axis.
    Projection {
        /// The image.
        filename: PathBuf,
        /// Field of view of the projection, degrees.
        fov: f32,
        /// Total emitted power, if given.
        power: Option<f32>,
    },
    /// `spot`: a point light restricted to a cone from `from` towards `to`.
    Spot {
        /// Intensity.
        intensity: SpectrumSpec,
        /// Position.
        from: [f32; 3],
        /// Target.
        to: [f32; 3],
        /// Cone half-angle in degrees.
        cone_angle: f32,
        /// Width of the falloff at the cone's edge in degrees.
        cone_delta_angle: f32,
        /// Total emitted power, if given.
        power: Option<f32>,
    },
    /// `distant`: radiance `L` arriving from `from - to`.
    Distant {
        /// Radiance.
        radiance: SpectrumSpec,
        /// Direction origin.
        from: [f32; 3],
        /// Direction target.
        to: [f32; 3],
        /// Illuminance at a surface facing the light, if given.
        illuminance: Option<f32>,
    },
    /// `infinite`: a uniform environment `L` or an equal-area octahedral image.
    Infinite {
        /// Uniform radiance (when there is no image).
        radiance: Option<SpectrumSpec>,
        /// Environment image.
        filename: Option<PathBuf>,
        /// Illuminance at an upward-facing surface, if given.
        illuminance: Option<f32>,
        /// The four corners (world space) of a rectangle the light is seen through, if given.
        portal: Option<[[f32; 3]; 4]>,
    },
}

/// Everything a light entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSettings {
    /// The light.
    pub kind: LightKind,
    /// Multiplier on the emitted quantity.
    pub scale: f32,
}

fn white() -> SpectrumSpec {
    // pbrt-v4's default: the color space's standard illuminant, which is RGB (1, 1, 1).
    SpectrumSpec::Rgb([1.0, 1.0, 1.0])
}

fn positive_opt(e: &Entity, name: &str) -> Result<Option<f32>, Error> {
    let v = e.params.get_opt_float(name)?;
    if let Some(x) = v
        && x <= 0.0
    {
        return Err(Error::new(e.params.loc(name).unwrap_or(&e.loc), format!("\"{name}\" must be positive")));
    }
    Ok(v)
}

/// The light's `"string filename"`, resolved as pbrt-v4 resolves paths and checked to exist
/// (`what` names the light in the error).
fn image_file(e: &Entity, what: &str) -> Result<Option<PathBuf>, Error> {
    let p = &e.params;
    let Some(name) = p.get_opt_string("filename")? else { return Ok(None) };
    let loc = p.loc("filename").unwrap_or(&e.loc);
    let path = loc.resolve(name);
    if !path.is_file() {
        return Err(Error::new(loc, format!("{what}: cannot find image \"{name}\" (tried {})", shown(&path))));
    }
    Ok(Some(path))
}

impl LightSettings {
    /// Reads a light entity. A light nimbus lacks is reported by name.
    pub fn from_entity(light: &LightEntity) -> Result<LightSettings, Error> {
        let e = &light.entity;
        let p = &e.params;
        let scale = p.get_one_float("scale", 1.0)?;
        let kind = match e.name.as_str() {
            "point" => LightKind::Point {
                intensity: spectrum(p, "I")?.unwrap_or_else(white),
                from: p.get_one_point3("from", [0.0; 3])?,
                power: positive_opt(e, "power")?,
            },
            "spot" => LightKind::Spot {
                intensity: spectrum(p, "I")?.unwrap_or_else(white),
                from: p.get_one_point3("from", [0.0; 3])?,
                to: p.get_one_point3("to", [0.0, 0.0, 1.0])?,
                cone_angle: checked_float(
                    p,
                    "coneangle",
                    30.0,
                    |a| a > 0.0 && a <= 180.0,
                    "must be in (0, 180] degrees",
                )?,
                cone_delta_angle: checked_float(p, "conedeltaangle", 5.0, |a| a >= 0.0, "cannot be negative")?,
                power: positive_opt(e, "power")?,
            },
            "goniometric" => LightKind::Goniometric {
                intensity: spectrum(p, "I")?.unwrap_or_else(white),
                filename: image_file(e, "goniometric light")?,
                power: positive_opt(e, "power")?,
            },
            "projection" => LightKind::Projection {
                filename: image_file(e, "projection light")?.ok_or_else(|| {
                    Error::new(&e.loc, "projection light: it needs a \"filename\" (the image it projects)")
                })?,
                fov: checked_float(p, "fov", 90.0, |f| f > 0.0 && f < 180.0, "must be between 0 and 180 degrees")?,
                power: positive_opt(e, "power")?,
            },
            "distant" => {
                let from = p.get_one_point3("from", [0.0; 3])?;
                let to = p.get_one_point3("to", [0.0, 0.0, 1.0])?;
                if from == to {
                    return Err(Error::new(
                        &e.loc,
                        "distant light: \"from\" and \"to\" are the same point, so there is no direction",
                    ));
                }
                LightKind::Distant {
                    radiance: spectrum(p, "L")?.unwrap_or_else(white),
                    from,
                    to,
                    illuminance: positive_opt(e, "illuminance")?,
                }
            }
            "infinite" => {
                let radiance = spectrum(p, "L")?;
                let filename = image_file(e, "infinite light")?;
                if radiance.is_some() && filename.is_some() {
                    return Err(Error::new(&e.loc, "infinite light: give either \"L\" or \"filename\", not both"));
                }
                let portal = match p.get_point3s("portal")? {
                    [] => None,
                    [a, b, c, d] => {
                        // Checked here so that `check` refuses what rendering would.
                        let corners = [*a, *b, *c, *d];
                        crate::lights::portal_frame(&corners.map(glam::Vec3::from)).map_err(|m| {
                            Error::new(p.loc("portal").unwrap_or(&e.loc), format!("infinite light: {m}"))
                        })?;
                        Some(corners)
                    }
                    other => {
                        return Err(Error::new(
                            p.loc("portal").unwrap_or(&e.loc),
                            format!("infinite light: a \"portal\" has 4 corners, not {}", other.len()),
                        ));
                    }
                };
                let radiance = if filename.is_none() { Some(radiance.unwrap_or_else(white)) } else { None };
                LightKind::Infinite { radiance, filename, illuminance: positive_opt(e, "illuminance")?, portal }
            }
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "light \"{other}\" is not supported by nimbus (it has point, spot, goniometric, projection, distant, infinite and diffuse area lights)"
                    ),
                ));
            }
        };
        Ok(LightSettings { kind, scale })
    }
}

/// Everything an area light (`AreaLightSource "diffuse"`) specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLightSettings {
    /// Emitted radiance (white with an image).
    pub radiance: SpectrumSpec,
    /// The emission image (`"string filename"`), read at the surface's (u, v).
    pub image: Option<PathBuf>,
    /// Multiplier.
    pub scale: f32,
    /// Emit from both sides.
    pub two_sided: bool,
    /// Total emitted power, if given.
    pub power: Option<f32>,
}

impl AreaLightSettings {
    /// Reads an area light entity.
    pub fn from_entity(e: &Entity) -> Result<AreaLightSettings, Error> {
        if e.name != "diffuse" {
            return Err(Error::new(
                &e.loc,
                format!("area light \"{}\" is not supported by nimbus (it has \"diffuse\")", e.name),
            ));
        }
        let p = &e.params;
        let image = image_file(e, "area light")?;
        let radiance = spectrum(p, "L")?;
        if image.is_some() && radiance.is_some() {
            return Err(Error::new(&e.loc, "area light: both \"L\" and \"filename\" given (pbrt-v4 refuses that too)"));
        }
        Ok(AreaLightSettings {
            radiance: radiance.unwrap_or_else(white),
            image,
            scale: p.get_one_float("scale", 1.0)?,
            two_sided: p.get_one_bool("twosided", false)?,
            power: positive_opt(e, "power")?,
        })
    }
}
