//! Photons from the lights (Deng et al. 2020, Sec. 4.2): emitted from every light in
//! proportion to its power, refracted through dielectric boundaries and passed through
//! `interface` surfaces, random-walking inside media (delta tracking through the majorant
//! grids, phase-function sampling), reporting each real scattering event's position and the
//! direction the photon came from.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::accel::NONE;
use crate::channels::Channels;
use crate::geometry::{Ray, spawn_ray};
use crate::integrators::common::media::sample_t_maj;
use crate::integrators::common::{medium_after, shading_frame};
use crate::lights::{LightKind, SceneSphere, smoothstep};
use crate::materials::bxdf::{ReflTransFlags, TransportMode};
use crate::math::Frame;
use crate::media::phase::HenyeyGreenstein;
use crate::sampling::distribution::AliasTable;
use crate::sampling::rng::Pcg32;
use crate::sampling::warp;
use crate::scene::Scene;
use crate::spectra::RgbRole;
use crate::textures::TexContext;

/// A photon leaving a light, carrying the channels `C` of the scene's transport.
#[derive(Clone, Copy, Debug)]
pub struct Photon<C> {
    /// Where it starts and where it goes.
    pub ray: Ray,
    /// The medium it starts in.
    pub medium: u32,
    /// Its power (W, per channel), divided by the densities of its choice.
    pub power: C,
    /// Whether it left a delta light (point, spot, distant), which no camera path can hit.
    pub delta: bool,
}

/// Chooses lights in proportion to their power, and directions partly towards the media.
pub struct Emitter {
    table: AliasTable,
    /// A sphere around where photons scattered in the pilot (the media), if known.
    target: Option<SceneSphere>,
}

/// Share of photons aimed at the media once the pilot has found them. The rest leave as the
/// light emits, so light that reaches the media only by way of other surfaces is still
/// learned; each photon's power divides by the mixture of the two densities, so the deposits
/// stay unbiased estimates of the light arriving in the media.
const AIMED: f32 = 0.75;

/// A direction from `p` into the cone subtending `target` (`None` when `p` is inside it):
/// the cone's frame and cos of its half-angle.
fn cone_towards(p: Vec3, target: &SceneSphere) -> Option<(Frame, f32)> {
    let to = target.center - p;
    let d2 = to.length_squared();
    let r2 = target.radius * target.radius;
    if d2 <= r2 * 1.0001 {
        return None;
    }
    let cos_max = (1.0 - r2 / d2).max(0.0).sqrt();
    Some((Frame::from_z(to / d2.sqrt()), cos_max))
}

impl Emitter {
    /// The lights of `scene`, or `None` when none emits.
    pub fn new(scene: &Scene) -> Option<Emitter> {
        let power: Vec<f32> = scene.lights.iter().map(|l| l.power(&scene.sphere)).collect();
        power.iter().any(|&p| p > 0.0).then(|| Emitter { table: AliasTable::new(&power), target: None })
    }

    /// Aims [`AIMED`] of the photons at `target`.
    pub fn aim_at(&mut self, target: SceneSphere) {
        self.target = Some(target);
    }

