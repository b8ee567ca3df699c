//! Materials at render time: texture inputs resolved to [`Tex`], turned into a BxDF at each
//! surface hit.

use super::bxdf::{
    Bxdf, CoatedDiffuseBxdf, ConductorBxdf, DielectricBxdf, DiffuseBxdf, ThinDielectricBxdf, TrowbridgeReitz,
};
use crate::color::Rgb;
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
        /// Multiplier on the Fresnel reflectance (1 unless a spectral fit needed it).
        scale: Rgb,
    },
    /// Normal-incidence reflectance (spectrum texture).
    Reflectance(Tex),
}

/// A material ready to produce BxDFs.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
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
        eta: f32,
        /// Roughness.
        roughness: RoughnessTex,
    },
    /// Thin glass.
    ThinDielectric {
        /// Index of refraction.
        eta: f32,
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
        eta: f32,
        /// Albedo of the medium in the coating.
        albedo: Tex,
        /// Its asymmetry (float texture).
        g: Tex,
        /// Random-walk depth.
        max_depth: u32,
        /// Walks per evaluation.
        n_samples: u32,
    },
    /// A medium boundary with no scattering of its own.
    Interface,
}

impl Material {
    /// True for `interface`: rays pass through and shadow rays are not blocked.
    #[inline]
    pub fn is_interface(&self) -> bool {
        matches!(self, Material::Interface)
    }

    /// The BxDF at a hit (`None` for interfaces).
    pub fn bxdf(&self, textures: &Textures, ctx: &TexContext) -> Option<Bxdf> {
        Some(match self {
            Material::Diffuse { reflectance } => {
                Bxdf::Diffuse(DiffuseBxdf::new(textures.eval(*reflectance, ctx).clamp(Rgb::ZERO, Rgb::ONE)))
            }
            Material::Conductor { input, roughness } => {
                let d = roughness.distribution(textures, ctx);
                match input {
                    ConductorInput::EtaK { eta, k, scale } => Bxdf::Conductor(
                        ConductorBxdf::new(d, textures.eval(*eta, ctx), textures.eval(*k, ctx))
                            .with_fresnel_scale(*scale),
                    ),
                    ConductorInput::Reflectance(r) => {
                        Bxdf::Conductor(ConductorBxdf::from_reflectance(d, textures.eval(*r, ctx)))
                    }
                }
            }
            Material::Dielectric { eta, roughness } => {
                Bxdf::Dielectric(DielectricBxdf::new(*eta, roughness.distribution(textures, ctx)))
            }
            Material::ThinDielectric { eta } => Bxdf::ThinDielectric(ThinDielectricBxdf::new(*eta)),
            Material::CoatedDiffuse { reflectance, roughness, thickness, eta, albedo, g, max_depth, n_samples } => {
                let top = DielectricBxdf::new(*eta, roughness.distribution(textures, ctx));
                let bottom = DiffuseBxdf::new(textures.eval(*reflectance, ctx).clamp(Rgb::ZERO, Rgb::ONE));
                Bxdf::CoatedDiffuse(CoatedDiffuseBxdf::new(
                    top,
                    bottom,
                    textures.eval_float(*thickness, ctx),
                    textures.eval(*albedo, ctx).clamp(Rgb::ZERO, Rgb::ONE),
                    textures.eval_float(*g, ctx),
                    *max_depth,
                    *n_samples,
                ))
            }
            Material::Interface => return None,
        })
    }
}
