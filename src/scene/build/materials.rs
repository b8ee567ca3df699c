//! Materials of a scene, their mixes resolved, and the media of subsurface materials.

use super::*;

pub(super) fn roughness(r: &Roughness, tb: &TextureBuilder, loc: &FileLoc) -> Result<RoughnessTex, Error> {
    Ok(RoughnessTex { u: tb.float(&r.u, loc)?, v: tb.float(&r.v, loc)?, remap: r.remap })
}

pub(super) fn eta_value(eta: &Eta, tb: &TextureBuilder, cs: ColorSpace, loc: &FileLoc) -> Result<SpectrumValue, Error> {
    tb.spectra.eta(eta, cs).map_err(|e| err(loc, e.to_string()))
}

pub(super) fn conductor_input(
    spec: &ConductorSpec,
    tb: &TextureBuilder,
    cs: ColorSpace,
    loc: &FileLoc,
) -> Result<ConductorInput, Error> {
    Ok(match spec {
        ConductorSpec::Reflectance(r) => ConductorInput::Reflectance(tb.spectrum(r, cs, loc)?),
        ConductorSpec::EtaK { eta: SpectrumInput::Value(eta), k: SpectrumInput::Value(k) } => {
            let c = tb.spectra.conductor(eta, k, cs).map_err(|m| err(loc, m.to_string()))?;
            ConductorInput::EtaK { eta: Tex::Const(c.eta), k: Tex::Const(c.k), scale: c.scale }
        }
        ConductorSpec::EtaK { eta, k } => {
            // Textured optical constants: used per channel as given.
            let as_tex = |s: &SpectrumInput| -> Result<Tex, Error> {
                Ok(match s {
                    SpectrumInput::Value(v) => {
                        let c = tb.spectra.conductor(v, v, cs).map_err(|m| err(loc, m.to_string()))?;
                        Tex::Const(c.eta)
                    }
                    t => tb.spectrum_as(t, cs, loc, true)?,
                })
            };
            ConductorInput::EtaK { eta: as_tex(eta)?, k: as_tex(k)?, scale: SpectrumValue::constant(1.0) }
        }
    })
}

/// Points each `mix` material at its two named parts: pbrt-v4 requires them to exist and
/// not be `interface`; nimbus also refuses a mix that contains itself.
pub(super) fn resolve_mixes(
    desc: &SceneDescription,
    materials: &mut [Material],
    named: &HashMap<String, u32>,
) -> Result<(), Error> {
    let entities = desc.materials.iter().chain(desc.named_materials.iter().map(|m| &m.entity));
    let mut parts = Vec::new();
    for (i, e) in entities.enumerate() {
        if e.name != "mix" {
            continue;
        }
        let names = e.params.get_strings("materials")?;
        let loc = e.params.loc("materials").unwrap_or(&e.loc);
        let mut pair = [0u32; 2];
        for (slot, name) in pair.iter_mut().zip(names) {
            let Some(&id) = named.get(name) else {
                return Err(err(loc, format!("mix: named material \"{name}\" not found")));
            };
            if materials[id as usize].is_interface() {
                return Err(err(
                    loc,
                    format!("mix: \"{name}\" is an \"interface\" material, which cannot be part of a mix"),
                ));
            }
            *slot = id;
        }
        parts.push((i, pair, loc));
    }
    for &(i, pair, _) in &parts {
        if let Material::Mix { materials: p, .. } = &mut materials[i] {
            *p = pair;
        }
    }
    // A mix reachable from itself would never resolve.
    for &(i, _, loc) in &parts {
        let mut stack = vec![(i as u32, 0usize)];
        while let Some((m, depth)) = stack.pop() {
            if let Material::Mix { materials: pair, .. } = &materials[m as usize] {
                for &p in pair {
                    if p as usize == i || depth > materials.len() {
                        return Err(err(loc, "mix: the material contains itself"));
                    }
                    stack.push((p, depth + 1));
                }
            }
        }
    }
    Ok(())
}

