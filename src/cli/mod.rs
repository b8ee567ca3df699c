//! Subcommands of the `nimbus` binary.

mod check;

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
}

/// Parses the command line and runs the subcommand; errors print to stderr and give exit
/// code 1.
pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(args) => check::run(&args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
