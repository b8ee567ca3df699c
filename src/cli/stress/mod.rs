//! `nimbus stress`: every integrator on a fixed matrix of small scenes (by default
//! `pbrt-scenes/stress/`, each varying one condition of a common base), at equal time, against
//! VolPath references cached beside the scenes as `compare` caches them. Each cell runs in its
//! own process and gets a verdict against volpath's cell on the same condition.
//!
//! - `cell.rs`: one cell, rendered by a child process and measured.
//! - `verdict.rs`: better / same / worse / biased / refused / failed.
//! - `report.rs`: `stress.csv` and `stress.md`.
//! - `heatmap.rs`: integrator × condition, coloured by the relMSE ratio to volpath.

mod cell;
mod heatmap;
mod report;
mod verdict;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use nimbus::integrators::{INTEGRATOR_NAMES, REFERENCE};

use cell::{Cell, CellSetup};
use verdict::Verdict;

/// Arguments of `nimbus stress`.
#[derive(clap::Args)]
pub struct StressArgs {
    /// Folder of the condition scenes (every `*.pbrt` in it, in name order).
    #[arg(long, default_value = "pbrt-scenes/stress")]
    scenes: PathBuf,
    /// Integrators, comma-separated (default: all of nimbus's; volpath is always run, as
    /// every verdict is relative to it).
    #[arg(long, value_delimiter = ',')]
    integrators: Vec<String>,
    /// Only the conditions whose names contain one of these, comma-separated.
    #[arg(long, value_delimiter = ',')]
    conditions: Vec<String>,
    /// Seconds per cell (equal time: a method's precomputation counts).
    #[arg(long, default_value_t = 2.0)]
    time: f64,
    /// Output folder.
    #[arg(long, default_value = "stress")]
    out: PathBuf,
    /// Sampler seed of the cells (the references use seed + 1).
    #[arg(long, default_value_t = 1)]
    seed: i32,
    /// Worker threads of each cell (default: all cores).
    #[arg(long)]
    nthreads: Option<usize>,
    /// Seconds after which a cell still running is stopped and counted as a hang (default:
    /// 20 × --time + 60).
    #[arg(long)]
    timeout: Option<f64>,
    /// Print only the verdict table.
    #[arg(long)]
    quiet: bool,
}

/// Everything a stress run produced.
pub struct Matrix {
    /// Seconds per cell.
    pub time: f64,
    /// Seed of the cells.
    pub seed: i32,
    /// Conditions, in order, with the first line of their scene's description.
    pub conditions: Vec<(String, String)>,
    /// Integrators, in order (volpath first).
    pub integrators: Vec<String>,
    /// Cells with their verdicts, condition-major.
    pub cells: Vec<(Cell, Verdict)>,
    /// Per condition: the reference's spp.
    pub reference_spp: Vec<u32>,
}

impl Matrix {
    /// The cell of `integrator` on `condition`.
    pub fn cell(&self, condition: &str, integrator: &str) -> Option<&(Cell, Verdict)> {
        self.cells.iter().find(|(c, _)| c.condition == condition && c.integrator == integrator)
    }
}

fn integrators(args: &StressArgs) -> Result<Vec<String>> {
    let mut names = vec![REFERENCE.to_string()];
    let asked: Vec<&str> = if args.integrators.is_empty() {
        INTEGRATOR_NAMES.to_vec()
    } else {
        args.integrators.iter().map(|s| s.trim()).filter(|s| !s.is_empty()).collect()
    };
    for name in asked {
        anyhow::ensure!(
            INTEGRATOR_NAMES.contains(&name),
            "unknown integrator \"{name}\" (nimbus has: {})",
            INTEGRATOR_NAMES.join(", ")
        );
        if !names.iter().any(|n| n == name) {
            names.push(name.to_string());
        }
    }
    Ok(names)
}

