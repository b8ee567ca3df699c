//! pbrt-v4's MIP map for image textures: the image resized up to powers of two with a
//! windowed sinc, a pyramid of 2×2 box-filtered levels, and a lookup whose level follows the
//! footprint of the shading point in (s, t) (`MIPMap::Filter` for its point, bilinear,
//! trilinear and elliptically weighted average filters).

use glam::Vec2;

use super::{Wrap, bilerp, texel};
use crate::color::Rgb;
use crate::imageio::Image;

/// The filter a texture's `"string filter"` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MipFilter {
    /// The nearest texel of the chosen level.
    Point,
    /// Bilinear at the chosen level (pbrt-v4's default).
    Bilinear,
    /// Bilinear at the two levels around the footprint, blended.
    Trilinear,
    /// pbrt-v4's elliptically weighted average (Heckbert's EWA with a Gaussian), over the
    /// footprint's ellipse at the two levels around its shorter axis, blended.
    Ewa,
}

/// An image and its pyramid (with its alpha channel's, if it has one).
#[derive(Clone, Debug)]
pub struct MipMap {
    levels: Vec<Image>,
    alpha: Option<Vec<Image>>,
    wrap: Wrap,
    filter: MipFilter,
    /// The `ewa` filter's largest ratio of the ellipse's axes (pbrt-v4's `maxanisotropy`).
    max_anisotropy: f32,
}

/// A lookup's result, with what pbrt-v4 makes of it for a float texture.
#[derive(Clone, Copy, Debug)]
pub struct MipSample {
    /// The filtered colour.
    pub rgb: Rgb,
    /// The filtered alpha, when the image has one.
    pub alpha: Option<f32>,
    /// Whether a single texel was read (point filter, or a footprint wider than the image),
    /// where pbrt-v4's float lookup takes the first channel instead of the mean or alpha.
    pub texel: bool,
}

impl MipSample {
    /// The value of a float texture (pbrt-v4's `MIPMap::Texel<Float>` and `Bilerp<Float>`):
    /// R for a single texel; otherwise the alpha if there is one, else the mean of R, G, B.
    pub fn float(&self) -> f32 {
        match (self.texel, self.alpha) {
            (true, _) => self.rgb.x,
            (false, Some(a)) => a,
            (false, None) => (self.rgb.x + self.rgb.y + self.rgb.z) / 3.0,
        }
    }
}

impl MipMap {
    /// The pyramid of `image` (pbrt-v4's `Image::GeneratePyramid`).
    pub fn new(image: Image, wrap: Wrap, filter: MipFilter) -> MipMap {
        let alpha = image.alpha().map(|a| {
            let mut img = Image::new(image.width, image.height);
            img.pixels = a.iter().map(|&v| Rgb::splat(v)).collect();
            pyramid(img, wrap)
        });
        MipMap { levels: pyramid(image, wrap), alpha, wrap, filter, max_anisotropy: 8.0 }
    }

    /// The same with another `maxanisotropy` for the `ewa` filter (pbrt-v4's default: 8).
    pub fn with_max_anisotropy(mut self, max_anisotropy: f32) -> MipMap {
        self.max_anisotropy = max_anisotropy;
        self
    }

    /// Whether the pyramid has levels above the finest (an image larger than one texel).
    pub fn has_levels(&self) -> bool {
        self.levels.len() > 1
    }

    /// The finest level.
    pub fn base(&self) -> &Image {
        &self.levels[0]
    }

