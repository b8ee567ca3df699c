//! pbrt-v4's `realistic` camera (Kolb, Mitchell and Hanrahan 1995; *Physically Based
//! Rendering*, 4th ed., Sec. 5.3): a film behind a system of spherical lens elements and an
//! aperture stop, read from a lens file, focused by a thick-lens approximation and sampled
//! through bounds on its exit pupil. Units are metres; lens space is camera space with z
//! mirrored, the film at z = 0 and the elements towards −z.

use std::sync::{Arc, Mutex};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::camera::settings::{Aperture, RealisticSettings};
use crate::error::{Error, Result};
use crate::math::{quadratic, refract, sqr};
use crate::samplers::radical_inverse;

/// Film rings over which exit-pupil bounds are found (pbrt-v4's 64).
const PUPIL_RINGS: usize = 64;

/// Points tried per ring on the rear element's plane: pbrt-v4's 2²⁰. Its bounds are part of
/// its answer: with a shaped aperture they cut a sliver off the pupil's blurred edge, and
/// 2¹⁶ points (looser bounds) rendered a square aperture 3.2 % brighter than pbrt-v4 and a
/// pentagon 0.4 % (a round stop: the same within 0.05 %). Finding them takes about 2 s on two
/// cores, so lenses are kept for reuse ([`RealisticLens::shared`]).
const PUPIL_SAMPLES: u32 = 1 << 20;

/// Lenses built in this process, most recent last (a few: one per scene rendered).
static BUILT: Mutex<Vec<(LensKey, Arc<RealisticLens>)>> = Mutex::new(Vec::new());

/// What a lens is built from.
type LensKey = (RealisticSettings, [u32; 2], u32);

/// Resolution of the built-in aperture shapes (pbrt-v4's 256).
const BUILTIN_APERTURE_RES: usize = 256;

/// One interface between lens elements (or the aperture stop, of curvature 0).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Interface {
    curvature_radius: f32,
    thickness: f32,
    eta: f32,
    aperture_radius: f32,
}

/// A grey image over the aperture stop's square, weighting what passes (pbrt-v4's
/// `apertureImage`), normalised so a full image passes as much as the round stop.
#[derive(Clone, Debug, PartialEq)]
struct ApertureImage {
    width: usize,
    height: usize,
    /// Rows bottom to top (pbrt-v4 flips the image read top to bottom).
    values: Vec<f32>,
}

impl ApertureImage {
    /// Bilinear lookup at `uv` in [0, 1]², black outside (pbrt-v4's `BilerpChannel` with
    /// `WrapMode::Black`).
    fn bilerp(&self, uv: Vec2) -> f32 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (xi, yi) = (x.floor(), y.floor());
        let (dx, dy) = (x - xi, y - yi);
        let at = |x: f32, y: f32| {
            if x < 0.0 || y < 0.0 || x >= self.width as f32 || y >= self.height as f32 {
                0.0
            } else {
                self.values[y as usize * self.width + x as usize]
            }
        };
        (1.0 - dx) * (1.0 - dy) * at(xi, yi)
            + dx * (1.0 - dy) * at(xi + 1.0, yi)
            + (1.0 - dx) * dy * at(xi, yi + 1.0)
            + dx * dy * at(xi + 1.0, yi + 1.0)
    }
}

/// A ray in lens or camera space.
#[derive(Clone, Copy, Debug)]
struct LensRay {
    o: Vec3,
    d: Vec3,
}

impl LensRay {
    fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }

    /// The same ray with z mirrored (camera space ↔ lens space).
    fn mirrored(&self) -> LensRay {
        let m = Vec3::new(1.0, 1.0, -1.0);
        LensRay { o: self.o * m, d: self.d * m }
    }
}

/// The lens system of a realistic camera, focused, with its exit-pupil bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct RealisticLens {
    /// From the scene side (first in the file) to the film side.
    interfaces: Vec<Interface>,
    /// The film's physical extent: its half-size in x and y.
    half_extent: Vec2,
    /// The film's diagonal.
    diagonal: f32,
    /// Per film ring (distance from the film's centre), bounds [min, max] on the rear
    /// element's plane of where rays get through, or `None` where none do.
    pupil_bounds: Vec<Option<[Vec2; 2]>>,
    aperture: Option<ApertureImage>,
}

