//! `nimbus graph build`: the radiance-graph thesis's `graph_maker`, mirrored. One graph file
//! per entry of `lightingCalculator.bounces`, named as graph_maker names them
//! (`<cfg>_d<depth>.txt`, depth = bounces + 1, though nimbus's files are binary), and
//! `<cfg>_stats.json` with the thesis's statistics and nimbus's own.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;
use clap::{Args, Subcommand};
use serde_json::json;

use nimbus::integrators::radiancegraph::{self, config::GraphConfig, file, volume::Volume};
use nimbus::scene::BuildOptions;

/// `nimbus graph ...`
#[derive(Args)]
pub struct GraphArgs {
    #[command(subcommand)]
    command: GraphCommand,
}

#[derive(Subcommand)]
enum GraphCommand {
    /// Build the radiance graphs of a scene (the thesis's graph_maker).
    Build(BuildArgs),
}

#[derive(Args)]
struct BuildArgs {
    /// Scene file.
    scene: PathBuf,
    /// Config file (default: the scene's name with `.json`; if absent, a graph sized for the
    /// medium and the camera from a pilot of light paths).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Absolute node radius, overriding the config's.
    #[arg(long)]
    node_radius: Option<f32>,
    /// No progress or summary on standard output.
    #[arg(long)]
    quiet: bool,
    /// Directory for the graph and stats files (default: beside the config).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Random seed (default: the scene's sampler seed).
    #[arg(long)]
    seed: Option<i32>,
    /// Print time and peak bytes per stage, and bytes per node and per edge at the build's peak.
    #[arg(long)]
    stats: bool,
}

/// Runs `nimbus graph`.
pub fn run(args: &GraphArgs) -> Result<ExitCode> {
    match &args.command {
        GraphCommand::Build(b) => build(b),
    }
}

fn fail(scene: &Path, message: impl std::fmt::Display) -> Result<ExitCode> {
    eprintln!("{}: error: {message}", scene.display());
    Ok(ExitCode::FAILURE)
}

