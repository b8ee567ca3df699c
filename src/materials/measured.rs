//! pbrt-v4's measured BRDFs (`Material "measured"`): the `.bsdf` tensor files of Dupuy and
//! Jakob, "An Adaptive Parameterization for Efficient Material Acquisition and Rendering"
//! (2018) — an NDF, the projected microfacet area σ, a visible-NDF warp and a luminance warp
//! (each tabulated over the incident direction), and spectral BRDF values in the warped
//! coordinates. This module reads the file into [`MeasuredData`]; the BxDF that evaluates and
//! samples it is [`crate::materials::bxdf::MeasuredBxdf`].

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;
use nimbus_parser::ColorSpace;

use crate::error::{Error, Result};
use crate::sampling::piecewise_linear::PiecewiseLinear2D;
use crate::spectra::{PiecewiseLinearSpectrum, spectrum_reflectance_rgb};

/// The tables of one measured BRDF.
#[derive(Debug)]
pub struct MeasuredData {
    /// The normal distribution D over (θ, φ) of the half vector, in unit-square coordinates.
    pub ndf: PiecewiseLinear2D,
    /// Projected microfacet area σ over the outgoing direction.
    pub sigma: PiecewiseLinear2D,
    /// The visible-NDF warp, conditioned on (φo, θo).
    pub vndf: PiecewiseLinear2D,
    /// The luminance warp, conditioned on (φo, θo).
    pub luminance: PiecewiseLinear2D,
    /// BRDF values in the warped coordinates, conditioned on (φo, θo, λ).
    pub spectra: PiecewiseLinear2D,
    /// The same as RGB reflectances in the film's color space, conditioned on (φo, θo,
    /// channel 0, 1, 2), for RGB transport.
    pub rgb: PiecewiseLinear2D,
    /// True for isotropic materials (φ measured relative to the outgoing direction).
    pub isotropic: bool,
}

/// A measured BRDF shared by every material that names its file (compared by identity).
#[derive(Clone, Debug)]
pub struct SharedMeasured(pub std::sync::Arc<MeasuredData>);

impl PartialEq for SharedMeasured {
    fn eq(&self, o: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &o.0)
    }
}

/// One field of a tensor file: its element type code, shape and raw little-endian bytes.
struct Field {
    dtype: u8,
    shape: Vec<usize>,
    data: Vec<u8>,
}

const UINT8: u8 = 1;
const FLOAT32: u8 = 10;

/// Bytes per element of each type code (pbrt-v4's `Tensor::Type`: 1..=11 are u8, i8, u16,
/// i16, u32, i32, u64, i64, f16, f32, f64).
fn type_size(dtype: u8) -> Option<usize> {
    Some(match dtype {
        1 | 2 => 1,
        3 | 4 | 9 => 2,
        5 | 6 | 10 => 4,
        7 | 8 | 11 => 8,
        _ => return None,
    })
}

/// Reads a tensor file (pbrt-v4's format: "tensor_file\0", version 1.0, then named fields
/// with a type, an offset and a shape).
fn read_tensor(bytes: &[u8]) -> Result<HashMap<String, Field>, String> {
    let take = |at: usize, n: usize| bytes.get(at..at + n).ok_or_else(|| "truncated tensor file".to_string());
    if take(0, 12)? != b"tensor_file\0" {
        return Err("not a tensor file (its header is not \"tensor_file\")".into());
    }
    let version = take(12, 2)?;
    if version != [1, 0] {
        return Err(format!("tensor file version {}.{} is not 1.0", version[0], version[1]));
    }
    let n_fields = u32::from_le_bytes(take(14, 4)?.try_into().unwrap());
    let mut at = 18;
    let mut fields = HashMap::new();
    for _ in 0..n_fields {
        let name_len = u16::from_le_bytes(take(at, 2)?.try_into().unwrap()) as usize;
        let name = String::from_utf8_lossy(take(at + 2, name_len)?).into_owned();
        at += 2 + name_len;
        let ndim = u16::from_le_bytes(take(at, 2)?.try_into().unwrap()) as usize;
        let dtype = take(at + 2, 1)?[0];
        let offset = u64::from_le_bytes(take(at + 3, 8)?.try_into().unwrap()) as usize;
        at += 11;
        let mut shape = Vec::with_capacity(ndim);
        let mut total = type_size(dtype).ok_or_else(|| format!("field \"{name}\" has unknown type {dtype}"))?;
        for _ in 0..ndim {
            let n = u64::from_le_bytes(take(at, 8)?.try_into().unwrap()) as usize;
            at += 8;
            shape.push(n);
            total = total.checked_mul(n).ok_or_else(|| format!("field \"{name}\" is too large"))?;
        }
        let data = bytes
            .get(offset..offset.saturating_add(total))
            .ok_or_else(|| format!("field \"{name}\" runs past the end of the file"))?
            .to_vec();
        fields.insert(name, Field { dtype, shape, data });
    }
    Ok(fields)
}

