//! The scene as the radiance-graph method sees it (thesis Sec. 4.8): one gray, non-emissive
//! medium (isotropic in the thesis; here HG with |g| ≤ [`MAX_G`]) bounded by `interface`
//! surfaces, lit by distant lights (the thesis's case), uniform `infinite` lights (its
//! Sec. 6.1 asks for them) and point lights. Everything the method
//! needs of the scene goes through here: where the medium ends along a ray, and the two
//! delta-tracking walks the thesis uses (sample a scattering event; ratio-track transmittance).

use glam::Vec3;

use crate::accel::NONE;
use crate::color::Rgb;
use crate::geometry::{Bounds3, Ray};
use crate::integrators::common::media::{ShadowEstimate, ratio_tracking, sample_t_maj};
use crate::lights::LightKind;
use crate::media::Medium;
use crate::sampling::rng::Pcg32;
use crate::scene::Scene;
use crate::spectra::SpectrumValue;

/// The most lights a graph carries scalars for (camera rays keep their radiance on the stack).
pub const MAX_LIGHTS: usize = 8;

/// The largest |g| the graph's directional radiance holds (README: the cloud's mean at
/// g = −0.5, 0.6, 0.75 and 0.877 was +1.0 %, +0.4 %, −1.2 % and −9.7 % off volpath's).
pub const MAX_G: f32 = 0.75;

/// A light the graph carries one radiance scalar per node for.
#[derive(Clone, Debug)]
pub enum GraphLight {
    /// Parallel light travelling along `dir`.
    Distant {
        /// Unit direction the light travels in (from the light into the scene).
        dir: Vec3,
        /// Radiance.
        l: SpectrumValue,
    },
    /// Constant radiance from every direction.
    Uniform {
        /// Radiance.
        l: SpectrumValue,
    },
    /// A point light (beyond the thesis): light paths start from it in every direction.
    Point {
        /// Position.
        pos: Vec3,
        /// Radiant intensity.
        i: SpectrumValue,
    },
}

impl GraphLight {
    /// The radiance.
    pub fn radiance(&self) -> &SpectrumValue {
        match self {
            GraphLight::Distant { l, .. } | GraphLight::Uniform { l } | GraphLight::Point { i: l, .. } => l,
        }
    }
}

/// The scene's medium and lights, once checked against the method's constraints.
pub struct Volume<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its one medium.
    pub medium: &'a Medium,
    /// The medium's index in `scene.media`.
    pub medium_index: u32,
    /// Bounds of the medium's boundary surfaces.
    pub bounds: Bounds3,
    /// Half the bounds' diagonal: the thesis's scene radius (`maxDistToCenter`).
    pub radius: f32,
    /// The lights, in scene order.
    pub lights: Vec<GraphLight>,
}

/// How a sampled segment ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A real scattering event at this point.
    Scatter(Vec3),
    /// Absorbed.
    Absorb,
    /// Reached the end of the segment (left the medium).
    Pass,
}