/// The homogeneous medium inside a `subsurface` material's boundary.
pub(super) struct SubsurfaceMedium {
    /// Its coefficients, when they are the same everywhere (zero otherwise).
    pub(super) sigma_a: SpectrumValue,
    pub(super) sigma_s: SpectrumValue,
    /// Where an input is a texture: the coefficients as functions of the entry point.
    pub(super) entered: Option<EntryCoefficients>,
    /// The coefficients differ between wavelengths somewhere.
    pub(super) chromatic: bool,
    pub(super) g: f32,
    pub(super) loc: FileLoc,
}

/// The medium a `subsurface` material describes: constant coefficients where every input is
/// a value, else the inputs evaluated where paths enter.
fn subsurface_medium(
    coefficients: &SubsurfaceCoefficients,
    scale: f32,
    g: f32,
    eta: f32,
    tb: &TextureBuilder,
    cs: ColorSpace,
    loc: &FileLoc,
) -> Result<SubsurfaceMedium, Error> {
    let medium = |sigma_a: SpectrumValue, sigma_s: SpectrumValue| SubsurfaceMedium {
        chromatic: !sigma_a.is_constant() || !sigma_s.is_constant(),
        sigma_a,
        sigma_s,
        entered: None,
        g,
        loc: loc.clone(),
    };
    if coefficients.textured() {
        let unbounded = |i: &SpectrumInput| tb.spectrum_as(i, cs, loc, true);
        let inputs = match coefficients {
            SubsurfaceCoefficients::Sigma { sigma_a, sigma_s } => {
                SubsurfaceInputs::Sigma { sigma_a: unbounded(sigma_a)?, sigma_s: unbounded(sigma_s)? }
            }
            SubsurfaceCoefficients::Reflectance { reflectance, mfp } => SubsurfaceInputs::Reflectance {
                reflectance: tb.spectrum(reflectance, cs, loc)?,
                mfp: unbounded(mfp)?,
                table: Arc::new(crate::materials::diffusion::DiffusionTable::new(g, eta)),
            },
        };
        let chromatic = match &inputs {
            SubsurfaceInputs::Sigma { sigma_a: a, sigma_s: b }
            | SubsurfaceInputs::Reflectance { reflectance: a, mfp: b, .. } => {
                tb.textures.is_chromatic(*a) || tb.textures.is_chromatic(*b)
            }
        };
        return Ok(SubsurfaceMedium {
            entered: Some(EntryCoefficients { inputs, scale }),
            chromatic,
            ..medium(SpectrumValue::ZERO, SpectrumValue::ZERO)
        });
    }
    let value = |i: &SpectrumInput| match i {
        SpectrumInput::Value(spec) => Ok(spec.clone()),
        SpectrumInput::Texture(name) => Err(err(loc, format!("subsurface: texture \"{name}\" read as a value"))),
    };
    let unbounded = |s: &SpectrumSpec| tb.spectra.unbounded(s, cs).map_err(|x| err(loc, x.to_string()));
    Ok(match coefficients {
        SubsurfaceCoefficients::Sigma { sigma_a, sigma_s } => {
            medium(unbounded(&value(sigma_a)?)?.scaled(scale), unbounded(&value(sigma_s)?)?.scaled(scale))
        }
        SubsurfaceCoefficients::Reflectance { reflectance, mfp } => {
            // pbrt-v4 inverts per sampled wavelength; nimbus per RGB channel of the
            // reflectance, the coefficients then upsampled as unbounded RGB.
            let r = tb.spectra.albedo(&value(reflectance)?, cs).map_err(|x| err(loc, x.to_string()))?.rgb;
            let mfp = unbounded(&value(mfp)?)?.rgb * scale;
            let table = crate::materials::diffusion::DiffusionTable::new(g, eta);
            let (mut a, mut s) = ([0.0f32; 3], [0.0f32; 3]);
            for c in 0..3 {
                (a[c], s[c]) = table.coefficients(r[c].clamp(0.0, 1.0), mfp[c].max(f32::MIN_POSITIVE));
            }
            medium(unbounded(&SpectrumSpec::Rgb(a))?, unbounded(&SpectrumSpec::Rgb(s))?)
        }
    })
}

