//! The comparison as CSV (every checkpoint), JSON (everything) and a Markdown table (final
//! errors).

use nimbus::integrators::REFERENCE;
use std::fmt::Write;

use serde_json::{Value, json};

use super::Comparison;
use super::run::{Checkpoint, ReferenceSource};

/// One line per checkpoint of every run.
pub fn csv(cmp: &Comparison) -> String {
    let mut s =
        String::from("integrator,mode,checkpoint,seconds,spp,mse,rmse,relmse,mae,mpe,mne,mean,mean_reference,final\n");
    for r in &cmp.runs {
        for (i, c) in r.checkpoints.iter().enumerate() {
            let m = &c.metrics;
            let _ = writeln!(
                s,
                "{},{},{i},{:.6},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{}",
                r.integrator,
                r.mode.label(),
                c.seconds,
                c.spp,
                m.mse,
                m.rmse,
                m.rel_mse,
                m.mae,
                m.mpe,
                m.mne,
                m.mean_test,
                m.mean_reference,
                c.last
            );
        }
    }
    s
}

fn checkpoint_json(c: &Checkpoint) -> Value {
    let m = &c.metrics;
    json!({
        "seconds": c.seconds,
        "spp": c.spp,
        "mse": m.mse,
        "rmse": m.rmse,
        "relmse": m.rel_mse,
        "mae": m.mae,
        "mpe": m.mpe,
        "mne": m.mne,
        "mean": m.mean_test,
        "final": c.last,
    })
}

/// Everything: the settings, the reference and every run with its checkpoints.
pub fn json(cmp: &Comparison) -> String {
    let reference = &cmp.reference;
    let runs: Vec<Value> = cmp
        .runs
        .iter()
        .map(|r| {
            let (exr, diff) = super::image_names(cmp, r);
            json!({
                "integrator": r.integrator,
                "mode": r.mode.label(),
                "setup_seconds": r.setup_seconds,
                "image": exr,
                "difference_image": diff,
                "final": checkpoint_json(r.last()),
                "checkpoints": r.checkpoints.iter().map(checkpoint_json).collect::<Vec<_>>(),
            })
        })
        .collect();
    let value = json!({
        "scene": cmp.scene.display().to_string(),
        "seed": cmp.seed,
        "time_budget": cmp.time_budget,
        "spp": cmp.spp,
        "checkpoints_per_doubling": cmp.checkpoints_per_doubling,
        "reference": {
            "path": reference.path.display().to_string(),
            "source": match reference.source {
                ReferenceSource::File => "file",
                ReferenceSource::Cached => "cached",
                ReferenceSource::Rendered => "rendered",
            },
            "integrator": REFERENCE,
            "spp": reference.spp,
            "seed": reference.seed,
            "width": reference.image.width,
            "height": reference.image.height,
            "mean": reference.image.pixels.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>()
                / (3 * reference.image.pixels.len().max(1)) as f64,
        },
        "difference_scale": cmp.diff_scale.iter().map(|(m, s)| (m.label().to_string(), json!(s))).collect::<serde_json::Map<_, _>>(),
        "runs": runs,
    });
    let mut s = serde_json::to_string_pretty(&value).unwrap_or_default();
    s.push('\n');
    s
}

/// The final errors of every run as a Markdown table, best relMSE first within each mode.
pub fn markdown(cmp: &Comparison) -> String {
    let mut s = String::new();
    let reference = &cmp.reference;
    let what = reference_what(cmp);
    let _ = writeln!(
        s,
        "Scene `{}`, reference `{}` ({what}), seed {}.\n",
        cmp.scene.display(),
        reference.path.display(),
        cmp.seed
    );
    let (headers, rows) = table(cmp);
    let _ = writeln!(s, "| {} |", headers.join(" | "));
    let _ = writeln!(s, "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|");
    for row in rows {
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    let _ = writeln!(s, "\n{LEGEND}");
    s
}

/// How the reference was made: "VolPath, 1024 spp, seed 2" or "given".
pub fn reference_what(cmp: &Comparison) -> String {
    match (cmp.reference.spp, cmp.reference.seed) {
        (Some(spp), Some(seed)) => format!("VolPath, {spp} spp, seed {seed}"),
        _ => "given".to_string(),
    }
}

/// What the table's columns mean.
pub const LEGEND: &str = "relMSE: mean of (x − ref)² / (ref² + 0.01) over pixels and channels; relMSE × time: lower \
     is more efficient; MPE / MNE: mean positive / negative error (x brighter / darker than the \
     reference; MPE − MNE is the mean error, which more samples drive to 0 unless the method \
     is biased); mean vs ref: difference of the image means. Time \
     counts building the scene and any preprocessing.";

/// The final errors of every run: column heads and one row of cells per run, the headline
/// mode first and best relMSE first within each mode (the Markdown table's rows).
pub fn table(cmp: &Comparison) -> (Vec<String>, Vec<Vec<String>>) {
    let headers =
        ["integrator", "mode", "time (s)", "spp", "relMSE", "relMSE × time", "MSE", "MAE", "MPE", "MNE", "mean vs ref"];
    let mut rows = Vec::new();
    for mode in [cmp.headline_mode(), other(cmp.headline_mode())] {
        let mut runs: Vec<_> = cmp.runs_of(mode).collect();
        runs.sort_by(|a, b| a.last().metrics.rel_mse.total_cmp(&b.last().metrics.rel_mse));
        for r in runs {
            let c = r.last();
            let m = &c.metrics;
            let bias = if m.mean_reference != 0.0 { 100.0 * (m.mean_test / m.mean_reference - 1.0) } else { 0.0 };
            rows.push(vec![
                r.integrator.clone(),
                r.mode.label().to_string(),
                crate::cli::plot::short(c.seconds),
                c.spp.to_string(),
                format!("{:.3e}", m.rel_mse),
                format!("{:.3e}", m.rel_mse * c.seconds),
                format!("{:.3e}", m.mse),
                format!("{:.3e}", m.mae),
                format!("{:.3e}", m.mpe),
                format!("{:.3e}", m.mne),
                format!("{bias:+.2}%"),
            ]);
        }
    }
    (headers.iter().map(|h| h.to_string()).collect(), rows)
}

fn other(mode: super::Mode) -> super::Mode {
    match mode {
        super::Mode::EqualTime => super::Mode::EqualSpp,
        super::Mode::EqualSpp => super::Mode::EqualTime,
    }
}