impl RealisticLens {
    /// [`RealisticLens::new`], or the same lens built before in this process (renders of one
    /// scene at several seeds or with several integrators find its exit pupil once).
    pub fn shared(settings: &RealisticSettings, resolution: [u32; 2], diagonal_mm: f32) -> Result<Arc<RealisticLens>> {
        let key: LensKey = (settings.clone(), resolution, diagonal_mm.to_bits());
        let built = |b: &[(LensKey, Arc<RealisticLens>)]| b.iter().find(|(k, _)| *k == key).map(|(_, l)| l.clone());
        if let Some(lens) = built(&BUILT.lock().unwrap_or_else(|e| e.into_inner())) {
            return Ok(lens);
        }
        let lens = Arc::new(RealisticLens::new(settings, resolution, diagonal_mm)?);
        let mut b = BUILT.lock().unwrap_or_else(|e| e.into_inner());
        if b.len() >= 4 {
            b.remove(0);
        }
        b.push((key, lens.clone()));
        Ok(lens)
    }

    /// The lens of `settings` focused at its focus distance, for a film of `resolution`
    /// pixels with a diagonal of `diagonal_mm`. Fails with pbrt-v4's reasons (no ray gets
    /// through, the focus distance is too short for the lens: [`Error::Invalid`]) or an
    /// aperture image's file error.
    pub fn new(settings: &RealisticSettings, resolution: [u32; 2], diagonal_mm: f32) -> Result<RealisticLens> {
        Self::with_pupil_samples(settings, resolution, diagonal_mm, PUPIL_SAMPLES)
    }

    /// Whether a lens can be built (it lets light through and focuses at its distance),
    /// without finding its exit pupil: what `nimbus check` asks.
    pub fn validate(settings: &RealisticSettings, resolution: [u32; 2], diagonal_mm: f32) -> Result<()> {
        Self::with_pupil_samples(settings, resolution, diagonal_mm, 0).map(|_| ())
    }

    /// [`RealisticLens::new`] with `samples` points per ring for the exit-pupil bounds (unit
    /// tests use fewer: any bounds that hold the pupil give the same expected value; none
    /// leaves them empty, for [`RealisticLens::validate`]).
    fn with_pupil_samples(
        settings: &RealisticSettings,
        resolution: [u32; 2],
        diagonal_mm: f32,
        samples: u32,
    ) -> Result<RealisticLens> {
        let diagonal = diagonal_mm * 0.001;
        let aspect = resolution[1] as f32 / resolution[0] as f32;
        let x = (sqr(diagonal) / (1.0 + sqr(aspect))).sqrt();
        let half_extent = Vec2::new(x / 2.0, aspect * x / 2.0);
        let mut interfaces = Vec::with_capacity(settings.elements.len());
        for e in &settings.elements {
            let [curvature, thickness, eta, aperture_diameter] = *e;
            let mut aperture_diameter = aperture_diameter / 1000.0;
            if curvature == 0.0 {
                // The stop opens to the requested diameter, at most to the lens's own.
                aperture_diameter = aperture_diameter.min(settings.aperture_diameter / 1000.0);
            }
            interfaces.push(Interface {
                curvature_radius: curvature / 1000.0,
                thickness: thickness / 1000.0,
                eta,
                aperture_radius: aperture_diameter / 2.0,
            });
        }
        let aperture = settings.aperture.as_ref().map(aperture_image).transpose()?;
        let mut lens = RealisticLens { interfaces, half_extent, diagonal, pupil_bounds: Vec::new(), aperture };
        let last = lens.interfaces.len() - 1;
        lens.interfaces[last].thickness = lens.focus_thick_lens(settings.focus_distance).map_err(Error::Invalid)?;
        if samples == 0 {
            return Ok(lens);
        }
        lens.pupil_bounds = (0..PUPIL_RINGS)
            .into_par_iter()
            .map(|i| {
                let r0 = i as f32 / PUPIL_RINGS as f32 * diagonal / 2.0;
                let r1 = (i + 1) as f32 / PUPIL_RINGS as f32 * diagonal / 2.0;
                lens.bound_exit_pupil(r0, r1, samples)
            })
            .collect();
        Ok(lens)
    }

