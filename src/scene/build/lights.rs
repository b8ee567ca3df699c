//! Lights of a scene: area lights' radiance and emission images, and every light source.

use super::*;

/// The factor pbrt-v4 scales an image infinite light by for an `illuminance` of `ev`: `ev`
/// over its reference illuminance of the image as read from `path` (the light's own `scale`
/// multiplies on top, as in pbrt-v4).
pub(super) fn illuminance_factor(
    ev: f32,
    path: Option<&std::path::Path>,
    image: &crate::imageio::Image,
) -> Result<f32, String> {
    let ordered = match path {
        Some(p) => crate::imageio::pbrt_channel_order(p)?,
        None => None,
    };
    let values = ordered.as_deref().unwrap_or(&image.pixels);
    let k_e = crate::lights::reference_illuminance(values, image.width, image.height);
    Ok(if k_e > 0.0 { ev / k_e } else { 1.0 })
}

/// An area light's radiance `L` (with an image, the factor its texels are scaled by) for a
/// primitive of `area`: pbrt-v4's `power` makes the primitive emit that many watts, counting
/// an image by its mean luminance.
pub(super) fn area_light_radiance(
    settings: &AreaLightSettings,
    image: Option<&EmissionImage>,
    e: &nimbus_parser::Entity,
    area: f32,
    spectra: &SpectrumResolver<'_>,
) -> Result<SpectrumValue, Error> {
    let l = match image {
        Some(_) => SpectrumValue::constant(1.0),
        None => spectra.illuminant(&settings.radiance, e.color_space).map_err(|m| err(&e.loc, m.to_string()))?,
    };
    let mut scale = settings.scale;
    if let Some(phi) = settings.power {
        let mean = image.map_or(1.0, |i| i.mean_luminance());
        let k_e = mean * if settings.two_sided { 2.0 } else { 1.0 } * area * std::f32::consts::PI;
        if k_e > 0.0 {
            scale *= phi / k_e;
        }
    }
    Ok(l.scaled(scale))
}

/// An area light's emission image, read once for all of a shape's primitives. RGB transport
/// converts each texel into the film's RGB (through its sensor) once, as it does for `L`.
pub(super) fn emission_image(
    settings: &AreaLightSettings,
    e: &nimbus_parser::Entity,
    spectra: &SpectrumResolver<'_>,
    rgb_transport: bool,
) -> Result<Option<Arc<EmissionImage>>, Error> {
    let Some(path) = &settings.image else { return Ok(None) };
    let loc = e.params.loc("filename").unwrap_or(&e.loc);
    let what = |m: crate::error::Error| err(loc, format!("area light image {}: {m}", nimbus_parser::loc_shown(path)));
    let image = crate::imageio::read_image(path).map_err(what)?;
    let mut image = EmissionImage::new(&image, e.color_space).map_err(what)?;
    if rgb_transport {
        image.map_pixels(|p| spectra.emitted_texel(p, e.color_space));
    }
    Ok(Some(Arc::new(image)))
}

