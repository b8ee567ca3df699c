//! `nimbus compare scene.pbrt --integrators a,b,...`: renders one scene with several
//! integrators at equal time and/or equal spp, measures each against a VolPath reference at
//! checkpoints along the way, and writes tables, charts, final images and error images.
//!
//! - `run.rs`: the reference (given, cached or rendered) and one integrator's timed render.
//! - `report.rs`: `results.csv`, `results.json`, `results.md`.
//! - `charts.rs`: relMSE against time (log-log) and a bar chart of the final relMSE.
//! - `html.rs`: `--html`, one self-contained interactive page (`report.js`, `report.css`).

mod charts;
mod html;
mod report;
pub(crate) mod run;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use nimbus::integrators::{INTEGRATOR_NAMES, REFERENCE};

use run::{Mode, Run};

/// Arguments of `nimbus compare`.
#[derive(clap::Args)]
#[command(group = clap::ArgGroup::new("reference_source").required(true).args(["reference", "reference_spp"]))]
#[command(group = clap::ArgGroup::new("budget").required(true).multiple(true).args(["time", "spp"]))]
pub struct CompareArgs {
    /// Scene file (`.pbrt` or `.pbrt.gz`).
    scene: PathBuf,
    /// Integrators to compare, comma-separated (any of nimbus's; an unknown name is answered
    /// with the list).
    #[arg(long, value_delimiter = ',', default_value = REFERENCE)]
    integrators: Vec<String>,
    /// Reference image (.exr) of the film's pixel bounds.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Render a VolPath reference at this spp, cached next to the scene as
    /// `<scene>.volpath-<N>spp-seed<S>.exr` and reused while it matches.
    #[arg(long)]
    reference_spp: Option<u32>,
    /// Seed of the rendered reference (default: the renders' seed + 1, so that the reference's
    /// samples are independent of theirs).
    #[arg(long)]
    reference_seed: Option<i32>,
    /// Equal time: render each integrator progressively for this many seconds, counted from
    /// before its scene is built.
    #[arg(long)]
    time: Option<f64>,
    /// Equal spp: render each integrator to this many samples per pixel.
    #[arg(long)]
    spp: Option<u32>,
    /// Sampler seed of the renders (default: the scene's).
    #[arg(long)]
    seed: Option<i32>,
    /// Checkpoints per doubling of the sample count (1, 2, 4, ... spp for 1).
    #[arg(long, default_value_t = 2)]
    checkpoints: u32,
    /// Output folder (default: `compare-<scene>`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    nthreads: Option<usize>,
    /// Print only the results table.
    #[arg(long)]
    quiet: bool,
    /// Also write one self-contained HTML page here: the reference, every image and its error
    /// side by side, a flip view (keys 0-9, e), synchronized zoom and pan, pixel values on
    /// hover, the error-vs-time chart and the table. It loads nothing from a network.
    #[arg(long)]
    html: Option<PathBuf>,
}

/// The scene's name without `.pbrt` / `.pbrt.gz`.
pub(crate) fn scene_stem(path: &Path) -> String {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    name.strip_suffix(".pbrt").unwrap_or(name).to_string()
}

/// Everything a comparison produced, for the reports.
pub struct Comparison {
    /// The scene file.
    pub scene: PathBuf,
    /// Seed of the renders.
    pub seed: i32,
    /// Checkpoints per doubling of spp.
    pub checkpoints_per_doubling: u32,
    /// `--time`
    pub time_budget: Option<f64>,
    /// `--spp`
    pub spp: Option<u32>,
    /// The reference and where it came from.
    pub reference: run::Reference,
    /// One run per integrator and mode, in the order given.
    pub runs: Vec<Run>,
    /// Difference shown at full intensity in the error images, per mode.
    pub diff_scale: Vec<(Mode, f64)>,
}

impl Comparison {
    /// The runs whose final errors the bar chart and the table lead with: equal time if it was
    /// asked for, else equal spp.
    pub fn headline_mode(&self) -> Mode {
        if self.time_budget.is_some() { Mode::EqualTime } else { Mode::EqualSpp }
    }

    /// Runs of one mode.
    pub fn runs_of(&self, mode: Mode) -> impl Iterator<Item = &Run> {
        self.runs.iter().filter(move |r| r.mode == mode)
    }
}

