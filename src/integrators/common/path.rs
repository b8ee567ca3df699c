//! The path loop of pbrt-v4's VolPathIntegrator (Pharr et al., PBR 4th ed., §14.2), written
//! once: delta tracking through media with majorant grids, emission with MIS, next-event
//! estimation with MIS between light and BSDF/phase sampling and residual-ratio-tracked
//! shadow rays, Russian roulette, `interface` surfaces crossed without counting a bounce. MIS uses
//! pbrt-v4's rescaled path probabilities: `r_u` (unidirectional) and `r_l` (light sampling)
//! per channel, with the balance heuristic; in chromatic media the channels are pbrt-v4's
//! wavelengths, one of them (`hero`, chosen per path, or per segment for path graphs)
//! driving distance sampling.

use glam::Vec3;

use super::camera_line::{line_direct, line_emission};
use super::direct::{LightRandoms, Scatterer, extra_direct, sample_direct};
use super::media::{Collision, Tracking};
use super::observer::{EmissionEvent, PathObserver, VertexEvent};
use super::state::{PathState, end_segment, rr};
use super::{MAX_SUBSURFACE_EVENTS, RayStats};
use crate::accel::{Found, Hit, NONE};
use crate::camera::Differentials;
use crate::channels::Channels;
use crate::geometry::Ray;
use crate::lights::LightContext;
use crate::materials::bxdf::{Bxdf, ReflTransFlags, TransportMode};
use crate::math::Frame;
use crate::media::MediumView;
use crate::media::phase::HenyeyGreenstein;
use crate::samplers::Sampler;
use crate::sampling::rng::Pcg32;
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
    /// Extra light samples (light sampling alone, no MIS) at the first vertex that samples
    /// lights, reported to the observer and not added to the path's estimate: path graphs
    /// use them for the pixel's direct light (Hu et al. 2024, Sec. 4). 0 for every per-ray
    /// method.
    pub extra_direct: u32,
    /// Extra first vertices along the camera line: on each stretch of the camera ray through
    /// a medium, this many more collisions are sampled by delta tracking (each from its own
    /// random numbers, up to the stretch's end) and each takes one light sample (light
    /// sampling alone), reported to the observer and not added to the path's estimate. With
    /// the path's own first vertex they are `line_direct + 1` independent estimates of the
    /// direct light at the camera ray's first collision there: path graphs take their mean
    /// for the pixel's non-aggregated direct light, which back-lit and rim-lit media are
    /// mostly made of. 0 for every per-ray method.
    pub line_direct: u32,
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
            line_direct: 0,
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

/// One copy of a path between events: where it goes, what it carries, and what the next
/// events need to know of the vertices before.
struct Walk<C: Channels> {
    ray: Ray,
    medium: u32,
    st: PathState<C>,
    /// Scattering vertices so far.
    depth: u32,
    /// Those of them inside `subsurface` media, which stand for pbrt-v4's BSSRDF: one event
    /// that its entry vertex already counted. `depth - free` is what `maxdepth` bounds.
    free: u32,
    /// The last vertex scattered perfectly specularly: emission found next is not weighed
    /// against light sampling.
    specular_bounce: bool,
    /// Some vertex so far scattered non-specularly (regularisation starts after it).
    any_non_specular: bool,
    /// Refraction's radiance scaling, undone for Russian roulette.
    eta_scale: f32,
    /// The previous scattering vertex and its shading normal (zero in media): the light
    /// sampler's context there, which MIS needs again when a light is hit.
    prev_p: Vec3,
    prev_n: Vec3,
    /// The extra light samples ([`PathConfig::extra_direct`]) were taken.
    extra_done: bool,
    /// The camera line's area lights have been estimated (`PathConfig::camera_line`): the
    /// area lights the path reaches at depth 0 are then already counted.
    line_done: bool,
    /// The ray's differentials while it has them (pbrt-v4's `RayDifferential`): the camera
    /// ray's, found at its first surface (`camera_diff` until then; crossing an `interface`
    /// keeps them), then reflected or refracted ones after perfectly specular bounces;
    /// textures filter over the footprint they give.
    camera_diff: bool,
    diff: Option<Differentials>,
}

/// A path copy left waiting after splitting at a medium vertex
/// ([`super::PathStrategy::split_medium`]): the walk after that vertex, continuing along
/// `ray`.
#[derive(Clone, Copy)]
struct Branch<C: Channels> {
    ray: Ray,
    medium: u32,
    st: PathState<C>,
    depth: u32,
    free: u32,
    prev_p: Vec3,
    eta_scale: f32,
    extra_done: bool,
    line_done: bool,
}

