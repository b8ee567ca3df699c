//! pbrt-v4's `ptex` texture: a Ptex file (per-face textures of a quad or triangle mesh) looked
//! up at the hit's face index (the shape's `faceIndices`) and (u, v), filtered as the Ptex
//! library filters for pbrt-v4 (its B-spline filter for quad files, its elliptical Gaussian
//! for triangle files) over the hit's (u, v) footprint, then, for an encoding other than linear,
//! quantised to 8 bits and decoded (pbrt-v4's `PtexTextureBase::SampleTexture`), and scaled.

mod file;
mod filter;
mod kernel;
mod texels;
mod triangle;

use std::path::Path;

use crate::error::{Error, Result};

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
    /// pbrt-v4's encoding names: `linear`, `sRGB`, `gamma <γ>`; another is [`Error::Invalid`].
    pub fn parse(s: &str) -> Result<Encoding> {
        match s {
            "linear" => Ok(Encoding::Linear),
            "sRGB" => Ok(Encoding::Srgb),
            _ => match s.strip_prefix("gamma ").map(|g| g.trim().parse::<f32>()) {
                Some(Ok(g)) if g.is_finite() => Ok(Encoding::Gamma(g)),
                _ => Err(Error::Invalid(format!("unknown encoding \"{s}\" (linear, sRGB or \"gamma <value>\")"))),
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

/// The first `nchan` (≤ 4) channels of `file`'s face `face` at (u, v) over the footprint
/// spanned by (uw1, vw1) and (uw2, vw2), scaled to [0, 1] for integer data, as the Ptex
/// library filters for pbrt-v4: a face whose neighbourhood is one constant reads it, triangle
/// files are filtered by the library's elliptical Gaussian whatever filter is asked for, quad
/// files by the B-spline pbrt-v4 asks for. A face id the file does not have reads zero.
#[allow(clippy::too_many_arguments)]
fn filtered(
    file: &PtexFile,
    nchan: usize,
    face: i32,
    u: f32,
    v: f32,
    uw1: f32,
    vw1: f32,
    uw2: f32,
    vw2: f32,
) -> [f32; 4] {
    let nchan = nchan.min(file.channels).min(4);
    let mut out = [0.0; 4];
    let Some(f) = usize::try_from(face).ok().and_then(|i| file.faces.get(i)) else { return out };
    if !(u.is_finite() && v.is_finite()) {
        return out;
    }
    let one = file.data_type.one();
    if f.is_neighbourhood_constant() {
        for (c, o) in out.iter_mut().enumerate().take(nchan) {
            *o = file.constant_value(face as usize, c) * (1.0 / one);
        }
        return out;
    }
    let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
    let (uw1, vw1, uw2, vw2) = (finite(uw1), finite(vw1), finite(uw2), finite(vw2));
    let eval = if file.triangles { triangle::eval } else { filter::eval };
    let (sums, weight) = eval(file, nchan, face, f, u, v, [uw1, vw1, uw2, vw2]);
    // Normalised by the weight applied and the data type's 1.
    if weight != 0.0 && weight.is_finite() {
        let scale = 1.0 / (weight * one);
        for (o, s) in out.iter_mut().zip(sums).take(nchan) {
            *o = s * scale;
        }
    }
    out
}

/// Ptex's `calcResFromWidth`: ⌈log₂(1/w)⌉, read from the float's exponent.
fn res_from_width(w: f32) -> i32 {
    127 - ((w.to_bits() >> 23) & 0xff) as i32
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
    /// Loads `path`. pbrt-v4 reads one- and three-channel files only: others are
    /// [`Error::Unsupported`].
    pub fn open(path: &Path, encoding: Encoding, scale: f32) -> Result<PtexTexture> {
        let file = PtexFile::open(path)?;
        if file.channels != 1 && file.channels != 3 {
            return Err(Error::Unsupported(format!(
                "\"{}\" has {} channels; ptex textures have one or three (as in pbrt-v4)",
                path.display(),
                file.channels
            )));
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
        let v = filtered(&self.file, nc, face, uv.x, uv.y, duvdx.x, duvdx.y, duvdy.x, duvdy.y);
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;
    use std::path::PathBuf;

    fn fixtures() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/ptex")
    }

    /// Every lookup of `expected.txt` (made with the Ptex library itself, set up as pbrt-v4
    /// sets it up) agrees with the port to float rounding: quad grids with a constant face, a
    /// 4×4 face and a 32×8 one (anisotropic reductions), a rotated face, a cube (valence-3
    /// corners), a valence-5 fan, subfaces and their T-junctions, neighbourhood-constant
    /// faces, half, float and 16-bit data, a tiled face with a constant tile; footprints from
    /// none to wider than a face, skewed and anisotropic.
    #[test]
    fn lookups_match_the_ptex_library() {
        let text = std::fs::read_to_string(fixtures().join("expected.txt")).unwrap();
        let mut files: HashMap<String, PtexFile> = HashMap::new();
        let (mut n, mut worst) = (0, 0f32);
        for line in text.lines().filter(|l| !l.trim().is_empty()) {
            let w: Vec<&str> = line.split_whitespace().collect();
            let file = files.entry(w[0].to_string()).or_insert_with(|| PtexFile::open(&fixtures().join(w[0])).unwrap());
            let f: Vec<f32> = w[2..8].iter().map(|x| x.parse().unwrap()).collect();
            let nchan: usize = w[8].parse().unwrap();
            let want: Vec<f32> = w[9..9 + nchan].iter().map(|x| x.parse().unwrap()).collect();
            let got = filtered(file, nchan, w[1].parse().unwrap(), f[0], f[1], f[2], f[3], f[4], f[5]);
            for c in 0..nchan {
                let err = (got[c] - want[c]).abs() / want[c].abs().max(1e-3);
                worst = worst.max(err);
                assert!(err < 1e-4, "{line}: channel {c} {} (library {})", got[c], want[c]);
            }
            n += 1;
        }
        assert!(n >= 1000, "{n} lookups");
        eprintln!("{n} lookups, worst relative difference {worst:e}");
    }
}