/// A material as the scene uses it: what scatters at its surface, how it perturbs the
/// shading geometry, and the medium behind it for `subsurface`.
pub(super) struct BuiltMaterial {
    pub(super) material: Material,
    pub(super) shading: ShadingPerturbation,
    pub(super) subsurface: Option<SubsurfaceMedium>,
}

/// Measured BRDFs read so far, by file: materials naming the same file share its tables.
pub(super) type MeasuredCache =
    std::cell::RefCell<HashMap<std::path::PathBuf, std::sync::Arc<crate::materials::measured::MeasuredData>>>;

pub(super) fn material(
    e: &nimbus_parser::Entity,
    tb: &TextureBuilder,
    measured: &MeasuredCache,
    warnings: &mut Vec<Warning>,
) -> Result<BuiltMaterial, Error> {
    let settings = MaterialSettings::from_entity(e, warnings)?;
    let cs = e.color_space;
    let loc = &e.loc;
    // pbrt-v4 applies the normal map when a material has both.
    let shading = if let Some(path) = &settings.normal_map {
        let image = load_texture_image(path, "linear").map_err(|m| err(e.params.loc("normalmap").unwrap_or(loc), m))?;
        ShadingPerturbation::NormalMap(Arc::new(image))
    } else if let Some(d) = &settings.displacement {
        ShadingPerturbation::Bump(tb.float(d, loc)?)
    } else {
        ShadingPerturbation::None
    };
    let mut subsurface = None;
    let material = match &settings.kind {
        MaterialKind::Diffuse { reflectance } => Material::Diffuse { reflectance: tb.spectrum(reflectance, cs, loc)? },
        MaterialKind::Conductor { spec, roughness: r } => {
            Material::Conductor { input: conductor_input(spec, tb, cs, loc)?, roughness: roughness(r, tb, loc)? }
        }
        MaterialKind::CoatedConductor {
            interface_roughness,
            thickness,
            interface_eta,
            conductor,
            conductor_roughness,
            albedo,
            g,
            max_depth,
            n_samples,
        } => Material::CoatedConductor {
            interface_roughness: roughness(interface_roughness, tb, loc)?,
            thickness: tb.float(thickness, loc)?,
            interface_eta: eta_value(interface_eta, tb, cs, loc)?,
            conductor: conductor_input(conductor, tb, cs, loc)?,
            conductor_roughness: roughness(conductor_roughness, tb, loc)?,
            albedo: tb.spectrum(albedo, cs, loc)?,
            g: tb.float(g, loc)?,
            max_depth: *max_depth,
            n_samples: *n_samples,
        },
        MaterialKind::DiffuseTransmission { reflectance, transmittance, scale } => Material::DiffuseTransmission {
            reflectance: tb.spectrum(reflectance, cs, loc)?,
            transmittance: tb.spectrum(transmittance, cs, loc)?,
            scale: *scale,
        },
        // The parts are named materials, some perhaps defined later: `resolve_mixes` sets
        // them once every material exists.
        MaterialKind::Mix { amount, .. } => Material::Mix { materials: [0, 0], amount: tb.float(amount, loc)? },
        MaterialKind::Dielectric { eta, roughness: r } => {
            Material::Dielectric { eta: eta_value(eta, tb, cs, loc)?, roughness: roughness(r, tb, loc)? }
        }
        MaterialKind::ThinDielectric { eta } => Material::ThinDielectric { eta: eta_value(eta, tb, cs, loc)? },
        MaterialKind::Interface => Material::Interface,
        MaterialKind::CoatedDiffuse { reflectance, roughness: r, thickness, eta, albedo, g, max_depth, n_samples } => {
            Material::CoatedDiffuse {
                reflectance: tb.spectrum(reflectance, cs, loc)?,
                roughness: roughness(r, tb, loc)?,
                thickness: tb.float(thickness, loc)?,
                eta: eta_value(eta, tb, cs, loc)?,
                albedo: tb.spectrum(albedo, cs, loc)?,
                g: tb.float(g, loc)?,
                max_depth: *max_depth,
                n_samples: *n_samples,
            }
        }
        MaterialKind::Subsurface { eta, roughness: r, coefficients, scale, g } => {
            subsurface = Some(subsurface_medium(coefficients, *scale, *g, *eta, tb, cs, loc)?);
            Material::Dielectric { eta: SpectrumValue::constant(*eta), roughness: roughness(r, tb, loc)? }
        }
        MaterialKind::Hair { absorption, eta, beta_m, beta_n, alpha } => Material::Hair {
            absorption: match absorption {
                HairAbsorptionSpec::SigmaA(s) => HairAbsorption::SigmaA(tb.spectrum_as(s, cs, loc, true)?),
                HairAbsorptionSpec::Reflectance(r) => HairAbsorption::Reflectance(tb.spectrum(r, cs, loc)?),
                HairAbsorptionSpec::Melanin { eumelanin, pheomelanin } => HairAbsorption::Melanin {
                    eumelanin: tb.float(eumelanin, loc)?,
                    pheomelanin: tb.float(pheomelanin, loc)?,
                },
            },
            eta: tb.float(eta, loc)?,
            beta_m: tb.float(beta_m, loc)?,
            beta_n: tb.float(beta_n, loc)?,
            alpha: tb.float(alpha, loc)?,
        },
        MaterialKind::Measured { filename } => {
            let mut cache = measured.borrow_mut();
            let data = match cache.get(filename) {
                Some(d) => d.clone(),
                None => {
                    let d = std::sync::Arc::new(
                        crate::materials::measured::MeasuredData::read(filename, tb.spectra.film)
                            .map_err(|m| err(e.params.loc("filename").unwrap_or(loc), format!("measured: {m}")))?,
                    );
                    cache.insert(filename.clone(), d.clone());
                    d
                }
            };
            Material::Measured { data: crate::materials::measured::SharedMeasured(data) }
        }
        MaterialKind::Unsupported(_) => Material::Diffuse { reflectance: Tex::Const(SpectrumValue::constant(0.5)) },
    };
    Ok(BuiltMaterial { material, shading, subsurface })
}

