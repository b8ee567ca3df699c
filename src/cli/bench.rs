//! `nimbus bench`: render throughput on the parity scenes, as a ratio to pbrt-v4's own
//! times for the same scenes on this kind of machine (`--nthreads 2 --spp 64`, wall seconds,
//! from ../shared/pbrt-v4-references/README.md), plus a CPU baseline measured in the same run
//! so figures from different machines can be compared.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;
use nimbus::scene::{BuildOptions, build_scene};

/// pbrt-v4's wall-clock seconds at `--nthreads 2 --spp 64` (median of 2-3 runs), per scene.
const PBRT_V4_SECONDS: &[(&str, f64)] = &[
    ("homogeneous-sphere", 6.5),
    ("wax-dielectric", 7.0),
    ("grid-cloud", 6.5),
    ("graph-cloud", 4.5),
    ("fog-spotlight", 11.2),
    ("rgbgrid-smoke", 6.3),
    ("emissive-grid", 3.0),
    ("cornell-surfaces", 6.0),
    ("vdb-cloud", 7.8),
];

/// Arguments of `nimbus bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenes to time (default: the pbrt-v4 parity scenes and pbrt-scenes/default.pbrt).
    scenes: Vec<PathBuf>,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64)]
    spp: u32,
    /// Worker threads (pbrt-v4's figures use 2).
    #[arg(long, default_value_t = 2)]
    nthreads: usize,
    /// Runs per scene; the median is reported.
    #[arg(long, default_value_t = 2)]
    repeat: usize,
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

fn default_scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/pbrt-v4-references/scenes");
    let mut v: Vec<PathBuf> = PBRT_V4_SECONDS.iter().map(|(n, _)| dir.join(format!("{n}.pbrt"))).collect();
    v.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/default.pbrt"));
    v
}

/// Times each scene (parse + build + render, as pbrt-v4's wall time includes) and prints a
/// table.
pub fn run(args: &BenchArgs) -> Result<ExitCode> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.nthreads.max(1)).build()?;
    let base = baseline_seconds();
    println!("baseline (fixed CPU workload): {:.3} s", base);
    println!("| scene | spp | nimbus s | Msamples/s | pbrt-v4 s | speed-up vs pbrt-v4 |");
    println!("|---|---|---|---|---|---|");
    let scenes = if args.scenes.is_empty() { default_scenes() } else { args.scenes.clone() };
    for path in scenes {
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let mut times = Vec::new();
        let mut samples = 0u64;
        let mut failed = None;
        for _ in 0..args.repeat.max(1) {
            let t = Instant::now();
            let result = pool.install(|| -> Result<u64, String> {
                let desc = nimbus::parser::load_file(&path).map_err(|e| e.to_string())?;
                let scene = build_scene(&desc, &BuildOptions { spp: Some(args.spp), ..Default::default() })
                    .map_err(|e| e.to_string())?;
                let integrator = scene.integrator.create(&scene);
                let r = nimbus::render::render(
                    &scene,
                    integrator.as_ref(),
                    &nimbus::render::RenderOptions { time_budget: None, quiet: true },
                );
                Ok(r.rays.camera)
            });
            match result {
                Ok(n) => {
                    samples = n;
                    times.push(t.elapsed().as_secs_f64());
                }
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        if let Some(e) = failed {
            println!("| {name} | {} | failed: {e} | | | |", args.spp);
            continue;
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        let pbrt = PBRT_V4_SECONDS.iter().find(|(n, _)| *n == name).map(|(_, s)| *s);
        println!(
            "| {name} | {} | {median:.2} | {:.3} | {} | {} |",
            args.spp,
            samples as f64 / median / 1e6,
            pbrt.map_or("-".into(), |s| format!("{s:.1}")),
            pbrt.map_or("-".into(), |s| format!("{:.2}x", s / median)),
        );
    }
    Ok(ExitCode::SUCCESS)
}
