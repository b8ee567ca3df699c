//! What the runs of a comparison say together: every metric as its mean over the seeds with
//! its standard error, the bias of the image mean with its z, and the time one method needs
//! to reach another's error.
//!
//! Seeds are independent renders (a method's precomputation included), so the spread of a
//! metric over seeds is its sampling spread whatever the method shares between pixels. Where
//! the reference came as two halves, errors are read with its noise removed
//! ([`nimbus::metrics::error_metrics_noise_removed`]) wherever a method's error is compared
//! with another's.

use nimbus::metrics::ErrorMetrics;

use super::run::{Checkpoint, Mode, Run};

/// A quantity's mean over the seeds and the standard error of that mean (the sample standard
/// deviation over √n; none for one seed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stat {
    /// Mean over the seeds.
    pub mean: f64,
    /// Standard error of the mean; `None` with fewer than two values.
    pub standard_error: Option<f64>,
    /// Number of values.
    pub n: usize,
}

impl Stat {
    /// Mean and standard error of `values` (at least one).
    pub fn of(values: &[f64]) -> Stat {
        let n = values.len();
        let mean = values.iter().sum::<f64>() / n.max(1) as f64;
        let standard_error = (n >= 2).then(|| {
            let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            (var / n as f64).sqrt()
        });
        Stat { mean, standard_error, n }
    }
}

/// Each error metric over the seeds.
#[derive(Clone, Debug)]
pub struct MetricStats {
    /// (name in the outputs, its statistic), in the order of [`METRICS`].
    pub values: Vec<(&'static str, Stat)>,
}

/// Reads one metric of [`ErrorMetrics`].
pub type Getter = fn(&ErrorMetrics) -> f64;

/// The error metrics the outputs name, and how each is read from [`ErrorMetrics`].
pub const METRICS: [(&str, Getter); 6] = [
    ("relmse", |m| m.rel_mse),
    ("mse", |m| m.mse),
    ("rmse", |m| m.rmse),
    ("mae", |m| m.mae),
    ("mpe", |m| m.mpe),
    ("mne", |m| m.mne),
];

impl MetricStats {
    fn of(metrics: &[&ErrorMetrics]) -> MetricStats {
        let values = METRICS
            .iter()
            .map(|(name, get)| (*name, Stat::of(&metrics.iter().map(|m| get(m)).collect::<Vec<_>>())))
            .collect();
        MetricStats { values }
    }