    /// The filtered value at `st` for a footprint whose (s, t) derivatives are `dst0` (along x)
    /// and `dst1` (along y).
    pub fn lookup(&self, st: Vec2, dst0: Vec2, dst1: Vec2) -> MipSample {
        let read = |levels: &[Image], how: Read| match how {
            Read::Texel(i, x, y) => texel(&levels[i], x, y, self.wrap),
            Read::Bilerp(i) => bilerp(&levels[i], st, self.wrap),
            Read::Trilinear(i, t) => {
                (1.0 - t) * bilerp(&levels[i], st, self.wrap) + t * bilerp(&levels[i + 1], st, self.wrap)
            }
        };
        if self.filter == MipFilter::Ewa {
            if let Some(rgb) = self.ewa(st, dst0, dst1) {
                // pbrt-v4's EWA sums texels: a float texture reads their first channel.
                return MipSample { rgb, alpha: None, texel: true };
            }
            let how = Read::Bilerp(0);
            return MipSample {
                rgb: read(&self.levels, how),
                alpha: self.alpha.as_ref().map(|a| read(a, how).x),
                texel: false,
            };
        }
        let how = self.read(st, dst0, dst1);
        MipSample {
            rgb: read(&self.levels, how),
            alpha: self.alpha.as_ref().map(|a| read(a, how).x),
            texel: matches!(how, Read::Texel(..)),
        }
    }

    /// pbrt-v4's EWA branch of `MIPMap::Filter`: the ellipse spanned by the footprint's (s, t)
    /// derivatives, its shorter axis stretched to at least 1/`max_anisotropy` of the longer,
    /// filtered at the two levels around the shorter axis's length and blended; `None` for a
    /// degenerate footprint, which pbrt-v4 reads bilinearly at the finest level.
    fn ewa(&self, st: Vec2, mut dst0: Vec2, mut dst1: Vec2) -> Option<Rgb> {
        if dst0.length_squared() < dst1.length_squared() {
            std::mem::swap(&mut dst0, &mut dst1);
        }
        let longer = dst0.length();
        let mut shorter = dst1.length();
        if shorter * self.max_anisotropy < longer && shorter > 0.0 {
            let scale = longer / (shorter * self.max_anisotropy);
            dst1 *= scale;
            shorter *= scale;
        }
        if shorter == 0.0 || !shorter.is_finite() {
            return None;
        }
        // Past the coarsest level both reads are its single texel (and the index stays small).
        let lod = ((self.levels.len() - 1) as f32 + shorter.log2()).clamp(0.0, self.levels.len() as f32);
        let i = lod.floor() as usize;
        let t = lod - i as f32;
        Some((1.0 - t) * self.ewa_level(i, st, dst0, dst1) + t * self.ewa_level(i + 1, st, dst0, dst1))
    }

    /// pbrt-v4's `MIPMap::EWA` at one level: texels inside the ellipse weighted by a Gaussian
    /// of their squared radius (its 128-entry table, e^(−2r²) − e^(−2), read by truncation).
    fn ewa_level(&self, level: usize, st: Vec2, dst0: Vec2, dst1: Vec2) -> Rgb {
        let n = self.levels.len();
        if level >= n {
            return texel(&self.levels[n - 1], 0, 0, self.wrap);
        }
        let img = &self.levels[level];
        let res = Vec2::new(img.width as f32, img.height as f32);
        let (st, d0, d1) = (st * res - 0.5, dst0 * res, dst1 * res);
        // The ellipse A s² + B s t + C t² < 1 (Heckbert), widened by a texel.
        let (mut a, mut b, mut c) =
            (d0.y * d0.y + d1.y * d1.y + 1.0, -2.0 * (d0.x * d0.y + d1.x * d1.y), d0.x * d0.x + d1.x * d1.x + 1.0);
        let inv_f = 1.0 / (a * c - b * b * 0.25);
        (a, b, c) = (a * inv_f, b * inv_f, c * inv_f);
        // Its bounding box.
        let det = -b * b + 4.0 * a * c;
        let inv_det = 1.0 / det;
        let (u_sqrt, v_sqrt) = ((det * c).max(0.0).sqrt(), (a * det).max(0.0).sqrt());
        let s0 = (st.x - 2.0 * inv_det * u_sqrt).ceil() as i64;
        let s1 = (st.x + 2.0 * inv_det * u_sqrt).floor() as i64;
        let t0 = (st.y - 2.0 * inv_det * v_sqrt).ceil() as i64;
        let t1 = (st.y + 2.0 * inv_det * v_sqrt).floor() as i64;
        let lut = &*EWA_WEIGHTS;
        let (mut sum, mut weights) = (Rgb::ZERO, 0.0f32);
        for it in t0..=t1 {
            let tt = it as f32 - st.y;
            for is in s0..=s1 {
                let ss = is as f32 - st.x;
                let r2 = a * ss * ss + b * ss * tt + c * tt * tt;
                if r2 < 1.0 {
                    let w = lut[((r2 * lut.len() as f32) as usize).min(lut.len() - 1)];
                    sum += w * texel(img, is, it, self.wrap);
                    weights += w;
                }
            }
        }
        // The ellipse, a texel wider than the footprint, always holds a texel centre.
        if weights > 0.0 { sum / weights } else { Rgb::ZERO }
    }

