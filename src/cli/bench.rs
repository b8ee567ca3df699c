//! `nimbus bench`: speed on the parity scenes against pbrt-v4's own figures for them
//! (`pbrt-scenes/pbrt-v4-references/speed.json`: wall seconds at `--nthreads 2 --spp 64` and the
//! MSE against the reference images at that spp), at equal spp and at equal error, for each
//! transport; plus a CPU baseline measured in the same run so figures from different machines
//! can be compared.
//!
//! Equal error: for an unbiased Monte Carlo estimator MSE ∝ 1/time, so nimbus needs
//! `t × mse / mse_pbrt` seconds to reach pbrt-v4's MSE, and its speed-up at equal error is
//! `(t_pbrt × mse_pbrt) / (t × mse)`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use nimbus::scene::BuildOptions;
use nimbus::scene::transport::SpectralMode;

/// Arguments of `nimbus bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenes to time (default: every scene of speed.json, and pbrt-scenes/default.pbrt).
    scenes: Vec<PathBuf>,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64)]
    spp: u32,
    /// Worker threads (pbrt-v4's figures use 2).
    #[arg(long, default_value_t = 2)]
    nthreads: usize,
    /// Runs per scene and transport (at least 2: seeds 1 and 2 give the MSE); the median time
    /// is reported.
    #[arg(long, default_value_t = 2)]
    repeat: usize,
    /// The pbrt-v4 references folder (scenes/, images/, speed.json).
    #[arg(long)]
    references: Option<PathBuf>,
    /// Transports to time, comma separated (`off` = RGB, `on` = spectral, `auto`).
    #[arg(long, value_delimiter = ',', default_value = "off,on")]
    spectral: Vec<SpectralMode>,
    /// Also write the results as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Time this integrator instead of the scenes' (its precomputation, e.g. guided's
    /// training, counts in the time), against pbrt-v4's VolPath figures.
    #[arg(long)]
    integrator: Option<String>,
}

/// pbrt-v4's figures for one scene.
#[derive(Clone, Copy, Debug)]
struct PbrtFigures {
    seconds: f64,
    mse: f64,
}

/// What speed.json says: pbrt-v4's spp, its thread count if given, and per-scene figures.
type Speed = (u32, Option<u64>, Vec<(String, PbrtFigures)>);

/// Reads speed.json: `{"spp": .., "threads": .., "scenes": {"name": {"seconds": .., "mse": ..}}}`.
fn read_speed(path: &Path) -> Result<Speed> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not valid JSON", path.display()))?;
    let spp =
        v.get("spp").and_then(|s| s.as_u64()).with_context(|| format!("{}: no integer \"spp\"", path.display()))?;
    let threads = match v.get("threads") {
        None => None,
        Some(t) => Some(t.as_u64().with_context(|| format!("{}: \"threads\" must be an integer", path.display()))?),
    };
    let scenes = v
        .get("scenes")
        .and_then(|s| s.as_object())
        .with_context(|| format!("{}: no \"scenes\" object", path.display()))?;
    let mut out = Vec::new();
    for (name, f) in scenes {
        let num = |key: &str| {
            f.get(key)
                .and_then(|x| x.as_f64())
                .filter(|x| x.is_finite() && *x > 0.0)
                .with_context(|| format!("{}: scenes.{name}.{key} must be a positive number", path.display()))
        };
        out.push((name.clone(), PbrtFigures { seconds: num("seconds")?, mse: num("mse")? }));
    }
    Ok((spp as u32, threads, out))
}

/// A scene's name as speed.json and the reference images name it: the file name without
/// `.pbrt` or `.pbrt.gz`.
fn scene_name(path: &Path) -> String {
    let file = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let file = file.strip_suffix(".gz").unwrap_or(&file);
    file.strip_suffix(".pbrt").unwrap_or(file).to_string()
}

/// The median of `times` (the mean of the middle two for an even count).
fn median(times: &mut [f64]) -> f64 {
    times.sort_by(f64::total_cmp);
    let n = times.len();
    if n % 2 == 1 { times[n / 2] } else { 0.5 * (times[n / 2 - 1] + times[n / 2]) }
}

