//! The sample values of one camera ray, drawn in pbrt-v4's order.

use glam::{UVec2, Vec2};

use super::Sampler;
use crate::film::filter::Filter;

/// Where on the film, when, and where on the lens a camera ray starts (pbrt-v4's
/// `CameraSample`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSample {
    /// Film position in continuous raster coordinates (pixel (x, y) covers [x, x+1)×[y, y+1)).
    pub p_film: Vec2,
    /// Time within the shutter interval, in [0, 1).
    pub time: f32,
    /// Lens position sample, in [0, 1)².
    pub p_lens: Vec2,
    /// Weight of the filter sample, to multiply the radiance by when it is added to the film.
    pub filter_weight: f32,
}

/// pbrt-v4's `GetCameraSample`: the pixel-2D dimensions pick a filter offset around the
/// pixel centre, then one dimension gives the time and two the lens position. Call right
/// after [`Sampler::start_pixel_sample`] so these are dimensions 0 to 4, as in pbrt.
pub fn get_camera_sample(sampler: &mut Sampler, pixel: UVec2, filter: &Filter) -> CameraSample {
    let fs = filter.sample(sampler.get_pixel_2d());
    let time = sampler.get_1d();
    let p_lens = sampler.get_2d();
    CameraSample { p_film: pixel.as_vec2() + fs.offset + Vec2::splat(0.5), time, p_lens, filter_weight: fs.weight }
}
