//! `nimbus diff test.exr ref.exr`: error metrics and an error image.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;

/// Arguments of `nimbus diff`.
#[derive(clap::Args)]
pub struct DiffArgs {
    /// Image to judge (.exr).
    test: PathBuf,
    /// Reference (.exr).
    reference: PathBuf,
    /// Write an error image: green where the test is brighter, red where darker.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Difference shown at full intensity in the error image (default: 4 × RMSE).
    #[arg(long)]
    scale: Option<f32>,
}

/// Prints the metrics; writes the error image if asked.
pub fn run(args: &DiffArgs) -> Result<ExitCode> {
    let read = |p: &PathBuf| nimbus::imageio::read_image(p).map_err(anyhow::Error::msg);
    let (t, r) = (read(&args.test)?, read(&args.reference)?);
    let m = nimbus::metrics::error_metrics(&t, &r).map_err(anyhow::Error::msg)?;
    println!("MSE      {:.6e}", m.mse);
    println!("RMSE     {:.6e}", m.rmse);
    println!("relMSE   {:.6e}", m.rel_mse);
    println!("MAE      {:.6e}", m.mae);
    println!("MPE      {:.6e}", m.mpe);
    println!("MNE      {:.6e}", m.mne);
    println!(
        "mean     test {:.6} reference {:.6} ({:+.3}%)",
        m.mean_test,
        m.mean_reference,
        100.0 * (m.mean_test / m.mean_reference - 1.0)
    );
    if let Some(out) = &args.out {
        let scale = args.scale.unwrap_or((4.0 * m.rmse) as f32).max(1e-12);
        let img = nimbus::metrics::difference_image(&t, &r, scale);
        nimbus::imageio::write_image(out, &img).map_err(anyhow::Error::msg)?;
    }
    Ok(ExitCode::SUCCESS)
}