    /// One metric by its name in [`METRICS`].
    pub fn get(&self, name: &str) -> Stat {
        self.values.iter().find(|(n, _)| *n == name).map(|(_, s)| *s).expect("a metric of METRICS")
    }
}

/// The image mean's offset from the reference's.
#[derive(Clone, Copy, Debug)]
pub struct Bias {
    /// mean(method) − mean(reference), over the seeds.
    pub offset: Stat,
    /// The offset relative to the reference's mean.
    pub relative: f64,
    /// Standard error of the offset: the seeds' spread and the reference's own (from its
    /// halves, when it has them) combined.
    pub standard_error: Option<f64>,
    /// offset / standard_error. Its standard error comes from n seeds, so z follows Student's
    /// t with n − 1 degrees of freedom, not a normal law: beyond ±4.3 is the 5 % level with 3
    /// seeds, beyond ±2.3 with 10.
    pub z: Option<f64>,
    /// n − 1, the degrees of freedom of z (none for one seed).
    pub degrees_of_freedom: Option<usize>,
}

/// The errors whose equal-error times are reported, and how error falls with time for an
/// unbiased method (error ∝ time^−exponent): squared errors as 1/t, absolute ones as 1/√t.
pub const EQUAL_ERROR_METRICS: [(&str, f64); 2] = [("relmse", 1.0), ("mae", 0.5)];

/// Time to equal error against the baseline, for one metric.
#[derive(Clone, Debug)]
pub struct EqualError {
    /// The metric (a name of [`EQUAL_ERROR_METRICS`]).
    pub metric: &'static str,
    /// The method's time to its final error (its run's length), over the seeds.
    pub method_seconds: Stat,
    /// The time the baseline needs to reach the method's final error, from the baseline's
    /// error-vs-time curve of the same seed, over the seeds where it is defined.
    pub baseline_seconds: Option<Stat>,
    /// baseline_seconds / method_seconds, seed by seed: the equal-error speed-up.
    pub speedup: Option<Stat>,
    /// Seeds where the baseline's curve ended above the method's error and its time was
    /// extrapolated at the unbiased rate from its last checkpoint.
    pub extrapolated: usize,
    /// Seeds where the method's error was within the reference's noise (no time defined).
    pub undefined: usize,
    /// The converse: the time the method needs to reach the baseline's final error, over the
    /// seeds where its curve reaches it (never extrapolated: a biased method may not).
    pub converse_seconds: Option<Stat>,
    /// Seeds where the method's curve reached the baseline's final error.
    pub converse_reached: usize,
}

/// Everything measured of one integrator in one mode.
#[derive(Clone, Debug)]
pub struct Summary {
    /// Integrator name.
    pub integrator: String,
    /// Equal time or equal spp.
    pub mode: Mode,
    /// The seeds, in run order.
    pub seeds: Vec<i32>,
    /// Final time (setup included).
    pub seconds: Stat,
    /// The method's preparation time.
    pub setup_seconds: Stat,
    /// Final spp.
    pub spp: Stat,
    /// Final errors against the reference as it is.
    pub error: MetricStats,
    /// Final errors with the reference's noise removed (a reference in two halves).
    pub error_noise_removed: Option<MetricStats>,
    /// Mean offset.
    pub bias: Bias,
    /// Baseline's relMSE / this method's, seed by seed, in this mode (noise removed where
    /// possible): the error ratio at equal time or equal spp.
    pub relmse_ratio: Option<Stat>,
    /// Time to equal error against the baseline, per metric (empty for the baseline itself or
    /// without one).
    pub equal_error: Vec<EqualError>,
}

/// A checkpoint's error for comparisons: noise removed when the reference allows.
pub fn best(c: &Checkpoint) -> &ErrorMetrics {
    c.noise_removed.as_ref().unwrap_or(&c.metrics)
}

fn metric(c: &Checkpoint, name: &str) -> f64 {
    let get = METRICS.iter().find(|(n, _)| *n == name).expect("a metric of METRICS").1;
    get(best(c))
}

/// The first time a run's error-vs-time curve reaches `target`: interpolated log-log between
/// the checkpoints around the crossing (linearly in time where an error is not positive, as a
/// noise-removed error can be); `None` if it never does.
pub fn time_to_reach(curve: &[(f64, f64)], target: f64) -> Option<f64> {
    let first = curve.iter().position(|(_, e)| *e <= target)?;
    if first == 0 {
        return Some(curve[0].0);
    }
    let ((t0, e0), (t1, e1)) = (curve[first - 1], curve[first]);
    if e1 > 0.0 && target > 0.0 && t0 > 0.0 {
        let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
        Some((t0.ln() + f * (t1.ln() - t0.ln())).exp())
    } else {
        let f = (target - e0) / (e1 - e0);
        Some(t0 + f * (t1 - t0))
    }
}

fn curve(r: &Run, name: &str) -> Vec<(f64, f64)> {
    r.checkpoints.iter().map(|c| (c.seconds, metric(c, name))).collect()
}

/// Summaries of every (integrator, mode), in run order, against `baseline` (an integrator
/// among the runs, or none). `reference_mean_se` is the standard error of the reference's
/// mean (from its halves), if known.
pub fn summarize(runs: &[Run], baseline: Option<&str>, reference_mean_se: Option<f64>) -> Vec<Summary> {
    let mut keys: Vec<(String, Mode)> = Vec::new();
    for r in runs {
        if !keys.iter().any(|(n, m)| *n == r.integrator && *m == r.mode) {
            keys.push((r.integrator.clone(), r.mode));
        }
    }
    keys.iter()
        .map(|(name, mode)| {
            let of: Vec<&Run> = runs.iter().filter(|r| r.integrator == *name && r.mode == *mode).collect();
            let base: Vec<&Run> = match baseline {
                Some(b) if b != name => runs.iter().filter(|r| r.integrator == b && r.mode == *mode).collect(),
                _ => Vec::new(),
            };
            summarize_one(name, *mode, &of, &base, reference_mean_se)
        })
        .collect()
}

fn summarize_one(name: &str, mode: Mode, runs: &[&Run], base: &[&Run], reference_mean_se: Option<f64>) -> Summary {
    let finals: Vec<&Checkpoint> = runs.iter().map(|r| r.last()).collect();
    let stat = |f: &dyn Fn(&Run) -> f64| Stat::of(&runs.iter().map(|r| f(r)).collect::<Vec<_>>());
    let noise_removed: Option<Vec<&ErrorMetrics>> = finals.iter().map(|c| c.noise_removed.as_ref()).collect();
    let mean_reference = finals[0].metrics.mean_reference;
    let offset = Stat::of(&finals.iter().map(|c| c.metrics.mean_test - c.metrics.mean_reference).collect::<Vec<_>>());
    let standard_error = offset.standard_error.map(|se| (se * se + reference_mean_se.unwrap_or(0.0).powi(2)).sqrt());
    let bias = Bias {
        offset,
        relative: if mean_reference != 0.0 { offset.mean / mean_reference } else { 0.0 },
        standard_error,
        z: standard_error.filter(|se| *se > 0.0).map(|se| offset.mean / se),
        degrees_of_freedom: (offset.n >= 2).then(|| offset.n - 1),
    };
    // Seed-by-seed pairs with the baseline's runs.
    let pairs: Vec<(&Run, &Run)> =
        runs.iter().filter_map(|r| base.iter().find(|b| b.seed == r.seed).map(|b| (*r, *b))).collect();
    let relmse_ratio = (!pairs.is_empty()).then(|| {
        let ratios: Vec<f64> = pairs
            .iter()
            .map(|(r, b)| metric(b.last(), "relmse") / metric(r.last(), "relmse"))
            .filter(|v| v.is_finite())
            .collect();
        Stat::of(&ratios)
    });
    let equal_error = if pairs.is_empty() {
        Vec::new()
    } else {
        EQUAL_ERROR_METRICS.iter().map(|(metric_name, exponent)| equal_error(&pairs, metric_name, *exponent)).collect()
    };
    Summary {
        integrator: name.to_string(),
        mode,
        seeds: runs.iter().map(|r| r.seed).collect(),
        seconds: stat(&|r| r.last().seconds),
        setup_seconds: stat(&|r| r.setup_seconds),
        spp: stat(&|r| r.last().spp as f64),
        error: MetricStats::of(&finals.iter().map(|c| &c.metrics).collect::<Vec<_>>()),
        error_noise_removed: noise_removed.map(|m| MetricStats::of(&m)),
        bias,
        relmse_ratio: relmse_ratio.filter(|s| s.n > 0),
        equal_error,
    }
}

fn equal_error(pairs: &[(&Run, &Run)], name: &'static str, exponent: f64) -> EqualError {
    let (mut baseline_seconds, mut speedup, mut converse) = (Vec::new(), Vec::new(), Vec::new());
    let (mut extrapolated, mut undefined) = (0, 0);
    for (r, b) in pairs {
        let target = metric(r.last(), name);
        let t_method = r.last().seconds;
        let base_curve = curve(b, name);
        if target > 0.0 {
            let t = time_to_reach(&base_curve, target).or_else(|| {
                // The baseline (the reference method, unbiased) ended above the method's
                // error: its error keeps falling as time^−exponent from its last checkpoint.
                let (t_last, e_last) = *base_curve.last()?;
                (e_last > 0.0).then(|| {
                    extrapolated += 1;
                    t_last * (e_last / target).powf(1.0 / exponent)
                })
            });
            if let Some(t) = t {
                baseline_seconds.push(t);
                speedup.push(t / t_method);
            }
        } else {
            undefined += 1;
        }
        if let Some(t) = time_to_reach(&curve(r, name), metric(b.last(), name)) {
            converse.push(t);
        }
    }
    let some = |v: &Vec<f64>| (!v.is_empty()).then(|| Stat::of(v));
    EqualError {
        metric: name,
        method_seconds: Stat::of(&pairs.iter().map(|(r, _)| r.last().seconds).collect::<Vec<_>>()),
        baseline_seconds: some(&baseline_seconds),
        speedup: some(&speedup),
        extrapolated,
        undefined,
        converse_seconds: some(&converse),
        converse_reached: converse.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nimbus::imageio::Image;

    fn metrics(e: f64, mean: f64) -> ErrorMetrics {
        ErrorMetrics {
            mse: e,
            rmse: e.sqrt(),
            rel_mse: e,
            mae: e.sqrt(),
            mpe: 0.0,
            mne: 0.0,
            mean_test: mean,
            mean_reference: 1.0,
        }
    }

    /// An unbiased run: relMSE = k / t at checkpoints t = 1, 2, 4, ..., `end` s.
    fn run(name: &str, seed: i32, k: f64, end: u32, mean: f64) -> Run {
        let mut t = 1;
        let mut checkpoints = Vec::new();
        while t <= end {
            let m = metrics(k / t as f64, mean);
            checkpoints.push(Checkpoint {
                seconds: t as f64,
                spp: t,
                metrics: m,
                noise_removed: Some(m),
                last: t * 2 > end,
            });
            t *= 2;
        }
        Run {
            integrator: name.into(),
            mode: Mode::EqualTime,
            seed,
            setup_seconds: 0.0,
            checkpoints,
            image: Image::new(1, 1),
        }
    }

    #[test]
    fn stat_is_mean_and_standard_error() {
        let s = Stat::of(&[1.0, 2.0, 3.0]);
        assert_eq!(s.mean, 2.0);
        assert!((s.standard_error.unwrap() - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(Stat::of(&[5.0]).standard_error, None);
    }

    #[test]
    fn time_to_reach_interpolates_log_log() {
        let curve = [(1.0, 1.0), (4.0, 0.25), (16.0, 0.0625)];
        assert!((time_to_reach(&curve, 0.5).unwrap() - 2.0).abs() < 1e-12);
        assert_eq!(time_to_reach(&curve, 2.0), Some(1.0));
        assert_eq!(time_to_reach(&curve, 0.01), None);
        // Non-positive (noise-removed) errors: linear in time.
        assert!((time_to_reach(&[(1.0, 1.0), (3.0, -1.0)], 0.0).unwrap() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn equal_error_speedup_of_a_method_with_a_quarter_of_the_error() {
        // The method has 4× less relMSE at every time over 16 s: volpath needs 4× the time
        // (64 s, extrapolated beyond its 16 s) to reach its final relMSE, and as much for its
        // MAE (2× less, falling as 1/√t); the method reaches volpath's final error at 4 s.
        let runs: Vec<Run> = [1, 2, 3]
            .into_iter()
            .flat_map(|seed| [run("volpath", seed, 1.0, 16, 1.0), run("m", seed, 0.25, 16, 1.0)])
            .collect();
        let s = summarize(&runs, Some("volpath"), Some(0.0));
        assert_eq!(s.len(), 2);
        assert!(s[0].equal_error.is_empty());
        let m = &s[1];
        assert_eq!(m.seeds, [1, 2, 3]);
        let rel = &m.equal_error[0];
        assert_eq!(rel.metric, "relmse");
        assert!((rel.speedup.unwrap().mean - 4.0).abs() < 1e-9, "{rel:?}");
        assert_eq!(rel.extrapolated, 3);
        assert!((rel.converse_seconds.unwrap().mean - 4.0).abs() < 1e-9, "{rel:?}");
        let mae = &m.equal_error[1];
        assert!((mae.speedup.unwrap().mean - 4.0).abs() < 1e-9, "{mae:?}");
        assert!((m.relmse_ratio.unwrap().mean - 4.0).abs() < 1e-9);
        assert_eq!(m.bias.z, None, "no spread over seeds: z undefined");
    }

    #[test]
    fn bias_z_combines_the_seeds_and_the_reference() {
        let runs: Vec<Run> =
            [1.1, 1.12, 1.08].iter().enumerate().map(|(i, &mean)| run("m", i as i32, 1.0, 4, mean)).collect();
        let s = &summarize(&runs, None, Some(0.01))[0];
        assert!((s.bias.offset.mean - 0.1).abs() < 1e-12);
        assert!((s.bias.relative - 0.1).abs() < 1e-12);
        let se = (0.02f64.powi(2) / 3.0 + 0.01f64.powi(2)).sqrt();
        assert!((s.bias.standard_error.unwrap() - se).abs() < 1e-12);
        assert!((s.bias.z.unwrap() - 0.1 / se).abs() < 1e-9);
        assert_eq!(s.bias.degrees_of_freedom, Some(2));
    }
}
