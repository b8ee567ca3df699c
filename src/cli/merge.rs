//! `nimbus merge DIR -o out.exr`: assembles the parts of a split render (`nimbus cluster`, or
//! any renders of one scene with `--pixelbounds` and `--seed`). Parts of the same pixel bounds
//! are seed batches, averaged weighted by their spp; parts of different bounds are tiles, placed
//! by their bounds. Every part's metadata is checked: one scene (hash), one integrator, one
//! film; no repeated seed within a batch, no overlapping tile, no uncovered pixel, and, when
//! `cluster.json` lists the parts expected, none missing.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use nimbus::imageio::Image;

/// Arguments of `nimbus merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// Folder of the parts (its `*.exr`; with `nimbus cluster`'s `cluster.json`, the parts it
    /// lists).
    dir: PathBuf,
    /// The merged image (.exr, or .png).
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
}

/// A part and what its metadata says.
struct Part {
    path: PathBuf,
    image: Image,
    scene_hash: String,
    integrator: String,
    spp: u32,
    seed: i32,
    /// x0 x1 y0 y1 of its pixels in the film.
    bounds: [u32; 4],
    /// x0 x1 y0 y1 of the whole film.
    film_bounds: [u32; 4],
}

fn parse_bounds(s: &str) -> Option<[u32; 4]> {
    let v: Vec<u32> = s.split_whitespace().map(|x| x.parse().ok()).collect::<Option<_>>()?;
    <[u32; 4]>::try_from(v).ok().filter(|b| b[0] < b[1] && b[2] < b[3])
}

/// `x0 x1 y0 y1` as a string, as the metadata writes it.
pub fn bounds_text(b: [u32; 4]) -> String {
    format!("{} {} {} {}", b[0], b[1], b[2], b[3])
}

fn read_part(path: &Path) -> Result<Part> {
    let mut image = nimbus::imageio::read_exr(path).map_err(anyhow::Error::msg)?;
    // A G-buffer's or spectral film's channels beyond RGB travel with the part.
    image.channels = nimbus::imageio::read_exr_channels(path).map_err(anyhow::Error::msg)?;
    let meta = |k: &str| -> Result<String> {
        image.metadata.get(k).cloned().with_context(|| {
            format!("{}: no \"{k}\" in its metadata (not a part rendered by nimbus render)", path.display())
        })
    };
    let number = |k: &str| -> Result<i64> {
        let v = meta(k)?;
        v.parse().with_context(|| format!("{}: \"{k}\" is \"{v}\", not a number", path.display()))
    };
    let bounds = |k: &str| -> Result<[u32; 4]> {
        let v = meta(k)?;
        parse_bounds(&v).with_context(|| format!("{}: \"{k}\" is \"{v}\", not x0 x1 y0 y1", path.display()))
    };
    let part = Part {
        path: path.to_path_buf(),
        scene_hash: meta("nimbus:scene-hash")?,
        integrator: meta("nimbus:integrator")?,
        spp: number("nimbus:spp")? as u32,
        seed: number("nimbus:seed")? as i32,
        bounds: bounds("nimbus:pixel-bounds")?,
        film_bounds: bounds("nimbus:film-bounds")?,
        image,
    };
    let (w, h) = ((part.bounds[1] - part.bounds[0]) as usize, (part.bounds[3] - part.bounds[2]) as usize);
    if (part.image.width, part.image.height) != (w, h) {
        bail!("{}: {}x{} pixels but its bounds hold {w}x{h}", path.display(), part.image.width, part.image.height);
    }
    Ok(part)
}

/// The split's mode and the parts `cluster.json` in `dir` expects, if there is one.
fn expected_parts(dir: &Path) -> Result<Option<(String, Vec<String>)>> {
    let path = dir.join("cluster.json");
    if !path.exists() {
        return Ok(None);
    }
    let manifest = super::cluster::Manifest::read(&path)?;
    Ok(Some((manifest.mode, manifest.tasks.iter().map(|t| t.output.clone()).collect())))
}

