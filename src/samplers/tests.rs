//! Tests every sampler against the contract of [`Sampler`]: range, determinism, dimension
//! bookkeeping, stratification and convergence.

use glam::{UVec2, Vec2};

use super::*;
use crate::samplers::settings::{Randomization, SamplerKind, SamplerSettings};

const RESOLUTION: UVec2 = UVec2::new(16, 16);

fn sampler(kind: SamplerKind, spp: u32, randomization: Randomization) -> Sampler {
    let settings = SamplerSettings { kind, pixel_samples: spp, seed: 7, randomization };
    Sampler::new(&settings, RESOLUTION)
}

/// Every sampler kind at `spp` samples per pixel (a square number; stratified gets √spp²).
fn all(spp: u32) -> Vec<(&'static str, Sampler)> {
    let side = spp.isqrt();
    let stratified = SamplerKind::Stratified { x: side, y: side, jitter: true };
    vec![
        ("independent", sampler(SamplerKind::Independent, spp, Randomization::FastOwen)),
        ("stratified", sampler(stratified, spp, Randomization::FastOwen)),
        ("sobol", sampler(SamplerKind::Sobol, spp, Randomization::FastOwen)),
        ("zsobol fastowen", sampler(SamplerKind::ZSobol, spp, Randomization::FastOwen)),
        ("zsobol owen", sampler(SamplerKind::ZSobol, spp, Randomization::Owen)),
        (
            "halton permutedigits",
            sampler(SamplerKind::Halton(HaltonRandomization::PermuteDigits), spp, Randomization::FastOwen),
        ),
        ("halton owen", sampler(SamplerKind::Halton(HaltonRandomization::Owen), spp, Randomization::FastOwen)),
        ("halton none", sampler(SamplerKind::Halton(HaltonRandomization::None), spp, Randomization::FastOwen)),
        ("paddedsobol fastowen", sampler(SamplerKind::PaddedSobol, spp, Randomization::FastOwen)),
        ("paddedsobol owen", sampler(SamplerKind::PaddedSobol, spp, Randomization::Owen)),
        ("pmj02bn", sampler(SamplerKind::Pmj02bn, spp, Randomization::FastOwen)),
    ]
}

/// The first values of a pixel sample, drawn in the camera's order and then past Sobol's 256
/// dimensions.
fn values(s: &mut Sampler, pixel: UVec2, index: u32) -> Vec<f32> {
    s.start_pixel_sample(pixel, index, 0);
    let mut v = Vec::new();
    let p = s.get_pixel_2d();
    v.extend([p.x, p.y, s.get_1d()]);
    while v.len() < 300 {
        let u = s.get_2d();
        v.extend([u.x, u.y, s.get_1d()]);
    }
    v
}

#[test]
fn values_lie_in_the_unit_interval() {
    for (name, mut s) in all(16) {
        assert_eq!(s.samples_per_pixel(), 16, "{name}");
        for pixel in [UVec2::ZERO, UVec2::new(15, 15), UVec2::new(3, 7)] {
            for index in 0..16 {
                for (d, u) in values(&mut s, pixel, index).into_iter().enumerate() {
                    assert!((0.0..1.0).contains(&u), "{name}: dimension {d} is {u}");
                }
            }
        }
    }
}

#[test]
fn values_depend_only_on_pixel_index_and_dimension() {
    let pixels = [UVec2::new(1, 2), UVec2::new(2, 1), UVec2::new(1, 3)];
    for (name, s) in all(16) {
        // Forward on one clone, backward on another: a value must not depend on history.
        let (mut a, mut b) = (s.clone(), s.clone());
        let forward: Vec<Vec<f32>> =
            pixels.iter().flat_map(|&p| (0..16).map(move |i| (p, i))).map(|(p, i)| values(&mut a, p, i)).collect();
        let mut backward: Vec<Vec<f32>> = pixels
            .iter()
            .flat_map(|&p| (0..16).map(move |i| (p, i)))
            .rev()
            .map(|(p, i)| values(&mut b, p, i))
            .collect();
        backward.reverse();
        assert_eq!(forward, backward, "{name}");
        // Different pixels and different samples of a pixel differ.
        assert_ne!(forward[0], forward[16], "{name}");
        assert_ne!(forward[0], forward[32], "{name}");
        assert_ne!(forward[0], forward[1], "{name}");
        // The seed changes everything.
        let mut reseeded = Sampler::new(&SamplerSettings { seed: 8, ..settings_of(name) }, RESOLUTION);
        assert_ne!(values(&mut reseeded, pixels[0], 0), forward[0], "{name}");
    }
}