impl<C: Channels> Walk<C> {
    /// A copy taken up where it was left: after a non-specular medium vertex, without
    /// differentials.
    fn resume(b: Branch<C>) -> Walk<C> {
        Walk {
            ray: b.ray,
            medium: b.medium,
            st: b.st,
            depth: b.depth,
            free: b.free,
            specular_bounce: false,
            any_non_specular: true,
            eta_scale: b.eta_scale,
            prev_p: b.prev_p,
            prev_n: Vec3::ZERO,
            extra_done: b.extra_done,
            line_done: b.line_done,
            camera_diff: false,
            diff: None,
        }
    }
}

/// Most path copies waiting at once; splitting makes fewer copies when it is full.
const MAX_PENDING: usize = 16;

/// How delta tracking through the current medium ended.
enum Tracked {
    /// Absorbed, or the path's weight vanished.
    Ended,
    /// Real scattering at this point.
    Scattered(Vec3),
    /// The segment's end (a surface, or infinity) was reached.
    Reached,
}

/// The loop's context: what every event reads (scene, parameters, wavelengths) and adds to
/// (the sampler's dimensions, the observer, the estimate, the waiting copies).
struct Tracer<'a, C: Channels, O> {
    scene: &'a Scene,
    config: &'a PathConfig,
    lambda: &'a mut C::Lambda,
    sampler: &'a mut Sampler,
    observer: &'a mut O,
    stats: &'a mut RayStats,
    /// A new hero channel at every vertex ([`PathConfig::hero_per_segment`] in chromatic media).
    per_segment: bool,
    camera_ray: Ray,
    /// After the last scattering event `maxdepth` allows, nothing can add to the path: no
    /// light is found by hitting or escaping (no area or infinite light), medium emission
    /// counts only before that event (pbrt-v4's `depth < maxDepth`), no subsurface medium
    /// scatters without counting, and the observer records no vertices. The path then ends
    /// after that event's light sample; its continuation would be traced for nothing.
    /// Every pixel is unchanged: the continuation's random numbers are drawn after all
    /// that the path adds.
    end_at_last_event: bool,
    /// The estimate so far.
    l: C,
    pending: [Option<Branch<C>>; MAX_PENDING],
    n_pending: usize,
}

/// Radiance arriving along `ray` (from the camera, in medium `medium`) at the wavelengths
/// `lambda` (which a dispersive surface may cut down to the first), estimated by one path in
/// the channels `C`. `observer` sees every vertex, light sample and emission event.
#[allow(clippy::too_many_arguments)]
pub fn trace_path<C: Channels, O: PathObserver<C>>(
    scene: &Scene,
    ray: Ray,
    medium: u32,
    lambda: &mut C::Lambda,
    sampler: &mut Sampler,
    config: &PathConfig,
    observer: &mut O,
    stats: &mut RayStats,
) -> C {
    // Chromatic media need a randomly chosen hero channel for spectral MIS.
    let hero = if scene.has_chromatic_media { C::hero_channel(sampler.get_1d()) } else { 0 };
    let mut walk = Walk {
        ray,
        medium,
        st: PathState { beta: C::ONE, r_u: C::ONE, r_l: C::ONE, hero, rr_scale: 1.0, time: ray.time, entered: None },
        depth: 0,
        free: 0,
        specular_bounce: false,
        any_non_specular: false,
        eta_scale: 1.0,
        prev_p: ray.o,
        prev_n: Vec3::ZERO,
        extra_done: false,
        line_done: false,
        camera_diff: scene.footprint.is_some(),
        diff: None,
    };
    let end_at_last_event = !observer.records_vertices() && !scene.continues_past_max_depth;
    let mut tracer = Tracer {
        scene,
        config,
        lambda,
        sampler,
        observer,
        stats,
        per_segment: config.hero_per_segment && scene.has_chromatic_media,
        end_at_last_event,
        camera_ray: ray,
        l: C::ZERO,
        pending: [None; MAX_PENDING],
        n_pending: 0,
    };
    loop {
        tracer.follow(&mut walk);
        // This copy of the path ended: take up the next waiting one.
        if tracer.n_pending == 0 {
            break;
        }
        tracer.n_pending -= 1;
        walk = Walk::resume(tracer.pending[tracer.n_pending].take().expect("pending path"));
    }
    tracer.l
}

