//! Image comparison: parity with a reference judged as the pbrt-v4 references' README does
//! (mean within a tolerance, 8×8 block differences consistent with noise).

use crate::error::{Error, Result};
use crate::imageio::Image;

mod reference_noise;
pub use reference_noise::{average, error_metrics_noise_removed, mean_standard_error, reference_noise};

/// How a pair of renders with different seeds compares to a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parity {
    /// |mean(M) − mean(ref)| / mean(ref) per channel, M = (A + B) / 2.
    pub mean_rel: [f64; 3],
    /// Σ over 8×8 blocks of (block mean of M − ref)² / Σ (block mean of (A − B)/2)², over all
    /// channels: ≈ 1 for unbiased renders, larger with bias.
    pub excess: f64,
}

impl Parity {
    /// The worst channel's relative mean difference.
    pub fn worst_mean_rel(&self) -> f64 {
        self.mean_rel.iter().copied().fold(0.0, f64::max)
    }
}

fn channel(p: glam::Vec3, c: usize) -> f64 {
    p[c] as f64
}

/// One 8×8 block's difference from the reference in units of its noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockZ {
    /// Block column (pixels bx·8 .. bx·8+8).
    pub bx: usize,
    /// Block row.
    pub by: usize,
    /// Channel-mean of (block mean of M − reference).
    pub diff: f64,
    /// diff / noise estimate (|A − B|/2 block mean, channel-mean).
    pub z: f64,
}

/// For a scene whose true image is gray (all lights and materials gray), an estimate of the
/// reference's own noise contribution to [`Parity::excess`]'s numerator relative to its
/// denominator: a spectral renderer's noise makes a gray image's channels differ, and the
/// spread of the channels around their mean measures it (assuming independent channels).
pub fn reference_noise_share(a: &Image, b: &Image, reference: &Image) -> f64 {
    let (bw, bh) = (a.width / 8, a.height / 8);
    let (mut noise, mut den) = (0.0f64, 0.0f64);
    for by in 0..bh {
        for bx in 0..bw {
            let mut r = [0.0f64; 3];
            let mut d = [0.0f64; 3];
            for y in by * 8..by * 8 + 8 {
                for x in bx * 8..bx * 8 + 8 {
                    for c in 0..3 {
                        r[c] += channel(reference.get(x, y), c) / 64.0;
                        d[c] += 0.5 * (channel(a.get(x, y), c) - channel(b.get(x, y), c)) / 64.0;
                    }
                }
            }
            let mean = (r[0] + r[1] + r[2]) / 3.0;
            noise += 1.5 * r.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
            den += d.iter().map(|v| v * v).sum::<f64>();
        }
    }
    if den > 0.0 { noise / den } else { 0.0 }
}

/// Per-block z-scores of M = (A + B)/2 against the reference, largest |z| first.
pub fn block_z_scores(a: &Image, b: &Image, reference: &Image) -> Vec<BlockZ> {
    let mut out = Vec::new();
    for by in 0..a.height / 8 {
        for bx in 0..a.width / 8 {
            let (mut d, mut n) = (0.0f64, 0.0f64);
            for c in 0..3 {
                let (mut sm, mut sr, mut sd2) = (0.0, 0.0, 0.0);
                for y in by * 8..by * 8 + 8 {
                    for x in bx * 8..bx * 8 + 8 {
                        let (pa, pb, pr) =
                            (channel(a.get(x, y), c), channel(b.get(x, y), c), channel(reference.get(x, y), c));
                        sm += 0.5 * (pa + pb);
                        sr += pr;
                        sd2 += (0.5 * (pa - pb)).powi(2);
                    }
                }
                d += (sm - sr) / 64.0 / 3.0;
                // Noise of the block mean of M from the per-pixel spread of (A − B)/2, whose mean
                // square estimates a pixel's variance of M.
                n += sd2 / 64.0 / 64.0 / 3.0;
            }
            out.push(BlockZ { bx, by, diff: d, z: if n > 0.0 { d / n.sqrt() } else { 0.0 } });
        }
    }
    out.sort_by(|p, q| q.z.abs().total_cmp(&p.z.abs()));
    out
}

