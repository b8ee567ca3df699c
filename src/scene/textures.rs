//! Texture settings with pbrt-v4's parameter names and defaults. Texture classes nimbus lacks
//! are reported by name and evaluate to a constant.

use std::path::PathBuf;

use nimbus_parser::loc_shown as shown;
use nimbus_parser::{Error, TextureEntity, TextureValue};

use crate::params::{FloatInput, float_input};
use crate::spectra::spec::{SpectrumInput, SpectrumSpec, spectrum_input};

/// How surface points map to texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Mapping {
    /// (u, v) scaled and offset.
    Uv {
        /// u scale.
        su: f32,
        /// v scale.
        sv: f32,
        /// u offset.
        du: f32,
        /// v offset.
        dv: f32,
    },
    /// Spherical coordinates about the texture space origin.
    Spherical,
    /// Cylindrical coordinates about the texture space z axis.
    Cylindrical,
    /// Projection onto two vectors.
    Planar {
        /// First axis.
        v1: [f32; 3],
        /// Second axis.
        v2: [f32; 3],
        /// u offset.
        du: f32,
        /// v offset.
        dv: f32,
    },
}

/// A value a texture blends: a constant or another texture, float or spectrum.
#[derive(Clone, Debug, PartialEq)]
pub enum TexInput {
    /// For float textures.
    Float(FloatInput),
    /// For spectrum textures.
    Spectrum(SpectrumInput),
}

/// What a texture is.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureKind {
    /// `constant`
    Constant(TexInput),
    /// `scale`: `tex` × `scale`
    Scale {
        /// The value scaled.
        tex: TexInput,
        /// The (float) scale.
        scale: FloatInput,
    },
    /// `mix`: lerp(`amount`, `tex1`, `tex2`)
    Mix {
        /// Value at amount 0.
        tex1: TexInput,
        /// Value at amount 1.
        tex2: TexInput,
        /// Blend.
        amount: FloatInput,
    },
    /// `checkerboard` (2D)
    Checkerboard {
        /// Value on even squares.
        tex1: TexInput,
        /// Value on odd squares.
        tex2: TexInput,
        /// Mapping.
        mapping: Mapping,
    },
    /// `checkerboard` with `"integer dimension" 3`: cubes of the texture-space point.
    Checkerboard3D {
        /// Value on even cubes.
        tex1: TexInput,
        /// Value on odd cubes.
        tex2: TexInput,
    },
    /// `bilerp`: bilinear interpolation of four corner values over (s, t).
    Bilerp {
        /// Values at (0, 0), (0, 1), (1, 0), (1, 1): `v00`, `v01`, `v10`, `v11`.
        v: [TexInput; 4],
        /// Mapping.
        mapping: Mapping,
    },
    /// `fbm` (float)
    Fbm {
        /// `octaves`.
        octaves: u32,
        /// `roughness`.
        roughness: f32,
    },
    /// `wrinkled` (float)
    Wrinkled {
        /// `octaves`.
        octaves: u32,
        /// `roughness`.
        roughness: f32,
    },
    /// `windy` (float)
    Windy,
    /// `marble` (spectrum)
    Marble {
        /// `octaves`.
        octaves: u32,
        /// `roughness`.
        roughness: f32,
        /// `scale`.
        scale: f32,
        /// `variation`.
        variation: f32,
    },
    /// `dots`
    Dots {
        /// `inside`.
        inside: TexInput,
        /// `outside`.
        outside: TexInput,
        /// Mapping.
        mapping: Mapping,
    },
    /// `directionmix`
    DirectionMix {
        /// `tex1` (along `dir`).
        tex1: TexInput,
        /// `tex2`.
        tex2: TexInput,
        /// `dir` (texture space).
        dir: [f32; 3],
    },
    /// `imagemap`
    ImageMap {
        /// The image.
        filename: PathBuf,
        /// pbrt-v4's filter (`bilinear`, `point`, `trilinear`, `ewa`): which of an image's
        /// channels a float texture reads depends on it.
        filter: String,
        /// The `ewa` filter's largest ratio of the footprint's axes (`maxanisotropy`, 8).
        max_anisotropy: f32,
        /// Multiplier.
        scale: f32,
        /// 1 - value.
        invert: bool,
        /// `repeat`, `black` or `clamp`.
        wrap: String,
        /// Color encoding of 8-bit images (`sRGB`, `linear`, `gamma g`).
        encoding: String,
        /// Mapping.
        mapping: Mapping,
    },
    /// `ptex`
    Ptex {
        /// The Ptex file.
        filename: PathBuf,
        /// Decoding of the filtered values (`gamma 2.2` unless given: pbrt-v4's default here).
        encoding: String,
        /// Multiplier.
        scale: f32,
    },
}

