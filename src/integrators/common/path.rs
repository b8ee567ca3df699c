//! The path loop of pbrt-v4's VolPathIntegrator (Pharr et al., PBR 4th ed., §14.2), written
//! once: delta tracking through media with majorant grids, emission with MIS, next-event
//! estimation with MIS between light and BSDF/phase sampling and ratio-tracking shadow rays,
//! Russian roulette, `interface` surfaces crossed without counting a bounce. MIS uses
//! pbrt-v4's rescaled path probabilities: `r_u` (unidirectional) and `r_l` (light sampling)
//! per channel, with the balance heuristic; in chromatic media the channels are pbrt-v4's
//! wavelengths, one of them (`hero`, chosen per path, or per segment for path graphs)
//! driving distance sampling.

use glam::{Vec2, Vec3};

use super::RayStats;
use super::media::{ShadowEstimate, line_transmittance, sample_t_maj};
use super::observer::{EmissionEvent, NeeEvent, NoObserver, PathObserver, VertexEvent};
use super::shadow::transmittance;
use crate::accel::{Hit, NONE};
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::lights::LightContext;
use crate::materials::bxdf::{Bxdf, ReflTransFlags, TransportMode};
use crate::math::Frame;
use crate::media::phase::HenyeyGreenstein;
use crate::samplers::Sampler;
use crate::sampling::rng::{Pcg32, hash_sample};
use crate::scene::Scene;

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
    /// Extra light samples (light sampling alone, no MIS) at the first vertex that samples
    /// lights, reported to the observer and not added to the path's estimate: path graphs
    /// use them for the pixel's direct light (Hu et al. 2024, Sec. 4). 0 for every per-ray
    /// method.
    pub extra_direct: u32,
    /// In chromatic media, draw the hero wavelength anew at every scattering vertex and apply
    /// the spectral MIS over the hero choice per segment (β and r_u divided by the mean of r_u
    /// there) instead of over the whole path: unbiased as well, and it makes every segment's
    /// factor unbiased on its own, which path graphs need when they splice one path's suffix
    /// onto another's prefix. pbrt-v4's volpath keeps one hero per path.
    pub hero_per_segment: bool,
    /// Estimate the area lights seen along the camera's straight line through media (through
    /// `interface` surfaces up to the first opaque one) as Le times the transmittance, added
    /// whatever the camera segment's delta tracking does, instead of adding Le only when
    /// delta tracking happens to reach the light (probability T). With S the radiance the
    /// path brings back when it scatters before the light (mean s̄), the pixel's variance
    /// falls by Le T (1 − T) (Le − 2 s̄) for an exact T: a gain wherever the light is brighter
    /// than twice what the medium scatters towards the camera, which holds for area lights
    /// (a medium scatters a fraction of a light's radiance, at most about half of it for a
    /// light filling a hemisphere) and fails for an environment seen through a bright
    /// medium (which scatters about as much as the sky sends), so escaping paths keep
    /// pbrt-v4's estimate. Path graphs use it (their pixels take first-segment emission
    /// unaggregated); pbrt-v4's volpath does not.
    pub camera_line: bool,
}

impl PathConfig {
    /// pbrt-v4's volpath loop: next-event estimation, no extra samples.
    pub fn volpath(max_depth: u32, regularize: bool) -> PathConfig {
        PathConfig {
            max_depth,
            regularize,
            next_event: true,
            extra_direct: 0,
            hero_per_segment: false,
            camera_line: false,
        }
    }
}

/// Local shading frame at a surface hit.
#[inline]
pub fn shading_frame(hit: &Hit) -> Frame {
    let s = &hit.surface;
    if s.dpdu.length_squared() > 0.0 { Frame::from_z_x(s.ns, s.dpdu) } else { Frame::from_z(s.ns) }
}

/// The medium on the side of a surface that `w` points into.
#[inline]
pub fn medium_after(scene: &Scene, hit: &Hit, w: Vec3, current: u32) -> u32 {
    if hit.prim.interface == NONE {
        return current;
    }
    let [inside, outside] = scene.interfaces[hit.prim.interface as usize];
    if w.dot(hit.surface.n) > 0.0 { outside } else { inside }
}