fn settings_of(name: &str) -> SamplerSettings {
    let kind = match name {
        "independent" => SamplerKind::Independent,
        "stratified" => SamplerKind::Stratified { x: 4, y: 4, jitter: true },
        "sobol" => SamplerKind::Sobol,
        "pmj02bn" => SamplerKind::Pmj02bn,
        _ => SamplerKind::ZSobol,
    };
    SamplerSettings {
        kind,
        pixel_samples: 16,
        seed: 7,
        randomization: if name == "zsobol owen" { Randomization::Owen } else { Randomization::FastOwen },
    }
}

#[test]
fn starting_dimension_skips_that_many_values() {
    for (name, mut s) in all(16) {
        let pixel = UVec2::new(4, 5);
        s.start_pixel_sample(pixel, 3, 0);
        for _ in 0..5 {
            s.get_1d();
        }
        let (a, b) = (s.get_2d(), s.get_1d());
        // Halton and pmj02bn keep dimensions 0 and 1 for the film position (`get_pixel_2d`),
        // so their other dimensions start at 2, as in pbrt-v4.
        let skipped = if name.starts_with("halton") || name == "pmj02bn" { 7 } else { 5 };
        s.start_pixel_sample(pixel, 3, skipped);
        assert_eq!((a, b), (s.get_2d(), s.get_1d()), "{name}");
    }
}

#[test]
fn camera_samples_come_in_pbrt_order() {
    use crate::film::filter::Filter;
    use crate::film::filter_settings::FilterSettings;
    let filter = Filter::new(&FilterSettings::Box { radius: [0.5, 0.5] });
    for (name, mut s) in all(16) {
        let pixel = UVec2::new(6, 2);
        s.start_pixel_sample(pixel, 5, 0);
        let cs = get_camera_sample(&mut s, pixel, &filter, CameraSampleUse::ALL);
        let after = s.get_1d();
        s.start_pixel_sample(pixel, 5, 0);
        let p = s.get_pixel_2d();
        assert!((cs.p_film - (pixel.as_vec2() + p)).abs().max_element() < 1e-5, "{name}");
        assert_eq!((cs.time, cs.p_lens, cs.filter_weight), (s.get_1d(), s.get_2d(), 1.0));
        // Values a scene has no use for are skipped: the same dimensions follow.
        for uses in [(false, true), (true, false), (false, false)] {
            let uses = CameraSampleUse { time: uses.0, lens: uses.1 };
            s.start_pixel_sample(pixel, 5, 0);
            let skipped = get_camera_sample(&mut s, pixel, &filter, uses);
            assert_eq!(skipped.p_film, cs.p_film, "{name}");
            assert_eq!(s.get_1d(), after, "{name} {uses:?}");
        }
    }
}

/// Skipping a dimension leaves the sampler where drawing it would: over a long path (past
/// Halton's wrap-around of its dimensions), whatever mix of draws and skips.
#[test]
fn skipped_dimensions_are_the_drawn_ones() {
    for (name, mut s) in all(16) {
        let pixel = UVec2::new(5, 3);
        for sample in [0, 7] {
            let mut drawn = Vec::new();
            s.start_pixel_sample(pixel, sample, 0);
            for _ in 0..700 {
                drawn.push((s.get_1d(), s.get_2d()));
            }
            s.start_pixel_sample(pixel, sample, 0);
            for (k, &(a, b)) in drawn.iter().enumerate() {
                match k % 3 {
                    0 => assert_eq!((s.get_1d(), s.get_2d()), (a, b), "{name}, pair {k}"),
                    1 => {
                        s.skip_1d();
                        assert_eq!(s.get_2d(), b, "{name}, pair {k}");
                    }
                    _ => {
                        assert_eq!(s.get_1d(), a, "{name}, pair {k}");
                        s.skip_2d();
                    }
                }
            }
        }
    }
}