fn validate(args: &CompareArgs) -> Result<Vec<String>> {
    if let Some(t) = args.time {
        anyhow::ensure!(t.is_finite() && t > 0.0, "--time must be a positive number of seconds");
    }
    anyhow::ensure!(args.spp != Some(0), "--spp must be at least 1");
    anyhow::ensure!(args.reference_spp != Some(0), "--reference-spp must be at least 1");
    anyhow::ensure!((1..=64).contains(&args.checkpoints), "--checkpoints must be 1 to 64 per doubling of spp");
    anyhow::ensure!(args.scene.as_os_str() != "-", "compare needs a scene file, not standard input");
    let mut names: Vec<String> = Vec::new();
    for name in &args.integrators {
        let name = name.trim();
        if name.is_empty() {
            continue;
        }
        anyhow::ensure!(
            INTEGRATOR_NAMES.contains(&name),
            "unknown integrator \"{name}\" (nimbus has: {})",
            INTEGRATOR_NAMES.join(", ")
        );
        anyhow::ensure!(!names.iter().any(|n| n == name), "integrator \"{name}\" is listed twice");
        names.push(name.to_string());
    }
    anyhow::ensure!(!names.is_empty(), "--integrators names no integrator");
    Ok(names)
}

/// Runs the comparison and writes its outputs.
pub fn run(args: &CompareArgs) -> Result<ExitCode> {
    let names = validate(args)?;
    if let Some(n) = args.nthreads {
        rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global().context("setting the thread count")?;
    }
    let say = |s: String| {
        if !args.quiet {
            eprintln!("{s}");
        }
    };
    let desc = nimbus::parser::load_file(&args.scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    let seed = match args.seed {
        Some(s) => s,
        None => {
            nimbus::samplers::settings::SamplerSettings::from_entity(&desc.sampler, desc.options.seed, &mut Vec::new())
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .seed
        }
    };
    let stem = scene_stem(&args.scene);
    let out_dir = args.out.clone().unwrap_or_else(|| PathBuf::from(format!("compare-{stem}")));
    let reference = match (&args.reference, args.reference_spp) {
        (Some(path), _) => run::Reference::from_file(path)?,
        (None, Some(n)) => {
            let ref_seed = args.reference_seed.unwrap_or(seed.wrapping_add(1));
            run::Reference::cached_or_rendered(&args.scene, &stem, &desc, n, ref_seed, args.quiet, &say)?
        }
        (None, None) => unreachable!("clap requires --reference or --reference-spp"),
    };
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;

    let mut runs = Vec::new();
    let mut warned = false;
    for name in &names {
        let modes = [(Mode::EqualTime, args.time.is_some()), (Mode::EqualSpp, args.spp.is_some())];
        for (mode, wanted) in modes {
            if !wanted {
                continue;
            }
            let setup = run::RunSetup {
                desc: &desc,
                scene_file: &args.scene,
                integrator: name,
                seed,
                mode,
                time: args.time,
                spp: args.spp,
                per_doubling: args.checkpoints,
                reference: &reference,
                print_warnings: !warned && !args.quiet,
            };
            let r = run::run_integrator(&setup)?;
            warned = true;
            let last = r.last();
            say(format!(
                "{name} ({}): {} spp in {:.2} s (setup {:.2} s), relMSE {:.4e}, MAE {:.4e}",
                mode.label(),
                last.spp,
                last.seconds,
                r.setup_seconds,
                last.metrics.rel_mse,
                last.metrics.mae
            ));
            runs.push(r);
        }
    }

    let mut diff_scale = Vec::new();
    for mode in [Mode::EqualTime, Mode::EqualSpp] {
        let best = runs.iter().filter(|r| r.mode == mode).map(|r| r.last().metrics.rmse).fold(f64::INFINITY, f64::min);
        if best.is_finite() {
            diff_scale.push((mode, (4.0 * best).max(1e-12)));
        }
    }
    let cmp = Comparison {
        scene: args.scene.clone(),
        seed,
        checkpoints_per_doubling: args.checkpoints,
        time_budget: args.time,
        spp: args.spp,
        reference,
        runs,
        diff_scale,
    };
    write_outputs(&cmp, &out_dir)?;
    if let Some(path) = &args.html {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        html::write(&html_report(&cmp), path)?;
        say(format!("wrote {}", path.display()));
    }
    print!("{}", report::markdown(&cmp));
    say(format!("wrote {}", out_dir.display()));
    Ok(ExitCode::SUCCESS)
}

/// The HTML page's content: the headline mode's final images, relMSE against time for each
/// mode that ran, the Markdown table's rows and its notes.
fn html_report(cmp: &Comparison) -> html::HtmlReport {
    let image = |i: &nimbus::imageio::Image| html::HtmlImage {
        width: i.width,
        height: i.height,
        rgb: i.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).collect(),
    };
    let methods = cmp
        .runs_of(cmp.headline_mode())
        .map(|r| {
            let c = r.last();
            html::HtmlMethod {
                name: r.integrator.clone(),
                caption: format!(
                    "relMSE {:.3e}, {} spp, {} s",
                    c.metrics.rel_mse,
                    c.spp,
                    crate::cli::plot::short(c.seconds)
                ),
                image: image(&r.image),
            }
        })
        .collect();
    // Equal time, when it ran, is the headline mode: it comes first.
    let charts = [Mode::EqualTime, Mode::EqualSpp]
        .into_iter()
        .filter(|&mode| cmp.runs_of(mode).next().is_some())
        .map(|mode| html::HtmlChart {
            title: format!("relMSE vs time ({})", mode.label()),
            x_label: "time since scene build (s)".into(),
            y_label: "relMSE".into(),
            series: cmp
                .runs_of(mode)
                .map(|r| html::HtmlSeries {
                    name: r.integrator.clone(),
                    color: charts::css_color(cmp, &r.integrator),
                    points: r.checkpoints.iter().map(|c| (c.seconds, c.metrics.rel_mse)).collect(),
                })
                .collect(),
        })
        .collect();
    let (headers, rows) = report::table(cmp);
    html::HtmlReport {
        title: format!("nimbus compare: {}", scene_stem(&cmp.scene)),
        notes: vec![
            format!(
                "Scene {}, reference {} ({}), seed {}.",
                cmp.scene.display(),
                cmp.reference.path.display(),
                report::reference_what(cmp),
                cmp.seed
            ),
            report::LEGEND.to_string(),
        ],
        reference: image(&cmp.reference.image),
        methods,
        charts,
        table: html::HtmlTable { headers, rows },
    }
}

