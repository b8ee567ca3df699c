//! Materials: pbrt-v4's BxDF models (evaluated in the local shading frame) and the
//! materials that create them at surface hits.

pub mod bxdf;
pub mod diffusion;
mod material;
pub mod measured;
mod shading;
pub mod subsurface;

pub use material::{ConductorInput, HairAbsorption, Material, RoughnessTex, resolve};
pub use shading::ShadingPerturbation;
