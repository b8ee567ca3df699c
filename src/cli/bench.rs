//! `nimbus bench`: speed on the parity scenes against pbrt-v4's own figures for them, at equal
//! spp and at equal error, for each transport; plus a CPU baseline measured in the same run so
//! figures from different machines can be compared. The figures are each folder's speed.json:
//! `pbrt-scenes/pbrt-v4-references` (wall seconds at `--nthreads 2 --spp 64`, MSE against the
//! reference images at that spp) and `pbrt-scenes/disney-cloud` (the real Disney cloud at 16 spp,
//! MSE against two independent reference halves with their own noise removed).
//!
//! With `--pbrt PATH` pbrt-v4 itself is timed in the same run instead, on the same seeds, spp
//! and thread count, in rounds with nimbus's transports (each round of a scene runs every one
//! once, starting with the next): ratios that the machine's speed on the day does not move,
//! nor its drifts within a scene's runs favour whichever runs first.
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
    /// Scenes to time (default: every scene of the speed.json files, and
    /// pbrt-scenes/default.pbrt).
    scenes: Vec<PathBuf>,
    /// Samples per pixel (default: each speed.json's, pbrt-v4's figures were measured at it).
    #[arg(long)]
    spp: Option<u32>,
    /// Worker threads (pbrt-v4's figures use 2).
    #[arg(long, default_value_t = 2)]
    nthreads: usize,
    /// Runs per scene and transport (at least 2: seeds 1 and 2 give the MSE); the fastest is
    /// reported.
    #[arg(long, default_value_t = 2)]
    repeat: usize,
    /// Folders of pbrt-v4 figures, comma separated: each has a speed.json, and scenes/NAME.pbrt
    /// and images/NAME.exr unless its speed.json names them (default:
    /// pbrt-scenes/pbrt-v4-references and pbrt-scenes/disney-cloud).
    #[arg(long, value_delimiter = ',')]
    references: Vec<PathBuf>,
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
    /// A pbrt-v4 executable to time in this run, in rounds with nimbus on each scene
    /// (`--quiet --nthreads N --spp S --seed 1|2 --outfile ...`, wall seconds, MSE against
    /// the same references), instead of the speed.json figures from another day.
    #[arg(long)]
    pbrt: Option<PathBuf>,
}

/// pbrt-v4's figures for one scene.
#[derive(Clone, Copy, Debug)]
struct PbrtFigures {
    seconds: f64,
    mse: f64,
}

/// One scene of a speed.json: its figures, where its scene file and reference images are
/// (one image, or two independent halves whose noise the MSE leaves out), and the spp and
/// thread count they were measured at.
#[derive(Clone, Debug)]
struct Entry {
    name: String,
    figures: Option<PbrtFigures>,
    scene: PathBuf,
    reference: Vec<PathBuf>,
    spp: u32,
    threads: Option<u64>,
}

/// The entries of `folder`'s speed.json: `{"spp": .., "threads": .., "scenes": {"name":
/// {"seconds": .., "mse": ..}}}`, where a scene may also name its `"scene"` file and its
/// `"reference"` images (one, or two independent halves), relative to the folder; by default
/// scenes/NAME.pbrt and images/NAME.exr.
fn read_entries(folder: &Path) -> Result<Vec<Entry>> {
    let path = &folder.join("speed.json");
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
        let figures = PbrtFigures { seconds: num("seconds")?, mse: num("mse")? };
        let scene = match f.get("scene") {
            None => folder.join(format!("scenes/{name}.pbrt")),
            Some(p) => folder
                .join(p.as_str().with_context(|| format!("{}: scenes.{name}.scene must be a path", path.display()))?),
        };
        let reference = match f.get("reference") {
            None => vec![folder.join(format!("images/{name}.exr"))],
            Some(r) => {
                let list = r.as_array().filter(|a| (1..=2).contains(&a.len()));
                let list = list.with_context(|| {
                    format!("{}: scenes.{name}.reference must be a list of one or two paths", path.display())
                })?;
                let paths: Option<Vec<PathBuf>> = list.iter().map(|p| p.as_str().map(|p| folder.join(p))).collect();
                paths.with_context(|| format!("{}: scenes.{name}.reference must hold paths", path.display()))?
            }
        };
        out.push(Entry { name: name.clone(), figures: Some(figures), scene, reference, spp: spp as u32, threads });
    }
    Ok(out)
}

