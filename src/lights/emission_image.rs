//! Image-textured emission: pbrt-v4's `diffuse` area light with a `filename`, whose radiance
//! at a point is the image at the shape's (u, v).

use glam::Vec2;
use nimbus_parser::ColorSpace;

use crate::channels::Channels;
use crate::color::{Rgb, luminance};
use crate::error::{Error, Result};
use crate::imageio::Image;
use crate::spectra::RgbRole;

/// An area light's emission image: linear RGB texels and the colour space they are in.
#[derive(Clone, Debug)]
pub struct EmissionImage {
    width: usize,
    height: usize,
    pixels: Vec<Rgb>,
    space: ColorSpace,
}

impl EmissionImage {
    /// The emission image `image` in colour space `space`; like pbrt-v4, refuses an empty
    /// image and one with infinite or NaN texels ([`Error::Invalid`]: the image may not come
    /// from a file, so the caller names where it came from).
    pub fn new(image: &Image, space: ColorSpace) -> Result<EmissionImage> {
        if image.width == 0 || image.height == 0 {
            return Err(Error::invalid("the emission image is empty"));
        }
        if image.pixels.iter().any(|p| !p.is_finite()) {
            return Err(Error::invalid(
                "the image has infinite or not-a-number texels and so is not suitable as a light",
            ));
        }
        Ok(EmissionImage { width: image.width, height: image.height, pixels: image.pixels.clone(), space })
    }

    /// Applies `f` to every texel (RGB transport through a camera sensor converts each texel
    /// once).
    pub fn map_pixels(&mut self, f: impl Fn(Rgb) -> Rgb) {
        for p in &mut self.pixels {
            *p = f(*p);
        }
    }

    /// The emitted radiance at surface coordinates `uv`, as pbrt-v4's `DiffuseAreaLight::L`:
    /// the image is read at (u, 1 − v) (its rows run top to bottom), interpolated bilinearly
    /// between texel centres with clamped edges, negative values clamped to zero, and turned
    /// into an illuminant spectrum for spectral transport.
    pub fn radiance<C: Channels>(&self, uv: Vec2, lambda: &C::Lambda) -> C {
        let rgb = self.bilerp(Vec2::new(uv.x, 1.0 - uv.y)).max(Rgb::ZERO);
        C::from_rgb(rgb, RgbRole::Illuminant, self.space, lambda)
    }

    fn texel(&self, x: i64, y: i64) -> Rgb {
        let x = x.clamp(0, self.width as i64 - 1) as usize;
        let y = y.clamp(0, self.height as i64 - 1) as usize;
        self.pixels[y * self.width + x]
    }

    /// pbrt-v4's `Image::Bilerp` with clamped wrapping.
    fn bilerp(&self, st: Vec2) -> Rgb {
        let x = st.x * self.width as f32 - 0.5;
        let y = st.y * self.height as f32 - 0.5;
        let (xf, yf) = (x.floor(), y.floor());
        let (dx, dy) = (x - xf, y - yf);
        let (xi, yi) = (xf as i64, yf as i64);
        (1.0 - dx) * (1.0 - dy) * self.texel(xi, yi)
            + dx * (1.0 - dy) * self.texel(xi + 1, yi)
            + (1.0 - dx) * dy * self.texel(xi, yi + 1)
            + dx * dy * self.texel(xi + 1, yi + 1)
    }

    /// The mean over texels and channels (pbrt-v4's light-BVH power estimate of the image).
    pub fn mean_channel(&self) -> f32 {
        let sum: f64 = self.pixels.iter().map(|p| (p.x + p.y + p.z) as f64).sum();
        (sum / (3 * self.pixels.len()) as f64) as f32
    }

    /// The mean luminance of the texels (pbrt-v4's `power` normalisation of the image).
    pub fn mean_luminance(&self) -> f32 {
        let sum: f64 = self.pixels.iter().map(|p| luminance(*p) as f64).sum();
        (sum / self.pixels.len() as f64) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> EmissionImage {
        EmissionImage::new(&Image::from_fn(w, h, |x, y| Rgb::splat(f(x, y))), ColorSpace::Srgb).unwrap()
    }

    #[test]
    fn texel_centres_are_exact_and_v_runs_up_the_image() {
        // 4×2 texels valued x + 10·y; (u, v) = (0.375, 0.75) is the centre of texel (1, 0):
        // v = 0.75 is the top row's centre because pbrt-v4 reads rows at 1 − v.
        let e = image(4, 2, |x, y| x as f32 + 10.0 * y as f32);
        let at = |u: f32, v: f32| e.radiance::<Rgb>(Vec2::new(u, v), &()).x;
        assert!((at(0.375, 0.75) - 1.0).abs() < 1e-5);
        assert!((at(0.375, 0.25) - 11.0).abs() < 1e-5);
        // Halfway between the centres of texels 1 and 2 of the bottom row; the edges clamp.
        assert!((at(0.5, 0.25) - 11.5).abs() < 1e-5);
        assert!((at(0.0, 0.0) - 10.0).abs() < 1e-5 && (at(1.0, 1.0) - 3.0).abs() < 1e-5);
        assert!((e.mean_channel() - 6.5).abs() < 1e-5 && (e.mean_luminance() - 6.5).abs() < 1e-3);
    }

    #[test]
    fn unusable_images_are_refused() {
        let mut img = Image::new(2, 2);
        img.pixels[3] = Rgb::new(f32::NAN, 0.0, 0.0);
        assert!(EmissionImage::new(&img, ColorSpace::Srgb).is_err());
        assert!(EmissionImage::new(&Image::new(0, 0), ColorSpace::Srgb).is_err());
    }
}
