//! `nimbus render scene.pbrt`: pbrt-v4's command line (`--spp`, `--outfile`, `--nthreads`,
//! `--seed`, `--cropwindow`, `--pixelbounds`, `--quick`, `--stats`) plus `--integrator` and
//! `--time`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use nimbus::scene::BuildOptions;
use nimbus::scene::transport::SpectralMode;
use nimbus::setup::unused_parameters;

/// Arguments of `nimbus render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (`.pbrt`, `.pbrt.gz`, or `-` for standard input).
    scene: PathBuf,
    /// Samples per pixel (overrides the scene's sampler).
    #[arg(long)]
    spp: Option<u32>,
    /// Output image (.exr float RGB with metadata, or .png 8-bit sRGB); default: the film's
    /// filename.
    #[arg(long)]
    outfile: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    nthreads: Option<usize>,
    /// Sampler seed.
    #[arg(long)]
    seed: Option<i32>,
    /// Render only this part of the image, in NDC: x0 x1 y0 y1 (or x0,x1,y0,y1 as pbrt-v4
    /// writes it).
    #[arg(long, num_args = 1..=4, value_delimiter = ',', value_names = ["X0", "X1", "Y0", "Y1"], allow_negative_numbers = true)]
    cropwindow: Option<Vec<f32>>,
    /// Render only these pixels: x0 x1 y0 y1 (or x0,x1,y0,y1 as pbrt-v4 writes it).
    #[arg(long, num_args = 1..=4, value_delimiter = ',', value_names = ["X0", "X1", "Y0", "Y1"], allow_negative_numbers = true)]
    pixelbounds: Option<Vec<i32>>,
    /// Quarter resolution and samples.
    #[arg(long)]
    quick: bool,
    /// Print rays/s, paths/s, memory and time per phase.
    #[arg(long)]
    stats: bool,
    /// Render with this integrator instead of the scene's (drop-in comparison).
    #[arg(long)]
    integrator: Option<String>,
    /// What the method prepares before rendering (a radiance graph, the thesis's
    /// `--graph-data`; a guide's trained trees, `--guide-cache`): loaded when the file exists
    /// (and refused when it was prepared for another scene or other settings), else prepared
    /// now and saved there, for later renders and other cameras.
    #[arg(long, value_name = "FILE", visible_aliases = ["graph-data", "guide-cache"])]
    precomputed: Option<PathBuf>,
    /// Longest light path, overriding the integrator's `maxdepth` (the radiance-graph
    /// thesis's pbrt-v4 has this flag; its VolPath references are rendered with it).
    #[arg(long, value_name = "N")]
    maxdepth: Option<u32>,
    /// Render progressively for this many seconds instead of to the scene's spp.
    #[arg(long)]
    time: Option<f64>,
    /// Replace the scene's camera transform by this `LookAt` (eye, look-at point, up): another
    /// view of the same scene, e.g. a frame of an orbit. The camera's medium stays the scene's.
    #[arg(long, num_args = 9, value_names = ["EX", "EY", "EZ", "LX", "LY", "LZ", "UX", "UY", "UZ"], allow_negative_numbers = true)]
    lookat: Option<Vec<f64>>,
    /// No progress bar or summary.
    #[arg(long)]
    quiet: bool,
    /// Fail on warnings (unused parameters, unsupported features with stand-ins).
    #[arg(long)]
    strict: bool,
    /// Light transport: `auto` (RGB where it gives the same answer, pbrt-v4's sampled
    /// spectra otherwise), `on` (always spectral) or `off` (always RGB); overrides the
    /// scene's `Option "spectral"`.
    #[arg(long, value_name = "auto|on|off")]
    spectral: Option<SpectralMode>,
}

/// Prints a scene's error at its place, or at the scene file when it has none (as `nimbus
/// check` prints it).
pub(crate) fn scene_error(e: &nimbus::parser::Error, scene: &std::path::Path) {
    match &e.loc {
        Some(loc) => eprintln!("{loc}: error: {}", e.message),
        None => eprintln!("{}: error: {}", scene.display(), e.message),
    }
}