/// What scatters at a vertex: a BSDF in a local frame, or a phase function.
enum Scatterer<'a, C> {
    Surface { bxdf: &'a Bxdf<C>, frame: &'a Frame, wo_local: Vec3 },
    Medium { phase: HenyeyGreenstein, wo: Vec3 },
}

impl<C: Channels> Scatterer<'_, C> {
    /// f·|cos| (or p) and the sampling density for direction `wi`.
    #[inline]
    fn eval(&self, wi: Vec3) -> (C, f32) {
        match self {
            Scatterer::Surface { bxdf, frame, wo_local } => {
                let wl = frame.to_local(wi);
                let f = bxdf.f(*wo_local, wl, TransportMode::Radiance) * wl.z.abs();
                if f.is_zero() {
                    return (f, 0.0);
                }
                (f, bxdf.pdf(*wo_local, wl, TransportMode::Radiance, ReflTransFlags::ALL))
            }
            Scatterer::Medium { phase, wo } => {
                let p = phase.p(*wo, wi);
                (C::splat(p), phase.pdf(*wo, wi))
            }
        }
    }
}

/// Per-path state shared by the loop and its helpers.
#[derive(Clone, Copy)]
struct PathState<C: Channels> {
    beta: C,
    r_u: C,
    r_l: C,
    hero: usize,
    /// What Russian roulette multiplies β by: the inverse of the factors path guiding put
    /// into β. Roulette on a guided path's β would kill the paths guiding sent towards the
    /// light (their factor is small because the guide's density there is high) and undo the
    /// guiding; on β·scale it survives as an unguided path would. 1 on unguided paths.
    rr_scale: f32,
    /// The path's time (its camera ray's): every ray of the path sees moving shapes there.
    time: f32,
}

/// A path copy left waiting after splitting at a medium vertex
/// ([`super::PathStrategy::split_medium`]): the loop's state after that vertex, continuing along
/// `ray`.
#[derive(Clone, Copy)]
struct Branch<C: Channels> {
    ray: Ray,
    medium: u32,
    st: PathState<C>,
    depth: u32,
    prev_p: Vec3,
    eta_scale: f32,
    extra_done: bool,
    line_done: bool,
}

/// Most path copies waiting at once; splitting makes fewer copies when it is full.
const MAX_PENDING: usize = 16;

