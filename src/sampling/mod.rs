//! Sampling: warps from the unit square to directions and shapes, and discrete and
//! tabulated distributions.

pub mod distribution;
pub mod piecewise_linear;
pub mod warp;

#[cfg(test)]
pub(crate) mod chi_square;
pub mod rng;
