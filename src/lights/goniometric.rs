//! pbrt-v4's goniometric light: a point source whose intensity varies with direction by an
//! equal-area image (pbrt-v4's `GoniometricLight`), its channels averaged to one.

use std::path::Path;

use glam::{Affine3A, Vec2, Vec3};

use crate::error::{Error, Result};
use crate::sampling::warp::equal_area_sphere_to_square;

/// The light's directional distribution: a square equal-area image of one channel, looked up
/// at the nearest pixel as pbrt-v4 does, in the light's frame.
#[derive(Clone, Debug)]
pub struct GoniometricImage {
    res: usize,
    values: Vec<f32>,
    mean: f32,
    /// Light space (with pbrt-v4's y/z swap) from world, for directions.
    light_from_world: Affine3A,
}

impl GoniometricImage {
    /// Reads `path` (EXR or PNG; RGB averaged per pixel) for a light placed by `world_from_light`.
    /// An image that is not square or has a pixel that is not finite is [`Error::Malformed`]
    /// (the file is not an equal-area map).
    pub fn read(path: &Path, world_from_light: &Affine3A) -> Result<GoniometricImage> {
        let img = crate::imageio::read_image(path)?;
        if img.width != img.height {
            return Err(Error::malformed(
                path,
                format!(
                    "image resolution ({}, {}) is not square, so it is not an equal-area map",
                    img.width, img.height
                ),
            ));
        }
        let values: Vec<f32> = img.pixels.iter().map(|p| (p.x + p.y + p.z) / 3.0).collect();
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(Error::malformed(
                path,
                format!("a pixel is {v}, not a finite value, so the image cannot be a light"),
            ));
        }
        Ok(GoniometricImage::new(img.width, values, world_from_light))
    }

    /// An image of `res`² values (row by row from the top).
    pub fn new(res: usize, values: Vec<f32>, world_from_light: &Affine3A) -> GoniometricImage {
        let mean = values.iter().map(|&v| v as f64).sum::<f64>() as f32 / values.len().max(1) as f32;
        // pbrt-v4 renders from light × swapYZ: the map's pole is the light's +y.
        let swap = Affine3A::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
        GoniometricImage { res, values, mean, light_from_world: (*world_from_light * swap).inverse() }
    }

    /// Mean over the map: the intensity's average over the sphere, per unit of `I`.
    pub fn mean(&self) -> f32 {
        self.mean
    }

    /// The map's value for light leaving in world direction `w` (pbrt-v4's `I(w)` over `I`).
    #[inline]
    pub fn lookup(&self, w: Vec3) -> f32 {
        let wl = self.light_from_world.transform_vector3(w).normalize_or_zero();
        if wl == Vec3::ZERO || self.res == 0 {
            return 0.0;
        }
        let uv: Vec2 = equal_area_sphere_to_square(wl);
        let n = self.res as f32;
        let x = ((uv.x * n) as usize).min(self.res - 1);
        let y = ((uv.y * n) as usize).min(self.res - 1);
        self.values[y * self.res + x]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp::equal_area_square_to_sphere;

    #[test]
    fn lookups_follow_the_equal_area_map_in_the_lights_frame() {
        // A 4×4 map whose values are their indices.
        let values: Vec<f32> = (0..16).map(|i| i as f32).collect();
        let img = GoniometricImage::new(4, values, &Affine3A::IDENTITY);
        assert_eq!(img.mean(), 7.5);
        for (x, y) in [(0usize, 0usize), (1, 2), (3, 3), (2, 1)] {
            // The centre of pixel (x, y) on the sphere, then through pbrt-v4's y/z swap.
            let d = equal_area_square_to_sphere(Vec2::new((x as f32 + 0.5) / 4.0, (y as f32 + 0.5) / 4.0));
            let w = Vec3::new(d.x, d.z, d.y);
            assert_eq!(img.lookup(w), (y * 4 + x) as f32, "pixel ({x}, {y})");
        }
        // A rotated light turns the map with it.
        let rot = Affine3A::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let turned = GoniometricImage::new(4, (0..16).map(|i| i as f32).collect(), &rot);
        let w = Vec3::new(0.3, 0.5, 0.8).normalize();
        assert_eq!(turned.lookup(rot.transform_vector3(w)), img.lookup(w));
    }
}
