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
    /// Print both images' values at these pixels (x,y).
    #[arg(long, value_parser = parse_pixel)]
    probe: Vec<(usize, usize)>,
}

fn parse_pixel(s: &str) -> Result<(usize, usize), String> {
    let (x, y) = s.split_once(',').ok_or("expected x,y")?;
    Ok((
        x.trim().parse().map_err(|_| "bad x")?,
        y.trim().parse().map_err(|_| "bad y")?,
    ))
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
    for &(x, y) in &args.probe {
        if x < t.width && y < t.height {
            let (a, b) = (t.get(x, y), r.get(x, y));
            println!(
                "pixel ({x},{y})  test {:.5} {:.5} {:.5}  reference {:.5} {:.5} {:.5}",
                a.x, a.y, a.z, b.x, b.y, b.z
            );
        }
    }
    if let Some(out) = &args.out {
        let scale = args.scale.unwrap_or((4.0 * m.rmse) as f32).max(1e-12);
        let img = nimbus::metrics::difference_image(&t, &r, scale);
        nimbus::imageio::write_image(out, &img).map_err(anyhow::Error::msg)?;
    }
    Ok(ExitCode::SUCCESS)
}
