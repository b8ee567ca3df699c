//! Mesh file formats.

pub mod ply;
