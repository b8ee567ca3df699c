//! pbrt-v4's `ptex` texture: a Ptex file (per-face textures of a quad mesh) looked up at the
//! hit's face index (the shape's `faceIndices`) and (u, v), filtered by the Ptex library's
//! B-spline filter over the hit's (u, v) footprint, then, for an encoding other than linear,
//! quantised to 8 bits and decoded (pbrt-v4's `PtexTextureBase::SampleTexture`), and scaled.

mod file;
mod filter;

use std::path::Path;

pub use file::PtexFile;

/// How filtered values are decoded (pbrt-v4's `ColorEncoding`, default `gamma 2.2` here).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Encoding {
    /// Values as they are.
    Linear,
    /// The sRGB curve, from 8 bits.
    Srgb,
    /// v^γ, from 8 bits.
    Gamma(f32),
}

impl Encoding {
    /// pbrt-v4's encoding names: `linear`, `sRGB`, `gamma <γ>`.
    pub fn parse(s: &str) -> Result<Encoding, String> {
        match s {
            "linear" => Ok(Encoding::Linear),
            "sRGB" => Ok(Encoding::Srgb),
            _ => match s.strip_prefix("gamma ").map(|g| g.trim().parse::<f32>()) {
                Some(Ok(g)) if g.is_finite() => Ok(Encoding::Gamma(g)),
                _ => Err(format!("unknown encoding \"{s}\" (linear, sRGB or \"gamma <value>\")")),
            },
        }
    }

    /// A filtered value decoded as pbrt-v4 decodes it: rounded to 8 bits first, except for
    /// `linear`.
    fn decode(self, v: f32) -> f32 {
        let q = || (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8 as f32 / 255.0;
        match self {
            Encoding::Linear => v,
            Encoding::Srgb => {
                let c = q();
                if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
            }
            Encoding::Gamma(g) => q().powf(g),
        }
    }
}

/// A loaded `ptex` texture.
pub struct PtexTexture {
    file: PtexFile,
    encoding: Encoding,
    scale: f32,
}

impl std::fmt::Debug for PtexTexture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PtexTexture")
            .field("faces", &self.file.faces.len())
            .field("channels", &self.file.channels)
            .field("encoding", &self.encoding)
            .field("scale", &self.scale)
            .finish()
    }
}

impl PtexTexture {
    /// Loads `path`. pbrt-v4 reads one- and three-channel files only.
    pub fn open(path: &Path, encoding: Encoding, scale: f32) -> Result<PtexTexture, String> {
        let file = PtexFile::open(path)?;
        if file.channels != 1 && file.channels != 3 {
            return Err(format!(
                "\"{}\" has {} channels; ptex textures have one or three (as in pbrt-v4)",
                path.display(),
                file.channels
            ));
        }
        Ok(PtexTexture { file, encoding, scale })
    }

    /// Channels (1 or 3).
    pub fn channels(&self) -> usize {
        self.file.channels
    }

    /// The texture of face `face` at `uv`, over the footprint ∂(u, v)/∂x and ∂(u, v)/∂y:
    /// one value per channel (the rest zero).
    pub fn lookup(&self, face: i32, uv: glam::Vec2, duvdx: glam::Vec2, duvdy: glam::Vec2) -> [f32; 3] {
        let nc = self.file.channels;
        let v = filter::eval(&self.file, nc, face, uv.x, uv.y, duvdx.x, duvdx.y, duvdy.x, duvdy.y);
        let mut out = [0.0; 3];
        for c in 0..nc {
            out[c] = self.encoding.decode(v[c]) * self.scale;
        }
        out
    }

    /// Whether the texture is gray for certain (one channel; a three-channel file counts as
    /// coloured).
    pub fn is_gray(&self) -> bool {
        self.file.channels == 1
    }

    /// Bytes of texel data in memory.
    pub fn memory_bytes(&self) -> usize {
        self.file.memory_bytes()
    }
}
