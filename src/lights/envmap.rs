//! Image environment maps in pbrt-v4's equal-area octahedral parameterisation (Clarberg
//! 2008), importance-sampled by a piecewise-constant distribution over the image.

use std::f32::consts::PI;

use crate::sampling::warp::{equal_area_sphere_to_square, equal_area_square_to_sphere};
use glam::{Affine3A, Vec2, Vec3};

use nimbus_parser::ColorSpace;

use crate::channels::Channels;
use crate::color::{Rgb, luminance};
use crate::imageio::Image;
use crate::sampling::distribution::PiecewiseConstant2D;
use crate::spectra::RgbRole;

/// An environment light's image, orientation and sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    size: usize,
    pixels: Vec<Rgb>,
    space: ColorSpace,
    world_from_light: Affine3A,
    light_from_world: Affine3A,
    distribution: PiecewiseConstant2D,
    average: f32,
}

impl EnvironmentMap {
    /// An environment map from a square image of color space `space`, scaled by `scale`.
    pub fn new(
        image: &Image,
        space: ColorSpace,
        world_from_light: Affine3A,
        scale: f32,
    ) -> crate::error::Result<EnvironmentMap> {
        if image.width != image.height || image.width == 0 {
            return Err(crate::error::Error::Invalid(format!(
                "environment image is {}x{}; pbrt-v4 environment maps are square equal-area octahedral images",
                image.width, image.height
            )));
        }
        let size = image.width;
        let pixels: Vec<Rgb> = image.pixels.iter().map(|p| p.max(Rgb::ZERO) * scale).collect();
        let lum: Vec<f32> = pixels.iter().map(|p| luminance(*p).max(0.0)).collect();
        let average = lum.iter().map(|&l| l as f64).sum::<f64>() as f32 / lum.len() as f32;
        let distribution = PiecewiseConstant2D::new(&lum, size, size, Vec2::ZERO, Vec2::ONE);
        Ok(EnvironmentMap {
            size,
            pixels,
            space,
            world_from_light,
            light_from_world: world_from_light.inverse(),
            distribution,
            average,
        })
    }

    /// The map with directions looked up (and their density evaluated) through
    /// `light_from_world` instead of the inverse of the frame samples are placed by. pbrt-v4
    /// places samples by the 3×3 of its render-from-light matrix and looks directions up by the
    /// 3×3 of that matrix's inverse; the two are each other's inverse unless the matrix is
    /// projective, where pbrt-v4's image is what this pair makes.
    pub fn with_lookup_frame(mut self, light_from_world: Affine3A) -> EnvironmentMap {
        self.light_from_world = light_from_world;
        self
    }

    /// Applies `f` to every pixel (e.g. RGB transport converting each texel through a camera
    /// sensor once); the sampling distribution is kept, as it only needs to be proportional
    /// to the radiance roughly.
    pub fn map_pixels(&mut self, f: impl Fn(Rgb) -> Rgb) {
        for p in &mut self.pixels {
            *p = f(*p);
        }
    }

    /// Mean luminance of the image (after scaling).
    pub fn average_radiance(&self) -> f32 {
        self.average
    }

    /// Radiance arriving from world direction `w` (nearest pixel, as pbrt-v4 looks it up).
    pub fn lookup<C: Channels>(&self, w: Vec3, lambda: &C::Lambda) -> C {
        let wl = self.light_from_world.transform_vector3(w).normalize_or_zero();
        self.radiance(equal_area_sphere_to_square(wl), lambda)
    }

    /// The pixel at `uv` as emitted radiance (an illuminant spectrum for spectral transport,
    /// as pbrt-v4's `ImageLe`).
    #[inline]
    fn radiance<C: Channels>(&self, uv: Vec2, lambda: &C::Lambda) -> C {
        nearest_radiance(&self.pixels, self.size, self.space, uv, lambda)
    }