    /// Distance from the film to the rear element.
    fn rear_z(&self) -> f32 {
        self.interfaces.last().map_or(0.0, |e| e.thickness)
    }

    /// Distance from the film to the front element.
    fn front_z(&self) -> f32 {
        self.interfaces.iter().map(|e| e.thickness).sum()
    }

    fn rear_radius(&self) -> f32 {
        self.interfaces.last().map_or(0.0, |e| e.aperture_radius)
    }

    /// The ray through continuous raster position `p_film` of a film of `resolution` and
    /// the exit-pupil sample `u_lens`, in camera space (direction not normalised), with its
    /// weight cos⁴θ / (p·z²) times the aperture image's; `None` when the lens stops it.
    pub fn generate(&self, p_film: Vec2, resolution: Vec2, u_lens: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let s = p_film / resolution;
        let p = -self.half_extent + s * 2.0 * self.half_extent;
        let p_film = Vec3::new(-p.x, p.y, 0.0);
        let (p_pupil, pdf) = self.sample_exit_pupil(Vec2::new(p_film.x, p_film.y), u_lens)?;
        let r_film = LensRay { o: p_film, d: p_pupil - p_film };
        let (out, weight) = self.trace_from_film(r_film)?;
        let cos_theta = r_film.d.normalize().z;
        let weight = weight * sqr(sqr(cos_theta)) / (pdf * sqr(self.rear_z()));
        Some((out.o, out.d, weight))
    }

    /// The film position (raster, for a film of `resolution`) and exit-pupil sample of a
    /// camera-space ray `o + t·d` that [`RealisticLens::generate`] made, found by tracing it
    /// back through the lens to the film: what pbrt-v4's numerical differentials shift and
    /// regenerate. `None` where the ray does not go back through the lens (rounding at an
    /// element's rim) or falls outside the pupil bounds it came from.
    pub fn film_sample(&self, o: Vec3, d: Vec3, resolution: Vec2) -> Option<(Vec2, Vec2)> {
        // Back along the ray from a point just outside the front element.
        let back = LensRay { o: o + d.normalize() * (0.1 * self.rear_z()), d: -d };
        let r = self.trace_from_scene(back)?;
        if r.d.z >= 0.0 {
            return None;
        }
        let film = r.at(-r.o.z / r.d.z);
        let pupil = r.at((self.rear_z() - r.o.z) / r.d.z);
        // Undo generate's film mapping and sample_exit_pupil's bounds and rotation.
        let p = Vec2::new(-film.x, film.y);
        let raster = (p + self.half_extent) / (2.0 * self.half_extent) * resolution;
        let r_film = Vec2::new(film.x, film.y).length();
        let ring = ((r_film / (self.diagonal / 2.0) * PUPIL_RINGS as f32) as usize).min(PUPIL_RINGS - 1);
        let [lo, hi] = self.pupil_bounds[ring]?;
        let (sin, cos) = if r_film != 0.0 { (film.y / r_film, film.x / r_film) } else { (0.0, 1.0) };
        let p_lens = Vec2::new(cos * pupil.x + sin * pupil.y, -sin * pupil.x + cos * pupil.y);
        let u_lens = (p_lens - lo) / (hi - lo);
        (raster.is_finite() && u_lens.is_finite()).then_some((raster, u_lens.clamp(Vec2::ZERO, Vec2::ONE)))
    }

