//! The matrix as CSV (one line per cell, every measurement) and Markdown (the verdict table,
//! then every cell's numbers and every refusal's and failure's message).

use nimbus::integrators::REFERENCE;
use std::fmt::Write;

use super::Matrix;
use super::cell::Cell;
use super::verdict::{self, Verdict};
use crate::cli::plot::short;

fn mib(bytes: Option<u64>) -> String {
    bytes.map_or("".into(), |b| format!("{:.1}", b as f64 / (1 << 20) as f64))
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

/// `relMSE ratio to volpath` as text ("0.42x"), or empty.
fn ratio_text(cell: &Cell, baseline: Option<&Cell>) -> String {
    baseline.and_then(|b| verdict::ratio(cell, b)).map_or(String::new(), |(r, _)| format!("{}x", short(r)))
}

/// One cell on one line, for the progress output.
pub fn one_line(cell: &Cell, v: &Verdict, baseline: Option<&Cell>) -> String {
    let mut s = format!("{:<14} {:<9}", cell.integrator, v.label());
    match (&cell.measured, v) {
        (_, Verdict::Refused(why) | Verdict::Failed(why)) => {
            let _ = write!(s, " {why}");
        }
        (Some(m), _) => {
            let _ = write!(
                s,
                " relMSE {:.3e} ({}), bias {:+.2} % (z {:+.1}), {} spp in {:.2} s, {} MiB",
                m.metrics.rel_mse,
                ratio_text(cell, baseline),
                100.0 * m.bias,
                m.bias_z,
                cell.spp,
                cell.seconds,
                mib(cell.peak_rss)
            );
        }
        (None, _) => {}
    }
    s
}

/// One line per cell.
pub fn csv(m: &Matrix) -> String {
    let mut s = String::from(
        "condition,integrator,verdict,biased,relmse,relmse_se,relmse_ratio,mse,mae,mpe,mne,bias,bias_z,mean,\
         mean_reference,nonfinite_samples,nonfinite_pixels,brightest,brightest_reference,spp,seconds,wall_seconds,\
         peak_rss_bytes,precomputed_bytes,reason\n",
    );
    for (c, v) in &m.cells {
        let baseline = m.cell(&c.condition, REFERENCE).map(|(b, _)| b);
        let ratio = baseline.and_then(|b| verdict::ratio(c, b)).map_or(String::new(), |(r, _)| format!("{r:.4}"));
        let reason = match v {
            Verdict::Refused(why) | Verdict::Failed(why) => why.as_str(),
            _ => "",
        };
        let _ = write!(s, "{},{},{},{},", c.condition, c.integrator, v.label(), verdict::biased(c));
        match &c.measured {
            Some(x) => {
                let e = &x.metrics;
                let _ = write!(
                    s,
                    "{:.6e},{:.3e},{ratio},{:.6e},{:.6e},{:.6e},{:.6e},{:.6},{:.2},{:.6e},{:.6e},{},{},{},{},",
                    e.rel_mse,
                    x.rel_mse_se,
                    e.mse,
                    e.mae,
                    e.mpe,
                    e.mne,
                    x.bias,
                    x.bias_z,
                    e.mean_test,
                    e.mean_reference,
                    c.nonfinite_samples,
                    x.nonfinite_pixels,
                    x.brightest.0,
                    x.brightest.1
                );
            }
            None => s.push_str(",,,,,,,,,,,,,,,"),
        }
        let _ = writeln!(
            s,
            "{},{:.3},{:.3},{},{},{}",
            c.spp,
            c.seconds,
            c.wall_seconds,
            c.peak_rss.map_or(String::new(), |b| b.to_string()),
            c.precomputed,
            csv_field(reason)
        );
    }
    s
}

/// The verdict of one cell as a table entry: the verdict, the ratio, a bias mark.
fn entry(m: &Matrix, cell: &Cell, v: &Verdict) -> String {
    let baseline = m.cell(&cell.condition, REFERENCE).map(|(b, _)| b);
    let mut s = match v {
        Verdict::Baseline => "1x".to_string(),
        Verdict::Refused(_) => "refused".to_string(),
        Verdict::Failed(_) => "**FAILED**".to_string(),
        Verdict::Biased(bias) => format!("**biased** {:+.1} %, {}", 100.0 * bias, ratio_text(cell, baseline)),
        _ => format!("{} {}", v.label(), ratio_text(cell, baseline)),
    };
    if verdict::biased(cell) && !matches!(v, Verdict::Biased(_)) {
        let bias = cell.measured.as_ref().map_or(0.0, |x| x.bias);
        let _ = write!(s, ", biased {:+.1} %", 100.0 * bias);
    }
    s
}

/// The cells that went wrong, counted: failed (crash, hang, NaN/Inf, memory) and biased
/// (a wrong mean), beside those rendered and refused.
pub fn counts(m: &Matrix) -> String {
    let n = |f: fn(&Verdict) -> bool| m.cells.iter().filter(|(_, v)| f(v)).count();
    format!(
        "{} cells: {} failed, {} biased, {} refused, {} rendered within noise of the reference's mean.",
        m.cells.len(),
        n(|v| matches!(v, Verdict::Failed(_))),
        n(|v| matches!(v, Verdict::Biased(_))),
        n(|v| matches!(v, Verdict::Refused(_))),
        n(|v| matches!(v, Verdict::Baseline | Verdict::Better | Verdict::Same | Verdict::Worse)),
    )
}

/// Conditions as rows, integrators as columns: each cell's verdict and relMSE ratio.
pub fn verdict_table(m: &Matrix) -> String {
    let mut s = format!("| condition | {} |\n|---|", m.integrators.join(" | "));
    s.push_str(&"---|".repeat(m.integrators.len()));
    s.push('\n');
    for (cond, _) in &m.conditions {
        let _ = write!(s, "| {cond} |");
        for name in &m.integrators {
            let e = m.cell(cond, name).map_or(String::new(), |(c, v)| entry(m, c, v));
            let _ = write!(s, " {e} |");
        }
        s.push('\n');
    }
    s
}

/// The verdict table, what each condition varies, every refusal and failure, and every
/// rendered cell's numbers.
pub fn markdown(m: &Matrix) -> String {
    let mut s = format!(
        "# nimbus stress: {} conditions x {} integrators, {} s per cell, seed {}\n\n\
         Each cell: the relMSE ratio to volpath's at equal time (the method's precomputation counted), \
         a verdict (better or worse beyond twice the ratio's standard error and beyond {}x; refused; \
         FAILED for a crash, a hang, NaN/Inf samples or more than {}x volpath's memory; biased where \
         the image mean is more than {} standard errors and {} % off the reference, whatever the ratio).\n\n\
         {}\n\n",
        m.conditions.len(),
        m.integrators.len(),
        short(m.time),
        m.seed,
        verdict::SAME_FACTOR,
        verdict::MEMORY_FACTOR,
        verdict::BIAS_Z,
        100.0 * verdict::BIAS_RELATIVE,
        counts(m),
    );
    s.push_str(&verdict_table(m));
    s.push_str("\n## Conditions\n\n| condition | what varies | reference |\n|---|---|---|\n");
    for ((cond, what), spp) in m.conditions.iter().zip(&m.reference_spp) {
        let _ = writeln!(s, "| {cond} | {what} | {REFERENCE}, {spp} spp |");
    }
    s.push_str("\n## Refusals, failures and biased cells\n\n");
    let mut any = false;
    for (c, v) in &m.cells {
        let why = match v {
            Verdict::Refused(why) | Verdict::Failed(why) => why.clone(),
            Verdict::Biased(bias) => {
                let z = c.measured.as_ref().map_or(0.0, |x| x.bias_z);
                format!("mean {:+.1} % off the reference ({z:+.1} standard errors)", 100.0 * bias)
            }
            _ => continue,
        };
        let _ = writeln!(s, "- {} on {}: {}: {why}", c.integrator, c.condition, v.label());
        any = true;
    }
    if !any {
        s.push_str("None.\n");
    }
    s.push_str(
        "\n## Every rendered cell\n\n| condition | integrator | relMSE | ratio | MPE | MNE | bias (z) | spp | s | \
         peak MiB | precomputed MiB | brightest / reference's |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (c, _) in &m.cells {
        let Some(x) = &c.measured else { continue };
        let baseline = m.cell(&c.condition, REFERENCE).map(|(b, _)| b);
        let _ = writeln!(
            s,
            "| {} | {} | {:.3e} | {} | {:.2e} | {:.2e} | {:+.2} % ({:+.1}) | {} | {:.2} | {} | {} | {} / {} |",
            c.condition,
            c.integrator,
            x.metrics.rel_mse,
            ratio_text(c, baseline),
            x.metrics.mpe,
            x.metrics.mne,
            100.0 * x.bias,
            x.bias_z,
            c.spp,
            c.seconds,
            mib(c.peak_rss),
            mib(Some(c.precomputed)),
            short(x.brightest.0 as f64),
            short(x.brightest.1 as f64)
        );
    }
    s
}