/// Everything a texture entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSettings {
    /// The texture.
    pub kind: TextureKind,
}

fn mapping(t: &TextureEntity) -> Result<Mapping, Error> {
    let p = &t.entity.params;
    Ok(match p.get_one_string("mapping", "uv")? {
        "uv" => Mapping::Uv {
            su: p.get_one_float("uscale", 1.0)?,
            sv: p.get_one_float("vscale", 1.0)?,
            du: p.get_one_float("udelta", 0.0)?,
            dv: p.get_one_float("vdelta", 0.0)?,
        },
        "spherical" => Mapping::Spherical,
        "cylindrical" => Mapping::Cylindrical,
        "planar" => Mapping::Planar {
            v1: p.get_one_vector3("v1", [1.0, 0.0, 0.0])?,
            v2: p.get_one_vector3("v2", [0.0, 1.0, 0.0])?,
            du: p.get_one_float("udelta", 0.0)?,
            dv: p.get_one_float("vdelta", 0.0)?,
        },
        other => {
            return Err(Error::new(
                p.loc("mapping").unwrap_or(&t.entity.loc),
                format!("unknown texture mapping \"{other}\""),
            ));
        }
    })
}

fn input(t: &TextureEntity, name: &str, default: f32) -> Result<TexInput, Error> {
    let p = &t.entity.params;
    Ok(match t.value {
        TextureValue::Float => TexInput::Float(float_input(p, name)?.unwrap_or(FloatInput::Value(default))),
        TextureValue::Spectrum => TexInput::Spectrum(
            spectrum_input(p, name)?.unwrap_or(SpectrumInput::Value(SpectrumSpec::Rgb([default; 3]))),
        ),
    })
}

fn checked_octaves(t: &TextureEntity) -> Result<u32, Error> {
    let p = &t.entity.params;
    let o = p.get_one_int("octaves", 8)?;
    if !(0..=32).contains(&o) {
        return Err(Error::new(p.loc("octaves").unwrap_or(&t.entity.loc), "\"octaves\" must be between 0 and 32"));
    }
    Ok(o as u32)
}

