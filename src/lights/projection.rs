//! pbrt-v4's projection light: a point source that projects an RGB image through a pinhole
//! of field of view `fov` along its +z axis, like a slide projector (pbrt-v4's
//! `ProjectionLight`).

use std::path::Path;

use glam::{Affine3A, Vec2, Vec3};
use nimbus_parser::ColorSpace;

use crate::color::Rgb;
use crate::error::{Error, Result};

/// The projected image and its frustum.
#[derive(Clone, Debug)]
pub struct ProjectionImage {
    width: usize,
    height: usize,
    pixels: Vec<Rgb>,
    /// The color space of the image's RGB.
    pub space: ColorSpace,
    /// 1 / tan(fov / 2).
    inv_tan: f32,
    screen_min: Vec2,
    screen_max: Vec2,
    /// Light space (with pbrt-v4's y flip) from world, for directions.
    light_from_world: Affine3A,
}

/// pbrt-v4's near plane for the projection: directions closer to the light's plane are dark.
const HITHER: f32 = 1e-3;

impl ProjectionImage {
    /// Reads `path` (EXR or PNG) for a light placed by `world_from_light` with field of view
    /// `fov` degrees. An image with a pixel that is not finite is [`Error::Malformed`].
    pub fn read(path: &Path, fov: f32, world_from_light: &Affine3A) -> Result<ProjectionImage> {
        let img = crate::imageio::read_image(path)?;
        if let Some(p) = img.pixels.iter().find(|p| !p.is_finite()) {
            return Err(Error::malformed(path, format!("a pixel is {p}, not finite, so the image cannot be a light")));
        }
        Ok(ProjectionImage::new(img.width, img.height, img.pixels, fov, world_from_light))
    }

    /// An image of `width` × `height` pixels (rows from the top).
    pub fn new(
        width: usize,
        height: usize,
        pixels: Vec<Rgb>,
        fov: f32,
        world_from_light: &Affine3A,
    ) -> ProjectionImage {
        let aspect = width as f32 / height as f32;
        let (screen_min, screen_max) = if aspect > 1.0 {
            (Vec2::new(-aspect, -1.0), Vec2::new(aspect, 1.0))
        } else {
            (Vec2::new(-1.0, -1.0 / aspect), Vec2::new(1.0, 1.0 / aspect))
        };
        let flip = Affine3A::from_scale(Vec3::new(1.0, -1.0, 1.0));
        ProjectionImage {
            width,
            height,
            pixels,
            space: ColorSpace::Srgb,
            inv_tan: 1.0 / (fov.to_radians() / 2.0).tan(),
            screen_min,
            screen_max,
            light_from_world: (*world_from_light * flip).inverse(),
        }
    }

    /// The image's RGB projected along world direction `w` (leaving the light), or `None`
    /// outside the frustum (pbrt-v4's `I(w)` before its illuminant spectrum and scale).
    #[inline]
    pub fn lookup(&self, w: Vec3) -> Option<Rgb> {
        let wl = self.light_from_world.transform_vector3(w);
        if wl.z < HITHER {
            return None;
        }
        let ps = Vec2::new(wl.x, wl.y) * (self.inv_tan / wl.z);
        if ps.cmplt(self.screen_min).any() || ps.cmpgt(self.screen_max).any() {
            return None;
        }
        let uv = (ps - self.screen_min) / (self.screen_max - self.screen_min);
        let x = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        Some(self.pixels[y * self.width + x].max(Rgb::ZERO))
    }

    /// Emitted power per unit scale, per RGB channel: the image over the frustum's solid
    /// angle (pbrt-v4's `Phi`, and the `k_e` its `power` divides by, with luminance weights).
    pub fn power_rgb(&self) -> Rgb {
        let mut sum = glam::DVec3::ZERO;
        for y in 0..self.height {
            for x in 0..self.width {
                let t = Vec2::new((x as f32 + 0.5) / self.width as f32, (y as f32 + 0.5) / self.height as f32);
                let ps = self.screen_min + t * (self.screen_max - self.screen_min);
                // The direction through the screen point and its dω/dA = cos³θ.
                let w = Vec3::new(ps.x / self.inv_tan, ps.y / self.inv_tan, 1.0).normalize();
                sum += self.pixels[y * self.width + x].max(Rgb::ZERO).as_dvec3() * f64::from(w.z.powi(3));
            }
        }
        let opposite = 1.0 / self.inv_tan;
        let aspect = self.width as f32 / self.height as f32;
        let a = 4.0 * opposite * opposite * if aspect > 1.0 { aspect } else { 1.0 / aspect };
        (sum * f64::from(a) / (self.width * self.height) as f64).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_image_fills_the_frustum_and_nothing_else() {
        // A 2×1 image, fov 90: the screen spans x in [-2, 2], y in [-1, 1] at z = 1.
        let img = ProjectionImage::new(
            2,
            1,
            vec![Rgb::new(1.0, 0.0, 0.0), Rgb::new(0.0, 1.0, 0.0)],
            90.0,
            &Affine3A::IDENTITY,
        );
        assert_eq!(img.lookup(Vec3::new(-1.0, 0.2, 1.0)), Some(Rgb::new(1.0, 0.0, 0.0)));
        assert_eq!(img.lookup(Vec3::new(1.0, 0.2, 1.0)), Some(Rgb::new(0.0, 1.0, 0.0)));
        assert_eq!(img.lookup(Vec3::new(2.5, 0.0, 1.0)), None, "beyond the screen's side");
        assert_eq!(img.lookup(Vec3::new(0.0, 1.5, 1.0)), None, "beyond its top");
        assert_eq!(img.lookup(Vec3::new(0.0, 0.0, -1.0)), None, "behind the light");
        // A white image's power: its solid angle (the frustum's), by the pixel sum.
        let white = ProjectionImage::new(64, 64, vec![Rgb::ONE; 64 * 64], 60.0, &Affine3A::IDENTITY);
        // The solid angle of a square pyramid of half-angle 30°: 4 asin(sin²30°).
        let exact = 4.0 * (0.5f32 * 0.5).asin();
        assert!((white.power_rgb().x - exact).abs() < 2e-3 * exact, "{} vs {exact}", white.power_rgb().x);
    }
}