impl<'a> Volume<'a> {
    /// Checks the method's constraints; the error lists every violated one.
    pub fn new(scene: &'a Scene) -> crate::Result<Volume<'a>> {
        let mut violated = Vec::new();
        let medium = match scene.media.as_slice() {
            [m] => Some(m),
            [] => {
                violated.push("one medium (the scene has none)".to_string());
                None
            }
            media => {
                let names: Vec<_> = media.iter().map(|m| format!("\"{}\"", m.name)).collect();
                violated.push(format!("one medium (the scene has {}: {})", media.len(), names.join(", ")));
                None
            }
        };
        if let Some(m) = medium {
            if m.g.abs() > MAX_G {
                violated.push(format!(
                    "a phase function with |g| ≤ {MAX_G} (medium \"{}\" has g = {}; the graph's directional radiance, \
                     spherical harmonics to band 2, is 9.7 % dark at g = 0.877)",
                    m.name, m.g
                ));
            }
            if m.chromatic {
                violated.push(format!("gray coefficients (medium \"{}\" has chromatic sigma_a or sigma_s)", m.name));
            }
            if m.emissive {
                violated.push(format!("a non-emissive medium (medium \"{}\" emits)", m.name));
            }
        }
        if scene.has_motion() {
            violated.push("a static scene (shapes or the camera move over the shutter interval)".to_string());
        }
        let mut lights = Vec::new();
        // Each other kind once (an emitting mesh has a light per triangle).
        let mut others: Vec<&str> = Vec::new();
        for light in &scene.lights {
            match &light.kind {
                LightKind::Distant { w, l } => lights.push(GraphLight::Distant { dir: -*w, l: *l }),
                LightKind::UniformInfinite { l } => lights.push(GraphLight::Uniform { l: *l }),
                LightKind::Point { p, i } => lights.push(GraphLight::Point { pos: *p, i: *i }),
                other => {
                    let name = light_kind_name(other);
                    if !others.contains(&name) {
                        others.push(name);
                    }
                }
            }
        }
        if !others.is_empty() {
            violated.push(format!(
                "distant, point and uniform infinite lights only (the scene has {} lights)",
                others.join(" and ")
            ));
        }
        if scene.lights.is_empty() {
            violated.push("at least one light (the scene has none)".to_string());
        }
        if scene.lights.len() > MAX_LIGHTS {
            violated.push(format!("at most {MAX_LIGHTS} lights (the scene has {})", scene.lights.len()));
        }
        if scene.camera_medium != NONE {
            violated.push("a camera outside the medium".to_string());
        }
        let surfaces = &scene.surfaces;
        if !surfaces.instances.is_empty() {
            violated.push("no object instances".to_string());
        }
        let prims = surfaces.top.as_ref().map_or(&[][..], |t| t.primitives());
        if prims.is_empty() {
            violated.push("a medium bounded by `interface` surfaces (the scene has no surfaces)".to_string());
        } else if prims.iter().any(|p| {
            p.interface == NONE
                || !surfaces.pass_through.get(p.material as usize).copied().unwrap_or(false)
                || scene.interfaces[p.interface as usize] != [0, NONE]
        }) {
            violated.push(
                "surfaces only as the medium's boundary (`interface` material, medium inside, none outside)".into(),
            );
        }
        if !violated.is_empty() {
            return Err(crate::Error::Unsupported(format!(
                "the radiance-graph method needs {}",
                violated.iter().map(|v| format!("\n  - {v}")).collect::<String>()
            )));
        }
        let bounds = surfaces.bounds();
        Ok(Volume {
            scene,
            medium: medium.expect("checked"),
            medium_index: 0,
            bounds,
            radius: 0.5 * (bounds.max - bounds.min).length(),
            lights,
        })
    }

    /// Centre of the bounds.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.bounds.min + self.bounds.max)
    }

    /// Where `ray` (from outside the medium) first enters it and where it next leaves:
    /// `(t_in, t_out)`. `None` if it misses.
    pub fn span(&self, ray: &Ray) -> Option<(f32, f32)> {
        let hit = self.scene.surfaces.intersect(ray, f32::INFINITY)?;
        // Entering: the direction points against the surface normal.
        if ray.d.dot(hit.surface.n) >= 0.0 {
            return None;
        }
        let t_in = hit.surface.t;
        let inner = hit.surface.spawn_ray(ray.d);
        let exit = self.exit(&inner)?;
        Some((t_in, (inner.o - ray.o).dot(ray.d) + exit))
    }

    /// The part of `ray` inside the medium from wherever its origin is: `(0, t_exit)` from
    /// inside, `(t_in, t_out)` from outside when it enters, `None` when it misses.
    pub fn span_from(&self, ray: &Ray) -> Option<(f32, f32)> {
        let hit = self.scene.surfaces.intersect(ray, f32::INFINITY)?;
        if ray.d.dot(hit.surface.n) > 0.0 { Some((0.0, hit.surface.t)) } else { self.span(ray) }
    }

    /// The medium's intervals along `ray` (whose origin is outside it) that start before
    /// `t_end`, in order, into `v` (cleared first; callers reuse it).
    pub fn intervals(&self, ray: &Ray, t_end: f32, v: &mut Vec<(f32, f32)>) {
        v.clear();
        let mut offset = 0.0;
        let mut r = *ray;
        // A closed boundary is crossed an even number of times; 64 bounds a pathological mesh.
        for _ in 0..64 {
            let Some((t_in, t_out)) = self.span(&r) else { break };
            if offset + t_in >= t_end {
                break;
            }
            v.push((offset + t_in, offset + t_out));
            let exit = r.at(t_out);
            let next = crate::geometry::spawn_ray(exit, r.d, r.d);
            offset += (next.o - r.o).dot(r.d);
            r = next;
        }
    }

    /// Transmittance along `ray` between distances `t0` and `t1`, given the medium's
    /// `intervals` along it: one ratio-tracking estimate per interval piece.
    pub fn transmittance_between(&self, ray: &Ray, intervals: &[(f32, f32)], t0: f32, t1: f32, rng: &mut Pcg32) -> f32 {
        let mut tr = 1.0;
        for &(a, b) in intervals {
            let (a, b) = (a.max(t0), b.min(t1));
            if a >= b {
                continue;
            }
            tr *= self.transmittance(&Ray::new(ray.at(a), ray.d), b - a, rng);
            if tr == 0.0 {
                break;
            }
        }
        tr
    }

