//! nimbus's own pbrt-v4 parity scenes (`pbrt-scenes/pbrt-v4-parity/`): features the shared
//! references do not cover (pbrt-v4's coated conductor, mix, diffuse transmission, bump and
//! normal maps, alpha, loop subdivision, bilinear patches, curves, hair, motion blur, Ptex), each
//! rendered by the real pbrt-v4 (README there). nimbus's volpath must converge to them.

use std::path::{Path, PathBuf};

use nimbus::imageio::Image;
use nimbus::scene::BuildOptions;

use crate::common::render_scene;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/pbrt-v4-parity")
}

/// Renders `scene` with `seeds` at `spp`.
fn renders(scene: &Path, spp: u32, seeds: std::ops::Range<i32>) -> Vec<Image> {
    let desc = nimbus::parser::load_file(scene).unwrap();
    seeds
        .map(|seed| {
            render_scene(
                &nimbus::setup::build(&desc, &BuildOptions { spp: Some(spp), seed: Some(seed), ..Default::default() })
                    .unwrap(),
            )
        })
        .collect()
}

/// pbrt-v4's own error in turning an RGB light into a spectrum and back (its 64³ table):
/// a sky of `rgb L [0.25 0.3 0.4]` alone renders 0.034 % dark in pbrt-v4 (mean 0.316559 for
/// 0.316667), where nimbus reproduces the RGB. Flat, nearly noiseless blocks of sky would
/// otherwise turn that into a large excess; each block is allowed this relative difference.
const CONVERSION: f64 = 5e-4;

/// Samples per pixel of the references (`render-references.sh`).
const REFERENCE_SPP: f64 = 4096.0;

/// The parity judgement with K renders instead of two: per 8×8 block and channel, the mean of
/// the K renders against the reference, over the noise of that mean estimated from the K block
/// means' own spread (K − 1 degrees of freedom per block, where two renders give one: on these
/// small images the noise sits in a few blocks, and one degree of freedom each made the
/// two-render excess swing between 1 and 4 on unbiased renders). Returns (worst channel's
/// relative mean difference, excess).
pub fn judge(images: &[Image], spp: u32, reference: &Image) -> (f64, f64) {
    let k = images.len() as f64;
    let (w, h) = (reference.width, reference.height);
    let mut mean_rel = 0.0f64;
    for c in 0..3 {
        let m: f64 = images.iter().flat_map(|i| i.pixels.iter().map(move |p| p[c] as f64)).sum::<f64>() / k;
        let r: f64 = reference.pixels.iter().map(|p| p[c] as f64).sum();
        mean_rel = mean_rel.max((m - r).abs() / r.max(1e-12));
    }
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for by in 0..h / 8 {
        for bx in 0..w / 8 {
            for c in 0..3 {
                let block = |img: &Image| {
                    let mut s = 0.0f64;
                    for y in by * 8..by * 8 + 8 {
                        for x in bx * 8..bx * 8 + 8 {
                            s += img.get(x, y)[c] as f64;
                        }
                    }
                    s / 64.0
                };
                let means: Vec<f64> = images.iter().map(block).collect();
                let m = means.iter().sum::<f64>() / k;
                let var_of_mean = means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (k - 1.0) / k;
                let r = block(reference);
                num += (m - r).powi(2);
                // The reference's own noise: the same per-sample variance at REFERENCE_SPP.
                den += var_of_mean * (1.0 + k * spp as f64 / REFERENCE_SPP) + (CONVERSION * r).powi(2);
            }
        }
    }
    (mean_rel, if den > 0.0 { num / den } else { f64::INFINITY })
}

/// The image mean of `images` (K renders at `spp`) against the reference's, worst channel:
/// (|difference| / reference, four standard errors / reference), the standard error measured
/// from the K renders' own means (the reference's noise counted as theirs at REFERENCE_SPP).
fn mean_within_noise(images: &[Image], spp: u32, reference: &Image) -> (f64, f64) {
    let k = images.len() as f64;
    let mut worst = (0.0f64, f64::INFINITY);
    for c in 0..3 {
        let means: Vec<f64> = images.iter().map(|i| i.pixels.iter().map(|p| p[c] as f64).sum::<f64>()).collect();
        let m = means.iter().sum::<f64>() / k;
        let var_of_mean = means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (k - 1.0) / k;
        let r: f64 = reference.pixels.iter().map(|p| p[c] as f64).sum();
        let se = (var_of_mean * (1.0 + k * spp as f64 / REFERENCE_SPP)).sqrt();
        let (rel, bound) = ((m - r).abs() / r.max(1e-12), 4.0 * se / r.max(1e-12));
        if rel - bound > worst.0 - worst.1 {
            worst = (rel, bound);
        }
    }
    worst
}

#[test]
fn own_parity_scenes_match_pbrt_v4() {
    for name in [
        "materials",
        "bump-alpha",
        "shapes",
        "motion",
        "hair",
        "measured",
        "spherical",
        "goniometric",
        "projection",
        "realistic",
        "realistic-wide",
        "portal",
        "alpha-light",
        "image-lights",
        "procedural",
        "differentials",
        "ewa",
        "displacement",
        "ptex",
        "invisible-light",
        "portal-spectrum",
        "projective-env",
    ] {
        let reference = nimbus::imageio::read_exr(&dir().join(format!("references/{name}.exr"))).unwrap();
        let images = renders(&dir().join(format!("{name}.pbrt")), 32, 1..9);
        let (mean_rel, excess) = judge(&images, 32, &reference);
        // Unbiased renders score about 1 here (0.4–1.9 over four seed sets at 32 spp); the curve
        // spawn offset these scenes found (twice pbrt-v4's) scored 2.2–3.0.
        eprintln!("{name}: mean_rel {mean_rel:.4}, excess {excess:.2}");
        assert!(mean_rel < 0.01 && excess < 2.0, "{name}: mean_rel {mean_rel:.4}, excess {excess:.2}");
    }
}

/// The real Disney cloud (`pbrt-scenes/disney-cloud/`, Walt Disney Animation Studios' data set at
/// its sixteenth resolution in the published pbrt-v4 scene, framed at 64×36): dense, albedo 1,
/// g = 0.877, paths of hundreds of events, against pbrt-v4 at 4096 spp.
#[test]
fn the_disney_cloud_matches_pbrt_v4() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/disney-cloud");
    let reference = nimbus::imageio::read_exr(&dir.join("references/disney-cloud-small.exr")).unwrap();
    let images = renders(&dir.join("disney-cloud-small.pbrt"), 32, 1..17);
    let (_, excess) = judge(&images, 32, &reference);
    // The image mean's noise is large here (one render's mean varies by about 2 %: a few
    // paths of hundreds of events carry much of it), so the mean is judged against four of
    // its standard errors measured from the renders, not a fixed 1 % (which 8 unbiased
    // renders missed at −1.45 % when the sampler's dimensions moved; 64 gave +0.37 ± 0.28 %).
    let (mean_rel, bound) = mean_within_noise(&images, 32, &reference);
    eprintln!("disney-cloud-small: mean_rel {mean_rel:.4} (4 standard errors {bound:.4}), excess {excess:.2}");
    assert!(
        mean_rel < bound && excess < 2.0,
        "disney-cloud-small: mean_rel {mean_rel:.4} (4 standard errors {bound:.4}), excess {excess:.2}"
    );
}
