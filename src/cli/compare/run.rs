//! The reference image and one integrator's timed render with checkpoints.

use nimbus::integrators::REFERENCE;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use nimbus::imageio::Image;
use nimbus::metrics::{ErrorMetrics, error_metrics};
use nimbus::parser::SceneDescription;
use nimbus::render::{RenderOptions, render, render_with_passes};
use nimbus::scene::{BuildOptions, Scene};
use nimbus::setup::unused_parameters;

/// Equal time or equal spp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// `--time T`: every integrator gets the same wall time, setup included.
    EqualTime,
    /// `--spp N`: every integrator renders N samples per pixel.
    EqualSpp,
}

impl Mode {
    /// Name in the outputs.
    pub fn label(self) -> &'static str {
        match self {
            Mode::EqualTime => "equal-time",
            Mode::EqualSpp => "equal-spp",
        }
    }
}

/// The error of a render against the reference at one point of its progress.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// Seconds since before the integrator's scene was built (time spent measuring the error
    /// is excluded).
    pub seconds: f64,
    /// Samples per pixel so far.
    pub spp: u32,
    /// Error against the reference.
    pub metrics: ErrorMetrics,
    /// Error with the reference's own noise removed, when the reference has two halves.
    pub noise_removed: Option<ErrorMetrics>,
    /// Whether this is the render's end.
    pub last: bool,
}

/// One integrator's render in one mode.
pub struct Run {
    /// Integrator name.
    pub integrator: String,
    /// Equal time or equal spp.
    pub mode: Mode,
    /// Sampler seed.
    pub seed: i32,
    /// Seconds to build the scene and create the integrator.
    pub setup_seconds: f64,
    /// Checkpoints in order; the last one is the final image.
    pub checkpoints: Vec<Checkpoint>,
    /// The final image.
    pub image: Image,
}

impl Run {
    /// The final checkpoint.
    pub fn last(&self) -> &Checkpoint {
        self.checkpoints.last().expect("a render has at least one pass")
    }
}

/// Where the reference came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReferenceSource {
    /// `--reference`
    File,
    /// `--reference-spp`, found in the cache.
    Cached,
    /// `--reference-spp`, rendered now.
    Rendered,
}

impl ReferenceSource {
    /// Name in the outputs.
    pub fn label(&self) -> &'static str {
        match self {
            ReferenceSource::File => "file",
            ReferenceSource::Cached => "cached",
            ReferenceSource::Rendered => "rendered",
        }
    }
}

/// The reference image: one image, or the mean of two independent halves (whose difference
/// measures its own noise).
pub struct Reference {
    /// Pixels (the halves' mean when there are two).
    pub image: Image,
    /// The two independent halves, when the reference came as two.
    pub halves: Option<[Image; 2]>,
    /// Its file or the halves' files.
    pub paths: Vec<PathBuf>,
    /// How it was obtained (the first half's way when there are two).
    pub source: ReferenceSource,
    /// Its spp (both halves together), when known (from the metadata nimbus writes).
    pub spp: Option<u32>,
    /// The seeds of its renders, when known.
    pub seeds: Vec<i32>,
}

fn scene_error(e: nimbus::parser::Error) -> anyhow::Error {
    anyhow::anyhow!("{e}")
}

impl Reference {
    /// `--reference path[,path]`: any EXR (or PNG), or two independent halves of one; its
    /// size is checked against the film later.
    pub fn from_files(paths: &[PathBuf]) -> Result<Reference> {
        anyhow::ensure!(
            (1..=2).contains(&paths.len()),
            "--reference takes one image or two independent halves, not {}",
            paths.len()
        );
        let mut images = Vec::new();
        for path in paths {
            let image = nimbus::imageio::read_image(path)
                .map_err(anyhow::Error::msg)
                .with_context(|| format!("reading the reference {}", path.display()))?;
            images.push(image);
        }
        let meta = |i: &Image, k: &str| i.metadata.get(k).and_then(|s| s.parse::<i64>().ok());
        let spp = images.iter().map(|i| meta(i, "nimbus:spp").map(|s| s as u32)).sum::<Option<u32>>();
        let seeds = images.iter().filter_map(|i| meta(i, "nimbus:seed").map(|s| s as i32)).collect();
        let source = ReferenceSource::File;
        if let [a, b] = &images[..] {
            anyhow::ensure!(
                (a.width, a.height) == (b.width, b.height),
                "the reference halves differ in size: {} is {}x{}, {} {}x{}",
                paths[0].display(),
                a.width,
                a.height,
                paths[1].display(),
                b.width,
                b.height
            );
            anyhow::ensure!(
                a.pixels != b.pixels,
                "the reference halves {} and {} are the same image: they must be independent renders",
                paths[0].display(),
                paths[1].display()
            );
        }
        Ok(Reference::of(images, paths.to_vec(), source, spp, seeds))
    }