    /// Distance from a point inside the medium along `ray` to the boundary.
    pub fn exit(&self, ray: &Ray) -> Option<f32> {
        self.scene.surfaces.intersect(ray, f32::INFINITY).map(|h| h.surface.t)
    }

    /// Samples where a segment from a point inside the medium first interacts (delta
    /// tracking with absorption and scattering as events, as the thesis's `TracePath`):
    /// a real scattering point, or the end of the path.
    pub fn sample_scatter(&self, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> Event {
        let u = rng.uniform();
        sample_event(self.medium, ray, t_max, u, rng)
    }

    /// Transmittance along `ray` to distance `t_max` inside the medium, one ratio-tracking
    /// estimate (thesis Eq. 4.22 averages these): the shadow rays' own ratio tracking, with
    /// no unidirectional technique to weigh against (r_u = 0), so the estimate is T_ray / r_l
    /// and r_l is 1 in a gray medium. Its Russian roulette below 0.05 is nimbus's (and
    /// pbrt-v4's): unbiased, and walks deep into a dense cloud stop early instead of
    /// multiplying ever smaller ratios to the far side. The thesis tracks to the end.
    pub fn transmittance(&self, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> f32 {
        ratio_tracked(self.medium, ray, t_max, rng)
    }
}

/// One ratio-tracking estimate of the transmittance along `ray` to `t_max` inside `medium`
/// (see [`Volume::transmittance`]).
fn ratio_tracked(medium: &Medium, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> f32 {
    let mut est = ShadowEstimate::<Rgb> { t_ray: Rgb::ONE, r_u: Rgb::ZERO, r_l: Rgb::ONE };
    ratio_tracking(medium.into(), ray, t_max, rng, 0, &(), &mut est);
    est.t_ray[0] / est.r_l[0]
}

/// Transmittance along `ray`, from a point inside `scene`'s one medium, to distance `t_end`
/// (∞: out of the scene): ratio tracking through each stretch of medium, the boundary
/// crossed as often as it is met.
pub fn transmittance_from_inside(scene: &Scene, ray: &Ray, t_end: f32, rng: &mut Pcg32) -> f32 {
    let medium = &scene.media[0];
    let (mut ray, mut inside, mut tr, mut left) = (*ray, true, 1.0f32, t_end);
    // A closed boundary is crossed an even number of times; 64 bounds a pathological mesh.
    for _ in 0..64 {
        let hit = scene.surfaces.intersect(&ray, left);
        if inside {
            let t_max = hit.as_ref().map_or(left, |h| h.surface.t);
            tr *= ratio_tracked(medium, &ray, t_max, rng);
            if tr == 0.0 {
                return 0.0;
            }
        }
        match hit {
            None => return tr,
            Some(h) => {
                inside = ray.d.dot(h.surface.n) < 0.0;
                let next = h.surface.spawn_ray(ray.d);
                left -= (next.o - ray.o).dot(ray.d);
                ray = next;
            }
        }
    }
    tr
}

/// Delta tracking through a gray medium with absorption and real scattering as events (the
/// thesis's `TracePath` and graph integrator), the first tentative collision at `u`.
#[inline]
pub fn sample_event(medium: &Medium, ray: &Ray, t_max: f32, u: f32, rng: &mut Pcg32) -> Event {
    let mut event = Event::Pass;
    sample_t_maj::<Rgb, _>(medium.into(), ray, t_max, u, rng, 0, &(), |p, mp, sigma_maj, _, rng| {
        let um = rng.uniform() * sigma_maj[0];
        if um < mp.sigma_a[0] {
            event = Event::Absorb;
            false
        } else if um < mp.sigma_a[0] + mp.sigma_s[0] {
            event = Event::Scatter(p);
            false
        } else {
            true
        }
    });
    event
}

fn light_kind_name(k: &LightKind) -> &'static str {
    match k {
        LightKind::Point { .. } => "point",
        LightKind::Goniometric { .. } => "goniometric",
        LightKind::Projection { .. } => "projection",
        LightKind::Spot { .. } => "spot",
        LightKind::Distant { .. } => "distant",
        LightKind::UniformInfinite { .. } => "uniform infinite",
        LightKind::ImageInfinite(_) => "image infinite",
        LightKind::PortalInfinite(_) => "infinite through a portal",
        LightKind::Area { .. } => "area",
    }
}
