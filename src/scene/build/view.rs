//! What the camera sees and how the film records it: film, camera, pixel bounds, sampler,
//! filter and sensor, with the command line's overrides.

use super::*;

/// The film, the camera and how pixels are sampled and recorded.
pub(super) struct View {
    pub(super) film: FilmSettings,
    pub(super) camera: Camera,
    pub(super) pixel_bounds: [u32; 4],
    pub(super) film_bounds: [u32; 4],
    pub(super) sampler: SamplerSettings,
    pub(super) filter: Filter,
    pub(super) sensor: PixelSensor,
}

/// Warnings for what pbrt-v4 does not animate.
pub(super) fn animation_warnings(desc: &SceneDescription, warnings: &mut Vec<Warning>) {
    // What pbrt-v4 does not animate it uses at the start of the motion, with these warnings.
    for l in desc.lights.iter().filter(|l| l.world_from_light.is_animated()) {
        warnings.push(Warning::new(&l.entity.loc, "Animated lights aren't supported. Using the start transform."));
    }
    for m in desc.media.iter().filter(|m| m.world_from_medium.is_animated()) {
        warnings.push(Warning::new(
            &m.entity.loc,
            "Animated transformation provided for medium. Only the start transform will be used.",
        ));
    }
    for t in desc.textures.iter().filter(|t| t.world_from_texture.is_animated()) {
        warnings.push(Warning::new(
            &t.entity.loc,
            "Animated world to texture transforms are not supported. Using the start transform.",
        ));
    }
}

/// The film, camera, sampler, filter and sensor, with `opts`' overrides (`--quick`, `--spp`,
/// `--seed`, `--cropwindow`, `--pixelbounds`).
pub(super) fn view(desc: &SceneDescription, opts: &BuildOptions, warnings: &mut Vec<Warning>) -> Result<View, Error> {
    let mut film = FilmSettings::from_entity(&desc.film)?;
    if opts.quick {
        film.resolution = [(film.resolution[0] / 4).max(1), (film.resolution[1] / 4).max(1)];
    }
    let film_cs = film.color_space;
    let camera_settings = CameraSettings::from_entity(&desc.camera)?;
    let world_from_camera = &desc.camera.world_from_camera;
    warnings.extend(camera_settings.aperture_warning(&desc.camera));
    let mut camera = Camera::new(&camera_settings, &world_from_camera.start, film.resolution, film.diagonal)
        .map_err(|m| err(&desc.camera.entity.loc, format!("realistic camera: {m}")))?;
    if world_from_camera.is_animated() {
        camera = camera.with_motion(motion_transform(world_from_camera, &desc.camera.entity.loc)?);
    }
    let pixel_bounds = pixel_bounds(&film, opts, &desc.film.loc)?;
    let film_opts = BuildOptions { pixel_bounds: None, crop_window: None, ..Default::default() };
    let film_bounds = self::pixel_bounds(&film, &film_opts, &desc.film.loc)?;
    let mut sampler = SamplerSettings::from_entity(&desc.sampler, desc.options.seed, warnings)?;
    // An explicit --spp is what the user asked for: --quick only quarters the scene's count.
    if let Some(spp) = opts.spp {
        sampler.pixel_samples = spp.max(1);
    } else if opts.quick {
        sampler.pixel_samples = (sampler.pixel_samples / 4).max(1);
    }
    if sampler.kind == crate::samplers::settings::SamplerKind::Pmj02bn {
        crate::samplers::settings::check_pmj02bn_samples(sampler.pixel_samples, &desc.sampler.loc)?;
    }
    if let Some(seed) = opts.seed {
        sampler.seed = seed;
    }
    let filter = Filter::new(&FilterSettings::from_entity(&desc.filter)?);

    // The film's sensor (pbrt-v4's imaging ratio: exposure time × ISO / 100).
    let exposure = camera_settings.shutter_close - camera_settings.shutter_open;
    let sensor = PixelSensor::new(&film.sensor, film.white_balance, film.iso, exposure, film_cs)
        .map_err(|m| err(desc.film.params.loc("sensor").unwrap_or(&desc.film.loc), m))?;
    Ok(View { film, camera, pixel_bounds, film_bounds, sampler, filter, sensor })
}

pub(super) fn pixel_bounds(film: &FilmSettings, opts: &BuildOptions, loc: &FileLoc) -> Result<[u32; 4], Error> {
    let [w, h] = film.resolution;
    let from_crop = |c: [f32; 4]| -> [i64; 4] {
        [
            (w as f32 * c[0]).ceil() as i64,
            (h as f32 * c[2]).ceil() as i64,
            (w as f32 * c[1]).ceil() as i64,
            (h as f32 * c[3]).ceil() as i64,
        ]
    };
    let b: [i64; 4] = if let Some([x0, x1, y0, y1]) = opts.pixel_bounds.or(film.pixel_bounds) {
        [x0 as i64, y0 as i64, x1 as i64, y1 as i64]
    } else if let Some(c) = opts.crop_window.or(film.crop_window) {
        from_crop(c)
    } else {
        [0, 0, w as i64, h as i64]
    };
    let clamped = [b[0].clamp(0, w as i64), b[1].clamp(0, h as i64), b[2].clamp(0, w as i64), b[3].clamp(0, h as i64)];
    if clamped[0] >= clamped[2] || clamped[1] >= clamped[3] {
        return Err(err(loc, format!("the pixel bounds {b:?} select no pixels of the {w}x{h} image")));
    }
    Ok([clamped[0] as u32, clamped[1] as u32, clamped[2] as u32, clamped[3] as u32])
}
