//! A cell's verdict against volpath's cell on the same condition.

use super::cell::{Cell, Outcome};
use nimbus::integrators::REFERENCE;

/// Where a method stands on one condition.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// volpath itself: the baseline of its row.
    Baseline,
    /// Lower relMSE than volpath at equal time, beyond noise.
    Better,
    /// relMSE within noise (or 25 %) of volpath's.
    Same,
    /// Higher relMSE than volpath, beyond noise.
    Worse,
    /// The image's mean is off the reference beyond noise ([`biased`]): a wrong answer, counted
    /// beside failures whatever its relMSE (the bias, as a fraction of the reference's mean).
    Biased(f64),
    /// The method declined the scene: why.
    Refused(String),
    /// A failure the stress test exists to catch: crash, hang, NaN/Inf, memory.
    Failed(String),
}

impl Verdict {
    /// Name in the outputs.
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::Baseline => "baseline",
            Verdict::Better => "better",
            Verdict::Same => "same",
            Verdict::Worse => "worse",
            Verdict::Biased(_) => "biased",
            Verdict::Refused(_) => "refused",
            Verdict::Failed(_) => "FAILED",
        }
    }
}

/// Ratios of relMSE within this factor of 1 count as the same even when the standard errors
/// are tiny: a method a quarter better or worse is not a different class of method.
pub const SAME_FACTOR: f64 = 1.25;

/// Memory a method may use over volpath's on the same scene (its precomputed structure aside).
pub const MEMORY_FACTOR: f64 = 2.0;

/// A biased cell: its mean is more than 3 standard errors and more than 1 % off the
/// reference's (both: a significant offset too small to matter, or a large one within the
/// noise of a short render, is not a verdict).
pub const BIAS_Z: f64 = 3.0;
/// See [`BIAS_Z`].
pub const BIAS_RELATIVE: f64 = 0.01;

/// The relMSE ratio of `cell` to `baseline` and the standard error of its logarithm (the
/// relative standard errors of both relMSEs, combined).
pub fn ratio(cell: &Cell, baseline: &Cell) -> Option<(f64, f64)> {
    let (a, b) = (cell.measured.as_ref()?, baseline.measured.as_ref()?);
    let (ea, eb) = (a.metrics.rel_mse, b.metrics.rel_mse);
    if !(ea > 0.0 && eb > 0.0 && ea.is_finite() && eb.is_finite()) {
        return None;
    }
    let sigma = ((a.rel_mse_se / ea).powi(2) + (b.rel_mse_se / eb).powi(2)).sqrt();
    Some((ea / eb, sigma))
}

/// Whether the cell's mean is off the reference beyond noise.
pub fn biased(cell: &Cell) -> bool {
    cell.measured.as_ref().is_some_and(|m| m.bias_z.abs() > BIAS_Z && m.bias.abs() > BIAS_RELATIVE)
}