/// Radiance arriving along `ray` (from the camera, in medium `medium`) at the wavelengths
/// `lambda` (which a dispersive surface may cut down to the first), estimated by one path in
/// the channels `C`. `observer` sees every vertex, light sample and emission event.
#[allow(clippy::too_many_arguments)]
pub fn trace_path<C: Channels, O: PathObserver<C>>(
    scene: &Scene,
    mut ray: Ray,
    mut medium: u32,
    lambda: &mut C::Lambda,
    sampler: &mut Sampler,
    config: &PathConfig,
    observer: &mut O,
    stats: &mut RayStats,
) -> C {
    let mut l = C::ZERO;
    // Chromatic media need a randomly chosen hero channel for spectral MIS.
    let hero = if scene.has_chromatic_media { C::hero_channel(sampler.get_1d()) } else { 0 };
    let per_segment = config.hero_per_segment && scene.has_chromatic_media;
    let mut st = PathState { beta: C::ONE, r_u: C::ONE, r_l: C::ONE, hero, rr_scale: 1.0, time: ray.time };
    let mut specular_bounce = false;
    let mut any_non_specular = false;
    let mut eta_scale = 1.0f32;
    let mut depth = 0u32;
    // The previous scattering vertex and its shading normal (zero in media): the light
    // sampler's context there, which MIS needs again when a light is hit.
    let mut prev_p = ray.o;
    let mut prev_n = Vec3::ZERO;
    let mut extra_done = false;
    // The camera line's area lights have been estimated (`PathConfig::camera_line`): the
    // area lights the path reaches at depth 0 are then already counted.
    let mut line_done = false;
    // The ray's differentials while it has them (pbrt-v4's `RayDifferential`): the camera
    // ray's, found at its first surface (from the camera ray: crossing an `interface` keeps
    // them), then reflected or refracted ones after perfectly specular bounces; textures
    // filter over the footprint they give.
    let camera_ray = ray;
    let mut camera_diff = scene.footprint.is_some();
    let mut diff = None;

    let mut pending = [None::<Branch<C>>; MAX_PENDING];
    let mut n_pending = 0usize;
    'paths: loop {
        'bounce: loop {
            stats.bounce += 1;
            // The hero of this segment (one per path unless `hero_per_segment`).
            let hero = st.hero;
            let hit = scene.surfaces.intersect(&ray, f32::INFINITY);
            if config.camera_line && depth == 0 && medium != NONE && !line_done {
                line_done = true;
                let c = line_emission(scene, ray, hit, medium, &st, lambda, stats);
                if !c.is_zero() {
                    l += c;
                    observer.on_emission(&EmissionEvent { depth, contribution: c, pdf_light: 0.0 });
                }
            }
            // Area lights on the camera line (depth 0) once it has been estimated.
            let line_counted = line_done && depth == 0;

            // Delta tracking through the current medium up to the surface.
            if medium != NONE {
                let m = &scene.media[medium as usize];
                let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.surface.t);
                let mut rng =
                    Pcg32::new(hash_sample(sampler.get_1d(), Vec2::ZERO), hash_sample(sampler.get_1d(), Vec2::ONE));
                let u = sampler.get_1d();
                let (mut scattered, mut terminated) = (false, false);
                let mut scatter_p = Vec3::ZERO;
                let t_maj =
                    sample_t_maj::<C, _>(m, &ray, t_max, u, &mut rng, hero, lambda, |p, mp, sigma_maj, t_maj, rng| {
                        if st.beta.is_zero() {
                            terminated = true;
                            return false;
                        }
                        // Medium emission, weighted by the chance of having reached it.
                        if depth < config.max_depth && !mp.le.is_zero() {
                            let pdf = sigma_maj[hero] * t_maj[hero];
                            let betap = st.beta * t_maj / pdf;
                            let r_e = st.r_u * sigma_maj * t_maj / pdf;
                            if !r_e.is_zero() {
                                let c = betap * mp.sigma_a * mp.le / r_e.average();
                                l += c;
                                observer.on_emission(&EmissionEvent { depth, contribution: c, pdf_light: 0.0 });
                            }
                        }
                        // Choose absorption, real scattering or null scattering with the hero
                        // channel's probabilities.
                        let p_absorb = mp.sigma_a[hero] / sigma_maj[hero];
                        let p_scatter = mp.sigma_s[hero] / sigma_maj[hero];
                        let um = rng.uniform();
                        if um < p_absorb {
                            terminated = true;
                            false
                        } else if um < p_absorb + p_scatter {
                            if depth >= config.max_depth {
                                terminated = true;
                                return false;
                            }
                            depth += 1;
                            // In a gray medium these ratios are 1: only chromatic media pay for
                            // spectral MIS.
                            if m.chromatic {
                                let pdf = t_maj[hero] * mp.sigma_s[hero];
                                st.beta *= t_maj * mp.sigma_s / pdf;
                                st.r_u *= t_maj * mp.sigma_s / pdf;
                            }
                            scattered = true;
                            scatter_p = p;
                            false
                        } else {
                            let sigma_n = (sigma_maj - mp.sigma_a - mp.sigma_s).max(C::ZERO);
                            let pdf = t_maj[hero] * sigma_n[hero];
                            if pdf == 0.0 {
                                st.beta = C::ZERO;
                            } else if m.chromatic {
                                st.beta *= t_maj * sigma_n / pdf;
                                st.r_u *= t_maj * sigma_n / pdf;
                                st.r_l *= t_maj * sigma_maj / pdf;
                            } else {
                                st.r_l *= sigma_maj[hero] / sigma_n[hero];
                            }
                            !st.beta.is_zero() && !st.r_u.is_zero()
                        }
                    });
                if terminated || st.beta.is_zero() || st.r_u.is_zero() {
                    break 'bounce;
                }
                if scattered {
                    (camera_diff, diff) = (false, None);
                    if per_segment {
                        end_segment(&mut st, sampler);
                    }
                    // Real scattering: next-event estimation, then sample the phase function.
                    let phase = HenyeyGreenstein::new(m.g);
                    let wo = -ray.d;
                    // Next-event estimation as Russian roulette where the observer expects it to
                    // find nothing (its probability divides what it finds).
                    let nee_prob =
                        if observer.guides() { observer.nee_medium_probability(medium, scatter_p) } else { 1.0 };
                    if config.next_event && (nee_prob >= 1.0 || sampler.get_1d() < nee_prob) {
                        let u_pick = sampler.get_1d();
                        let u_light = sampler.get_2d();
                        let sc = Scatterer::Medium { phase, wo };
                        if let Some(c) = sample_direct(
                            scene,
                            scatter_p,
                            None,
                            medium,
                            &sc,
                            (u_pick, u_light),
                            &st,
                            lambda,
                            depth - 1,
                            observer,
                            stats,
                            true,
                        ) {
                            l += if nee_prob < 1.0 { c / nee_prob } else { c };
                        }
                        if config.extra_direct > 0 && !extra_done {
                            extra_done = true;
                            let c =
                                extra_direct(scene, scatter_p, None, medium, &sc, &st, lambda, config, sampler, stats);
                            observer.on_extra_direct(depth - 1, c);
                        }
                    }
                    // Splitting where the observer guides and asks for it: the path continues in
                    // several independent directions, each with its share of β (roulette's test
                    // below sees β as it was before the split).
                    let mut copies = 1u32;
                    if observer.guides() {
                        let beta = (st.beta / st.r_u.average()).average();
                        let n = observer.split_medium(medium, scatter_p, beta);
                        copies = n.clamp(1, (MAX_PENDING - n_pending) as u32 + 1);
                        if copies > 1 {
                            st.beta /= copies as f32;
                            st.rr_scale *= copies as f32;
                        }
                    }
                    let at_vertex = st;
                    let mut next: Option<(Ray, PathState<C>)> = None;
                    for _ in 0..copies {
                        let mut st = at_vertex;
                        // The continuation: (direction, phase value, β's factor, MIS density),
                        // from the guide when the observer guides here, else from the phase
                        // function.
                        let guided = if observer.guides() {
                            let u = sampler.get_1d();
                            observer.guide_medium(medium, scatter_p, wo, &phase, u).map(|gs| (gs, phase.p(wo, gs.wi)))
                        } else {
                            None
                        };
                        let (wi, p, factor, pdf) = match guided {
                            Some((gs, p)) => {
                                // The phase function's own sampling has factor p/pdf = 1.
                                st.rr_scale = (st.rr_scale / gs.weight).clamp(1e-20, 1e20);
                                (gs.wi, p, gs.weight, gs.pdf)
                            }
                            None => {
                                let u = sampler.get_2d();
                                let Some(ps) = phase.sample_p(wo, u) else {
                                    continue;
                                };
                                (ps.wi, ps.p, ps.p / ps.pdf, ps.pdf)
                            }
                        };
                        if pdf == 0.0 || factor == 0.0 || !factor.is_finite() {
                            continue;
                        }
                        observer.on_vertex(&VertexEvent {
                            depth: depth - 1,
                            p: scatter_p,
                            n: Vec3::ZERO,
                            wo,
                            wi,
                            pdf,
                            f: C::splat(p),
                            beta: st.beta,
                            specular: false,
                            in_medium: true,
                            g: m.g,
                            lambertian: false,
                        });
                        st.beta *= factor;
                        st.r_l = st.r_u / pdf;
                        let out = Ray::timed(scatter_p, wi, st.time);
                        if rr(&mut st, eta_scale, depth, sampler) {
                            continue;
                        }
                        if next.is_none() {
                            next = Some((out, st));
                        } else {
                            pending[n_pending] = Some(Branch {
                                ray: out,
                                medium,
                                st,
                                depth,
                                prev_p: scatter_p,
                                eta_scale,
                                extra_done,
                                line_done,
                            });
                            n_pending += 1;
                        }
                    }
                    let Some((out, st_next)) = next else { break 'bounce };
                    (ray, st) = (out, st_next);
                    prev_p = scatter_p;
                    prev_n = Vec3::ZERO;
                    specular_bounce = false;
                    any_non_specular = true;
                    continue;
                }
                if m.chromatic {
                    let h = t_maj[hero];
                    st.beta *= t_maj / h;
                    st.r_u *= t_maj / h;
                    st.r_l *= t_maj / h;
                }
            }

            let Some(mut hit) = hit else {
                // Escaped: environment emission.
                for &i in &scene.infinite_lights {
                    let light = &scene.lights[i as usize];
                    let le = light.le::<C>(ray.o, ray.d, lambda);
                    if le.is_zero() {
                        continue;
                    }
                    let (c, pdf_light) = if depth == 0 || specular_bounce || !config.next_event {
                        (st.beta * le / st.r_u.average(), 0.0)
                    } else {
                        let pdf = scene.light_sampler.pmf(prev_p, prev_n, i as usize)
                            * light.pdf_li(&LightContext { p: prev_p }, ray.d, None, &scene.surfaces.shapes);
                        (st.beta * le / (st.r_u + st.r_l * pdf).average(), pdf)
                    };
                    l += c;
                    observer.on_emission(&EmissionEvent { depth, contribution: c, pdf_light });
                }
                break;
            };
            let s = &hit.surface;
            let wo = -ray.d;

            // Emission from an area light that was hit.
            if hit.prim.area_light != NONE && !line_counted {
                let light = &scene.lights[hit.prim.area_light as usize];
                let le = light.emitted::<C>(s, wo, lambda, &scene.surfaces);
                if !le.is_zero() {
                    let (c, pdf_light) = if depth == 0 || specular_bounce || !config.next_event {
                        (st.beta * le / st.r_u.average(), 0.0)
                    } else {
                        let pdf = scene.light_sampler.pmf(prev_p, prev_n, hit.prim.area_light as usize)
                            * light.pdf_li(&LightContext { p: prev_p }, ray.d, Some(s), &scene.surfaces.shapes);
                        (st.beta * le / (st.r_u + st.r_l * pdf).average(), pdf)
                    };
                    l += c;
                    observer.on_emission(&EmissionEvent { depth, contribution: c, pdf_light });
                }
            }

            if camera_diff {
                camera_diff = false;
                diff = scene.footprint.as_ref().and_then(|f| f.camera_differentials(&scene.camera, &camera_ray));
            }
            let (material, tex_ctx) = scene.surface_material(&mut hit, wo, diff.as_ref());
            let s = &hit.surface;
            let Some(mut bxdf) = material.bxdf::<C>(&scene.textures, &tex_ctx, lambda) else {
                // An interface: cross it without counting a bounce.
                medium = medium_after(scene, &hit, ray.d, medium);
                ray = hit.spawn_ray(ray.d);
                continue;
            };
            if depth == config.max_depth {
                break;
            }
            depth += 1;
            if per_segment {
                end_segment(&mut st, sampler);
            }
            if config.regularize && any_non_specular {
                bxdf.regularize();
            }
            let frame = shading_frame(&hit);
            let wo_local = frame.to_local(wo);

            // Next-event estimation.
            if config.next_event && bxdf.flags().is_non_specular() {
                let u_pick = sampler.get_1d();
                let u_light = sampler.get_2d();
                let sc = Scatterer::Surface { bxdf: &bxdf, frame: &frame, wo_local };
                if let Some(c) = sample_direct(
                    scene,
                    s.p,
                    Some(&hit),
                    medium,
                    &sc,
                    (u_pick, u_light),
                    &st,
                    lambda,
                    depth - 1,
                    observer,
                    stats,
                    true,
                ) {
                    l += c;
                }
                if config.extra_direct > 0 && !extra_done {
                    extra_done = true;
                    let c = extra_direct(scene, s.p, Some(&hit), medium, &sc, &st, lambda, config, sampler, stats);
                    observer.on_extra_direct(depth - 1, c);
                }
            }

            // Continue the path by sampling the BSDF.
            let uc = sampler.get_1d();
            let u = sampler.get_2d();
            let Some(bs) = bxdf.sample_f(wo_local, uc, u, TransportMode::Radiance, ReflTransFlags::ALL) else {
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
                beta: st.beta,
                specular: bs.is_specular(),
                in_medium: false,
                g: 0.0,
                lambertian: matches!(bxdf, Bxdf::Diffuse(_)),
            });
            st.beta *= f_cos / bs.pdf;
            st.r_l = if bs.pdf_is_proportional {
                st.r_u / bxdf.pdf(wo_local, bs.wi, TransportMode::Radiance, ReflTransFlags::ALL)
            } else {
                st.r_u / bs.pdf
            };
            diff = match diff {
                Some(d) if bs.is_specular() => {
                    scene.specular_differentials(&hit, &tex_ctx, &d, wo, wi, bs.is_transmission(), bs.eta)
                }
                _ => None,
            };
            specular_bounce = bs.is_specular();
            any_non_specular |= !bs.is_specular();
            if bs.is_transmission() {
                eta_scale *= bs.eta * bs.eta;
            }
            prev_p = s.p;
            prev_n = s.ns;
            medium = medium_after(scene, &hit, wi, medium);
            ray = hit.spawn_ray(wi);
            if rr(&mut st, eta_scale, depth, sampler) {
                break;
            }
        }
        // This copy of the path ended: take up the next waiting one.
        if n_pending == 0 {
            break 'paths;
        }
        n_pending -= 1;
        let b = pending[n_pending].take().expect("pending path");
        (ray, medium, st, depth, prev_p, eta_scale, extra_done, line_done) =
            (b.ray, b.medium, b.st, b.depth, b.prev_p, b.eta_scale, b.extra_done, b.line_done);
        (prev_n, specular_bounce, any_non_specular, camera_diff, diff) = (Vec3::ZERO, false, true, false, None);
    }
    l
}

