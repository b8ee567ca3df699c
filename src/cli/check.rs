//! `nimbus check scene.pbrt`: parse, read every entity's settings, build the scene as
//! `render` builds it, check the method's constraints, print every error or a summary.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use nimbus::scene::BuildOptions;
use nimbus::setup::check_scene_full;

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

/// Runs the check; scene errors print as `file:line:col: error: message`, every one found.
pub fn run(args: &CheckArgs) -> Result<ExitCode> {
    let desc = match nimbus::parser::load_file(&args.scene) {
        Ok(d) => d,
        Err(e) => {
            super::render::scene_error(&e, &args.scene);
            return Ok(ExitCode::FAILURE);
        }
    };
    let opts =
        BuildOptions { scene_file: (args.scene.as_os_str() != "-").then(|| args.scene.clone()), ..Default::default() };
    let full = check_scene_full(&desc, &opts);
    // The first is where `render` stops; the others are what else the readers found.
    for e in &full.errors {
        super::render::scene_error(e, &args.scene);
    }
    let report = match full.summary {
        Some(r) if full.errors.is_empty() => r,
        _ => {
            if full.errors.len() > 1 {
                eprintln!("{} errors", full.errors.len());
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
