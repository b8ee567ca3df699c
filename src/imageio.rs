//! Reading and writing images: OpenEXR (float RGB, with metadata) and 8-bit sRGB PNG.
//! Outputs are written to a temporary file next to the target and renamed into place, so a
//! reader never sees half an image.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::color::Rgb;
use crate::error::{Error, Result};

/// A linear RGB image, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, row-major.
    pub pixels: Vec<Rgb>,
    /// String metadata (`nimbus:spp`, ...), kept in EXR attributes.
    pub metadata: BTreeMap<String, String>,
    /// Further named channels written beside R, G and B to EXR (a G-buffer's `Albedo.R`,
    /// `P.X`, ...), each row-major like `pixels`; PNG ignores them.
    pub channels: Vec<(String, Vec<f32>)>,
}

impl Image {
    /// Keeps `alpha` (one value per pixel) as channel `A` unless it is empty or all one.
    fn keep_alpha(&mut self, alpha: Vec<f32>) {
        if alpha.len() == self.pixels.len() && alpha.iter().any(|&a| a != 1.0) {
            self.channels.push(("A".into(), alpha));
        }
    }

    /// The alpha channel a file carried (RGBA PNG or OpenEXR), if not all one.
    pub fn alpha(&self) -> Option<&[f32]> {
        self.channels.iter().find(|(n, _)| n == "A").map(|(_, v)| v.as_slice())
    }

    /// The image whose pixel (x, y) is `f(x, y)`.
    pub fn from_fn(width: usize, height: usize, f: impl Fn(usize, usize) -> Rgb) -> Image {
        let mut img = Image::new(width, height);
        for y in 0..height {
            for x in 0..width {
                img.pixels[y * width + x] = f(x, y);
            }
        }
        img
    }

    /// A black image.
    pub fn new(width: usize, height: usize) -> Image {
        Image {
            width,
            height,
            pixels: vec![Rgb::ZERO; width * height],
            metadata: BTreeMap::new(),
            channels: Vec::new(),
        }
    }

    /// The pixel at (x, y).
    pub fn get(&self, x: usize, y: usize) -> Rgb {
        self.pixels[y * self.width + x]
    }

    /// Mean of every pixel.
    pub fn mean(&self) -> Rgb {
        let mut s = [0.0f64; 3];
        for p in &self.pixels {
            s[0] += p.x as f64;
            s[1] += p.y as f64;
            s[2] += p.z as f64;
        }
        let n = self.pixels.len().max(1) as f64;
        Rgb::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    }
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temp_path(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, "write", e)
    })
}

/// An OpenEXR library error on `path` by kind: the file system's errors stay [`Error::Io`]
/// (so that a missing file can be told apart), features the library lacks are
/// [`Error::Unsupported`], the rest are [`Error::Malformed`]. The text stays "path: cause".
fn exr_error(path: &Path, action: &'static str, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(source) => Error::io(path, action, source),
        exr::error::Error::NotSupported(_) => Error::Unsupported(format!("{}: {e}", path.display())),
        other => Error::malformed(path, other.to_string()),
    }
}

/// Writes `image` as `.exr` (32-bit float RGB) or `.png` (8-bit sRGB), chosen by extension.
pub fn write_image(path: &Path, image: &Image) -> Result<()> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) {
        Some(e) if e == "exr" => write_atomically(path, |tmp| write_exr(tmp, image)),
        Some(e) if e == "png" => write_atomically(path, |tmp| write_png(tmp, image)),
        _ => Err(Error::Unsupported(format!("{}: unsupported output format (use .exr or .png)", path.display()))),
    }
}

fn write_exr(path: &Path, image: &crate::imageio::Image) -> Result<()> {
    use exr::meta::attribute::{AttributeValue, Text};
    use exr::prelude::*;
    let (w, h) = (image.width, image.height);
    let mut attributes = LayerAttributes::named("");
    attributes.software_name = Some(Text::from("nimbus"));
    // EXR text holds single bytes: characters beyond Latin-1 (a σ in a message, a path in
    // another script) become '?' rather than failing the write.
    let text = |s: &str| {
        let latin1: String = s.chars().map(|c| if (c as u32) < 256 { c } else { '?' }).collect();
        Text::new_or_none(latin1.as_str()).unwrap_or_else(|| Text::from("?"))
    };
    for (k, v) in &image.metadata {
        attributes.other.insert(text(k), AttributeValue::Text(text(v)));
    }
    if image.channels.is_empty() {
        let layer = Layer::new(
            (w, h),
            attributes,
            Encoding::FAST_LOSSLESS,
            SpecificChannels::rgb(|pos: Vec2<usize>| {
                let p = image.pixels[pos.y() * w + pos.x()];
                (p.x, p.y, p.z)
            }),
        );
        return Image::from_layer(layer).write().to_file(path).map_err(|e| exr_error(path, "write", e));
    }
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        list.push(AnyChannel::new(*name, FlatSamples::F32(image.pixels.iter().map(|p| p[c]).collect())));
    }
    for (name, values) in &image.channels {
        if values.len() != w * h {
            // Spelt out: exr's prelude brings its own `Error` into this function.
            return Err(crate::error::Error::Invalid(format!(
                "{}: channel {name} has {} values for {w}x{h} pixels",
                path.display(),
                values.len()
            )));
        }
        list.push(AnyChannel::new(text(name), FlatSamples::F32(values.clone())));
    }
    let layer = Layer::new((w, h), attributes, Encoding::FAST_LOSSLESS, AnyChannels::sort(list));
    Image::from_layer(layer).write().to_file(path).map_err(|e| exr_error(path, "write", e))
}

