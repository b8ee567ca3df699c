//! Rendering a scene into an image: tiles in parallel with rayon, each pixel's samples in a
//! fixed order so the image is the same at any thread count, progressive passes for a time
//! budget.

mod combine;
mod correction;
mod gbuffer;
mod window;

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::UVec2;
use rayon::prelude::*;

use crate::color::Rgb;
use crate::film::settings::FilmKind;
use crate::imageio::Image;
use crate::integrators::common::RayStats;
use crate::integrators::image_pass::{ImagePass, RenderChannels, camera_ray};
use crate::integrators::{ImageIntegrator, Integrator, PixelValue};
use crate::samplers::settings::SamplerSettings;
use crate::samplers::{CameraSample, Sampler, get_camera_sample};
use crate::scene::Scene;
use crate::scene::transport::Transport;
use crate::spectra::SampledSpectrum;

/// Side of a square tile in pixels.
const TILE: u32 = 16;

/// Samples per pixel a ZSobol sampler is made for when rendering to a time budget.
const PROGRESSIVE_SPP: u32 = 1 << 16;

/// How to run a render.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderOptions {
    /// Stop after this many seconds (progressive), instead of at the scene's spp.
    pub time_budget: Option<f64>,
    /// Print nothing while rendering.
    pub quiet: bool,
}

/// A finished render.
pub struct RenderResult {
    /// The image (the film's pixel bounds).
    pub image: Image,
    /// Samples per pixel reached.
    pub spp: u32,
    /// Seconds spent rendering (excluding scene building).
    pub seconds: f64,
    /// Rays traced.
    pub rays: RayStats,
    /// Samples whose radiance was NaN or infinite (zeroed, as pbrt-v4 does; counted so that
    /// a method producing them is seen).
    pub nonfinite_samples: u64,
}

/// Per-pixel accumulation: Σ w·L and Σ w (pbrt-v4's RGBFilm).
#[derive(Clone, Copy, Debug, Default)]
struct FilmSum {
    rgb: [f64; 3],
    weight: f64,
    nonfinite: u32,
}

/// Σ L, Σ L² and the count of a pixel's unweighted samples, for the G-buffer's variance
/// channels (kept only for a G-buffer film: 48 of the 88 bytes a pixel took when every film
/// kept them).
#[derive(Clone, Copy, Debug, Default)]
struct Spread {
    sum: [f64; 3],
    sum_sq: [f64; 3],
    count: u32,
}

/// A pixel's sums over some of its samples (one tile's pass).
#[derive(Clone, Copy, Debug, Default)]
struct PixelSum {
    film: FilmSum,
    spread: Spread,
}

/// A sample as the film takes it: clamped to the film's `max` component value, or None when
/// it is NaN or infinite (it would poison the pixel; pbrt-v4 logs it and adds zero).
#[inline]
fn admit(mut l: Rgb, max: f32) -> Option<Rgb> {
    if !l.is_finite() {
        return None;
    }
    let m = l.max_element();
    if m > max {
        l *= max / m;
    }
    Some(l)
}

impl FilmSum {
    /// Adds one sample with filter weight `w`, clamped to the film's `max` component value;
    /// returns it as added (zero when it was not finite).
    #[inline]
    fn add(&mut self, l: Rgb, w: f32, max: f32) -> Rgb {
        let l = match admit(l, max) {
            Some(l) => l,
            None => {
                self.nonfinite += 1;
                Rgb::ZERO
            }
        };
        let w = w as f64;
        for c in 0..3 {
            self.rgb[c] += w * l[c] as f64;
        }
        self.weight += w;
        l
    }

    /// Adds another pixel's sums (a later pass of the same pixel).
    #[inline]
    fn merge(&mut self, o: &FilmSum) {
        for c in 0..3 {
            self.rgb[c] += o.rgb[c];
        }
        self.weight += o.weight;
        self.nonfinite += o.nonfinite;
    }
}

