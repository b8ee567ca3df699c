//! The comparison as CSV (every checkpoint of every seed), JSON (everything; its schema is
//! `docs/compare-results.md`) and a Markdown table (each method's final errors over the
//! seeds).

use nimbus::integrators::REFERENCE;
use nimbus::metrics::ErrorMetrics;
use std::fmt::Write;

use serde_json::{Map, Value, json};

use super::Comparison;
use super::run::{Checkpoint, Mode};
use super::stats::{METRICS, MetricStats, Stat, Summary};

/// The `schema` field of results.json: bumped when a field changes meaning or goes.
pub const SCHEMA: &str = "nimbus-compare/2";

/// One line per checkpoint of every run.
pub fn csv(cmp: &Comparison) -> String {
    let mut s = String::from(
        "integrator,mode,seed,checkpoint,seconds,spp,mse,rmse,relmse,mae,mpe,mne,mean,mean_reference,\
         relmse_noise_removed,mae_noise_removed,final\n",
    );
    for r in &cmp.runs {
        for (i, c) in r.checkpoints.iter().enumerate() {
            let m = &c.metrics;
            let removed = |f: fn(&ErrorMetrics) -> f64| {
                c.noise_removed.as_ref().map_or(String::new(), |n| format!("{:.6e}", f(n)))
            };
            let _ = writeln!(
                s,
                "{},{},{},{i},{:.6},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}",
                r.integrator,
                r.mode.label(),
                r.seed,
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
                removed(|n| n.rel_mse),
                removed(|n| n.mae),
                c.last
            );
        }
    }
    s
}

fn metrics_json(m: &ErrorMetrics) -> Value {
    Value::Object(METRICS.iter().map(|(name, get)| (name.to_string(), json!(get(m)))).collect())
}

fn checkpoint_json(c: &Checkpoint) -> Value {
    json!({
        "seconds": c.seconds,
        "spp": c.spp,
        "error": metrics_json(&c.metrics),
        "error_noise_removed": c.noise_removed.as_ref().map(metrics_json),
        "mean": c.metrics.mean_test,
        "final": c.last,
    })
}

fn stat_json(s: &Stat) -> Value {
    json!({ "mean": s.mean, "standard_error": s.standard_error, "n": s.n })
}

fn stats_json(m: &MetricStats) -> Value {
    Value::Object(m.values.iter().map(|(name, s)| (name.to_string(), stat_json(s))).collect())
}

fn summary_json(s: &Summary) -> Value {
    let equal_error: Map<String, Value> = s
        .equal_error
        .iter()
        .map(|e| {
            let v = json!({
                "method_seconds": stat_json(&e.method_seconds),
                "baseline_seconds": e.baseline_seconds.as_ref().map(stat_json),
                "speedup": e.speedup.as_ref().map(stat_json),
                "extrapolated": e.extrapolated,
                "undefined": e.undefined,
                "converse_seconds": e.converse_seconds.as_ref().map(stat_json),
                "converse_reached": e.converse_reached,
            });
            (e.metric.to_string(), v)
        })
        .collect();
    json!({
        "integrator": s.integrator,
        "mode": s.mode.label(),
        "seeds": s.seeds,
        "seconds": stat_json(&s.seconds),
        "setup_seconds": stat_json(&s.setup_seconds),
        "spp": stat_json(&s.spp),
        "error": stats_json(&s.error),
        "error_noise_removed": s.error_noise_removed.as_ref().map(stats_json),
        "bias": {
            "offset": stat_json(&s.bias.offset),
            "relative": s.bias.relative,
            "standard_error": s.bias.standard_error,
            "bias_z": s.bias.z,
            "degrees_of_freedom": s.bias.degrees_of_freedom,
        },
        "relmse_ratio": s.relmse_ratio.as_ref().map(stat_json),
        "time_to_equal_error": if equal_error.is_empty() { Value::Null } else { Value::Object(equal_error) },
    })
}

