//! Next-event estimation at a path vertex: one light sample MIS-weighted against BSDF or
//! phase sampling (pbrt-v4's `SampleLd`, PBR 4th ed. §14.2.4), and the extra light samples
//! path graphs take at a pixel's first vertex.

use glam::{Vec2, Vec3};

use super::RayStats;
use super::media::ShadowEstimate;
use super::observer::{NeeEvent, NoObserver, PathObserver};
use super::path::{PathConfig, medium_after};
use super::shadow::transmittance;
use super::state::PathState;
use crate::accel::Hit;
use crate::channels::Channels;
use crate::lights::LightContext;
use crate::materials::bxdf::{Bxdf, ReflTransFlags, TransportMode};
use crate::math::Frame;
use crate::media::phase::HenyeyGreenstein;
use crate::samplers::Sampler;
use crate::sampling::rng::{Pcg32, hash_sample};
use crate::scene::Scene;
use crate::textures::TexContext;

/// What scatters at a vertex: a BSDF in a local frame, or a phase function.
pub(super) enum Scatterer<'a, C> {
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

/// The mean of `config.extra_direct` light samples at a vertex, by light sampling alone (so
/// each is unbiased without the BSDF/phase technique). Their random numbers come from a
/// generator seeded by one sampler dimension, so the count does not shift the sampler's
/// dimensions for the rest of the path.
#[allow(clippy::too_many_arguments)]
pub(super) fn extra_direct<C: Channels>(
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
        if let Some(c) = light_sample_alone(scene, p, hit, medium, scatterer, st, lambda, &mut rng, stats) {
            sum += c;
        }
    }
    sum / config.extra_direct as f32
}

/// The random numbers of a light sample: given (the extra samples draw theirs from a
/// generator), or drawn from the path's sampler as pbrt-v4 draws them (one dimension to pick
/// the light, two to sample it), a value the sample would not read skipped rather than
/// generated (one light to pick, a distant or point light to sample).
pub(super) enum LightRandoms<'s> {
    Given(f32, Vec2),
    Sampler(&'s mut Sampler),
}

/// One light sample at a vertex by light sampling alone (unbiased without the BSDF/phase
/// technique), its random numbers and its shadow ray's stream drawn from `rng`: the extra
/// samples' ([`extra_direct`], the camera line's extra first vertices).
#[allow(clippy::too_many_arguments)]
pub(super) fn light_sample_alone<C: Channels>(
    scene: &Scene,
    p: Vec3,
    hit: Option<&Hit>,
    medium: u32,
    scatterer: &Scatterer<'_, C>,
    st: &PathState<C>,
    lambda: &C::Lambda,
    rng: &mut Pcg32,
    stats: &mut RayStats,
) -> Option<C> {
    let u = (rng.uniform(), Vec2::new(rng.uniform(), rng.uniform()));
    let stream = (u64::from(rng.next_u32()) << 32 | u64::from(rng.next_u32())) | 1;
    let u = LightRandoms::Given(u.0, u.1);
    sample_direct(scene, p, hit, medium, scatterer, u, st, lambda, 0, &mut NoObserver, stats, Some(stream))
}

/// One light sample at a vertex at `p` (on the surface `hit`, or inside `medium` when there
/// is none): the path's own sample (`extra` None), MIS-weighted against BSDF/phase sampling
/// (pbrt-v4's SampleLd); or one of the extra samples (`Some(stream)`), by light sampling
/// alone, its shadow ray's random numbers drawn from the stream `stream` (pbrt-v4 seeds them
/// by the ray alone, so a delta light's extra samples would repeat one transmittance
/// estimate: their mean would be no better than one of them). The shadow ray crosses `interface` surfaces and
/// accumulates residual-ratio-tracking transmittance through media.
#[allow(clippy::too_many_arguments)]
pub(super) fn sample_direct<C: Channels, O: PathObserver<C>>(
    scene: &Scene,
    p: Vec3,
    hit: Option<&Hit>,
    medium: u32,
    scatterer: &Scatterer<'_, C>,
    randoms: LightRandoms<'_>,
    st: &PathState<C>,
    lambda: &C::Lambda,
    depth: u32,
    observer: &mut O,
    stats: &mut RayStats,
    extra: Option<u64>,
) -> Option<C> {
    let n_ctx = hit.map_or(Vec3::ZERO, |h| h.surface.ns);
    let (picked, u_light, u_shadow) = match randoms {
        LightRandoms::Given(u_pick, u_light) => (scene.light_sampler.sample(p, n_ctx, u_pick), u_light, None),
        LightRandoms::Sampler(sampler) => {
            let u_pick = if scene.light_sampler.reads_sample() {
                sampler.get_1d()
            } else {
                sampler.skip_1d();
                0.5
            };
            let picked = scene.light_sampler.sample(p, n_ctx, u_pick);
            let u_light = if picked.is_some_and(|(i, _)| scene.lights[i].reads_sample()) {
                sampler.get_2d()
            } else {
                sampler.skip_2d();
                Vec2::splat(0.5)
            };
            // The shadow ray's first tentative collision, stratified as the path's are. A
            // scene without tracked media keeps pbrt-v4's dimensions: there the value would
            // go unused, and the extra dimension cost many-lights (homogeneous fog, 70
            // lights) 8 % of its MSE over 18 seeds.
            let u_shadow = scene.has_tracked_media.then(|| sampler.get_1d_shifted());
            (picked, u_light, u_shadow)
        }
    };
    let (index, pmf) = picked?;
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
    // In the path's medium the ray sees the coefficients the path took in; entering another
    // here, those of this point.
    let entered = match hit {
        Some(h) if shadow_medium != medium => {
            let s = &h.surface;
            let ctx = TexContext {
                face: scene.surfaces.shapes.face_index(h.prim.geometry),
                ..TexContext::at(s.p, s.uv, s.n)
            };
            scene.entered_at(shadow_medium, &ctx, lambda)
        }
        _ => st.entered,
    };
    let ShadowEstimate { t_ray, r_u, r_l } = transmittance(
        scene,
        p,
        n,
        (shadow_medium, entered),
        &ls,
        (st.hero, st.time, extra.unwrap_or(0), u_shadow),
        lambda,
        stats,
    )?;
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
    let contribution = if ls.delta || extra.is_some() {
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
