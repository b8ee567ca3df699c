//! Light sources with pbrt-v4's radiometry: point, spot, goniometric, projection, distant,
//! uniform and image infinite lights (also through a portal), and diffuse area lights (one per
//! emitting primitive, as in pbrt-v4).

mod bvh;
mod emission_image;
mod envmap;
pub mod goniometric;
mod portal;
pub mod projection;
mod sampler;

pub use bvh::{LightBounds, LightBvh, light_bounds};
pub use emission_image::EmissionImage;
pub use envmap::{EnvironmentMap, reference_illuminance};
pub use portal::{PortalMap, portal_frame};
pub use sampler::{LightSampler, LightSamplerKind};

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::accel::{Geometry, NONE, ShapeStore, Surfaces};
use crate::channels::Channels;
use crate::color::{Rgb, average};
use crate::math::Frame;
use crate::sampling::warp;
use crate::shapes::{SurfaceHit, triangle_sample};
use crate::spectra::{RgbRole, SpectrumValue};

/// What a light is.
#[derive(Clone, Debug)]
pub enum LightKind {
    /// Isotropic point source of intensity `i`.
    Point {
        /// Position.
        p: Vec3,
        /// Radiant intensity.
        i: SpectrumValue,
    },
    /// Point source whose intensity `i` is weighted by direction by an equal-area image.
    Goniometric {
        /// Position.
        p: Vec3,
        /// Radiant intensity where the image is 1.
        i: SpectrumValue,
        /// The directional weights.
        image: std::sync::Arc<goniometric::GoniometricImage>,
    },
    /// Point source projecting an RGB image through a pinhole (pbrt-v4's `projection`).
    Projection {
        /// Position.
        p: Vec3,
        /// Multiplier on the image's RGB (pbrt-v4's `scale`, after `power`).
        scale: f32,
        /// The image and its frustum.
        image: std::sync::Arc<projection::ProjectionImage>,
    },
    /// Point source limited to a cone with a smooth falloff.
    Spot {
        /// Position.
        p: Vec3,
        /// Frame whose z axis is the spot direction.
        frame: Frame,
        /// Radiant intensity on the axis.
        i: SpectrumValue,
        /// cos of the angle where the falloff starts.
        cos_falloff_start: f32,
        /// cos of the cone angle (falloff end).
        cos_falloff_end: f32,
    },
    /// Parallel light arriving from direction `-w`.
    Distant {
        /// Unit direction towards the light.
        w: Vec3,
        /// Radiance.
        l: SpectrumValue,
    },
    /// Constant radiance from every direction.
    UniformInfinite {
        /// Radiance.
        l: SpectrumValue,
    },
    /// Radiance from an equal-area octahedral image.
    ImageInfinite(Box<EnvironmentMap>),
    /// An environment (image or constant) seen only through a rectangular portal.
    PortalInfinite(Box<PortalMap>),
    /// A diffuse emitter on one primitive.
    Area {
        /// The emitting geometry (never an instance).
        geometry: Geometry,
        /// Emitted radiance (with an image: the factor the image's radiance is scaled by).
        l: SpectrumValue,
        /// The emission image read at the surface's (u, v) (`"string filename"`), shared by
        /// the shape's primitives.
        image: Option<Arc<EmissionImage>>,
        /// Emits from both sides.
        two_sided: bool,
        /// Surface area (world space).
        area: f32,
        /// The emitting shape's medium interface index, or [`crate::accel::NONE`]: the media on
        /// its two sides (light tracing starts in the one it leaves towards).
        interface: u32,
        /// The shape's alpha texture (index into [`Surfaces::alphas`]), or
        /// [`crate::accel::NONE`]: pbrt-v4 masks the emission where the alpha test fails.
        alpha: u32,
        /// The shape has a constant alpha of 0: pbrt-v4's invisible area light. No ray ever
        /// hits its shape, yet it emits unmasked, and light sampling is its only strategy, so
        /// its samples take no MIS weight (pbrt-v4 makes it a `DeltaPosition` light for this).
        invisible: bool,
    },
}