    /// Which texels pbrt-v4's `MIPMap::Filter` reads (other filters than `ewa`).
    fn read(&self, st: Vec2, dst0: Vec2, dst1: Vec2) -> Read {
        let width = 2.0 * dst0.abs().max_element().max(dst1.abs().max_element());
        let n = self.levels.len();
        let level = (n - 1) as f32 + width.max(1e-8).log2();
        if level >= (n - 1) as f32 {
            return Read::Texel(n - 1, 0, 0);
        }
        let i = (level.floor() as i64).max(0) as usize;
        match self.filter {
            MipFilter::Point => {
                let img = &self.levels[i];
                let x = (st.x * img.width as f32 - 0.5).round() as i64;
                let y = (st.y * img.height as f32 - 0.5).round() as i64;
                Read::Texel(i, x, y)
            }
            // pbrt-v4 reads level 0 alone whenever the footprint falls below level 1.
            MipFilter::Bilinear | MipFilter::Trilinear if i == 0 => Read::Bilerp(0),
            MipFilter::Bilinear => Read::Bilerp(i),
            MipFilter::Trilinear => Read::Trilinear(i, level - i as f32),
            MipFilter::Ewa => unreachable!("read by MipMap::ewa"),
        }
    }
}

/// pbrt-v4's `MIPFilterLUT`: e^(−2 r²) − e^(−2) at r² = i/127.
static EWA_WEIGHTS: std::sync::LazyLock<[f32; 128]> =
    std::sync::LazyLock::new(|| std::array::from_fn(|i| ((-2.0 * i as f64 / 127.0).exp() - (-2.0f64).exp()) as f32));

/// What a lookup reads: one texel of a level, a level bilinearly, or two levels blended.
#[derive(Clone, Copy, Debug)]
enum Read {
    Texel(usize, i64, i64),
    Bilerp(usize),
    Trilinear(usize, f32),
}

/// pbrt-v4's `Image::GeneratePyramid`: resized up to powers of two, then halved by 2×2 box
/// filtering down to one texel.
fn pyramid(image: Image, wrap: Wrap) -> Vec<Image> {
    let mut level = if image.width.is_power_of_two() && image.height.is_power_of_two() {
        image
    } else {
        resize_up(&image, image.width.next_power_of_two(), image.height.next_power_of_two(), wrap)
    };
    let mut levels = Vec::new();
    loop {
        let (w, h) = (level.width, level.height);
        if w == 1 && h == 1 {
            levels.push(level);
            break;
        }
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let mut next = Image::new(nw, nh);
        for y in 0..nh {
            for x in 0..nw {
                let (x0, y0) = (2 * x, 2 * y);
                let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
                let p = |x: usize, y: usize| level.pixels[y * w + x];
                next.pixels[y * nw + x] = 0.25 * (p(x0, y0) + p(x1, y0) + p(x0, y1) + p(x1, y1));
            }
        }
        levels.push(std::mem::replace(&mut level, next));
    }
    levels
}

