//! The camera line's area lights ([`super::PathConfig::camera_line`]): what delta tracking
//! along the camera's straight line adds at depth 0, estimated by ratio tracking whatever the
//! segment's own tracking does.

use super::RayStats;
use super::media::line_transmittance;
use super::path::medium_after;
use crate::accel::{Hit, NONE};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::sampling::rng::Pcg32;
use crate::scene::Scene;

/// The area-light emission along the straight line `ray` (starting in `medium`, first hitting
/// `hit`): lights hit through `interface` surfaces and the one opaque surface it ends at,
/// each times the transmittance up to it ([`line_transmittance`]),
/// which is the expectation of what delta tracking along the line adds at depth 0
/// ([`PathConfig::camera_line`]). The estimate is the same for every channel's sampling
/// technique, so `weight`, the path's β/mean(r_u), weighs it as any depth-0 emission.
pub(super) fn line_emission<C: Channels>(
    scene: &Scene,
    mut ray: Ray,
    mut hit: Option<Hit>,
    mut medium: u32,
    weight: C,
    lambda: &C::Lambda,
    stats: &mut RayStats,
) -> C {
    // Most lines reach no light: find out by intersections alone before tracking anything.
    let (mut probe, mut next) = (ray, hit);
    loop {
        let Some(h) = next else { return C::ZERO };
        if h.prim.area_light != NONE {
            break;
        }
        if !scene.materials[h.prim.material as usize].is_interface() {
            return C::ZERO;
        }
        probe = h.spawn_ray(probe.d);
        stats.shadow += 1;
        next = scene.surfaces.intersect(&probe, f32::INFINITY);
    }
    // Its own stream: the camera segment's delta tracking keeps its random numbers.
    let mut rng = Pcg32::new(
        crate::sampling::rng::hash_vec3(ray.o) ^ 0x5851_f42d_4c95_7f2d,
        crate::sampling::rng::hash_vec3(ray.d),
    );
    let mut weight = weight;
    let mut sum = C::ZERO;
    loop {
        if medium != NONE {
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.surface.t);
            weight *= line_transmittance::<C>(&scene.media[medium as usize], &ray, t_max, &mut rng, lambda);
            if weight.is_zero() {
                return sum;
            }
        }
        let Some(h) = hit else { return sum };
        if h.prim.area_light != NONE {
            sum += weight
                * scene.lights[h.prim.area_light as usize].emitted::<C>(&h.surface, -ray.d, lambda, &scene.surfaces);
        }
        if !scene.materials[h.prim.material as usize].is_interface() {
            return sum;
        }
        medium = medium_after(scene, &h, ray.d, medium);
        ray = h.spawn_ray(ray.d);
        stats.shadow += 1;
        hit = scene.surfaces.intersect(&ray, f32::INFINITY);
    }
}