/// A light and the medium it sits in.
#[derive(Clone, Debug)]
pub struct Light {
    /// The light.
    pub kind: LightKind,
    /// Index of the medium around it, or [`crate::accel::NONE`].
    pub medium: u32,
}

/// Where lighting is sampled from.
#[derive(Clone, Copy, Debug)]
pub struct LightContext {
    /// Reference point.
    pub p: Vec3,
}

/// Incident light sampled from a light.
#[derive(Clone, Copy, Debug)]
pub struct LightSample<C = Rgb> {
    /// Radiance arriving (for delta lights, the incident radiance-like quantity I/r²).
    pub l: C,
    /// Unit direction from the reference point towards the light.
    pub wi: Vec3,
    /// Density per solid angle (1 for delta lights).
    pub pdf: f32,
    /// Point on the light (far away for infinite and distant lights).
    pub p: Vec3,
    /// Normal at `p` for area lights (zero otherwise).
    pub n: Vec3,
    /// True for lights that cannot be hit by rays (point, spot, distant, an invisible area
    /// light): no other strategy finds them, so the sample takes no MIS weight.
    pub delta: bool,
    /// True when `p` is at infinity (the shadow ray is unbounded).
    pub infinite: bool,
}

/// Scene extent, for distant and infinite lights.
#[derive(Clone, Copy, Debug)]
pub struct SceneSphere {
    /// Centre of a sphere bounding the scene.
    pub center: Vec3,
    /// Its radius.
    pub radius: f32,
}

impl Light {
    /// True for lights with a delta distribution (never hit by rays).
    pub fn is_delta(&self) -> bool {
        matches!(
            self.kind,
            LightKind::Point { .. }
                | LightKind::Goniometric { .. }
                | LightKind::Spot { .. }
                | LightKind::Distant { .. }
        )
    }

    /// True for lights at infinity that escaped rays see.
    pub fn is_infinite(&self) -> bool {
        matches!(
            self.kind,
            LightKind::UniformInfinite { .. } | LightKind::ImageInfinite(_) | LightKind::PortalInfinite(_)
        )
    }

    /// Whether next-event estimation samples this light. A uniform environment is left to
    /// BSDF and phase sampling, as pbrt-v4 does (its sampled pdf would only add variance).
    pub fn samples_directly(&self) -> bool {
        !matches!(self.kind, LightKind::UniformInfinite { .. })
    }

    /// Whether [`Self::sample_li`] reads its `u`: lights at a point or from one direction
    /// have one sample to give.
    pub fn reads_sample(&self) -> bool {
        !matches!(
            self.kind,
            LightKind::Point { .. }
                | LightKind::Goniometric { .. }
                | LightKind::Projection { .. }
                | LightKind::Spot { .. }
                | LightKind::Distant { .. }
        )
    }

    /// Total emitted power (channel average), for choosing lights in proportion to it.
    pub fn power(&self, scene: &SceneSphere) -> f32 {
        let p = match &self.kind {
            LightKind::Point { i, .. } => 4.0 * PI * average(i.rgb),
            LightKind::Goniometric { i, image, .. } => 4.0 * PI * average(i.rgb) * image.mean(),
            LightKind::Projection { scale, image, .. } => scale * average(image.power_rgb()),
            LightKind::Spot { i, cos_falloff_start, cos_falloff_end, .. } => {
                2.0 * PI * average(i.rgb) * ((1.0 - cos_falloff_start) + (cos_falloff_start - cos_falloff_end) / 2.0)
            }
            LightKind::Distant { l, .. } => PI * scene.radius * scene.radius * average(l.rgb),
            LightKind::UniformInfinite { l } => 4.0 * PI * PI * scene.radius * scene.radius * average(l.rgb),
            LightKind::ImageInfinite(map) => 4.0 * PI * PI * scene.radius * scene.radius * map.average_radiance(),
            LightKind::PortalInfinite(map) => map.power(),
            LightKind::Area { l, image, two_sided, area, .. } => {
                let mean = image.as_ref().map_or(1.0, |i| i.mean_channel());
                PI * if *two_sided { 2.0 } else { 1.0 } * area * average(l.rgb) * mean
            }
        };
        if p.is_finite() { p.max(0.0) } else { 0.0 }
    }

