//! RGB or spectral transport: the first quantity of the scene that varies with wavelength,
//! among the materials shapes use and the media, decides `auto`; the spectral film needs
//! spectral transport.

use super::*;

/// What decides whether the scene is chromatic.
#[derive(Clone, Copy)]
pub(super) struct Chromatic<'a> {
    pub(super) materials: &'a [Material],
    pub(super) textures: &'a Textures,
    pub(super) material_ids: &'a dyn Fn(&MaterialRef) -> u32,
    pub(super) used_media: &'a std::collections::HashSet<&'a str>,
    pub(super) spectra: &'a SpectrumResolver<'a>,
}

/// The transport the scene renders with, and why.
pub(super) fn choose_transport(
    desc: &SceneDescription,
    opts: &BuildOptions,
    film: &FilmSettings,
    needs: &SceneNeeds,
    ctx: &Chromatic<'_>,
    subsurface: &[Option<SubsurfaceMedium>],
) -> Result<TransportChoice, Error> {
    let mode = match (&opts.spectral, &desc.options.spectral) {
        (Some(m), _) => *m,
        (None, Some(s)) => s.parse().map_err(|m: String| err(&desc.film.loc, m))?,
        (None, None) => SpectralMode::Auto,
    };
    let mut chromatic = first_chromatic(desc, ctx)?;
    if chromatic.is_none() {
        let shapes = desc.shapes.iter().chain(desc.instance_definitions.iter().flat_map(|d| d.shapes.iter()));
        chromatic = shapes
            .filter_map(|shape| subsurface[(ctx.material_ids)(&shape.material) as usize].as_ref())
            .find(|m| m.chromatic)
            .map(|m| format!("{}: subsurface material's sigma_a or sigma_s varies with wavelength", m.loc));
    }
    let mut transport = TransportChoice::new(mode, chromatic.as_deref());
    // The spectral film records spectra, which only spectral transport has.
    if let FilmKind::Spectral { .. } = film.kind {
        if mode == SpectralMode::Off {
            return Err(err(
                &desc.film.loc,
                "the spectral film records spectra: it needs spectral transport, not --spectral off",
            ));
        }
        if let Some(why) = needs.spectral_film_refusal {
            return Err(err(&desc.film.loc, why));
        }
        transport =
            TransportChoice { transport: Transport::Spectral, reason: "the spectral film records spectra".into() };
    }
    Ok(transport)
}

/// The first quantity of the scene that varies with wavelength, named with its location:
/// a material that a shape uses, or a medium the camera, a light or a boundary uses.
fn first_chromatic(desc: &SceneDescription, ctx: &Chromatic<'_>) -> Result<Option<String>, Error> {
    let Chromatic { materials, textures, material_ids, used_media, spectra } = *ctx;
    let shapes = desc.shapes.iter().chain(desc.instance_definitions.iter().flat_map(|d| d.shapes.iter()));
    for shape in shapes {
        let id = material_ids(&shape.material) as usize;
        if let Some(input) = materials.get(id).and_then(|m| m.chromatic_input(materials, textures)) {
            let loc = match &shape.material {
                MaterialRef::Index(i) => desc.materials.get(*i).map(|m| &m.loc),
                MaterialRef::Named(n) => desc.named_materials.iter().find(|m| &m.name == n).map(|m| &m.entity.loc),
            }
            .unwrap_or(&shape.entity.loc);
            return Ok(Some(format!("{loc}: material {input} varies with wavelength")));
        }
    }
    for m in desc.media.iter().filter(|m| used_media.contains(m.name.as_str())) {
        let settings = MediumSettings::from_entity(m)?;
        let cs = m.entity.color_space;
        let chromatic = match &settings.kind {
            MediumSpec::RgbGrid { sigma_a, sigma_s, .. } => [sigma_a, sigma_s]
                .iter()
                .filter_map(|g| g.as_ref())
                .any(|g| g.iter().any(|c| c[0] != c[1] || c[1] != c[2])),
            _ => {
                let unbounded =
                    |s: &SpectrumSpec| spectra.unbounded(s, cs).map_err(|x| err(&m.entity.loc, x.to_string()));
                !unbounded(&settings.sigma_a)?.is_constant() || !unbounded(&settings.sigma_s)?.is_constant()
            }
        };
        if chromatic {
            return Ok(Some(format!("{}: medium \"{}\" has chromatic sigma_a or sigma_s", m.entity.loc, m.name)));
        }
    }
    Ok(None)
}