    /// A point on the rear element's plane within the exit-pupil bounds of the film ring at
    /// `p_film`, rotated to `p_film`'s angle, and its density.
    fn sample_exit_pupil(&self, p_film: Vec2, u_lens: Vec2) -> Option<(Vec3, f32)> {
        let r_film = p_film.length();
        let ring = ((r_film / (self.diagonal / 2.0) * PUPIL_RINGS as f32) as usize).min(PUPIL_RINGS - 1);
        let [lo, hi] = self.pupil_bounds[ring]?;
        let p_lens = lo + u_lens * (hi - lo);
        let area = (hi.x - lo.x) * (hi.y - lo.y);
        let (sin, cos) = if r_film != 0.0 { (p_film.y / r_film, p_film.x / r_film) } else { (0.0, 1.0) };
        let p = Vec3::new(cos * p_lens.x - sin * p_lens.y, sin * p_lens.x + cos * p_lens.y, self.rear_z());
        Some((p, 1.0 / area))
    }

    /// Traces a camera-space ray leaving the film through the elements, rear to front: the
    /// camera-space ray leaving the front element and the aperture image's weight, or `None`.
    fn trace_from_film(&self, r: LensRay) -> Option<(LensRay, f32)> {
        let mut z = 0.0;
        let mut weight = 1.0;
        let mut r = r.mirrored();
        for i in (0..self.interfaces.len()).rev() {
            let e = self.interfaces[i];
            z -= e.thickness;
            let stop = e.curvature_radius == 0.0;
            let (t, n) = meet_interface(&e, z, &r)?;
            let hit = r.at(t);
            match (&self.aperture, stop) {
                (Some(image), true) => {
                    let uv = (Vec2::new(hit.x, hit.y) / e.aperture_radius + Vec2::ONE) / 2.0;
                    weight = image.bilerp(uv);
                    if weight == 0.0 {
                        return None;
                    }
                }
                _ => {
                    if sqr(hit.x) + sqr(hit.y) > sqr(e.aperture_radius) {
                        return None;
                    }
                }
            }
            r.o = hit;
            if !stop {
                let eta_i = e.eta;
                let eta_t = if i > 0 && self.interfaces[i - 1].eta != 0.0 { self.interfaces[i - 1].eta } else { 1.0 };
                r.d = refract(-r.d.normalize(), n, eta_t / eta_i)?.0;
            }
        }
        Some((r.mirrored(), weight))
    }

    /// Traces a camera-space ray from the scene through the elements, front to rear, to the
    /// film side (the aperture image is not consulted, as in pbrt-v4).
    fn trace_from_scene(&self, r: LensRay) -> Option<LensRay> {
        let mut z = -self.front_z();
        let mut r = r.mirrored();
        for (i, e) in self.interfaces.iter().enumerate() {
            let stop = e.curvature_radius == 0.0;
            let (t, n) = meet_interface(e, z, &r)?;
            let hit = r.at(t);
            if sqr(hit.x) + sqr(hit.y) > sqr(e.aperture_radius) {
                return None;
            }
            r.o = hit;
            if !stop {
                let eta_i = if i == 0 || self.interfaces[i - 1].eta == 0.0 { 1.0 } else { self.interfaces[i - 1].eta };
                let eta_t = if e.eta != 0.0 { e.eta } else { 1.0 };
                r.d = refract(-r.d.normalize(), n, eta_t / eta_i)?.0;
            }
            z += e.thickness;
        }
        Some(r.mirrored())
    }

