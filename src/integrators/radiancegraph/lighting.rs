//! Direct light per node (thesis Sec. 4.4, Eq. 4.22): L_d(a) = T_r(a, l) / 4π for a distant
//! light, with T_r averaged over rays from a grid of points on a disk through the node,
//! perpendicular to the light, each ratio-tracked `lightIterations` times to a uniformly
//! random depth inside the node's sphere.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::config::LightingCalculator;
use super::sh;
use super::volume::{GraphLight, Volume, sample_area_lights};
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::math::Frame;
use crate::sampling::rng::Pcg32;
use crate::sampling::warp;

/// 1/4π: the isotropic phase function.
const INV_4PI: f32 = 1.0 / (4.0 * std::f32::consts::PI);

/// The thesis's disk points (`GetDiskPoints`): a square grid with `n` points per radius
/// (spacing r/(n+1)) clipped to the disk, in the disk's (x, y) coordinates; `n = 0` is the
/// centre alone.
pub fn disk_points(radius: f32, n: u32) -> Vec<Vec2> {
    let n = n as i32;
    let step = radius / (n + 1) as f32;
    let mut v = Vec::new();
    for x in -n..=n {
        for y in -n..=n {
            let p = Vec2::new(x as f32, y as f32) * step;
            if p.length() <= radius {
                v.push(p);
            }
        }
    }
    v
}

/// Direct light scalars of every node for every light: `result[light][node]`, the value of
/// Eq. 4.22 without L_e (each light's radiance multiplies its scalars when rendering). In an
/// anisotropic medium a uniform light's are, per node, the [`sh::COEFFS`] coefficients of
/// the light it scatters toward each direction (`result[light][node * COEFFS + k]`): light
/// from every direction is not scattered isotropically when the transmittance toward the
/// sky differs by direction.
pub fn direct_light(
    volume: &Volume,
    positions: &[Vec3],
    radius: f32,
    config: &LightingCalculator,
    seed: u64,
) -> crate::Result<Vec<Vec<f32>>> {
    let disk = disk_points(radius, config.points_on_radius_light);
    let estimates = config.light_iterations as usize * disk.len();
    let n = positions.len() as u64;
    volume
        .lights
        .iter()
        .enumerate()
        .map(|(li, light)| {
            let per_node = |scratch: &mut Scratch, a: usize, sh_out: &mut [f32; sh::COEFFS]| {
                let mut rng = Pcg32::new(li as u64 * n + a as u64, seed ^ 0x006c_6967_6874);
                match light {
                    GraphLight::Distant { dir, .. } => {
                        let iterations = config.light_iterations;
                        distant(volume, positions[a], radius, *dir, &disk, iterations, &mut rng, scratch) * INV_4PI
                    }
                    GraphLight::Point { pos, .. } => {
                        point(volume, positions[a], radius, *pos, estimates, &mut rng) * INV_4PI
                    }
                    GraphLight::Uniform { .. } => {
                        uniform(volume, positions[a], radius, estimates, &mut rng, scratch, sh_out)
                    }
                    GraphLight::Area { lights, .. } => {
                        area(volume, positions[a], radius, lights, estimates, &mut rng, sh_out)
                    }
                    GraphLight::Emission { l } => emission(volume, positions[a], radius, l.rgb, estimates, &mut rng),
                    // Computed below.
                    GraphLight::Reflected { .. } => 0.0,
                }
            };
            let by_direction =
                matches!(light, GraphLight::Uniform { .. } | GraphLight::Area { .. } | GraphLight::Reflected { .. });
            let k = if by_direction && volume.medium.g != 0.0 { sh::COEFFS } else { 1 };
            let per_node = |scratch: &mut Scratch, a: usize| -> [f32; sh::COEFFS] {
                let mut c = [0.0; sh::COEFFS];
                let v = per_node(scratch, a, &mut c);
                if k == 1 {
                    c[0] = v;
                }
                c
            };
            // Light reflected into the medium by the surfaces beside it: in an isotropic medium
            // part of each light's scalar; in an anisotropic one the coefficients of a light of
            // its own (`GraphLight::Reflected`), as it arrives from other directions.
            let g = volume.medium.g;
            let reflected = |a: usize, of: &GraphLight, sh_out: &mut [f32; sh::COEFFS]| -> Result<f32, Vec3> {
                let mut rng = Pcg32::new(li as u64 * n + a as u64, seed ^ 0x0073_7572_6661_6365);
                let (mut sum, mut coeffs) = (0.0f64, [0.0f64; sh::COEFFS]);
                let bands = sh::bands(g);
                for _ in 0..estimates.max(1) {
                    let x = point_in_node(volume, positions[a], radius, &mut rng);
                    let d = warp::uniform_sphere(Vec2::new(rng.uniform(), rng.uniform()));
                    let v = super::volume::reflected_along(volume.scene, &Ray::new(x, d), of, &mut rng)?;
                    sum += f64::from(v);
                    if g != 0.0 && v > 0.0 {
                        for ((c, b), y) in coeffs.iter_mut().zip(bands).zip(sh::basis(-d)) {
                            *c += f64::from(v * b * y);
                        }
                    }
                }
                let m = estimates.max(1) as f64;
                for (o, c) in sh_out.iter_mut().zip(coeffs) {
                    *o = (c / m) as f32;
                }
                Ok((sum / m) as f32)
            };
            let per_node = |scratch: &mut Scratch, a: usize| -> Result<[f32; sh::COEFFS], Vec3> {
                if let GraphLight::Reflected { of } = light {
                    let mut c = [0.0; sh::COEFFS];
                    let v = reflected(a, of, &mut c)?;
                    if k == 1 {
                        c[0] = v;
                    }
                    return Ok(c);
                }
                let mut c = per_node(scratch, a);
                if volume.has_opaque && g == 0.0 {
                    c[0] += reflected(a, light, &mut [0.0; sh::COEFFS])?;
                }
                Ok(c)
            };
            let values: Result<Vec<[f32; sh::COEFFS]>, Vec3> = if config.run_in_parallel {
                (0..positions.len()).into_par_iter().map_init(Scratch::default, per_node).collect()
            } else {
                let mut scratch = Scratch::default();
                (0..positions.len()).map(|a| per_node(&mut scratch, a)).collect()
            };
            let values = values.map_err(|at| {
                crate::Error::Unsupported(format!(
                    "the radiance-graph method needs surfaces beside the medium that reflect gray light (the one at \
                     ({:.3}, {:.3}, {:.3}) reflects colors, which one value per light and node cannot carry)",
                    at.x, at.y, at.z
                ))
            })?;
            Ok(values.iter().flat_map(|c| c[..k].iter().copied()).collect())
        })
        .collect()
}