/// sRGB opto-electronic transfer function.
fn srgb_encode(v: f32) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

fn write_png(path: &Path, image: &Image) -> Result<()> {
    // The encoder's own errors are about the image (its size), not the file.
    let err = |e: png::EncodingError| match e {
        png::EncodingError::IoError(source) => Error::io(path, "write", source),
        other => Error::Invalid(format!("{}: {other}", path.display())),
    };
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, "create", e))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), image.width as u32, image.height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    for (k, v) in &image.metadata {
        let _ = enc.add_text_chunk(k.clone(), v.clone());
    }
    let mut writer = enc.write_header().map_err(err)?;
    let data: Vec<u8> =
        image.pixels.iter().flat_map(|p| [srgb_encode(p.x), srgb_encode(p.y), srgb_encode(p.z)]).collect();
    writer.write_image_data(&data).map_err(err)?;
    writer.finish().map_err(err)
}

/// Reads an EXR (linear) or PNG (sRGB-encoded 8 or 16 bit) image as linear RGB.
pub fn read_image(path: &Path) -> Result<crate::imageio::Image> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()) {
        Some(e) if e == "exr" => read_exr(path),
        Some(e) if e == "png" => read_png(path),
        _ => Err(Error::Unsupported(format!(
            "{}: unsupported image format (nimbus reads .exr and .png)",
            path.display()
        ))),
    }
}

fn srgb_decode(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// Reads a PNG, decoding sRGB to linear.
pub fn read_png(path: &Path) -> Result<crate::imageio::Image> {
    // A file that ends early is corrupt, not unreadable: the decoder reports it as an I/O
    // error of kind UnexpectedEof.
    let err = |e: png::DecodingError| match e {
        png::DecodingError::IoError(source) if source.kind() != std::io::ErrorKind::UnexpectedEof => {
            Error::io(path, "read", source)
        }
        other => Error::malformed(path, other.to_string()),
    };
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, "read", e))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(err)?;
    let mut buf = vec![0; reader.output_buffer_size().ok_or_else(|| Error::malformed(path, "image too large"))?];
    let info = reader.next_frame(&mut buf).map_err(err)?;
    let (w, h) = (info.width as usize, info.height as usize);
    let channels = info.color_type.samples();
    let sixteen = info.bit_depth == png::BitDepth::Sixteen;
    let value = |i: usize| -> f32 {
        if sixteen { u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]]) as f32 / 65535.0 } else { buf[i] as f32 / 255.0 }
    };
    let mut pixels = Vec::with_capacity(w * h);
    let mut alpha = Vec::new();
    for k in 0..w * h {
        let base = k * channels;
        let rgb = match channels {
            1 | 2 => Rgb::splat(srgb_decode(value(base))),
            _ => Rgb::new(srgb_decode(value(base)), srgb_decode(value(base + 1)), srgb_decode(value(base + 2))),
        };
        pixels.push(rgb);
        // pbrt-v4 keeps an RGBA PNG's alpha (decoded like the colour channels; a gray PNG's
        // alpha it drops).
        if channels == 4 {
            alpha.push(srgb_decode(value(base + 3)));
        }
    }
    let mut image =
        crate::imageio::Image { width: w, height: h, pixels, metadata: BTreeMap::new(), channels: Vec::new() };
    image.keep_alpha(alpha);
    Ok(image)
}

