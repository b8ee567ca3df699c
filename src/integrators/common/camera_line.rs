//! The camera line, estimated beyond what the path's own camera segment does: its area
//! lights ([`super::PathConfig::camera_line`]: what delta tracking along the camera's
//! straight line adds at depth 0, estimated by ratio tracking whatever the segment's own
//! tracking does), and the direct light at more first collisions along it
//! ([`super::PathConfig::line_direct`]).

use glam::Vec2;

use super::RayStats;
use super::direct::{Scatterer, light_sample_alone};
use super::media::{Collision, Tracking, line_transmittance};
use super::path::medium_after;
use super::state::PathState;
use crate::accel::{Hit, NONE};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::media::MediumView;
use crate::media::phase::HenyeyGreenstein;
use crate::sampling::rng::{Pcg32, hash_sample};
use crate::scene::Scene;

/// The sum of `n` independent estimates of the direct light at the first collision along
/// `ray` through `medium` up to `t_max` (a stretch of the camera line, `(ray, t_max, medium)`),
/// each as the path's own camera segment would make it: a collision by delta tracking from the
/// path state `st` at the stretch's start (absorption, or no collision before `t_max`, gives
/// nothing; β and r_u take the same ratios as the path's in chromatic media), then one light
/// sample there by light sampling alone (unbiased without the phase technique), its shadow
/// ray on a stream of its own. `seed` (one sampler dimension) seeds every random number.
/// Also returns the estimates' sample variance (of their channels' mean; 0 for fewer than
/// two), from which a method can judge how many are worth taking.
pub(super) fn line_direct<C: Channels>(
    scene: &Scene,
    (ray, t_max, medium): (&Ray, f32, u32),
    st: &PathState<C>,
    n: u32,
    seed: f32,
    lambda: &C::Lambda,
    stats: &mut RayStats,
) -> (C, f32) {
    let m = &scene.media[medium as usize];
    let view = MediumView { medium: m, entered: st.entered };
    let scatterer = Scatterer::Medium { phase: HenyeyGreenstein::new(m.g), wo: -ray.d };
    let mut rng = Pcg32::new(hash_sample(seed, Vec2::new(0.75, 0.25)), 0x2545_f491_4f6c_dd1d);
    let (mut sum, mut squares) = (C::ZERO, 0.0f64);
    for _ in 0..n {
        let mut s = *st;
        let hero = s.hero;
        let mut at = None;
        let walk = Tracking { medium: view, ray, t_max, hero, lambda, residual: false };
        let u = rng.uniform();
        walk.run(u, &mut rng, |c: &Collision<C>, rng| {
            let (mp, sigma_maj, t_maj) = (&c.mp, c.sigma_maj, c.t_s);
            let um = rng.uniform();
            let p_absorb = mp.sigma_a[hero] / sigma_maj[hero];
            let p_scatter = mp.sigma_s[hero] / sigma_maj[hero];
            if um < p_absorb {
                false
            } else if um < p_absorb + p_scatter {
                s.scatter_collision(t_maj, mp.sigma_s, m.chromatic);
                at = Some(c.p);
                false
            } else {
                let sigma_n = (sigma_maj - mp.sigma_a - mp.sigma_s).max(C::ZERO);
                s.null_collision(t_maj, sigma_n, m.chromatic);
                !s.beta.is_zero() && !s.r_u.is_zero()
            }
        });
        let Some(p) = at else { continue };
        if s.beta.is_zero() || s.r_u.is_zero() {
            continue;
        }
        if let Some(c) = light_sample_alone(scene, p, None, medium, &scatterer, &s, lambda, &mut rng, stats) {
            sum += c;
            squares += f64::from(c.average()).powi(2);
        }
    }
    let spread = if n > 1 {
        let mean = f64::from(sum.average()) / f64::from(n);
        ((squares - f64::from(n) * mean * mean) / f64::from(n - 1)).max(0.0) as f32
    } else {
        0.0
    };
    (sum, spread)
}

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
