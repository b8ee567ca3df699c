//! `nimbus parity a.exr b.exr ref.exr`: the pbrt-v4 references' parity judgement.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;

/// Arguments of `nimbus parity`.
#[derive(clap::Args)]
pub struct ParityArgs {
    /// First render.
    a: PathBuf,
    /// Second render of the same scene with another seed, same spp.
    b: PathBuf,
    /// Reference image.
    reference: PathBuf,
    /// Also list the N 8×8 blocks that differ most (in units of their noise).
    #[arg(long, default_value_t = 0)]
    worst: usize,
}

/// Prints mean_rel (worst channel and per channel) and excess.
pub fn run(args: &ParityArgs) -> Result<ExitCode> {
    let read = |p: &PathBuf| nimbus::imageio::read_exr(p).map_err(anyhow::Error::msg);
    let (a, b, r) = (read(&args.a)?, read(&args.b)?, read(&args.reference)?);
    let p = nimbus::metrics::parity(&a, &b, &r).map_err(anyhow::Error::msg)?;
    println!(
        "mean_rel {:.4} (r {:.4} g {:.4} b {:.4})  excess {:.3}",
        p.worst_mean_rel(),
        p.mean_rel[0],
        p.mean_rel[1],
        p.mean_rel[2],
        p.excess
    );
    for b in nimbus::metrics::block_z_scores(&a, &b, &r)
        .iter()
        .take(args.worst)
    {
        println!(
            "block ({:3},{:3})  diff {:+.5}  z {:+.2}",
            b.bx * 8,
            b.by * 8,
            b.diff,
            b.z
        );
    }
    Ok(ExitCode::SUCCESS)
}
