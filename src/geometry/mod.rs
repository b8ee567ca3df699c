//! Geometry shared by shapes and integrators: rays, bounds and mesh file formats.

mod bounds;
pub mod ply;
mod ray;

pub use bounds::Bounds3;
pub use ray::{Ray, offset_origin, position_error, spawn_ray, spawn_ray_to};