impl TextureSettings {
    /// Reads a texture entity.
    pub fn from_entity(t: &TextureEntity) -> Result<TextureSettings, Error> {
        let e = &t.entity;
        let p = &e.params;
        let kind = match e.name.as_str() {
            "constant" => TextureKind::Constant(input(t, "value", 1.0)?),
            "scale" => TextureKind::Scale {
                tex: input(t, "tex", 1.0)?,
                scale: float_input(p, "scale")?.unwrap_or(FloatInput::Value(1.0)),
            },
            "mix" => TextureKind::Mix {
                tex1: input(t, "tex1", 0.0)?,
                tex2: input(t, "tex2", 1.0)?,
                amount: float_input(p, "amount")?.unwrap_or(FloatInput::Value(0.5)),
            },
            "checkerboard" => match p.get_one_int("dimension", 2)? {
                2 => TextureKind::Checkerboard {
                    tex1: input(t, "tex1", 1.0)?,
                    tex2: input(t, "tex2", 0.0)?,
                    mapping: mapping(t)?,
                },
                3 => TextureKind::Checkerboard3D { tex1: input(t, "tex1", 1.0)?, tex2: input(t, "tex2", 0.0)? },
                dim => {
                    return Err(Error::new(
                        p.loc("dimension").unwrap_or(&e.loc),
                        format!("checkerboard dimension {dim}: pbrt-v4's checkerboards have 2 or 3"),
                    ));
                }
            },
            "bilerp" => TextureKind::Bilerp {
                v: [input(t, "v00", 0.0)?, input(t, "v01", 1.0)?, input(t, "v10", 0.0)?, input(t, "v11", 1.0)?],
                mapping: mapping(t)?,
            },
            "fbm" | "wrinkled" | "windy" if t.value == TextureValue::Spectrum => {
                return Err(Error::new(
                    &e.loc,
                    format!("texture \"{}\" is a float texture (pbrt-v4 has no spectrum {})", e.name, e.name),
                ));
            }
            "fbm" | "wrinkled" => {
                let octaves = checked_octaves(t)?;
                let roughness = p.get_one_float("roughness", 0.5)?;
                if e.name == "fbm" {
                    TextureKind::Fbm { octaves, roughness }
                } else {
                    TextureKind::Wrinkled { octaves, roughness }
                }
            }
            "windy" => TextureKind::Windy,
            "marble" => {
                if t.value == TextureValue::Float {
                    return Err(Error::new(
                        &e.loc,
                        "texture \"marble\" is a spectrum texture (pbrt-v4 has no float marble)",
                    ));
                }
                TextureKind::Marble {
                    octaves: checked_octaves(t)?,
                    roughness: p.get_one_float("roughness", 0.5)?,
                    scale: p.get_one_float("scale", 1.0)?,
                    variation: p.get_one_float("variation", 0.2)?,
                }
            }
            // pbrt-v4 (through its latest version) passes `inside` and `outside` to the
            // texture's constructor in the opposite order of its parameters, so its dots show
            // `outside` (default 0) and the space between them `inside` (default 1). Scenes
            // were made to look right in pbrt-v4, so nimbus renders what pbrt-v4 renders.
            "dots" => TextureKind::Dots {
                inside: input(t, "outside", 0.0)?,
                outside: input(t, "inside", 1.0)?,
                mapping: mapping(t)?,
            },
            "directionmix" => TextureKind::DirectionMix {
                tex1: input(t, "tex1", 0.0)?,
                tex2: input(t, "tex2", 1.0)?,
                dir: p.get_one_vector3("dir", [0.0, 1.0, 0.0])?,
            },
            "imagemap" => {
                let Some(name) = p.get_opt_string("filename")? else {
                    return Err(Error::new(&e.loc, "imagemap: missing \"string filename\""));
                };
                let loc = p.loc("filename").unwrap_or(&e.loc);
                let filename = loc.resolve(name);
                if !filename.is_file() {
                    return Err(Error::new(
                        loc,
                        format!("imagemap: cannot find image \"{name}\" (tried {})", shown(&filename)),
                    ));
                }
                let filter = p.get_one_string("filter", "bilinear")?.to_string();
                let max_anisotropy = p.get_one_float("maxanisotropy", 8.0)?;
                if max_anisotropy.is_nan() || max_anisotropy <= 0.0 {
                    let loc = p.loc("maxanisotropy").unwrap_or(&e.loc);
                    return Err(Error::new(
                        loc,
                        format!("imagemap: \"maxanisotropy\" must be positive (got {max_anisotropy})"),
                    ));
                }
                TextureKind::ImageMap {
                    filename,
                    filter,
                    max_anisotropy,
                    scale: p.get_one_float("scale", 1.0)?,
                    invert: p.get_one_bool("invert", false)?,
                    wrap: p.get_one_string("wrap", "repeat")?.to_string(),
                    encoding: p.get_one_string("encoding", "sRGB")?.to_string(),
                    mapping: mapping(t)?,
                }
            }
            "ptex" => {
                let Some(name) = p.get_opt_string("filename")? else {
                    return Err(Error::new(&e.loc, "ptex: missing \"string filename\""));
                };
                let loc = p.loc("filename").unwrap_or(&e.loc);
                let filename = loc.resolve(name);
                if !filename.is_file() {
                    return Err(Error::new(
                        loc,
                        format!("ptex: cannot find file \"{name}\" (tried {})", shown(&filename)),
                    ));
                }
                TextureKind::Ptex {
                    filename,
                    encoding: p.get_one_string("encoding", "gamma 2.2")?.to_string(),
                    scale: p.get_one_float("scale", 1.0)?,
                }
            }
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "texture type \"{other}\" is unknown (pbrt-v4's are bilerp, checkerboard, constant, \
                         directionmix, dots, fbm, imagemap, marble, mix, ptex, scale, windy and wrinkled)"
                    ),
                ));
            }
        };
        Ok(TextureSettings { kind })
    }
}