    /// The rear element's distance from the film that focuses the lens at `distance`
    /// (pbrt-v4's `FocusThickLens`: cardinal points of the thick-lens approximation, then
    /// the translation δ that images the plane at `distance` onto the film).
    fn focus_thick_lens(&self, distance: f32) -> Result<f32, String> {
        let x = 0.001 * self.diagonal;
        let cardinal = |r_in: LensRay, r_out: LensRay| {
            let tf = -r_out.o.x / r_out.d.x;
            let tp = (r_in.o.x - r_out.o.x) / r_out.d.x;
            (-r_out.at(tp).z, -r_out.at(tf).z)
        };
        let trouble =
            "the lens lets no ray through for its thick-lens approximation (is the aperture stop very small?)";
        let r_scene = LensRay { o: Vec3::new(x, 0.0, self.front_z() + 1.0), d: Vec3::NEG_Z };
        let r_film = self.trace_from_scene(r_scene).ok_or(trouble)?;
        let (pz0, fz0) = cardinal(r_scene, r_film);
        let r_film = LensRay { o: Vec3::new(x, 0.0, self.rear_z() - 1.0), d: Vec3::Z };
        let (r_scene, _) = self.trace_from_film(r_film).ok_or(trouble)?;
        let (pz1, _) = cardinal(r_film, r_scene);
        let f = fz0 - pz0;
        let z = -distance;
        let c = (pz1 - z - pz0) * (pz1 - z - 4.0 * f - pz0);
        if c <= 0.0 || c.is_nan() {
            return Err(format!("focusdistance {distance} is too short for this lens (it cannot focus that close)"));
        }
        let delta = (pz1 - z + pz0 - c.sqrt()) / 2.0;
        Ok(self.rear_z() + delta)
    }

    /// Bounds on the rear element's plane of the points through which rays from the film
    /// segment x ∈ [x0, x1] (y = 0) get through the lens.
    fn bound_exit_pupil(&self, x0: f32, x1: f32, samples: u32) -> Option<[Vec2; 2]> {
        let rear = 1.5 * self.rear_radius();
        let (lo_rear, hi_rear) = (Vec2::splat(-rear), Vec2::splat(rear));
        let mut bounds: Option<[Vec2; 2]> = None;
        let inside = |b: &Option<[Vec2; 2]>, p: Vec2| b.is_some_and(|[lo, hi]| p.cmpge(lo).all() && p.cmple(hi).all());
        for i in 0..samples {
            let f = (i as f32 + 0.5) / samples as f32;
            let p_film = Vec3::new(x0 + f * (x1 - x0), 0.0, 0.0);
            let u = Vec2::new(radical_inverse(2, u64::from(i)), radical_inverse(3, u64::from(i)));
            let p = lo_rear + u * (hi_rear - lo_rear);
            if inside(&bounds, p) {
                continue;
            }
            let p_rear = Vec3::new(p.x, p.y, self.rear_z());
            if self.trace_from_film(LensRay { o: p_film, d: p_rear - p_film }).is_some() {
                bounds = Some(match bounds {
                    Some([lo, hi]) => [lo.min(p), hi.max(p)],
                    None => [p, p],
                });
            }
        }
        // Expanded by twice the samples' spacing: the pupil's edge lies between samples.
        let pad = 2.0 * (hi_rear - lo_rear).length() / (samples as f32).sqrt();
        bounds.map(|[lo, hi]| [lo - Vec2::splat(pad), hi + Vec2::splat(pad)])
    }
}

/// Where a lens-space ray meets interface `e` whose vertex is at `z`: the plane of the
/// aperture stop (normal unused) or the element's sphere.
fn meet_interface(e: &Interface, z: f32, r: &LensRay) -> Option<(f32, Vec3)> {
    if e.curvature_radius == 0.0 {
        let t = (z - r.o.z) / r.d.z;
        (t >= 0.0).then_some((t, Vec3::ZERO))
    } else {
        intersect_element(e.curvature_radius, z + e.curvature_radius, r)
    }
}

/// Intersection of a lens-space ray with a spherical element of `radius` centred on the axis
/// at `z_center`: the distance and the normal facing the ray (pbrt-v4's
/// `IntersectSphericalElement`).
fn intersect_element(radius: f32, z_center: f32, r: &LensRay) -> Option<(f32, Vec3)> {
    let o = r.o - Vec3::new(0.0, 0.0, z_center);
    let a = r.d.length_squared();
    let b = 2.0 * r.d.dot(o);
    let c = o.length_squared() - radius * radius;
    let (t0, t1) = quadratic(a, b, c)?;
    let closer = (r.d.z > 0.0) ^ (radius < 0.0);
    let t = if closer { t0.min(t1) } else { t0.max(t1) };
    if t < 0.0 {
        return None;
    }
    let n = (o + t * r.d).normalize();
    Some((t, if n.dot(-r.d) < 0.0 { -n } else { n }))
}

