//! Materials at render time: texture inputs resolved to [`Tex`], turned into a BxDF at each
//! surface hit.

use super::bxdf::{
    Bxdf, CoatedDiffuseBxdf, ConductorBxdf, DielectricBxdf, DiffuseBxdf, ThinDielectricBxdf, TrowbridgeReitz,
};
use crate::color::Channels;
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
    /// A medium boundary with no scattering of its own.
    Interface,
}

impl Material {
    /// True for `interface`: rays pass through and shadow rays are not blocked.
    #[inline]
    pub fn is_interface(&self) -> bool {
        matches!(self, Material::Interface)
    }

    /// The first input that varies with wavelength, by parameter name, or `None` when RGB
    /// transport carries the material exactly (every input gray, η constant).
    pub fn chromatic_input(&self, textures: &Textures) -> Option<&'static str> {
        let chromatic = |t: &Tex| textures.is_chromatic(*t);
        match self {
            Material::Diffuse { reflectance } => chromatic(reflectance).then_some("reflectance"),
            Material::Conductor { input: ConductorInput::EtaK { eta, k, scale }, .. } => {
                (chromatic(eta) || chromatic(k) || !scale.is_constant()).then_some("eta/k")
            }
            Material::Conductor { input: ConductorInput::Reflectance(r), .. } => chromatic(r).then_some("reflectance"),
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
                let d = roughness.distribution(textures, ctx);
                match input {
                    ConductorInput::EtaK { eta, k, scale } => {
                        let eta = textures.eval::<C>(*eta, ctx, lambda, RgbRole::Unbounded);
                        let k = textures.eval::<C>(*k, ctx, lambda, RgbRole::Unbounded);
                        Bxdf::Conductor(ConductorBxdf::new(d, eta, k).with_fresnel_scale(C::eval(scale, lambda)))
                    }
                    ConductorInput::Reflectance(r) => {
                        let r = textures.eval::<C>(*r, ctx, lambda, RgbRole::Albedo);
                        Bxdf::Conductor(ConductorBxdf::from_reflectance(d, r))
                    }
                }
            }
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
            Material::Interface => return None,
        })
    }
}