    /// Samples a direction in proportion to luminance: (direction, pdf per solid angle,
    /// radiance).
    pub fn sample<C: Channels>(&self, u: Vec2, lambda: &C::Lambda) -> Option<(Vec3, f32, C)> {
        let s = self.distribution.sample(u);
        if s.pdf <= 0.0 {
            return None;
        }
        let wl = equal_area_square_to_sphere(s.point);
        let w = self.world_from_light.transform_vector3(wl).normalize();
        // The mapping is area preserving: the solid-angle density is the square's over 4π.
        Some((w, s.pdf / (4.0 * PI), self.radiance(s.point, lambda)))
    }

    /// Density of [`EnvironmentMap::sample`] for world direction `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        let wl = self.light_from_world.transform_vector3(w).normalize_or_zero();
        self.distribution.pdf(equal_area_sphere_to_square(wl)) / (4.0 * PI)
    }
}

/// pbrt-v4's reference for an image infinite light's `illuminance`: the illuminance at a point
/// facing the light space's +z axis, ∫ L cos θ over that hemisphere, as pbrt-v4 computes it
/// from a `width`×`height` image. Two of its quirks are part of every pbrt-v4 image, so nimbus
/// keeps them: it counts 2π/N steradians per texel where a texel of the equal-area map covers
/// 4π/N (half the true illuminance: image lights shine twice the illuminance asked for), and
/// it weighs the file's first three channels in the file's order, which for an OpenEXR file
/// is alphabetical (B, G, R: the caller passes `values` in that order).
pub fn reference_illuminance(values: &[Rgb], width: usize, height: usize) -> f32 {
    let mut sum = 0.0f64;
    for y in 0..height {
        for x in 0..width {
            let uv = Vec2::new((x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32);
            let w = equal_area_square_to_sphere(uv);
            if w.z > 0.0 {
                sum += (luminance(values[y * width + x]) * w.z) as f64;
            }
        }
    }
    (sum * 2.0 * PI as f64 / (width * height) as f64) as f32
}

/// The texel of a square `size`² image holding `uv`, as emitted radiance in the path's
/// channels (an illuminant spectrum for spectral transport, as pbrt-v4's image lights).
#[inline]
pub(super) fn nearest_radiance<C: Channels>(
    pixels: &[Rgb],
    size: usize,
    space: ColorSpace,
    uv: Vec2,
    lambda: &C::Lambda,
) -> C {
    let n = size as f32;
    let x = ((uv.x * n) as usize).min(size - 1);
    let y = ((uv.y * n) as usize).min(size - 1);
    C::from_rgb(pixels[y * size + x], RgbRole::Illuminant, space, lambda)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_area_mapping_round_trips() {
        for i in 0..32 {
            for j in 0..32 {
                let p = Vec2::new((i as f32 + 0.5) / 32.0, (j as f32 + 0.5) / 32.0);
                let w = equal_area_square_to_sphere(p);
                assert!((w.length() - 1.0).abs() < 1e-5);
                let q = equal_area_sphere_to_square(w);
                assert!((p - q).length() < 1e-4, "{p:?} -> {w:?} -> {q:?}");
            }
        }
    }

    #[test]
    fn sampling_pdf_matches_lookup_pdf() {
        let mut img = Image::new(8, 8);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = Rgb::splat(1.0 + (k % 5) as f32);
        }
        let map = EnvironmentMap::new(&img, ColorSpace::Srgb, Affine3A::IDENTITY, 1.0).unwrap();
        for u in [Vec2::new(0.1, 0.2), Vec2::new(0.7, 0.4), Vec2::new(0.95, 0.9)] {
            let (w, pdf, l) = map.sample::<Rgb>(u, &()).unwrap();
            assert!((map.pdf(w) - pdf).abs() < 1e-3 * pdf, "{} vs {pdf}", map.pdf(w));
            assert_eq!(map.lookup::<Rgb>(w, &()), l);
        }
        // A constant map of 1 has illuminance π; pbrt-v4's reference gives π/2.
        assert!((reference_illuminance(&[Rgb::ONE; 64 * 64], 64, 64) - PI / 2.0).abs() < 0.03);
    }
}
