//! pbrt-v4's `gbuffer` film: beside the image, each pixel's first visible surface — its
//! albedo, position, geometric and shading normals, uv and the camera-space depth
//! derivatives — and the variance of its samples, as the EXR channels pbrt-v4 writes
//! (`Albedo.R`, `P.X`, `dzdx`, `N.X`, `Ns.X`, `u`, `Variance.R`, `RelativeVariance.R`, ...).
//!
//! pbrt-v4 records the visible surface when a camera path's first real event is a surface
//! (after crossing `interface` boundaries), so in a medium a pixel's G-buffer averages the
//! samples that got through. nimbus computes the same average in expectation, without its
//! noise: every camera sample is traced again to its first surface and weighted by the
//! media's transmittance along the way (ratio tracking), the probability that pbrt-v4's path
//! would have reached it. The pass replays each pixel's camera samples (same sampler
//! dimensions, hence the same rays and filter weights) after the render, so it serves every
//! integrator, per-ray or whole-image.

use glam::{Affine3A, DVec2, DVec3, UVec2, Vec2, Vec3};
use rayon::prelude::*;

use super::{Accumulator, camera_sample};
use crate::accel::NONE;
use crate::channels::Channels;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::integrators::common::media::{ShadowEstimate, ratio_tracking};
use crate::integrators::common::path::{medium_after, shading_frame};
use crate::materials::bxdf::{ReflTransFlags, TransportMode};
use crate::media::MediumKind;
use crate::samplers::Sampler;
use crate::sampling::rng::{Pcg32, hash_vec3};
use crate::scene::Scene;

/// What a camera sample sees first, in the film's output space.
#[derive(Clone, Copy, Debug)]
struct VisibleSurface {
    p: Vec3,
    n: Vec3,
    ns: Vec3,
    uv: Vec2,
    dzdx: f32,
    dzdy: f32,
    albedo: Rgb,
}

/// A pixel's sums: Σw over all samples (pbrt-v4 divides the albedo by it), Σw·T over those
/// that see a surface (T their transmittance) and the T-weighted attribute sums.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    weight: f64,
    surface_weight: f64,
    albedo: DVec3,
    p: DVec3,
    n: DVec3,
    ns: DVec3,
    uv: DVec2,
    dz: DVec2,
}

/// Number of BSDF samples in the albedo estimate (as pbrt-v4's `rho` at the first hit).
const RHO_SAMPLES: usize = 16;

/// The albedo estimate's fixed samples: a (0,2)-sequence over [0,1)² (van der Corput ×
/// Sobol' dimension 1) for directions and a rotated lattice for the lobe choice.
fn rho_samples() -> [(f32, Vec2); RHO_SAMPLES] {
    std::array::from_fn(|i| {
        let a = i as u32;
        let x = a.reverse_bits() as f32 * (1.0 / 4_294_967_296.0);
        let y = crate::samplers::sobol_bits(a as u64, 1) as f32 * (1.0 / 4_294_967_296.0);
        let uc = (0.5 + i as f32 * 0.618_034) % 1.0;
        (uc, Vec2::new(x, y) + Vec2::splat(0.5 / RHO_SAMPLES as f32))
    })
}

/// The first non-interface surface along the camera ray and the media's transmittance up to
/// it; `dx`, `dy` are the rays one pixel over (pbrt-v4's camera ray differentials, scaled by
/// `diff_scale`) and `output_from_world` the film's coordinate system at the ray's time.
fn visible_surface(
    scene: &Scene,
    mut ray: Ray,
    (dx, dy, diff_scale): (Ray, Ray, f32),
    output_from_world: &Affine3A,
) -> Option<(VisibleSurface, f32)> {
    let mut medium = scene.camera_medium;
    let mut transmittance = 1.0f32;
    let mut rng = Pcg32::new(hash_vec3(ray.o), hash_vec3(ray.d));
    // Textures filter over the camera ray's footprint, as in the render.
    let diff = scene.footprint.as_ref().and_then(|f| f.camera_differentials(&scene.camera, &ray));
    // A bounded number of boundaries: a ray caught between coincident interfaces gives up.
    for _ in 0..256 {
        let hit = scene.surfaces.intersect(&ray, f32::INFINITY);
        if medium != NONE {
            let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.surface.t);
            let m = &scene.media[medium as usize];
            transmittance *= match &m.kind {
                // Closed form where there is one; ratio tracking's unbiased estimate elsewhere.
                MediumKind::Homogeneous { sigma_a, sigma_s, .. } => {
                    (-(sigma_a.rgb + sigma_s.rgb) * t_max).exp().average()
                }
                _ => {
                    let mut est = ShadowEstimate::<Rgb>::default();
                    ratio_tracking(None, m.into(), &ray, t_max, &mut rng, 0, &(), &mut est);
                    (est.t_ray / est.r_l.average()).average()
                }
            };
            if transmittance <= 0.0 || !transmittance.is_finite() {
                return None;
            }
        }
        let mut hit = hit?;
        let wo = -ray.d;
        let (material, tex_ctx) = scene.surface_material(&mut hit, wo, diff.as_ref());
        let s = hit.surface;
        let Some(bxdf) = material.bxdf::<Rgb>(&scene.textures, &tex_ctx, &mut ()) else {
            medium = medium_after(scene, &hit, ray.d, medium);
            ray = hit.spawn_ray(ray.d);
            continue;
        };
        let frame = shading_frame(&hit);
        let wo_local = frame.to_local(wo);
        let mut albedo = Rgb::ZERO;
        for (uc, u) in rho_samples() {
            if let Some(bs) = bxdf.sample_f(wo_local, uc, u, TransportMode::Radiance, ReflTransFlags::ALL)
                && bs.pdf > 0.0
            {
                albedo += bs.f * bs.wi.z.abs() / bs.pdf;
            }
        }
        albedo /= RHO_SAMPLES as f32;
        // Where the neighbouring pixels' rays meet the tangent plane (pbrt-v4's
        // ComputeDifferentials): the position's change per pixel.
        let on_plane = |r: &Ray| {
            let d = s.n.dot(r.d);
            if d == 0.0 {
                return Vec3::ZERO;
            }
            let t = s.n.dot(s.p - r.o) / d;
            if t.is_finite() { (r.o + r.d * t - s.p) * diff_scale } else { Vec3::ZERO }
        };
        let (dpdx, dpdy) = (on_plane(&dx), on_plane(&dy));
        let out_n = |n: Vec3| output_from_world.matrix3.inverse().transpose().mul_vec3a(n.into()).normalize_or_zero();
        // Facing the viewer, as pbrt-v4's VisibleSurface (FaceForward(n, wo)): a surface's
        // normal otherwise follows its winding or orientation.
        let facing = |n: Vec3| if n.dot(wo) < 0.0 { -n } else { n };
        let surface = VisibleSurface {
            p: output_from_world.transform_point3(s.p),
            n: Vec3::from(out_n(facing(s.n))),
            ns: Vec3::from(out_n(facing(s.ns))),
            uv: s.uv,
            dzdx: output_from_world.transform_vector3(dpdx).z,
            dzdy: output_from_world.transform_vector3(dpdy).z,
            albedo,
        };
        return Some((surface, transmittance));
    }
    None
}