    /// A point of an area light's shape, uniform by area (`None` for other lights and shapes
    /// that cannot be sampled so): where light tracing starts.
    pub fn sample_area_point(&self, shapes: &ShapeStore, u: Vec2) -> Option<crate::shapes::ShapeSample> {
        let LightKind::Area { geometry, .. } = &self.kind else { return None };
        match *geometry {
            Geometry::Triangle { mesh, tri } => Some(triangle_sample(&shapes.meshes[mesh as usize], tri, u)),
            Geometry::Sphere(i) => shapes.spheres[i as usize].sample_area(u),
            Geometry::Disk(i) => shapes.disks[i as usize].sample_area(u),
            Geometry::Cylinder(i) => shapes.cylinders[i as usize].sample_area(u),
            Geometry::Bilinear { mesh, patch } => shapes.bilinear_meshes[mesh as usize].sample_area(patch, u),
            Geometry::Curve(_) | Geometry::Instance(_) | Geometry::Hull(_) => None,
        }
    }

    /// Samples incident light at `ctx`, in the path's channels.
    pub fn sample_li<C: Channels>(
        &self,
        ctx: &LightContext,
        u: Vec2,
        surfaces: &Surfaces,
        scene: &SceneSphere,
        lambda: &C::Lambda,
    ) -> Option<LightSample<C>> {
        let shapes = &surfaces.shapes;
        match &self.kind {
            LightKind::Point { p, i } => point_sample(*p, ctx.p, |_| Some(C::eval(i, lambda))),
            LightKind::Goniometric { p, i, image } => point_sample(*p, ctx.p, |wi| {
                let weight = image.lookup(-wi);
                (weight > 0.0).then(|| C::eval(i, lambda) * weight)
            }),
            LightKind::Projection { p, scale, image } => point_sample(*p, ctx.p, |wi| {
                let rgb = image.lookup(-wi)?;
                (rgb.max_element() > 0.0).then(|| C::from_rgb(rgb, RgbRole::Illuminant, image.space, lambda) * *scale)
            }),
            LightKind::Spot { p, frame, i, cos_falloff_start, cos_falloff_end } => point_sample(*p, ctx.p, |wi| {
                let falloff = smoothstep(*cos_falloff_end, *cos_falloff_start, frame.z.dot(-wi));
                (falloff > 0.0).then(|| C::eval(i, lambda) * falloff)
            }),
            LightKind::Distant { w, l } => Some(LightSample {
                l: C::eval(l, lambda),
                wi: *w,
                pdf: 1.0,
                p: ctx.p + *w * (2.0 * scene.radius),
                n: Vec3::ZERO,
                delta: true,
                infinite: true,
            }),
            LightKind::UniformInfinite { l } => {
                let wi = warp::uniform_sphere(u);
                Some(infinite_sample(ctx, scene, wi, warp::UNIFORM_SPHERE_PDF, C::eval(l, lambda)))
            }
            LightKind::ImageInfinite(map) => {
                let (wi, pdf, l) = map.sample::<C>(u, lambda)?;
                Some(infinite_sample(ctx, scene, wi, pdf, l))
            }
            LightKind::PortalInfinite(map) => {
                let (wi, pdf, l) = map.sample::<C>(ctx.p, u, lambda)?;
                Some(infinite_sample(ctx, scene, wi, pdf, l))
            }
            LightKind::Area { geometry, l, image, two_sided, alpha, invisible, .. } => {
                let s = match *geometry {
                    Geometry::Triangle { mesh, tri } => triangle_sample(&shapes.meshes[mesh as usize], tri, u),
                    Geometry::Sphere(i) => shapes.spheres[i as usize].sample(ctx.p, u)?,
                    Geometry::Disk(i) => shapes.disks[i as usize].sample_area(u)?,
                    Geometry::Cylinder(i) => shapes.cylinders[i as usize].sample_area(u)?,
                    Geometry::Bilinear { mesh, patch } => {
                        shapes.bilinear_meshes[mesh as usize].sample_area(patch, u)?
                    }
                    Geometry::Curve(_) | Geometry::Instance(_) | Geometry::Hull(_) => return None,
                };
                let to = s.p - ctx.p;
                let d2 = to.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let wi = to / d2.sqrt();
                let cos_light = s.n.dot(-wi);
                let pdf = if s.solid_angle {
                    s.pdf
                } else {
                    if cos_light.abs() == 0.0 {
                        return None;
                    }
                    s.pdf * d2 / cos_light.abs()
                };
                if !pdf.is_finite() || pdf <= 0.0 {
                    return None;
                }
                if !(*two_sided || cos_light > 0.0) || l.is_zero() {
                    return None;
                }
                let uv =
                    if *alpha != NONE || image.is_some() { shapes.uv_at(*geometry, s.p, ctx.p)? } else { Vec2::ZERO };
                if *alpha != NONE && alpha_masked(surfaces, *alpha, s.p, uv, s.n) {
                    return None;
                }
                let le = area_radiance(l, image.as_deref(), uv, lambda);
                Some(LightSample { l: le, wi, pdf, p: s.p, n: s.n, delta: *invisible, infinite: false })
            }
        }
    }