/// Compares two renders `a`, `b` (different seeds, same spp) with `reference`; images of
/// different sizes are [`Error::Invalid`].
pub fn parity(a: &Image, b: &Image, reference: &Image) -> Result<Parity> {
    for (name, img) in [("second render", b), ("reference", reference)] {
        if (img.width, img.height) != (a.width, a.height) {
            return Err(Error::Invalid(format!(
                "{name} is {}x{}, the render is {}x{}",
                img.width, img.height, a.width, a.height
            )));
        }
    }
    let n = a.pixels.len() as f64;
    let mut mean_rel = [0.0; 3];
    for (c, m) in mean_rel.iter_mut().enumerate() {
        let mm: f64 =
            a.pixels.iter().zip(&b.pixels).map(|(x, y)| 0.5 * (channel(*x, c) + channel(*y, c))).sum::<f64>() / n;
        let mr: f64 = reference.pixels.iter().map(|x| channel(*x, c)).sum::<f64>() / n;
        *m = if mr > 0.0 { (mm - mr).abs() / mr } else { (mm - mr).abs() };
    }
    let (bw, bh) = (a.width / 8, a.height / 8);
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for by in 0..bh {
        for bx in 0..bw {
            for c in 0..3 {
                let (mut sm, mut sr, mut sd) = (0.0, 0.0, 0.0);
                for y in by * 8..by * 8 + 8 {
                    for x in bx * 8..bx * 8 + 8 {
                        let (pa, pb, pr) =
                            (channel(a.get(x, y), c), channel(b.get(x, y), c), channel(reference.get(x, y), c));
                        sm += 0.5 * (pa + pb);
                        sr += pr;
                        sd += 0.5 * (pa - pb);
                    }
                }
                num += ((sm - sr) / 64.0).powi(2);
                den += (sd / 64.0).powi(2);
            }
        }
    }
    Ok(Parity {
        mean_rel,
        excess: if den > 0.0 {
            num / den
        } else if num == 0.0 {
            1.0
        } else {
            f64::INFINITY
        },
    })
}

/// Error of a test image against a reference, over all pixels and channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Mean squared error.
    pub mse: f64,
    /// Root mean squared error.
    pub rmse: f64,
    /// Relative MSE: mean of (a − b)² / (b² + 0.01).
    pub rel_mse: f64,
    /// Mean absolute error.
    pub mae: f64,
    /// Mean positive error, mean of max(a − b, 0) (van den Hurk 2026, Eq. 5.1).
    pub mpe: f64,
    /// Mean negative error, mean of max(b − a, 0) (Eq. 5.1).
    pub mne: f64,
    /// Mean of the test image (all channels).
    pub mean_test: f64,
    /// Mean of the reference (all channels).
    pub mean_reference: f64,
}

/// Compares `test` with `reference` (same size; other sizes are [`Error::Invalid`]).
pub fn error_metrics(test: &Image, reference: &Image) -> Result<ErrorMetrics> {
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(Error::Invalid(format!(
            "image sizes differ: test is {}x{}, reference is {}x{}",
            test.width, test.height, reference.width, reference.height
        )));
    }
    let (mut se, mut rel, mut ae, mut pe, mut ne, mut st, mut sr) = (0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (a, b) in test.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (x, y) = (a[c] as f64, b[c] as f64);
            let d = x - y;
            se += d * d;
            rel += d * d / (y * y + 0.01);
            ae += d.abs();
            pe += d.max(0.0);
            ne += (-d).max(0.0);
            st += x;
            sr += y;
        }
    }
    let n = (test.pixels.len() * 3).max(1) as f64;
    Ok(ErrorMetrics {
        mse: se / n,
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        mae: ae / n,
        mpe: pe / n,
        mne: ne / n,
        mean_test: st / n,
        mean_reference: sr / n,
    })
}

/// A false-color image of `test − reference`: green where the test is brighter, red where
/// darker, scaled so that `scale` (per-pixel channel-mean difference) is full intensity.
pub fn difference_image(test: &Image, reference: &Image, scale: f32) -> Image {
    let mut out = Image::new(test.width, test.height);
    for (o, (a, b)) in out.pixels.iter_mut().zip(test.pixels.iter().zip(&reference.pixels)) {
        let d = ((*a - *b).x + (*a - *b).y + (*a - *b).z) / 3.0 / scale;
        *o = if d >= 0.0 { glam::Vec3::new(0.0, d.min(1.0), 0.0) } else { glam::Vec3::new((-d).min(1.0), 0.0, 0.0) };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(values: &[f32]) -> Image {
        let mut i = Image::new(values.len(), 1);
        i.pixels = values.iter().map(|v| glam::Vec3::splat(*v)).collect();
        i
    }

    #[test]
    fn metrics_match_hand_computed_values() {
        let m = error_metrics(&img(&[1.0, 0.0]), &img(&[0.5, 0.5])).unwrap();
        assert!((m.mse - 0.25).abs() < 1e-12);
        assert!((m.rmse - 0.5).abs() < 1e-12);
        assert!((m.mae - 0.5).abs() < 1e-12);
        assert!((m.mpe - 0.25).abs() < 1e-12);
        assert!((m.mne - 0.25).abs() < 1e-12);
        assert!((m.rel_mse - 0.25 / 0.26).abs() < 1e-9);
        assert!((m.mean_test - 0.5).abs() < 1e-12);
        assert!(error_metrics(&img(&[1.0]), &img(&[1.0, 2.0])).is_err());
    }

    #[test]
    fn parity_of_identical_noise_free_images() {
        let a = Image { pixels: vec![glam::Vec3::ONE; 64], ..Image::new(8, 8) };
        let p = parity(&a, &a, &a).unwrap();
        assert_eq!(p.worst_mean_rel(), 0.0);
        assert_eq!(p.excess, 1.0);
    }
}
