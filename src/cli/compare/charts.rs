//! Charts of a comparison with `plotters`, each as SVG and PNG. Text uses a subset of DejaVu
//! Sans embedded in the binary (`assets/fonts/`), so no system font is needed.

use std::path::Path;

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::run::Mode;
use super::stats::Summary;
use super::{Comparison, Run, report};
use crate::cli::plot::{FAMILY, plot_err, short, write_both};

const SIZE: (u32, u32) = (800, 500);

/// Tableau 10: one color per integrator, in the order given on the command line.
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn color_of(cmp: &Comparison, integrator: &str) -> RGBColor {
    let mut names: Vec<&str> = Vec::new();
    for r in &cmp.runs {
        if !names.contains(&r.integrator.as_str()) {
            names.push(&r.integrator);
        }
    }
    let i = names.iter().position(|n| *n == integrator).unwrap_or(0);
    COLORS[i % COLORS.len()]
}

/// An integrator's colour as CSS (`#rrggbb`), the same as in the charts.
pub fn css_color(cmp: &Comparison, integrator: &str) -> String {
    let c = color_of(cmp, integrator);
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

fn mode_title(cmp: &Comparison, mode: Mode) -> String {
    match mode {
        Mode::EqualTime => format!("equal time, {} s", short(cmp.time_budget.unwrap_or(0.0))),
        Mode::EqualSpp => format!("equal spp, {} spp", cmp.spp.unwrap_or(0)),
    }
}

/// Lower and upper ends of a log axis around the positive values.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi { (1e-3, 1.0) } else { (lo / 1.5, hi * 1.5) }
}

/// relMSE (the reference's noise removed when it has halves) against time since the scene
/// was built, log-log, a line per integrator and seed through its checkpoints: equal-time runs
/// if there are any, else equal-spp runs.
pub fn error_vs_time(cmp: &Comparison, base: &Path) -> Result<()> {
    write_both(base, SIZE, |root| draw_error_vs_time(cmp, root), |root| draw_error_vs_time(cmp, root))
}

fn draw_error_vs_time<DB: DrawingBackend>(cmp: &Comparison, root: DrawingArea<DB, Shift>) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let mode = cmp.headline_mode();
    let runs: Vec<&Run> = cmp.runs_of(mode).collect();
    let points = |r: &Run| -> Vec<(f64, f64)> {
        r.checkpoints
            .iter()
            .map(|c| (c.seconds, super::stats::best(c).rel_mse))
            .filter(|(t, e)| *t > 0.0 && *e > 0.0 && e.is_finite())
            .collect()
    };
    let x = log_range(runs.iter().flat_map(|r| r.checkpoints.iter().map(|c| c.seconds)));
    let y = log_range(runs.iter().flat_map(|r| r.checkpoints.iter().map(|c| super::stats::best(c).rel_mse)));
    let title = format!("relMSE vs time ({})", mode_title(cmp, mode));
    root.fill(&WHITE).map_err(plot_err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(&title, (FAMILY, 22))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc("time since scene build (s)")
        .y_desc(if cmp.reference.halves.is_some() { "relMSE, reference noise removed" } else { "relMSE" })
        .x_label_formatter(&|v| short(*v))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(plot_err)?;
    for r in &runs {
        let color = color_of(cmp, &r.integrator);
        let pts = points(r);
        let series = chart.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2))).map_err(plot_err)?;
        // One legend entry per integrator, however many seeds.
        if r.seed == cmp.first_seed() {
            series
                .label(r.integrator.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2)));
        }
        chart.draw_series(pts.iter().map(|p| Circle::new(*p, 3, color.filled()))).map_err(plot_err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(plot_err)?;
    root.present().map_err(plot_err)?;
    Ok(())
}

/// The final relMSE of each integrator as bars (the mean over the seeds, with a whisker of
/// ± its standard error; the reference's noise removed when it has halves): equal time if it
/// was asked for, else equal spp. Each bar is labelled with its value and spp.
pub fn final_error_bars(cmp: &Comparison, base: &Path) -> Result<()> {
    write_both(base, SIZE, |root| draw_bars(cmp, root), |root| draw_bars(cmp, root))
}

