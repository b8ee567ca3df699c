//! `nimbus compare scene.pbrt --integrators a,b,...`: renders one scene with several
//! integrators at equal time and/or equal spp, measures each against a VolPath reference at
//! checkpoints along the way, and writes tables, charts, final images and error images.
//!
//! - `run.rs`: the reference (given, cached or rendered; one image or two independent halves)
//!   and one integrator's timed render.
//! - `stats.rs`: means and standard errors over seeds, bias and its z, time to equal error.
//! - `report.rs`: `results.csv`, `results.json` (its schema: `docs/compare-results.md`),
//!   `results.md`.
//! - `charts.rs`: relMSE against time (log-log) and a bar chart of the final relMSE.
//! - `html.rs`: `--html`, one self-contained interactive page (`report.js`, `report.css`).

mod charts;
mod html;
mod report;
pub(crate) mod run;
mod stats;

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
    /// Reference image (.exr) of the film's pixel bounds, or two independent halves of one,
    /// comma-separated (their mean is the reference; their difference measures its noise,
    /// which is then removed from the errors).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    reference: Vec<PathBuf>,
    /// Render a VolPath reference at this spp as two independent halves of N/2 spp, each
    /// cached next to the scene as `<scene>.volpath-<N/2>spp-seed<S>.exr` and reused while it
    /// matches.
    #[arg(long)]
    reference_spp: Option<u32>,
    /// Seed of the rendered reference's first half; the second has the next (default: the
    /// renders' first seed + 1000, so that the reference's samples are independent of theirs).
    #[arg(long)]
    reference_seed: Option<i32>,
    /// Independent renders per integrator and mode, at seeds S, S + 1, ... (S the first
    /// seed): every metric is reported as its mean with its standard error.
    #[arg(long, default_value_t = 1)]
    seeds: u32,
    /// The integrator that time to equal error and error ratios are measured against (one
    /// of --integrators; none if it is not among them).
    #[arg(long, default_value = REFERENCE)]
    baseline: String,
    /// Equal time: render each integrator progressively for this many seconds, counted from
    /// before its scene is built.
    #[arg(long)]
    time: Option<f64>,
    /// Equal spp: render each integrator to this many samples per pixel.
    #[arg(long)]
    spp: Option<u32>,
    /// Sampler seed of the renders, the first when there are several (default: the scene's).
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
    /// What the one listed integrator that prepares before rendering (radiancegraph's graph,
    /// guided's guide cache) prepared, as `nimbus render --precomputed` reads it: loaded when
    /// the file exists (it must be this scene's), else prepared once before the timed runs
    /// and saved there. Every run then loads it, so its time counts loading, not preparing,
    /// and the seeds vary the render, not the preparation (e.g. frames of an orbit from one
    /// graph).
    #[arg(long, value_name = "FILE", visible_aliases = ["graph-data", "guide-cache"])]
    precomputed: Option<PathBuf>,
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
    /// Seeds of the renders (each integrator and mode renders once per seed).
    pub seeds: Vec<i32>,
    /// The integrator the others are measured against, if it was compared.
    pub baseline: Option<String>,
    /// Checkpoints per doubling of spp.
    pub checkpoints_per_doubling: u32,
    /// `--time`
    pub time_budget: Option<f64>,
    /// `--spp`
    pub spp: Option<u32>,
    /// The reference and where it came from.
    pub reference: run::Reference,
    /// One run per seed, integrator and mode: seeds outermost, then integrators in the order
    /// given.
    pub runs: Vec<Run>,
    /// What the reference's own noise adds to each error (a reference in two halves).
    pub reference_noise: Option<nimbus::metrics::ErrorMetrics>,
    /// Standard error of the reference's mean (a reference in two halves).
    pub reference_mean_se: Option<f64>,
    /// Each integrator and mode over the seeds, in run order.
    pub summaries: Vec<stats::Summary>,
    /// Difference shown at full intensity in the error images, per mode.
    pub diff_scale: Vec<(Mode, f64)>,
    /// `--precomputed`: which integrator read it, and how it was had.
    pub precomputed: Option<Precomputed>,
}

/// `--precomputed`: the file one integrator's runs all loaded their preparation from.
pub struct Precomputed {
    /// The integrator that prepares.
    pub integrator: String,
    /// The file.
    pub file: PathBuf,
    /// Seconds preparing it took before the runs, when it was prepared now (`None`: it
    /// existed and was loaded).
    pub prepared_seconds: Option<f64>,
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

    /// Summaries of one mode.
    pub fn summaries_of(&self, mode: Mode) -> impl Iterator<Item = &stats::Summary> {
        self.summaries.iter().filter(move |s| s.mode == mode)
    }

