//! The scene as the radiance-graph method sees it (thesis Sec. 4.8): one gray, non-emissive
//! medium (isotropic in the thesis; here HG with |g| ≤ [`MAX_G`]) bounded by `interface`
//! surfaces, lit by distant lights (the thesis's case), uniform `infinite` lights (its
//! Sec. 6.1 asks for them) and point lights. Everything the method
//! needs of the scene goes through here: where the medium ends along a ray, and the two
//! delta-tracking walks the thesis uses (sample a scattering event; ratio-track transmittance).

use glam::Vec3;

use crate::accel::{Hit, NONE, Primitive};
use crate::color::Rgb;
use crate::geometry::{Bounds3, Ray};
use crate::integrators::common::media::{ShadowEstimate, ratio_tracking, sample_t_maj};
use crate::lights::LightKind;
use crate::materials::bxdf::{ReflTransFlags, TransportMode};
use crate::media::{Emission, Medium, MediumKind, MediumPoint};
use crate::sampling::rng::Pcg32;
use crate::scene::Scene;
use crate::spectra::SpectrumValue;

use super::similarity::{self, Similarity};

/// The most lights a graph carries scalars for (camera rays keep their radiance on the stack).
pub const MAX_LIGHTS: usize = 8;

/// The most surface reflections a light path takes between two scattering points in the
/// medium (a path between facing mirrors would not end by itself).
pub const MAX_SURFACE_BOUNCES: usize = 8;

/// The largest |g| the graph's directional radiance holds (README: the test cloud's mean at
/// g = −0.5, 0.6, 0.75 and 0.877 was +1.0 %, +0.4 %, −1.2 % and −9.7 % off volpath's; the
/// Disney cloud's at 0.877, +64 %; +29 % with the direct light at the nodes' kept vertices).
/// Beyond it, up to [`similarity::MAX_G`], the graph holds the similar isotropic medium.
pub const MAX_G: f32 = 0.75;

/// A light the graph carries one radiance scalar per node for.
#[derive(Clone, Debug, PartialEq)]
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
    /// The medium's own emission (beyond the thesis), one spectrum times a scalar field
    /// (`Le` of a homogeneous medium, `Le` × `Lescale` of a grid): light paths start from
    /// emitting points of the medium; a node's direct light is the emission reaching it.
    Emission {
        /// The emission's spectrum (its scalar field multiplies it).
        l: SpectrumValue,
    },
    /// Light of `of` reflected once by the surfaces beside an anisotropic medium into it (beyond
    /// the thesis): a light of its own, whose direct values are directional coefficients, as
    /// it arrives from the surfaces' directions, not the light's.
    Reflected {
        /// The light reflected.
        of: Box<GraphLight>,
    },
    /// Diffuse area lights of one radiance (beyond the thesis; an emitting mesh is one light
    /// per triangle): light paths start from their surfaces, cosine-distributed.
    Area {
        /// Their indices in the scene's lights.
        lights: Vec<u32>,
        /// Radiance.
        l: SpectrumValue,
    },
}

impl GraphLight {
    /// The radiance.
    pub fn radiance(&self) -> &SpectrumValue {
        match self {
            GraphLight::Distant { l, .. }
            | GraphLight::Uniform { l }
            | GraphLight::Point { i: l, .. }
            | GraphLight::Emission { l }
            | GraphLight::Area { l, .. } => l,
            GraphLight::Reflected { of } => of.radiance(),
        }
    }
}