/// Per-thread buffers of the direct-light walks.
#[derive(Default)]
struct Scratch {
    intervals: Vec<(f32, f32)>,
    overlaps: Vec<(f32, f32)>,
}

/// Mean transmittance from a distant light travelling along `dir` into the node at `c`.
#[allow(clippy::too_many_arguments)] // the node, the light, the disk and the scratch buffers
fn distant(
    volume: &Volume,
    c: Vec3,
    radius: f32,
    dir: Vec3,
    disk: &[Vec2],
    iterations: u32,
    rng: &mut Pcg32,
    scratch: &mut Scratch,
) -> f32 {
    let f = Frame::from_z(dir);
    let back = 2.0 * volume.radius + radius;
    let (mut sum, mut count) = (0.0f64, 0u32);
    for q in disk {
        let o = c - dir * back + f.x * q.x + f.y * q.y;
        let ray = Ray::new(o, dir);
        // The chord of the node's sphere along this ray: centred on the closest approach.
        let t_mid = (c - o).dot(dir);
        let half = (radius * radius - q.length_squared()).max(0.0).sqrt();
        let (s0, s1) = (t_mid - half, t_mid + half);
        let Scratch { intervals, overlaps } = scratch;
        volume.intervals(&ray, s1, intervals);
        // The part of the chord inside the medium, where the node's points are.
        overlaps.clear();
        overlaps.extend(intervals.iter().map(|&(a, b)| (a.max(s0), b.min(s1))).filter(|&(a, b)| a < b));
        let length: f32 = overlaps.iter().map(|(a, b)| b - a).sum();
        if length <= 0.0 {
            continue;
        }
        for _ in 0..iterations {
            // A uniform depth in the chord's medium part.
            let mut u = rng.uniform() * length;
            let mut depth = overlaps[overlaps.len() - 1].1;
            for &(a, b) in overlaps.iter() {
                if u < b - a {
                    depth = a + u;
                    break;
                }
                u -= b - a;
            }
            // An opaque surface between the light and the point (from far beyond the walk's
            // start as well) leaves it dark.
            if !volume.occluded(&Ray::new(ray.at(depth), -dir), f32::INFINITY) {
                sum += f64::from(volume.transmittance_between(&ray, intervals, 0.0, depth, rng));
            }
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { (sum / f64::from(count)) as f32 }
}

/// Mean over uniform points of the node's sphere inside the medium of T_r / r² from a point
/// light at `light` (beyond the thesis: its direct light per unit intensity, times 4π p).
fn point(volume: &Volume, c: Vec3, radius: f32, light: Vec3, estimates: usize, rng: &mut Pcg32) -> f32 {
    let at = |x: Vec3, rng: &mut Pcg32| {
        let d2 = x.distance_squared(light);
        let ray = Ray::new(x, (light - x) / d2.sqrt());
        f64::from(super::volume::transmittance_from_inside(volume.scene, &ray, d2.sqrt(), rng) / d2)
    };
    let (mut sum, mut count) = (0.0f64, 0u32);
    for _ in 0..estimates.max(1) {
        // A uniform point of the sphere (rejection), counted when it is in the medium.
        let v = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - Vec3::ONE;
        if v.length_squared() < 1.0 && volume.contains(c + v * radius) {
            sum += at(c + v * radius, rng);
            count += 1;
        }
    }
    // No point in the medium drawn: the centre, a scattering point.
    if count == 0 { at(c, rng) as f32 } else { (sum / f64::from(count)) as f32 }
}

/// ∫ p T_r dω over area lights of unit radiance (beyond the thesis): the mean over uniform
/// points of the node's medium part of light samples toward them (one light chosen by area,
/// a point by its own sampling), T_r/pdf each, times the isotropic phase function; in an
/// anisotropic medium also the coefficients of the scattered light into `sh_out`, as
/// [`uniform`]'s. An opaque surface between (the light's own shape included, for a point
/// behind it) leaves nothing.
fn area(
    volume: &Volume,
    c: Vec3,
    radius: f32,
    lights: &[u32],
    estimates: usize,
    rng: &mut Pcg32,
    sh_out: &mut [f32; sh::COEFFS],
) -> f32 {
    let scene = volume.scene;
    let g = volume.medium.g;
    let bands = sh::bands(g);
    let mut coeffs = [0.0f64; sh::COEFFS];
    let mut sum = 0.0f64;
    let n = estimates.max(1);
    for _ in 0..n {
        let x = point_in_node(volume, c, radius, rng);
        let Some((wi, dist, pdf)) = sample_area_lights(scene, lights, x, rng) else { continue };
        let t = super::volume::transmittance_from_inside(scene, &Ray::new(x, wi), dist, rng);
        if t <= 0.0 {
            continue;
        }
        let w = t / pdf * INV_4PI;
        sum += f64::from(w);
        if g != 0.0 {
            for ((c, b), y) in coeffs.iter_mut().zip(bands).zip(sh::basis(-wi)) {
                *c += f64::from(w * b * y);
            }
        }
    }
    for (o, c) in sh_out.iter_mut().zip(coeffs) {
        *o = (c / n as f64) as f32;
    }
    (sum / n as f64) as f32
}

/// The medium's emission of unit spectrum `unit` scattered at the node at `c` (beyond the
/// thesis): the mean, over uniform points of the node's medium part and uniform directions,
/// of the emission reaching the point along the direction (isotropic scattering: the
/// direction's density 1/4π cancels the phase function's).
fn emission(volume: &Volume, c: Vec3, radius: f32, unit: Rgb, estimates: usize, rng: &mut Pcg32) -> f32 {
    let n = estimates.max(1);
    let mut sum = 0.0f64;
    for _ in 0..n {
        let x = point_in_node(volume, c, radius, rng);
        let d = warp::uniform_sphere(Vec2::new(rng.uniform(), rng.uniform()));
        sum += f64::from(super::volume::emission_along(volume.scene, &Ray::new(x, d), unit, rng));
    }
    (sum / n as f64) as f32
}

/// A uniform point of the sphere of radius `radius` around the node at `c` that lies in the
/// medium (rejection; the centre, a scattering point, after 16 misses).
fn point_in_node(volume: &Volume, c: Vec3, radius: f32, rng: &mut Pcg32) -> Vec3 {
    for _ in 0..16 {
        let v = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - Vec3::ONE;
        if v.length_squared() < 1.0 && volume.contains(c + v * radius) {
            return c + v * radius;
        }
    }
    c
}

/// ∫ p T_r dω for a uniform light: the mean over uniform directions of the transmittance from
/// uniform points of the node's medium part to the boundary. In an anisotropic medium (HG,
/// asymmetry g ≠ 0) also, into `sh_out`, the coefficients of ∫ 4π p T_r dω/4π as a function of
/// the scattered direction: light arriving from direction d travels along −d, so it adds
/// T_r · 4π g^l Y_lm(−d) (see `sh`).
fn uniform(
    volume: &Volume,
    c: Vec3,
    radius: f32,
    estimates: usize,
    rng: &mut Pcg32,
    scratch: &mut Scratch,
    sh_out: &mut [f32; sh::COEFFS],
) -> f32 {
    let back = 2.0 * volume.radius + radius;
    let g = volume.medium.g;
    let bands = sh::bands(g);
    let mut coeffs = [0.0f64; sh::COEFFS];
    let mut sum = 0.0f64;
    for _ in 0..estimates {
        let d = warp::uniform_sphere(Vec2::new(rng.uniform(), rng.uniform()));
        // A uniform point of the sphere inside the medium (rejection; the centre, always
        // inside for a node, after 16 misses).
        let intervals = &mut scratch.intervals;
        let mut found = None;
        for _ in 0..16 {
            let v = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - Vec3::ONE;
            if v.length_squared() >= 1.0 {
                continue;
            }
            // From outside, back through the point, so the walk sees every boundary crossing.
            let ray = Ray::new(c + v * radius - d * back, d);
            volume.intervals(&ray, f32::INFINITY, intervals);
            if intervals.iter().any(|&(a, b)| a <= back && back <= b) {
                found = Some(ray);
                break;
            }
        }
        let ray = found.unwrap_or_else(|| {
            let ray = Ray::new(c - d * back, d);
            volume.intervals(&ray, f32::INFINITY, intervals);
            ray
        });
        let t = if volume.occluded(&Ray::new(ray.at(back), d), f32::INFINITY) {
            0.0
        } else {
            volume.transmittance_between(&ray, intervals, back, f32::INFINITY, rng)
        };
        sum += f64::from(t);
        if g != 0.0 && t > 0.0 {
            for ((c, b), y) in coeffs.iter_mut().zip(bands).zip(sh::basis(-d)) {
                *c += f64::from(t * b * y);
            }
        }
    }
    let n = estimates.max(1) as f64;
    for (o, c) in sh_out.iter_mut().zip(coeffs) {
        *o = (c / n) as f32;
    }
    (sum / n) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disk_points_as_the_thesis() {
        assert_eq!(disk_points(1.0, 0), [Vec2::ZERO]);
        // n = 1: spacing ½, the whole 3×3 grid (corners at 0.71).
        assert_eq!(disk_points(1.0, 1).len(), 9);
        // n = 2: spacing ⅓; corners (±⅔, ±⅔) are at 0.94 ≤ 1, all 25 points stay.
        assert_eq!(disk_points(1.0, 2).len(), 25);
        // n = 3: spacing ¼; the corners (±¾, ±¾) at 1.06 drop, (±¾, ±½) at 0.90 stay: 49 − 4.
        assert_eq!(disk_points(1.0, 3).len(), 45);
    }
}
