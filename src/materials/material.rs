//! Materials at render time: texture inputs resolved to [`Tex`], turned into a BxDF at each
//! surface hit.

use glam::Vec3;

use super::bxdf::{
    Bxdf, CoatedConductorBase, CoatedConductorBxdf, CoatedDiffuseBxdf, ConductorBxdf, DielectricBxdf, DiffuseBxdf,
    DiffuseTransmissionBxdf, HairBxdf, ThinDielectricBxdf, TrowbridgeReitz,
};
use crate::channels::Channels;
use crate::sampling::rng::murmur_hash64a;
use crate::spectra::{RgbRole, SpectrumValue};
use crate::textures::{Tex, TexContext, Textures};

/// Microfacet roughness inputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughnessTex {
    /// Roughness along u (float texture).
    pub u: Tex,
    /// Roughness along v (float texture).
    pub v: Tex,
    /// pbrt-v4's `remaproughness`.
    pub remap: bool,
}

impl RoughnessTex {
    fn distribution(&self, textures: &Textures, ctx: &TexContext) -> TrowbridgeReitz {
        TrowbridgeReitz::from_roughness(textures.eval_float(self.u, ctx), textures.eval_float(self.v, ctx), self.remap)
    }
}

/// A conductor's optical constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConductorInput {
    /// Complex IOR per channel, with the per-channel Fresnel scale of the spectral fit.
    EtaK {
        /// η (spectrum texture).
        eta: Tex,
        /// k (spectrum texture).
        k: Tex,
        /// Multiplier on the Fresnel reflectance (1 unless an RGB fit of spectral constants
        /// needed it).
        scale: SpectrumValue,
    },
    /// Normal-incidence reflectance (spectrum texture).
    Reflectance(Tex),
}

impl ConductorInput {
    fn bxdf<C: Channels>(
        &self,
        d: TrowbridgeReitz,
        textures: &Textures,
        ctx: &TexContext,
        lambda: &C::Lambda,
    ) -> ConductorBxdf<C> {
        match self {
            ConductorInput::EtaK { eta, k, scale } => {
                let eta = textures.eval::<C>(*eta, ctx, lambda, RgbRole::Unbounded);
                let k = textures.eval::<C>(*k, ctx, lambda, RgbRole::Unbounded);
                ConductorBxdf::new(d, eta, k).with_fresnel_scale(C::eval(scale, lambda))
            }
            ConductorInput::Reflectance(r) => {
                let r = textures.eval::<C>(*r, ctx, lambda, RgbRole::Albedo);
                ConductorBxdf::from_reflectance(d, r)
            }
        }
    }

    fn chromatic(&self, textures: &Textures) -> Option<&'static str> {
        let chromatic = |t: &Tex| textures.is_chromatic(*t);
        match self {
            ConductorInput::EtaK { eta, k, scale } => {
                (chromatic(eta) || chromatic(k) || !scale.is_constant()).then_some("eta/k")
            }
            ConductorInput::Reflectance(r) => chromatic(r).then_some("reflectance"),
        }
    }
}

/// Where a hair's absorption comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HairAbsorption {
    /// σa (spectrum texture, unbounded).
    SigmaA(Tex),
    /// A reflectance inverted to σa (spectrum texture, albedo).
    Reflectance(Tex),
    /// Eumelanin and pheomelanin concentrations (float textures).
    Melanin {
        /// Eumelanin.
        eumelanin: Tex,
        /// Pheomelanin.
        pheomelanin: Tex,
    },
}

