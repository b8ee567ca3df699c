//! Participating media: the volume data they are built from.

pub mod grid;