    fn of(
        mut images: Vec<Image>,
        paths: Vec<PathBuf>,
        source: ReferenceSource,
        spp: Option<u32>,
        seeds: Vec<i32>,
    ) -> Reference {
        if images.len() == 2 {
            let b = images.pop().expect("two images");
            let a = images.pop().expect("two images");
            let image = nimbus::metrics::average(&a, &b);
            Reference { image, halves: Some([a, b]), paths, source, spp, seeds }
        } else {
            let image = images.pop().expect("one image");
            Reference { image, halves: None, paths, source, spp, seeds }
        }
    }

    /// The file(s), for messages.
    pub fn describe_paths(&self) -> String {
        self.paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(" + ")
    }

    /// `--reference-spp n`: two independent VolPath halves of ⌈n/2⌉ spp each, at seeds
    /// `seed` and `seed + 1`, each cached or rendered as [`Reference::cached_or_rendered`].
    pub fn halves_cached_or_rendered(
        scene_path: &Path,
        stem: &str,
        desc: &SceneDescription,
        spp: u32,
        seed: i32,
        quiet: bool,
        say: &dyn Fn(String),
    ) -> Result<Reference> {
        let half = spp.div_ceil(2);
        let a = Reference::cached_or_rendered(scene_path, stem, desc, half, seed, quiet, say)?;
        let b = Reference::cached_or_rendered(scene_path, stem, desc, half, seed.wrapping_add(1), quiet, say)?;
        let source = if a.source == ReferenceSource::Rendered || b.source == ReferenceSource::Rendered {
            ReferenceSource::Rendered
        } else {
            ReferenceSource::Cached
        };
        let paths = [a.paths, b.paths].concat();
        let seeds = [a.seeds, b.seeds].concat();
        Ok(Reference::of(vec![a.image, b.image], paths, source, Some(2 * half), seeds))
    }