/// MSE of each image against `reference`: one image, or the mean of two independent halves,
/// with the mean's own noise (E[(h1 − h2)²]/4) subtracted.
fn mse_against(images: &[nimbus::imageio::Image], reference: &[PathBuf]) -> Result<f64, String> {
    let read = |p: &PathBuf| nimbus::imageio::read_exr(p).map_err(|e| format!("{}: {e}", p.display()));
    let refs = reference.iter().map(read).collect::<Result<Vec<_>, _>>()?;
    let mse = |a: &nimbus::imageio::Image, b: &nimbus::imageio::Image| {
        nimbus::metrics::error_metrics(a, b).map(|e| e.mse).map_err(|e| e.to_string())
    };
    let (mean, noise) = match refs.as_slice() {
        [r] => (r.clone(), 0.0),
        [a, b] => {
            let mut m = a.clone();
            for (p, q) in m.pixels.iter_mut().zip(&b.pixels) {
                *p = 0.5 * (*p + *q);
            }
            (m, mse(a, b)? / 4.0)
        }
        _ => return Err("one reference image or two halves".into()),
    };
    let m = images.iter().map(|i| mse(i, &mean)).collect::<Result<Vec<_>, _>>()?;
    Ok(m.iter().sum::<f64>() / m.len() as f64 - noise)
}

/// A scene's name as speed.json and the reference images name it: the file name without
/// `.pbrt` or `.pbrt.gz`.
fn scene_name(path: &Path) -> String {
    let file = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let file = file.strip_suffix(".gz").unwrap_or(&file);
    file.strip_suffix(".pbrt").unwrap_or(file).to_string()
}

/// The fastest of `times`. Other work on the machine only ever slows a run down (on the 2-core
/// machines of the references, medians of 3 moved single scenes' ratios by 20 % between two
/// runs an hour apart), so the fastest run is the closest to a program's own cost; both
/// programs are timed the same way, as pbrt-v4's stored figures were (best of 2).
fn fastest(times: &[f64]) -> f64 {
    times.iter().copied().fold(f64::INFINITY, f64::min)
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

/// One pbrt-v4 run on `scene` with seed `seed`: its wall time (start-up and exit included, as
/// the stored figures) and image.
fn pbrt_once(
    pbrt: &Path,
    scene: &Path,
    spp: u32,
    nthreads: usize,
    seed: i32,
) -> Result<(f64, nimbus::imageio::Image), String> {
    let scene = std::fs::canonicalize(scene).map_err(|e| format!("{}: {e}", scene.display()))?;
    let dir = scene.parent().unwrap_or(Path::new("."));
    let out = std::env::temp_dir().join(format!("nimbus-bench-pbrt-{}-{seed}.exr", std::process::id()));
    let t = Instant::now();
    let output = std::process::Command::new(pbrt)
        .current_dir(dir)
        .args(["--quiet", "--nthreads", &nthreads.to_string(), "--spp", &spp.to_string()])
        .args(["--seed", &seed.to_string(), "--outfile"])
        .arg(&out)
        .arg(&scene)
        .stdout(std::process::Stdio::null())
        .output()
        .map_err(|e| format!("{}: cannot run: {e}", pbrt.display()))?;
    let seconds = t.elapsed().as_secs_f64();
    let image = nimbus::imageio::read_exr(&out);
    let _ = std::fs::remove_file(&out);
    if !output.status.success() {
        let err = String::from_utf8_lossy(&output.stderr);
        let last = err.lines().last().unwrap_or("").trim().to_string();
        return Err(format!("{} exited with {}: {last}", pbrt.display(), output.status));
    }
    let image = image.map_err(|e| format!("{}: no image: {e}", pbrt.display()))?;
    Ok((seconds, image))
}

/// What is timed on a scene: the pbrt-v4 executable, or nimbus in one transport.
#[derive(Clone, Copy)]
enum Runner<'a> {
    Pbrt(&'a Path),
    Nimbus(SpectralMode),
}

/// A runner's runs of one scene: wall times, the images of seeds 1 and 2, nimbus's transport,
/// or the error that stopped it.
#[derive(Default)]
struct Tally {
    times: Vec<f64>,
    images: Vec<nimbus::imageio::Image>,
    transport: &'static str,
    failed: Option<String>,
}

/// One scene and transport, measured.
#[derive(Debug)]
struct Row {
    scene: String,
    spp: u32,
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
            "scene": self.scene, "spp": self.spp, "mode": self.mode, "transport": self.transport, "seconds": self.seconds,
            "mse": self.mse, "pbrt_seconds": self.pbrt_seconds, "pbrt_mse": self.pbrt_mse,
            "speedup_equal_spp": self.speedup_equal_spp, "speedup_equal_error": self.speedup_equal_error,
        })
    }
}