impl Spread {
    /// Counts one sample `l` (as the film added it).
    #[inline]
    fn add(&mut self, l: Rgb) {
        for c in 0..3 {
            let v = l[c] as f64;
            self.sum[c] += v;
            self.sum_sq[c] += v * v;
        }
        self.count += 1;
    }

    #[inline]
    fn merge(&mut self, o: &Spread) {
        for c in 0..3 {
            self.sum[c] += o.sum[c];
            self.sum_sq[c] += o.sum_sq[c];
        }
        self.count += o.count;
    }
}

impl PixelSum {
    /// Adds one sample with filter weight `w`, clamped to the film's `max` component value;
    /// the variance sums count it when `counted` (for a G-buffer, when the camera ray sees a
    /// surface, as pbrt-v4 counts).
    #[inline]
    fn add(&mut self, l: Rgb, w: f32, max: f32, counted: bool) {
        let l = self.film.add(l, w, max);
        if counted {
            self.spread.add(l);
        }
    }
}

/// The spectral film's bands: (count, λmin, λmax), or `None` for other films.
fn spectral_bands(scene: &Scene) -> Option<(usize, f32, f32)> {
    match scene.film.kind {
        FilmKind::Spectral { buckets, lambda_min, lambda_max } => Some((buckets as usize, lambda_min, lambda_max)),
        _ => None,
    }
}

/// The camera sample of sample `s` of `pixel`: the same values [`camera_ray`] uses.
fn camera_sample(scene: &Scene, sampler: &mut Sampler, pixel: UVec2, s: u32) -> CameraSample {
    sampler.start_pixel_sample(pixel, s, 0);
    // The wavelength dimension, unused here.
    sampler.skip_1d();
    get_camera_sample(sampler, pixel, &scene.filter, scene.camera_sample_use)
}

/// One whole-image sample from `method`, added to the film's pixels as the method hands
/// them over (a per-pixel copy of the sums was 96 bytes a pixel at the process's peak).
fn image_sample(
    scene: &Scene,
    method: &dyn ImageIntegrator,
    sampler: &Sampler,
    tiles: &[[u32; 4]],
    acc: &mut Accumulator,
    sample: u32,
) -> RayStats {
    let pass = ImagePass::new(scene, sampler, tiles, acc.origin, acc.width, sample);
    let max = scene.film.max_component_value;
    let gbuffer = matches!(scene.film.kind, FilmKind::GBuffer { .. });
    // One sampler to replay the camera samples with (not a clone per pixel).
    let mut replay = sampler.clone();
    let (origin, width) = (acc.origin, acc.width);
    let (pixels, spread, pairs) = (&mut acc.pixels, &mut acc.spread, &mut acc.pairs);
    method.sample_image(scene, &pass, &mut |PixelValue { index, weight, l, unbiased }| {
        let added = pixels[index as usize].add(l, weight, max);
        // The variance channels count samples whose camera ray (recomputed) sees a surface.
        if gbuffer {
            let pixel = origin + UVec2::new(index % width, index / width);
            let (ray, _, _) = camera_ray::<Rgb>(scene, &mut replay, pixel, sample);
            if ray.is_some_and(|c| gbuffer::sees_surface(scene, c.ray)) {
                spread[index as usize].add(added);
            }
        }
        if let Some(u) = unbiased {
            if pairs.is_empty() {
                pairs.resize(pixels.len(), combine::PairSums::default());
            }
            // U is taken as the film took L: clamped, and zero when not finite.
            pairs[index as usize].add(added, admit(u, max).unwrap_or(Rgb::ZERO), weight, sample);
        }
    })
}

/// What rendering one tile (or one whole-image sample) returns: per pixel its index and
/// sums, the spectral film's band sums of those pixels in the same order, and ray counts.
type TileResult = (Vec<(u32, PixelSum)>, Vec<f64>, RayStats);