/// The condition scenes in `dir`, in name order, filtered by `only`.
fn scenes(dir: &Path, only: &[String]) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).with_context(|| format!("reading the stress scenes in {}", dir.display()))?;
    let mut paths = Vec::new();
    for e in entries {
        let path = e.with_context(|| format!("reading {}", dir.display()))?.path();
        let stem = super::compare::scene_stem(&path);
        let wanted = only.is_empty() || only.iter().any(|o| stem.contains(o.as_str()));
        if path.extension().is_some_and(|x| x == "pbrt") && wanted {
            paths.push(path);
        }
    }
    paths.sort();
    anyhow::ensure!(
        !paths.is_empty(),
        "{} has no condition scenes (*.pbrt){}",
        dir.display(),
        if only.is_empty() { "" } else { " matching --conditions" }
    );
    Ok(paths)
}

/// What the condition varies: its scene's first comment line after "condition <name>: ".
fn description(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let first = text.lines().next().unwrap_or("").trim_start_matches('#').trim();
    first.split_once(": ").map_or(first, |(_, d)| d).trim_end_matches('.').to_string()
}

/// Runs the matrix and writes its outputs.
pub fn run(args: &StressArgs) -> Result<ExitCode> {
    anyhow::ensure!(args.time.is_finite() && args.time > 0.0, "--time must be a positive number of seconds");
    if let Some(t) = args.timeout {
        anyhow::ensure!(t.is_finite() && t > 0.0, "--timeout must be a positive number of seconds");
    }
    if let Some(n) = args.nthreads {
        rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global().context("setting the thread count")?;
    }
    let names = integrators(args)?;
    let paths = scenes(&args.scenes, &args.conditions)?;
    let say = |s: String| {
        if !args.quiet {
            eprintln!("{s}");
        }
    };
    let timeout = args.timeout.unwrap_or(20.0 * args.time + 60.0);
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let mut matrix = Matrix {
        time: args.time,
        seed: args.seed,
        conditions: Vec::new(),
        integrators: names.clone(),
        cells: Vec::new(),
        reference_spp: Vec::new(),
    };
    for path in &paths {
        let stem = super::compare::scene_stem(path);
        let desc = nimbus::parser::load_file(path).map_err(|e| anyhow::anyhow!("{e}"))?;
        let spp =
            nimbus::samplers::settings::SamplerSettings::from_entity(&desc.sampler, desc.options.seed, &mut Vec::new())
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .pixel_samples;
        say(format!("{stem}: {}", description(path)));
        let reference = super::compare::run::Reference::cached_or_rendered(
            path,
            &stem,
            &desc,
            spp,
            args.seed.wrapping_add(1),
            args.quiet,
            &say,
        )?;
        let dir = args.out.join("cells").join(&stem);
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let mut row: Vec<Cell> = Vec::new();
        for name in &names {
            let setup = CellSetup {
                scene: path,
                condition: &stem,
                integrator: name,
                time: args.time,
                seed: args.seed,
                nthreads: args.nthreads,
                timeout,
                dir: &dir,
                reference: &reference.image,
            };
            row.push(cell::run_cell(&setup)?);
        }
        let baseline = row.iter().find(|c| c.integrator == REFERENCE).cloned();
        for c in row {
            let v = verdict::judge(&c, baseline.as_ref());
            say(format!("  {}", report::one_line(&c, &v, baseline.as_ref())));
            matrix.cells.push((c, v));
        }
        matrix.conditions.push((stem, description(path)));
        matrix.reference_spp.push(reference.spp.unwrap_or(spp));
    }
    let write = |name: &str, text: String| -> Result<()> {
        let path = args.out.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    write("stress.csv", report::csv(&matrix))?;
    write("stress.md", report::markdown(&matrix))?;
    heatmap::draw(&matrix, &args.out.join("heatmap"))?;
    print!("{}", report::verdict_table(&matrix));
    say(format!("wrote {}", args.out.display()));
    say(report::counts(&matrix));
    let failed = matrix.cells.iter().filter(|(_, v)| matches!(v, Verdict::Failed(_))).count();
    if failed > 0 {
        eprintln!("error: {failed} cell(s) failed (crash, hang, NaN/Inf or memory): see stress.md");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
