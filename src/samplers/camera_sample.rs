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

/// Which of a camera sample's values the scene uses. pbrt-v4 draws the time and the lens
/// position for every camera ray; a scene where nothing moves has no use for the time, and a
/// camera without a lens none for the lens position. Values not used are skipped
/// ([`Sampler::skip_1d`]), so the same dimensions follow them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraSampleUse {
    /// Something moves over the shutter interval.
    pub time: bool,
    /// The camera samples a lens (thin lens or realistic).
    pub lens: bool,
}

impl CameraSampleUse {
    /// Every value drawn, as pbrt-v4 draws them.
    pub const ALL: CameraSampleUse = CameraSampleUse { time: true, lens: true };
}

/// pbrt-v4's `GetCameraSample`: the pixel-2D dimensions pick a filter offset around the
/// pixel centre, then one dimension gives the time and two the lens position (½ and the
/// lens centre where `uses` says the scene has no use for them). Call right after
/// [`Sampler::start_pixel_sample`] so these are dimensions 0 to 4, as in pbrt.
pub fn get_camera_sample(sampler: &mut Sampler, pixel: UVec2, filter: &Filter, uses: CameraSampleUse) -> CameraSample {
    let fs = filter.sample(sampler.get_pixel_2d());
    let time = if uses.time {
        sampler.get_1d()
    } else {
        sampler.skip_1d();
        0.5
    };
    let p_lens = if uses.lens {
        sampler.get_2d()
    } else {
        sampler.skip_2d();
        Vec2::splat(0.5)
    };
    CameraSample { p_film: pixel.as_vec2() + fs.offset + Vec2::splat(0.5), time, p_lens, filter_weight: fs.weight }
}