    /// `--reference-spp n`: `<scene dir>/<stem>.volpath-<n>spp-seed<seed>.exr` if it is there
    /// and its metadata (integrator, spp, seed, scene-file hash) and size match; otherwise a
    /// VolPath render, written there.
    pub fn cached_or_rendered(
        scene_path: &Path,
        stem: &str,
        desc: &SceneDescription,
        spp: u32,
        seed: i32,
        quiet: bool,
        say: &dyn Fn(String),
    ) -> Result<Reference> {
        let dir = scene_path.parent().unwrap_or(Path::new("."));
        let path = dir.join(format!("{stem}.{REFERENCE}-{spp}spp-seed{seed}.exr"));
        let hash = crate::cli::scene_hash::of_file(scene_path)?;
        let opts =
            BuildOptions { integrator: Some(REFERENCE.into()), spp: Some(spp), seed: Some(seed), ..Default::default() };
        let setup = nimbus::setup::build(desc, &opts).map_err(scene_error)?;
        let scene = &setup.scene;
        let (w, h) = film_size(scene);
        if path.exists() {
            let why_not = match nimbus::imageio::read_exr(&path) {
                Err(e) => Some(e.to_string()),
                Ok(image) => {
                    let meta = |k: &str| image.metadata.get(k).map(String::as_str);
                    let expected = [
                        ("nimbus:integrator", REFERENCE.to_string()),
                        ("nimbus:spp", spp.to_string()),
                        ("nimbus:seed", seed.to_string()),
                        ("nimbus:scene-hash", hash.clone()),
                    ];
                    let mismatch = expected.iter().find(|(k, v)| meta(k) != Some(v.as_str()));
                    match mismatch {
                        Some((k, v)) => Some(format!("its {k} is {:?}, not \"{v}\"", meta(k).unwrap_or("missing"))),
                        None if (image.width, image.height) != (w, h) => {
                            Some(format!("it is {}x{}, the film {w}x{h}", image.width, image.height))
                        }
                        None => {
                            say(format!("reference: {} (cached)", path.display()));
                            let source = ReferenceSource::Cached;
                            return Ok(Reference::of(vec![image], vec![path], source, Some(spp), vec![seed]));
                        }
                    }
                }
            };
            say(format!("reference: not reusing {}: {}", path.display(), why_not.unwrap_or_default()));
        }
        say(format!("reference: rendering {REFERENCE} at {spp} spp, seed {seed} -> {}", path.display()));
        let integrator = setup.prepare().map_err(anyhow::Error::msg)?.integrator;
        let result = render(scene, integrator.as_ref(), &RenderOptions { time_budget: None, quiet });
        let mut image = result.image;
        image.metadata.insert("nimbus:integrator".into(), REFERENCE.into());
        image.metadata.insert("nimbus:spp".into(), result.spp.to_string());
        image.metadata.insert("nimbus:seed".into(), seed.to_string());
        image.metadata.insert("nimbus:time".into(), format!("{:.3}", result.seconds));
        image.metadata.insert("nimbus:scene".into(), scene_path.display().to_string());
        image.metadata.insert("nimbus:scene-hash".into(), hash);
        nimbus::imageio::write_image(&path, &image)
            .map_err(anyhow::Error::msg)
            .context("caching the reference next to the scene")?;
        say(format!("reference: {} spp in {:.2} s", result.spp, result.seconds));
        Ok(Reference::of(vec![image], vec![path], ReferenceSource::Rendered, Some(spp), vec![seed]))
    }
}

fn film_size(scene: &Scene) -> (usize, usize) {
    let b = scene.pixel_bounds;
    ((b[2] - b[0]) as usize, (b[3] - b[1]) as usize)
}

/// Sample counts at which checkpoints are taken: `per_doubling` per doubling of the sample
/// count, 2^(j / per_doubling) rounded, from 1 up to `max`.
pub fn checkpoint_spp(per_doubling: u32, max: u32) -> Vec<u32> {
    let mut v: Vec<u32> = Vec::new();
    for j in 0.. {
        let s = 2f64.powf(j as f64 / per_doubling.max(1) as f64).round();
        if s > max as f64 {
            break;
        }
        if v.last() != Some(&(s as u32)) {
            v.push(s as u32);
        }
    }
    v
}

/// Highest spp of the checkpoint schedule in an equal-time run (the last pass, where the
/// budget runs out, is a checkpoint too).
const MAX_CHECKPOINT_SPP: u32 = 1 << 24;

/// What one integrator's render needs.
pub struct RunSetup<'a> {
    /// The parsed scene.
    pub desc: &'a SceneDescription,
    /// Its file (methods that precompute read their config beside it).
    pub scene_file: &'a std::path::Path,
    /// Integrator name.
    pub integrator: &'a str,
    /// Sampler seed.
    pub seed: i32,
    /// Equal time or equal spp.
    pub mode: Mode,
    /// `--time`
    pub time: Option<f64>,
    /// `--spp`
    pub spp: Option<u32>,
    /// Checkpoints per doubling of spp.
    pub per_doubling: u32,
    /// The reference.
    pub reference: &'a Reference,
    /// Print the scene's warnings.
    pub print_warnings: bool,
    /// `--precomputed`, for the integrator that reads it: its preparation is loaded from there.
    pub precomputed: Option<&'a Path>,
}