/// Runs the render.
pub fn run(args: &RenderArgs) -> Result<ExitCode> {
    let t_start = Instant::now();
    if let Some(n) = args.nthreads {
        rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global().context("setting the thread count")?;
    }
    if let Some(t) = args.time
        && (!t.is_finite() || t <= 0.0)
    {
        anyhow::bail!("--time must be a positive number of seconds");
    }
    for (flag, n) in [
        ("--cropwindow", args.cropwindow.as_ref().map(Vec::len)),
        ("--pixelbounds", args.pixelbounds.as_ref().map(Vec::len)),
    ] {
        if let Some(n) = n
            && n != 4
        {
            anyhow::bail!("{flag} takes four numbers, x0 x1 y0 y1 (or x0,x1,y0,y1 as pbrt-v4 writes them); got {n}");
        }
    }
    let mut desc = match nimbus::parser::load_file(&args.scene) {
        Ok(d) => d,
        Err(e) => {
            scene_error(&e, &args.scene);
            return Ok(ExitCode::FAILURE);
        }
    };
    if let Some(v) = &args.lookat {
        let camera_from_world =
            nimbus::parser::transform::look_at([v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]])
                .ok_or_else(|| anyhow::anyhow!("--lookat: the view direction is zero or parallel to up"))?;
        let world_from_camera = camera_from_world.inverse();
        let t = &mut desc.camera.world_from_camera;
        (t.start, t.end) = (world_from_camera, world_from_camera);
    }
    let t_parsed = Instant::now();
    let opts = BuildOptions {
        integrator: args.integrator.clone(),
        scene_file: (args.scene.as_os_str() != "-").then(|| args.scene.clone()),
        precomputed: args.precomputed.clone(),
        max_depth: args.maxdepth,
        spp: args.spp,
        seed: args.seed,
        quick: args.quick,
        crop_window: args.cropwindow.as_ref().map(|v| [v[0], v[1], v[2], v[3]]),
        pixel_bounds: args.pixelbounds.as_ref().map(|v| [v[0], v[1], v[2], v[3]]),
        spectral: args.spectral,
    };
    let setup = match nimbus::setup::build(&desc, &opts) {
        Ok(s) => s,
        Err(e) => {
            scene_error(&e, &args.scene);
            return Ok(ExitCode::FAILURE);
        }
    };
    let scene = &setup.scene;
    let mut warnings = scene.warnings.clone();
    warnings.extend(unused_parameters(&desc));
    for w in &warnings {
        match &w.loc {
            Some(loc) => eprintln!("{loc}: warning: {}", w.message),
            None => eprintln!("warning: {}", w.message),
        }
    }
    if args.strict && !warnings.is_empty() {
        eprintln!("error: {} warning(s) and --strict was given", warnings.len());
        return Ok(ExitCode::FAILURE);
    }
    let t_built = Instant::now();
    let rss_before_setup = super::memory::rss_bytes();
    // A method's precomputation (guide training, graph building) counts in the budget.
    let prepared = match setup.prepare() {
        Ok(p) => p,
        Err(e) => {
            scene_error(&nimbus::setup::method_error(&desc, &e), &args.scene);
            return Ok(ExitCode::FAILURE);
        }
    };
    let (integrator, setup) = (&prepared.integrator, prepared.seconds);
    // What a method's precomputed structure cost as the system counts it (its own count
    // misses transient allocations: traced path batches, hash-map growth), when it has one.
    let precomputed = match (integrator.precomputed_bytes(), rss_before_setup, super::memory::peak_rss_bytes()) {
        (0, ..) => 0,
        (own, Some(before), Some(peak)) => (own as u64).max(peak.saturating_sub(before)),
        (own, ..) => own as u64,
    };
    let time_budget = prepared.remaining(args.time);
    let result = nimbus::render::render(
        scene,
        integrator.as_ref(),
        &nimbus::render::RenderOptions { time_budget, quiet: args.quiet },
    );
    let t_rendered = Instant::now();
    let mut image = result.image;
    image.metadata.insert("nimbus:spp".into(), result.spp.to_string());
    image.metadata.insert("nimbus:time".into(), format!("{:.3}", result.seconds));
    image.metadata.insert("nimbus:integrator".into(), integrator.name().to_string());
    image.metadata.insert("nimbus:seed".into(), scene.sampler.seed.to_string());
    image.metadata.insert("nimbus:scene".into(), args.scene.display().to_string());
    image.metadata.insert("nimbus:transport".into(), scene.transport.transport.name().to_string());
    image.metadata.insert("nimbus:transport-reason".into(), scene.transport.reason.clone());
    image.metadata.insert("nimbus:sensor".into(), scene.sensor.name().to_string());
    image.metadata.insert("nimbus:setup-time".into(), format!("{setup:.3}"));
    // Where this image lies in the film, so that parts rendered with --pixelbounds merge.
    let pbrt_order = |b: [u32; 4]| super::merge::bounds_text([b[0], b[2], b[1], b[3]]);
    image.metadata.insert("nimbus:pixel-bounds".into(), pbrt_order(scene.pixel_bounds));
    image.metadata.insert("nimbus:film-bounds".into(), pbrt_order(scene.film_bounds));
    if args.scene.as_os_str() != "-" {
        image.metadata.insert("nimbus:scene-hash".into(), super::scene_hash::of_file(&args.scene)?);
    }
    if let Some(v) = &args.lookat {
        let text: Vec<String> = v.iter().map(f64::to_string).collect();
        image.metadata.insert("nimbus:camera".into(), format!("LookAt {}", text.join(" ")));
    }
    image.metadata.insert("nimbus:nonfinite-samples".into(), result.nonfinite_samples.to_string());
    image.metadata.insert("nimbus:precomputed-bytes".into(), precomputed.to_string());
    let peak_rss = super::memory::peak_rss_bytes();
    if let Some(bytes) = peak_rss {
        image.metadata.insert("nimbus:peak-rss-bytes".into(), bytes.to_string());
    }
    let out = args.outfile.clone().unwrap_or_else(|| PathBuf::from(&scene.film.filename));
    nimbus::imageio::write_image(&out, &image).map_err(anyhow::Error::msg)?;
    let t_written = Instant::now();
    if !args.quiet {
        eprintln!(
            "{}: {}x{}, {} spp, {} in {:.2} s",
            out.display(),
            image.width,
            image.height,
            result.spp,
            integrator.name(),
            result.seconds
        );
    }
    if args.stats {
        let secs = result.seconds.max(1e-9);
        println!(
            "phase       parse {:.3} s, build {:.3} s (geometry {:.3} s), render {:.3} s, write {:.3} s",
            (t_parsed - t_start).as_secs_f64(),
            (t_built - t_parsed).as_secs_f64(),
            scene.stats.geometry_seconds,
            (t_rendered - t_built).as_secs_f64(),
            (t_written - t_rendered).as_secs_f64()
        );
        println!(
            "rays        {} total ({} camera, {} bounce, {} shadow), {:.3} M rays/s",
            result.rays.total(),
            result.rays.camera,
            result.rays.bounce,
            result.rays.shadow,
            result.rays.total() as f64 / secs / 1e6
        );
        println!("paths       {:.3} M paths/s", result.rays.camera as f64 / secs / 1e6);
        println!(
            "geometry    {} primitives, {} triangles, {:.1} MiB of mesh data, {}",
            scene.stats.primitives,
            scene.stats.triangles,
            scene.stats.mesh_bytes as f64 / (1 << 20) as f64,
            if scene.surfaces.top.is_some() { "BVH built" } else { "no surfaces, no BVH" }
        );
        println!(
            "transport   {} ({}); sensor {}, imaging ratio {}",
            match scene.transport.transport {
                nimbus::scene::transport::Transport::Rgb => "rgb (3 channels)",
                nimbus::scene::transport::Transport::Spectral => "spectral (4 sampled wavelengths)",
            },
            scene.transport.reason,
            scene.sensor.name(),
            scene.sensor.imaging_ratio()
        );
        for line in integrator.report() {
            println!("{line}");
        }
        println!(
            "memory      peak {} resident; {} NaN or infinite samples (zeroed)",
            peak_rss.map_or("unknown".into(), |b| format!("{:.1} MiB", b as f64 / (1 << 20) as f64)),
            result.nonfinite_samples
        );
        println!("lights      {}", scene.lights.len());
        for m in &scene.media {
            println!(
                "medium      \"{}\": {}, {:.2} MiB",
                m.name,
                m.representation(scene.transport.transport == nimbus::scene::transport::Transport::Spectral),
                m.memory_bytes() as f64 / (1 << 20) as f64
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
