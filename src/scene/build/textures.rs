//! Textures of a scene: each named texture built once, and the images they read.

use super::*;

/// Builds textures and remembers which name maps to which node.
pub(super) struct TextureBuilder<'a> {
    pub(super) textures: Textures,
    pub(super) float_names: HashMap<String, u32>,
    /// Float textures of the `constant` type with a plain value (the one kind of texture
    /// pbrt-v4 tells apart, for its invisible area lights).
    pub(super) float_constants: HashMap<String, f32>,
    pub(super) spectrum_names: HashMap<String, u32>,
    pub(super) spectra: SpectrumResolver<'a>,
}

impl TextureBuilder<'_> {
    pub(super) fn float(&self, input: &FloatInput, loc: &FileLoc) -> Result<Tex, Error> {
        Ok(match input {
            FloatInput::Value(v) => Tex::Const(SpectrumValue::constant(*v)),
            FloatInput::Texture(name) => Tex::Node(
                *self
                    .float_names
                    .get(name)
                    .ok_or_else(|| err(loc, format!("float texture \"{name}\" is not defined")))?,
            ),
        })
    }

    /// A spectrum texture input; a constant is read as a reflectance, or as an unbounded
    /// coefficient with `unbounded`.
    pub(super) fn spectrum(&self, input: &SpectrumInput, cs: ColorSpace, loc: &FileLoc) -> Result<Tex, Error> {
        self.spectrum_as(input, cs, loc, false)
    }

    pub(super) fn spectrum_as(
        &self,
        input: &SpectrumInput,
        cs: ColorSpace,
        loc: &FileLoc,
        unbounded: bool,
    ) -> Result<Tex, Error> {
        Ok(match input {
            SpectrumInput::Value(spec) => {
                let v = if unbounded { self.spectra.unbounded(spec, cs) } else { self.spectra.albedo(spec, cs) };
                Tex::Const(v.map_err(|e| err(loc, e.to_string()))?)
            }
            SpectrumInput::Texture(name) => Tex::Node(
                *self
                    .spectrum_names
                    .get(name)
                    .ok_or_else(|| err(loc, format!("spectrum texture \"{name}\" is not defined")))?,
            ),
        })
    }

    pub(super) fn input(&self, input: &TexInput, cs: ColorSpace, loc: &FileLoc) -> Result<Tex, Error> {
        match input {
            TexInput::Float(f) => self.float(f, loc),
            TexInput::Spectrum(s) => self.spectrum(s, cs, loc),
        }
    }

    pub(super) fn add(&mut self, t: &nimbus_parser::TextureEntity) -> Result<(), Error> {
        let e = &t.entity;
        let settings = TextureSettings::from_entity(t)?;
        // Only textures that map points through it need the transform inverted: pbrt-v4 goes
        // on past a texture declared under a singular transform that maps by (u, v).
        let texture_from_world = || affine(&t.world_from_texture.start, &e.loc).map(|a| a.inverse());
        let mapping = |m: &Mapping| -> Result<TexMapping, Error> {
            Ok(match m {
                Mapping::Uv { su, sv, du, dv } => TexMapping::Uv { s: Vec2::new(*su, *sv), d: Vec2::new(*du, *dv) },
                Mapping::Spherical => TexMapping::Spherical { texture_from_world: texture_from_world()? },
                Mapping::Cylindrical => TexMapping::Cylindrical { texture_from_world: texture_from_world()? },
                Mapping::Planar { v1, v2, du, dv } => TexMapping::Planar {
                    texture_from_world: texture_from_world()?,
                    vs: Vec3::from(*v1),
                    vt: Vec3::from(*v2),
                    d: Vec2::new(*du, *dv),
                },
            })
        };
        let cs = e.color_space;
        let node = match &settings.kind {
            TextureKind::Constant(v) => {
                TexNode::Scale { tex: self.input(v, cs, &e.loc)?, scale: Tex::Const(SpectrumValue::constant(1.0)) }
            }
            TextureKind::Scale { tex, scale } => {
                TexNode::Scale { tex: self.input(tex, cs, &e.loc)?, scale: self.float(scale, &e.loc)? }
            }
            TextureKind::Mix { tex1, tex2, amount } => TexNode::Mix {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                amount: self.float(amount, &e.loc)?,
            },
            TextureKind::Checkerboard { tex1, tex2, mapping: m } => TexNode::Checkerboard {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                mapping: mapping(m)?,
            },
            TextureKind::Checkerboard3D { tex1, tex2 } => TexNode::Checkerboard3D {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                texture_from_world: texture_from_world()?,
            },
            TextureKind::Bilerp { v, mapping: m } => TexNode::Bilerp {
                v: [
                    self.input(&v[0], cs, &e.loc)?,
                    self.input(&v[1], cs, &e.loc)?,
                    self.input(&v[2], cs, &e.loc)?,
                    self.input(&v[3], cs, &e.loc)?,
                ],
                mapping: mapping(m)?,
            },
            TextureKind::Fbm { octaves, roughness } => {
                TexNode::Fbm { texture_from_world: texture_from_world()?, octaves: *octaves, omega: *roughness }
            }
            TextureKind::Wrinkled { octaves, roughness } => {
                TexNode::Wrinkled { texture_from_world: texture_from_world()?, octaves: *octaves, omega: *roughness }
            }
            TextureKind::Windy => TexNode::Windy { texture_from_world: texture_from_world()? },
            TextureKind::Marble { octaves, roughness, scale, variation } => TexNode::Marble {
                texture_from_world: texture_from_world()?,
                octaves: *octaves,
                omega: *roughness,
                scale: *scale,
                variation: *variation,
            },
            TextureKind::Dots { inside, outside, mapping: m } => TexNode::Dots {
                inside: self.input(inside, cs, &e.loc)?,
                outside: self.input(outside, cs, &e.loc)?,
                mapping: mapping(m)?,
            },
            TextureKind::DirectionMix { tex1, tex2, dir } => TexNode::DirectionMix {
                a: self.input(tex1, cs, &e.loc)?,
                b: self.input(tex2, cs, &e.loc)?,
                // A texture-space direction, taken to world space (pbrt-v4's renderFromTexture).
                dir: texture_from_world()?.inverse().transform_vector3(Vec3::from(*dir)).normalize_or_zero(),
            },
            TextureKind::ImageMap { filename, filter, max_anisotropy, scale, invert, wrap, encoding, mapping: m } => {
                let image = load_texture_image(filename, encoding).map_err(|m| err(&e.loc, m))?;
                let wrap = match wrap.as_str() {
                    "repeat" => Wrap::Repeat,
                    "black" => Wrap::Black,
                    "clamp" => Wrap::Clamp,
                    other => {
                        return Err(err(
                            &e.loc,
                            format!("imagemap: unknown wrap mode \"{other}\" (repeat, black or clamp)"),
                        ));
                    }
                };
                let gray = image.pixels.iter().all(|p| p.x == p.y && p.y == p.z);
                let filter = match filter.as_str() {
                    "point" => MipFilter::Point,
                    "bilinear" => MipFilter::Bilinear,
                    "trilinear" => MipFilter::Trilinear,
                    "ewa" | "EWA" => MipFilter::Ewa,
                    other => {
                        return Err(err(
                            &e.loc,
                            format!("imagemap: unknown filter \"{other}\" (point, bilinear, trilinear or ewa)"),
                        ));
                    }
                };
                TexNode::Image {
                    image: Arc::new(MipMap::new(image, wrap, filter).with_max_anisotropy(*max_anisotropy)),
                    mapping: mapping(m)?,
                    scale: *scale,
                    invert: *invert,
                    space: cs,
                    gray,
                    float: t.value == TextureValue::Float,
                }
            }
            TextureKind::Ptex { filename, encoding, scale } => {
                let encoding = PtexEncoding::parse(encoding)
                    .map_err(|m| err(t.entity.params.loc("encoding").unwrap_or(&e.loc), format!("ptex: {m}")))?;
                let texture =
                    PtexTexture::open(filename, encoding, *scale).map_err(|m| err(&e.loc, format!("ptex: {m}")))?;
                TexNode::Ptex { texture: Arc::new(texture), float: t.value == TextureValue::Float }
            }
        };
        let id = self.textures.nodes.len() as u32;
        self.textures.nodes.push(node);
        match t.value {
            TextureValue::Float => self.float_names.insert(t.name.clone(), id),
            TextureValue::Spectrum => self.spectrum_names.insert(t.name.clone(), id),
        };
        match (&t.value, &settings.kind) {
            (TextureValue::Float, TextureKind::Constant(TexInput::Float(FloatInput::Value(v)))) => {
                self.float_constants.insert(t.name.clone(), *v)
            }
            _ => self.float_constants.remove(&t.name),
        };
        Ok(())
    }

    /// The value of the float texture `name` when it is a `constant` texture.
    pub(super) fn constant_float(&self, name: &str) -> Option<f32> {
        self.float_constants.get(name).copied()
    }
}