/// pbrt-v4's `WindowedSinc` with radius 2 and τ = 2 (a Lanczos kernel).
fn windowed_sinc(x: f32) -> f32 {
    let sinc =
        |x: f32| if x.abs() < 1e-5 { 1.0 } else { (std::f32::consts::PI * x).sin() / (std::f32::consts::PI * x) };
    if x.abs() > 2.0 { 0.0 } else { sinc(x) * sinc(x / 2.0) }
}

/// pbrt-v4's `ResampleWeights`: for each new pixel, its first source pixel and four weights.
fn resample_weights(old: usize, new: usize) -> Vec<(i64, [f32; 4])> {
    (0..new)
        .map(|i| {
            let center = (i as f32 + 0.5) * old as f32 / new as f32;
            let first = (center - 2.0 + 0.5).floor();
            let mut w = [0.0; 4];
            for (j, wj) in w.iter_mut().enumerate() {
                *wj = windowed_sinc(first + j as f32 + 0.5 - center);
            }
            let sum: f32 = w.iter().sum();
            (first as i64, w.map(|v| v / sum))
        })
        .collect()
}

/// pbrt-v4's `Image::FloatResizeUp`: separable windowed-sinc resampling to `w`×`h`, negative
/// results clamped to zero.
fn resize_up(image: &Image, w: usize, h: usize, wrap: Wrap) -> Image {
    let xw = resample_weights(image.width, w);
    let yw = resample_weights(image.height, h);
    // Along x, every source row.
    let mut rows = Image::new(w, image.height);
    for y in 0..image.height {
        for (x, (first, wt)) in xw.iter().enumerate() {
            let mut v = Rgb::ZERO;
            for (j, &k) in wt.iter().enumerate() {
                v += k * texel(image, first + j as i64, y as i64, wrap);
            }
            rows.pixels[y * w + x] = v;
        }
    }
    let mut out = Image::new(w, h);
    for (y, (first, wt)) in yw.iter().enumerate() {
        for x in 0..w {
            let mut v = Rgb::ZERO;
            for (j, &k) in wt.iter().enumerate() {
                v += k * texel(&rows, x as i64, first + j as i64, wrap);
            }
            out.pixels[y * w + x] = v.max(Rgb::ZERO);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Image {
        Image::from_fn(w, h, |x, y| Rgb::splat(f(x, y)))
    }

    #[test]
    fn levels_average_their_children_down_to_one_texel() {
        let m = MipMap::new(image(4, 2, |x, y| (x + 4 * y) as f32), Wrap::Clamp, MipFilter::Bilinear);
        assert_eq!(m.levels.len(), 3);
        assert_eq!(m.levels[1].pixels, vec![Rgb::splat(2.5), Rgb::splat(4.5)]);
        assert_eq!(m.levels[2].pixels, vec![Rgb::splat(3.5)]);
        // No footprint: the finest level; a footprint of the whole image: the top texel.
        let st = Vec2::new(0.125, 0.25);
        assert_eq!(m.lookup(st, Vec2::ZERO, Vec2::ZERO).rgb, Rgb::splat(0.0));
        assert_eq!(m.lookup(st, Vec2::new(0.6, 0.0), Vec2::ZERO).rgb, Rgb::splat(3.5));
        // A footprint of two texels (width 2 · 0.25 = 0.5 of the image): level 1.
        assert_eq!(m.lookup(Vec2::new(0.25, 0.5), Vec2::new(0.25, 0.0), Vec2::ZERO).rgb, Rgb::splat(2.5));
    }

    #[test]
    fn resizing_up_keeps_constants_and_powers_of_two_unchanged() {
        let m = MipMap::new(image(3, 5, |_, _| 0.7), Wrap::Repeat, MipFilter::Bilinear);
        assert_eq!((m.base().width, m.base().height), (4, 8));
        assert!(m.base().pixels.iter().all(|p| (p.x - 0.7).abs() < 1e-5));
        let ramp = image(4, 4, |x, y| (x * 4 + y) as f32);
        let same = resize_up(&ramp, 4, 4, Wrap::Clamp);
        assert!(same.pixels.iter().zip(&ramp.pixels).all(|(a, b)| (*a - *b).abs().max_element() < 1e-5));
    }

    #[test]
    fn float_lookups_read_what_pbrt_v4_reads() {
        let mut img = Image::new(2, 2);
        img.pixels = vec![Rgb::new(0.9, 0.3, 0.0); 4];
        let m = MipMap::new(img.clone(), Wrap::Clamp, MipFilter::Bilinear);
        let st = Vec2::splat(0.5);
        // Bilinear: the mean of the channels; a footprint wider than the image: one texel, R.
        assert!((m.lookup(st, Vec2::ZERO, Vec2::ZERO).float() - 0.4).abs() < 1e-6);
        assert_eq!(m.lookup(st, Vec2::splat(2.0), Vec2::ZERO).float(), 0.9);
        // Point: R.
        let p = MipMap::new(img.clone(), Wrap::Clamp, MipFilter::Point);
        assert_eq!(p.lookup(st, Vec2::ZERO, Vec2::ZERO).float(), 0.9);
        // With an alpha channel (not all one) bilinear lookups read it.
        img.channels.push(("A".into(), vec![0.25; 4]));
        let a = MipMap::new(img, Wrap::Clamp, MipFilter::Bilinear);
        assert_eq!(a.lookup(st, Vec2::ZERO, Vec2::ZERO).float(), 0.25);
    }

    /// EWA is a normalised weighted average: a constant image gives its constant for any
    /// footprint (round, elongated past `maxanisotropy`, wider than the image, degenerate);
    /// a float lookup reads the texels' first channel, as pbrt-v4's `EWA<Float>` does.
    #[test]
    fn ewa_averages_over_the_footprint() {
        let mut img = Image::new(16, 8);
        img.pixels = vec![Rgb::new(0.9, 0.3, 0.0); 16 * 8];
        let m = MipMap::new(img, Wrap::Repeat, MipFilter::Ewa).with_max_anisotropy(4.0);
        let st = Vec2::new(0.37, 0.61);
        for (d0, d1) in [
            (Vec2::new(0.01, 0.0), Vec2::new(0.0, 0.01)),
            (Vec2::new(0.2, 0.05), Vec2::new(-0.001, 0.004)),
            (Vec2::new(3.0, 0.0), Vec2::new(0.0, 2.0)),
            (Vec2::new(0.003, 0.002), Vec2::new(0.0, 0.0)),
            (Vec2::new(1e30, 0.0), Vec2::new(0.0, 1e30)),
        ] {
            let v = m.lookup(st, d0, d1);
            assert!((v.rgb - Rgb::new(0.9, 0.3, 0.0)).abs().max_element() < 1e-5, "{d0} {d1}: {}", v.rgb);
        }
        assert!((m.lookup(st, Vec2::new(0.01, 0.0), Vec2::new(0.0, 0.01)).float() - 0.9).abs() < 1e-5);
        // A checkerboard of single texels averages to its mean over a footprint of many
        // texels, and keeps its contrast under one much smaller than a texel.
        let mut img = Image::new(64, 64);
        img.pixels = (0..64 * 64).map(|i| Rgb::splat(((i % 64 + i / 64) % 2) as f32)).collect();
        let m = MipMap::new(img, Wrap::Repeat, MipFilter::Ewa);
        let wide = m.lookup(st, Vec2::new(0.1, 0.0), Vec2::new(0.0, 0.1)).rgb.x;
        assert!((wide - 0.5).abs() < 0.02, "{wide}");
        let centre = Vec2::new(10.5, 20.5) / 64.0;
        let sharp = m.lookup(centre, Vec2::new(1e-4, 0.0), Vec2::new(0.0, 1e-4)).rgb.x;
        assert!((sharp - 0.5).abs() > 0.3, "{sharp}");
    }
}
