//! The shadow ray of next-event estimation: opaque surfaces block it, `interface` surfaces
//! let it through into the medium beyond, and media attenuate it by residual ratio tracking
//! with pbrt-v4's rescaled probabilities.

use glam::Vec3;

use super::RayStats;
use super::media::{ShadowEstimate, ratio_tracking};
use super::path::medium_after;
use crate::accel::NONE;
use crate::channels::Channels;
use crate::geometry::{Ray, offset_origin_by};
use crate::lights::LightSample;
use crate::media::{MediumPoint, MediumView};
use crate::sampling::rng::Pcg32;
use crate::scene::Scene;

/// Transmittance from `p` to the light sample, with the rescaled probabilities of the
/// segments through media, or `None` when something opaque is in the way.
/// (`#[inline]`: it was private to the path loop's module, where the compiler could inline
/// it; it stays inlinable across codegen units.)
#[inline]
#[allow(clippy::too_many_arguments)]
pub(super) fn transmittance<C: Channels>(
    scene: &Scene,
    p: Vec3,
    (n, p_error): (Vec3, f32),
    (mut medium, entered): (u32, Option<MediumPoint<C>>),
    ls: &LightSample<C>,
    (hero, time, stream, mut first_u): (usize, f32, u64, Option<f32>),
    lambda: &C::Lambda,
    stats: &mut RayStats,
) -> Option<ShadowEstimate<C>> {
    let mut est = ShadowEstimate::default();
    let origin = if n == Vec3::ZERO { p } else { offset_origin_by(p, n, ls.wi, p_error) };
    let mut ray = Ray::timed(origin, ls.wi, time);
    // Distance left to the light point; the light's own surface is not an occluder.
    let mut remaining = if ls.infinite { f32::INFINITY } else { (ls.p - origin).length() * (1.0 - 1e-4) };
    if medium == NONE && !scene.has_interfaces {
        stats.shadow += 1;
        return (!scene.surfaces.occluded(&ray, remaining)).then_some(est);
    }
    // pbrt-v4 seeds the tracking by the ray (stream 0); other streams decorrelate repeated
    // samples along one ray.
    let mut rng = Pcg32::new(crate::sampling::rng::hash_vec3(ray.o) ^ stream, crate::sampling::rng::hash_vec3(ray.d));
    let mut first = true;
    loop {
        stats.shadow += 1;
        // The hit's geometry is computed only if the ray gets through the medium to it.
        let found = scene.surfaces.find(&ray, remaining);
        if let Some(f) = &found
            && !scene.materials[f.prim().material as usize].is_interface()
        {
            return None;
        }
        if medium != NONE {
            let t_max = found.as_ref().map_or(remaining, |f| f.t());
            let m = &scene.media[medium as usize];
            // Only the first medium can take its coefficients from an entry point: such a
            // medium's boundary is its subsurface material's dielectric, never an interface.
            let entered = if first { entered } else { None };
            if m.from_entry && entered.is_none() {
                return None;
            }
            let view = MediumView { medium: m, entered };
            ratio_tracking(first_u.take(), view, &ray, t_max, &mut rng, hero, lambda, &mut est);
            if est.t_ray.is_zero() {
                return None;
            }
        }
        let Some(h) = found.map(|f| scene.surfaces.resolve(&f)) else { return Some(est) };
        first = false;
        medium = medium_after(scene, &h, ray.d, medium);
        let travelled = h.surface.t;
        ray = h.spawn_ray(ray.d);
        remaining -= travelled;
        if remaining <= 0.0 {
            return Some(est);
        }
    }
}