/// The verdict of `cell` against `baseline` (volpath's cell on the same condition; `None`
/// when volpath itself did not render it).
pub fn judge(cell: &Cell, baseline: Option<&Cell>) -> Verdict {
    match &cell.outcome {
        Outcome::Refused(why) => return Verdict::Refused(why.clone()),
        Outcome::Crashed(what) => return Verdict::Failed(format!("crashed: {what}")),
        Outcome::Hung(t) => return Verdict::Failed(format!("still running after {t:.0} s")),
        Outcome::Rendered => {}
    }
    let m = cell.measured.as_ref().expect("a rendered cell is measured");
    if m.nonfinite_pixels > 0 || cell.nonfinite_samples > 0 {
        return Verdict::Failed(format!(
            "{} NaN/Inf samples zeroed, {} NaN/Inf pixels",
            cell.nonfinite_samples, m.nonfinite_pixels
        ));
    }
    if cell.integrator == REFERENCE {
        // The reference method off its own converged image is a finding, not a baseline.
        return if biased(cell) { Verdict::Biased(m.bias) } else { Verdict::Baseline };
    }
    let Some(baseline) = baseline.filter(|b| b.outcome == Outcome::Rendered) else {
        return Verdict::Failed(format!("{REFERENCE} did not render this condition"));
    };
    if let (Some(mem), Some(base)) = (cell.render_memory(), baseline.render_memory())
        && mem as f64 > MEMORY_FACTOR * base as f64
    {
        return Verdict::Failed(format!(
            "{:.1} MiB resident, more than {MEMORY_FACTOR}x {REFERENCE}'s {:.1} MiB",
            mem as f64 / (1 << 20) as f64,
            base as f64 / (1 << 20) as f64
        ));
    }
    if biased(cell) {
        return Verdict::Biased(m.bias);
    }
    match ratio(cell, baseline) {
        None => Verdict::Same,
        Some((r, sigma)) => {
            let band = (2.0 * sigma).max(SAME_FACTOR.ln());
            if r.ln() < -band {
                Verdict::Better
            } else if r.ln() > band {
                Verdict::Worse
            } else {
                Verdict::Same
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::stress::cell::Measured;
    use nimbus::metrics::ErrorMetrics;

    fn cell(integrator: &str, rel_mse: f64, se: f64, bias: f64, bias_z: f64, rss: u64) -> Cell {
        let metrics = ErrorMetrics {
            mse: rel_mse,
            rmse: rel_mse.sqrt(),
            rel_mse,
            mae: 0.0,
            mpe: 0.0,
            mne: 0.0,
            mean_test: 1.0 + bias,
            mean_reference: 1.0,
        };
        Cell {
            condition: "c".into(),
            integrator: integrator.into(),
            outcome: Outcome::Rendered,
            wall_seconds: 1.0,
            seconds: 1.0,
            spp: 16,
            peak_rss: Some(rss),
            precomputed: 0,
            nonfinite_samples: 0,
            measured: Some(Measured {
                metrics,
                rel_mse_se: se,
                bias,
                bias_z,
                brightest: (1.0, 1.0),
                nonfinite_pixels: 0,
            }),
            image: None,
        }
    }

    #[test]
    fn verdicts_follow_the_ratio_beyond_noise() {
        let base = cell(REFERENCE, 1e-3, 1e-5, 0.0, 0.0, 10 << 20);
        assert_eq!(judge(&base, Some(&base)), Verdict::Baseline);
        assert_eq!(judge(&cell("m", 0.5e-3, 1e-5, 0.0, 0.0, 10 << 20), Some(&base)), Verdict::Better);
        assert_eq!(judge(&cell("m", 2e-3, 1e-5, 0.0, 0.0, 10 << 20), Some(&base)), Verdict::Worse);
        // Within 25 %: the same, however precise.
        assert_eq!(judge(&cell("m", 1.2e-3, 1e-6, 0.0, 0.0, 10 << 20), Some(&base)), Verdict::Same);
        // Twice the error but a standard error of 60 %: not distinguishable from noise.
        assert_eq!(judge(&cell("m", 2e-3, 1.2e-3, 0.0, 0.0, 10 << 20), Some(&base)), Verdict::Same);
    }

    #[test]
    fn failures_outrank_errors() {
        let base = cell(REFERENCE, 1e-3, 1e-5, 0.0, 0.0, 10 << 20);
        let mut c = cell("m", 0.5e-3, 1e-5, 0.0, 0.0, 25 << 20);
        assert!(matches!(judge(&c, Some(&base)), Verdict::Failed(m) if m.contains("2x volpath")));
        // The radiance graph's graph is reported apart, not counted.
        c.precomputed = 20 << 20;
        assert_eq!(judge(&c, Some(&base)), Verdict::Better);
        c.nonfinite_samples = 3;
        assert!(matches!(judge(&c, Some(&base)), Verdict::Failed(m) if m.contains("NaN")));
        c.outcome = Outcome::Hung(60.0);
        assert!(matches!(judge(&c, Some(&base)), Verdict::Failed(m) if m.contains("after 60 s")));
        c.outcome = Outcome::Refused("needs one medium".into());
        assert_eq!(judge(&c, Some(&base)), Verdict::Refused("needs one medium".into()));
        assert!(matches!(judge(&cell("m", 1e-3, 0.0, 0.0, 0.0, 1), None), Verdict::Failed(_)));
    }

    #[test]
    fn bias_needs_both_significance_and_size() {
        assert!(biased(&cell("m", 1e-3, 1e-5, 0.03, 9.0, 1)));
        assert!(!biased(&cell("m", 1e-3, 1e-5, 0.03, 2.0, 1)), "within noise");
        assert!(!biased(&cell("m", 1e-3, 1e-5, 0.002, 9.0, 1)), "significant but under 1 %");
        // A biased cell's verdict says so whatever its relMSE; failures still outrank it.
        let base = cell(REFERENCE, 1e-3, 1e-5, 0.0, 0.0, 10 << 20);
        assert_eq!(judge(&cell("m", 0.5e-3, 1e-5, -0.05, -6.0, 10 << 20), Some(&base)), Verdict::Biased(-0.05));
        assert!(matches!(judge(&cell("m", 0.5e-3, 1e-5, -0.05, -6.0, 25 << 20), Some(&base)), Verdict::Failed(_)));
        assert_eq!(judge(&cell(REFERENCE, 1e-3, 1e-5, 0.02, 3.5, 1), None), Verdict::Biased(0.02));
    }
}
