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
    /// The scene is gray: estimate the reference's own (spectral) noise from its channel
    /// spread and report the excess without it.
    #[arg(long)]
    gray: bool,
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
    if args.gray {
        let share = nimbus::metrics::reference_noise_share(&a, &b, &r);
        println!("reference noise share {share:.3} (gray scene): excess without it {:.3}", p.excess - share);
    }
    let z = nimbus::metrics::block_z_scores(&a, &b, &r);
    let n = z.len().max(1) as f64;
    let rms = (z.iter().map(|b| b.z * b.z).sum::<f64>() / n).sqrt();
    let frac = |k: f64| z.iter().filter(|b| b.z.abs() > k).count() as f64 / n * 100.0;
    println!(
        "block z-scores: rms {rms:.2}, |z|>2 {:.1}%, |z|>3 {:.1}% (noise alone: ~1, 4.6%, 0.3%)",
        frac(2.0),
        frac(3.0)
    );
    for b in z.iter().take(args.worst) {
        println!("block ({:3},{:3})  diff {:+.5}  z {:+.2}", b.bx * 8, b.by * 8, b.diff, b.z);
    }
    Ok(ExitCode::SUCCESS)
}