    /// Density (per solid angle) with which [`Light::sample_li`] would pick direction `wi`
    /// from `ctx`; for area lights `hit` is where that direction meets the light.
    pub fn pdf_li(&self, ctx: &LightContext, wi: Vec3, hit: Option<&SurfaceHit>, shapes: &ShapeStore) -> f32 {
        match &self.kind {
            LightKind::Point { .. }
            | LightKind::Goniometric { .. }
            | LightKind::Projection { .. }
            | LightKind::Spot { .. }
            | LightKind::Distant { .. } => 0.0,
            LightKind::UniformInfinite { .. } => warp::UNIFORM_SPHERE_PDF,
            LightKind::ImageInfinite(map) => map.pdf(wi),
            LightKind::PortalInfinite(map) => map.pdf(ctx.p, wi),
            LightKind::Area { geometry, area, .. } => {
                let Some(hit) = hit else { return 0.0 };
                match *geometry {
                    Geometry::Sphere(i) => shapes.spheres[i as usize].pdf(ctx.p, wi, hit),
                    // Patches are not sampled uniformly in area: the density at the point the
                    // direction meets (found again from the reference point).
                    Geometry::Bilinear { mesh, patch } => {
                        let m = &shapes.bilinear_meshes[mesh as usize];
                        let cos = hit.n.dot(wi).abs();
                        match m.param(patch, &crate::geometry::Ray::new(ctx.p, wi)) {
                            Some((u, v)) if cos > 0.0 => {
                                m.pdf_area(patch, Vec2::new(u, v)) * ctx.p.distance_squared(hit.p) / cos
                            }
                            _ => 0.0,
                        }
                    }
                    _ => {
                        let cos = hit.n.dot(wi).abs();
                        if cos == 0.0 { 0.0 } else { ctx.p.distance_squared(hit.p) / (cos * area) }
                    }
                }
            }
        }
    }

    /// Radiance an area light emits from `hit` in direction `w` (pointing away from it).
    #[inline]
    pub fn emitted<C: Channels>(&self, hit: &SurfaceHit, w: Vec3, lambda: &C::Lambda, surfaces: &Surfaces) -> C {
        if self.emits(hit, w, surfaces) {
            let LightKind::Area { l, image, .. } = &self.kind else {
                unreachable!("only area lights emit from surfaces")
            };
            area_radiance(l, image.as_deref(), hit.uv, lambda)
        } else {
            C::ZERO
        }
    }

