//! Materials: the scattering functions (BxDFs) of pbrt-v4's materials, evaluated in the local
//! shading frame.

pub mod bxdf;
