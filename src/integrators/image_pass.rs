//! What a render hands a method: the camera ray of each pixel sample, drawn in pbrt-v4's
//! order, and for whole-image methods ([`super::ImageIntegrator`]) one pass of every pixel's
//! camera ray at once. `render/` drives these; the methods only receive them.

use glam::UVec2;
use rayon::prelude::*;

use super::Integrator;
use super::common::RayStats;
use crate::camera::CameraRay;
use crate::channels::Channels;
use crate::color::Rgb;
use crate::film::channels::FilmChannels;
use crate::film::settings::FilmKind;
use crate::geometry::Ray;
use crate::samplers::{Sampler, get_camera_sample};
use crate::scene::Scene;
use crate::spectra::{SampledSpectrum, SampledWavelengths};

/// The channels a method can be asked for: how to ask an integrator for them (per camera
/// ray), on top of how they reach the film.
pub trait RenderChannels: FilmChannels {
    /// The integrator's estimate along `ray` in these channels.
    fn li(
        integrator: &dyn Integrator,
        scene: &Scene,
        ray: Ray,
        lambda: &mut Self::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> Self;
}

impl RenderChannels for Rgb {
    #[inline]
    fn li(
        integrator: &dyn Integrator,
        scene: &Scene,
        ray: Ray,
        lambda: &mut (),
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> Rgb {
        integrator.li_rgb(scene, ray, lambda, sampler, stats)
    }
}

impl RenderChannels for SampledSpectrum {
    #[inline]
    fn li(
        integrator: &dyn Integrator,
        scene: &Scene,
        ray: Ray,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> SampledSpectrum {
        integrator.li_spectral(scene, ray, lambda, sampler, stats)
    }
}

/// The camera ray of sample `s` of `pixel` (`None` when a realistic camera's lens stops it),
/// its wavelengths and its filter weight, drawn in pbrt-v4's order.
#[inline]
pub fn camera_ray<C: Channels>(
    scene: &Scene,
    sampler: &mut Sampler,
    pixel: UVec2,
    s: u32,
) -> (Option<CameraRay>, C::Lambda, f32) {
    sampler.start_pixel_sample(pixel, s, 0);
    // pbrt-v4 draws the wavelengths first; RGB skips the same dimension so the two
    // representations see the same samples afterwards.
    let u = if C::SAMPLES_WAVELENGTHS && !scene.disable_wavelength_jitter {
        sampler.get_1d()
    } else {
        sampler.skip_1d();
        0.5
    };
    // The spectral film samples its range uniformly, as pbrt-v4's does.
    let lambda = match scene.film.kind {
        FilmKind::Spectral { lambda_min, lambda_max, .. } => C::sample_lambda_uniform(u, lambda_min, lambda_max),
        _ => C::sample_lambda(u),
    };
    let cs = get_camera_sample(sampler, pixel, &scene.filter, scene.camera_sample_use);
    (scene.camera.generate_ray(cs.p_film, cs.p_lens, scene.camera.time(cs.time)), lambda, cs.filter_weight)
}

/// One whole-image sample: every pixel's camera ray for one sample index, handed to an
/// [`ImageIntegrator`], in the representation the method asks for.
pub struct ImagePass<'a> {
    scene: &'a Scene,
    sampler: &'a Sampler,
    tiles: &'a [[u32; 4]],
    origin: UVec2,
    width: u32,
    sample: u32,
}

/// A camera ray of an [`ImagePass`].
#[derive(Clone, Copy, Debug)]
pub struct PixelRay {
    /// The pixel's index in the film (row-major within the pixel bounds).
    pub index: u32,
    /// The filter weight of the camera sample.
    pub weight: f32,
    /// The camera ray, or `None` when a realistic camera's lens stopped it: the sample then
    /// brings back nothing, but its filter weight still counts (as in pbrt-v4).
    pub ray: Option<CameraRay>,
}

impl<'a> ImagePass<'a> {
    /// Sample `sample` of the pixels of `tiles` (film pixel bounds starting at `origin`,
    /// `width` pixels wide), drawn from `sampler`.
    pub fn new(
        scene: &'a Scene,
        sampler: &'a Sampler,
        tiles: &'a [[u32; 4]],
        origin: UVec2,
        width: u32,
        sample: u32,
    ) -> ImagePass<'a> {
        ImagePass { scene, sampler, tiles, origin, width, sample }
    }

    /// The sample index (0 for the first sample of every pixel).
    pub fn sample_index(&self) -> u32 {
        self.sample
    }

    /// The number of pixels the pass traces (one camera ray each).
    pub fn pixel_count(&self) -> usize {
        self.tiles.iter().map(|t| (t[2] - t[0]) as usize * (t[3] - t[1]) as usize).sum()
    }

    /// Traces every pixel's camera ray with `f`, in parallel over tiles. Each tile starts a
    /// `T` with `init(tile index)` and ends with `done(tile index, T)`, which runs on the
    /// tile's thread as soon as the tile is traced (so a caller can hand each tile storage from
    /// a pool and give it back, or move a tile's results out while other tiles are running);
    /// `done`'s results come in tile order, pixels in scanline order within a tile, whatever
    /// the thread count. `f` gets the pixel's sampler positioned after the camera sample's
    /// dimensions, as a per-ray integrator's `li` does.
    pub fn trace_pixels<C: RenderChannels, T, U: Send>(
        &self,
        init: impl Fn(usize) -> T + Sync,
        f: impl Fn(&mut T, PixelRay, &mut C::Lambda, &mut Sampler, &mut RayStats) + Sync,
        done: impl Fn(usize, T) -> U + Sync,
    ) -> (Vec<U>, RayStats) {
        let results: Vec<(U, RayStats)> = self
            .tiles
            .par_iter()
            .enumerate()
            .map(|(i, tile)| {
                let mut sampler = self.sampler.clone();
                let mut stats = RayStats::default();
                let mut t = init(i);
                for y in tile[1]..tile[3] {
                    for x in tile[0]..tile[2] {
                        let pixel = UVec2::new(x, y);
                        let (ray, mut lambda, weight) = camera_ray::<C>(self.scene, &mut sampler, pixel, self.sample);
                        stats.camera += 1;
                        let index = (y - self.origin.y) * self.width + (x - self.origin.x);
                        f(&mut t, PixelRay { index, weight, ray }, &mut lambda, &mut sampler, &mut stats);
                    }
                }
                (done(i, t), stats)
            })
            .collect();
        let mut stats = RayStats::default();
        let out = results
            .into_iter()
            .map(|(t, s)| {
                stats.add(&s);
                t
            })
            .collect();
        (out, stats)
    }
}