fn name_of(p: &Path) -> String {
    p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// Reads, checks and merges the parts in `dir`.
pub fn merge_dir(dir: &Path, output: &Path) -> Result<Image> {
    let expected = expected_parts(dir)?;
    let mut paths: Vec<PathBuf> = match &expected {
        Some((mode, names)) => {
            let missing: Vec<&String> = names.iter().filter(|n| !dir.join(n).exists()).collect();
            if !missing.is_empty() {
                bail!(
                    "{} of {} parts are missing in {}: {} (`nimbus cluster --resume {}` resubmits them)",
                    missing.len(),
                    names.len(),
                    dir.display(),
                    missing.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", "),
                    dir.display()
                );
            }
            if mode == "cameras" {
                bail!(
                    "{} holds camera frames, each an image of its own (all {} are there): nothing to merge",
                    dir.display(),
                    names.len()
                );
            }
            names.iter().map(|n| dir.join(n)).collect()
        }
        None => std::fs::read_dir(dir)
            .with_context(|| format!("reading {}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "exr"))
            .filter(|p| output.file_name() != p.file_name() || output.parent() != p.parent())
            .collect(),
    };
    paths.sort();
    if paths.is_empty() {
        bail!("{} has no parts (*.exr) to merge", dir.display());
    }
    let parts = paths.iter().map(|p| read_part(p)).collect::<Result<Vec<_>>>()?;
    let first = &parts[0];
    for p in &parts[1..] {
        let differs = |what: &str, a: &str, b: &str| -> Result<()> {
            if a != b {
                bail!(
                    "{} is from another {what} ({b}) than {} ({a}): parts must be one render split up",
                    name_of(&p.path),
                    name_of(&first.path)
                );
            }
            Ok(())
        };
        differs("scene", &first.scene_hash, &p.scene_hash)?;
        differs("integrator", &first.integrator, &p.integrator)?;
        differs("film", &bounds_text(first.film_bounds), &bounds_text(p.film_bounds))?;
        let names = |q: &Part| q.image.channels.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>().join(" ");
        differs("film's channels", &names(first), &names(p))?;
    }
    // Seed batches: the parts of each pixel bounds, no seed twice.
    let mut groups: BTreeMap<[u32; 4], Vec<&Part>> = BTreeMap::new();
    for p in &parts {
        let group = groups.entry(p.bounds).or_default();
        if let Some(q) = group.iter().find(|q| q.seed == p.seed) {
            bail!(
                "{} and {} are the same pixels with the same seed ({}): the batch would count the same samples twice",
                name_of(&q.path),
                name_of(&p.path),
                p.seed
            );
        }
        group.push(p);
    }
    // Tiles: the groups must not overlap and must cover the film.
    let tiles: Vec<([u32; 4], &Vec<&Part>)> = groups.iter().map(|(b, g)| (*b, g)).collect();
    for (i, (a, ga)) in tiles.iter().enumerate() {
        for (b, gb) in &tiles[i + 1..] {
            if a[0] < b[1] && b[0] < a[1] && a[2] < b[3] && b[2] < a[3] {
                bail!(
                    "{} (pixels {}) and {} (pixels {}) overlap",
                    name_of(&ga[0].path),
                    bounds_text(*a),
                    name_of(&gb[0].path),
                    bounds_text(*b)
                );
            }
        }
    }
    // A variance is not the mean of the batches' variances (their means differ too), and the
    // parts do not carry what pooling needs.
    if let Some((name, _)) = first.image.channels.iter().find(|(n, _)| n.contains("Variance."))
        && let Some((_, group)) = tiles.iter().find(|(_, g)| g.len() > 1)
    {
        bail!(
            "{} and {} are seed batches of a film with a \"{name}\" channel, which averaging would get \
             wrong: split such a film into --tiles",
            name_of(&group[0].path),
            name_of(&group[1].path)
        );
    }
    let fb = first.film_bounds;
    let (w, h) = ((fb[1] - fb[0]) as usize, (fb[3] - fb[2]) as usize);
    let mut covered = vec![false; w * h];
    let mut image = Image::new(w, h);
    image.channels = first.image.channels.iter().map(|(n, _)| (n.clone(), vec![0.0; w * h])).collect();
    for (b, group) in &tiles {
        if b[0] < fb[0] || b[1] > fb[1] || b[2] < fb[2] || b[3] > fb[3] {
            bail!(
                "{} (pixels {}) lies outside the film ({})",
                name_of(&group[0].path),
                bounds_text(*b),
                bounds_text(fb)
            );
        }
        let total: f64 = group.iter().map(|p| p.spp as f64).sum();
        let (tw, th) = ((b[1] - b[0]) as usize, (b[3] - b[2]) as usize);
        for y in 0..th {
            for x in 0..tw {
                let (fx, fy) = (x + (b[0] - fb[0]) as usize, y + (b[2] - fb[2]) as usize);
                // One part: its pixel exactly (tiles merge bit for bit).
                let v = if group.len() == 1 {
                    group[0].image.get(x, y)
                } else {
                    let sum =
                        group.iter().fold(glam::DVec3::ZERO, |s, p| s + p.image.get(x, y).as_dvec3() * p.spp as f64);
                    (sum / total).as_vec3()
                };
                image.pixels[fy * w + fx] = v;
                covered[fy * w + fx] = true;
                for (c, (_, out)) in image.channels.iter_mut().enumerate() {
                    let at = y * tw + x;
                    out[fy * w + fx] = if group.len() == 1 {
                        group[0].image.channels[c].1[at]
                    } else {
                        let sum: f64 = group.iter().map(|p| p.image.channels[c].1[at] as f64 * p.spp as f64).sum();
                        (sum / total) as f32
                    };
                }
            }
        }
    }
    if let Some(i) = covered.iter().position(|c| !c) {
        let (x, y) = (i % w + fb[0] as usize, i / w + fb[2] as usize);
        let n = covered.iter().filter(|c| !**c).count();
        bail!("the parts leave {n} pixels of the film uncovered, the first at ({x}, {y})");
    }
    let spp: Vec<u32> = tiles.iter().map(|(_, g)| g.iter().map(|p| p.spp).sum()).collect();
    let mut seeds: Vec<i32> = parts.iter().map(|p| p.seed).collect();
    seeds.sort_unstable();
    seeds.dedup();
    // The first part's metadata (the film's own keys, e.g. a spectral film's layout), less what
    // belongs to one part, then what the merge knows.
    let per_part = ["time", "setup-time", "peak-rss-bytes", "nonfinite-samples", "precomputed-bytes", "spp", "seed"];
    image.metadata = first.image.metadata.clone();
    image.metadata.retain(|k, _| !per_part.iter().any(|p| k.strip_prefix("nimbus:") == Some(p)));
    let m = &mut image.metadata;
    m.insert("nimbus:pixel-bounds".into(), bounds_text(fb));
    if spp.iter().all(|&s| s == spp[0]) {
        m.insert("nimbus:spp".into(), spp[0].to_string());
    }
    if let [seed] = seeds.as_slice() {
        m.insert("nimbus:seed".into(), seed.to_string());
    } else {
        m.insert("nimbus:seeds".into(), seeds.iter().map(i32::to_string).collect::<Vec<_>>().join(" "));
    }
    m.insert("nimbus:merged-parts".into(), parts.len().to_string());
    Ok(image)
}

/// Runs the merge.
pub fn run(args: &MergeArgs) -> Result<ExitCode> {
    let image = merge_dir(&args.dir, &args.output)?;
    nimbus::imageio::write_image(&args.output, &image).map_err(anyhow::Error::msg)?;
    eprintln!(
        "{}: {}x{} from {} parts",
        args.output.display(),
        image.width,
        image.height,
        image.metadata.get("nimbus:merged-parts").map_or("?", String::as_str)
    );
    Ok(ExitCode::SUCCESS)
}