    /// A photon at the wavelengths `lambda` (`None` when the sample carries nothing, e.g.
    /// outside a spotlight's cone).
    pub fn emit<C: Channels>(&self, scene: &Scene, lambda: &C::Lambda, rng: &mut Pcg32) -> Option<Photon<C>> {
        let pick = self.table.sample(rng.uniform())?;
        let light = &scene.lights[pick.index];
        let u = Vec2::new(rng.uniform(), rng.uniform());
        let u2 = Vec2::new(rng.uniform(), rng.uniform());
        let aim = self.target.is_some() && rng.uniform() < AIMED;
        let sphere = scene.sphere;
        // A ray arriving from direction `w` (towards the light) through the disk covering the
        // scene's bounding sphere or the target, and the reciprocal of the density of its
        // point on the plane (per area).
        let from_infinity = |w: Vec3, u: Vec2| {
            let f = Frame::from_z(w);
            let disk = |s: &SceneSphere| (s.center - f.z * f.z.dot(s.center), s.radius);
            let (scene_c, scene_r) = disk(&sphere);
            let (c, r) = match (&self.target, aim) {
                (Some(t), true) => disk(t),
                _ => (scene_c, scene_r),
            };
            let d = warp::concentric_disk(u) * r;
            let on_plane = c + f.x * d.x + f.y * d.y;
            // The mixture's density at that point of the plane.
            let inside = |(c, r): (Vec3, f32)| ((on_plane - c).length_squared() <= r * r) as u32 as f32 / (PI * r * r);
            let pdf = match &self.target {
                Some(t) => AIMED * inside(disk(t)) + (1.0 - AIMED) * inside((scene_c, scene_r)),
                None => 1.0 / (PI * scene_r * scene_r),
            };
            (Ray::new(on_plane + w * (sphere.center.dot(w) + 2.0 * sphere.radius), -w), 1.0 / pdf)
        };
        // A direction from `p` by `native` (direction and density), or aimed at the target,
        // and the mixture's density for it.
        let leave = |p: Vec3, native: &dyn Fn(Vec2) -> Vec3, native_pdf: &dyn Fn(Vec3) -> f32| {
            let cone = self.target.as_ref().and_then(|t| cone_towards(p, t));
            let d = match (cone, aim) {
                (Some((f, cos_max)), true) => f.to_world(warp::uniform_cone(u2, cos_max)),
                _ => native(u2),
            };
            let pdf = match cone {
                Some((f, cos_max)) => {
                    let in_cone = f.z.dot(d) >= cos_max;
                    AIMED * if in_cone { warp::uniform_cone_pdf(cos_max) } else { 0.0 } + (1.0 - AIMED) * native_pdf(d)
                }
                None => native_pdf(d),
            };
            (d, pdf)
        };
        let mut medium = light.medium;
        let (ray, power) = match &light.kind {
            LightKind::Point { p, i } => {
                let (d, pdf) = leave(*p, &warp::uniform_sphere, &|_| warp::UNIFORM_SPHERE_PDF);
                (Ray::new(*p, d), C::eval(i, lambda) / pdf)
            }
            LightKind::Goniometric { p, i, image } => {
                // Directions as a point light's, weighted by the map.
                let (d, pdf) = leave(*p, &warp::uniform_sphere, &|_| warp::UNIFORM_SPHERE_PDF);
                (Ray::new(*p, d), C::eval(i, lambda) * (image.lookup(d) / pdf))
            }
            LightKind::Projection { p, scale, image } => {
                let (d, pdf) = leave(*p, &warp::uniform_sphere, &|_| warp::UNIFORM_SPHERE_PDF);
                let l = match image.lookup(d) {
                    Some(rgb) => C::from_rgb(rgb, RgbRole::Illuminant, image.space, lambda) * (*scale / pdf),
                    None => C::ZERO,
                };
                (Ray::new(*p, d), l)
            }
            LightKind::Spot { p, frame, i, cos_falloff_start, cos_falloff_end } => {
                let end = *cos_falloff_end;
                let native = |u: Vec2| frame.to_world(warp::uniform_cone(u, end));
                let native_pdf = |d: Vec3| if frame.z.dot(d) >= end { warp::uniform_cone_pdf(end) } else { 0.0 };
                let (d, pdf) = leave(*p, &native, &native_pdf);
                let falloff = smoothstep(end, *cos_falloff_start, frame.z.dot(d));
                (Ray::new(*p, d), C::eval(i, lambda) * (falloff / pdf))
            }
            LightKind::Distant { w, l } => {
                let (ray, area) = from_infinity(*w, u);
                (ray, C::eval(l, lambda) * area)
            }
            LightKind::UniformInfinite { l } => {
                let w = warp::uniform_sphere(u2);
                let (ray, area) = from_infinity(w, u);
                (ray, C::eval(l, lambda) * (area / warp::UNIFORM_SPHERE_PDF))
            }
            LightKind::ImageInfinite(map) => {
                let (w, pdf, l) = map.sample::<C>(u2, lambda)?;
                let (ray, area) = from_infinity(w, u);
                (ray, l * (area / pdf))
            }
            // From the whole environment, as pbrt-v4's `SampleLe` (not only through the
            // portal): the walls around it stop the rest.
            LightKind::PortalInfinite(map) => {
                let (w, pdf, l) = map.sample_emission::<C>(u2, lambda)?;
                let (ray, area) = from_infinity(w, u);
                (ray, l * (area / pdf))
            }
            LightKind::Area { geometry, l, image, two_sided, interface, alpha, .. } => {
                let shapes = &scene.surfaces.shapes;
                let s = light.sample_area_point(shapes, u)?;
                // pbrt-v4's `SampleLe` checks the point against the alpha texture.
                let uv = if *alpha != NONE || image.is_some() {
                    shapes.uv_at(*geometry, s.p, s.p + s.n)?
                } else {
                    Vec2::ZERO
                };
                if *alpha != NONE && crate::lights::alpha_masked(&scene.surfaces, *alpha, s.p, uv, s.n) {
                    return None;
                }
                // Natively cosine-weighted about the normal (either side for two-sided
                // emitters); the power is L·|cos| over the densities.
                let n = s.n;
                let sides = if *two_sided { 2.0 } else { 1.0 };
                let flip = *two_sided && rng.uniform() < 0.5;
                let native = |u: Vec2| {
                    let side = if flip { -n } else { n };
                    Frame::from_z(side).to_world(warp::cosine_hemisphere(u))
                };
                let native_pdf = |d: Vec3| {
                    let c = n.dot(d);
                    if *two_sided { c.abs() / (sides * PI) } else { c.max(0.0) / PI }
                };
                let (d, pdf) = leave(s.p, &native, &native_pdf);
                let cos = n.dot(d);
                if pdf <= 0.0 || (!*two_sided && cos <= 0.0) {
                    return None;
                }
                let le: C = crate::lights::area_radiance(l, image.as_deref(), uv, lambda);
                let power = le * (cos.abs() / (pdf * s.pdf));
                let ray = spawn_ray(s.p, if cos > 0.0 { n } else { -n }, d);
                // The medium on the side the photon leaves towards: the shape's interface says,
                // else the medium whose boundary encloses the light.
                medium = if *interface != NONE {
                    let [inside, outside] = scene.interfaces[*interface as usize];
                    if cos > 0.0 { outside } else { inside }
                } else {
                    medium_containing(scene, ray)
                };
                (ray, power)
            }
        };
        let power = power / pick.pmf;
        let delta = light.is_delta();
        (power.max_element() > 0.0 && power.is_finite()).then_some(Photon { ray, medium, power, delta })
    }
}