/// `--precomputed FILE` for `integrator` when the file does not exist yet: the method
/// prepares (trains, builds its graph) once at `seed` and saves it there, before any timed
/// run, so that every run then loads the same file in the same time. The seconds it took.
pub fn prepare_file(
    desc: &SceneDescription,
    scene_file: &Path,
    integrator: &str,
    file: &Path,
    seed: i32,
) -> Result<f64> {
    if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let opts = BuildOptions {
        integrator: Some(integrator.into()),
        scene_file: Some(scene_file.to_path_buf()),
        seed: Some(seed),
        precomputed: Some(file.to_path_buf()),
        ..Default::default()
    };
    let setup = nimbus::setup::build(desc, &opts).map_err(scene_error)?;
    let prepared = setup.prepare().map_err(anyhow::Error::msg)?;
    anyhow::ensure!(file.exists(), "{integrator} prepared, but wrote no {}", file.display());
    Ok(prepared.seconds)
}

/// Builds the scene for the integrator and renders it, measuring the error against the
/// reference after every pass that ends on a checkpoint's spp and after the last pass. The
/// method's preparation (training, a graph build) and rendering are counted, as `nimbus
/// render --time` counts them (`registry::Prepared::remaining`); building the scene, the same
/// for every method, and measuring the error are not.
pub fn run_integrator(s: &RunSetup<'_>) -> Result<Run> {
    let spp = match s.mode {
        Mode::EqualTime => None,
        Mode::EqualSpp => s.spp,
    };
    let opts = BuildOptions {
        integrator: Some(s.integrator.into()),
        scene_file: Some(s.scene_file.to_path_buf()),
        spp,
        seed: Some(s.seed),
        precomputed: s.precomputed.map(Path::to_path_buf),
        ..Default::default()
    };
    let setup = nimbus::setup::build(s.desc, &opts).map_err(scene_error)?;
    let prepared = setup.prepare().map_err(anyhow::Error::msg)?;
    let scene = &setup.scene;
    let (integrator, setup_seconds) = (&prepared.integrator, prepared.seconds);
    let (w, h) = film_size(scene);
    let reference = &s.reference.image;
    anyhow::ensure!(
        (reference.width, reference.height) == (w, h),
        "the reference {} is {}x{} but the scene's film renders {w}x{h} pixels",
        s.reference.describe_paths(),
        reference.width,
        reference.height
    );
    if s.print_warnings {
        let mut warnings = scene.warnings.clone();
        warnings.extend(unused_parameters(s.desc));
        for w in warnings {
            match &w.loc {
                Some(loc) => eprintln!("{loc}: warning: {}", w.message),
                None => eprintln!("warning: {}", w.message),
            }
        }
    }
    let (budget, max_spp) = match s.mode {
        Mode::EqualTime => {
            let t = s.time.unwrap_or(0.0);
            (prepared.remaining(Some(t)), MAX_CHECKPOINT_SPP)
        }
        Mode::EqualSpp => (None, scene.sampler.pixel_samples),
    };
    let ends = checkpoint_spp(s.per_doubling, max_spp);
    let mut checkpoints = Vec::new();
    let result = render_with_passes(
        scene,
        integrator.as_ref(),
        &RenderOptions { time_budget: budget, quiet: true },
        &ends,
        &mut |pass| {
            if pass.last || ends.binary_search(&pass.spp).is_ok() {
                let image = pass.image();
                if let Ok(metrics) = error_metrics(&image, reference) {
                    let noise_removed = s
                        .reference
                        .halves
                        .as_ref()
                        .and_then(|[a, b]| nimbus::metrics::error_metrics_noise_removed(&image, a, b).ok());
                    let seconds = setup_seconds + pass.seconds;
                    checkpoints.push(Checkpoint { seconds, spp: pass.spp, metrics, noise_removed, last: pass.last });
                }
            }
        },
    );
    anyhow::ensure!(!checkpoints.is_empty(), "{}: the render ended before its first pass", s.integrator);
    Ok(Run {
        integrator: s.integrator.to_string(),
        mode: s.mode,
        seed: s.seed,
        setup_seconds,
        checkpoints,
        image: result.image,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_are_log_spaced_in_spp() {
        assert_eq!(checkpoint_spp(1, 64), [1, 2, 4, 8, 16, 32, 64]);
        assert_eq!(checkpoint_spp(2, 16), [1, 2, 3, 4, 6, 8, 11, 16]);
        assert_eq!(checkpoint_spp(1, 1), [1]);
        assert_eq!(checkpoint_spp(3, 5), [1, 2, 3, 4, 5]);
    }
}