    /// The first seed, whose runs' images are the outputs' headline images.
    pub fn first_seed(&self) -> i32 {
        self.seeds[0]
    }
}

/// The one integrator of `names` that prepares before rendering, for `--precomputed`.
fn preparing_integrator(desc: &nimbus::parser::SceneDescription, names: &[String]) -> Result<String> {
    let mut preparing = Vec::new();
    for name in names {
        let settings = nimbus::integrators::IntegratorSettings::from_entity(&desc.integrator, Some(name))
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        if settings.prepares() {
            preparing.push(name.as_str());
        }
    }
    match preparing[..] {
        [one] => Ok(one.to_string()),
        [] => anyhow::bail!(
            "--precomputed: none of {} prepares anything before rendering (such a file holds what a \
             method builds or trains before its renders: a graph, a guide cache)",
            names.join(", ")
        ),
        _ => anyhow::bail!(
            "--precomputed names one file, but {} each prepare their own: compare them in separate runs",
            preparing.join(" and ")
        ),
    }
}

fn validate(args: &CompareArgs) -> Result<Vec<String>> {
    if let Some(t) = args.time {
        anyhow::ensure!(t.is_finite() && t > 0.0, "--time must be a positive number of seconds");
    }
    anyhow::ensure!(args.spp != Some(0), "--spp must be at least 1");
    anyhow::ensure!(args.reference_spp != Some(0), "--reference-spp must be at least 1");
    anyhow::ensure!(args.reference_spp.is_none_or(|n| n >= 2), "--reference-spp must be at least 2 (two halves)");
    anyhow::ensure!((1..=1000).contains(&args.seeds), "--seeds must be 1 to 1000");
    anyhow::ensure!(
        args.reference.len() <= 2,
        "--reference takes one image or two independent halves, not {}",
        args.reference.len()
    );
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
    // Before any rendering: a --precomputed that no listed method (or more than one) reads.
    let preparing = args.precomputed.as_ref().map(|_| preparing_integrator(&desc, &names)).transpose()?;
    let seeds: Vec<i32> = (0..args.seeds as i32).map(|i| seed.wrapping_add(i)).collect();
    let stem = scene_stem(&args.scene);
    let out_dir = args.out.clone().unwrap_or_else(|| PathBuf::from(format!("compare-{stem}")));
    let reference = match args.reference_spp {
        None => run::Reference::from_files(&args.reference)?,
        Some(n) => {
            let ref_seed = args.reference_seed.unwrap_or(seed.wrapping_add(1000));
            let clash = seeds.iter().find(|s| **s == ref_seed || **s == ref_seed.wrapping_add(1));
            anyhow::ensure!(
                clash.is_none(),
                "the reference's halves (seeds {ref_seed} and {}) would share seed {} with the renders: pick another --reference-seed",
                ref_seed.wrapping_add(1),
                clash.copied().unwrap_or_default()
            );
            run::Reference::halves_cached_or_rendered(&args.scene, &stem, &desc, n, ref_seed, args.quiet, &say)?
        }
    };
    let (reference_noise, reference_mean_se) = match &reference.halves {
        Some([a, b]) => {
            (Some(nimbus::metrics::reference_noise(a, b)?), Some(nimbus::metrics::mean_standard_error(a, b)?))
        }
        None => (None, None),
    };
    if let Some(noise) = &reference_noise {
        say(format!(
            "reference: two halves; their noise adds {:.3e} to a relMSE against it (removed below)",
            noise.rel_mse
        ));
    } else {
        say("reference: one image; its own noise is not removed from the errors (give two halves to remove it)".into());
    }
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let precomputed = match (&args.precomputed, preparing) {
        (Some(file), Some(integrator)) => {
            let prepared_seconds = if file.exists() {
                say(format!("{integrator}: every run loads {}", file.display()));
                None
            } else {
                say(format!("{integrator}: preparing {} once, before the timed runs", file.display()));
                Some(run::prepare_file(&desc, &args.scene, &integrator, file, seed)?)
            };
            Some(Precomputed { integrator, file: file.clone(), prepared_seconds })
        }
        _ => None,
    };

    let mut runs = Vec::new();
    let mut warned = false;
    // Seeds outermost: a slow drift of the machine's speed falls on every method alike.
    for &seed in &seeds {
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
                    precomputed: precomputed.as_ref().filter(|p| p.integrator == *name).map(|p| p.file.as_path()),
                };
                let r = run::run_integrator(&setup)?;
                warned = true;
                let last = r.last();
                let removed =
                    last.noise_removed.map_or(String::new(), |m| format!(" ({:.4e} noise removed)", m.rel_mse));
                say(format!(
                    "{name} ({}, seed {seed}): {} spp in {:.2} s (setup {:.2} s), relMSE {:.4e}{removed}, MAE {:.4e}",
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
    }
    let baseline = names.iter().find(|n| **n == args.baseline).cloned();
    if baseline.is_none() && names.len() > 1 {
        say(format!("the baseline {} is not among the integrators: no time to equal error", args.baseline));
    }
    let summaries = stats::summarize(&runs, baseline.as_deref(), reference_mean_se);

    let mut diff_scale = Vec::new();
    for mode in [Mode::EqualTime, Mode::EqualSpp] {
        let best = runs.iter().filter(|r| r.mode == mode).map(|r| r.last().metrics.rmse).fold(f64::INFINITY, f64::min);
        if best.is_finite() {
            diff_scale.push((mode, (4.0 * best).max(1e-12)));
        }
    }
    let cmp = Comparison {
        scene: args.scene.clone(),
        seeds,
        baseline,
        checkpoints_per_doubling: args.checkpoints,
        time_budget: args.time,
        spp: args.spp,
        reference,
        runs,
        reference_noise,
        reference_mean_se,
        summaries,
        diff_scale,
        precomputed,
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

/// The HTML page's content: the headline mode's final images of the first seed, error against
/// time for every run of each mode that ran, the Markdown table's rows and its notes.
fn html_report(cmp: &Comparison) -> html::HtmlReport {
    let image = |i: &nimbus::imageio::Image| html::HtmlImage {
        width: i.width,
        height: i.height,
        rgb: i.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).collect(),
    };
    let relmse = |s: &stats::Summary| s.error_noise_removed.as_ref().unwrap_or(&s.error).get("relmse");
    let methods = cmp
        .runs_of(cmp.headline_mode())
        .filter(|r| r.seed == cmp.first_seed())
        .map(|r| {
            let sum = cmp.summaries.iter().find(|s| s.integrator == r.integrator && s.mode == r.mode);
            let caption = match sum {
                Some(s) => format!(
                    "relMSE {} over {} seed(s), {} spp, {} s",
                    report::pm(&relmse(s), |v| format!("{v:.3e}")),
                    s.seeds.len(),
                    s.spp.mean.round(),
                    crate::cli::plot::short(s.seconds.mean)
                ),
                None => String::new(),
            };
            html::HtmlMethod { name: r.integrator.clone(), caption, image: image(&r.image) }
        })
        .collect();
    let noise_removed = cmp.reference.halves.is_some();
    // Equal time, when it ran, is the headline mode: it comes first.
    let charts = [Mode::EqualTime, Mode::EqualSpp]
        .into_iter()
        .filter(|&mode| cmp.runs_of(mode).next().is_some())
        .map(|mode| html::HtmlChart {
            title: format!("relMSE vs time ({})", mode.label()),
            x_label: "time since scene build (s)".into(),
            y_label: if noise_removed { "relMSE, reference noise removed" } else { "relMSE" }.into(),
            series: cmp
                .runs_of(mode)
                .map(|r| html::HtmlSeries {
                    name: if r.seed == cmp.first_seed() {
                        r.integrator.clone()
                    } else {
                        format!("{} (seed {})", r.integrator, r.seed)
                    },
                    color: charts::css_color(cmp, &r.integrator),
                    // A log axis: a noise-removed error at or below zero has no place on it.
                    points: r
                        .checkpoints
                        .iter()
                        .map(|c| (c.seconds, stats::best(c).rel_mse))
                        .filter(|(_, e)| *e > 0.0)
                        .collect(),
                })
                .collect(),
        })
        .collect();
    let (headers, rows) = report::table(cmp);
    html::HtmlReport {
        title: format!("nimbus compare: {}", scene_stem(&cmp.scene)),
        notes: vec![
            format!(
                "Scene {}, reference {} ({}), {}.",
                cmp.scene.display(),
                cmp.reference.describe_paths(),
                report::reference_what(cmp),
                report::seeds_what(cmp)
            ),
            report::LEGEND.to_string(),
        ]
        .into_iter()
        .chain(report::precomputed_what(cmp))
        .collect(),
        reference: image(&cmp.reference.image),
        methods,
        charts,
        table: html::HtmlTable { headers, rows },
    }
}

/// File names of a run's final image and error image: `<integrator>.exr` for the headline
/// mode, `<integrator>-<N>spp.exr` for equal spp when both modes ran; `-seed<S>` added for
/// every seed but the first.
pub fn image_names(cmp: &Comparison, r: &Run) -> (String, String) {
    let mut base = if r.mode == cmp.headline_mode() {
        r.integrator.clone()
    } else {
        format!("{}-{}spp", r.integrator, cmp.spp.unwrap_or(0))
    };
    if r.seed != cmp.first_seed() {
        base = format!("{base}-seed{}", r.seed);
    }
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
        image.metadata.insert("nimbus:seed".into(), r.seed.to_string());
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