/// Everything: the settings, the reference, each method over the seeds and every run with
/// its checkpoints.
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
                "seed": r.seed,
                "setup_seconds": r.setup_seconds,
                "image": exr,
                "difference_image": diff,
                "final": checkpoint_json(r.last()),
                "checkpoints": r.checkpoints.iter().map(checkpoint_json).collect::<Vec<_>>(),
            })
        })
        .collect();
    let value = json!({
        "schema": SCHEMA,
        "scene": cmp.scene.display().to_string(),
        "seeds": cmp.seeds,
        "baseline": cmp.baseline,
        "time_budget": cmp.time_budget,
        "spp": cmp.spp,
        "checkpoints_per_doubling": cmp.checkpoints_per_doubling,
        "reference": {
            "paths": reference.paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "halves": reference.halves.is_some(),
            "source": reference.source.label(),
            "integrator": REFERENCE,
            "spp": reference.spp,
            "seeds": reference.seeds,
            "width": reference.image.width,
            "height": reference.image.height,
            "mean": reference.image.pixels.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>()
                / (3 * reference.image.pixels.len().max(1)) as f64,
            "mean_standard_error": cmp.reference_mean_se,
            "reference_noise": cmp.reference_noise.as_ref().map(metrics_json),
        },
        "precomputed": cmp.precomputed.as_ref().map(|p| json!({
            "integrator": p.integrator,
            "file": p.file.display().to_string(),
            "prepared_seconds": p.prepared_seconds,
        })),
        "difference_scale": cmp.diff_scale.iter().map(|(m, s)| (m.label().to_string(), json!(s))).collect::<Map<_, _>>(),
        "summaries": cmp.summaries.iter().map(summary_json).collect::<Vec<_>>(),
        "runs": runs,
    });
    let mut s = serde_json::to_string_pretty(&value).unwrap_or_default();
    s.push('\n');
    s
}

/// `mean ± standard error` with three significant digits (the mean alone for one seed).
pub fn pm(s: &Stat, f: fn(f64) -> String) -> String {
    match s.standard_error {
        Some(se) => format!("{} ± {}", f(s.mean), f(se)),
        None => f(s.mean),
    }
}

fn sci(v: f64) -> String {
    format!("{v:.3e}")
}

fn ratio(v: f64) -> String {
    format!("{v:.2}×")
}

fn seconds(v: f64) -> String {
    crate::cli::plot::short(v)
}

/// The table's rows, best relMSE first within each mode, headline mode first: the cells of
/// the Markdown table and of the HTML report.
pub fn table(cmp: &Comparison) -> (Vec<String>, Vec<Vec<String>>) {
    let baseline = cmp.baseline.clone().unwrap_or_else(|| "baseline".into());
    let headers = [
        "integrator",
        "mode",
        "seeds",
        "time (s)",
        "spp",
        "relMSE",
        "relMSE, reference noise removed",
        "MAE, reference noise removed",
        "mean vs reference (z)",
        &format!("relMSE ratio: {baseline} / it"),
        &format!("time to equal relMSE: {baseline} / it"),
        &format!("time to equal MAE: {baseline} / it"),
    ]
    .map(String::from)
    .to_vec();
    let mut rows = Vec::new();
    for mode in [cmp.headline_mode(), other(cmp.headline_mode())] {
        let mut sums: Vec<&Summary> = cmp.summaries_of(mode).collect();
        let key = |s: &Summary| s.error_noise_removed.as_ref().unwrap_or(&s.error).get("relmse").mean;
        sums.sort_by(|a, b| key(a).total_cmp(&key(b)));
        for s in sums {
            let removed = |name| s.error_noise_removed.as_ref().map_or("—".to_string(), |m| pm(&m.get(name), sci));
            let bias = match (s.bias.z, s.bias.degrees_of_freedom) {
                (Some(z), Some(dof)) => format!("{:+.2}% ({z:+.1}, {dof} dof)", 100.0 * s.bias.relative),
                _ => format!("{:+.2}%", 100.0 * s.bias.relative),
            };
            let equal = |metric: &str| {
                let e = s.equal_error.iter().find(|e| e.metric == metric);
                match e.and_then(|e| e.speedup.as_ref().map(|v| (e, v))) {
                    Some((e, v)) if e.extrapolated > 0 => {
                        format!("{} (extrapolated ×{})", pm(v, ratio), e.extrapolated)
                    }
                    Some((_, v)) => pm(v, ratio),
                    None if e.is_some_and(|e| e.undefined > 0) => "within reference noise".into(),
                    None => "—".into(),
                }
            };
            rows.push(vec![
                s.integrator.clone(),
                s.mode.label().to_string(),
                s.seeds.len().to_string(),
                pm(&s.seconds, seconds),
                pm(&s.spp, |v| format!("{v:.0}")),
                pm(&s.error.get("relmse"), sci),
                removed("relmse"),
                removed("mae"),
                bias,
                s.relmse_ratio.as_ref().map_or("—".into(), |v| pm(v, ratio)),
                equal("relmse"),
                equal("mae"),
            ]);
        }
    }
    (headers, rows)
}