/// A fixed scalar workload (a tiny ray-sphere loop) to calibrate machine speed.
fn baseline_seconds() -> f64 {
    let t = Instant::now();
    let mut hits = 0u64;
    let mut x = 0.123f32;
    for i in 0..20_000_000u32 {
        x = (x * 1.618_034 + 0.1).fract();
        let (ox, oy) = (x * 2.0 - 1.0, ((i % 977) as f32) / 977.0 * 2.0 - 1.0);
        if ox * ox + oy * oy < 1.0 {
            hits += 1;
        }
    }
    std::hint::black_box(hits);
    t.elapsed().as_secs_f64()
}

/// The build options of one timed run.
fn options(spp: u32, seed: i32, mode: SpectralMode, integrator: Option<&str>) -> BuildOptions {
    BuildOptions {
        spp: Some(spp),
        seed: Some(seed),
        spectral: Some(mode),
        integrator: integrator.map(String::from),
        ..Default::default()
    }
}

/// One run: parse, build and render (pbrt-v4's wall time includes them all).
fn run_once(path: &Path, opts: &BuildOptions) -> Result<(f64, nimbus::imageio::Image, &'static str), String> {
    let t = Instant::now();
    let desc = nimbus::parser::load_file(path).map_err(|e| e.to_string())?;
    let setup = nimbus::setup::build(&desc, opts).map_err(|e| e.to_string())?;
    let prepared = setup.prepare()?;
    let scene = &setup.scene;
    let r = nimbus::render::render(
        scene,
        prepared.integrator.as_ref(),
        &nimbus::render::RenderOptions { time_budget: None, quiet: true },
    );
    Ok((t.elapsed().as_secs_f64(), r.image, scene.transport.transport.name()))
}

/// One scene and transport, measured.
#[derive(Debug)]
struct Row {
    scene: String,
    mode: String,
    transport: String,
    seconds: f64,
    mse: Option<f64>,
    pbrt_seconds: Option<f64>,
    pbrt_mse: Option<f64>,
    speedup_equal_spp: Option<f64>,
    speedup_equal_error: Option<f64>,
}

impl Row {
    fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "scene": self.scene, "mode": self.mode, "transport": self.transport, "seconds": self.seconds,
            "mse": self.mse, "pbrt_seconds": self.pbrt_seconds, "pbrt_mse": self.pbrt_mse,
            "speedup_equal_spp": self.speedup_equal_spp, "speedup_equal_error": self.speedup_equal_error,
        })
    }
}

