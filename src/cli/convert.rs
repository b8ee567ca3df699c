//! `nimbus convert in.exr out.png`: change image format (linear EXR ↔ sRGB PNG), optionally
//! scaling by an exposure factor.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;

/// Arguments of `nimbus convert`.
#[derive(clap::Args)]
pub struct ConvertArgs {
    /// Input image (.exr or .png).
    input: PathBuf,
    /// Output image (.exr or .png).
    output: PathBuf,
    /// Multiply pixel values by this factor first.
    #[arg(long, default_value_t = 1.0)]
    scale: f32,
}

/// Converts the image.
pub fn run(args: &ConvertArgs) -> Result<ExitCode> {
    let mut img = nimbus::imageio::read_image(&args.input).map_err(anyhow::Error::msg)?;
    for p in &mut img.pixels {
        *p *= args.scale;
    }
    nimbus::imageio::write_image(&args.output, &img).map_err(anyhow::Error::msg)?;
    Ok(ExitCode::SUCCESS)
}
