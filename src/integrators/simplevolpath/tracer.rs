//! The shading loop: the paper's `radiance(ray)` (§2), made iterative. Every event the
//! probabilistic intersection returns is shaded the same way, a surface with its BSDF and a
//! medium particle with its phase function and albedo (§4: "exactly how surfaces are shaded,
//! except that we use the phase function"):
//!
//! 1. add the emission found there (an area light hit, a medium particle's σa/σt·Le, the
//!    environment when the ray escapes) — the only way light is found, apart from delta
//!    lights below;
//! 2. at a medium particle, weight by the single-scattering albedo Λ = σs/σt (Eq. 5);
//! 3. draw one direction ω' from the mixture density p (§3) and trace it (§4);
//! 4. multiply by ρ(ω, ω') cos θ' / p(ω') — Equation 2 — or p(ω, ω') / p(ω') in a medium,
//!    with p evaluated for every component where the ray went ([`super::mixture`]).
//!
//! There is no shadow ray and no direct/indirect split, with one exception the paper does not
//! meet: point, spot and distant lights are deltas that no direction can hit, so each vertex
//! makes one deterministic connection to one of them ([`DeltaLights`]), traced with the same
//! probabilistic intersection (a medium 'hit' blocks it like a surface does).
//!
//! Russian roulette (pbrt-v4's, on the throughput with refraction's scaling undone) ends
//! long paths from the third vertex on; it is not in the paper.

use glam::{Vec2, Vec3};

use super::intersection::{Event, Intersection, Seed, intersect};
use super::mixture::{Mixture, Scatterer};
use crate::accel::{Hit, NONE};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::integrators::common::{MAX_SUBSURFACE_EVENTS, RayStats, medium_after, shading_frame};
use crate::lights::LightContext;
use crate::media::phase::HenyeyGreenstein;
use crate::samplers::Sampler;

/// The throughput above which a medium vertex samples the phase function alone (see
/// `Path::mix_share`).
const MAX_MIXING_BETA: f32 = 2.0;
use crate::sampling::distribution::AliasTable;
use crate::scene::Scene;

/// Per-path state.
struct Path<C> {
    /// Throughput (per channel: f_c / p_hero).
    beta: C,
    /// Spectral-MIS ratios p_c / p_hero of chromatic media (1 otherwise).
    r_u: C,
    /// The channel whose coefficients drive distance sampling in chromatic media.
    hero: usize,
    /// Scattering events so far.
    depth: u32,
    /// Those inside `subsurface` media, which `maxdepth` does not count (pbrt-v4's BSSRDF is
    /// one event, counted at its entry vertex).
    free: u32,
    /// Product of η² over refractions (undone for Russian roulette).
    eta_scale: f32,
    /// The camera ray's time, which every ray of the path keeps.
    time: f32,
}

impl<C: Channels> Path<C> {
    /// Takes on the throughput factor of reaching an event.
    #[inline]
    fn carry(&mut self, i: &Intersection<C>) {
        self.beta *= i.beta;
        self.r_u *= i.r_u;
    }

    /// Radiance `le` found at the current event, as it reaches the camera.
    #[inline]
    fn weigh(&self, le: C) -> C {
        self.beta * le / self.r_u.average()
    }

    /// Counts a scattering event in `medium` (at a surface, the one the path arrives in);
    /// false when `max_depth` (or, inside a subsurface medium, its own bound) ends the path.
    #[inline]
    fn count(&mut self, medium: Option<&crate::media::Medium>, max_depth: u32) -> bool {
        if medium.is_some_and(|m| m.subsurface) {
            if self.free >= MAX_SUBSURFACE_EVENTS {
                return false;
            }
            self.free += 1;
        } else if self.depth - self.free == max_depth {
            return false;
        }
        self.depth += 1;
        true
    }

    /// How much of the mixture a medium vertex samples from: the scale of the luminaire and
    /// environment shares ([`super::mixture::Mixture::weights`]). A vertex's weight f/p is at
    /// most Λ/c_s (c_s < 1 the phase function's share): unbiased at each vertex, but a product
    /// over n vertices whose second moment can grow as (1/c_s)^n, which the long
    /// forward-scattering chains of a dense cloud turn into fireflies (with g = 0.877,
    /// p_s ≫ p_e ahead, so most vertices weigh about 1/c_s). The coefficients may depend on
    /// anything but the direction drawn here, so a path whose throughput β has risen above 1
    /// scales the other shares by 1/β (c_s = 1 − (1 − c_s⁰)/β: a vertex multiplies β by at
    /// most β/(β − 1 + c_s⁰), so β grows by less than 1 − c_s⁰ per vertex instead of by the
    /// factor 1/c_s⁰) and above [`MAX_MIXING_BETA`] samples the phase function alone (weight
    /// Λ ≤ 1): β never exceeds about MAX_MIXING_BETA·Λ through the media's mixtures, each
    /// vertex stays an unbiased one-sample MIS estimator, and luminaires keep being sampled
    /// along the chains of a small light's medium (the stress matrix's `08-light-small`, where
    /// turning the mixture off above β = 1 left a light of radius 0.05 to the phase function:
    /// relMSE 4125× volpath's). Surface vertices keep the mixture: their chains are short
    /// (ρ < 1, roulette), and a small luminaire found by the BSDF alone would be a firefly of
    /// its own.
    #[inline]
    fn mix_share(&self) -> f32 {
        let beta = (self.beta * self.eta_scale / self.r_u.average()).max_element();
        if beta <= 1.0 {
            1.0
        } else if beta <= MAX_MIXING_BETA {
            1.0 / beta
        } else {
            0.0
        }
    }

