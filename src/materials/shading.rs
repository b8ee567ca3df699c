//! Shading geometry a material perturbs before it scatters: pbrt-v4's bump mapping
//! (`displacement`) and normal maps (`normalmap`), applied as pbrt-v4's
//! `SurfaceInteraction::GetBSDF` applies them (the normal map wins when both are given).

use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::imageio::Image;
use crate::math::Frame;
use crate::shapes::{SurfaceDerivatives, SurfaceHit};
use crate::textures::{Tex, TexContext, Textures, Wrap, bilerp};

/// pbrt-v4's finite-difference step in u and v where a hit has no footprint in (u, v).
const BUMP_DELTA: f32 = 0.0005;

/// What a material does to the shading geometry.
#[derive(Clone, Debug, Default)]
pub enum ShadingPerturbation {
    /// Nothing: the shape's shading normal.
    #[default]
    None,
    /// Bump mapping by a scalar displacement along the shading normal (float texture).
    Bump(Tex),
    /// A tangent-space normal map (linear RGB, (2c − 1) per channel).
    NormalMap(Arc<Image>),
}

impl ShadingPerturbation {
    /// True when the shape's shading geometry is used unchanged.
    #[inline]
    pub fn is_none(&self) -> bool {
        matches!(self, ShadingPerturbation::None)
    }

    /// Replaces the hit's shading normal and tangent by the perturbed ones, given the
    /// surface's derivatives there and its texture lookup `ctx` (with its footprint, which
    /// sets a bump's finite-difference steps). Degenerate parameterisations (no ∂p/∂u or
    /// ∂p/∂v: a bump or a map has no frame) keep the shape's.
    pub fn apply(&self, textures: &Textures, s: &mut SurfaceHit, d: &SurfaceDerivatives, ctx: &TexContext) {
        let (dpdu, dpdv) = match self {
            ShadingPerturbation::None => return,
            ShadingPerturbation::Bump(displacement) => bump(textures, *displacement, s, d, ctx),
            ShadingPerturbation::NormalMap(map) => normal_map(map, s, d),
        };
        // pbrt-v4's SetShadingGeometry(normalize(∂p/∂u × ∂p/∂v), ..., false): the shading
        // normal is turned to the geometric normal's side.
        let ns = dpdu.cross(dpdv).normalize_or_zero();
        if ns == Vec3::ZERO || !ns.is_finite() {
            return;
        }
        s.ns = if ns.dot(s.n) < 0.0 { -ns } else { ns };
        s.dpdu = dpdu;
    }
}

/// pbrt-v4's `BumpMap`: p'(u, v) = p + d(u, v)·n, differentiated by forward differences of the
/// displacement over half the hit's (u, v) footprint (0.0005 without one) and the normal's
/// own derivatives; the shifted lookups keep the footprint.
fn bump(
    textures: &Textures,
    displacement: Tex,
    s: &SurfaceHit,
    d: &SurfaceDerivatives,
    ctx: &TexContext,
) -> (Vec3, Vec3) {
    let eval = |p: Vec3, uv: Vec2| textures.eval_float(displacement, &TexContext { p, uv, ..*ctx });
    let step = |a: f32, b: f32| {
        let h = 0.5 * (a.abs() + b.abs());
        if h == 0.0 { BUMP_DELTA } else { h }
    };
    let (du, dv) = (step(ctx.duvdx.x, ctx.duvdy.x), step(ctx.duvdx.y, ctx.duvdy.y));
    let disp = eval(s.p, s.uv);
    let u_displace = eval(s.p + du * d.dpdu, s.uv + Vec2::new(du, 0.0));
    let v_displace = eval(s.p + dv * d.dpdv, s.uv + Vec2::new(0.0, dv));
    let dpdu = d.dpdu + (u_displace - disp) / du * s.ns + disp * d.dndu;
    let dpdv = d.dpdv + (v_displace - disp) / dv * s.ns + disp * d.dndv;
    (dpdu, dpdv)
}

