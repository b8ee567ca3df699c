//! Sampling: warps from the unit square to directions and shapes, and discrete and
//! tabulated distributions.

pub mod warp;