/// The medium a ray starts in, found from the first medium boundary it crosses (the side it
/// came from), passing through other surfaces; [`NONE`] when it crosses none. Camera paths
/// learn their media from the camera's; a light without a medium interface of its own is
/// found this way, as a path from the camera reaching it would be in that medium.
fn medium_containing(scene: &Scene, mut ray: Ray) -> u32 {
    for _ in 0..64 {
        let Some(hit) = scene.surfaces.intersect(&ray, f32::INFINITY) else { return NONE };
        if hit.prim.interface != NONE {
            let [inside, outside] = scene.interfaces[hit.prim.interface as usize];
            return if ray.d.dot(hit.surface.n) > 0.0 { inside } else { outside };
        }
        ray = hit.surface.spawn_ray(ray.d);
    }
    NONE
}

/// Traces `photon` for at most `max_depth` scattering events (in media and at surfaces), and
/// calls `deposit(medium, p, towards_light, power, refracted)` at each real scattering event
/// in a medium where a camera path could collect the light it brings: not while a photon from a
/// delta light has met only specular surfaces, since a camera path continuing towards such
/// light can never hit the light (next-event estimation takes that light, or nothing does),
/// and a guide that learned it would send paths where nothing can be found (a distant
/// light's direct beam made grid-cloud's guide a spike at the sun).
///
/// The photon is an analog random walk in one channel `c` of its wavelengths `lambda` (an RGB
/// channel chosen uniformly, or the first of four sampled wavelengths): its expected deposits
/// are those of the channels' mean, or of the light weighted by the visible-wavelength
/// density.
#[allow(clippy::too_many_arguments)]
pub fn trace<C: Channels>(
    scene: &Scene,
    photon: &Photon<C>,
    lambda: &mut C::Lambda,
    c: usize,
    max_depth: u32,
    rng: &mut Pcg32,
    mut deposit: impl FnMut(u32, Vec3, Vec3, f32, bool),
) {
    let mut power = photon.power[c];
    if power <= 0.0 {
        return;
    }
    let (mut ray, mut medium) = (photon.ray, photon.medium);
    let mut depth = 0u32;
    let mut collectable = !photon.delta;
    // Whether the photon has passed through a surface that transmits (a dielectric): light
    // that next-event estimation cannot bring, the light guiding is for.
    let mut refracted = false;
    loop {
        let hit = scene.surfaces.intersect(&ray, f32::INFINITY);
        if medium != NONE {
            let m = &scene.media[medium as usize];
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.surface.t);
            let (mut scattered, mut absorbed) = (None, false);
            let u = rng.uniform();
            sample_t_maj::<C, _>(m.into(), &ray, t_max, u, rng, c, lambda, |p, mp, sigma_maj, _, rng| {
                let um = rng.uniform() * sigma_maj[c];
                if um < mp.sigma_a[c] {
                    absorbed = true;
                    false
                } else if um < mp.sigma_a[c] + mp.sigma_s[c] {
                    scattered = Some(p);
                    false
                } else {
                    true
                }
            });
            if absorbed {
                return;
            }
            if let Some(p) = scattered {
                if depth >= max_depth {
                    return;
                }
                depth += 1;
                if collectable {
                    deposit(medium, p, -ray.d, power, refracted);
                }
                collectable = true;
                let phase = HenyeyGreenstein::new(m.g);
                let Some(ps) = phase.sample_p(-ray.d, Vec2::new(rng.uniform(), rng.uniform())) else {
                    return;
                };
                ray = Ray::new(p, ps.wi);
                continue;
            }
        }
        let Some(mut hit) = hit else { return };
        let (material, _) = scene.surface_material(&mut hit, -ray.d, None);
        let s = &hit.surface;
        // Light paths carry no camera footprint (pbrt-v4 has none there either).
        let tex_ctx =
            TexContext { face: scene.surfaces.shapes.face_index(hit.prim.geometry), ..TexContext::at(s.p, s.uv, s.n) };
        let Some(bxdf) = material.bxdf::<C>(&scene.textures, &tex_ctx, lambda) else {
            medium = medium_after(scene, &hit, ray.d, medium);
            ray = s.spawn_ray(ray.d);
            continue;
        };
        if depth >= max_depth {
            return;
        }
        depth += 1;
        let frame = shading_frame(&hit);
        let wo = frame.to_local(-ray.d);
        let uc = rng.uniform();
        let u = Vec2::new(rng.uniform(), rng.uniform());
        let Some(bs) = bxdf.sample_f(wo, uc, u, TransportMode::Importance, ReflTransFlags::ALL) else {
            return;
        };
        if bs.pdf <= 0.0 {
            return;
        }
        // The throughput of this bounce, played as Russian roulette where it is below one so
        // that photons keep comparable powers.
        let ratio = bs.f[c] * bs.wi.z.abs() / bs.pdf;
        if !(ratio > 0.0 && ratio.is_finite()) {
            return;
        }
        if ratio < 1.0 {
            if rng.uniform() >= ratio {
                return;
            }
        } else {
            power *= ratio;
        }
        collectable |= !bs.is_specular();
        refracted |= bs.is_transmission();
        let wi = frame.to_world(bs.wi);
        medium = medium_after(scene, &hit, wi, medium);
        ray = s.spawn_ray(wi);
    }
}
