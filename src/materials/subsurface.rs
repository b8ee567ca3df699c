//! The coefficients of a `subsurface` material whose inputs are textures. pbrt-v4 evaluates
//! its BSSRDF's σa and σs where a path enters the surface (`SubsurfaceMaterial::GetBSSRDF`,
//! inverting its diffusion table for that point's `reflectance` at every lookup), and the
//! whole profile below uses them. nimbus renders the medium itself, so a path fixes the
//! medium's coefficients where it crosses into it and keeps them until it leaves.

use std::sync::Arc;

use super::diffusion::DiffusionTable;
use crate::channels::Channels;
use crate::media::MediumPoint;
use crate::spectra::RgbRole;
use crate::textures::{Tex, TexContext, Textures};

/// What the coefficients come from.
#[derive(Clone, Debug)]
pub enum SubsurfaceInputs {
    /// σa and σs themselves.
    Sigma {
        /// Absorption (unbounded).
        sigma_a: Tex,
        /// Scattering (unbounded).
        sigma_s: Tex,
    },
    /// A total diffuse reflectance and a mean free path, inverted per channel through the
    /// photon beam diffusion table (pbrt-v4's `SubsurfaceFromDiffuse`).
    Reflectance {
        /// Reflectance (an albedo, clamped to [0, 1]).
        reflectance: Tex,
        /// Mean free path (unbounded).
        mfp: Tex,
        /// ρ_eff(ρ) for the material's g and η.
        table: Arc<DiffusionTable>,
    },
}

/// A subsurface medium's coefficients as functions of the entry point.
#[derive(Clone, Debug)]
pub struct EntryCoefficients {
    /// The inputs.
    pub inputs: SubsurfaceInputs,
    /// pbrt-v4's `scale`: multiplies σa and σs, or the mean free path.
    pub scale: f32,
}

impl EntryCoefficients {
    /// σa and σs (no emission) at the entry point `ctx`, in the path's channels.
    #[inline]
    pub fn at<C: Channels>(&self, textures: &Textures, ctx: &TexContext, lambda: &C::Lambda) -> MediumPoint<C> {
        let unbounded = |t: Tex| textures.eval::<C>(t, ctx, lambda, RgbRole::Unbounded);
        let (sigma_a, sigma_s) = match &self.inputs {
            SubsurfaceInputs::Sigma { sigma_a, sigma_s } => {
                (unbounded(*sigma_a).max(C::ZERO) * self.scale, unbounded(*sigma_s).max(C::ZERO) * self.scale)
            }
            SubsurfaceInputs::Reflectance { reflectance, mfp, table } => {
                let r = textures.eval::<C>(*reflectance, ctx, lambda, RgbRole::Albedo).clamp(0.0, 1.0);
                let mfp = (unbounded(*mfp) * self.scale).max(C::splat(f32::MIN_POSITIVE));
                // σt = 1/mfp, split by the albedo whose diffusion profile reflects r.
                let rho = r.map(|r| table.albedo(r));
                (mfp.zip_map(rho, |m, rho| (1.0 - rho) / m), mfp.zip_map(rho, |m, rho| rho / m))
            }
        };
        MediumPoint { sigma_a, sigma_s, le: C::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::spectra::SpectrumValue;

    /// Each channel's σt is 1/(scale·mfp) and its albedo the one whose total diffuse
    /// reflectance is that channel's `reflectance`; σa and σs are scaled as given.
    #[test]
    fn reflectance_inverts_per_channel_and_sigma_scales() {
        let table = Arc::new(DiffusionTable::new(0.0, 1.33));
        let gray = |v: f32| Tex::Const(SpectrumValue::constant(v));
        let mut r = SpectrumValue::constant(0.0);
        r.rgb = Rgb::new(0.2, 0.5, 0.8);
        let e = EntryCoefficients {
            inputs: SubsurfaceInputs::Reflectance { reflectance: Tex::Const(r), mfp: gray(0.5), table: table.clone() },
            scale: 2.0,
        };
        let ctx = TexContext::at(glam::Vec3::ZERO, glam::Vec2::ZERO, glam::Vec3::Z);
        let mp: MediumPoint<Rgb> = e.at(&Textures::default(), &ctx, &());
        let t = mp.sigma_a + mp.sigma_s;
        assert!((t - Rgb::ONE).abs().max_element() < 1e-6, "σt = 1/(2·0.5): {t}");
        for (c, want) in [0.2, 0.5, 0.8].into_iter().enumerate() {
            let rho = mp.sigma_s[c] / t[c];
            assert!((table.rho_eff(rho) - want).abs() < 0.01, "channel {c}: ρ_eff({rho}) vs {want}");
        }
        let e = EntryCoefficients {
            inputs: SubsurfaceInputs::Sigma { sigma_a: gray(0.1), sigma_s: gray(3.0) },
            scale: 10.0,
        };
        let mp: MediumPoint<Rgb> = e.at(&Textures::default(), &ctx, &());
        assert_eq!((mp.sigma_a, mp.sigma_s, mp.le), (Rgb::splat(1.0), Rgb::splat(30.0), Rgb::ZERO));
    }
}
