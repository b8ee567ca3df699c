//! pbrt-v4's infinite light seen through a portal (`"point3 portal"`, Bitterli et al. 2015's
//! rectified parameterisation as *Physically Based Rendering*, 4th ed., Sec. 12.5.3 writes
//! it): the environment is resampled into the portal's frame, where the directions through the
//! rectangle from any point form an axis-aligned window of the image; light sampling draws
//! from that window only. As in pbrt-v4 the environment is seen only through the portal: a
//! ray that leaves the scene elsewhere brings nothing back.

use std::f32::consts::PI;

use glam::{Affine3A, Vec2, Vec3};
use nimbus_parser::ColorSpace;

use super::envmap::nearest_radiance;
use crate::channels::Channels;
use crate::color::{Rgb, average};
use crate::error::{Error, Result};
use crate::imageio::Image;
use crate::math::Frame;
use crate::sampling::warp::equal_area_sphere_to_square;

/// An environment behind a rectangular portal, rectified, with its windowed sampling table.
#[derive(Clone, Debug)]
pub struct PortalMap {
    size: usize,
    /// The rectified image (scaled), rows by v.
    pixels: Vec<Rgb>,
    space: ColorSpace,
    /// The portal's corners (world space), in the scene file's order.
    portal: [Vec3; 4],
    /// x along corner 0 → 3, y along 0 → 1, z their cross product (into the scene's
    /// outside, where the light comes from).
    frame: Frame,
    /// Per pixel: mean channel × the map's Jacobian d(u,v)/dω at its centre.
    func: Vec<f32>,
    /// Integrals of `func` over [0, i/n] × [0, j/n], (n + 1)² of them.
    sat: Vec<f64>,
}