impl Field {
    fn floats(&self) -> Vec<f32> {
        self.data.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect()
    }
}

impl MeasuredData {
    /// Reads `path`, checking the fields' shapes as pbrt-v4 does; RGB tables are made for
    /// `film`'s color space. A file that cannot be read is [`Error::Io`], one whose contents
    /// are wrong [`Error::Malformed`].
    pub fn read(path: &Path, film: ColorSpace) -> Result<MeasuredData> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", e))?;
        MeasuredData::parse(&bytes, film).map_err(|m| Error::malformed(path, m))
    }

    /// [`MeasuredData::read`] from the file's bytes. Having no file to name, the errors are
    /// [`Error::Invalid`] with the message alone.
    pub fn from_bytes(bytes: &[u8], film: ColorSpace) -> Result<MeasuredData> {
        MeasuredData::parse(bytes, film).map_err(Error::Invalid)
    }

    /// [`MeasuredData::from_bytes`] with the message alone, for [`MeasuredData::read`] to name
    /// the file.
    fn parse(bytes: &[u8], film: ColorSpace) -> Result<MeasuredData, String> {
        let t = read_tensor(bytes)?;
        let get = |name: &str, dtype: u8, ndim: usize| -> Result<&Field, String> {
            let f = t.get(name).ok_or_else(|| format!("invalid BRDF file: no field \"{name}\""))?;
            if f.dtype != dtype || f.shape.len() != ndim {
                return Err(format!("invalid BRDF file: field \"{name}\" has the wrong type or rank"));
            }
            Ok(f)
        };
        let theta_i = get("theta_i", FLOAT32, 1)?;
        let phi_i = get("phi_i", FLOAT32, 1)?;
        let ndf = get("ndf", FLOAT32, 2)?;
        let sigma = get("sigma", FLOAT32, 2)?;
        let vndf = get("vndf", FLOAT32, 4)?;
        let luminance = get("luminance", FLOAT32, 4)?;
        let spectra = get("spectra", FLOAT32, 5)?;
        let wavelengths = get("wavelengths", FLOAT32, 1)?;
        get("description", UINT8, 1)?;
        let jacobian = get("jacobian", UINT8, 1)?;
        let (np, nt) = (phi_i.shape[0], theta_i.shape[0]);
        let (vs, ls, ss) = (&vndf.shape, &luminance.shape, &spectra.shape);
        let ok = vs[0] == np
            && vs[1] == nt
            && ls[0] == np
            && ls[1] == nt
            && ls[2] == ls[3]
            && ss[0] == np
            && ss[1] == nt
            && ss[2] == wavelengths.shape[0]
            && ss[3] == ss[4]
            && ls[2] == ss[3]
            && ls[3] == ss[4]
            && jacobian.shape[0] == 1;
        if !ok {
            return Err("invalid BRDF file structure (field shapes do not agree)".into());
        }
        let (phi, theta, lambda) = (phi_i.floats(), theta_i.floats(), wavelengths.floats());
        let isotropic = np <= 2;
        if !isotropic {
            let reduction = (2.0 * std::f32::consts::PI / (phi[np - 1] - phi[0])).round();
            if reduction != 1.0 {
                return Err(format!("reduction {reduction} (!= 1) is not supported (nor is it by pbrt-v4)"));
            }
        }
        let bad = |what: &str| format!("invalid BRDF file: the {what} table is malformed or zero");
        let ndf = PiecewiseLinear2D::new(&ndf.floats(), ndf.shape[1], ndf.shape[0], &[], false, false)
            .ok_or_else(|| bad("ndf"))?;
        let sigma = PiecewiseLinear2D::new(&sigma.floats(), sigma.shape[1], sigma.shape[0], &[], false, false)
            .ok_or_else(|| bad("sigma"))?;
        let vndf = PiecewiseLinear2D::new(&vndf.floats(), vs[3], vs[2], &[&phi, &theta], true, true)
            .ok_or_else(|| bad("vndf"))?;
        let luminance = PiecewiseLinear2D::new(&luminance.floats(), ls[3], ls[2], &[&phi, &theta], true, true)
            .ok_or_else(|| bad("luminance"))?;
        let values = spectra.floats();
        if values.iter().any(|v| !v.is_finite()) {
            return Err(bad("spectra"));
        }
        // RGB: each wavelength node's hat function seen as a reflectance under the film's
        // illuminant, so that RGB = Σ_k s_k W_k is the tabulated spectrum's reflectance RGB.
        let weights: Vec<Vec3> = (0..lambda.len())
            .map(|k| {
                // Beyond the table the values are held (the tables clamp the parameter).
                let last = lambda.len() - 1;
                let mut pairs: Vec<(f64, f64)> =
                    lambda.iter().enumerate().map(|(j, &l)| (l as f64, if j == k { 1.0 } else { 0.0 })).collect();
                if lambda[0] > 360.0 {
                    pairs.insert(0, (360.0, if k == 0 { 1.0 } else { 0.0 }));
                }
                if lambda[last] < 830.0 {
                    pairs.push((830.0, if k == last { 1.0 } else { 0.0 }));
                }
                match PiecewiseLinearSpectrum::from_pairs(pairs, "measured BRDF wavelengths") {
                    Ok(s) => spectrum_reflectance_rgb(&crate::spectra::Spectrum::PiecewiseLinear(s), film),
                    Err(_) => Vec3::ZERO,
                }
            })
            .collect();
        if lambda.windows(2).any(|w| w[1] <= w[0]) {
            return Err("invalid BRDF file: wavelengths do not increase".into());
        }
        let grid = ss[3] * ss[4];
        let mut rgb = vec![0.0f32; np * nt * 3 * grid];
        for a in 0..np * nt {
            for k in 0..lambda.len() {
                let src = &values[(a * lambda.len() + k) * grid..(a * lambda.len() + k + 1) * grid];
                for c in 0..3 {
                    let dst = &mut rgb[(a * 3 + c) * grid..(a * 3 + c + 1) * grid];
                    for (d, s) in dst.iter_mut().zip(src) {
                        *d += weights[k][c] * s;
                    }
                }
            }
        }
        let channels = [0.0, 1.0, 2.0];
        let spectra = PiecewiseLinear2D::new(&values, ss[4], ss[3], &[&phi, &theta, &lambda], false, false)
            .ok_or_else(|| bad("spectra"))?;
        let rgb = PiecewiseLinear2D::new(&rgb, ss[4], ss[3], &[&phi, &theta, &channels], false, false)
            .ok_or_else(|| bad("spectra"))?;
        Ok(MeasuredData { ndf, sigma, vndf, luminance, spectra, rgb, isotropic })
    }

    /// Bytes of table data.
    pub fn bytes(&self) -> usize {
        [&self.ndf, &self.sigma, &self.vndf, &self.luminance, &self.spectra, &self.rgb].iter().map(|t| t.bytes()).sum()
    }
}