/// The film being accumulated.
pub struct Accumulator {
    width: u32,
    height: u32,
    origin: UVec2,
    pixels: Vec<FilmSum>,
    /// Per pixel, the G-buffer's variance sums; empty for other films.
    spread: Vec<Spread>,
    /// The spectral film's bands: per pixel, Σ w·L of each band and then Σ w of each band.
    bands: Vec<f64>,
    /// Per pixel, the sums of the unbiased estimates a method hands over beside its own
    /// ([`PixelValue::unbiased`]); empty when it hands none.
    pairs: Vec<combine::PairSums>,
}

impl Accumulator {
    fn new(bounds: [u32; 4], bands: usize, gbuffer: bool) -> Accumulator {
        let (w, h) = (bounds[2] - bounds[0], bounds[3] - bounds[1]);
        let n = (w * h) as usize;
        Accumulator {
            width: w,
            height: h,
            origin: UVec2::new(bounds[0], bounds[1]),
            pixels: vec![FilmSum::default(); n],
            spread: if gbuffer { vec![Spread::default(); n] } else { Vec::new() },
            bands: vec![0.0; (w * h) as usize * 2 * bands],
            pairs: Vec::new(),
        }
    }

    /// The film's [`combine::outlook`], when a method hands it unbiased estimates beside its own.
    fn outlook(&self) -> Option<crate::integrators::Outlook> {
        (!self.pairs.is_empty()).then(|| combine::outlook(self.width as usize, &self.pairs)).flatten()
    }

    /// Adds pixel `i`'s sums over `count` samples of a paired method's unbiased estimate alone
    /// (taken per camera ray: [`ImageIntegrator::image_sample_pays`]).
    fn add_unpaired(&mut self, i: usize, film: &FilmSum, count: u32) {
        if self.pairs.is_empty() {
            self.pairs.resize(self.pixels.len(), combine::PairSums::default());
        }
        self.pairs[i].add_unpaired(film.rgb, film.weight, count);
        self.pixels[i].nonfinite += film.nonfinite;
    }

    /// pbrt-v4's spectral-film channels `S0.<λ>nm` (band centres, ',' for the decimal point as
    /// the OpenEXR spectral layout asks): each band's weighted mean radiance.
    fn band_channels(&self, (n, min, max): (usize, f32, f32)) -> Vec<(String, Vec<f32>)> {
        (0..n)
            .map(|b| {
                let centre = min + (b as f32 + 0.5) / n as f32 * (max - min);
                let name = format!("S0.{centre:.3}nm").replace('.', ",").replacen(',', ".", 1);
                let values = self
                    .bands
                    .chunks_exact(2 * n)
                    .map(|p| if p[n + b] > 0.0 { (p[b] / p[n + b]) as f32 } else { 0.0 })
                    .collect();
                (name, values)
            })
            .collect()
    }

    /// The image: each pixel's weighted mean, through `output` (the film's conversion to the
    /// output color space). Where the method handed unbiased estimates beside its own, the
    /// pixel is their combination ([`combine`]).
    fn image(&self, output: glam::DMat3) -> Image {
        let mut img = Image::new(self.width as usize, self.height as usize);
        let combined = (!self.pairs.is_empty())
            .then(|| combine::combine(self.width as usize, self.pixels.iter().map(|p| (p.rgb, p.weight)), &self.pairs));
        for (i, (o, p)) in img.pixels.iter_mut().zip(&self.pixels).enumerate() {
            let mean = match &combined {
                Some(c) => glam::DVec3::from_array(c[i]),
                None if p.weight != 0.0 => glam::DVec3::from_array(p.rgb) / p.weight,
                None => continue,
            };
            *o = (output * mean).as_vec3();
        }
        img
    }
}