impl PortalMap {
    /// The environment of square equal-area `image` (color space `space`, oriented by
    /// `world_from_light`, scaled by `scale`) behind the rectangle `portal` (world space).
    pub fn new(
        image: &Image,
        space: ColorSpace,
        world_from_light: Affine3A,
        scale: f32,
        portal: [Vec3; 4],
    ) -> Result<PortalMap> {
        if image.width != image.height || image.width == 0 {
            return Err(Error::Invalid(format!(
                "the portal light's image is {}x{}; pbrt-v4 environment maps are square equal-area images",
                image.width, image.height
            )));
        }
        let frame = portal_frame(&portal)?;
        let n = image.width;
        let light_from_world = world_from_light.inverse();
        let mut map = PortalMap {
            size: n,
            pixels: Vec::with_capacity(n * n),
            space,
            portal,
            frame,
            func: Vec::with_capacity(n * n),
            sat: Vec::new(),
        };
        for y in 0..n {
            for x in 0..n {
                let uv = Vec2::new((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
                let (w, duv_dw) = map.render_from_image(uv);
                let wl = light_from_world.transform_vector3(w).normalize();
                let rgb = bilerp_octahedral(image, equal_area_sphere_to_square(wl)).max(Rgb::ZERO) * scale;
                map.pixels.push(rgb);
                map.func.push(average(rgb) * duv_dw);
            }
        }
        map.sat = summed_area(&map.func, n);
        Ok(map)
    }

    /// Applies `f` to every pixel (RGB transport through a camera sensor); the sampling
    /// table is kept, as it only needs to be roughly proportional.
    pub fn map_pixels(&mut self, f: impl Fn(Rgb) -> Rgb) {
        self.pixels.iter_mut().for_each(|p| *p = f(*p));
    }

    /// The portal's area.
    fn area(&self) -> f32 {
        (self.portal[1] - self.portal[0]).length() * (self.portal[3] - self.portal[0]).length()
    }

    /// Power-like weight for choosing among lights (pbrt-v4's `Phi`, channel mean).
    pub fn power(&self) -> f32 {
        let n = self.size;
        let mut sum = 0.0f64;
        for y in 0..n {
            for x in 0..n {
                let uv = Vec2::new((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
                let (_, duv_dw) = self.render_from_image(uv);
                sum += f64::from(average(self.pixels[y * n + x]) / duv_dw);
            }
        }
        self.area() * (sum / (n * n) as f64) as f32
    }

    /// The image point of world direction `w` and the Jacobian d(u,v)/dω there; `None`
    /// for directions not towards the portal's outside.
    fn image_from_render(&self, w: Vec3) -> Option<(Vec2, f32)> {
        let l = self.frame.to_local(w);
        if l.z <= 0.0 {
            return None;
        }
        let duv_dw = PI * PI * (1.0 - l.x * l.x) * (1.0 - l.y * l.y) / l.z;
        let (alpha, beta) = (l.x.atan2(l.z), l.y.atan2(l.z));
        let uv = Vec2::new(((alpha + PI / 2.0) / PI).clamp(0.0, 1.0), ((beta + PI / 2.0) / PI).clamp(0.0, 1.0));
        Some((uv, duv_dw))
    }

    /// The world direction of image point `uv` and the Jacobian d(u,v)/dω there.
    fn render_from_image(&self, uv: Vec2) -> (Vec3, f32) {
        let (alpha, beta) = (-PI / 2.0 + uv.x * PI, -PI / 2.0 + uv.y * PI);
        let w = Vec3::new(alpha.tan(), beta.tan(), 1.0).normalize();
        let duv_dw = PI * PI * (1.0 - w.x * w.x) * (1.0 - w.y * w.y) / w.z;
        (self.frame.to_world(w), duv_dw)
    }

    /// The window of the image seen through the portal from `p`.
    fn image_bounds(&self, p: Vec3) -> Option<[Vec2; 2]> {
        let (a, _) = self.image_from_render((self.portal[0] - p).normalize())?;
        let (b, _) = self.image_from_render((self.portal[2] - p).normalize())?;
        Some([a.min(b), a.max(b)])
    }

    /// The pixel at `uv` as emitted radiance (nearest, as pbrt-v4 looks it up).
    fn lookup<C: Channels>(&self, uv: Vec2, lambda: &C::Lambda) -> C {
        nearest_radiance(&self.pixels, self.size, self.space, uv, lambda)
    }

    /// Radiance along a ray from `o` leaving the scene in direction `d`: the environment if
    /// the ray passes through the portal, else nothing.
    pub fn le<C: Channels>(&self, o: Vec3, d: Vec3, lambda: &C::Lambda) -> C {
        let (Some((uv, _)), Some([lo, hi])) = (self.image_from_render(d.normalize()), self.image_bounds(o)) else {
            return C::ZERO;
        };
        if uv.cmpge(lo).all() && uv.cmple(hi).all() { self.lookup(uv, lambda) } else { C::ZERO }
    }

    /// A direction from `p` through the portal, in proportion to the radiance there:
    /// (direction, density per solid angle, radiance).
    pub fn sample<C: Channels>(&self, p: Vec3, u: Vec2, lambda: &C::Lambda) -> Option<(Vec3, f32, C)> {
        let window = self.image_bounds(p)?;
        let (uv, map_pdf) = self.sample_window(u, window)?;
        let (wi, duv_dw) = self.render_from_image(uv);
        if duv_dw == 0.0 {
            return None;
        }
        Some((wi, map_pdf / duv_dw, self.lookup(uv, lambda)))
    }

    /// Density of [`PortalMap::sample`] from `p` for direction `w`.
    pub fn pdf(&self, p: Vec3, w: Vec3) -> f32 {
        let Some((uv, duv_dw)) = self.image_from_render(w) else { return 0.0 };
        if duv_dw == 0.0 {
            return 0.0;
        }
        let Some(window) = self.image_bounds(p) else { return 0.0 };
        // Outside the window nothing is sampled (pbrt-v4 returns the window's density there
        // too, harmlessly: no radiance comes from those directions).
        if !(uv.cmpge(window[0]).all() && uv.cmple(window[1]).all()) {
            return 0.0;
        }
        let integral = self.integral(window);
        if integral <= 0.0 { 0.0 } else { (f64::from(self.eval(uv)) / integral) as f32 / duv_dw }
    }

    /// A direction light arrives from (photon emission), drawn from the whole image as
    /// pbrt-v4's `SampleLe` does: (direction towards the environment, density per solid angle,
    /// radiance).
    pub fn sample_emission<C: Channels>(&self, u: Vec2, lambda: &C::Lambda) -> Option<(Vec3, f32, C)> {
        let (uv, map_pdf) = self.sample_window(u, [Vec2::ZERO, Vec2::ONE])?;
        let (w, duv_dw) = self.render_from_image(uv);
        if duv_dw == 0.0 {
            return None;
        }
        Some((w, map_pdf / duv_dw, self.lookup(uv, lambda)))
    }

    /// `func` at the pixel holding `uv`.
    fn eval(&self, uv: Vec2) -> f32 {
        let n = self.size;
        let x = ((uv.x * n as f32) as usize).min(n - 1);
        let y = ((uv.y * n as f32) as usize).min(n - 1);
        self.func[y * n + x]
    }

    /// ∫ func over [0, u] × [0, v]: the summed-area table interpolated bilinearly, which is
    /// exact for a piecewise-constant function.
    fn cumulative(&self, p: Vec2) -> f64 {
        let n = self.size;
        let (x, y) = (f64::from(p.x.clamp(0.0, 1.0)) * n as f64, f64::from(p.y.clamp(0.0, 1.0)) * n as f64);
        let (xi, yi) = ((x as usize).min(n - 1), (y as usize).min(n - 1));
        let (dx, dy) = (x - xi as f64, y - yi as f64);
        let at = |i: usize, j: usize| self.sat[j * (n + 1) + i];
        (1.0 - dx) * (1.0 - dy) * at(xi, yi)
            + dx * (1.0 - dy) * at(xi + 1, yi)
            + (1.0 - dx) * dy * at(xi, yi + 1)
            + dx * dy * at(xi + 1, yi + 1)
    }

    /// ∫ func over the window [lo, hi].
    fn integral(&self, [lo, hi]: [Vec2; 2]) -> f64 {
        self.cumulative(hi) - self.cumulative(Vec2::new(lo.x, hi.y)) - self.cumulative(Vec2::new(hi.x, lo.y))
            + self.cumulative(lo)
    }

    /// pbrt-v4's `WindowedPiecewiseConstant2D::Sample`: x from the window's marginal, y from
    /// the conditional in the pixel column of x; the point and its density on the image.
    fn sample_window(&self, u: Vec2, [lo, hi]: [Vec2; 2]) -> Option<(Vec2, f32)> {
        let total = self.integral([lo, hi]);
        if total <= 0.0 {
            return None;
        }
        let n = self.size as f32;
        let x = invert(|x| self.integral([lo, Vec2::new(x, hi.y)]) / total, f64::from(u.x), lo.x, hi.x, self.size);
        let (mut c0, mut c1) = ((x * n).floor() / n, (x * n).ceil() / n);
        if c0 == c1 {
            c1 += 1.0 / n;
        }
        c0 = c0.max(0.0);
        let column = self.integral([Vec2::new(c0, lo.y), Vec2::new(c1, hi.y)]);
        if column <= 0.0 {
            return None;
        }
        let y = invert(
            |y| self.integral([Vec2::new(c0, lo.y), Vec2::new(c1, y)]) / column,
            f64::from(u.y),
            lo.y,
            hi.y,
            self.size,
        );
        let p = Vec2::new(x, y);
        Some((p, (f64::from(self.eval(p)) / total) as f32))
    }
}

/// The portal's frame (x along corner 0 → 3, y along 0 → 1, z out of the scene through it),
/// or why the corners are not a rectangle (pbrt-v4's checks: opposite edges parallel, corners
/// at right angles), which is [`Error::Invalid`].
pub fn portal_frame(portal: &[Vec3; 4]) -> Result<Frame> {
    let edge = |a: usize, b: usize| (portal[b] - portal[a]).normalize_or_zero();
    let (p01, p12, p32, p03) = (edge(0, 1), edge(1, 2), edge(3, 2), edge(0, 3));
    let planar = (p01.dot(p32) - 1.0).abs() <= 1e-3 && (p12.dot(p03) - 1.0).abs() <= 1e-3;
    let square = [p01.dot(p12), p12.dot(p32), p32.dot(p03), p03.dot(p01)].iter().all(|d| d.abs() <= 1e-3);
    if !planar || !square {
        return Err(Error::invalid(
            "the portal is not a rectangle (pbrt-v4 needs its 4 corners in order, at right angles)",
        ));
    }
    Ok(Frame { x: p03, y: p01, z: p03.cross(p01) })
}

/// The x in [lo, hi] where the increasing, piecewise-linear (between multiples of 1/n)
/// function `cdf` reaches `u`: bisection down to one piece, then linear (pbrt-v4's
/// `SampleBisection`).
fn invert(cdf: impl Fn(f32) -> f64, u: f64, mut lo: f32, mut hi: f32, n: usize) -> f32 {
    let n = n as f32;
    while (n * hi).ceil() - (n * lo).floor() > 1.0 {
        let mid = (lo + hi) / 2.0;
        if mid <= lo || mid >= hi {
            break;
        }
        if cdf(mid) > u {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let (a, b) = (cdf(lo), cdf(hi));
    let t = if b > a { ((u - a) / (b - a)) as f32 } else { 0.5 };
    (lo + t * (hi - lo)).clamp(lo, hi)
}

/// Integrals of a piecewise-constant `func` (n × n pixels over [0, 1]²) over [0, i/n] × [0, j/n].
fn summed_area(func: &[f32], n: usize) -> Vec<f64> {
    let mut sat = vec![0.0f64; (n + 1) * (n + 1)];
    let cell = 1.0 / (n * n) as f64;
    for j in 0..n {
        let mut row = 0.0f64;
        for i in 0..n {
            row += f64::from(func[j * n + i]) * cell;
            sat[(j + 1) * (n + 1) + i + 1] = sat[j * (n + 1) + i + 1] + row;
        }
    }
    sat
}

/// Bilinear lookup of an equal-area octahedral image at `uv`, wrapping across its edges as the
/// sphere does (pbrt-v4's `WrapMode::OctahedralSphere`).
fn bilerp_octahedral(image: &Image, uv: Vec2) -> Rgb {
    let (w, h) = (image.width as i64, image.height as i64);
    let x = uv.x * w as f32 - 0.5;
    let y = uv.y * h as f32 - 0.5;
    let (xi, yi) = (x.floor() as i64, y.floor() as i64);
    let (dx, dy) = (x - xi as f32, y - yi as f32);
    let at = |mut px: i64, mut py: i64| {
        if px < 0 {
            px = -px - 1;
            py = h - 1 - py;
        } else if px >= w {
            px = 2 * w - 1 - px;
            py = h - 1 - py;
        }
        if py < 0 {
            px = w - 1 - px;
            py = -py - 1;
        } else if py >= h {
            px = w - 1 - px;
            py = 2 * h - 1 - py;
        }
        if w == 1 {
            px = 0;
        }
        if h == 1 {
            py = 0;
        }
        image.pixels[(py.clamp(0, h - 1) * w + px.clamp(0, w - 1)) as usize]
    };
    at(xi, yi) * ((1.0 - dx) * (1.0 - dy))
        + at(xi + 1, yi) * (dx * (1.0 - dy))
        + at(xi, yi + 1) * ((1.0 - dx) * dy)
        + at(xi + 1, yi + 1) * (dx * dy)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16² environment with structure, behind a 1 × 0.6 portal in the plane z = 2 (the
    /// outside is +z).
    fn map() -> PortalMap {
        let mut img = Image::new(16, 16);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = Rgb::new(1.0 + (k % 7) as f32, 0.5 + (k % 3) as f32, 2.0);
        }
        // pbrt-v4's order: (corner 3 − corner 0) × (corner 1 − corner 0) points out of the
        // scene, through the portal.
        let portal = [
            Vec3::new(-0.5, -0.3, 2.0),
            Vec3::new(-0.5, 0.3, 2.0),
            Vec3::new(0.5, 0.3, 2.0),
            Vec3::new(0.5, -0.3, 2.0),
        ];
        PortalMap::new(&img, ColorSpace::Srgb, Affine3A::IDENTITY, 1.0, portal).unwrap()
    }

    /// Samples go through the portal, carry the radiance the light sends along them, and
    /// their density is the one `pdf` gives; from points off the axis too.
    #[test]
    fn samples_pass_the_portal_with_consistent_densities() {
        let m = map();
        for p in [Vec3::ZERO, Vec3::new(0.7, -0.2, 0.5)] {
            for i in 0..64 {
                let u = Vec2::new((i as f32 * 0.618_034).fract(), (i as f32 + 0.5) / 64.0);
                let (w, pdf, l) = m.sample::<Rgb>(p, u, &()).unwrap();
                // Through the rectangle: the ray meets z = 2 inside it.
                let t = (2.0 - p.z) / w.z;
                let hit = p + w * t;
                assert!(t > 0.0 && hit.x.abs() <= 0.5 + 1e-3 && hit.y.abs() <= 0.3 + 1e-3, "{hit}");
                assert!((m.pdf(p, w) / pdf - 1.0).abs() < 1e-3, "pdf {} vs {pdf}", m.pdf(p, w));
                assert_eq!(m.le::<Rgb>(p, w, &()), l);
            }
        }
    }

    /// The densities integrate to one over the directions through the portal (a quadrature
    /// over the sphere), and a direction that misses the portal has none and no radiance.
    #[test]
    fn density_integrates_to_one_over_the_portal() {
        let m = map();
        let p = Vec3::new(0.2, 0.1, 0.0);
        let n = 600;
        let mut sum = 0.0f64;
        for j in 0..n {
            for i in 0..2 * n {
                let cos = 1.0 - (j as f32 + 0.5) / n as f32;
                let phi = 2.0 * PI * (i as f32 + 0.5) / (2 * n) as f32;
                let s = (1.0 - cos * cos).sqrt();
                let w = Vec3::new(s * phi.cos(), s * phi.sin(), cos);
                sum += f64::from(m.pdf(p, w)) * (2.0 * PI as f64 / (2 * n) as f64) * (1.0 / n as f64);
            }
        }
        assert!((sum - 1.0).abs() < 0.01, "∫ pdf = {sum}");
        let away = Vec3::new(0.9, 0.0, 0.3).normalize();
        assert_eq!(m.pdf(p, away), 0.0);
        assert_eq!(m.le::<Rgb>(p, away, &()), Rgb::ZERO);
    }
}