/// A stream seed takes the place of one dimension (the values after it are those after one
/// draw). ZSobol's differ between dimensions, samples and pixels (no two walks share a
/// stream); the other samplers hash their value, as pbrt-v4 does, and pmj02bn's values
/// repeat across dimensions.
#[test]
fn stream_seed_stands_for_one_dimension() {
    for (name, mut s) in all(16) {
        let mut seen = std::collections::HashSet::new();
        for pixel in [UVec2::new(5, 3), UVec2::new(6, 3), UVec2::new(5, 4)] {
            for sample in [0, 1, 7] {
                s.start_pixel_sample(pixel, sample, 0);
                let mut drawn = Vec::new();
                for _ in 0..40 {
                    s.get_1d();
                    drawn.push(s.get_2d());
                }
                s.start_pixel_sample(pixel, sample, 0);
                for (k, &b) in drawn.iter().enumerate() {
                    let seed = s.stream_seed();
                    let unique = seen.insert(seed);
                    assert!(
                        unique || !name.starts_with("zsobol"),
                        "{name}: seeds repeat at {pixel}, sample {sample}, pair {k}"
                    );
                    assert_eq!(s.get_2d(), b, "{name}: dimensions after the seed, pair {k}");
                }
            }
        }
    }
}

/// Counts per cell of a `n`×`n` grid.
fn cell_counts(points: &[Vec2], n: usize) -> Vec<u32> {
    let mut counts = vec![0; n * n];
    for p in points {
        counts[(p.y * n as f32) as usize * n + (p.x * n as f32) as usize] += 1;
    }
    counts
}

#[test]
fn stratified_sampler_hits_every_stratum_once() {
    for jitter in [true, false] {
        let mut s = sampler(SamplerKind::Stratified { x: 4, y: 3, jitter }, 12, Randomization::FastOwen);
        for pixel in [UVec2::ZERO, UVec2::new(9, 4)] {
            let mut cells = vec![[0u32; 12]; 3];
            for index in 0..12 {
                s.start_pixel_sample(pixel, index, 0);
                for pair in cells.iter_mut().take(2) {
                    let u = s.get_2d();
                    pair[(u.y * 3.0) as usize * 4 + (u.x * 4.0) as usize] += 1;
                    if !jitter {
                        assert_eq!((u * Vec2::new(4.0, 3.0)).fract(), Vec2::splat(0.5));
                    }
                }
                cells[2][(s.get_1d() * 12.0) as usize] += 1;
            }
            assert!(cells.iter().flatten().all(|&c| c == 1), "{cells:?}");
        }
    }
}

#[test]
fn sobol_samplers_fill_every_elementary_interval() {
    // 64 points of a (0,2)-sequence put exactly one point in each cell of an 8×8 grid (and of
    // the 4×16 and 16×4 ones), and 64 points of a (0,1)-sequence one in each 1/64 of [0, 1).
    // Owen scrambling keeps that. ZSobol uses only Sobol' dimensions 0 and 1, so this holds
    // for all its dimensions; the per-pixel Sobol' sampler's later pairs are other
    // dimensions of the sequence, held to at most one point beyond the mean per cell.
    for (name, mut s) in all(64).into_iter().filter(|(n, _)| n.contains("sobol")) {
        for pixel in [UVec2::new(0, 0), UVec2::new(5, 11), UVec2::new(15, 2)] {
            for start in [0u32, 2, 9, 30] {
                let mut points = Vec::new();
                let mut ones = Vec::new();
                for index in 0..64 {
                    s.start_pixel_sample(pixel, index, start);
                    points.push(s.get_2d());
                    ones.push(s.get_1d());
                }
                let counts = cell_counts(&points, 8);
                let max = *counts.iter().max().unwrap();
                if start == 0 || name.starts_with("zsobol") {
                    assert!(counts.iter().all(|&c| c == 1), "{name} {pixel} {start}");
                    let mut strata = [0u32; 64];
                    for u in ones {
                        strata[(u * 64.0) as usize] += 1;
                    }
                    assert!(strata.iter().all(|&c| c == 1), "{name} {pixel} {start} 1D");
                } else {
                    assert!(max <= 2, "{name} {pixel} {start}: {max} points in a cell");
                }
            }
        }
    }
}