    /// Whether an area light emits from `hit` in direction `w` at all.
    #[inline]
    pub fn emits(&self, hit: &SurfaceHit, w: Vec3, surfaces: &Surfaces) -> bool {
        match &self.kind {
            LightKind::Area { l, two_sided, alpha, .. } => {
                (*two_sided || hit.n.dot(w) > 0.0)
                    && !l.is_zero()
                    && (*alpha == NONE || !alpha_masked(surfaces, *alpha, hit.p, hit.uv, hit.n))
            }
            _ => false,
        }
    }

    /// Radiance an infinite light sends along a ray from `o` leaving the scene in direction
    /// `d` (a portal light sends it only through its portal).
    #[inline]
    pub fn le<C: Channels>(&self, o: Vec3, d: Vec3, lambda: &C::Lambda) -> C {
        match &self.kind {
            LightKind::UniformInfinite { l } => C::eval(l, lambda),
            LightKind::ImageInfinite(map) => map.lookup(d, lambda),
            LightKind::PortalInfinite(map) => map.le(o, d, lambda),
            _ => C::ZERO,
        }
    }
}

/// An area light's radiance at surface coordinates `uv`: `l`, times the image there if it has
/// one.
#[inline]
pub(crate) fn area_radiance<C: Channels>(
    l: &SpectrumValue,
    image: Option<&EmissionImage>,
    uv: Vec2,
    lambda: &C::Lambda,
) -> C {
    let le = C::eval(l, lambda);
    match image {
        Some(image) => le * image.radiance::<C>(uv, lambda),
        None => le,
    }
}

/// A sample of an infinite light from `ctx`: radiance `l` arriving along `wi` with density
/// `pdf`, from a point beyond the scene.
#[inline]
fn infinite_sample<C>(ctx: &LightContext, scene: &SceneSphere, wi: Vec3, pdf: f32, l: C) -> LightSample<C> {
    LightSample { l, wi, pdf, p: ctx.p + wi * (2.0 * scene.radius), n: Vec3::ZERO, delta: false, infinite: true }
}

/// pbrt-v4's `DiffuseAreaLight::AlphaMasked`: no emission where the shape's alpha is 0, none
/// where a number hashed from the point exceeds a fractional alpha (a fixed pattern over the
/// surface, apart from the alpha test rays get when they hit it). pbrt-v4 evaluates the alpha
/// here at a bare `Interaction(p, uv)`, whose Ptex face id is 0, and so does nimbus.
pub(crate) fn alpha_masked(surfaces: &Surfaces, alpha: u32, p: Vec3, uv: Vec2, n: Vec3) -> bool {
    let a = surfaces.textures.eval_float(surfaces.alphas[alpha as usize], &crate::textures::TexContext::at(p, uv, n));
    if a >= 1.0 {
        return false;
    }
    if a <= 0.0 {
        return true;
    }
    let mut bytes = [0u8; 12];
    for (i, v) in [p.x, p.y, p.z].iter().enumerate() {
        bytes[4 * i..4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
    (crate::sampling::rng::murmur_hash64a(&bytes, 0) as u32) as f32 * (1.0 / 4_294_967_296.0) > a
}

/// pbrt-v4's SmoothStep: 0 below `a`, 1 above `b`, cubic between.
#[inline]
pub fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The sample of a light at point `p` seen from `from`: the intensity it sends towards
/// `from` (`intensity(wi)` with `wi` pointing at the light; `None` for none) over the squared
/// distance.
#[inline]
fn point_sample<C: Channels>(p: Vec3, from: Vec3, intensity: impl FnOnce(Vec3) -> Option<C>) -> Option<LightSample<C>> {
    let d2 = p.distance_squared(from);
    if d2 == 0.0 {
        return None;
    }
    let wi = (p - from) / d2.sqrt();
    let i = intensity(wi)?;
    Some(LightSample { l: i / d2, wi, pdf: 1.0, p, n: Vec3::ZERO, delta: true, infinite: false })
}
