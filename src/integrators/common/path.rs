//! The path loop of pbrt-v4's VolPathIntegrator (Pharr et al., PBR 4th ed., §14.2), written
//! once: emission with MIS, next-event estimation with MIS between light and BSDF sampling,
//! Russian roulette, `interface` surfaces skipped without counting a bounce. MIS uses pbrt-v4's
//! rescaled path probabilities: `r_u` (unidirectional, per channel) and `r_l` (light
//! sampling), with the balance heuristic over the two strategies.

use glam::Vec3;

use super::RayStats;
use super::observer::{EmissionEvent, NeeEvent, PathObserver, VertexEvent};
use crate::accel::{Hit, NONE};
use crate::color::{Rgb, average};
use crate::geometry::{Ray, spawn_ray, spawn_ray_to};
use crate::lights::LightContext;
use crate::materials::bxdf::{Bxdf, ReflTransFlags, TransportMode};
use crate::math::Frame;
use crate::samplers::Sampler;
use crate::scene::Scene;
use crate::textures::TexContext;

/// Parameters of the loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathConfig {
    /// Maximum number of scattering events.
    pub max_depth: u32,
    /// Roughen near-specular BSDFs after the first non-specular bounce.
    pub regularize: bool,
    /// Sample lights at vertices (next-event estimation with MIS). Without it, emission is
    /// only found by scattering: a simpler unbiased estimator that tests use to check MIS.
    pub next_event: bool,
}

/// The last scattering vertex, for MIS of emission found by the next ray.
#[derive(Clone, Copy, Debug)]
struct PrevVertex {
    p: Vec3,
}

/// Local shading frame at a surface hit.
#[inline]
fn shading_frame(hit: &Hit) -> Frame {
    let s = &hit.surface;
    if s.dpdu.length_squared() > 0.0 {
        Frame::from_z_x(s.ns, s.dpdu)
    } else {
        Frame::from_z(s.ns)
    }
}

/// Radiance arriving along `ray` (from the camera, in medium `medium`), estimated by one
/// path. `observer` sees every vertex, light sample and emission event.
pub fn trace_path<O: PathObserver>(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    config: &PathConfig,
    observer: &mut O,
    stats: &mut RayStats,
) -> Rgb {
    let mut l = Rgb::ZERO;
    let mut beta = Rgb::ONE;
    let r_u = Rgb::ONE;
    let mut r_l = Rgb::ONE;
    let mut specular_bounce = false;
    let mut any_non_specular = false;
    let mut eta_scale = 1.0f32;
    let mut depth = 0u32;
    let mut prev = PrevVertex { p: ray.o };

    loop {
        stats.bounce += 1;
        let Some(hit) = scene.surfaces.intersect(&ray, f32::INFINITY) else {
            // Escaped: environment emission.
            for &i in &scene.infinite_lights {
                let light = &scene.lights[i as usize];
                let le = light.le(ray.d);
                if le == Rgb::ZERO {
                    continue;
                }
                let c = if depth == 0 || specular_bounce || !config.next_event {
                    beta * le / average(r_u)
                } else {
                    let pdf = scene.light_sampler.pmf(i as usize)
                        * light.pdf_li(
                            &LightContext { p: prev.p },
                            ray.d,
                            None,
                            &scene.surfaces.shapes,
                        );
                    let r_l_light = r_l * pdf;
                    beta * le / average(r_u + r_l_light)
                };
                l += c;
                observer.on_emission(&EmissionEvent {
                    depth,
                    contribution: c,
                });
            }
            break;
        };
        let s = &hit.surface;
        let wo = -ray.d;

        // Emission from an area light that was hit.
        if hit.prim.area_light != NONE {
            let light = &scene.lights[hit.prim.area_light as usize];
            let le = light.emitted(s, wo);
            if le != Rgb::ZERO {
                let c = if depth == 0 || specular_bounce || !config.next_event {
                    beta * le / average(r_u)
                } else {
                    let pdf = scene.light_sampler.pmf(hit.prim.area_light as usize)
                        * light.pdf_li(
                            &LightContext { p: prev.p },
                            ray.d,
                            Some(s),
                            &scene.surfaces.shapes,
                        );
                    beta * le / average(r_u + r_l * pdf)
                };
                l += c;
                observer.on_emission(&EmissionEvent {
                    depth,
                    contribution: c,
                });
            }
        }

        let material = &scene.materials[hit.prim.material as usize];
        let tex_ctx = TexContext { p: s.p, uv: s.uv };
        let Some(mut bxdf) = material.bxdf(&scene.textures, &tex_ctx) else {
            // An interface: continue through it without counting a bounce.
            ray = spawn_ray(s.p, s.n, ray.d);
            continue;
        };
        if depth == config.max_depth {
            break;
        }
        depth += 1;
        if config.regularize && any_non_specular {
            bxdf.regularize();
        }
        let frame = shading_frame(&hit);
        let wo_local = frame.to_local(wo);
        let flags = bxdf.flags();

        // Next-event estimation.
        if config.next_event && flags.is_non_specular() {
            let u_pick = sampler.get_1d();
            let u_light = sampler.get_2d();
            if let Some(c) = sample_direct(
                scene,
                &hit,
                &frame,
                &bxdf,
                wo_local,
                u_pick,
                u_light,
                beta,
                r_u,
                depth - 1,
                observer,
                stats,
            ) {
                l += c;
            }
        }

        // Continue the path by sampling the BSDF.
        let uc = sampler.get_1d();
        let u = sampler.get_2d();
        let Some(bs) = bxdf.sample_f(
            wo_local,
            uc,
            u,
            TransportMode::Radiance,
            ReflTransFlags::ALL,
        ) else {
            break;
        };
        let wi = frame.to_world(bs.wi);
        let f_cos = bs.f * bs.wi.z.abs();
        observer.on_vertex(&VertexEvent {
            depth: depth - 1,
            p: s.p,
            n: s.ns,
            wo,
            wi,
            pdf: bs.pdf,
            f: f_cos,
            beta,
            specular: bs.is_specular(),
            in_medium: false,
        });
        beta *= f_cos / bs.pdf;
        r_l = if bs.pdf_is_proportional {
            r_u / bxdf.pdf(
                wo_local,
                bs.wi,
                TransportMode::Radiance,
                ReflTransFlags::ALL,
            )
        } else {
            r_u / bs.pdf
        };
        specular_bounce = bs.is_specular();
        any_non_specular |= !bs.is_specular();
        if bs.is_transmission() {
            eta_scale *= bs.eta * bs.eta;
        }
        prev = PrevVertex { p: s.p };
        ray = spawn_ray(s.p, s.n, wi);

        if beta == Rgb::ZERO || !beta.is_finite() {
            break;
        }
        // Russian roulette on the throughput with the radiance scaling of refraction undone.
        let rr_beta = beta * eta_scale / average(r_u);
        let rr_max = rr_beta.max_element();
        let u_rr = sampler.get_1d();
        if rr_max < 1.0 && depth > 1 {
            let q = (1.0 - rr_max).max(0.0);
            if u_rr < q {
                break;
            }
            beta /= 1.0 - q;
        }
    }
    l
}