/// The area-light emission along the straight line `ray` (starting in `medium`, first hitting
/// `hit`): lights hit through `interface` surfaces and the one opaque surface it ends at,
/// each times the transmittance up to it ([`line_transmittance`]),
/// which is the expectation of what delta tracking along the line adds at depth 0
/// ([`PathConfig::camera_line`]). The estimate is the same for every channel's sampling
/// technique, so β/mean(r_u) weighs it as any depth-0 emission.
fn line_emission<C: Channels>(
    scene: &Scene,
    mut ray: Ray,
    mut hit: Option<Hit>,
    mut medium: u32,
    st: &PathState<C>,
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
    let mut weight = st.beta / st.r_u.average();
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

/// Ends a segment of a path in chromatic media ([`PathConfig::hero_per_segment`]): the spectral
/// MIS over the segment's hero choice (the balance heuristic, f / mean of the channels'
/// densities = β / mean of r_u), then a new hero for the next segment.
#[inline]
fn end_segment<C: Channels>(st: &mut PathState<C>, sampler: &mut Sampler) {
    let a = st.r_u.average();
    if a > 0.0 {
        st.beta /= a;
    }
    // The segment's densities are accounted for: the next one starts its own ratios, with a
    // hero drawn uniformly among the channels (the path's wavelengths are fixed by now, so
    // the next segment's one-sample MIS needs its own uniform choice; for the first segment
    // pbrt's random first wavelength is that choice).
    st.r_u = C::ONE;
    st.hero = ((sampler.get_1d() * C::CHANNELS as f32) as usize).min(C::CHANNELS - 1);
}

/// Russian roulette on the throughput with refraction's radiance scaling undone; true
/// when the path ends.
#[inline]
fn rr<C: Channels>(st: &mut PathState<C>, eta_scale: f32, depth: u32, sampler: &mut Sampler) -> bool {
    if st.beta.is_zero() || !st.beta.is_finite() {
        return true;
    }
    let rr_beta = st.beta * (eta_scale * st.rr_scale) / st.r_u.average();
    let rr_max = rr_beta.max_element();
    let u_rr = sampler.get_1d();
    if rr_max < 1.0 && depth > 1 {
        let q = (1.0 - rr_max).max(0.0);
        if u_rr < q {
            return true;
        }
        st.beta /= 1.0 - q;
    }
    false
}

/// The mean of `config.extra_direct` light samples at a vertex, by light sampling alone (so
/// each is unbiased without the BSDF/phase technique). Their random numbers come from a
/// generator seeded by one sampler dimension, so the count does not shift the sampler's
/// dimensions for the rest of the path.
#[allow(clippy::too_many_arguments)]
fn extra_direct<C: Channels>(
    scene: &Scene,
    p: Vec3,
    hit: Option<&Hit>,
    medium: u32,
    scatterer: &Scatterer<'_, C>,
    st: &PathState<C>,
    lambda: &C::Lambda,
    config: &PathConfig,
    sampler: &mut Sampler,
    stats: &mut RayStats,
) -> C {
    let mut rng = Pcg32::new(hash_sample(sampler.get_1d(), Vec2::new(0.25, 0.75)), 0x9e37_79b9);
    let mut sum = C::ZERO;
    for _ in 0..config.extra_direct {
        let u = (rng.uniform(), Vec2::new(rng.uniform(), rng.uniform()));
        if let Some(c) =
            sample_direct(scene, p, hit, medium, scatterer, u, st, lambda, 0, &mut NoObserver, stats, false)
        {
            sum += c;
        }
    }
    sum / config.extra_direct as f32
}

/// One light sample at a vertex at `p` (on the surface `hit`, or inside `medium` when there
/// is none), MIS-weighted against BSDF/phase sampling when `mis` (pbrt-v4's SampleLd), by
/// light sampling alone otherwise. The shadow ray crosses `interface` surfaces and
/// accumulates ratio-tracking transmittance through media.
#[allow(clippy::too_many_arguments)]
fn sample_direct<C: Channels, O: PathObserver<C>>(
    scene: &Scene,
    p: Vec3,
    hit: Option<&Hit>,
    medium: u32,
    scatterer: &Scatterer<'_, C>,
    (u_pick, u_light): (f32, Vec2),
    st: &PathState<C>,
    lambda: &C::Lambda,
    depth: u32,
    observer: &mut O,
    stats: &mut RayStats,
    mis: bool,
) -> Option<C> {
    let n_ctx = hit.map_or(Vec3::ZERO, |h| h.surface.ns);
    let (index, pmf) = scene.light_sampler.sample(p, n_ctx, u_pick)?;
    let light = &scene.lights[index];
    let ls = light.sample_li::<C>(&LightContext { p }, u_light, &scene.surfaces, &scene.sphere, lambda)?;
    if ls.pdf == 0.0 || ls.l.is_zero() {
        return None;
    }
    let (f, pdf_scatter) = scatterer.eval(ls.wi);
    if f.is_zero() {
        return None;
    }
    // A shadow ray leaving a surface starts in the medium on the side it leaves towards.
    let (n, shadow_medium) = match hit {
        Some(h) => ((h.surface.n, h.surface.p_error), medium_after(scene, h, ls.wi, medium)),
        None => ((Vec3::ZERO, 0.0), medium),
    };
    let ShadowEstimate { t_ray, r_u, r_l } =
        transmittance(scene, p, n, shadow_medium, &ls, (st.hero, st.time), lambda, stats)?;
    // Where the path is guided, the scattering technique MIS weighs against is the guide's
    // (looked up only for unoccluded samples: inside a dielectric most are blocked).
    let pdf_scatter = match scatterer {
        Scatterer::Medium { phase, wo } if hit.is_none() && observer.guides() => {
            observer.guide_medium_pdf(medium, p, *wo, phase, ls.wi).unwrap_or(pdf_scatter)
        }
        _ => pdf_scatter,
    };
    let pdf_light = pmf * ls.pdf;
    let r_l = r_l * st.r_u * pdf_light;
    let r_u = r_u * st.r_u * pdf_scatter;
    let contribution = if ls.delta || !mis {
        st.beta * f * t_ray * ls.l / r_l.average()
    } else {
        st.beta * f * t_ray * ls.l / (r_l + r_u).average()
    };
    observer.on_nee(&NeeEvent {
        depth,
        p,
        wi: ls.wi,
        pdf_light,
        pdf_scatter: if ls.delta { 0.0 } else { pdf_scatter },
        contribution,
    });
    Some(contribution)
}