/// Writes a tensor file with `fields` (name, type code, shape, little-endian data): the
/// format [`MeasuredData::read`] reads, for test data.
pub fn write_tensor(fields: &[(&str, u8, Vec<usize>, Vec<u8>)]) -> Vec<u8> {
    let mut header = Vec::new();
    header.extend_from_slice(b"tensor_file\0");
    header.extend_from_slice(&[1, 0]);
    header.extend_from_slice(&(fields.len() as u32).to_le_bytes());
    let header_len: usize = 18 + fields.iter().map(|(n, _, s, _)| 2 + n.len() + 2 + 1 + 8 + 8 * s.len()).sum::<usize>();
    let mut offset = header_len;
    let mut body = Vec::new();
    for (name, dtype, shape, data) in fields {
        header.extend_from_slice(&(name.len() as u16).to_le_bytes());
        header.extend_from_slice(name.as_bytes());
        header.extend_from_slice(&(shape.len() as u16).to_le_bytes());
        header.push(*dtype);
        header.extend_from_slice(&(offset as u64).to_le_bytes());
        for n in shape {
            header.extend_from_slice(&(*n as u64).to_le_bytes());
        }
        body.extend_from_slice(data);
        offset += data.len();
    }
    header.extend(body);
    header
}

/// A small synthetic `.bsdf` file (isotropic, 4 incident elevations, 3 wavelengths, 8 × 8
/// grids of smooth positive values; `gray` makes the spectra the same at every wavelength):
/// not a physical material, but every table is valid, which is what sampling, inversion and
/// evaluation must be consistent on.
pub fn synthetic_bsdf(gray: bool) -> Vec<u8> {
    const N: usize = 8;
    let f32s = |v: Vec<f32>| v.into_iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let grid = |f: &dyn Fn(f32, f32) -> f32| {
        let mut v = Vec::with_capacity(N * N);
        for y in 0..N {
            for x in 0..N {
                v.push(f(x as f32 / (N - 1) as f32, y as f32 / (N - 1) as f32));
            }
        }
        v
    };
    let thetas = [0.0f32, 0.5, 1.0, 1.5];
    let lambdas = [400.0f32, 550.0, 700.0];
    let mut vndf = Vec::new();
    let mut lum = Vec::new();
    let mut spectra = Vec::new();
    for (t, _) in thetas.iter().enumerate() {
        let t = t as f32;
        vndf.extend(grid(&|x, y| 1.0 + 0.3 * (2.0 * x + t).sin() + 0.2 * y));
        lum.extend(grid(&|x, y| 1.0 + 0.4 * x * y + 0.1 * t));
        for k in 0..lambdas.len() {
            let k = if gray { 1.0 } else { k as f32 };
            spectra.extend(grid(&|x, y| 0.05 + 0.02 * k + 0.03 * x + 0.01 * y));
        }
    }
    write_tensor(&[
        ("description", UINT8, vec![1], vec![b'x']),
        ("jacobian", UINT8, vec![1], vec![1]),
        ("theta_i", FLOAT32, vec![thetas.len()], f32s(thetas.to_vec())),
        ("phi_i", FLOAT32, vec![1], f32s(vec![0.0])),
        ("wavelengths", FLOAT32, vec![3], f32s(lambdas.to_vec())),
        ("ndf", FLOAT32, vec![N, N], f32s(grid(&|x, _| 1.0 + 0.5 * (3.0 * x).cos()))),
        ("sigma", FLOAT32, vec![N, N], f32s(grid(&|x, _| 0.8 + 0.2 * x))),
        ("vndf", FLOAT32, vec![1, thetas.len(), N, N], f32s(vndf)),
        ("luminance", FLOAT32, vec![1, thetas.len(), N, N], f32s(lum)),
        ("spectra", FLOAT32, vec![1, thetas.len(), 3, N, N], f32s(spectra)),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_its_tables_and_refuses_broken_files() {
        let bytes = synthetic_bsdf(false);
        let d = MeasuredData::from_bytes(&bytes, ColorSpace::Srgb).unwrap();
        assert!(d.isotropic);
        assert!(d.bytes() > 0);
        // The RGB version of a gray spectrum is gray with the same value.
        let g = MeasuredData::from_bytes(&synthetic_bsdf(true), ColorSpace::Srgb).unwrap();
        let p = glam::Vec2::new(0.3, 0.6);
        let s = g.spectra.evaluate(p, &[0.0, 0.7, 500.0]);
        for c in [0.0, 1.0, 2.0] {
            let r = g.rgb.evaluate(p, &[0.0, 0.7, c]);
            assert!((r - s).abs() < 2e-3 * s, "channel {c}: {r} vs {s}");
        }
        assert!(
            MeasuredData::from_bytes(&bytes[..bytes.len() / 2], ColorSpace::Srgb)
                .unwrap_err()
                .to_string()
                .contains("past the end")
        );
        assert!(
            MeasuredData::from_bytes(b"not a tensor file at all", ColorSpace::Srgb)
                .unwrap_err()
                .to_string()
                .contains("header")
        );
        let mut wrong = bytes.clone();
        wrong[12] = 2;
        assert!(MeasuredData::from_bytes(&wrong, ColorSpace::Srgb).unwrap_err().to_string().contains("version"));
        let missing = write_tensor(&[("description", UINT8, vec![1], vec![b'x'])]);
        assert!(MeasuredData::from_bytes(&missing, ColorSpace::Srgb).unwrap_err().to_string().contains("no field"));
    }
}