/// The scene's medium and lights, once checked against the method's constraints.
pub struct Volume<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its one medium, as the graph transports it: the scene's, or where it scatters forward
    /// beyond [`MAX_G`] the similar isotropic medium ([`similarity`]).
    pub medium: std::borrow::Cow<'a, Medium>,
    /// Set where `medium` is the similar medium of the scene's.
    pub similarity: Option<Similarity>,
    /// The medium's index in `scene.media`.
    pub medium_index: u32,
    /// Bounds of the medium's boundary surfaces.
    pub bounds: Bounds3,
    /// Half the bounds' diagonal: the thesis's scene radius (`maxDistToCenter`).
    pub radius: f32,
    /// The lights, in scene order.
    pub lights: Vec<GraphLight>,
    /// Some surface beside the medium may stop light ([`SurfaceKind::Opaque`]).
    pub has_opaque: bool,
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
            if m.g < -MAX_G || m.g > similarity::MAX_G {
                violated.push(format!(
                    "a phase function with g in [−{MAX_G}, {}] (medium \"{}\" has g = {}; the graph's directional \
                     radiance, spherical harmonics to band 2, holds |g| ≤ {MAX_G}, and the similar isotropic medium \
                     stands in for forward scattering up to {})",
                    similarity::MAX_G,
                    m.name,
                    m.g,
                    similarity::MAX_G
                ));
            } else if m.g > MAX_G && matches!(m.kind, MediumKind::RgbGrid(_)) {
                violated.push(format!(
                    "a phase function with |g| ≤ {MAX_G} in an `rgbgrid` medium (medium \"{}\" has g = {}: the similar \
                     medium that stands in for stronger forward scattering needs density-scaled coefficients)",
                    m.name, m.g
                ));
            }
            if m.chromatic {
                violated.push(format!("gray coefficients (medium \"{}\" has chromatic sigma_a or sigma_s)", m.name));
            }
            if m.emissive {
                match emission_spectrum(m) {
                    None => violated.push(format!(
                        "a non-emissive medium, or one whose emission is one spectrum times a scalar field \
                         (medium \"{}\" emits by temperature or per-voxel color)",
                        m.name
                    )),
                    Some(_) if m.g != 0.0 => violated.push(format!(
                        "a non-emissive medium, or an isotropic one (medium \"{}\" emits and has g = {})",
                        m.name, m.g
                    )),
                    Some(_) => {}
                }
            }
        }
        if scene.has_motion() {
            violated.push("a static scene (shapes or the camera move over the shutter interval)".to_string());
        }
        let mut lights = Vec::new();
        // Each other kind once (an emitting mesh has a light per triangle).
        let mut others: Vec<&str> = Vec::new();
        for (i, light) in scene.lights.iter().enumerate() {
            match &light.kind {
                LightKind::Distant { w, l } => lights.push(GraphLight::Distant { dir: -*w, l: *l }),
                LightKind::UniformInfinite { l } => lights.push(GraphLight::Uniform { l: *l }),
                LightKind::Point { p, i } => lights.push(GraphLight::Point { pos: *p, i: *i }),
                // One graph light per radiance: its scalars are per unit of it.
                LightKind::Area { l, image: None, alpha: NONE, invisible: false, .. } => {
                    let index = i as u32;
                    match lights.iter_mut().find(|g| matches!(g, GraphLight::Area { l: gl, .. } if gl == l)) {
                        Some(GraphLight::Area { lights, .. }) => lights.push(index),
                        _ => lights.push(GraphLight::Area { lights: vec![index], l: *l }),
                    }
                }
                LightKind::Area { image: Some(_), .. } => others.push("area (with an emission image)"),
                LightKind::Area { .. } => others.push("area (with an alpha texture)"),
                other => {
                    let name = light_kind_name(other);
                    if !others.contains(&name) {
                        others.push(name);
                    }
                }
            }
        }
        if let Some(l) = medium.filter(|m| m.emissive && m.g == 0.0).and_then(emission_spectrum) {
            lights.push(GraphLight::Emission { l });
        }
        others.dedup();
        if !others.is_empty() {
            violated.push(format!(
                "distant, point, uniform infinite and diffuse area lights only (the scene has {} lights)",
                others.join(" and ")
            ));
        }
        if lights.is_empty() && others.is_empty() {
            violated.push("at least one light (the scene has none)".to_string());
        }
        if scene.camera_medium != NONE {
            violated.push("a camera outside the medium".to_string());
        }
        let surfaces = &scene.surfaces;
        if !surfaces.instances.is_empty() {
            violated.push("no object instances".to_string());
        }
        let prims = surfaces.top.as_ref().map_or(&[][..], |t| t.primitives());
        let mut bounds = Bounds3::EMPTY;
        for p in prims {
            if surface_kind(scene, p) == SurfaceKind::Boundary {
                let b = match p.geometry {
                    crate::accel::Geometry::Hull(k) => surfaces.hulls.all[k as usize].bounds(),
                    g => surfaces.shapes.bounds(g),
                };
                bounds = bounds.union(&b);
            }
        }
        if bounds.is_empty() {
            violated.push("a medium bounded by `interface` surfaces (the scene has none)".to_string());
        }
        if prims.iter().any(|p| surface_kind(scene, p) == SurfaceKind::OtherInterface) {
            violated.push(
                "surfaces that change the medium only as its boundary (`interface` material, medium inside, \
                 none outside)"
                    .into(),
            );
        }
        let has_opaque = prims.iter().any(|p| surface_kind(scene, p) == SurfaceKind::Opaque);
        if let Some(m) = medium.filter(|m| has_opaque && m.emissive) {
            violated.push(format!(
                "a non-emissive medium where surfaces stand beside it (medium \"{}\" emits: the light it sends \
                 to them and back is not in the graph)",
                m.name
            ));
        }
        // In an anisotropic medium the light the surfaces reflect into it is a light of its own.
        // (The similar medium is isotropic: its light paths bounce off the surfaces.)
        if medium.is_some_and(|m| has_opaque && m.g != 0.0 && m.g <= MAX_G) {
            let reflected: Vec<GraphLight> =
                lights.iter().map(|l| GraphLight::Reflected { of: Box::new(l.clone()) }).collect();
            lights.extend(reflected);
        }
        if lights.len() > MAX_LIGHTS {
            violated.push(format!(
                "at most {MAX_LIGHTS} lights, area lights of one radiance counted once and, in an anisotropic \
                 medium beside surfaces, each light's reflection once more (the scene has {})",
                lights.len()
            ));
        }
        if !violated.is_empty() {
            return Err(crate::Error::Unsupported(format!(
                "the radiance-graph method needs {}",
                violated.iter().map(|v| format!("\n  - {v}")).collect::<String>()
            )));
        }
        let medium = medium.expect("checked");
        let similarity = (medium.g > MAX_G).then(|| Similarity::new(medium.g));
        Ok(Volume {
            scene,
            medium: match similarity {
                Some(_) => std::borrow::Cow::Owned(similarity::similar(medium).expect("checked")),
                None => std::borrow::Cow::Borrowed(medium),
            },
            similarity,
            medium_index: 0,
            bounds,
            radius: 0.5 * (bounds.max - bounds.min).length(),
            lights,
            has_opaque,
        })
    }

    /// Centre of the bounds.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.bounds.min + self.bounds.max)
    }

    /// Where `ray` (from outside the medium) first enters it and where it next leaves (at the
    /// boundary, or an opaque surface inside): `(t_in, t_out)`. `None` if it misses, or meets
    /// an opaque surface first.
    pub fn span(&self, ray: &Ray) -> Option<(f32, f32)> {
        let (t_in, hit, kind) = first_hit(self.scene, ray, f32::INFINITY, false)?;
        // Entering: the direction points against the surface normal.
        if kind != SurfaceKind::Boundary || ray.d.dot(hit.surface.n) >= 0.0 {
            return None;
        }
        let inner = hit.surface.spawn_ray(ray.d);
        let exit = self.exit(&inner)?;
        Some((t_in, (inner.o - ray.o).dot(ray.d) + exit))
    }

    /// The part of `ray` inside the medium from wherever its origin is: `(0, t_exit)` from
    /// inside, `(t_in, t_out)` from outside when it enters, `None` when it misses.
    pub fn span_from(&self, ray: &Ray) -> Option<(f32, f32)> {
        // Inside when the first boundary met is left through.
        let (_, hit, _) = first_hit(self.scene, ray, f32::INFINITY, true)?;
        if ray.d.dot(hit.surface.n) > 0.0 { Some((0.0, self.exit(ray)?)) } else { self.span(ray) }
    }

    /// The medium's intervals along `ray` (whose origin is outside it) that start before
    /// `t_end`, in order, into `v` (cleared first; callers reuse it). Opaque surfaces are
    /// passed: [`Volume::occluded`] asks for them.
    pub fn intervals(&self, ray: &Ray, t_end: f32, v: &mut Vec<(f32, f32)>) {
        v.clear();
        let (mut r, mut offset, mut start) = (*ray, 0.0, None);
        // A closed boundary is crossed an even number of times; 64 bounds a pathological mesh.
        for _ in 0..64 {
            let Some((t, hit, _)) = first_hit(self.scene, &r, f32::INFINITY, true) else { break };
            let t = offset + t;
            if r.d.dot(hit.surface.n) < 0.0 {
                if t >= t_end {
                    break;
                }
                start = Some(t);
            } else if let Some(a) = start.take() {
                v.push((a, t));
            }
            let next = hit.surface.spawn_ray(r.d);
            offset += (next.o - r.o).dot(r.d);
            r = next;
        }
    }

    /// Whether `x` is inside the medium: a ray from it meets the boundary from inside first.
    pub fn contains(&self, x: Vec3) -> bool {
        let ray = Ray::new(x, Vec3::Y);
        matches!(first_hit(self.scene, &ray, f32::INFINITY, true), Some((_, h, _)) if ray.d.dot(h.surface.n) > 0.0)
    }

    /// Whether an opaque surface (any but the medium's boundary) lies along `ray` before
    /// `t_max`: light from beyond it does not arrive.
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.has_opaque && first_opaque(self.scene, ray, t_max)
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

    /// Distance from a point inside the medium along `ray` to where light along it leaves the
    /// medium or stops: the boundary, or an opaque surface inside the medium.
    pub fn exit(&self, ray: &Ray) -> Option<f32> {
        first_hit(self.scene, ray, f32::INFINITY, false).map(|(t, _, _)| t)
    }

    /// A light path's segment `ray` from inside the medium passed through it: where the
    /// surfaces beside the medium send it back in, if they do. At each opaque surface it meets
    /// the BSDF samples a direction and the path goes on with probability f|cos|/pdf (gray:
    /// [`Volume::new`] and the direct light check it), so it stays a path of weight one whose
    /// next scattering point is an edge like any other; the medium's part of the way back is
    /// `(ray, t_max)` from where it enters. At most [`MAX_SURFACE_BOUNCES`] reflections.
    pub fn reflect_back(&self, ray: &Ray, rng: &mut Pcg32) -> Option<(Ray, f32)> {
        if !self.has_opaque {
            return None;
        }
        let scene = self.scene;
        let mut ray = *ray;
        for _ in 0..MAX_SURFACE_BOUNCES {
            let mut hit = next_opaque(scene, &ray)?;
            let wo = -ray.d;
            let (material, ctx) = scene.surface_material(&mut hit, wo, None);
            let bxdf = material.bxdf::<Rgb>(&scene.textures, &ctx, &mut ())?;
            let frame = crate::integrators::common::shading_frame(&hit);
            let u = glam::Vec2::new(rng.uniform(), rng.uniform());
            let bs =
                bxdf.sample_f(frame.to_local(wo), rng.uniform(), u, TransportMode::Radiance, ReflTransFlags::ALL)?;
            let weight = crate::color::average(bs.f * bs.wi.z.abs() / bs.pdf);
            // Also ends a NaN weight.
            if weight.is_nan() || rng.uniform() >= weight {
                return None;
            }
            let wi = frame.to_world(bs.wi);
            ray = hit.spawn_ray(wi);
            if let Some((t_in, t_out)) = self.span_from(&ray) {
                return Some((Ray::new(ray.at(t_in), wi), t_out - t_in));
            }
        }
        None
    }

    /// Samples where a segment from a point inside the medium first interacts (delta
    /// tracking with absorption and scattering as events, as the thesis's `TracePath`):
    /// a real scattering point, or the end of the path.
    pub fn sample_scatter(&self, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> Event {
        let u = rng.uniform();
        sample_event(&self.medium, ray, t_max, u, rng)
    }

    /// Transmittance along `ray` to distance `t_max` inside the medium, one ratio-tracking
    /// estimate (thesis Eq. 4.22 averages these): the shadow rays' own ratio tracking, with
    /// no unidirectional technique to weigh against (r_u = 0), so the estimate is T_ray / r_l
    /// and r_l is 1 in a gray medium. Its Russian roulette below 0.05 is nimbus's (and
    /// pbrt-v4's): unbiased, and walks deep into a dense cloud stop early instead of
    /// multiplying ever smaller ratios to the far side. The thesis tracks to the end.
    pub fn transmittance(&self, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> f32 {
        ratio_tracked(&self.medium, ray, t_max, rng)
    }

    /// [`transmittance_from_inside`] through the graph's medium (the similar one where it
    /// stands in for the scene's): what the build's direct light asks.
    pub fn transmittance_out(&self, ray: &Ray, t_end: f32, rng: &mut Pcg32) -> f32 {
        transmittance_from_inside(self.scene, &self.medium, ray, t_end, rng)
    }

    /// [`reflected_along`] through the graph's medium.
    pub fn reflected_along(&self, ray: &Ray, light: &GraphLight, rng: &mut Pcg32) -> Result<f32, Vec3> {
        reflected_along(self.scene, &self.medium, ray, light, rng)
    }
}

/// One ratio-tracking estimate of the transmittance along `ray` to `t_max` inside `medium`
/// (see [`Volume::transmittance`]).
fn ratio_tracked(medium: &Medium, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> f32 {
    let mut est = ShadowEstimate::<Rgb> { t_ray: Rgb::ONE, r_u: Rgb::ZERO, r_l: Rgb::ONE };
    ratio_tracking(None, medium.into(), ray, t_max, rng, 0, &(), &mut est);
    est.t_ray[0] / est.r_l[0]
}

/// Transmittance along `ray`, from a point inside `scene`'s one medium, to distance `t_end`
/// (∞: out of the scene): ratio tracking through each stretch of medium, the boundary
/// crossed as often as it is met; 0 behind an opaque surface.
pub fn transmittance_from_inside(scene: &Scene, medium: &Medium, ray: &Ray, t_end: f32, rng: &mut Pcg32) -> f32 {
    match walk(scene, medium, ray, t_end, true, rng) {
        (t, None) => t,
        (_, Some(_)) => 0.0,
    }
}

/// Along `ray` from a point inside the medium (`inside`) or outside it, to distance `t_end`:
/// the transmittance up to where it stops, and the opaque surface it stops at, if any, with
/// whether that surface is inside the medium.
pub fn walk(
    scene: &Scene,
    medium: &Medium,
    ray: &Ray,
    t_end: f32,
    inside: bool,
    rng: &mut Pcg32,
) -> (f32, Option<(Hit, bool)>) {
    let (mut ray, mut inside, mut tr, mut left) = (*ray, inside, 1.0f32, t_end);
    // A closed boundary is crossed an even number of times; 64 bounds a pathological mesh.
    for _ in 0..64 {
        let hit = first_hit(scene, &ray, left, false);
        if inside {
            let t_max = hit.as_ref().map_or(left, |h| h.0);
            tr *= ratio_tracked(medium, &ray, t_max, rng);
            if tr == 0.0 {
                return (0.0, None);
            }
        }
        match hit {
            None => return (tr, None),
            Some((_, h, SurfaceKind::Opaque)) => return (tr, Some((h, inside))),
            Some((_, h, _)) => {
                inside = ray.d.dot(h.surface.n) < 0.0;
                let next = h.surface.spawn_ray(ray.d);
                left -= (next.o - ray.o).dot(ray.d);
                ray = next;
            }
        }
    }
    (tr, None)
}

/// What a surface is to the method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceKind {
    /// The medium's boundary: an `interface` material with the medium inside, none outside.
    Boundary,
    /// A surface beside the medium that changes no medium (ground, objects, area lights'
    /// shapes): camera paths shade it as volpath does; it stops light paths and shadow rays.
    Opaque,
    /// An `interface` material that changes no medium: crossed as if absent.
    Invisible,
    /// Any other change of medium (a dielectric around the medium, ...).
    OtherInterface,
}

/// The kind of primitive `p` of `scene`.
pub fn surface_kind(scene: &Scene, p: &Primitive) -> SurfaceKind {
    let pass = scene.surfaces.pass_through.get(p.material as usize).copied().unwrap_or(false);
    let sides = (p.interface != NONE).then(|| scene.interfaces[p.interface as usize]);
    match sides {
        Some([inside, outside]) if inside != outside => {
            if pass && [inside, outside] == [0, NONE] {
                SurfaceKind::Boundary
            } else {
                SurfaceKind::OtherInterface
            }
        }
        _ if pass => SurfaceKind::Invisible,
        _ => SurfaceKind::Opaque,
    }
}

/// The first surface along `ray` before `t_max` that the method sees, with its distance
/// along `ray` and its kind: invisible surfaces are passed, and opaque ones too where
/// `boundary_only`.
fn first_hit(scene: &Scene, ray: &Ray, t_max: f32, boundary_only: bool) -> Option<(f32, Hit, SurfaceKind)> {
    let (mut r, mut offset) = (*ray, 0.0);
    for _ in 0..64 {
        let hit = scene.surfaces.intersect(&r, t_max - offset)?;
        let kind = surface_kind(scene, &hit.prim);
        if kind == SurfaceKind::Boundary || (kind != SurfaceKind::Invisible && !boundary_only) {
            return Some((offset + hit.surface.t, hit, kind));
        }
        let next = hit.surface.spawn_ray(r.d);
        offset += (next.o - r.o).dot(r.d);
        r = next;
    }
    None
}

/// The first opaque surface along `ray` (boundaries and invisible surfaces passed).
fn next_opaque(scene: &Scene, ray: &Ray) -> Option<Hit> {
    let mut r = *ray;
    for _ in 0..64 {
        let (_, hit, kind) = first_hit(scene, &r, f32::INFINITY, false)?;
        if kind != SurfaceKind::Boundary {
            return Some(hit);
        }
        r = hit.surface.spawn_ray(r.d);
    }
    None
}

/// Whether an opaque surface lies along `ray` before `t_max` (boundaries passed).
fn first_opaque(scene: &Scene, ray: &Ray, t_max: f32) -> bool {
    let (mut r, mut offset) = (*ray, 0.0);
    for _ in 0..64 {
        let Some((t, hit, kind)) = first_hit(scene, &r, t_max - offset, false) else { return false };
        if kind != SurfaceKind::Boundary {
            return true;
        }
        let next = hit.surface.spawn_ray(r.d);
        offset += t + (next.o - hit.surface.p).dot(r.d);
        r = next;
    }
    false
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

/// The spectrum of `medium`'s emission when it is one spectrum times a scalar field (a
/// homogeneous medium's `Le`; a grid's `Le` with its `Lescale` grid), else `None`.
pub fn emission_spectrum(medium: &Medium) -> Option<SpectrumValue> {
    match &medium.kind {
        MediumKind::Homogeneous { le, .. } => Some(*le),
        MediumKind::Grid(g) => match &g.emission {
            Emission::Radiance { le, .. } => Some(*le),
            _ => None,
        },
        MediumKind::RgbGrid(_) => None,
    }
}

/// The emission reaching the origin of `ray` (inside the medium) along it, per unit of the
/// emission's spectrum `unit` (RGB): ∫ T_r(t) σa(t) s(t) dt over the medium's stretches, s
/// the emission's scalar field. At each tentative collision of the majorant the collision
/// estimator adds the ratio-tracked transmittance so far times σa s / σmaj; Russian roulette
/// below 0.05 as the shadow rays'. Opaque surfaces end it.
pub fn emission_along(scene: &Scene, ray: &Ray, unit: Rgb, rng: &mut Pcg32) -> f32 {
    let medium = &scene.media[0];
    let c = if unit.x >= unit.y && unit.x >= unit.z {
        0
    } else if unit.y >= unit.z {
        1
    } else {
        2
    };
    let per_unit = 1.0 / unit[c];
    let (mut ray, mut inside, mut tr, mut sum) = (*ray, true, 1.0f32, 0.0f32);
    for _ in 0..64 {
        let hit = first_hit(scene, &ray, f32::INFINITY, false);
        if inside {
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.0);
            let u = rng.uniform();
            tr = collision_walk(medium, &ray, t_max, u, rng, tr, |_, mp, w, _| {
                sum += w * mp.sigma_a[0] * mp.le[c] * per_unit;
            });
            if tr == 0.0 {
                return sum;
            }
        }
        match hit {
            None | Some((_, _, SurfaceKind::Opaque)) => return sum,
            Some((_, h, _)) => {
                inside = ray.d.dot(h.surface.n) < 0.0;
                ray = h.surface.spawn_ray(ray.d);
            }
        }
    }
    sum
}

/// Light of unit radiance from `light` arriving at the origin of `ray` (in the medium) along
/// it, backwards, after one reflection off a surface beside the medium (beyond the thesis): one
/// sample of T_r(x, y) f(y) |cos| T_r(y, light) L / pdf_light at the first opaque surface y
/// along the ray. Light that crosses the medium on its way to a surface, and from there back
/// into the medium, is in the graph's transport no further than this one reflection. `Err`
/// (where) when the surface reflects colored light. Transmittance through `medium`: the
/// graph's (the similar medium where it stands in for the scene's).
pub fn reflected_along(
    scene: &Scene,
    medium: &Medium,
    ray: &Ray,
    light: &GraphLight,
    rng: &mut Pcg32,
) -> Result<f32, Vec3> {
    let d = ray.d;
    let (t_to, Some((mut hit, inside))) = walk(scene, medium, ray, f32::INFINITY, true, rng) else {
        return Ok(0.0);
    };
    if t_to <= 0.0 {
        return Ok(0.0);
    }
    let y = hit.surface.p;
    // Toward the light: (direction, radiance per unit, density, distance).
    let (wi, l, pdf, dist) = match light {
        GraphLight::Distant { dir, .. } => (-*dir, 1.0, 1.0, f32::INFINITY),
        GraphLight::Uniform { .. } => (
            crate::sampling::warp::uniform_sphere(glam::Vec2::new(rng.uniform(), rng.uniform())),
            1.0,
            crate::sampling::warp::UNIFORM_SPHERE_PDF,
            f32::INFINITY,
        ),
        GraphLight::Point { pos, .. } => {
            let d2 = pos.distance_squared(y);
            ((*pos - y) / d2.sqrt(), 1.0 / d2, 1.0, d2.sqrt() * (1.0 - 1e-4))
        }
        GraphLight::Area { lights, .. } => match sample_area_lights(scene, lights, y, rng) {
            Some((wi, dist, pdf)) => (wi, 1.0, pdf, dist),
            None => return Ok(0.0),
        },
        // Volume refuses an emitting medium beside surfaces; a reflected light is reflected
        // once, by its own light.
        GraphLight::Emission { .. } | GraphLight::Reflected { .. } => return Ok(0.0),
    };
    let wo = -d;
    let (material, ctx) = scene.surface_material(&mut hit, wo, None);
    let Some(bxdf) = material.bxdf::<Rgb>(&scene.textures, &ctx, &mut ()) else { return Ok(0.0) };
    let frame = crate::integrators::common::shading_frame(&hit);
    let wl = frame.to_local(wi);
    let f = bxdf.f(frame.to_local(wo), wl, TransportMode::Radiance) * wl.z.abs();
    if f.max_element() <= 0.0 {
        return Ok(0.0);
    }
    if f.max_element() - f.min_element() > 1e-3 * f.max_element() {
        return Err(y);
    }
    let (t_from, stopped) = walk(scene, medium, &hit.surface.spawn_ray(wi), dist, inside, rng);
    if stopped.is_some() {
        return Ok(0.0);
    }
    Ok(t_to * f.x * l * t_from / pdf)
}

/// A collision estimator along `ray` to `t_max` in `medium` (gray): at each tentative collision
/// of the majorant (the first at `u`), `add(p, coefficients, w, rng)` with w the ratio-tracked
/// transmittance so far, starting from `tr`, over σmaj — so that Σ w·f estimates
/// ∫ T_r(t) f(t) dt —, then the transmittance takes the null fraction, with Russian roulette
/// below 0.05 as the shadow rays'. Returns the transmittance at `t_max` (0 once roulette or a
/// collision ends it).
pub fn collision_walk(
    medium: &Medium,
    ray: &Ray,
    t_max: f32,
    u: f32,
    rng: &mut Pcg32,
    mut tr: f32,
    mut add: impl FnMut(Vec3, &MediumPoint<Rgb>, f32, &mut Pcg32),
) -> f32 {
    sample_t_maj::<Rgb, _>(medium.into(), ray, t_max, u, rng, 0, &(), |p, mp, sigma_maj, _, rng| {
        let s = sigma_maj[0];
        add(p, mp, tr / s, rng);
        tr *= ((s - mp.sigma_a[0] - mp.sigma_s[0]) / s).max(0.0);
        if tr < 0.05 {
            if rng.uniform() < 0.75 {
                tr = 0.0;
            } else {
                tr /= 0.25;
            }
        }
        tr > 0.0
    });
    tr
}

/// A light sample at `p` from the area lights `lights` of one radiance, per unit of it: one of
/// them chosen by area, a point by its own sampling. Returns the unit direction toward it,
/// the distance to stop short of its surface (which would count as an occluder), and the
/// sample's density (choice × solid angle); `None` when the sample carries nothing.
pub fn sample_area_lights(scene: &Scene, lights: &[u32], p: Vec3, rng: &mut Pcg32) -> Option<(Vec3, f32, f32)> {
    let total: f32 = lights.iter().map(|&i| light_area(scene, i)).sum();
    let i = pick_by_area(scene, lights, total, rng.uniform());
    let pmf = light_area(scene, i) / total;
    let u = glam::Vec2::new(rng.uniform(), rng.uniform());
    let ctx = crate::lights::LightContext { p };
    let ls = scene.lights[i as usize].sample_li::<Rgb>(&ctx, u, &scene.surfaces, &scene.sphere, &())?;
    Some((ls.wi, ls.p.distance(p) * (1.0 - 1e-4), pmf * ls.pdf))
}

/// The area of scene light `i` (0 for a light that is not an area light).
fn light_area(scene: &Scene, i: u32) -> f32 {
    match scene.lights[i as usize].kind {
        LightKind::Area { area, .. } => area,
        _ => 0.0,
    }
}

/// One of the area lights `lights`, chosen by `u` in proportion to their areas.
pub fn pick_area_light(scene: &Scene, lights: &[u32], u: f32) -> u32 {
    let total: f32 = lights.iter().map(|&i| light_area(scene, i)).sum();
    pick_by_area(scene, lights, total, u)
}

/// [`pick_area_light`] with the areas' sum `total` known.
fn pick_by_area(scene: &Scene, lights: &[u32], total: f32, u: f32) -> u32 {
    let mut left = u * total;
    for &i in lights {
        let a = light_area(scene, i);
        if left < a {
            return i;
        }
        left -= a;
    }
    lights[lights.len() - 1]
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
