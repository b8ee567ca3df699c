//! The matrix as a heat map: a row per condition, a column per integrator, each cell coloured
//! by log relMSE ratio to volpath (blue better, red worse, white the same), labelled with the
//! ratio; refused cells gray, failed cells black, biased cells outlined with their bias.

use nimbus::integrators::REFERENCE;
use std::path::Path;

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::Matrix;
use super::verdict::{self, Verdict};
use crate::cli::plot::{FAMILY, plot_err, short, write_both};

const ROW: i32 = 30;
const COL: i32 = 128;
const LABEL: i32 = 150;
const TOP: i32 = 70;
const BOTTOM: i32 = 90 + 18;

/// Ratios are coloured on a log₂ scale saturating at this many doublings.
const SATURATE: f64 = 3.0;

fn size(m: &Matrix) -> (u32, u32) {
    let w = LABEL + COL * m.integrators.len() as i32 + 20;
    let h = TOP + ROW * m.conditions.len() as i32 + BOTTOM;
    (w.max(640) as u32, h as u32)
}

/// Blue (better) through white to red (worse), by log₂ of the ratio.
fn ratio_color(ratio: f64) -> RGBColor {
    let t = (ratio.log2() / SATURATE).clamp(-1.0, 1.0);
    let mix = |a: u8, b: u8, f: f64| (a as f64 + (b as f64 - a as f64) * f).round() as u8;
    let (end, f) = if t < 0.0 { ((33, 102, 172), -t) } else { ((178, 24, 43), t) };
    RGBColor(mix(255, end.0, f), mix(255, end.1, f), mix(255, end.2, f))
}

/// Writes `<base>.svg` and `<base>.png`.
pub fn draw(m: &Matrix, base: &Path) -> Result<()> {
    write_both(base, size(m), |root| draw_on(m, root), |root| draw_on(m, root))
}

fn text_style(size: u32, color: RGBColor, h: HPos) -> TextStyle<'static> {
    TextStyle { font: (FAMILY, size).into_font(), color: color.to_backend_color(), pos: Pos::new(h, VPos::Center) }
}

fn draw_on<DB: DrawingBackend>(m: &Matrix, root: DrawingArea<DB, Shift>) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_err)?;
    let title = format!("relMSE relative to {REFERENCE} at equal time ({} s per cell)", short(m.time));
    root.draw(&Text::new(title, (LABEL, 22), text_style(18, BLACK, HPos::Left))).map_err(plot_err)?;
    for (j, name) in m.integrators.iter().enumerate() {
        let x = LABEL + COL * j as i32 + COL / 2;
        root.draw(&Text::new(name.clone(), (x, TOP - 14), text_style(14, BLACK, HPos::Center))).map_err(plot_err)?;
    }
    for (i, (cond, _)) in m.conditions.iter().enumerate() {
        let y0 = TOP + ROW * i as i32;
        root.draw(&Text::new(cond.clone(), (LABEL - 8, y0 + ROW / 2), text_style(13, BLACK, HPos::Right)))
            .map_err(plot_err)?;
        for (j, name) in m.integrators.iter().enumerate() {
            let x0 = LABEL + COL * j as i32;
            let Some((cell, v)) = m.cell(cond, name) else { continue };
            let baseline = m.cell(cond, REFERENCE).map(|(b, _)| b);
            let ratio = baseline.and_then(|b| verdict::ratio(cell, b)).map(|(r, _)| r);
            let (fill, ink, label) = match v {
                Verdict::Refused(_) => (RGBColor(215, 215, 215), RGBColor(80, 80, 80), "refused".to_string()),
                Verdict::Failed(_) => (BLACK, WHITE, "FAILED".to_string()),
                Verdict::Baseline => (WHITE, BLACK, "1x".to_string()),
                _ => match ratio {
                    Some(r) => {
                        let ink = if (r.log2() / SATURATE).abs() > 0.6 { WHITE } else { BLACK };
                        (ratio_color(r), ink, format!("{}x", short(r)))
                    }
                    None => (WHITE, BLACK, v.label().to_string()),
                },
            };
            let biased = verdict::biased(cell);
            let label = match (&cell.measured, biased) {
                (Some(x), true) => format!("{label} b{:+.0}%", 100.0 * x.bias),
                _ => label,
            };
            let rect = [(x0 + 1, y0 + 1), (x0 + COL - 1, y0 + ROW - 1)];
            root.draw(&Rectangle::new(rect, fill.filled())).map_err(plot_err)?;
            if biased {
                let inner = [(x0 + 2, y0 + 2), (x0 + COL - 2, y0 + ROW - 2)];
                root.draw(&Rectangle::new(inner, RGBColor(255, 170, 0).stroke_width(3))).map_err(plot_err)?;
            }
            root.draw(&Text::new(label, (x0 + COL / 2, y0 + ROW / 2), text_style(13, ink, HPos::Center)))
                .map_err(plot_err)?;
        }
    }
    // The colour scale: 1/8x to 8x, and what the marks mean.
    let y = TOP + ROW * m.conditions.len() as i32 + 24;
    let steps = 13;
    for k in 0..steps {
        let r = 2f64.powf(SATURATE * (2.0 * k as f64 / (steps - 1) as f64 - 1.0));
        let x0 = LABEL + 34 * k;
        root.draw(&Rectangle::new([(x0, y), (x0 + 33, y + 16)], ratio_color(r).filled())).map_err(plot_err)?;
        if k % 2 == 0 {
            root.draw(&Text::new(format!("{}x", short(r)), (x0 + 16, y + 28), text_style(11, BLACK, HPos::Center)))
                .map_err(plot_err)?;
        }
    }
    let note =
        format!("blue: lower relMSE than {REFERENCE}; red: higher; orange outline: biased (b: mean off the reference)");
    root.draw(&Text::new(note, (LABEL, y + 50), text_style(12, BLACK, HPos::Left))).map_err(plot_err)?;
    // What went wrong, counted: failures and biased cells side by side.
    root.draw(&Text::new(super::report::counts(m), (LABEL, y + 68), text_style(12, BLACK, HPos::Left)))
        .map_err(plot_err)?;
    root.present().map_err(plot_err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_run_from_blue_through_white_to_red() {
        assert_eq!(ratio_color(1.0), RGBColor(255, 255, 255));
        assert_eq!(ratio_color(1.0 / 64.0), RGBColor(33, 102, 172));
        assert_eq!(ratio_color(64.0), RGBColor(178, 24, 43));
        let half = ratio_color(2f64.powf(SATURATE / 2.0));
        assert!(half.0 > half.2 && half.1 < 255);
    }
}