/// File names of a run's final image and error image: `<integrator>.exr` for the headline
/// mode, `<integrator>-<N>spp.exr` for equal spp when both modes ran.
pub fn image_names(cmp: &Comparison, r: &Run) -> (String, String) {
    let base = if r.mode == cmp.headline_mode() {
        r.integrator.clone()
    } else {
        format!("{}-{}spp", r.integrator, cmp.spp.unwrap_or(0))
    };
    (format!("{base}.exr"), format!("{base}-diff.png"))
}

fn write_outputs(cmp: &Comparison, dir: &Path) -> Result<()> {
    let write = |name: &str, text: String| -> Result<()> {
        let path = dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    for r in &cmp.runs {
        let (exr, png) = image_names(cmp, r);
        let mut image = r.image.clone();
        let last = r.last();
        image.metadata.insert("nimbus:spp".into(), last.spp.to_string());
        image.metadata.insert("nimbus:time".into(), format!("{:.3}", last.seconds));
        image.metadata.insert("nimbus:integrator".into(), r.integrator.clone());
        image.metadata.insert("nimbus:seed".into(), cmp.seed.to_string());
        image.metadata.insert("nimbus:scene".into(), cmp.scene.display().to_string());
        image.metadata.insert("nimbus:compare-mode".into(), r.mode.label().into());
        nimbus::imageio::write_image(&dir.join(exr), &image).map_err(anyhow::Error::msg)?;
        let scale = cmp.diff_scale.iter().find(|(m, _)| *m == r.mode).map_or(1.0, |(_, s)| *s);
        let diff = nimbus::metrics::difference_image(&r.image, &cmp.reference.image, scale as f32);
        nimbus::imageio::write_image(&dir.join(png), &diff).map_err(anyhow::Error::msg)?;
    }
    write("results.csv", report::csv(cmp))?;
    write("results.json", report::json(cmp))?;
    write("results.md", report::markdown(cmp))?;
    charts::error_vs_time(cmp, &dir.join("relmse-vs-time"))?;
    charts::final_error_bars(cmp, &dir.join("relmse-bars"))?;
    Ok(())
}