impl Accumulator {
    /// pbrt-v4's `Variance.*` and `RelativeVariance.*` channels: the sample variance
    /// (unbiased) in sensor RGB of each pixel's samples that see a surface, and that over
    /// their mean.
    fn variance(&self, scene: &Scene) -> Vec<(String, Vec<f32>)> {
        // RGB transport applies the imaging ratio at output; spectral samples carry it.
        let k = match scene.transport.transport {
            Transport::Rgb => f64::from(scene.sensor.imaging_ratio()),
            Transport::Spectral => 1.0,
        };
        let mut out: Vec<(String, Vec<f32>)> = ["Variance.R", "Variance.G", "Variance.B"]
            .iter()
            .chain(&["RelativeVariance.R", "RelativeVariance.G", "RelativeVariance.B"])
            .map(|n| (n.to_string(), Vec::with_capacity(self.spread.len())))
            .collect();
        for p in &self.spread {
            let n = p.count as f64;
            for c in 0..3 {
                let mean = if n > 0.0 { k * p.sum[c] / n } else { 0.0 };
                let var =
                    if n > 1.0 { k * k * (p.sum_sq[c] - p.sum[c] * p.sum[c] / n).max(0.0) / (n - 1.0) } else { 0.0 };
                out[c].1.push(var as f32);
                out[3 + c].1.push(if mean != 0.0 { (var / mean) as f32 } else { 0.0 });
            }
        }
        out
    }
}

/// Renders samples `[first, first + count)` of every pixel in one tile.
#[allow(clippy::too_many_arguments)]
fn render_tile<C: RenderChannels>(
    scene: &Scene,
    integrator: &dyn Integrator,
    sampler: &mut Sampler,
    acc_origin: UVec2,
    acc_width: u32,
    tile: [u32; 4],
    first: u32,
    count: u32,
    out: &mut Vec<(u32, PixelSum)>,
    bands_out: &mut Vec<f64>,
    stats: &mut RayStats,
) {
    let max = scene.film.max_component_value;
    let gbuffer = matches!(scene.film.kind, FilmKind::GBuffer { .. });
    let bands = spectral_bands(scene);
    for y in tile[1]..tile[3] {
        for x in tile[0]..tile[2] {
            let pixel = UVec2::new(x, y);
            let mut sum = PixelSum::default();
            let band_start = bands_out.len();
            if let Some((n, ..)) = bands {
                bands_out.resize(band_start + 2 * n, 0.0);
            }
            for s in first..first + count {
                let (ray, mut lambda, weight) = camera_ray::<C>(scene, sampler, pixel, s);
                stats.camera += 1;
                let counted = !gbuffer || ray.is_some_and(|c| gbuffer::sees_surface(scene, c.ray));
                let l = match ray {
                    Some(c) => C::li(integrator, scene, c.ray, &mut lambda, sampler, stats) * c.weight,
                    None => C::ZERO,
                };
                if let Some(b) = bands {
                    l.add_to_bands(&lambda, weight, max, b, &mut bands_out[band_start..]);
                }
                sum.add(l.to_film(&lambda, &scene.sensor), weight, max, counted);
            }
            let index = (y - acc_origin.y) * acc_width + (x - acc_origin.x);
            out.push((index, sum));
        }
    }
}

fn tiles(bounds: [u32; 4]) -> Vec<[u32; 4]> {
    let mut v = Vec::new();
    let mut y = bounds[1];
    while y < bounds[3] {
        let mut x = bounds[0];
        while x < bounds[2] {
            v.push([x, y, (x + TILE).min(bounds[2]), (y + TILE).min(bounds[3])]);
            x += TILE;
        }
        y += TILE;
    }
    v
}

/// The film after one pass of a render, handed to [`render_with_passes`]'s callback.
pub struct Pass<'a> {
    /// Samples per pixel so far.
    pub spp: u32,
    /// Seconds spent rendering so far; time spent in the callback is not counted.
    pub seconds: f64,
    /// Whether this is the last pass.
    pub last: bool,
    acc: &'a Accumulator,
    output: glam::DMat3,
}

impl Pass<'_> {
    /// The image so far (what [`render`] would return if it stopped here).
    pub fn image(&self) -> Image {
        self.acc.image(self.output)
    }
}