/// A material ready to produce BxDFs.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// A measured BRDF (pbrt-v4's `.bsdf` tables).
    Measured {
        /// Its tables.
        data: crate::materials::measured::SharedMeasured,
    },
    /// Lambertian.
    Diffuse {
        /// Albedo.
        reflectance: Tex,
    },
    /// Metal.
    Conductor {
        /// Optical constants.
        input: ConductorInput,
        /// Roughness.
        roughness: RoughnessTex,
    },
    /// Glass.
    Dielectric {
        /// Index of refraction.
        eta: SpectrumValue,
        /// Roughness.
        roughness: RoughnessTex,
    },
    /// Thin glass.
    ThinDielectric {
        /// Index of refraction.
        eta: SpectrumValue,
    },
    /// Dielectric coating over a diffuse base.
    CoatedDiffuse {
        /// Base albedo.
        reflectance: Tex,
        /// Coating roughness.
        roughness: RoughnessTex,
        /// Coating thickness (float texture).
        thickness: Tex,
        /// Coating IOR.
        eta: SpectrumValue,
        /// Albedo of the medium in the coating.
        albedo: Tex,
        /// Its asymmetry (float texture).
        g: Tex,
        /// Random-walk depth.
        max_depth: u32,
        /// Walks per evaluation.
        n_samples: u32,
    },
    /// Dielectric coating over a conductor.
    CoatedConductor {
        /// Coating roughness.
        interface_roughness: RoughnessTex,
        /// Coating thickness (float texture).
        thickness: Tex,
        /// Coating IOR.
        interface_eta: SpectrumValue,
        /// The conductor's optical constants (relative to vacuum: divided by the coating's η
        /// per hit).
        conductor: ConductorInput,
        /// The conductor's roughness.
        conductor_roughness: RoughnessTex,
        /// Albedo of the medium in the coating.
        albedo: Tex,
        /// Its asymmetry (float texture).
        g: Tex,
        /// Random-walk depth.
        max_depth: u32,
        /// Walks per evaluation.
        n_samples: u32,
    },
    /// Lambertian reflection and transmission.
    DiffuseTransmission {
        /// Reflectance (spectrum texture).
        reflectance: Tex,
        /// Transmittance (spectrum texture).
        transmittance: Tex,
        /// Factor on both.
        scale: f32,
    },
    /// Hair fibres (pbrt-v4's hair BSDF).
    Hair {
        /// The fibre's absorption.
        absorption: HairAbsorption,
        /// Index of refraction (float texture).
        eta: Tex,
        /// Longitudinal roughness (float texture).
        beta_m: Tex,
        /// Azimuthal roughness (float texture).
        beta_n: Tex,
        /// Scale tilt in degrees (float texture).
        alpha: Tex,
    },
    /// One of two materials per hit, chosen by [`resolve`].
    Mix {
        /// Indices of the two materials in the scene's table.
        materials: [u32; 2],
        /// Probability of the second (float texture).
        amount: Tex,
    },
    /// A medium boundary with no scattering of its own.
    Interface,
}

/// The material a hit at `ctx.p` seen from `wo` scatters with: `mix` materials are resolved
/// by pbrt-v4's deterministic choice (`MixMaterial::ChooseMaterial`): the second material
/// where a hash of the hit point, `wo` and the pair is below `amount`. The hash makes the
/// choice the same for every ray that reaches the same point from the same direction
/// (shadow rays and camera rays agree); pbrt-v4 hashes the materials' addresses, nimbus
/// their indices, so the pattern differs while its statistics do not.
/// Returns the chosen material's index.
pub fn resolve(materials: &[Material], id: u32, textures: &Textures, ctx: &TexContext, wo: Vec3) -> u32 {
    let mut id = id;
    // Mix cycles are refused when the scene is built, so this ends.
    while let Material::Mix { materials: pair, amount } = &materials[id as usize] {
        let amount = textures.eval_float(*amount, ctx);
        let second = if amount <= 0.0 {
            false
        } else if amount >= 1.0 {
            true
        } else {
            amount >= mix_hash(ctx.p, wo, *pair)
        };
        id = pair[second as usize];
    }
    id
}

/// A uniform number in [0, 1) from the bytes of `p`, `wo` and the pair (pbrt-v4's `HashFloat`).
fn mix_hash(p: Vec3, wo: Vec3, pair: [u32; 2]) -> f32 {
    let mut bytes = [0u8; 32];
    for (i, x) in [p.x, p.y, p.z, wo.x, wo.y, wo.z].iter().enumerate() {
        bytes[4 * i..4 * i + 4].copy_from_slice(&x.to_le_bytes());
    }
    bytes[24..28].copy_from_slice(&pair[0].to_le_bytes());
    bytes[28..32].copy_from_slice(&pair[1].to_le_bytes());
    (murmur_hash64a(&bytes, 0) as u32) as f32 * (1.0 / 4_294_967_296.0)
}