/// The aperture image of `aperture`: a built-in shape or an image file's mean of R, G and B,
/// flipped bottom to top and scaled so that its mean is π/4 (a full circle's share of the
/// square).
fn aperture_image(aperture: &Aperture) -> Result<ApertureImage> {
    let n = BUILTIN_APERTURE_RES;
    let centre = |x: usize, y: usize| {
        Vec2::new(-1.0 + 2.0 * (x as f32 + 0.5) / n as f32, -1.0 + 2.0 * (y as f32 + 0.5) / n as f32)
    };
    // Stored as pbrt-v4 holds its aperture images after flipping them: the lookup's row grows
    // with the stop's y, and row k is the drawn (or read) row n − 1 − k.
    let (width, height, mut values) = match aperture {
        Aperture::Gaussian => {
            let v = (0..n * n)
                .map(|i| {
                    let p = centre(i % n, i / n);
                    ((-p.length_squared()).exp() - (-1.0f32).exp()).max(0.0)
                })
                .collect();
            (n, n, v)
        }
        Aperture::Square => {
            let inside = |k: usize| k >= n / 4 && k < 3 * n / 4;
            (n, n, (0..n * n).map(|i| if inside(i % n) && inside(i / n) { 4.0 } else { 0.0 }).collect())
        }
        Aperture::Pentagon => {
            let (c1, c2) = ((5f32.sqrt() - 1.0) / 4.0, (5f32.sqrt() + 1.0) / 4.0);
            let s1 = (10.0 + 2.0 * 5f32.sqrt()).sqrt() / 4.0;
            let s2 = (10.0 - 2.0 * 5f32.sqrt()).sqrt() / 4.0;
            let vert = [(0.0, 1.0), (s1, c1), (s2, -c2), (-s2, -c2), (-s1, c1)].map(|(x, y)| Vec2::new(x, y) * 0.8);
            (n, n, rasterize(&vert, n))
        }
        Aperture::Star => {
            let inner = 72f32.to_radians().cos() / 36f32.to_radians().cos();
            let mut vert: Vec<Vec2> = (0..10)
                .map(|i| {
                    let r = if i & 1 == 1 { 1.0 } else { inner };
                    let a = std::f32::consts::PI * i as f32 / 5.0;
                    Vec2::new(r * a.cos(), r * a.sin())
                })
                .collect();
            vert.reverse();
            (n, n, rasterize(&vert, n))
        }
        Aperture::Image(path) => {
            let image = crate::imageio::read_image(path)?;
            let (w, h) = (image.width, image.height);
            // Rows bottom to top.
            let v = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, h - 1 - i / w);
                    let p = image.pixels[y * w + x];
                    (p.x + p.y + p.z) / 3.0
                })
                .collect();
            (w, h, v)
        }
    };
    let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len().max(1) as f64;
    if mean <= 0.0 || mean.is_nan() {
        return Err(Error::invalid("the aperture image is black: no light would pass"));
    }
    let scale = (std::f64::consts::PI / 4.0 / mean) as f32;
    values.iter_mut().for_each(|v| *v *= scale);
    Ok(ApertureImage { width, height, values })
}

