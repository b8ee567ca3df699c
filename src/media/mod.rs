//! Participating media: phase functions, media (homogeneous, grids, procedural, VDB), and
//! majorant grids for delta tracking.

pub mod phase;