/// pbrt-v4's `NormalMap`: the map's normal in the frame (∂p/∂u, ns), with the tangents made
/// perpendicular to it and their lengths kept.
fn normal_map(map: &Image, s: &SurfaceHit, d: &SurfaceDerivatives) -> (Vec3, Vec3) {
    if d.dpdu.length_squared() == 0.0 {
        return (d.dpdu, d.dpdv);
    }
    // pbrt-v4 flips v so that the map is not upside down, and repeats it.
    let c = bilerp(map, Vec2::new(s.uv.x, 1.0 - s.uv.y), Wrap::Repeat);
    let local = (2.0 * c - Vec3::ONE).normalize_or_zero();
    if local == Vec3::ZERO {
        return (d.dpdu, d.dpdv);
    }
    let frame = Frame::from_z_x(s.ns, d.dpdu);
    let ns = frame.to_world(local);
    let (ulen, vlen) = (d.dpdu.length(), d.dpdv.length());
    let dpdu = (d.dpdu - d.dpdu.dot(ns) * ns).normalize_or_zero() * ulen;
    let dpdv = ns.cross(dpdu).normalize_or_zero() * vlen;
    (dpdu, dpdv)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane_hit() -> SurfaceHit {
        SurfaceHit {
            t: 1.0,
            p: Vec3::new(0.3, 0.2, 0.0),
            n: Vec3::Z,
            ns: Vec3::Z,
            uv: Vec2::new(0.3, 0.2),
            dpdu: Vec3::X,
            p_error: 0.0,
        }
    }

    const PLANE: SurfaceDerivatives =
        SurfaceDerivatives { dpdu: Vec3::X, dpdv: Vec3::Y, dndu: Vec3::ZERO, dndv: Vec3::ZERO };

    fn image(width: usize, height: usize, pixels: Vec<Vec3>) -> Arc<Image> {
        let mut img = Image::new(width, height);
        img.pixels = pixels;
        Arc::new(img)
    }

    fn constant(v: f32) -> Tex {
        Tex::Const(crate::spectra::SpectrumValue::constant(v))
    }

    #[test]
    fn a_linear_bump_tilts_the_normal_by_its_slope() {
        // A two-texel image (0, 1) rises linearly between its texel centres (u = 0.25 and
        // 0.75): scaled by 0.25, d(u, v) = 0.5·(u − 0.25) there. On the plane z = 0 (u = x)
        // the bumped surface z = 0.5·x has normal (−0.5, 0, 1)/|·|; forward differences of a
        // linear function are exact.
        let mut textures = Textures::default();
        textures.nodes.push(crate::textures::TexNode::Image {
            image: Arc::new(crate::textures::MipMap::new(
                (*image(2, 1, vec![Vec3::ZERO, Vec3::ONE])).clone(),
                Wrap::Clamp,
                crate::textures::MipFilter::Bilinear,
            )),
            mapping: crate::textures::TexMapping::Uv { s: Vec2::ONE, d: Vec2::ZERO },
            scale: 0.25,
            invert: false,
            space: nimbus_parser::ColorSpace::Srgb,
            gray: true,
            float: true,
        });
        let mut s = plane_hit();
        let ctx = TexContext::at(s.p, s.uv, s.n);
        ShadingPerturbation::Bump(Tex::Node(0)).apply(&textures, &mut s, &PLANE, &ctx);
        let expected = Vec3::new(-0.5, 0.0, 1.0).normalize();
        assert!((s.ns - expected).length() < 1e-3, "{:?}", s.ns);
        assert!(s.dpdu.dot(s.ns).abs() < 1e-5);
        // A constant displacement on a plane changes nothing.
        let mut s = plane_hit();
        let ctx = TexContext::at(s.p, s.uv, s.n);
        ShadingPerturbation::Bump(constant(0.25)).apply(&textures, &mut s, &PLANE, &ctx);
        assert!((s.ns - Vec3::Z).length() < 1e-6);
        // With a footprint the step is half of it in (u, v), as pbrt-v4 takes it: at u = 0.7
        // a step of 0.1 crosses the last texel centre, where the ramp stops, and sees half
        // the slope (0.25 instead of 0.5).
        let mut s = SurfaceHit { p: Vec3::new(0.7, 0.2, 0.0), uv: Vec2::new(0.7, 0.2), ..plane_hit() };
        let ctx =
            TexContext { duvdx: Vec2::new(0.1, 0.0), duvdy: Vec2::new(0.1, 0.0), ..TexContext::at(s.p, s.uv, s.n) };
        ShadingPerturbation::Bump(Tex::Node(0)).apply(&textures, &mut s, &PLANE, &ctx);
        let expected = Vec3::new(-0.25, 0.0, 1.0).normalize();
        assert!((s.ns - expected).length() < 1e-3, "{:?}", s.ns);
    }

    #[test]
    fn a_constant_bump_on_a_sphere_keeps_its_normal() {
        // Displacing a sphere by a constant gives a bigger sphere with the same normals: the
        // curvature term d·∂n/∂u carries the whole effect.
        let sphere = crate::shapes::Sphere::new(glam::Affine3A::IDENTITY, false, 1.0, -1.0, 1.0, 360.0);
        let p = Vec3::new(0.3, -0.5, 0.6).normalize();
        let hit = sphere.hit(1.0, p);
        let d = sphere.derivatives(&hit);
        let mut s = hit;
        let ctx = TexContext::at(s.p, s.uv, s.n);
        ShadingPerturbation::Bump(constant(0.3)).apply(&Textures::default(), &mut s, &d, &ctx);
        assert!((s.ns - hit.ns).length() < 1e-4, "{:?} vs {:?}", s.ns, hit.ns);
        // ∂n/∂u on a unit sphere is ∂p/∂u (n = p): the tangents scale by 1 + d.
        assert!((s.dpdu.length() / hit.dpdu.length() - 1.3).abs() < 1e-3);
    }

    #[test]
    fn normal_maps_rotate_the_normal_in_the_tangent_frame() {
        // A flat map (0.5, 0.5, 1) is the unperturbed normal; a texel (c + 1)/2 for a unit c
        // makes the normal c in the frame (∂p/∂u, ∂p/∂v, n).
        let mut s = plane_hit();
        ShadingPerturbation::NormalMap(image(2, 2, vec![Vec3::new(0.5, 0.5, 1.0); 4])).apply(
            &Textures::default(),
            &mut s,
            &PLANE,
            &TexContext::at(Vec3::ZERO, Vec2::ZERO, Vec3::Z),
        );
        assert!((s.ns - Vec3::Z).length() < 1e-6, "{:?}", s.ns);
        let tilt = Vec3::new(0.6, 0.0, 0.8);
        let mut s = plane_hit();
        ShadingPerturbation::NormalMap(image(1, 1, vec![(tilt + Vec3::ONE) * 0.5])).apply(
            &Textures::default(),
            &mut s,
            &PLANE,
            &TexContext::at(Vec3::ZERO, Vec2::ZERO, Vec3::Z),
        );
        assert!((s.ns - tilt).length() < 1e-5, "{:?}", s.ns);
        assert!((s.dpdu.length() - 1.0).abs() < 1e-5 && s.dpdu.dot(s.ns).abs() < 1e-5);
    }
}
