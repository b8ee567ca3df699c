//! One cell of the matrix: one integrator on one condition's scene, rendered by a child
//! `nimbus render` (so that a crash, a hang or a runaway allocation is the cell's result, not
//! the end of the run, and its peak memory is its own), then measured against the reference.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use nimbus::imageio::Image;
use nimbus::metrics::{ErrorMetrics, error_metrics};

/// How the child ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// It wrote its image.
    Rendered,
    /// It refused the scene (exit code 1, an `error:` message): the message.
    Refused(String),
    /// It panicked or was killed by a signal: what it said.
    Crashed(String),
    /// It was still running at the timeout (seconds) and was stopped.
    Hung(f64),
}

/// The error of a rendered cell against the reference, with the statistics the verdict
/// needs.
#[derive(Clone, Debug)]
pub struct Measured {
    /// MSE, relMSE, MAE, MPE/MNE, means.
    pub metrics: ErrorMetrics,
    /// Standard error of the relMSE (of the mean of the per-pixel relative squared errors).
    pub rel_mse_se: f64,
    /// Mean difference to the reference over its mean: the bias, relative.
    pub bias: f64,
    /// The mean difference over its standard error (pixels independent): |z| > 4 is no noise.
    pub bias_z: f64,
    /// The brightest pixel's largest channel, and the reference's.
    pub brightest: (f32, f32),
    /// Pixels that are NaN or infinite in the written image.
    pub nonfinite_pixels: usize,
}

/// One integrator on one condition.
#[derive(Clone, Debug)]
pub struct Cell {
    /// Condition (the scene file's stem).
    pub condition: String,
    /// Integrator.
    pub integrator: String,
    /// How the render ended.
    pub outcome: Outcome,
    /// Wall-clock seconds of the child process (start-up, parsing and writing included).
    pub wall_seconds: f64,
    /// Seconds of the budget it used: the method's setup (graph build, training) and the
    /// render.
    pub seconds: f64,
    /// Samples per pixel reached.
    pub spp: u32,
    /// Peak resident memory of the child, bytes.
    pub peak_rss: Option<u64>,
    /// Bytes of what the method precomputed (the radiance graph), reported apart.
    pub precomputed: u64,
    /// Samples the film zeroed because they were NaN or infinite.
    pub nonfinite_samples: u64,
    /// The error, when it rendered.
    pub measured: Option<Measured>,
    /// The rendered image, when there is one.
    pub image: Option<PathBuf>,
}

impl Cell {
    /// Peak memory without the precomputed structure (what the 2×-volpath rule bounds).
    pub fn render_memory(&self) -> Option<u64> {
        self.peak_rss.map(|b| b.saturating_sub(self.precomputed))
    }
}

/// What a cell needs.
pub struct CellSetup<'a> {
    /// The condition's scene.
    pub scene: &'a Path,
    /// Its name.
    pub condition: &'a str,
    /// Integrator.
    pub integrator: &'a str,
    /// Equal-time budget, seconds.
    pub time: f64,
    /// Sampler seed.
    pub seed: i32,
    /// Worker threads of the child.
    pub nthreads: Option<usize>,
    /// Seconds after which the child is stopped.
    pub timeout: f64,
    /// Where the image and the log go (`<dir>/<integrator>.exr`, `.log`).
    pub dir: &'a Path,
    /// The reference.
    pub reference: &'a Image,
}

/// The message of a refusal in a child's log: everything from the first `error: ` on (a
/// message may list several lines), joined by "; ".
fn error_message(log: &str) -> Option<String> {
    let at = log.find("error: ")?;
    let lines: Vec<&str> = log[at + "error: ".len()..].lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    Some(lines.join("; ").replace("; - ", " - "))
}