/// The scene's materials: anonymous ones by index, then named ones, with their shading
/// perturbations (bump, normal maps) and the media of subsurface materials.
pub(super) struct Materials {
    pub(super) materials: Vec<Material>,
    pub(super) shading: Vec<ShadingPerturbation>,
    pub(super) subsurface: Vec<Option<SubsurfaceMedium>>,
    pub(super) named: HashMap<String, u32>,
}

/// Builds every material of `desc` and resolves its mixes; a subsurface material inside a
/// mix is refused.
pub(super) fn build_materials(
    desc: &SceneDescription,
    tb: &TextureBuilder<'_>,
    warnings: &mut Vec<Warning>,
) -> Result<Materials, Error> {
    let mut materials = Vec::with_capacity(desc.materials.len() + desc.named_materials.len());
    let mut shading = Vec::with_capacity(materials.capacity());
    let mut subsurface = Vec::with_capacity(materials.capacity());
    let mut named = HashMap::new();
    let entities =
        desc.materials.iter().map(|m| (None, m)).chain(desc.named_materials.iter().map(|m| (Some(&m.name), &m.entity)));
    let measured = MeasuredCache::default();
    for (name, e) in entities {
        if let Some(name) = name {
            named.insert(name.clone(), materials.len() as u32);
        }
        let built = material(e, tb, &measured, warnings)?;
        materials.push(built.material);
        shading.push(built.shading);
        subsurface.push(built.subsurface);
    }
    resolve_mixes(desc, &mut materials, &named)?;
    for m in &materials {
        if let Material::Mix { materials: pair, .. } = m
            && let Some(part) = pair.iter().find_map(|&i| subsurface[i as usize].as_ref())
        {
            return Err(err(
                &part.loc,
                "a subsurface material cannot be part of a mix in nimbus (its medium boundary belongs to the shape)",
            ));
        }
    }
    Ok(Materials { materials, shading, subsurface, named })
}