/// One light sample at a surface vertex, MIS-weighted against BSDF sampling (pbrt-v4's
/// SampleLd). Shadow rays pass through `interface` surfaces.
#[allow(clippy::too_many_arguments)]
fn sample_direct<O: PathObserver>(
    scene: &Scene,
    hit: &Hit,
    frame: &Frame,
    bxdf: &Bxdf,
    wo_local: Vec3,
    u_pick: f32,
    u_light: glam::Vec2,
    beta: Rgb,
    r_p: Rgb,
    depth: u32,
    observer: &mut O,
    stats: &mut RayStats,
) -> Option<Rgb> {
    let s = &hit.surface;
    let (index, pmf) = scene.light_sampler.sample(u_pick)?;
    let light = &scene.lights[index];
    let ctx = LightContext { p: s.p };
    let ls = light.sample_li(&ctx, u_light, &scene.surfaces.shapes, &scene.sphere)?;
    if ls.pdf == 0.0 || ls.l == Rgb::ZERO {
        return None;
    }
    let wi_local = frame.to_local(ls.wi);
    let f = bxdf.f(wo_local, wi_local, TransportMode::Radiance) * wi_local.z.abs();
    if f == Rgb::ZERO {
        return None;
    }
    if !unoccluded(scene, s.p, s.n, &ls, stats) {
        return None;
    }
    let pdf_light = pmf * ls.pdf;
    let contribution = if ls.delta {
        beta * f * ls.l / average(r_p * pdf_light)
    } else {
        let pdf_scatter = bxdf.pdf(
            wo_local,
            wi_local,
            TransportMode::Radiance,
            ReflTransFlags::ALL,
        );
        beta * f * ls.l / average(r_p * pdf_light + r_p * pdf_scatter)
    };
    observer.on_nee(&NeeEvent {
        depth,
        p: s.p,
        wi: ls.wi,
        pdf_light,
        pdf_scatter: if ls.delta {
            0.0
        } else {
            bxdf.pdf(
                wo_local,
                wi_local,
                TransportMode::Radiance,
                ReflTransFlags::ALL,
            )
        },
        contribution,
    });
    Some(contribution)
}

/// Whether the light sample is visible from `p`: nothing but `interface` surfaces between.
fn unoccluded(
    scene: &Scene,
    p: Vec3,
    n: Vec3,
    ls: &crate::lights::LightSample,
    stats: &mut RayStats,
) -> bool {
    let (mut ray, mut t_max) = if ls.infinite {
        (spawn_ray(p, n, ls.wi), f32::INFINITY)
    } else if ls.n != Vec3::ZERO {
        // Area light: stop just short of the sampled point on the light itself.
        spawn_ray_to(p, n, ls.p)
    } else {
        let (r, d) = spawn_ray_to(p, n, ls.p);
        (r, d)
    };
    if !scene.has_interfaces {
        stats.shadow += 1;
        return !scene.surfaces.occluded(&ray, t_max);
    }
    loop {
        stats.shadow += 1;
        let Some(h) = scene.surfaces.intersect(&ray, t_max) else {
            return true;
        };
        if !scene.materials[h.prim.material as usize].is_interface() {
            return false;
        }
        let travelled = h.surface.t;
        ray = spawn_ray(h.surface.p, h.surface.n, ray.d);
        if t_max.is_finite() {
            t_max -= travelled;
            if t_max <= 0.0 {
                return true;
            }
        }
    }
}