fn draw_bars<DB: DrawingBackend>(cmp: &Comparison, root: DrawingArea<DB, Shift>) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let mode = cmp.headline_mode();
    let sums: Vec<&Summary> = cmp.summaries_of(mode).collect();
    let relmse = |s: &Summary| s.error_noise_removed.as_ref().unwrap_or(&s.error).get("relmse");
    let n = sums.len();
    let top = sums
        .iter()
        .map(|s| relmse(s).mean + relmse(s).standard_error.unwrap_or(0.0))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let top = if top > 0.0 { top * 1.2 } else { 1.0 };
    root.fill(&WHITE).map_err(plot_err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("final relMSE ({})", mode_title(cmp, mode)), (FAMILY, 22))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..n as f64, 0.0..top)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc(if cmp.reference.halves.is_some() { "relMSE, reference noise removed" } else { "relMSE" })
        .y_label_formatter(&|v| if *v == 0.0 { "0".into() } else { format!("{v:.1e}") })
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(WHITE)
        .draw()
        .map_err(plot_err)?;
    let label_style = TextStyle::from((FAMILY, 14).into_font()).pos(Pos::new(HPos::Center, VPos::Bottom));
    for (i, s) in sums.iter().enumerate() {
        let e = relmse(s);
        let v = e.mean.max(0.0);
        let x = i as f64;
        let bar = Rectangle::new([(x + 0.2, 0.0), (x + 0.8, v)], color_of(cmp, &s.integrator).filled());
        chart.draw_series(std::iter::once(bar)).map_err(plot_err)?;
        let mut label_at = v;
        if let Some(se) = e.standard_error {
            let whisker = vec![(x + 0.5, (v - se).max(0.0)), (x + 0.5, v + se)];
            chart.draw_series(std::iter::once(PathElement::new(whisker, BLACK.stroke_width(2)))).map_err(plot_err)?;
            label_at = v + se;
        }
        let text = format!(
            "{} ({} spp, {} s)",
            report::pm(&e, |v| format!("{v:.2e}")),
            s.spp.mean.round(),
            short(s.seconds.mean)
        );
        chart
            .draw_series(std::iter::once(Text::new(text, (x + 0.5, label_at), label_style.clone())))
            .map_err(plot_err)?;
        // The integrator's name under its bar (the x axis has no ticks of its own).
        let (px, py) = chart.backend_coord(&(x + 0.5, 0.0));
        let name_style = TextStyle::from((FAMILY, 15).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(s.integrator.clone(), (px, py + 8), name_style)).map_err(plot_err)?;
    }
    root.present().map_err(plot_err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::compare::run::{Checkpoint, Reference, ReferenceSource};
    use nimbus::imageio::Image;
    use nimbus::integrators::REFERENCE;
    use nimbus::metrics::ErrorMetrics;

    fn run(name: &str, mode: Mode, scale: f64) -> Run {
        let checkpoints = (0..12)
            .map(|i| {
                let spp = 1u32 << i;
                let e = scale / spp as f64 + 1e-5;
                let metrics = ErrorMetrics {
                    mse: e,
                    rmse: e.sqrt(),
                    rel_mse: e,
                    mae: e,
                    mpe: e,
                    mne: e,
                    mean_test: 0.5,
                    mean_reference: 0.5,
                };
                Checkpoint { seconds: 0.01 * spp as f64 * scale, spp, metrics, noise_removed: None, last: i == 11 }
            })
            .collect();
        Run { integrator: name.into(), mode, seed: 0, setup_seconds: 0.01, checkpoints, image: Image::new(2, 2) }
    }

    /// Dark pixels in a box of the PNG: text and lines were drawn there.
    fn ink(png: &Path, x: std::ops::Range<usize>, y: std::ops::Range<usize>) -> usize {
        let img = nimbus::imageio::read_image(png).unwrap();
        y.flat_map(|y| x.clone().map(move |x| (x, y))).filter(|&(x, y)| img.get(x, y).max_element() < 0.2).count()
    }

    #[test]
    fn charts_draw_text_with_the_embedded_font() {
        let dir = std::env::temp_dir().join(format!("nimbus-charts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let runs = vec![run(REFERENCE, Mode::EqualTime, 1.0), run("othermethod", Mode::EqualTime, 0.3)];
        let cmp = Comparison {
            scene: "s.pbrt".into(),
            seeds: vec![0],
            baseline: Some(REFERENCE.into()),
            checkpoints_per_doubling: 1,
            time_budget: Some(10.0),
            spp: None,
            reference: Reference {
                image: Image::new(2, 2),
                halves: None,
                paths: vec!["r.exr".into()],
                source: ReferenceSource::File,
                spp: None,
                seeds: Vec::new(),
            },
            summaries: crate::cli::compare::stats::summarize(&runs, Some(REFERENCE), None),
            runs,
            reference_noise: None,
            reference_mean_se: None,
            diff_scale: Vec::new(),
            precomputed: None,
        };
        error_vs_time(&cmp, &dir.join("t")).unwrap();
        final_error_bars(&cmp, &dir.join("b")).unwrap();
        for base in ["t", "b"] {
            let png = dir.join(base).with_extension("png");
            // The title is text: centred at the top.
            assert!(ink(&png, 250..550, 5..35) > 100, "{base}: no title drawn");
            let svg = std::fs::read_to_string(dir.join(base).with_extension("svg")).unwrap();
            assert!(svg.contains("othermethod"), "{base}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(short(0.25), "0.25");
        assert_eq!(short(3.0), "3");
        assert_eq!(short(120.0), "120");
        assert_eq!(short(0.00012), "1e-4");
    }
}