/// The light `l`, or `None` for one that emits nothing (pbrt-v4 warns of it, and so do we, in
/// `warnings`, with every other conversion pbrt-v4 warns of).
pub(super) fn light(
    l: &nimbus_parser::LightEntity,
    spectra: &SpectrumResolver<'_>,
    transport: Transport,
    medium: u32,
    render_from_world: &glam::Affine3A,
    warnings: &mut Vec<Warning>,
) -> Result<Option<Light>, Error> {
    let e = &l.entity;
    let settings = LightSettings::from_entity(l)?;
    // An infinite light's directions: pbrt-v4 places samples by one frame and looks
    // directions up by another (see `direction_frames`); the others are placed by the affine.
    let (world, lookup) = match &settings.kind {
        LightSpec::Infinite { filename, .. } => {
            let f = direction_frames(&l.world_from_light.start, render_from_world, &e.loc)?;
            // A uniform sky, or a portal's 1x1 image of L, has no orientation to get wrong.
            if f.bent && filename.is_some() {
                warnings.push(Warning::new(
                    &e.loc,
                    "infinite light under a projective transform: pbrt-v4 looks its directions up through the \
                     inverse's 3x3 but places its light samples through the transform's own 3x3, unnormalised, so \
                     its image mixes two skies; nimbus renders the sky pbrt-v4's camera rays see, sampled \
                     consistently (the two agree only with the camera at the origin)",
                ));
            }
            (f.forward, f.inverse)
        }
        _ => {
            let a = affine(&l.world_from_light.start, &e.loc)?;
            (a, a.inverse())
        }
    };
    let rgb = |s: &SpectrumSpec| spectra.illuminant(s, e.color_space).map_err(|m| err(&e.loc, m.to_string()));
    let kind = match &settings.kind {
        LightSpec::Point { intensity, from, power } => {
            let mut scale = settings.scale;
            if let Some(phi) = power {
                scale *= phi / (4.0 * std::f32::consts::PI);
            }
            LightKind::Point { p: world.transform_point3(Vec3::from(*from)), i: rgb(intensity)?.scaled(scale) }
        }
        LightSpec::Goniometric { intensity, filename, power } => {
            let Some(path) = filename else {
                // pbrt-v4 warns and the light emits nothing; nimbus says so and leaves it out.
                warnings.push(Warning::new(
                    &e.loc,
                    "No \"filename\" parameter provided for goniometric light (it emits nothing).",
                ));
                return Ok(None);
            };
            let image = crate::lights::goniometric::GoniometricImage::read(path, &world)
                .map_err(|m| err(&e.loc, format!("goniometric light: {m}")))?;
            let mut scale = settings.scale;
            if let Some(phi) = power {
                let k_e = 4.0 * std::f32::consts::PI * image.mean();
                if k_e <= 0.0 {
                    return Err(err(&e.loc, "goniometric light: \"power\" is given but its image is black"));
                }
                scale *= phi / k_e;
            }
            LightKind::Goniometric {
                p: world.transform_point3(Vec3::ZERO),
                i: rgb(intensity)?.scaled(scale),
                image: std::sync::Arc::new(image),
            }
        }
        LightSpec::Projection { filename, fov, power } => {
            let image = crate::lights::projection::ProjectionImage::read(filename, *fov, &world)
                .map_err(|m| err(&e.loc, format!("projection light: {m}")))?;
            let mut scale = settings.scale;
            if let Some(phi) = power {
                // pbrt-v4's k_e: the image's luminance over the frustum's solid angle.
                let k_e = crate::color::luminance(image.power_rgb());
                if k_e <= 0.0 {
                    return Err(err(&e.loc, "projection light: \"power\" is given but its image is black"));
                }
                scale *= phi / k_e;
            }
            LightKind::Projection { p: world.transform_point3(Vec3::ZERO), scale, image: std::sync::Arc::new(image) }
        }
        LightSpec::Spot { intensity, from, to, cone_angle, cone_delta_angle, power } => {
            let cos_end = cone_angle.to_radians().cos();
            let cos_start = (cone_angle - cone_delta_angle).to_radians().cos();
            let mut scale = settings.scale;
            if let Some(phi) = power {
                let k_e = 2.0 * std::f32::consts::PI * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0);
                scale *= phi / k_e;
            }
            let p = world.transform_point3(Vec3::from(*from));
            let dir = world.transform_vector3(Vec3::from(*to) - Vec3::from(*from));
            if dir.length_squared() == 0.0 {
                return Err(err(&e.loc, "spot light: \"from\" and \"to\" are the same point"));
            }
            LightKind::Spot {
                p,
                frame: Frame::from_z(dir.normalize()),
                i: rgb(intensity)?.scaled(scale),
                cos_falloff_start: cos_start,
                cos_falloff_end: cos_end,
            }
        }
        LightSpec::Distant { radiance, from, to, illuminance } => {
            let w = world.transform_vector3(Vec3::from(*from) - Vec3::from(*to)).normalize();
            let scale = settings.scale * illuminance.unwrap_or(1.0);
            LightKind::Distant { w, l: rgb(radiance)?.scaled(scale) }
        }
        LightSpec::Infinite { radiance, filename, illuminance, portal: Some(corners) } => {
            // pbrt-v4 renders `L` with a portal as a 1×1 image of its RGB.
            let mut cs = e.color_space;
            let image = match (radiance, filename) {
                (_, Some(path)) => crate::imageio::read_image(path).map_err(|m| err(&e.loc, m))?,
                (Some(SpectrumSpec::Rgb(c)), None) => {
                    let mut image = crate::imageio::Image::new(1, 1);
                    image.pixels[0] = Rgb::from(*c);
                    image
                }
                (Some(spec), None) => {
                    // Any other spectrum becomes sRGB through its XYZ, as pbrt-v4 makes it (with
                    // its warning): not normalised to 1 nit, as the same `L` without a portal is.
                    let loc = e.params.loc("L").unwrap_or(&e.loc);
                    let rgb = crate::spectra::srgb_of_spectrum(spec).map_err(|m| err(loc, m.to_string()))?;
                    warnings.push(Warning::new(
                        loc,
                        "Converting non-RGB \"L\" parameter to RGB so that a portal light can be used.",
                    ));
                    cs = nimbus_parser::ColorSpace::Srgb;
                    let mut image = crate::imageio::Image::new(1, 1);
                    image.pixels[0] = rgb;
                    image
                }
                (None, None) => return Err(err(&e.loc, "infinite light without radiance or image")),
            };
            let mut scale = settings.scale;
            if let Some(ev) = illuminance {
                scale *= illuminance_factor(*ev, filename.as_deref(), &image).map_err(|m| err(&e.loc, m))?;
            }
            // The corners are world-space points (pbrt-v4 does not apply the light's transform
            // to them), the image is oriented by the light's transform: the frame pbrt-v4 looks
            // its directions up by, inverted.
            let loc = e.params.loc("portal").unwrap_or(&e.loc);
            let mut map = PortalMap::new(&image, cs, lookup.inverse(), scale, corners.map(Vec3::from))
                .map_err(|m| err(loc, format!("infinite light: {m}")))?;
            if transport == Transport::Rgb && !spectra.sensor.is_passthrough() {
                map.map_pixels(|p| spectra.emitted_texel(p, cs));
            }
            LightKind::PortalInfinite(Box::new(map))
        }
        LightSpec::Infinite { radiance: Some(r), illuminance, .. } => {
            let scale = settings.scale * illuminance.map_or(1.0, |ev| ev / std::f32::consts::PI);
            LightKind::UniformInfinite { l: rgb(r)?.scaled(scale) }
        }
        LightSpec::Infinite { radiance: None, filename: Some(path), illuminance, .. } => {
            let cs = e.color_space;
            let image = crate::imageio::read_image(path).map_err(|m| err(&e.loc, m))?;
            let mut scale = settings.scale;
            if let Some(ev) = illuminance {
                scale *= illuminance_factor(*ev, Some(path), &image).map_err(|m| err(&e.loc, m))?;
            }
            let mut map =
                EnvironmentMap::new(&image, cs, world, scale).map_err(|m| err(&e.loc, m))?.with_lookup_frame(lookup);
            // RGB transport sees each texel's film RGB; through a camera sensor that is the
            // texel's illuminant spectrum seen by the sensor (spectral transport converts at
            // lookup).
            if transport == Transport::Rgb && !spectra.sensor.is_passthrough() {
                map.map_pixels(|p| spectra.emitted_texel(p, cs));
            }
            LightKind::ImageInfinite(Box::new(map))
        }
        LightSpec::Infinite { .. } => {
            return Err(err(&e.loc, "infinite light without radiance or image"));
        }
    };
    Ok(Some(Light { kind, medium }))
}
