//! `nimbus check scene.pbrt`: parse, read every entity's settings, print a summary.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use nimbus::setup::check_scene;

/// Arguments of `nimbus check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// Scene file (`.pbrt`, `.pbrt.gz`, or `-` for standard input).
    scene: PathBuf,
    /// Treat warnings (unused parameters, unsupported features with stand-ins) as errors,
    /// as pbrt-v4 does.
    #[arg(long)]
    strict: bool,
}

fn counts(m: &BTreeMap<String, usize>) -> String {
    let total: usize = m.values().sum();
    if total == 0 {
        return "0".into();
    }
    let parts: Vec<String> = m.iter().map(|(k, v)| format!("{k} {v}")).collect();
    format!("{total} ({})", parts.join(", "))
}

/// Runs the check; scene errors print as `file:line:col: error: message`.
pub fn run(args: &CheckArgs) -> Result<ExitCode> {
    let report = nimbus::parser::load_file(&args.scene).and_then(|scene| check_scene(&scene));
    let report = match report {
        Ok(r) => r,
        Err(e) => {
            match &e.loc {
                Some(loc) => eprintln!("{loc}: error: {}", e.message),
                None => eprintln!("error: {}", e.message),
            }
            return Ok(ExitCode::FAILURE);
        }
    };
    for w in &report.warnings {
        match &w.loc {
            Some(loc) => eprintln!("{loc}: warning: {}", w.message),
            None => eprintln!("warning: {}", w.message),
        }
    }
    println!(
        "scene       {} ({} file{})",
        args.scene.display(),
        report.files.len(),
        if report.files.len() == 1 { "" } else { "s" }
    );
    println!("camera      {}", report.camera);
    println!("film        {}x{} -> {}", report.resolution[0], report.resolution[1], report.filename);
    println!("sampler     {}, {} spp", report.sampler, report.spp);
    println!("integrator  {} {}", report.integrator, report.integrator_params.join(", "));
    println!("shapes      {}, {} triangles, {} instances", counts(&report.shapes), report.triangles, report.instances);
    println!("lights      {}", counts(&report.lights));
    println!("media       {}", counts(&report.media));
    println!("materials   {}", counts(&report.materials));
    println!("textures    {}", counts(&report.textures));
    println!("warnings    {}", report.warnings.len());
    if args.strict && !report.warnings.is_empty() {
        eprintln!("error: {} warning(s) and --strict was given", report.warnings.len());
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