/// Times each scene in each transport and prints a Markdown table.
pub fn run(args: &BenchArgs) -> Result<ExitCode> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let folders = if args.references.is_empty() {
        vec![root.join("pbrt-scenes/pbrt-v4-references"), root.join("pbrt-scenes/disney-cloud")]
    } else {
        args.references.clone()
    };
    let mut entries = Vec::new();
    for f in &folders {
        entries.extend(read_entries(f)?);
    }
    let first_spp = entries.first().map(|e| e.spp);
    let entries: Vec<Entry> = if args.scenes.is_empty() {
        let mut v = entries;
        v.push(Entry {
            name: "default".into(),
            figures: None,
            scene: root.join("pbrt-scenes/default.pbrt"),
            reference: vec![folders[0].join("images/default.exr")],
            spp: first_spp.unwrap_or(64),
            threads: None,
        });
        v
    } else {
        // A scene named in a speed.json gets its figures and reference; another one the first
        // folder's images/NAME.exr.
        args.scenes
            .iter()
            .map(|p| {
                let name = scene_name(p);
                match entries.iter().find(|e| e.name == name) {
                    Some(e) => Entry { scene: p.clone(), ..e.clone() },
                    None => Entry {
                        reference: vec![folders[0].join(format!("images/{name}.exr"))],
                        name,
                        figures: None,
                        scene: p.clone(),
                        spp: first_spp.unwrap_or(64),
                        threads: None,
                    },
                }
            })
            .collect()
    };
    for e in &entries {
        if let Some(spp) = args.spp
            && spp != e.spp
            && e.figures.is_some()
        {
            eprintln!(
                "note: {}: pbrt-v4's figures are at {} spp; ratios at {spp} spp are not comparable",
                e.name, e.spp
            );
        }
        if let Some(t) = e.threads
            && t != args.nthreads as u64
        {
            eprintln!(
                "note: {}: pbrt-v4's figures are on {t} threads; ratios on {} are not comparable",
                e.name, args.nthreads
            );
        }
    }
    if args.spectral.is_empty() {
        bail!("--spectral needs at least one of off, on, auto");
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.nthreads.max(1)).build()?;
    let base = baseline_seconds();
    let spp_note = args.spp.map_or("each speed.json's spp".to_string(), |s| format!("{s} spp"));
    println!("baseline (fixed CPU workload): {base:.3} s; {} threads, {spp_note}", args.nthreads);
    match &args.pbrt {
        Some(p) => println!("pbrt-v4: {} timed in this run, in rounds with nimbus on each scene", p.display()),
        None => println!("pbrt-v4: the speed.json figures (measured on another day: compare within one run)"),
    }
    if let Some(i) = &args.integrator {
        println!("integrator: {i} (the scenes' own otherwise); pbrt-v4's figures are its VolPath's");
    }
    println!("equal error: speed-up = (pbrt-v4 s × pbrt-v4 MSE) / (nimbus s × nimbus MSE), as MSE ∝ 1/time");
    println!(
        "| scene | spp | transport | nimbus s | pbrt-v4 s | speed-up (equal spp) | nimbus MSE | pbrt-v4 MSE | speed-up (equal error) |"
    );
    println!("|---|--:|---|--:|--:|--:|--:|--:|--:|");
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for entry in &entries {
        let (name, path) = (&entry.name, &entry.scene);
        let spp = args.spp.unwrap_or(entry.spp);
        // No reference means no MSE: say why instead of leaving a silent "-".
        let missing = entry.reference.iter().find(|p| !p.exists());
        if let Some(p) = missing {
            eprintln!("note: {name}: no MSE ({}: no such file)", p.display());
        }
        // Every runner once per round, seeds 1 and 2 alternating between rounds (the first two
        // give the MSE), each round starting with the next runner: whatever the machine does
        // meanwhile falls on all of them alike, not on whichever always comes last.
        let mut runners = Vec::new();
        if let (Some(pbrt), None) = (&args.pbrt, missing) {
            runners.push(Runner::Pbrt(pbrt));
        }
        runners.extend(args.spectral.iter().map(|&m| Runner::Nimbus(m)));
        let mut tallies: Vec<Tally> = runners.iter().map(|_| Tally::default()).collect();
        for k in 0..args.repeat.max(2) {
            let seed = 1 + (k % 2) as i32;
            for j in 0..runners.len() {
                let i = (j + k) % runners.len();
                let tally = &mut tallies[i];
                if tally.failed.is_some() {
                    continue;
                }
                let run = match runners[i] {
                    Runner::Pbrt(pbrt) => pbrt_once(pbrt, path, spp, args.nthreads, seed).map(|(t, img)| (t, img, "")),
                    Runner::Nimbus(mode) => {
                        pool.install(|| run_once(path, &options(spp, seed, mode, args.integrator.as_deref())))
                    }
                };
                match run {
                    Ok((t, img, transport)) => {
                        tally.times.push(t);
                        tally.transport = transport;
                        if k < 2 {
                            tally.images.push(img);
                        }
                    }
                    Err(e) => tally.failed = Some(e),
                }
            }
        }
        let figures = match (&args.pbrt, missing) {
            (None, _) => entry.figures,
            (Some(_), Some(_)) => None,
            (Some(pbrt), None) => {
                // The pbrt-v4 runner is the first.
                let tally = &tallies[0];
                let figures = match &tally.failed {
                    Some(e) => Err(e.clone()),
                    None => mse_against(&tally.images, &entry.reference)
                        .map(|mse| PbrtFigures { seconds: fastest(&tally.times), mse })
                        .map_err(|e| format!("{}: {e}", pbrt.display())),
                };
                match figures {
                    Ok(f) => Some(f),
                    Err(e) => {
                        println!("| {name} | {spp} | pbrt-v4 | failed: {e} | | | | | |");
                        failures.push(serde_json::json!({ "scene": name, "mode": "pbrt-v4", "error": e }));
                        continue;
                    }
                }
            }
        };
        for (runner, tally) in runners.iter().zip(&tallies) {
            let Runner::Nimbus(mode) = *runner else { continue };
            let (times, images, transport) = (&tally.times, &tally.images, tally.transport);
            if let Some(e) = &tally.failed {
                println!("| {name} | {spp} | {mode} | failed: {e} | | | | | |");
                failures.push(serde_json::json!({ "scene": name, "mode": mode.to_string(), "error": e }));
                continue;
            }
            let seconds = fastest(times);
            let mse = if missing.is_some() {
                None
            } else {
                match mse_against(images, &entry.reference) {
                    Ok(m) => Some(m),
                    Err(e) => {
                        eprintln!("note: {name}: no MSE: {e}");
                        None
                    }
                }
            };
            let equal_spp = figures.map(|f| f.seconds / seconds);
            let equal_error = figures.zip(mse).map(|(f, m)| (f.seconds * f.mse) / (seconds * m));
            let fmt = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |v| format!("{v:.p$}"));
            let fmte = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3e}"));
            println!(
                "| {name} | {spp} | {transport} ({mode}) | {seconds:.2} | {} | {} | {} | {} | {} |",
                fmt(figures.map(|f| f.seconds), 2),
                equal_spp.map_or("-".into(), |v| format!("{v:.2}x")),
                fmte(mse),
                fmte(figures.map(|f| f.mse)),
                equal_error.map_or("-".into(), |v| format!("{v:.2}x")),
            );
            rows.push(Row {
                scene: name.clone(),
                spp,
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
            "baseline_seconds": base, "threads": args.nthreads, "integrator": args.integrator,
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
    fn names_and_fastest_times() {
        assert_eq!(scene_name(Path::new("a/b/cloud.pbrt")), "cloud");
        assert_eq!(scene_name(Path::new("cloud.pbrt.gz")), "cloud");
        assert_eq!(fastest(&[3.0, 1.0]), 1.0);
        assert_eq!(fastest(&[3.0, 1.5, 2.0]), 1.5);
    }
}