/// Renders `scene` with `integrator`: to the scene's spp, or progressively for the time
/// budget (passes of 1, 1, 2, 4, ... up to 64 samples, the last ones cut to what the rest of
/// the budget holds, until the budget is spent or a ZSobol sampler reaches 65536 spp).
pub fn render(scene: &Scene, integrator: &dyn Integrator, options: &RenderOptions) -> RenderResult {
    render_with_passes(scene, integrator, options, &[], &mut |_| {})
}

/// [`render`], calling `on_pass` after every pass: checkpoints of a progressive render at no
/// extra rendering. Passes also end at each sample count in `pass_ends` (ascending), so a
/// caller can look at the image at chosen spp. The time `on_pass` takes is excluded from the
/// budget and from [`RenderResult::seconds`]. The image at a given spp is the same whatever
/// `pass_ends` is, up to the order of floating-point sums.
pub fn render_with_passes(
    scene: &Scene,
    integrator: &dyn Integrator,
    options: &RenderOptions,
    pass_ends: &[u32],
    on_pass: &mut dyn FnMut(&Pass<'_>),
) -> RenderResult {
    let start = Instant::now();
    // Time spent in `on_pass`, not counted as rendering.
    let mut paused = std::time::Duration::ZERO;
    let bounds = scene.pixel_bounds;
    let bands = spectral_bands(scene);
    let gbuffer = matches!(scene.film.kind, FilmKind::GBuffer { .. });
    let mut acc = Accumulator::new(bounds, bands.map_or(0, |b| b.0), gbuffer);
    let tiles = tiles(bounds);
    let full = UVec2::new(scene.film.resolution[0], scene.film.resolution[1]);
    let base_sampler = match options.time_budget {
        // A budget may take more samples than the scene asks for. ZSobol's sample index shares
        // its bits with the pixel's Morton code and pmj02bn's points come from sequences of
        // 2^16, so they get room for PROGRESSIVE_SPP samples (the render stops there); the
        // other samplers continue their sequences.
        Some(_) => {
            let pixel_samples = scene.sampler.pixel_samples.max(PROGRESSIVE_SPP);
            Sampler::new(&SamplerSettings { pixel_samples, ..scene.sampler.clone() }, full)
        }
        None => Sampler::new(&scene.sampler, full),
    };
    let target_spp = base_sampler.samples_per_pixel();
    let max_spp = match (&base_sampler, options.time_budget) {
        (Sampler::ZSobol(_) | Sampler::Pmj02bn(_), _) | (_, None) => target_spp,
        (_, Some(_)) => u32::MAX,
    };
    let rays = AtomicU64::new(0);
    let mut total_stats = RayStats::default();
    let progress = (!options.quiet).then(|| {
        let pb = indicatif::ProgressBar::new(if options.time_budget.is_some() {
            0
        } else {
            target_spp as u64 * tiles.len() as u64
        });
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} tile-passes, ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        pb
    });
    let mut spp_done = 0u32;
    let mut pass = 0u32;
    loop {
        let count = match options.time_budget {
            Some(_) if pass == 0 => 1,
            Some(t) => {
                // No more samples than the rest of the budget holds at the pace so far, so the
                // render overshoots the budget by about one sample's time, not one pass's.
                let seconds = (start.elapsed() - paused).as_secs_f64();
                let fit = ((t - seconds) * spp_done as f64 / seconds.max(1e-9)).max(1.0);
                spp_done.clamp(1, 64).min(fit as u32)
            }
            None => target_spp - spp_done,
        }
        .min(max_spp - spp_done);
        let count = match pass_ends.iter().find(|&&e| e > spp_done) {
            Some(&end) => count.min(end - spp_done),
            None => count,
        };
        if count == 0 {
            break;
        }
        // A whole-image method takes `count` samples of the whole image, one after another,
        // each added to the film before the next is taken (holding a pass's samples until its
        // end held up to 64 images' sums: memory growing with the pass length), for as long
        // as it says they pay; the rest of the pass, and any other method's, per camera ray.
        let mut per_ray_from = spp_done;
        let whole = integrator.whole_image();
        if let Some(method) = whole {
            while per_ray_from < spp_done + count && method.image_sample_pays(per_ray_from, &|| acc.outlook()) {
                let stats = image_sample(scene, method, &base_sampler, &tiles, &mut acc, per_ray_from);
                if let Some(pb) = &progress {
                    pb.inc(tiles.len() as u64);
                }
                rays.fetch_add(stats.total(), Ordering::Relaxed);
                total_stats.add(&stats);
                per_ray_from += 1;
            }
        }
        let per_ray = spp_done + count - per_ray_from;
        let results: Vec<TileResult> = if per_ray == 0 {
            Vec::new()
        } else {
            tiles
                .par_iter()
                .map(|tile| {
                    let mut sampler = base_sampler.clone();
                    let mut out = Vec::with_capacity(((tile[2] - tile[0]) * (tile[3] - tile[1])) as usize);
                    let mut stats = RayStats::default();
                    let mut band_sums = Vec::new();
                    let tile_fn = match scene.transport.transport {
                        Transport::Rgb => render_tile::<Rgb>,
                        Transport::Spectral => render_tile::<SampledSpectrum>,
                    };
                    tile_fn(
                        scene,
                        integrator,
                        &mut sampler,
                        acc.origin,
                        acc.width,
                        *tile,
                        per_ray_from,
                        per_ray,
                        &mut out,
                        &mut band_sums,
                        &mut stats,
                    );
                    if let Some(pb) = &progress {
                        pb.inc(per_ray as u64);
                    }
                    rays.fetch_add(stats.total(), Ordering::Relaxed);
                    (out, band_sums, stats)
                })
                .collect()
        };
        // A whole-image method's samples per camera ray carry its unbiased estimate alone.
        let unpaired = whole.is_some();
        for (out, band_sums, stats) in &results {
            total_stats.add(stats);
            for (i, s) in out {
                if unpaired {
                    acc.add_unpaired(*i as usize, &s.film, per_ray);
                    continue;
                }
                acc.pixels[*i as usize].merge(&s.film);
                if let Some(spread) = acc.spread.get_mut(*i as usize) {
                    spread.merge(&s.spread);
                }
            }
            // Each pixel of the tile, in order, has 2n band sums.
            if let Some((n, ..)) = bands {
                for ((i, _), sums) in out.iter().zip(band_sums.chunks_exact(2 * n)) {
                    let start = *i as usize * 2 * n;
                    for (a, b) in acc.bands[start..start + 2 * n].iter_mut().zip(sums) {
                        *a += b;
                    }
                }
            }
        }
        spp_done += count;
        pass += 1;
        let seconds = (start.elapsed() - paused).as_secs_f64();
        let last = match options.time_budget {
            Some(t) => seconds >= t || spp_done >= max_spp,
            None => spp_done >= target_spp,
        };
        let before = Instant::now();
        on_pass(&Pass { spp: spp_done, seconds, last, acc: &acc, output: scene.film_output() });
        paused += before.elapsed();
        if last {
            break;
        }
    }
    if let Some(pb) = progress {
        pb.finish_and_clear();
    }
    let mut image = acc.image(scene.film_output());
    if let FilmKind::GBuffer { world } = scene.film.kind {
        image.channels = gbuffer::channels(scene, &base_sampler, &acc, spp_done, world);
        image.channels.extend(acc.variance(scene));
    }
    if let Some(b) = bands {
        image.channels = acc.band_channels(b);
        image.metadata.insert("spectralLayoutVersion".into(), "1.0".into());
        image.metadata.insert("emissiveUnits".into(), "W.m^-2.sr^-1".into());
    }
    let nonfinite_samples = acc.pixels.iter().map(|p| p.nonfinite as u64).sum();
    RenderResult {
        image,
        spp: spp_done,
        seconds: (start.elapsed() - paused).as_secs_f64(),
        rays: total_stats,
        nonfinite_samples,
    }
}