impl Material {
    /// True for `interface`: rays pass through and shadow rays are not blocked.
    #[inline]
    pub fn is_interface(&self) -> bool {
        matches!(self, Material::Interface)
    }

    /// Whether the material's η varies with wavelength: a path through it keeps only its
    /// hero wavelength (pbrt-v4's `TerminateSecondary`). `materials` is the scene's table, for
    /// the parts of a `mix`.
    pub fn is_dispersive(&self, materials: &[Material]) -> bool {
        match self {
            Material::Dielectric { eta, .. }
            | Material::ThinDielectric { eta }
            | Material::CoatedDiffuse { eta, .. } => !eta.is_constant(),
            Material::CoatedConductor { interface_eta, .. } => !interface_eta.is_constant(),
            Material::Mix { materials: pair, .. } => {
                pair.iter().any(|&i| materials[i as usize].is_dispersive(materials))
            }
            _ => false,
        }
    }

    /// The first input that varies with wavelength, by parameter name, or `None` when RGB
    /// transport carries the material exactly (every input gray, η constant). `materials`
    /// is the scene's table, for the parts of a `mix`.
    pub fn chromatic_input(&self, materials: &[Material], textures: &Textures) -> Option<&'static str> {
        let chromatic = |t: &Tex| textures.is_chromatic(*t);
        match self {
            Material::Diffuse { reflectance } => chromatic(reflectance).then_some("reflectance"),
            Material::Conductor { input, .. } => input.chromatic(textures),
            Material::CoatedConductor { interface_eta, conductor, albedo, .. } => {
                conductor.chromatic(textures).or_else(|| {
                    if chromatic(albedo) {
                        Some("albedo")
                    } else {
                        (!interface_eta.is_constant()).then_some("interface.eta (dispersion)")
                    }
                })
            }
            Material::DiffuseTransmission { reflectance, transmittance, .. } => {
                if chromatic(reflectance) {
                    Some("reflectance")
                } else {
                    chromatic(transmittance).then_some("transmittance")
                }
            }
            Material::Mix { materials: pair, .. } => {
                pair.iter().find_map(|&i| materials[i as usize].chromatic_input(materials, textures))
            }
            Material::Hair { absorption: HairAbsorption::SigmaA(t), .. } => chromatic(t).then_some("sigma_a"),
            Material::Hair { absorption: HairAbsorption::Reflectance(t), .. } => chromatic(t).then_some("reflectance"),
            Material::Hair { absorption: HairAbsorption::Melanin { .. }, .. } => Some("eumelanin/pheomelanin"),
            Material::Dielectric { eta, .. } | Material::ThinDielectric { eta } => {
                (!eta.is_constant()).then_some("eta (dispersion)")
            }
            Material::CoatedDiffuse { reflectance, eta, albedo, .. } => {
                if chromatic(reflectance) {
                    Some("reflectance")
                } else if chromatic(albedo) {
                    Some("albedo")
                } else {
                    (!eta.is_constant()).then_some("eta (dispersion)")
                }
            }
            // The tables are spectral; their RGB version is an approximation.
            Material::Measured { .. } => Some("measured BRDF"),
            Material::Interface => None,
        }
    }

    /// The BxDF at a hit (`None` for interfaces), in the path's channels. A dispersive
    /// index of refraction keeps only the path's first wavelength (pbrt-v4's dielectric
    /// materials call `TerminateSecondary`).
    pub fn bxdf<C: Channels>(&self, textures: &Textures, ctx: &TexContext, lambda: &mut C::Lambda) -> Option<Bxdf<C>> {
        let albedo = |t: Tex, lambda: &C::Lambda| textures.eval::<C>(t, ctx, lambda, RgbRole::Albedo).clamp(0.0, 1.0);
        Some(match self {
            Material::Diffuse { reflectance } => Bxdf::Diffuse(DiffuseBxdf::new(albedo(*reflectance, lambda))),
            Material::Conductor { input, roughness } => {
                Bxdf::Conductor(input.bxdf::<C>(roughness.distribution(textures, ctx), textures, ctx, lambda))
            }
            Material::CoatedConductor {
                interface_roughness,
                thickness,
                interface_eta,
                conductor,
                conductor_roughness,
                albedo: medium_albedo,
                g,
                max_depth,
                n_samples,
            } => {
                let eta = C::eta(interface_eta, lambda);
                let eta = if eta == 0.0 { 1.0 } else { eta };
                let top = DielectricBxdf::new(eta, interface_roughness.distribution(textures, ctx));
                let bottom = CoatedConductorBase::new(
                    &conductor
                        .bxdf::<C>(conductor_roughness.distribution(textures, ctx), textures, ctx, lambda)
                        .relative_to(eta),
                );
                Bxdf::CoatedConductor(CoatedConductorBxdf::new(
                    top,
                    bottom,
                    textures.eval_float(*thickness, ctx),
                    albedo(*medium_albedo, lambda),
                    textures.eval_float(*g, ctx).clamp(-1.0, 1.0),
                    *max_depth,
                    *n_samples,
                ))
            }
            Material::DiffuseTransmission { reflectance, transmittance, scale } => {
                let scaled = |t: Tex| (textures.eval::<C>(t, ctx, lambda, RgbRole::Albedo) * *scale).clamp(0.0, 1.0);
                Bxdf::DiffuseTransmission(DiffuseTransmissionBxdf::new(scaled(*reflectance), scaled(*transmittance)))
            }
            Material::Hair { absorption, eta, beta_m, beta_n, alpha } => {
                let beta_m = textures.eval_float(*beta_m, ctx).max(1e-2);
                let beta_n = textures.eval_float(*beta_n, ctx).max(1e-2);
                let sigma_a = match absorption {
                    HairAbsorption::SigmaA(t) => {
                        textures.eval::<C>(*t, ctx, lambda, RgbRole::Unbounded).map(|x| x.max(0.0))
                    }
                    HairAbsorption::Reflectance(t) => HairBxdf::sigma_a_from_reflectance(albedo(*t, lambda), beta_n),
                    HairAbsorption::Melanin { eumelanin, pheomelanin } => {
                        let rgb = HairBxdf::<C>::sigma_a_from_concentration(
                            textures.eval_float(*eumelanin, ctx).max(0.0),
                            textures.eval_float(*pheomelanin, ctx).max(0.0),
                        );
                        C::from_rgb(rgb, RgbRole::Unbounded, nimbus_parser::ColorSpace::Srgb, lambda)
                    }
                };
                // Across the fibre: v = 0 at one edge, 1 at the other (the curve's v).
                let h = -1.0 + 2.0 * ctx.uv.y;
                Bxdf::Hair(HairBxdf::new(
                    h,
                    textures.eval_float(*eta, ctx),
                    sigma_a,
                    beta_m,
                    beta_n,
                    textures.eval_float(*alpha, ctx),
                ))
            }
            Material::Mix { .. } => unreachable!("mix materials are resolved before their BxDF is asked for"),
            Material::Dielectric { eta, roughness } => {
                Bxdf::Dielectric(DielectricBxdf::new(C::eta(eta, lambda), roughness.distribution(textures, ctx)))
            }
            Material::ThinDielectric { eta } => Bxdf::ThinDielectric(ThinDielectricBxdf::new(C::eta(eta, lambda))),
            Material::CoatedDiffuse {
                reflectance,
                roughness,
                thickness,
                eta,
                albedo: medium_albedo,
                g,
                max_depth,
                n_samples,
            } => {
                let top = DielectricBxdf::new(C::eta(eta, lambda), roughness.distribution(textures, ctx));
                let bottom = DiffuseBxdf::new(albedo(*reflectance, lambda));
                Bxdf::CoatedDiffuse(CoatedDiffuseBxdf::new(
                    top,
                    bottom,
                    textures.eval_float(*thickness, ctx),
                    albedo(*medium_albedo, lambda),
                    textures.eval_float(*g, ctx),
                    *max_depth,
                    *n_samples,
                ))
            }
            Material::Measured { data } => {
                Bxdf::Measured(crate::materials::bxdf::MeasuredBxdf::new(data.0.clone(), lambda))
            }
            Material::Interface => return None,
        })
    }
}