/// The image of an `imagemap` (or a normal map) at `path`, linear, its PNG values decoded by
/// `encoding`: the file's errors as [`crate::imageio::read_image`] gives them, an encoding it
/// does not know [`Error::Invalid`](crate::error::Error::Invalid).
pub(super) fn load_texture_image(path: &Path, encoding: &str) -> crate::error::Result<crate::imageio::Image> {
    let is_png = path.extension().is_some_and(|x| x.eq_ignore_ascii_case("png"));
    let mut image = crate::imageio::read_image(path)?;
    if is_png && encoding != "sRGB" {
        // read_image decoded sRGB; re-encode and apply the requested encoding instead.
        let gamma = match encoding {
            "linear" => 1.0,
            e if e.starts_with("gamma ") => e[6..]
                .trim()
                .parse::<f32>()
                .map_err(|_| crate::error::Error::Invalid(format!("imagemap: bad encoding \"{e}\"")))?,
            other => {
                return Err(crate::error::Error::Invalid(format!(
                    "imagemap: unknown encoding \"{other}\" (sRGB, linear or \"gamma g\")"
                )));
            }
        };
        let enc = |v: f32| {
            if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
        };
        for p in &mut image.pixels {
            *p = Rgb::new(enc(p.x).powf(gamma), enc(p.y).powf(gamma), enc(p.z).powf(gamma));
        }
        // pbrt-v4 decodes an 8-bit image's alpha with the same encoding.
        for (_, values) in image.channels.iter_mut().filter(|(n, _)| n == "A") {
            for a in values.iter_mut() {
                *a = enc(*a).powf(gamma);
            }
        }
    }
    Ok(image)
}