    /// Russian roulette; true when the path ends. The sampler value is drawn at every vertex.
    #[inline]
    fn roulette(&mut self, sampler: &mut Sampler) -> bool {
        let u = sampler.get_1d();
        let rr = (self.beta * self.eta_scale / self.r_u.average()).max_element();
        if rr < 1.0 && self.depth > 2 {
            let q = (1.0 - rr).max(0.0);
            if u < q {
                return true;
            }
            self.beta /= 1.0 - q;
        }
        false
    }
}

/// x / y per channel, 0 where y is 0 (a channel without extinction has no particles; its
/// throughput to this event is already 0).
#[inline]
fn ratio<C: Channels>(x: C, y: C) -> C {
    x.zip_map(y, |a, b| if b > 0.0 { a / b } else { 0.0 })
}

/// Radiance the infinite lights send along an escaping ray.
#[inline]
fn escaped<C: Channels>(scene: &Scene, o: Vec3, d: Vec3, lambda: &C::Lambda) -> C {
    scene.infinite_lights.iter().fold(C::ZERO, |sum, &i| sum + scene.lights[i as usize].le(o, d, lambda))
}

/// Point, spot and distant lights, chosen in proportion to power for the one deterministic
/// connection per vertex that they need (a deviation from the paper: they cannot be hit).
#[derive(Clone, Debug)]
pub struct DeltaLights {
    table: Option<AliasTable>,
}

impl DeltaLights {
    /// The delta lights of `scene`.
    pub fn new(scene: &Scene) -> DeltaLights {
        let w: Vec<f32> =
            scene.lights.iter().map(|l| if l.is_delta() { l.power(&scene.sphere) } else { 0.0 }).collect();
        DeltaLights { table: w.iter().any(|p| *p > 0.0).then(|| AliasTable::new(&w)) }
    }