/// pbrt-v4's polygon rasterisation for the built-in apertures: 1 where the winding number of
/// `vert` around the pixel's centre is not zero; row y drawn at p.y = −1 + 2(y + ½)/n, stored
/// flipped (row n − 1 − y) as pbrt-v4 flips it.
fn rasterize(vert: &[Vec2], n: usize) -> Vec<f32> {
    let mut out = vec![0.0; n * n];
    for y in 0..n {
        for x in 0..n {
            let p = Vec2::new(-1.0 + 2.0 * (x as f32 + 0.5) / n as f32, -1.0 + 2.0 * (y as f32 + 0.5) / n as f32);
            let mut winding = 0;
            for i in 0..vert.len() {
                let (a, b) = (vert[i], vert[(i + 1) % vert.len()]);
                let e = (p.x - a.x) * (b.y - a.y) - (p.y - a.y) * (b.x - a.x);
                if a.y <= p.y {
                    if b.y > p.y && e > 0.0 {
                        winding += 1;
                    }
                } else if b.y <= p.y && e < 0.0 {
                    winding -= 1;
                }
            }
            out[(n - 1 - y) * n + x] = if winding == 0 { 0.0 } else { 1.0 };
        }
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// pbrt-v4-scenes' `lenses/dgauss.50mm.dat`: a double-Gauss f/2 lens of 50 mm focal
    /// length (Tronnier, US patent 2,673,491), scene side first.
    pub(crate) const DGAUSS: [[f32; 4]; 11] = [
        [29.475, 3.76, 1.67, 25.2],
        [84.83, 0.12, 1.0, 25.2],
        [19.275, 4.025, 1.67, 23.0],
        [40.77, 3.275, 1.699, 23.0],
        [12.75, 5.705, 1.0, 18.0],
        [0.0, 4.5, 0.0, 17.1],
        [-14.495, 1.18, 1.603, 17.0],
        [40.77, 6.065, 1.658, 20.0],
        [-20.385, 0.19, 1.0, 20.0],
        [437.065, 3.22, 1.717, 20.0],
        [-39.73, 0.0, 1.0, 20.0],
    ];

    fn lens(aperture_mm: f32, focus: f32) -> RealisticLens {
        let settings = RealisticSettings {
            elements: DGAUSS.to_vec(),
            aperture_diameter: aperture_mm,
            focus_distance: focus,
            aperture: None,
        };
        RealisticLens::with_pupil_samples(&settings, [96, 64], 35.0, 1 << 16).unwrap()
    }

    /// Tracing a generated ray back through the lens finds the film position and pupil
    /// sample it was generated from (what the camera's numerical differentials regenerate).
    #[test]
    fn film_sample_inverts_generate() {
        let l = lens(20.0, 3.0);
        let res = Vec2::new(96.0, 64.0);
        let mut found = 0;
        for (p, u) in [
            (Vec2::new(48.3, 31.7), Vec2::new(0.5, 0.5)),
            (Vec2::new(10.2, 5.9), Vec2::new(0.3, 0.8)),
            (Vec2::new(80.5, 50.1), Vec2::new(0.7, 0.2)),
            (Vec2::new(60.0, 12.0), Vec2::new(0.45, 0.6)),
        ] {
            let Some((o, d, _)) = l.generate(p, res, u) else { continue };
            let (p2, u2) = l.film_sample(o, d, res).expect("the ray traces back");
            assert!((p2 - p).abs().max_element() < 2e-3, "film {p} came back as {p2}");
            assert!((u2 - u).abs().max_element() < 2e-3, "pupil sample {u} came back as {u2}");
            found += 1;
        }
        assert!(found >= 3, "{found} rays got through the lens");
    }

    /// Rays from the film's centre through every part of the pupil meet the optical axis at
    /// the focus distance (to within the lens's spherical aberration), and the lens sits
    /// about one focal length (50 mm) in front of the film.
    #[test]
    fn focuses_at_the_focus_distance() {
        for focus in [1.0f32, 5.0] {
            let l = lens(10.0, focus);
            // Where the ray through pupil point u (along x) crosses the axis, if it gets through.
            let crossing = |u: f32| {
                let (o, d, _) = l.generate(Vec2::new(48.0, 32.0), Vec2::new(96.0, 64.0), Vec2::new(u, 0.5))?;
                (d.x.abs() > 1e-6).then(|| o.z - o.x / d.x * d.z)
            };
            // Near the axis (where the thick-lens approximation that focused it holds).
            let paraxial: Vec<f32> = (0..8).filter_map(|i| crossing(0.49 + 0.0025 * i as f32)).collect();
            assert!(paraxial.len() >= 6, "{} paraxial rays through the lens", paraxial.len());
            for z in &paraxial {
                assert!((z / focus - 1.0).abs() < 0.01, "focus {focus}: a paraxial ray crosses the axis at {z}");
            }
            // Over the whole pupil: within the lens's spherical aberration, marginal rays short.
            let all: Vec<f32> = (0..64).filter_map(|i| crossing((i as f32 + 0.5) / 64.0)).collect();
            assert!(all.len() > 20, "{} rays through the lens", all.len());
            for z in &all {
                assert!(*z > 0.85 * focus && *z < 1.01 * focus, "focus {focus}: a ray crosses the axis at {z}");
            }
            let film_to_rear = l.rear_z();
            assert!(film_to_rear > 0.02 && film_to_rear < 0.06, "rear element {film_to_rear} m from the film");
        }
    }

    /// Under a uniform radiance of 1, a film point's expected value is ∫ cos⁴θ / z² dA over
    /// the points of the rear element's plane through which light gets to it. The camera's
    /// estimate (exit-pupil bounds, their density, the rotation to the film point's angle)
    /// matches a quadrature over the whole square around the rear element, which does not
    /// use the bounds; at the centre and near the film's corner, where the lens vignettes.
    #[test]
    fn uniform_radiance_matches_a_quadrature_over_the_rear_element() {
        let l = lens(10.0, 5.0);
        let res = Vec2::new(96.0, 64.0);
        for p_raster in [Vec2::new(48.0, 32.0), Vec2::new(90.0, 6.0)] {
            let n = 256;
            let mut estimate = 0.0f64;
            for j in 0..n {
                for i in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    if let Some((_, _, w)) = l.generate(p_raster, res, u) {
                        estimate += f64::from(w);
                    }
                }
            }
            estimate /= (n * n) as f64;
            // The same film point, traced on a fine grid over the rear element's square.
            let s = p_raster / res;
            let p = -l.half_extent + s * 2.0 * l.half_extent;
            let p_film = Vec3::new(-p.x, p.y, 0.0);
            let half = 1.5 * l.rear_radius();
            let m = 1024;
            let cell = (2.0 * half / m as f32) as f64;
            let mut quadrature = 0.0f64;
            for j in 0..m {
                for i in 0..m {
                    let q = Vec2::new(
                        -half + (i as f32 + 0.5) * 2.0 * half / m as f32,
                        -half + (j as f32 + 0.5) * 2.0 * half / m as f32,
                    );
                    let d = Vec3::new(q.x, q.y, l.rear_z()) - p_film;
                    if l.trace_from_film(LensRay { o: p_film, d }).is_some() {
                        let cos = f64::from(d.normalize().z);
                        quadrature += cos.powi(4) / f64::from(sqr(l.rear_z())) * cell * cell;
                    }
                }
            }
            assert!(quadrature > 0.0);
            let rel = estimate / quadrature - 1.0;
            assert!(rel.abs() < 0.01, "at {p_raster}: camera {estimate}, quadrature {quadrature} ({rel:+.4})");
        }
    }

    /// pbrt-v4 scales an aperture image so that it passes what the round stop passes: with
    /// the stop the only limit (the film's centre, a small opening), each built-in shape
    /// brings the same light as the round stop, within the rasterisation's error.
    #[test]
    fn aperture_shapes_pass_what_the_round_stop_passes() {
        let centre = |aperture: Option<Aperture>| {
            let settings =
                RealisticSettings { elements: DGAUSS.to_vec(), aperture_diameter: 8.0, focus_distance: 5.0, aperture };
            let l = RealisticLens::with_pupil_samples(&settings, [96, 64], 35.0, 1 << 16).unwrap();
            let n = 200;
            let mut sum = 0.0f64;
            for j in 0..n {
                for i in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    if let Some((_, _, w)) = l.generate(Vec2::new(48.0, 32.0), Vec2::new(96.0, 64.0), u) {
                        sum += f64::from(w);
                    }
                }
            }
            sum / (n * n) as f64
        };
        let round = centre(None);
        for shape in [Aperture::Gaussian, Aperture::Square, Aperture::Pentagon, Aperture::Star] {
            let v = centre(Some(shape.clone()));
            assert!((v / round - 1.0).abs() < 0.03, "{shape:?}: {v} against the round stop's {round}");
        }
    }
}
