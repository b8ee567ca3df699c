//! Subcommands of the `nimbus` binary.

mod bench;
mod check;
mod cluster;
mod compare;
mod convert;
mod diff;
mod graph;
mod memory;
mod merge;
mod parity;
mod plot;
mod render;
mod scene_hash;
mod stress;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// nimbus renders participating media (clouds, smoke, fog, milk, wax) from pbrt-v4 scenes.
#[derive(Parser)]
#[command(name = "nimbus", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Read a scene and report what it contains, or what is wrong with it and where.
    Check(check::CheckArgs),
    /// Render a scene to an image.
    Render(render::RenderArgs),
    /// Time renders of the parity scenes against pbrt-v4's times (speed as a ratio).
    Bench(bench::BenchArgs),
    /// Convert an image between EXR (linear float) and PNG (8-bit sRGB).
    Convert(convert::ConvertArgs),
    /// Render a scene with several integrators at equal time and/or equal spp and measure each
    /// against a VolPath reference: tables, charts, final and error images.
    Compare(compare::CompareArgs),
    /// Compare an image with a reference: MSE, relMSE, MAE, MPE/MNE, means, error image.
    Diff(diff::DiffArgs),
    /// The radiance-graph method's precomputation: `graph build` (the thesis's graph_maker).
    Graph(graph::GraphArgs),
    /// Judge two renders (different seeds) against a reference as the pbrt-v4 parity suite
    /// does: relative mean difference and block-noise excess.
    Parity(parity::ParityArgs),
    /// Render every integrator on a matrix of small scenes that each vary one condition, at
    /// equal time against VolPath references: where each method is better, the same, worse,
    /// biased or refuses (stress.csv, stress.md, a heat map).
    Stress(stress::StressArgs),
    /// Split a render into a Slurm job array (tiles, seed batches or camera frames), with a
    /// precomputation job it depends on for methods that precompute; `--submit` submits it.
    Cluster(cluster::ClusterArgs),
    /// Assemble the parts of a split render: tiles by their pixel bounds, seed batches by an
    /// spp-weighted average, checked against each other's metadata.
    Merge(merge::MergeArgs),
}

/// Parses the command line and runs the subcommand; errors print to stderr and give exit
/// code 1.
pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(args) => check::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Parity(args) => parity::run(&args),
        Command::Diff(args) => diff::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Graph(args) => graph::run(&args),
        Command::Stress(args) => stress::run(&args),
        Command::Cluster(args) => cluster::run(&args),
        Command::Merge(args) => merge::run(&args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