fn build(args: &BuildArgs) -> Result<ExitCode> {
    let t0 = Instant::now();
    let desc = match nimbus::parser::load_file(&args.scene) {
        Ok(d) => d,
        Err(e) => {
            match &e.loc {
                Some(loc) => eprintln!("{loc}: error: {}", e.message),
                None => eprintln!("error: {}", e.message),
            }
            return Ok(ExitCode::FAILURE);
        }
    };
    let opts = BuildOptions { seed: args.seed, ..Default::default() };
    let scene = match nimbus::setup::build(&desc, &opts) {
        Ok(s) => s.scene,
        Err(e) => return fail(&args.scene, e.message),
    };
    // graph_maker: the config defaults to the scene's name with `.json`; outputs are named
    // after the config.
    let config_path = args.config.clone().unwrap_or_else(|| args.scene.with_extension("json"));
    if let Some(r) = args.node_radius
        && !(r > 0.0 && r.is_finite())
    {
        return fail(&args.scene, format!("--node-radius must be positive (got {r})"));
    }
    let volume = match Volume::new(&scene) {
        Ok(v) => v,
        Err(e) => return fail(&args.scene, e),
    };
    let seed = scene.sampler.seed as u64;
    let (config, sizing) = if config_path.exists() || args.config.is_some() {
        match GraphConfig::from_file(&config_path) {
            Ok(c) => (c, None),
            Err(e) => {
                eprintln!("error: {e}");
                return Ok(ExitCode::FAILURE);
            }
        }
    } else {
        // No config: a graph sized for this medium and camera, not the thesis's one size.
        let max_depth = match radiancegraph::scene_max_depth(&desc.integrator) {
            Ok(d) => d,
            Err(e) => return fail(&args.scene, e.message),
        };
        let sizing = radiancegraph::sizing::size(&volume, seed, max_depth);
        if !args.quiet {
            println!("{}: {}", config_path.display(), sizing.explain());
        }
        (sizing.config.clone(), Some(sizing))
    };
    let node_radius = args.node_radius.or(sizing.as_ref().map(|s| s.radius));
    let (graphs, stats) = match radiancegraph::build(&scene, &config, node_radius, seed) {
        Ok(g) => g,
        Err(e) => return fail(&args.scene, e),
    };
    let stem = config_path.file_stem().map_or("graph".into(), |s| s.to_string_lossy().into_owned());
    let dir = match &args.out {
        Some(d) => d.clone(),
        None => config_path.parent().map_or(PathBuf::from("."), Path::to_path_buf),
    };
    std::fs::create_dir_all(&dir).map_err(|e| anyhow::anyhow!("{}: cannot create: {e}", dir.display()))?;
    let (scene_hash, config_hash) = (file::scene_hash(&volume), file::config_hash(&config));
    let mut written = Vec::new();
    for (i, g) in graphs.graphs.iter().enumerate() {
        let path = dir.join(format!("{stem}_d{}.txt", g.bounces_done + 1));
        let f = graphs.file(i, scene_hash, config_hash, stats.node_radius);
        if let Err(e) = f.write(&path) {
            eprintln!("error: {e}");
            return Ok(ExitCode::FAILURE);
        }
        if g.bounces_done != g.bounces && !args.quiet {
            println!(
                "numerical limits reached with depth {}, depth {} not possible",
                g.bounces_done + 1,
                g.bounces + 1
            );
        }
        written.push(path);
    }
    let seconds = t0.elapsed().as_secs_f64();
    let edges = stats.edges as f64;
    let mut doc = json!({
        "amounts": { "edges": stats.edges, "vertices": stats.vertices },
        "duration": { "seconds": seconds.round() as u64, "formatted": format_time(seconds) },
        "edges": {
            "more_than_once": stats.edges_more_than_once,
            "more_than_once_ratio": if edges > 0.0 { stats.edges_more_than_once as f64 / edges } else { 0.0 },
        },
        "in_node_path_length": { "avg": stats.in_node_path_length.0, "std": stats.in_node_path_length.1 },
        "sizes": { "node_radius": stats.node_radius, "scene_radius": stats.scene_radius },
        "nimbus": {
            "seconds": seconds,
            "light_paths": stats.paths.0,
            "reinforcement_paths": stats.paths.1,
            "reinforcement_rounds": stats.paths.2,
            "stages": stats.stages.iter().map(|s| json!({
                "name": s.name, "seconds": s.seconds, "peak_bytes": s.peak_bytes,
            })).collect::<Vec<_>>(),
            "build_peak_bytes_per_node": stats.build_peak_bytes_per_node(),
            "build_peak_bytes_per_edge": stats.build_peak_bytes_per_edge(),
        },
    });
    if let Some(s) = &sizing {
        doc["nimbus"]["sizing"] = json!({
            "radius_from": s.radius_from,
            "free_path": s.free_path,
            "pixel_footprint": s.footprint,
            "occupied_volume": s.occupied_volume,
            "points_per_path": s.points_per_path,
            "iterations_per_step": s.config.graph_builder.iterations_per_step,
            "expected_nodes": s.expected_nodes(),
            "radius_per_free_path": s.radius / s.free_path,
            "coarse": s.coarse(),
        });
    }
    if let Some((avg, std)) = stats.render_search_range {
        doc["render_search_range"] = json!({ "avg": avg, "std": std });
    }
    let stats_path = dir.join(format!("{stem}_stats.json"));
    std::fs::write(&stats_path, serde_json::to_string_pretty(&doc)? + "\n")
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", stats_path.display()))?;
    if !args.quiet {
        println!(
            "{} nodes, {} edges in {:.2} s ({:.1} B/node and {:.1} B/edge at the build's peak)",
            stats.vertices,
            stats.edges,
            seconds,
            stats.build_peak_bytes_per_node(),
            stats.build_peak_bytes_per_edge()
        );
        for p in &written {
            println!("wrote {}", p.display());
        }
        println!("wrote {}", stats_path.display());
    }
    if args.stats {
        println!("paths       {} light, {} reinforcement ({} rounds)", stats.paths.0, stats.paths.1, stats.paths.2);
        for s in &stats.stages {
            println!("stage       {:<14} {:>8.3} s  peak {:>8.1} MB", s.name, s.seconds, s.peak_bytes as f64 / 1e6);
        }
        println!(
            "memory      {:.1} B/node, {:.1} B/edge at the build's peak ({} nodes, {} edges)",
            stats.build_peak_bytes_per_node(),
            stats.build_peak_bytes_per_edge(),
            stats.vertices,
            stats.edges
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The thesis's `FormatTime`: "13m 30s", "2h 19m 39s", "29s".
fn format_time(seconds: f64) -> String {
    let s = seconds.round() as u64;
    let (h, m, s) = (s / 3600, s / 60 % 60, s % 60);
    if h > 0 {
        format!("{h}h {m}m {s}s")
    } else if m > 0 {
        format!("{m}m {s}s")
    } else {
        format!("{s}s")
    }
}