/// The table with a line on the scene and reference above it and the metrics' meaning below.
pub fn markdown(cmp: &Comparison) -> String {
    let mut s = String::new();
    let reference = &cmp.reference;
    let _ = writeln!(
        s,
        "Scene `{}`, reference `{}` ({}), {}.\n",
        cmp.scene.display(),
        reference.describe_paths(),
        reference_what(cmp),
        seeds_what(cmp)
    );
    let (headers, rows) = table(cmp);
    let _ = writeln!(s, "| {} |", headers.join(" | "));
    let align: Vec<&str> = headers.iter().enumerate().map(|(i, _)| if i < 2 { "---" } else { "--:" }).collect();
    let _ = writeln!(s, "|{}|", align.join("|"));
    for row in rows {
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    let _ = writeln!(s, "\n{LEGEND}");
    if let Some(note) = precomputed_what(cmp) {
        let _ = writeln!(s, "\n{note}");
    }
    s
}

/// `--precomputed`: what every run of the method that prepares loaded, and what that means
/// for its times and its seeds.
pub fn precomputed_what(cmp: &Comparison) -> Option<String> {
    let p = cmp.precomputed.as_ref()?;
    let how = match p.prepared_seconds {
        Some(t) => format!("prepared once before the runs in {} s and saved there", crate::cli::plot::short(t)),
        None => "loaded as it was".into(),
    };
    Some(format!(
        "{} read its preparation from {} ({how}): its times count loading it, not preparing it, and its seeds \
         vary the render, not the preparation.",
        p.integrator,
        p.file.display()
    ))
}

/// How the reference was made: "two independent halves, 4096 spp in all, seeds [1000, 1001]",
/// "1024 spp" or "given".
pub fn reference_what(cmp: &Comparison) -> String {
    let reference = &cmp.reference;
    match (reference.spp, &reference.halves) {
        (Some(spp), Some(_)) => format!("two independent halves, {spp} spp in all, seeds {:?}", reference.seeds),
        (Some(spp), None) => format!("{spp} spp"),
        (None, Some(_)) => "two independent halves".into(),
        (None, None) => "given".to_string(),
    }
}

/// "seed 1" or "seeds 1–3 (mean ± standard error)".
pub fn seeds_what(cmp: &Comparison) -> String {
    match &cmp.seeds[..] {
        [one] => format!("seed {one}"),
        many => format!("seeds {}–{} (mean ± standard error)", many[0], many[many.len() - 1]),
    }
}

/// What the table's columns mean.
pub const LEGEND: &str = "relMSE: mean of (x − ref)² / (ref² + 0.01) over pixels and channels. Reference noise \
     removed: each error extrapolated to a noiseless reference from the errors against the reference and against \
     each of its halves (for relMSE, relMSE − relMSE(halves)/4). Mean vs reference: the image mean's offset, and \
     its z (offset over its standard error, from the seeds' spread and the reference's halves), a Student t \
     with seeds − 1 degrees of freedom: a bias at the 5 % level beyond ±4.3 with 3 seeds, ±2.3 with 10. Time to equal error: the time the baseline needs to reach the method's final error (its \
     error-vs-time curve, same seed, extrapolated at the unbiased rate when it ends above it) over the \
     method's time. Time counts the method's preparation (training, a graph build), not building the scene.";

fn other(mode: Mode) -> Mode {
    match mode {
        Mode::EqualTime => Mode::EqualSpp,
        Mode::EqualSpp => Mode::EqualTime,
    }
}