impl<C: Channels, O: PathObserver<C>> Tracer<'_, C, O> {
    /// Follows one copy of the path, event by event, until it ends: the segment to the next
    /// surface (and the camera line's lights), delta tracking through its medium (scattering
    /// there, or reaching the surface), escaping to the environment, or a surface's emission
    /// and scattering.
    #[inline]
    fn follow(&mut self, w: &mut Walk<C>) {
        loop {
            self.stats.bounce += 1;
            let found = self.scene.surfaces.find(&w.ray, f32::INFINITY);
            self.camera_line(w, found.as_ref());
            // Area lights on the camera line (depth 0) once it has been estimated.
            let line_counted = w.line_done && w.depth == 0;
            if w.medium != NONE {
                let t_max = found.map_or(f32::INFINITY, |f| f.t());
                let line = self.line_direct(w, t_max);
                let tracked = self.track_medium(w, t_max);
                if let Some((sum, spread)) = line {
                    let own = matches!(tracked, Tracked::Scattered(_));
                    self.observer.on_line_direct(sum, spread, self.config.line_direct, own);
                }
                match tracked {
                    Tracked::Ended => return,
                    Tracked::Scattered(p) if self.scatter_in_medium(w, p) => continue,
                    Tracked::Scattered(_) => return,
                    Tracked::Reached => {}
                }
            }
            let Some(hit) = found.map(|f| self.scene.surfaces.resolve(&f)) else {
                self.escape(w);
                return;
            };
            if !line_counted {
                self.surface_emission(w, &hit);
            }
            if !self.scatter_at_surface(w, hit) {
                return;
            }
        }
    }

    /// The camera line's area lights, once, on the camera segment through a medium
    /// ([`PathConfig::camera_line`]).
    #[inline]
    fn camera_line(&mut self, w: &mut Walk<C>, found: Option<&Found>) {
        if self.config.camera_line && w.depth == 0 && w.medium != NONE && !w.line_done {
            w.line_done = true;
            let hit = found.map(|f| self.scene.surfaces.resolve(f));
            let weight = w.st.beta / w.st.r_u.average();
            let c = line_emission(self.scene, w.ray, hit, w.medium, weight, self.lambda, self.stats);
            if !c.is_zero() {
                self.l += c;
                self.observer.on_emission(&EmissionEvent { depth: w.depth, contribution: c, pdf_light: 0.0 });
            }
        }
    }

    /// The extra first vertices' light samples on the camera line's stretch through the
    /// walk's medium up to `t_max` ([`PathConfig::line_direct`]): their sum and sample
    /// variance, or None where none are taken (past the first vertex, in `subsurface` media,
    /// which stand for a BSSRDF).
    #[inline]
    fn line_direct(&mut self, w: &Walk<C>, t_max: f32) -> Option<(C, f32)> {
        let (scene, config) = (self.scene, self.config);
        if config.line_direct == 0 || w.depth != 0 || config.max_depth == 0 {
            return None;
        }
        let m = &scene.media[w.medium as usize];
        if m.subsurface {
            return None;
        }
        // One sampler dimension seeds them all, so their count does not shift the path's own.
        let seed = self.sampler.get_1d();
        let stretch = (&w.ray, t_max, w.medium);
        Some(line_direct(scene, stretch, &w.st, config.line_direct, seed, self.lambda, self.stats))
    }

    /// Delta tracking through the current medium up to the surface at `t_max` (or infinity),
    /// adding the medium's emission on the way (PBR 4th ed. §14.2.2).
    #[inline]
    fn track_medium(&mut self, w: &mut Walk<C>, t_max: f32) -> Tracked {
        let config = self.config;
        let m = &self.scene.media[w.medium as usize];
        let view = MediumView { medium: m, entered: w.st.entered };
        let hero = w.st.hero;
        // pbrt-v4 spends three dimensions here: two hashed into the walk's random stream, one
        // for the first tentative collision's distance. This walk seeds its stream from one
        // and takes the first collision's optical depth and its event choice (absorption,
        // scattering, null) from a 2D sample (the choice's coordinate moved per pixel:
        // `Sampler::get_2d_shifted_y`), so both are stratified over the pixel's samples
        // (graph-cloud at 64 spp: MSE −8 % from the pair alone, −18 % with the optical depth
        // carried across majorant segments, the choice reused past null collisions and the
        // shadow rays' first collisions, all from the sampler; same expectation).
        let seed = self.sampler.stream_seed();
        let mut rng = Pcg32::new(seed, seed ^ 0x9e37_79b9_7f4a_7c15);
        let uv = self.sampler.get_2d_shifted_y();
        let (u, mut u_event) = (uv.x, Some(uv.y));
        let mut event_scale = 1.0f32;
        let (mut scattered, mut terminated) = (false, false);
        let mut scatter_p = Vec3::ZERO;
        let (st, depth, free, l, observer) = (&mut w.st, &mut w.depth, &mut w.free, &mut self.l, &mut *self.observer);
        // The light technique samples null vertices as residual ratio tracking does
        // (`media::ratio_tracking`): σr e^(−∫σr), σr = σmaj − σc, e^(−∫σr) = T_maj e^(∫σc); the
        // e^(∫σc) is applied once, where the walk reaches its end (`r_l` is read only there).
        let mut tau_l = C::ZERO;
        let walk = Tracking { medium: view, ray: &w.ray, t_max, hero, lambda: self.lambda, residual: false };
        let tail = walk.run(u, &mut rng, |c: &Collision<C>, rng| {
            let (p, mp, sigma_maj, t_maj) = (c.p, &c.mp, c.sigma_maj, c.t_s);
            if st.beta.is_zero() {
                terminated = true;
                return false;
            }
            // Medium emission, weighted by the chance of having reached it.
            if *depth - *free < config.max_depth && !mp.le.is_zero() {
                let pdf = sigma_maj[hero] * t_maj[hero];
                let betap = st.beta * t_maj / pdf;
                let r_e = st.r_u * sigma_maj * t_maj / pdf;
                if !r_e.is_zero() {
                    let c = betap * mp.sigma_a * mp.le / r_e.average();
                    *l += c;
                    observer.on_emission(&EmissionEvent { depth: *depth, contribution: c, pdf_light: 0.0 });
                }
            }
            // Choose absorption, real scattering or null scattering with the hero channel's
            // probabilities.
            let p_absorb = mp.sigma_a[hero] / sigma_maj[hero];
            let p_scatter = mp.sigma_s[hero] / sigma_maj[hero];
            let from_sampler = u_event.is_some();
            let um = u_event.take().unwrap_or_else(|| rng.uniform());
            if um < p_absorb {
                terminated = true;
                false
            } else if um < p_absorb + p_scatter {
                if m.subsurface {
                    if *free >= MAX_SUBSURFACE_EVENTS {
                        terminated = true;
                        return false;
                    }
                    *free += 1;
                } else if *depth - *free >= config.max_depth {
                    terminated = true;
                    return false;
                }
                *depth += 1;
                st.scatter_collision(t_maj, mp.sigma_s, m.chromatic);
                scattered = true;
                scatter_p = p;
                false
            } else {
                // Given a null collision, where `um` fell in its share is uniform again and
                // independent of all else: the next collision's choice reuses it, so choices
                // along a segment stay stratified as the sampler stratifies them, for as long
                // as the rescaled value keeps 16 of its 24 bits.
                let p_null = 1.0 - p_absorb - p_scatter;
                if from_sampler && event_scale * p_null >= 1.0 / 256.0 {
                    event_scale *= p_null;
                    u_event = Some(((um - p_absorb - p_scatter) / p_null).clamp(0.0, 1.0 - f32::EPSILON));
                }
                let sigma_n = (sigma_maj - mp.sigma_a - mp.sigma_s).max(C::ZERO);
                let sigma_r = (sigma_maj - c.sigma_c).max(C::ZERO);
                tau_l += c.tau_c;
                let pdf = st.null_collision(t_maj, sigma_n, m.chromatic);
                // The light technique's r_l takes the residual σr (above).
                if pdf != 0.0 {
                    if m.chromatic {
                        st.r_l *= t_maj * sigma_r / pdf;
                    } else {
                        st.r_l *= sigma_r[hero] / sigma_n[hero];
                    }
                }
                !st.beta.is_zero() && !st.r_u.is_zero()
            }
        });
        let t_maj = tail.t_s;
        if terminated || w.st.beta.is_zero() || w.st.r_u.is_zero() {
            return Tracked::Ended;
        }
        if scattered {
            return Tracked::Scattered(scatter_p);
        }
        if m.chromatic {
            let h = t_maj[hero];
            w.st.beta *= t_maj / h;
            w.st.r_u *= t_maj / h;
            w.st.r_l *= t_maj / h;
        }
        tau_l += tail.tau_c;
        if !tau_l.is_zero() {
            // A path gets here with probability ≤ e^(−∫σc) (σc ≤ σt): the cap only keeps it finite.
            w.st.r_l *= tau_l.map(|t| t.min(80.0).exp());
        }
        Tracked::Reached
    }

    /// Next-event estimation at the vertex at `p` (on the surface `hit`, else in the walk's
    /// medium), divided by `prob`, the chance it was taken; then the extra light samples
    /// ([`PathConfig::extra_direct`]) at the first vertex that samples lights.
    #[inline]
    fn next_event(&mut self, w: &mut Walk<C>, p: Vec3, hit: Option<&Hit>, sc: &Scatterer<'_, C>, prob: f32) {
        let (scene, config, medium) = (self.scene, self.config, w.medium);
        let u = LightRandoms::Sampler(&mut *self.sampler);
        let (st, depth) = (&w.st, w.depth - 1);
        if let Some(c) =
            sample_direct(scene, p, hit, medium, sc, u, st, self.lambda, depth, self.observer, self.stats, None)
        {
            self.l += if prob < 1.0 { c / prob } else { c };
        }
        if config.extra_direct > 0 && !w.extra_done {
            w.extra_done = true;
            let c = extra_direct(scene, p, hit, medium, sc, st, self.lambda, config, self.sampler, self.stats);
            self.observer.on_extra_direct(depth, c);
        }
    }

    /// Real scattering in a medium at `p`: next-event estimation, then the phase function (or
    /// the observer's guide) picks the continuation, split into several copies where the
    /// observer asks. False when no copy continues.
    #[inline]
    fn scatter_in_medium(&mut self, w: &mut Walk<C>, p: Vec3) -> bool {
        let (scene, config, medium) = (self.scene, self.config, w.medium);
        let m = &scene.media[medium as usize];
        (w.camera_diff, w.diff) = (false, None);
        if self.per_segment {
            end_segment(&mut w.st, self.sampler);
        }
        let wo = -w.ray.d;
        // A cached estimate ends the path here (radiance graphs).
        if self.observer.ends_in_medium(w.depth) {
            let u = self.sampler.get_1d();
            let v = self.observer.medium_estimate::<C>(medium, p, wo, self.lambda, u);
            if !v.is_zero() {
                let c = w.st.beta * v / w.st.r_u.average();
                self.l += c;
                self.observer.on_emission(&EmissionEvent { depth: w.depth, contribution: c, pdf_light: 0.0 });
            }
            return false;
        }
        let phase = HenyeyGreenstein::new(m.g);
        // Next-event estimation as Russian roulette where the observer expects it to find
        // nothing (its probability divides what it finds).
        let nee_prob = if self.observer.guides() { self.observer.nee_medium_probability(medium, p) } else { 1.0 };
        if config.next_event && (nee_prob >= 1.0 || self.sampler.get_1d() < nee_prob) {
            self.next_event(w, p, None, &Scatterer::Medium { phase, wo }, nee_prob);
        }
        if self.end_at_last_event && w.depth - w.free >= config.max_depth {
            return false;
        }
        // Splitting where the observer guides and asks for it: the path continues in several
        // independent directions, each with its share of β (roulette's test below sees β as
        // it was before the split).
        let mut copies = 1u32;
        if self.observer.guides() {
            let beta = (w.st.beta / w.st.r_u.average()).average();
            let n = self.observer.split_medium(medium, p, beta);
            copies = n.clamp(1, (MAX_PENDING - self.n_pending) as u32 + 1);
            if copies > 1 {
                w.st.beta /= copies as f32;
                w.st.rr_scale *= copies as f32;
            }
        }
        let at_vertex = w.st;
        let mut next: Option<(Ray, PathState<C>)> = None;
        for _ in 0..copies {
            let mut st = at_vertex;
            // The continuation: (direction, phase value, β's factor, MIS density), from the
            // guide when the observer guides here, else from the phase function.
            let guided = if self.observer.guides() {
                let u = self.sampler.get_1d();
                self.observer.guide_medium(medium, p, wo, &phase, u).map(|gs| (gs, phase.p(wo, gs.wi)))
            } else {
                None
            };
            let (wi, f, factor, pdf) = match guided {
                Some((gs, f)) => {
                    // The phase function's own sampling has factor p/pdf = 1.
                    st.rr_scale = (st.rr_scale / gs.weight).clamp(1e-20, 1e20);
                    (gs.wi, f, gs.weight, gs.pdf)
                }
                None => {
                    let u = self.sampler.get_2d();
                    let Some(ps) = phase.sample_p(wo, u) else {
                        continue;
                    };
                    (ps.wi, ps.p, ps.p / ps.pdf, ps.pdf)
                }
            };
            if pdf == 0.0 || factor == 0.0 || !factor.is_finite() {
                continue;
            }
            self.observer.on_vertex(&VertexEvent {
                depth: w.depth - 1,
                p,
                n: Vec3::ZERO,
                wo,
                wi,
                pdf,
                f: C::splat(f),
                beta: st.beta,
                specular: false,
                in_medium: true,
                g: m.g,
                lambertian: false,
            });
            st.beta *= factor;
            st.r_l = st.r_u / pdf;
            let out = Ray::timed(p, wi, st.time);
            if rr(&mut st, w.eta_scale, w.depth, self.sampler) {
                continue;
            }
            if next.is_none() {
                next = Some((out, st));
            } else {
                self.pending[self.n_pending] = Some(Branch {
                    ray: out,
                    medium,
                    st,
                    depth: w.depth,
                    free: w.free,
                    prev_p: p,
                    eta_scale: w.eta_scale,
                    extra_done: w.extra_done,
                    line_done: w.line_done,
                });
                self.n_pending += 1;
            }
        }
        let Some((out, st)) = next else { return false };
        (w.ray, w.st) = (out, st);
        (w.prev_p, w.prev_n) = (p, Vec3::ZERO);
        (w.specular_bounce, w.any_non_specular) = (false, true);
        true
    }

    /// The path escaped: the environment's emission, MIS-weighted against light sampling
    /// where the previous vertex sampled lights.
    #[inline]
    fn escape(&mut self, w: &Walk<C>) {
        let scene = self.scene;
        for &i in &scene.infinite_lights {
            let light = &scene.lights[i as usize];
            let le = light.le::<C>(w.ray.o, w.ray.d, self.lambda);
            if le.is_zero() {
                continue;
            }
            let st = &w.st;
            let (c, pdf_light) = if w.depth == 0 || w.specular_bounce || !self.config.next_event {
                (st.beta * le / st.r_u.average(), 0.0)
            } else {
                let pdf = scene.light_sampler.pmf(w.prev_p, w.prev_n, i as usize)
                    * light.pdf_li(&LightContext { p: w.prev_p }, w.ray.d, None, &scene.surfaces.shapes);
                (st.beta * le / (st.r_u + st.r_l * pdf).average(), pdf)
            };
            self.l += c;
            self.observer.on_emission(&EmissionEvent { depth: w.depth, contribution: c, pdf_light });
        }
    }

    /// Emission from an area light the path hit, MIS-weighted as [`Self::escape`]'s.
    #[inline]
    fn surface_emission(&mut self, w: &Walk<C>, hit: &Hit) {
        if hit.prim.area_light == NONE {
            return;
        }
        let scene = self.scene;
        let (s, st) = (&hit.surface, &w.st);
        let light = &scene.lights[hit.prim.area_light as usize];
        let le = light.emitted::<C>(s, -w.ray.d, self.lambda, &scene.surfaces);
        if le.is_zero() {
            return;
        }
        let (c, pdf_light) = if w.depth == 0 || w.specular_bounce || !self.config.next_event {
            (st.beta * le / st.r_u.average(), 0.0)
        } else {
            let pdf = scene.light_sampler.pmf(w.prev_p, w.prev_n, hit.prim.area_light as usize)
                * light.pdf_li(&LightContext { p: w.prev_p }, w.ray.d, Some(s), &scene.surfaces.shapes);
            (st.beta * le / (st.r_u + st.r_l * pdf).average(), pdf)
        };
        self.l += c;
        self.observer.on_emission(&EmissionEvent { depth: w.depth, contribution: c, pdf_light });
    }

    /// The walk goes on in `medium` from the surface point `ctx`: a medium that takes its
    /// coefficients from where the path enters it gets them here.
    #[inline]
    fn enter(&mut self, w: &mut Walk<C>, medium: u32, ctx: &TexContext) {
        if medium != w.medium {
            w.medium = medium;
            w.st.entered = self.scene.entered_at(medium, ctx, self.lambda);
        }
    }

    /// At a surface: an `interface` is crossed without counting a bounce; otherwise
    /// next-event estimation, then the BSDF samples the continuation and Russian roulette
    /// may end the path. False when the path ends.
    #[inline]
    fn scatter_at_surface(&mut self, w: &mut Walk<C>, mut hit: Hit) -> bool {
        let (scene, config) = (self.scene, self.config);
        let wo = -w.ray.d;
        if w.camera_diff {
            w.camera_diff = false;
            w.diff = scene.footprint.as_ref().and_then(|f| f.camera_differentials(&scene.camera, &self.camera_ray));
        }
        let (material, tex_ctx) = scene.surface_material(&mut hit, wo, w.diff.as_ref());
        let Some(mut bxdf) = material.bxdf::<C>(&scene.textures, &tex_ctx, self.lambda) else {
            // An interface: cross it without counting a bounce.
            self.enter(w, medium_after(scene, &hit, w.ray.d, w.medium), &tex_ctx);
            w.ray = hit.spawn_ray(w.ray.d);
            return true;
        };
        // Inside a subsurface medium the boundary's scattering is part of the BSSRDF's one
        // event (pbrt-v4 samples the exit point's BSDF without counting it).
        let inside = w.medium != NONE && scene.media[w.medium as usize].subsurface;
        if inside {
            if w.free >= MAX_SUBSURFACE_EVENTS {
                return false;
            }
            w.free += 1;
        } else if w.depth - w.free == config.max_depth {
            return false;
        }
        w.depth += 1;
        if self.per_segment {
            end_segment(&mut w.st, self.sampler);
        }
        if config.regularize && w.any_non_specular {
            bxdf.regularize();
        }
        let s = &hit.surface;
        let frame = shading_frame(&hit);
        let wo_local = frame.to_local(wo);

        // Next-event estimation.
        if config.next_event && bxdf.flags().is_non_specular() {
            self.next_event(w, s.p, Some(&hit), &Scatterer::Surface { bxdf: &bxdf, frame: &frame, wo_local }, 1.0);
        }
        if self.end_at_last_event && w.depth - w.free >= config.max_depth {
            return false;
        }

        // Continue the path by sampling the BSDF (a BxDF of one lobe has no lobe to choose:
        // its dimension is skipped).
        let uc = if bxdf.reads_uc() {
            self.sampler.get_1d()
        } else {
            self.sampler.skip_1d();
            0.5
        };
        let u = self.sampler.get_2d();
        let Some(bs) = bxdf.sample_f(wo_local, uc, u, TransportMode::Radiance, ReflTransFlags::ALL) else {
            return false;
        };
        let wi = frame.to_world(bs.wi);
        let f_cos = bs.f * bs.wi.z.abs();
        self.observer.on_vertex(&VertexEvent {
            depth: w.depth - 1,
            p: s.p,
            n: s.ns,
            wo,
            wi,
            pdf: bs.pdf,
            f: f_cos,
            beta: w.st.beta,
            specular: bs.is_specular(),
            in_medium: false,
            g: 0.0,
            lambertian: matches!(bxdf, Bxdf::Diffuse(_)),
        });
        w.st.beta *= f_cos / bs.pdf;
        w.st.r_l = if bs.pdf_is_proportional {
            w.st.r_u / bxdf.pdf(wo_local, bs.wi, TransportMode::Radiance, ReflTransFlags::ALL)
        } else {
            w.st.r_u / bs.pdf
        };
        w.diff = match w.diff.take() {
            Some(d) if bs.is_specular() => {
                scene.specular_differentials(&hit, &tex_ctx, &d, wo, wi, bs.is_transmission(), bs.eta)
            }
            _ => None,
        };
        w.specular_bounce = bs.is_specular();
        w.any_non_specular |= !bs.is_specular();
        if bs.is_transmission() {
            w.eta_scale *= bs.eta * bs.eta;
        }
        (w.prev_p, w.prev_n) = (s.p, s.ns);
        self.enter(w, medium_after(scene, &hit, wi, w.medium), &tex_ctx);
        w.ray = hit.spawn_ray(wi);
        !rr(&mut w.st, w.eta_scale, w.depth, self.sampler)
    }
}
