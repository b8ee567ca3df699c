//! Participating media of a scene: only those the camera, lights or boundaries use.

use super::*;

/// Names of the media that the camera, lights or boundary surfaces refer to.
pub(super) fn used_media(desc: &SceneDescription) -> std::collections::HashSet<&str> {
    let shapes = desc.shapes.iter().chain(desc.instance_definitions.iter().flat_map(|d| d.shapes.iter()));
    let from_shapes = shapes.filter_map(|s| s.medium_interface.as_ref()).flat_map(|mi| [&mi.inside, &mi.outside]);
    std::iter::once(&desc.camera.medium)
        .chain(desc.lights.iter().map(|l| &l.medium))
        .chain(from_shapes)
        .filter_map(|n| n.as_deref())
        .collect()
}

/// Creates a render-time medium from its settings.
pub(super) fn build_medium(
    m: &nimbus_parser::MediumEntity,
    settings: &MediumSettings<'_>,
    spectra: &SpectrumResolver<'_>,
    transport: Transport,
) -> Result<Medium, Error> {
    let e = &m.entity;
    let cs = e.color_space;
    let unbounded = |s: &SpectrumSpec| spectra.unbounded(s, cs).map_err(|x| err(&e.loc, x.to_string()));
    let sigma_a = unbounded(&settings.sigma_a)?.scaled(settings.scale);
    let sigma_s = unbounded(&settings.sigma_s)?.scaled(settings.scale);
    let le = match &settings.le {
        Some(s) => spectra.illuminant(s, cs).map_err(|x| err(&e.loc, x.to_string()))?.scaled(settings.le_scale),
        None => SpectrumValue::ZERO,
    };
    // A homogeneous medium has no use for its transform: pbrt-v4 goes on past a singular one.
    let world = match settings.kind {
        MediumSpec::Homogeneous => Affine3A::IDENTITY,
        _ => affine(&m.world_from_medium.start, &e.loc)?,
    };
    let g = settings.g;
    let dense = |n: [u32; 3], v: &[f32]| {
        DenseGrid::new(glam::UVec3::from(n), v.to_vec()).ok_or_else(|| err(&e.loc, "grid size mismatch"))
    };
    Ok(match &settings.kind {
        MediumSpec::Homogeneous => Medium::homogeneous(m.name.clone(), sigma_a, sigma_s, le, g),
        MediumSpec::UniformGrid { n, bounds, density, temperature, le_scale_grid } => {
            // pbrt-v4 keeps `Lescale` as a grid; without one it is a single sample of 1.
            let scale_grid = || match le_scale_grid {
                Some(v) => dense(*n, v),
                None => dense([1, 1, 1], &[1.0]),
            };
            let emission = match temperature {
                Some(t) => Emission::Temperature {
                    grid: Field::Dense(dense(*n, t.values.unwrap_or(&[]))?),
                    offset: t.offset,
                    scale: t.scale,
                    le_scale: settings.le_scale,
                    scale_grid: Some(scale_grid()?),
                    table: Box::new(BlackbodyRgbTable::for_sensor(spectra.sensor)),
                },
                None if !le.is_zero() => Emission::Radiance { le, scale: scale_grid()? },
                None => Emission::None,
            };
            let b = Bounds3::new(Vec3::from(bounds[0]), Vec3::from(bounds[1]));
            Medium::grid(
                m.name.clone(),
                world,
                b,
                Density::Field(Field::Dense(dense(*n, density)?)),
                sigma_a,
                sigma_s,
                emission,
                g,
            )
        }
        MediumSpec::Cloud { bounds, density, wispiness, frequency } => {
            let b = Bounds3::new(Vec3::from(bounds[0]), Vec3::from(bounds[1]));
            let cloud = crate::media::cloud::Cloud { density: *density, wispiness: *wispiness, frequency: *frequency };
            // pbrt-v4's procedural cloud does not emit.
            let emission = Emission::None;
            Medium::grid(m.name.clone(), world, b, Density::Cloud(cloud), sigma_a, sigma_s, emission, g)
        }
        MediumSpec::RgbGrid { n, bounds, sigma_a: ga, sigma_s: gs, le: gl } => {
            let scale = settings.scale;
            // Voxels packed for the transport: film RGB, or the sigmoid polynomial and scale of
            // the scene's RGB as a spectrum (pbrt-v4's SampledGrid of RGB spectra).
            let spectral = transport == Transport::Spectral;
            let rgb_grid = |v: &[[f32; 3]], f: &(dyn Fn(Rgb) -> Vec4 + Sync)| {
                use rayon::prelude::*;
                DenseGrid::new(glam::UVec3::from(*n), v.par_iter().map(|c| f(Rgb::from(*c))).collect())
                    .ok_or_else(|| err(&e.loc, "grid size mismatch"))
            };
            let coefficient = |c: Rgb| {
                let c = if spectral { c } else { spectra.grid_coefficient(c, cs) };
                pack_voxel(c * scale, RgbRole::Unbounded, cs, spectral)
            };
            let emitted = |c: Rgb| {
                let c = if spectral { c } else { spectra.emitted_texel(c, cs) };
                pack_voxel(c, RgbRole::Illuminant, cs, spectral)
            };
            let chromatic =
                [ga, gs].iter().filter_map(|g| g.as_ref()).any(|g| g.iter().any(|c| c[0] != c[1] || c[1] != c[2]));
            let sa = ga.map(|v| rgb_grid(v, &coefficient)).transpose()?;
            let ss = gs.map(|v| rgb_grid(v, &coefficient)).transpose()?;
            let le_grid = gl.map(|v| rgb_grid(v, &emitted)).transpose()?;
            let b = Bounds3::new(Vec3::from(bounds[0]), Vec3::from(bounds[1]));
            // pbrt-v4 does not normalise rgbgrid emission: an RGB illuminant spectrum whose film
            // RGB is ∫ȳ times the voxel's.
            let le_scale = settings.le_scale * crate::spectra::CIE_Y_INTEGRAL as f32;
            Medium::rgb_grid(m.name.clone(), world, b, sa, ss, le_grid, le_scale, cs, g, chromatic, spectral)
        }
        MediumSpec::Vdb { openvdb, filename, grid_name, temperature_name, temperature } => {
            let loc = e.params.loc("filename").unwrap_or(&e.loc);
            let file = VdbFile::open(filename, *openvdb).map_err(|x| err(loc, x.to_string()))?;
            let density = file.read_grid(grid_name).map_err(|x| err(loc, x.to_string()))?;
            // pbrt-v4 reads the temperature grid when the file has one.
            let emission = if file.has_grid(temperature_name) {
                let t = file.read_grid(temperature_name).map_err(|x| err(loc, x.to_string()))?;
                Emission::Temperature {
                    grid: Field::Sparse(Box::new(t)),
                    offset: temperature.offset,
                    scale: temperature.scale,
                    le_scale: settings.le_scale,
                    scale_grid: None,
                    table: Box::new(BlackbodyRgbTable::for_sensor(spectra.sensor)),
                }
            } else {
                Emission::None
            };
            let b = density.world_bounds();
            Medium::grid(
                m.name.clone(),
                world,
                b,
                Density::Field(Field::Sparse(Box::new(density))),
                sigma_a,
                sigma_s,
                emission,
                g,
            )
        }
    })
}