/// Times each scene in each transport and prints a Markdown table.
pub fn run(args: &BenchArgs) -> Result<ExitCode> {
    let refs = args
        .references
        .clone()
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/pbrt-v4-references"));
    let (pbrt_spp, pbrt_threads, pbrt) = read_speed(&refs.join("speed.json"))?;
    if args.spp != pbrt_spp {
        eprintln!(
            "note: speed.json holds pbrt-v4's figures at {pbrt_spp} spp; ratios at {} spp are not comparable",
            args.spp
        );
    }
    if let Some(t) = pbrt_threads
        && t != args.nthreads as u64
    {
        eprintln!(
            "note: speed.json holds pbrt-v4's figures on {t} threads; ratios on {} are not comparable",
            args.nthreads
        );
    }
    let scenes = if args.scenes.is_empty() {
        let mut v: Vec<PathBuf> = pbrt.iter().map(|(n, _)| refs.join(format!("scenes/{n}.pbrt"))).collect();
        v.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/default.pbrt"));
        v
    } else {
        args.scenes.clone()
    };
    if args.spectral.is_empty() {
        bail!("--spectral needs at least one of off, on, auto");
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.nthreads.max(1)).build()?;
    let base = baseline_seconds();
    println!("baseline (fixed CPU workload): {base:.3} s; {} threads, {} spp", args.nthreads, args.spp);
    if let Some(i) = &args.integrator {
        println!("integrator: {i} (the scenes' own otherwise); pbrt-v4's figures are its VolPath's");
    }
    println!("equal error: speed-up = (pbrt-v4 s × pbrt-v4 MSE) / (nimbus s × nimbus MSE), as MSE ∝ 1/time");
    println!(
        "| scene | transport | nimbus s | pbrt-v4 s | speed-up (equal spp) | nimbus MSE | pbrt-v4 MSE | speed-up (equal error) |"
    );
    println!("|---|---|--:|--:|--:|--:|--:|--:|");
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for path in &scenes {
        let name = scene_name(path);
        let figures = pbrt.iter().find(|(n, _)| *n == name).map(|(_, f)| *f);
        let ref_path = refs.join(format!("images/{name}.exr"));
        // No reference means no MSE: say why instead of leaving a silent "-".
        let reference = match nimbus::imageio::read_exr(&ref_path) {
            Ok(r) => Some(r),
            Err(e) => {
                eprintln!("note: {name}: no MSE ({}: {e})", ref_path.display());
                None
            }
        };
        for &mode in &args.spectral {
            // Seeds 1 and 2 as pbrt-v4's MSE figure; the timed runs alternate them.
            let mut times = Vec::new();
            let mut images = Vec::new();
            let mut transport = "";
            let mut failed = None;
            for k in 0..args.repeat.max(2) {
                match pool.install(|| {
                    run_once(path, &options(args.spp, 1 + (k % 2) as i32, mode, args.integrator.as_deref()))
                }) {
                    Ok((t, img, tr)) => {
                        times.push(t);
                        transport = tr;
                        if k < 2 {
                            images.push(img);
                        }
                    }
                    Err(e) => {
                        failed = Some(e);
                        break;
                    }
                }
            }
            if let Some(e) = failed {
                println!("| {name} | {mode} | failed: {e} | | | | | |");
                failures.push(serde_json::json!({ "scene": name, "mode": mode.to_string(), "error": e }));
                continue;
            }
            let seconds = median(&mut times);
            let mse = match &reference {
                None => None,
                Some(r) => {
                    let m: Result<Vec<f64>, nimbus::Error> =
                        images.iter().map(|i| nimbus::metrics::error_metrics(i, r).map(|e| e.mse)).collect();
                    match m {
                        Ok(m) => Some(m.iter().sum::<f64>() / m.len() as f64),
                        Err(e) => {
                            eprintln!("note: {name}: no MSE against {}: {e}", ref_path.display());
                            None
                        }
                    }
                }
            };
            let equal_spp = figures.map(|f| f.seconds / seconds);
            let equal_error = figures.zip(mse).map(|(f, m)| (f.seconds * f.mse) / (seconds * m));
            let fmt = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |v| format!("{v:.p$}"));
            let fmte = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3e}"));
            println!(
                "| {name} | {transport} ({mode}) | {seconds:.2} | {} | {} | {} | {} | {} |",
                fmt(figures.map(|f| f.seconds), 2),
                equal_spp.map_or("-".into(), |v| format!("{v:.2}x")),
                fmte(mse),
                fmte(figures.map(|f| f.mse)),
                equal_error.map_or("-".into(), |v| format!("{v:.2}x")),
            );
            rows.push(Row {
                scene: name.clone(),
                mode: mode.to_string(),
                transport: transport.to_string(),
                seconds,
                mse,
                pbrt_seconds: figures.map(|f| f.seconds),
                pbrt_mse: figures.map(|f| f.mse),
                speedup_equal_spp: equal_spp,
                speedup_equal_error: equal_error,
            });
        }
    }
    if let Some(path) = &args.json {
        let rows: Vec<serde_json::Value> = rows.iter().map(Row::to_json).collect();
        let doc = serde_json::json!({
            "baseline_seconds": base, "spp": args.spp, "threads": args.nthreads, "integrator": args.integrator,
            "rows": rows, "failures": failures,
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    if !failures.is_empty() {
        eprintln!("error: {} scene/transport run(s) failed (see the table)", failures.len());
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_medians() {
        assert_eq!(scene_name(Path::new("a/b/cloud.pbrt")), "cloud");
        assert_eq!(scene_name(Path::new("cloud.pbrt.gz")), "cloud");
        assert_eq!(median(&mut [3.0, 1.0]), 2.0);
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
    }
}