    /// The light arriving from one delta light at vertex `x` (on surface `hit`, or in a
    /// medium), scattered towards the previous vertex: f·L·T / P(light), with the
    /// transmittance T estimated by tracing the connection through the probabilistic
    /// intersection (1 if it arrives, 0 if anything — a surface or a medium particle — comes
    /// first; with spectral-MIS ratios in chromatic media).
    #[allow(clippy::too_many_arguments)]
    fn connect<C: Channels>(
        &self,
        scene: &Scene,
        x: Vec3,
        hit: Option<&Hit>,
        medium: u32,
        sc: &Scatterer<'_, C>,
        path: &Path<C>,
        lambda: &C::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> C {
        let Some(table) = &self.table else { return C::ZERO };
        let u_pick = sampler.get_1d();
        let seed = Seed::draw(scene, sampler);
        if !sc.is_non_specular() {
            return C::ZERO;
        }
        let Some(pick) = table.sample(u_pick) else { return C::ZERO };
        let light = &scene.lights[pick.index];
        let ctx = LightContext { p: x };
        let Some(ls) = light.sample_li::<C>(&ctx, Vec2::ZERO, &scene.surfaces, &scene.sphere, lambda) else {
            return C::ZERO;
        };
        let (f, _) = sc.eval(ls.wi);
        if f.is_zero() || ls.l.is_zero() {
            return C::ZERO;
        }
        let (origin, mut medium) = match hit {
            Some(h) => (h.surface.offset_origin(ls.wi), medium_after(scene, h, ls.wi, medium)),
            None => (x, medium),
        };
        let mut ray = Ray::timed(origin, ls.wi, path.time);
        let mut t_max = if ls.infinite { f32::INFINITY } else { (ls.p - origin).length() };
        let (mut tr, mut r_u) = (C::ONE, C::ONE);
        let mut seed = seed;
        loop {
            let i = intersect::<C>(scene, ray, medium, t_max, seed, path.hero, lambda, &mut stats.shadow);
            tr *= i.beta;
            r_u *= i.r_u;
            match i.event {
                Event::Escape => break,
                // An emissive interface is still only a boundary for the connection.
                Event::Surface(h) if scene.materials[h.prim.material as usize].is_interface() => {
                    medium = medium_after(scene, &h, ray.d, i.medium);
                    let next = h.spawn_ray(ray.d);
                    t_max -= (next.o - ray.o).dot(ray.d);
                    if t_max <= 0.0 {
                        break;
                    }
                    ray = next;
                    seed = Seed::draw(scene, sampler);
                }
                _ => return C::ZERO,
            }
        }
        path.beta * f * ls.l * tr / (pick.pmf * (path.r_u * r_u).average())
    }
}

/// Radiance arriving at the camera along `ray` at the wavelengths `lambda`, one path.
#[allow(clippy::too_many_arguments)]
pub fn trace<C: Channels>(
    scene: &Scene,
    mixture: &Mixture,
    delta: &DeltaLights,
    max_depth: u32,
    ray: Ray,
    lambda: &mut C::Lambda,
    sampler: &mut Sampler,
    stats: &mut RayStats,
) -> C {
    let hero = if scene.has_chromatic_media { C::hero_channel(sampler.get_1d()) } else { 0 };
    let mut path = Path { beta: C::ONE, r_u: C::ONE, hero, depth: 0, free: 0, eta_scale: 1.0, time: ray.time };
    let mut l = C::ZERO;
    let seed = Seed::draw(scene, sampler);
    // The camera ray's differentials, for textures at the first event (pbrt-v4's SimpleVolPath
    // spawns later rays without any).
    let camera_diff = scene.footprint.as_ref().and_then(|f| f.camera_differentials(&scene.camera, &ray));
    let mut isect =
        intersect::<C>(scene, ray, scene.camera_medium, f32::INFINITY, seed, hero, lambda, &mut stats.bounce);
    path.carry(&isect);
    loop {
        if path.beta.is_zero() || !path.beta.is_finite() {
            break;
        }
        let wo = -isect.ray.d;
        // Shade the event: emission, then what scatters there.
        let bxdf;
        let (x, hit, sc) = match isect.event {
            Event::Escape => {
                l += path.weigh(escaped(scene, isect.ray.o, isect.ray.d, lambda));
                break;
            }
            Event::Surface(mut hit) => {
                if hit.prim.area_light != NONE {
                    l += path.weigh(scene.lights[hit.prim.area_light as usize].emitted(
                        &hit.surface,
                        wo,
                        lambda,
                        &scene.surfaces,
                    ));
                }
                let (material, tex_ctx) =
                    scene.surface_material(&mut hit, wo, camera_diff.as_ref().filter(|_| path.depth == 0));
                let s = &hit.surface;
                let Some(b) = material.bxdf::<C>(&scene.textures, &tex_ctx, lambda) else {
                    // An emissive `interface`: its light is counted; the ray goes on.
                    let medium = medium_after(scene, &hit, isect.ray.d, isect.medium);
                    let seed = Seed::draw(scene, sampler);
                    let ray = hit.spawn_ray(isect.ray.d);
                    isect = intersect(scene, ray, medium, f32::INFINITY, seed, hero, lambda, &mut stats.bounce);
                    path.carry(&isect);
                    continue;
                };
                if !path.count(scene.media.get(isect.medium as usize), max_depth) {
                    break;
                }
                bxdf = b;
                let frame = shading_frame(&hit);
                (s.p, Some(hit), Scatterer::Surface { bxdf: &bxdf, frame, wo: frame.to_local(wo) })
            }
            Event::Medium { p, point, medium } => {
                // The particle emits σa/σt·Le (what a 'hit' with probability ∝ σt sees of the
                // σa·Le emitted per unit length), counted below maxdepth as pbrt-v4 does.
                let sigma_t = point.sigma_a + point.sigma_s;
                if path.depth - path.free < max_depth && !point.le.is_zero() {
                    l += path.weigh(ratio(point.sigma_a, sigma_t) * point.le);
                }
                if !path.count(scene.media.get(medium as usize), max_depth) {
                    break;
                }
                // Equation 5: the particle reflects the fraction Λ = σs/σt.
                path.beta *= ratio(point.sigma_s, sigma_t);
                if path.beta.is_zero() {
                    break; // a purely absorbing particle
                }
                let phase = HenyeyGreenstein::new(scene.media[medium as usize].g);
                (p, None, Scatterer::Medium { phase, wo })
            }
        };
        if path.roulette(sampler) {
            break;
        }
        l += delta.connect(scene, x, hit.as_ref(), isect.medium, &sc, &path, lambda, sampler, stats);

        // Equation 2: one direction from the mixture density, traced by the probabilistic
        // intersection, weighted by f / p with p evaluated where the ray went.
        let u_comp = sampler.get_1d();
        let u = sampler.get_2d();
        let mix = if matches!(sc, Scatterer::Medium { .. }) { path.mix_share() } else { 1.0 };
        let Some(s) = mixture.sample(scene, x, &sc, mix, u_comp, u, lambda) else { break };
        if s.f.is_zero() {
            break;
        }
        let (ray, medium) = match &hit {
            Some(h) => (h.spawn_ray(s.wi), medium_after(scene, h, s.wi, isect.medium)),
            None => (Ray::timed(x, s.wi, path.time), isect.medium),
        };
        let seed = Seed::draw(scene, sampler);
        let next = intersect(scene, ray, medium, f32::INFINITY, seed, hero, lambda, &mut stats.bounce);
        let first = match &next.event {
            Event::Surface(h) => Some(h),
            _ => None,
        };
        let Some(pdf) = mixture.pdf_along(scene, x, &s, first) else { break };
        if pdf <= 0.0 {
            break;
        }
        path.beta *= s.f / pdf;
        path.eta_scale *= s.eta * s.eta;
        isect = next;
        path.carry(&isect);
    }
    l
}
