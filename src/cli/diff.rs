//! `nimbus diff test.exr ref.exr`: error metrics and an error image.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};

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
    /// Restrict the metrics to pixels x0..x1, y0..y1 (exclusive ends).
    #[arg(long, num_args = 4, value_names = ["X0", "X1", "Y0", "Y1"])]
    region: Option<Vec<usize>>,
    /// Print both images' values at these pixels (x,y).
    #[arg(long, value_parser = parse_pixel)]
    probe: Vec<(usize, usize)>,
}

fn parse_pixel(s: &str) -> Result<(usize, usize), String> {
    let (x, y) = s.split_once(',').ok_or("expected x,y")?;
    Ok((x.trim().parse().map_err(|_| "bad x")?, y.trim().parse().map_err(|_| "bad y")?))
}

/// Prints the metrics; writes the error image if asked.
pub fn run(args: &DiffArgs) -> Result<ExitCode> {
    let read = |p: &PathBuf, what: &str| {
        nimbus::imageio::read_image(p).map_err(anyhow::Error::msg).with_context(|| format!("cannot read the {what}"))
    };
    let (mut t, mut r) = (read(&args.test, "test image")?, read(&args.reference, "reference")?);
    anyhow::ensure!(
        (t.width, t.height) == (r.width, r.height),
        "the images differ in size: {} is {}x{}, the reference {} is {}x{}",
        args.test.display(),
        t.width,
        t.height,
        args.reference.display(),
        r.width,
        r.height
    );
    if let Some(reg) = &args.region {
        let crop = |img: &nimbus::imageio::Image| -> Result<nimbus::imageio::Image> {
            let (x0, x1, y0, y1) = (reg[0], reg[1].min(img.width), reg[2], reg[3].min(img.height));
            anyhow::ensure!(x0 < x1 && y0 < y1, "--region selects no pixels");
            let mut out = nimbus::imageio::Image::new(x1 - x0, y1 - y0);
            for y in y0..y1 {
                for x in x0..x1 {
                    out.pixels[(y - y0) * (x1 - x0) + (x - x0)] = img.get(x, y);
                }
            }
            Ok(out)
        };
        t = crop(&t)?;
        r = crop(&r)?;
    }
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