/// The shifted draws (a medium walk's first event, a shadow ray's first collision) keep a
/// ZSobol pixel's 64 samples in every 8×8 cell and 1/64 stratum once, as the plain draws do,
/// and differ from them by a shift that changes from pixel to pixel and from seed to seed
/// (the pair's first value is the plain one).
#[test]
fn shifted_draws_stay_stratified_and_move_per_pixel() {
    let first = |seed: i32, pixel: UVec2| {
        let settings = SamplerSettings { seed, pixel_samples: 64, ..settings_of("zsobol fastowen") };
        let mut s = Sampler::new(&settings, UVec2::new(32, 32));
        let (mut pairs, mut ones, mut plain) = (Vec::new(), Vec::new(), Vec::new());
        for index in 0..64 {
            s.start_pixel_sample(pixel, index, 7);
            pairs.push(s.get_2d_shifted_y());
            ones.push(s.get_1d_shifted());
            s.start_pixel_sample(pixel, index, 7);
            plain.push(s.get_2d());
        }
        (pairs, ones, plain)
    };
    let mut shifts = std::collections::HashSet::new();
    for seed in [1, 2] {
        for pixel in [UVec2::new(0, 0), UVec2::new(5, 11), UVec2::new(6, 11)] {
            let (pairs, ones, plain) = first(seed, pixel);
            assert!(cell_counts(&pairs, 8).iter().all(|&c| c == 1), "seed {seed}, {pixel}");
            let mut strata = [0u32; 64];
            ones.iter().for_each(|u| strata[(u * 64.0) as usize] += 1);
            assert!(strata.iter().all(|&c| c == 1), "seed {seed}, {pixel}: 1D");
            // The XOR of a shifted and a plain value is the pixel's shift, the same for all
            // its samples (its leading 12 bits, which f32 rounding rarely reaches).
            let xor = |a: f32, b: f32| ((a * 4_294_967_296.0) as u64 ^ (b * 4_294_967_296.0) as u64) >> 20;
            assert!(pairs.iter().zip(&plain).all(|(p, q)| p.x == q.x), "seed {seed}, {pixel}: the first is plain");
            let shift = xor(pairs[0].y, plain[0].y);
            let same = pairs.iter().zip(&plain).filter(|(p, q)| xor(p.y, q.y) == shift).count();
            assert!(same >= 60, "seed {seed}, {pixel}: {same} of 64 samples share the shift");
            shifts.insert(shift);
        }
    }
    assert_eq!(shifts.len(), 6, "every pixel and seed its own shift");
}

#[test]
fn low_discrepancy_samplers_integrate_smooth_functions_faster() {
    // ∫∫ sin(πx) sin(πy) + x y² over [0, 1]² = 4/π² + 1/6.
    let f = |p: Vec2| (std::f32::consts::PI * p.x).sin() * (std::f32::consts::PI * p.y).sin() + p.x * p.y * p.y;
    let exact = 4.0 / std::f64::consts::PI.powi(2) + 1.0 / 6.0;
    let spp = 256;
    for start in [0u32, 3] {
        let mut rmse = Vec::new();
        for (name, mut s) in all(spp) {
            let mut sq = 0.0;
            let mut pixels = 0;
            for y in 0..8 {
                for x in 0..8 {
                    let pixel = UVec2::new(x, y);
                    let mut sum = 0.0f64;
                    for index in 0..spp {
                        s.start_pixel_sample(pixel, index, start);
                        sum += f(s.get_2d()) as f64;
                    }
                    sq += (sum / spp as f64 - exact).powi(2);
                    pixels += 1;
                }
            }
            rmse.push((name, (sq / pixels as f64).sqrt()));
        }
        let independent = rmse[0].1;
        for &(name, e) in &rmse[1..] {
            // Independent sampling's error is about 0.02 here, stratified's about 0.0025 and
            // the Sobol' samplers' below 0.001 (N^-1 against N^-1/2, and better).
            // Halton's per-pixel points are every (2^a·3^b)-th of one sequence: about 0.003.
            // pmj02bn's per-pixel blue-noise rotation (pbrt-v4's Cranley–Patterson shift)
            // wraps the net around the square, which costs the smoothness Sobol' exploits:
            // about 0.0025, like stratified.
            let bound =
                if name == "stratified" || name.starts_with("halton") || name == "pmj02bn" { 0.25 } else { 0.1 };
            assert!(e < bound * independent, "start {start}: {rmse:?}");
        }
    }
}