/// Renders and measures one cell.
pub fn run_cell(s: &CellSetup<'_>) -> Result<Cell> {
    let exe = std::env::current_exe().context("finding the nimbus executable")?;
    let image_path = s.dir.join(format!("{}.exr", s.integrator));
    let log_path = s.dir.join(format!("{}.log", s.integrator));
    let _ = std::fs::remove_file(&image_path);
    let log = std::fs::File::create(&log_path).with_context(|| format!("creating {}", log_path.display()))?;
    let mut cmd = Command::new(exe);
    cmd.arg("render")
        .arg(s.scene)
        .args(["--integrator", s.integrator, "--quiet", "--time", &s.time.to_string()])
        .args(["--seed", &s.seed.to_string()])
        .arg("--outfile")
        .arg(&image_path)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(log);
    if let Some(n) = s.nthreads {
        cmd.args(["--nthreads", &n.to_string()]);
    }
    let start = Instant::now();
    let mut child = cmd.spawn().context("starting a cell's render")?;
    let status = loop {
        if let Some(status) = child.try_wait().context("waiting for a cell's render")? {
            break Some(status);
        }
        if start.elapsed().as_secs_f64() > s.timeout {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let wall_seconds = start.elapsed().as_secs_f64();
    let log = std::fs::read_to_string(&log_path).unwrap_or_default();
    let mut cell = Cell {
        condition: s.condition.to_string(),
        integrator: s.integrator.to_string(),
        outcome: Outcome::Rendered,
        wall_seconds,
        seconds: 0.0,
        spp: 0,
        peak_rss: None,
        precomputed: 0,
        nonfinite_samples: 0,
        measured: None,
        image: None,
    };
    let Some(status) = status else {
        cell.outcome = Outcome::Hung(s.timeout);
        return Ok(cell);
    };
    if let Some(at) = log.find("panicked at") {
        cell.outcome = Outcome::Crashed(log[at..].lines().take(2).collect::<Vec<_>>().join(" "));
        return Ok(cell);
    }
    match status.code() {
        Some(0) => {}
        Some(1) => {
            cell.outcome = Outcome::Refused(error_message(&log).unwrap_or_else(|| "no message".into()));
            return Ok(cell);
        }
        Some(code) => {
            cell.outcome = Outcome::Crashed(format!("exit code {code}: {}", log.trim()));
            return Ok(cell);
        }
        None => {
            cell.outcome = Outcome::Crashed(format!("killed by a signal ({status}): {}", log.trim()));
            return Ok(cell);
        }
    }
    let image = nimbus::imageio::read_exr(&image_path).map_err(anyhow::Error::msg)?;
    let meta = |k: &str| image.metadata.get(k).map(String::as_str);
    let number = |k: &str| meta(k).and_then(|v| v.parse::<f64>().ok());
    cell.spp = number("nimbus:spp").unwrap_or(0.0) as u32;
    cell.seconds = number("nimbus:time").unwrap_or(0.0) + number("nimbus:setup-time").unwrap_or(0.0);
    cell.peak_rss = meta("nimbus:peak-rss-bytes").and_then(|v| v.parse().ok());
    cell.precomputed = meta("nimbus:precomputed-bytes").and_then(|v| v.parse().ok()).unwrap_or(0);
    cell.nonfinite_samples = meta("nimbus:nonfinite-samples").and_then(|v| v.parse().ok()).unwrap_or(0);
    cell.measured = Some(measure(&image, s.reference).with_context(|| format!("measuring {}", image_path.display()))?);
    cell.image = Some(image_path);
    Ok(cell)
}

/// The error of `image` against `reference`, with the standard errors of the relMSE and of
/// the mean difference, treating pixels as independent samples.
pub fn measure(image: &Image, reference: &Image) -> Result<Measured> {
    let metrics = error_metrics(image, reference).map_err(anyhow::Error::msg)?;
    let n = image.pixels.len().max(1) as f64;
    let (mut rel, mut rel_sq, mut d, mut d_sq) = (0.0f64, 0.0, 0.0, 0.0);
    let mut nonfinite_pixels = 0;
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        if !a.is_finite() {
            nonfinite_pixels += 1;
        }
        let (mut e, mut diff) = (0.0f64, 0.0f64);
        for c in 0..3 {
            let (x, y) = (a[c] as f64, b[c] as f64);
            e += (x - y) * (x - y) / (y * y + 0.01) / 3.0;
            diff += (x - y) / 3.0;
        }
        rel += e;
        rel_sq += e * e;
        d += diff;
        d_sq += diff * diff;
    }
    let se = |sum: f64, sum_sq: f64| ((sum_sq / n - (sum / n).powi(2)).max(0.0) / (n - 1.0).max(1.0)).sqrt();
    let rel_mse_se = se(rel, rel_sq);
    let mean_ref = metrics.mean_reference.abs().max(1e-12);
    let d_se = se(d, d_sq);
    let bias_z = if d_se > 0.0 { d / n / d_se } else { 0.0 };
    let brightest =
        |img: &Image| img.pixels.iter().map(|p| p.max_element()).filter(|v| v.is_finite()).fold(0.0, f32::max);
    Ok(Measured {
        metrics,
        rel_mse_se,
        bias: d / n / mean_ref,
        bias_z,
        brightest: (brightest(image), brightest(reference)),
        nonfinite_pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn refusals_keep_every_line_of_the_message() {
        let log = "s.pbrt: error: the radiance-graph method needs \n  - one medium (the scene has none)\n  - a light\n";
        assert_eq!(
            error_message(log).unwrap(),
            "the radiance-graph method needs - one medium (the scene has none) - a light"
        );
        assert_eq!(error_message("warning: x\n"), None);
    }

    #[test]
    fn a_uniform_offset_is_bias_and_noise_is_not() {
        let mut reference = Image::new(32, 32);
        let mut rng = nimbus::sampling::rng::Pcg32::new(1, 2);
        for p in &mut reference.pixels {
            *p = Vec3::splat(0.5);
        }
        let mut noisy = reference.clone();
        for p in &mut noisy.pixels {
            *p += Vec3::splat(0.2 * (rng.uniform() - 0.5));
        }
        let m = measure(&noisy, &reference).unwrap();
        assert!(m.bias_z.abs() < 4.0, "{m:?}");
        // relMSE of uniform noise of width 0.2: 0.2² / 12 / (0.25 + 0.01).
        let expected = 0.04 / 12.0 / 0.26;
        assert!((m.metrics.rel_mse - expected).abs() < 4.0 * m.rel_mse_se, "{m:?}");
        let mut shifted = noisy.clone();
        for p in &mut shifted.pixels {
            *p += Vec3::splat(0.01);
        }
        let m = measure(&shifted, &reference).unwrap();
        assert!(m.bias_z > 4.0 && (m.bias - 0.02).abs() < 0.005, "{m:?}");
        let mut broken = reference.clone();
        broken.pixels[3] = Vec3::splat(f32::NAN);
        assert_eq!(measure(&broken, &reference).unwrap().nonfinite_pixels, 1);
    }
}
