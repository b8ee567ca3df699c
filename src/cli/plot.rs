//! What every chart of the CLI shares: the embedded font, writing SVG and PNG from one
//! drawing function, and number labels. Charts use `plotters`; text uses a subset of DejaVu
//! Sans embedded in the binary (`assets/fonts/`), so no system font is needed.

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");

/// The font family charts name.
pub const FAMILY: &str = "sans-serif";

/// A number with about three significant digits and no trailing zeros: 0.25, 3, 120.
pub fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if !(1e-3..1e5).contains(&v.abs()) {
        return format!("{v:.0e}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// An SVG drawing area.
pub type Svg<'a> = DrawingArea<SVGBackend<'a>, Shift>;
/// A bitmap drawing area.
pub type Bitmap<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Writes `<base>.svg` and `<base>.png` of `size` pixels, drawn by `svg` and `png` (the same
/// generic drawing function on each backend).
pub fn write_both(
    base: &Path,
    size: (u32, u32),
    svg: impl FnOnce(Svg<'_>) -> Result<()>,
    png: impl FnOnce(Bitmap<'_>) -> Result<()>,
) -> Result<()> {
    plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
        .map_err(|_| anyhow!("the embedded chart font cannot be read"))?;
    let mut text = String::new();
    svg(SVGBackend::with_string(&mut text, size).into_drawing_area())?;
    let path = base.with_extension("svg");
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;

    let mut rgb = vec![255u8; (size.0 * size.1 * 3) as usize];
    png(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area())?;
    let path = base.with_extension("png");
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, size.0, size.1);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().context("encoding a chart")?;
    writer.write_image_data(&rgb).context("encoding a chart")?;
    writer.finish().context("encoding a chart")?;
    std::fs::write(&path, bytes).with_context(|| format!("writing {}", path.display()))
}

/// A drawing error as an error of the command.
pub fn plot_err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing a chart: {e}")
}