/// The scene's media, the named ones' indices, and each material's subsurface medium (or
/// `NONE`).
pub(super) struct Media {
    pub(super) media: Vec<Medium>,
    pub(super) ids: HashMap<String, u32>,
    pub(super) subsurface: Vec<u32>,
    pub(super) entry_coefficients: Vec<Option<EntryCoefficients>>,
}

/// Builds the media the camera, lights or boundary surfaces use (`used`), then one medium per
/// subsurface material (shapes sharing the material share it).
pub(super) fn build_media(
    desc: &SceneDescription,
    used: &std::collections::HashSet<&str>,
    spectra: &SpectrumResolver<'_>,
    transport: Transport,
    subsurface: &[Option<SubsurfaceMedium>],
) -> Result<Media, Error> {
    let mut media = Vec::new();
    let mut media_ids: HashMap<String, u32> = HashMap::new();
    for m in &desc.media {
        let settings = MediumSettings::from_entity(m)?;
        if used.contains(m.name.as_str()) {
            media_ids.insert(m.name.clone(), media.len() as u32);
            media.push(build_medium(m, &settings, spectra, transport)?);
        }
    }
    // A subsurface material's medium, one per material (shapes sharing it share it).
    let subsurface_media: Vec<u32> = subsurface
        .iter()
        .enumerate()
        .map(|(i, m)| match m {
            Some(m) => {
                let name = format!("subsurface material {i}");
                let mut medium = Medium::homogeneous(name, m.sigma_a, m.sigma_s, SpectrumValue::ZERO, m.g);
                medium.subsurface = true;
                medium.chromatic = m.chromatic;
                medium.from_entry = m.entered.is_some();
                media.push(medium);
                media.len() as u32 - 1
            }
            None => NONE,
        })
        .collect();
    // The media before them have their own coefficients.
    let mut entry_coefficients: Vec<Option<EntryCoefficients>> = Vec::new();
    if subsurface.iter().flatten().any(|m| m.entered.is_some()) {
        entry_coefficients = (0..media.len()).map(|_| None).collect();
        for (m, &i) in subsurface.iter().zip(&subsurface_media) {
            if let Some(m) = m {
                entry_coefficients[i as usize] = m.entered.clone();
            }
        }
    }
    Ok(Media { media, ids: media_ids, subsurface: subsurface_media, entry_coefficients })
}