/// Whether the camera ray meets a surface other than a medium boundary: the samples whose
/// radiance pbrt-v4's variance channels count.
pub(super) fn sees_surface(scene: &Scene, mut ray: Ray) -> bool {
    for _ in 0..256 {
        let Some(hit) = scene.surfaces.intersect(&ray, f32::INFINITY) else { return false };
        if !scene.materials[hit.prim.material as usize].is_interface() {
            return true;
        }
        ray = hit.spawn_ray(ray.d);
    }
    false
}

/// The G-buffer channels for `spp` samples of every pixel of `acc`, in pbrt-v4's names and
/// order, positions and normals in camera space unless `world`.
pub(super) fn channels(
    scene: &Scene,
    sampler: &Sampler,
    acc: &Accumulator,
    spp: u32,
    world: bool,
) -> Vec<(String, Vec<f32>)> {
    let diff_scale = (1.0 / (spp.max(1) as f32).sqrt()).max(0.125);
    let rows: Vec<Vec<Sums>> = (0..acc.height)
        .into_par_iter()
        .map(|row| {
            let mut sampler = sampler.clone();
            (0..acc.width)
                .map(|col| {
                    let pixel = UVec2::new(acc.origin.x + col, acc.origin.y + row);
                    let mut sums = Sums::default();
                    for s in 0..spp {
                        let cs = camera_sample(scene, &mut sampler, pixel, s);
                        let camera = &scene.camera;
                        let time = camera.time(cs.time);
                        let w = cs.filter_weight as f64;
                        sums.weight += w;
                        // A sample a realistic camera's lens stops sees nothing; a neighbour it
                        // stops gives no differential (zero, as for the sample itself).
                        let Some(ray) = camera.generate_ray(cs.p_film, cs.p_lens, time).map(|c| c.ray) else {
                            continue;
                        };
                        let dx = camera.generate_ray(cs.p_film + Vec2::X, cs.p_lens, time).map_or(ray, |c| c.ray);
                        let dy = camera.generate_ray(cs.p_film + Vec2::Y, cs.p_lens, time).map_or(ray, |c| c.ray);
                        let output_from_world =
                            if world { Affine3A::IDENTITY } else { camera.world_from_camera_at(time).inverse() };
                        let Some((v, t)) = visible_surface(scene, ray, (dx, dy, diff_scale), &output_from_world) else {
                            continue;
                        };
                        let wt = w * t as f64;
                        sums.surface_weight += wt;
                        sums.albedo += wt * v.albedo.as_dvec3();
                        sums.p += wt * v.p.as_dvec3();
                        sums.n += wt * v.n.as_dvec3();
                        sums.ns += wt * v.ns.as_dvec3();
                        sums.uv += wt * v.uv.as_dvec2();
                        sums.dz += wt * DVec2::new(v.dzdx as f64, v.dzdy as f64);
                    }
                    sums
                })
                .collect()
        })
        .collect();
    let names = [
        "Albedo.R", "Albedo.G", "Albedo.B", "P.X", "P.Y", "P.Z", "dzdx", "dzdy", "N.X", "N.Y", "N.Z", "Ns.X", "Ns.Y",
        "Ns.Z", "u", "v",
    ];
    let mut out: Vec<(String, Vec<f32>)> =
        names.iter().map(|n| (n.to_string(), Vec::with_capacity((acc.width * acc.height) as usize))).collect();
    for s in rows.iter().flatten() {
        let albedo = if s.weight != 0.0 { s.albedo / s.weight } else { DVec3::ZERO };
        let k = if s.surface_weight != 0.0 { 1.0 / s.surface_weight } else { 0.0 };
        let (p, uv, dz) = (s.p * k, s.uv * k, s.dz * k);
        let (n, ns) = (s.n.normalize_or_zero(), s.ns.normalize_or_zero());
        let values = [
            albedo.x,
            albedo.y,
            albedo.z,
            p.x,
            p.y,
            p.z,
            dz.x.abs(),
            dz.y.abs(),
            n.x,
            n.y,
            n.z,
            ns.x,
            ns.y,
            ns.z,
            uv.x,
            uv.y,
        ];
        for (o, v) in out.iter_mut().zip(values) {
            o.1.push(v as f32);
        }
    }
    out
}