/// Reads the first RGB(A) layer of an OpenEXR file (an alpha other than 1 kept as channel
/// `A`) and its text attributes.
pub fn read_exr(path: &Path) -> Result<crate::imageio::Image> {
    use exr::prelude::*;
    type Pixels = (usize, usize, Vec<Rgb>, Vec<f32>);
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| {
            let n = res.width() * res.height();
            (res.width(), res.height(), vec![Rgb::ZERO; n], vec![1.0; n])
        },
        |(w, _h, px, alpha): &mut Pixels, pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Rgb::new(r, g, b);
            alpha[pos.y() * *w + pos.x()] = a;
        },
    )
    .map_err(|e| exr_error(path, "read", e))?;
    let (width, height, pixels, alpha) = img.layer_data.channel_data.pixels;
    let mut metadata = BTreeMap::new();
    for (k, v) in &img.layer_data.attributes.other {
        if let exr::meta::attribute::AttributeValue::Text(t) = v {
            metadata.insert(k.to_string(), t.to_string());
        }
    }
    if pixels.iter().any(|p| !p.is_finite()) {
        return Err(crate::error::Error::malformed(path, "image contains NaN or infinite values"));
    }
    let mut image = crate::imageio::Image { width, height, pixels, metadata, channels: Vec::new() };
    image.keep_alpha(alpha);
    Ok(image)
}

/// Every channel of an OpenEXR file's first layer other than R, G, B and A, by name (a
/// G-buffer's `Albedo.R`, `P.X`, ...), as 32-bit floats in row-major order.
pub fn read_exr_channels(path: &Path) -> Result<Vec<(String, Vec<f32>)>> {
    use exr::prelude::*;
    let img = read_all_flat_layers_from_file(path).map_err(|e| exr_error(path, "read", e))?;
    let layer = img.layer_data.first().ok_or_else(|| crate::error::Error::malformed(path, "no layer"))?;
    Ok(layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect::<Vec<f32>>()))
        .filter(|(n, _)| !["R", "G", "B", "A"].contains(&n.as_str()))
        .collect())
}

/// The first three channels of an image file in the order pbrt-v4 reads them, per pixel: for
/// an OpenEXR file its channel list, which is sorted by name (B, G, R; with alpha A, B, G),
/// and `None` for other formats (R, G, B) or files with fewer channels.
pub fn pbrt_channel_order(path: &Path) -> Result<Option<Vec<Rgb>>> {
    use exr::prelude::*;
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        return Ok(None);
    }
    let img = read_all_flat_layers_from_file(path).map_err(|e| exr_error(path, "read", e))?;
    let layer = img.layer_data.first().ok_or_else(|| crate::error::Error::malformed(path, "no layer"))?;
    let mut channels: Vec<_> = layer.channel_data.list.iter().collect();
    channels.sort_by_key(|c| c.name.to_string());
    if channels.len() < 3 {
        return Ok(None);
    }
    let v: Vec<Vec<f32>> = channels[..3].iter().map(|c| c.sample_data.values_as_f32().collect()).collect();
    Ok(Some((0..v[0].len()).map(|i| Rgb::new(v[0][i], v[1][i], v[2][i])).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_keeps_pixels_and_metadata() {
        let dir = std::env::temp_dir().join(format!("nimbus-imageio-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.exr");
        let mut img = Image::new(3, 2);
        img.pixels[4] = Rgb::new(0.25, 1.5, 3.0);
        img.metadata.insert("nimbus:spp".into(), "16".into());
        write_image(&path, &img).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        assert_eq!(back.pixels, img.pixels);
        assert_eq!(back.metadata.get("nimbus:spp").map(String::as_str), Some("16"));
        write_image(&dir.join("t.png"), &img).unwrap();
        assert!(write_image(&dir.join("t.bmp"), &img).is_err());
        assert_eq!(srgb_encode(1.0), 255);
        assert_eq!(srgb_encode(0.0), 0);
        assert_eq!(srgb_encode(0.5), 188);
        // Metadata beyond Latin-1 is written with '?' in its place, not a panic.
        img.metadata.insert("nimbus:scene".into(), "сцены/σ.pbrt".into());
        write_image(&path, &img).unwrap();
        assert_eq!(read_exr(&path).unwrap().metadata.get("nimbus:scene").map(String::as_str), Some("?????/?.pbrt"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn rgba_png_alpha_is_kept_as_pbrt_decodes_it() {
        let dir = std::env::temp_dir().join(format!("nimbus-imageio-alpha-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.png");
        let file = std::fs::File::create(&path).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 2, 1);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[255, 0, 0, 255, 0, 255, 0, 128]).unwrap();
        w.finish().unwrap();
        let img = read_png(&path).unwrap();
        assert_eq!(img.pixels[0], Rgb::new(1.0, 0.0, 0.0));
        // pbrt-v4 decodes an 8-bit alpha with the image's encoding, sRGB here.
        let a = img.alpha().expect("alpha kept");
        assert!(a[0] == 1.0 && (a[1] - srgb_decode(128.0 / 255.0)).abs() < 1e-6, "{a:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
