//! Textures as pbrt-v4 evaluates them, filtered over the hit's footprint where pbrt-v4
//! filters: constants, scale, mix, 2D and 3D checkerboards, image maps, Ptex files and noise,
//! over uv, spherical, cylindrical or planar mappings. Float textures evaluate to gray RGB
//! and are read from the first channel.
//! Spectrum textures evaluate in the path's channels: constants are scene spectra, and image
//! texels become spectra (for spectral transport) only after filtering, as in pbrt-v4's
//! `RGBImageTexture`.

mod mipmap;
mod ptex;

pub use mipmap::{MipFilter, MipMap, MipSample};
pub use ptex::{Encoding as PtexEncoding, PtexTexture};

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};

use nimbus_parser::ColorSpace;

use crate::channels::Channels;
use crate::color::Rgb;
use crate::imageio::Image;
use crate::math::noise;
use crate::spectra::{RgbRole, SpectrumValue};

/// A texture input: a constant (the common case, no indirection) or a texture node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tex {
    /// A constant value.
    Const(SpectrumValue),
    /// Index of a node in [`Textures`].
    Node(u32),
}

/// Where a texture is evaluated.
#[derive(Clone, Copy, Debug)]
pub struct TexContext {
    /// World-space point.
    pub p: Vec3,
    /// Surface (u, v).
    pub uv: Vec2,
    /// Geometric normal (for `directionmix`; zero where there is none).
    pub n: Vec3,
    /// The point's screen-space footprint, ∂p/∂x and ∂p/∂y (zero: a point lookup, as for
    /// alpha tests and light paths), [`crate::camera::Footprint`].
    pub dpdx: Vec3,
    /// See `dpdx`.
    pub dpdy: Vec3,
    /// The footprint in (u, v): ∂(u, v)/∂x (zero without a footprint).
    pub duvdx: Vec2,
    /// ∂(u, v)/∂y.
    pub duvdy: Vec2,
    /// The hit primitive's Ptex face id (pbrt-v4's `faceIndex`; 0 where there is none).
    pub face: i32,
}

impl TexContext {
    /// A lookup at a point without a footprint.
    pub fn at(p: Vec3, uv: Vec2, n: Vec3) -> TexContext {
        TexContext { p, uv, n, dpdx: Vec3::ZERO, dpdy: Vec3::ZERO, duvdx: Vec2::ZERO, duvdy: Vec2::ZERO, face: 0 }
    }
}

/// How points map to (s, t).
#[derive(Clone, Debug)]
pub enum TexMapping {
    /// (su·u + du, sv·v + dv)
    Uv {
        /// Scale.
        s: Vec2,
        /// Offset.
        d: Vec2,
    },
    /// Spherical angles about texture-space origin.
    Spherical {
        /// Texture-from-world.
        texture_from_world: Affine3A,
    },
    /// Cylindrical about texture-space z.
    Cylindrical {
        /// Texture-from-world.
        texture_from_world: Affine3A,
    },
    /// Projection onto two texture-space vectors.
    Planar {
        /// Texture-from-world.
        texture_from_world: Affine3A,
        /// s axis.
        vs: Vec3,
        /// t axis.
        vt: Vec3,
        /// Offset.
        d: Vec2,
    },
}

impl TexMapping {
    /// The footprint of `ctx` in (s, t): (∂s/∂x, ∂t/∂x) and (∂s/∂y, ∂t/∂y), as pbrt-v4's
    /// mappings compute them. pbrt-v4's spherical mapping pairs s (from θ) with the derivative
    /// of φ and t with that of θ; nimbus keeps that pairing, as it decides pbrt-v4's filtering.
    pub fn footprint(&self, ctx: &TexContext) -> (Vec2, Vec2) {
        let along = |dsdp: Vec3, dtdp: Vec3, m: &Affine3A| {
            let (dx, dy) = (m.transform_vector3(ctx.dpdx), m.transform_vector3(ctx.dpdy));
            (Vec2::new(dsdp.dot(dx), dtdp.dot(dx)), Vec2::new(dsdp.dot(dy), dtdp.dot(dy)))
        };
        let finite = |(a, b): (Vec2, Vec2)| {
            if a.is_finite() && b.is_finite() { (a, b) } else { (Vec2::ZERO, Vec2::ZERO) }
        };
        match self {
            TexMapping::Uv { s, .. } => (*s * ctx.duvdx, *s * ctx.duvdy),
            TexMapping::Spherical { texture_from_world } => {
                let p = texture_from_world.transform_point3(ctx.p);
                let x2y2 = p.x * p.x + p.y * p.y;
                let r = x2y2.sqrt();
                let dsdp = Vec3::new(-p.y, p.x, 0.0) / (2.0 * PI * x2y2);
                let dtdp = Vec3::new(p.x * p.z / r, p.y * p.z / r, -r) / (PI * (x2y2 + p.z * p.z));
                finite(along(dsdp, dtdp, texture_from_world))
            }
            TexMapping::Cylindrical { texture_from_world } => {
                let p = texture_from_world.transform_point3(ctx.p);
                let dsdp = Vec3::new(-p.y, p.x, 0.0) / (2.0 * PI * (p.x * p.x + p.y * p.y));
                finite(along(dsdp, Vec3::Z, texture_from_world))
            }
            TexMapping::Planar { texture_from_world, vs, vt, .. } => along(*vs, *vt, texture_from_world),
        }
    }

    /// (s, t) at `ctx`.
    pub fn map(&self, ctx: &TexContext) -> Vec2 {
        match self {
            TexMapping::Uv { s, d } => *s * ctx.uv + *d,
            TexMapping::Spherical { texture_from_world } => {
                let v = texture_from_world.transform_point3(ctx.p).normalize_or_zero();
                let theta = v.z.clamp(-1.0, 1.0).acos();
                let mut phi = v.y.atan2(v.x);
                if phi < 0.0 {
                    phi += 2.0 * PI;
                }
                Vec2::new(theta / PI, phi / (2.0 * PI))
            }
            TexMapping::Cylindrical { texture_from_world } => {
                let p = texture_from_world.transform_point3(ctx.p);
                Vec2::new((PI + p.y.atan2(p.x)) / (2.0 * PI), p.z)
            }
            TexMapping::Planar { texture_from_world, vs, vt, d } => {
                let v = texture_from_world.transform_point3(ctx.p);
                Vec2::new(d.x + v.dot(*vs), d.y + v.dot(*vt))
            }
        }
    }
}

/// How image lookups outside [0, 1] behave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Tile.
    Repeat,
    /// Black outside.
    Black,
    /// Clamp to the edge.
    Clamp,
}

/// One texture.
#[derive(Clone, Debug)]
pub enum TexNode {
    /// `tex` × `scale`.
    Scale {
        /// Value.
        tex: Tex,
        /// Factor (float).
        scale: Tex,
    },
    /// lerp(amount, a, b).
    Mix {
        /// At amount 0.
        a: Tex,
        /// At amount 1.
        b: Tex,
        /// Blend (float).
        amount: Tex,
    },
    /// Alternating squares of `a` (even) and `b` (odd).
    Checkerboard {
        /// Even squares.
        a: Tex,
        /// Odd squares.
        b: Tex,
        /// Mapping.
        mapping: TexMapping,
    },
    /// Alternating cubes of `a` (even) and `b` (odd) in texture space (pbrt-v4's 3D
    /// checkerboard, point mapping).
    Checkerboard3D {
        /// Even cubes.
        a: Tex,
        /// Odd cubes.
        b: Tex,
        /// Texture space from world space (the inverse of the texture's transform).
        texture_from_world: Affine3A,
    },
    /// pbrt-v4's `bilerp`: (1−s)(1−t)·v00 + (1−s)t·v01 + s(1−t)·v10 + st·v11.
    Bilerp {
        /// v00, v01, v10, v11.
        v: [Tex; 4],
        /// Mapping.
        mapping: TexMapping,
    },
    /// pbrt-v4's `fbm` (float): fractional Brownian motion of the texture-space point.
    Fbm {
        /// Texture from world.
        texture_from_world: Affine3A,
        /// Octaves.
        octaves: u32,
        /// Amplitude ratio between octaves (`roughness`).
        omega: f32,
    },
    /// pbrt-v4's `wrinkled` (float): turbulence of the texture-space point.
    Wrinkled {
        /// Texture from world.
        texture_from_world: Affine3A,
        /// Octaves.
        octaves: u32,
        /// Amplitude ratio between octaves (`roughness`).
        omega: f32,
    },
    /// pbrt-v4's `windy` (float): wave height times wind strength.
    Windy {
        /// Texture from world.
        texture_from_world: Affine3A,
    },
    /// pbrt-v4's `marble` (spectrum): a colour spline over a noise-perturbed sine.
    Marble {
        /// Texture from world.
        texture_from_world: Affine3A,
        /// Octaves.
        octaves: u32,
        /// Amplitude ratio between octaves (`roughness`).
        omega: f32,
        /// Frequency.
        scale: f32,
        /// Strength of the perturbation.
        variation: f32,
    },
    /// pbrt-v4's `dots`: `inside` in randomly placed discs of a unit grid over (s, t).
    Dots {
        /// Inside the discs.
        inside: Tex,
        /// Elsewhere.
        outside: Tex,
        /// Mapping.
        mapping: TexMapping,
    },
    /// pbrt-v4's `directionmix`: lerp by |n · dir| between `b` (0) and `a` (1).
    DirectionMix {
        /// Where the normal is along `dir`.
        a: Tex,
        /// Where it is perpendicular.
        b: Tex,
        /// Unit direction (world space).
        dir: Vec3,
    },
    /// A bilinearly filtered image.
    Image {
        /// Pixels (linear) and their MIP pyramid.
        image: Arc<MipMap>,
        /// Mapping.
        mapping: TexMapping,
        /// Multiplier.
        scale: f32,
        /// 1 - value.
        invert: bool,
        /// Color space of the texels.
        space: ColorSpace,
        /// True when every texel is gray (RGB transport then carries it exactly).
        gray: bool,
        /// A float texture: its lookups read what pbrt-v4 reads for one ([`MipSample::float`]).
        float: bool,
    },
    /// pbrt-v4's `ptex`: per-face textures read at the hit's face id and (u, v).
    Ptex {
        /// The file, its encoding and scale.
        texture: Arc<PtexTexture>,
        /// A float texture: the mean of a three-channel file's channels, as in pbrt-v4.
        float: bool,
    },
}

/// All texture nodes of a scene.
#[derive(Clone, Debug, Default)]
pub struct Textures {
    /// Nodes; [`Tex::Node`] indexes this.
    pub nodes: Vec<TexNode>,
}

impl Textures {
    /// Whether any texture filters over the shading point's footprint (procedural noise and
    /// the 3D checkerboard): only then do hits compute one.
    pub fn uses_footprint(&self) -> bool {
        self.nodes.iter().any(|n| {
            matches!(
                n,
                TexNode::Fbm { .. }
                    | TexNode::Wrinkled { .. }
                    | TexNode::Windy { .. }
                    | TexNode::Marble { .. }
                    | TexNode::Checkerboard3D { .. }
                    | TexNode::Checkerboard { .. }
                    | TexNode::Image { .. }
                    | TexNode::Ptex { .. }
            )
        })
    }

    /// Whether any texture reads a footprint in (u, v) (MIP-mapped images, uv-mapped
    /// checkerboards), which costs the surface's derivatives at each hit.
    pub fn uses_uv_footprint(&self) -> bool {
        self.nodes.iter().any(|n| {
            matches!(n, TexNode::Image { image, .. } if image.has_levels())
                || matches!(n, TexNode::Ptex { .. })
                || matches!(n, TexNode::Checkerboard { mapping: TexMapping::Uv { .. }, .. })
        })
    }

    /// Evaluates a spectrum texture input in the path's channels; image texels are read as
    /// spectra of kind `role` (albedo, unbounded or illuminant, as pbrt-v4's material
    /// parameters ask for them).
    #[inline]
    pub fn eval<C: Channels>(&self, t: Tex, ctx: &TexContext, lambda: &C::Lambda, role: RgbRole) -> C {
        match t {
            Tex::Const(c) => C::eval(&c, lambda),
            Tex::Node(i) => self.eval_node(&self.nodes[i as usize], ctx, lambda, role),
        }
    }

    /// Evaluates a spectrum texture input as RGB.
    #[inline]
    pub fn eval_rgb(&self, t: Tex, ctx: &TexContext) -> Rgb {
        self.eval::<Rgb>(t, ctx, &(), RgbRole::Albedo)
    }

    /// Evaluates a float texture input (first channel).
    #[inline]
    pub fn eval_float(&self, t: Tex, ctx: &TexContext) -> f32 {
        self.eval_rgb(t, ctx).x
    }

    /// True when the input varies with wavelength somewhere: a non-constant spectrum or an
    /// image with a colored texel (RGB transport then only approximates it).
    pub fn is_chromatic(&self, t: Tex) -> bool {
        match t {
            Tex::Const(c) => !c.is_constant(),
            Tex::Node(i) => match &self.nodes[i as usize] {
                TexNode::Scale { tex, scale } => self.is_chromatic(*tex) || self.is_chromatic(*scale),
                TexNode::Mix { a, b, amount } => {
                    self.is_chromatic(*a) || self.is_chromatic(*b) || self.is_chromatic(*amount)
                }
                TexNode::Checkerboard { a, b, .. } | TexNode::Checkerboard3D { a, b, .. } => {
                    self.is_chromatic(*a) || self.is_chromatic(*b)
                }
                TexNode::Bilerp { v, .. } => v.iter().any(|t| self.is_chromatic(*t)),
                TexNode::Fbm { .. } | TexNode::Wrinkled { .. } | TexNode::Windy { .. } => false,
                TexNode::Marble { .. } => true,
                TexNode::Dots { inside: a, outside: b, .. } | TexNode::DirectionMix { a, b, .. } => {
                    self.is_chromatic(*a) || self.is_chromatic(*b)
                }
                TexNode::Image { gray, .. } => !gray,
                TexNode::Ptex { texture, .. } => !texture.is_gray(),
            },
        }
    }

    fn eval_node<C: Channels>(&self, node: &TexNode, ctx: &TexContext, lambda: &C::Lambda, role: RgbRole) -> C {
        match node {
            TexNode::Scale { tex, scale } => {
                let s = self.eval_float(*scale, ctx);
                if s == 0.0 { C::ZERO } else { self.eval::<C>(*tex, ctx, lambda, role) * s }
            }
            TexNode::Mix { a, b, amount } => {
                let t = self.eval_float(*amount, ctx);
                let va = if t != 1.0 { self.eval(*a, ctx, lambda, role) } else { C::ZERO };
                let vb = if t != 0.0 { self.eval(*b, ctx, lambda, role) } else { C::ZERO };
                va * (1.0 - t) + vb * t
            }
            TexNode::Checkerboard { a, b, mapping } => {
                // pbrt-v4's filtered checkerboard over 1.5 × the (s, t) footprint (point
                // sampled without one, and for mappings other than uv).
                let st = mapping.map(ctx);
                let (dst0, dst1) = mapping.footprint(ctx);
                let w = 1.5 * dst0.abs().max(dst1.abs());
                let t = 0.5 - 0.5 * filtered_square(st.x, w.x) * filtered_square(st.y, w.y);
                let va = if t != 1.0 { self.eval(*a, ctx, lambda, role) } else { C::ZERO };
                let vb = if t != 0.0 { self.eval(*b, ctx, lambda, role) } else { C::ZERO };
                va * (1.0 - t) + vb * t
            }
            TexNode::Checkerboard3D { a, b, texture_from_world } => {
                // pbrt-v4's filtered checkerboard: the product of the three axes' box-filtered
                // square waves over 1.5 × the footprint (a triangle filter's reach).
                let p = texture_from_world.transform_point3(ctx.p);
                let (dx, dy) =
                    (texture_from_world.transform_vector3(ctx.dpdx), texture_from_world.transform_vector3(ctx.dpdy));
                let w = 1.5 * dx.abs().max(dy.abs());
                let t = 0.5 - 0.5 * filtered_square(p.x, w.x) * filtered_square(p.y, w.y) * filtered_square(p.z, w.z);
                let va = if t != 1.0 { self.eval(*a, ctx, lambda, role) } else { C::ZERO };
                let vb = if t != 0.0 { self.eval(*b, ctx, lambda, role) } else { C::ZERO };
                va * (1.0 - t) + vb * t
            }
            TexNode::Bilerp { v, mapping } => {
                let st = mapping.map(ctx);
                let (s, t) = (st.x, st.y);
                self.eval::<C>(v[0], ctx, lambda, role) * ((1.0 - s) * (1.0 - t))
                    + self.eval::<C>(v[1], ctx, lambda, role) * ((1.0 - s) * t)
                    + self.eval::<C>(v[2], ctx, lambda, role) * (s * (1.0 - t))
                    + self.eval::<C>(v[3], ctx, lambda, role) * (s * t)
            }
            TexNode::Fbm { texture_from_world, octaves, omega } => {
                let (p, dx, dy) = texture_point(texture_from_world, ctx);
                C::splat(noise::fbm(p, dx, dy, *omega, *octaves))
            }
            TexNode::Wrinkled { texture_from_world, octaves, omega } => {
                let (p, dx, dy) = texture_point(texture_from_world, ctx);
                C::splat(noise::turbulence(p, dx, dy, *omega, *octaves))
            }
            TexNode::Windy { texture_from_world } => {
                let (p, dx, dy) = texture_point(texture_from_world, ctx);
                let wind = noise::fbm(0.1 * p, 0.1 * dx, 0.1 * dy, 0.5, 3);
                let wave = noise::fbm(p, dx, dy, 0.5, 6);
                C::splat(wind.abs() * wave)
            }
            TexNode::Marble { texture_from_world, octaves, omega, scale, variation } => {
                let (p, dx, dy) = texture_point(texture_from_world, ctx);
                let (p, dx, dy) = (*scale * p, *scale * dx, *scale * dy);
                let marble = p.y + variation * noise::fbm(p, dx, dy, *omega, *octaves);
                C::from_rgb(marble_color(0.5 + 0.5 * marble.sin()), role, ColorSpace::Srgb, lambda)
            }
            TexNode::Dots { inside, outside, mapping } => {
                let st = mapping.map(ctx);
                if in_dot(st) { self.eval(*inside, ctx, lambda, role) } else { self.eval(*outside, ctx, lambda, role) }
            }
            TexNode::DirectionMix { a, b, dir } => {
                let amount = ctx.n.dot(*dir).abs();
                let va = if amount != 0.0 { self.eval(*a, ctx, lambda, role) } else { C::ZERO };
                let vb = if amount != 1.0 { self.eval(*b, ctx, lambda, role) } else { C::ZERO };
                va * amount + vb * (1.0 - amount)
            }
            TexNode::Image { image, mapping, scale, invert, space, float, .. } => {
                let mut st = mapping.map(ctx);
                // pbrt-v4 flips t so that images are not upside down.
                st.y = 1.0 - st.y;
                let (dst0, dst1) = mapping.footprint(ctx);
                let sample = image.lookup(st, dst0, dst1);
                let v = if *float { Rgb::splat(sample.float()) } else { sample.rgb } * *scale;
                let v = if *invert { (Rgb::ONE - v).max(Rgb::ZERO) } else { v.max(Rgb::ZERO) };
                C::from_rgb(v, role, *space, lambda)
            }
            TexNode::Ptex { texture, float } => {
                let v = texture.lookup(ctx.face, ctx.uv, ctx.duvdx, ctx.duvdy);
                if texture.channels() == 1 {
                    return C::splat(v[0]);
                }
                if *float {
                    return C::splat((v[0] + v[1] + v[2]) / 3.0);
                }
                // pbrt-v4 reads a ptex file's RGB in sRGB whatever the scene's colour space,
                // clamped to [0, 1] for albedos.
                let rgb = Rgb::from(v);
                let rgb = if matches!(role, RgbRole::Albedo) { rgb.clamp(Rgb::ZERO, Rgb::ONE) } else { rgb };
                C::from_rgb(rgb, role, ColorSpace::Srgb, lambda)
            }
        }
    }
}

/// pbrt-v4's marble colours: a cubic Bézier spline through nine sRGB colours, scaled by 1.5.
fn marble_color(t: f32) -> Rgb {
    const COLORS: [[f32; 3]; 9] = [
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.5, 0.5, 0.5],
        [0.6, 0.59, 0.58],
        [0.58, 0.58, 0.6],
        [0.58, 0.58, 0.6],
        [0.2, 0.2, 0.33],
        [0.58, 0.58, 0.6],
    ];
    let n_seg = COLORS.len() - 3;
    let first = ((t * n_seg as f32).floor().max(0.0) as usize).min(n_seg - 1);
    let t = t * n_seg as f32 - first as f32;
    let c = |i: usize| Rgb::from(COLORS[first + i]);
    let lerp = |t: f32, a: Rgb, b: Rgb| (1.0 - t) * a + t * b;
    let (s0, s1, s2) = (lerp(t, c(0), c(1)), lerp(t, c(1), c(2)), lerp(t, c(2), c(3)));
    let (s0, s1) = (lerp(t, s0, s1), lerp(t, s1, s2));
    (1.5 * lerp(t, s0, s1)).clamp(Rgb::ZERO, Rgb::ONE)
}

/// pbrt-v4's `dots`: whether (s, t) lies in the disc of radius 0.35 that noise places (or
/// leaves out) in its unit cell.
fn in_dot(st: Vec2) -> bool {
    let noise2 = |x: f32, y: f32| noise::noise(Vec3::new(x, y, 0.5));
    let (s_cell, t_cell) = ((st.x + 0.5).floor(), (st.y + 0.5).floor());
    if noise2(s_cell + 0.5, t_cell + 0.5) <= 0.0 {
        return false;
    }
    let (radius, max_shift) = (0.35f32, 0.5 - 0.35);
    let s_center = s_cell + max_shift * noise2(s_cell + 1.5, t_cell + 2.8);
    let t_center = t_cell + max_shift * noise2(s_cell + 4.5, t_cell + 9.8);
    (st - Vec2::new(s_center, t_center)).length_squared() < radius * radius
}

pub(crate) fn texel(image: &Image, x: i64, y: i64, wrap: Wrap) -> Rgb {
    let (w, h) = (image.width as i64, image.height as i64);
    let (x, y) = match wrap {
        Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
        Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        Wrap::Black => {
            if x < 0 || y < 0 || x >= w || y >= h {
                return Rgb::ZERO;
            }
            (x, y)
        }
    };
    image.pixels[(y * w + x) as usize]
}

/// Bilinear lookup with pixel centres at half-integers (pbrt-v4's Image::Bilerp).
pub(crate) fn bilerp(image: &Image, st: Vec2, wrap: Wrap) -> Rgb {
    let x = st.x * image.width as f32 - 0.5;
    let y = st.y * image.height as f32 - 0.5;
    let (xi, yi) = (x.floor(), y.floor());
    let (dx, dy) = (x - xi, y - yi);
    let (xi, yi) = (xi as i64, yi as i64);
    (1.0 - dx) * (1.0 - dy) * texel(image, xi, yi, wrap)
        + dx * (1.0 - dy) * texel(image, xi + 1, yi, wrap)
        + (1.0 - dx) * dy * texel(image, xi, yi + 1, wrap)
        + dx * dy * texel(image, xi + 1, yi + 1, wrap)
}

/// A 3D texture's point and footprint in texture space.
#[inline]
fn texture_point(texture_from_world: &Affine3A, ctx: &TexContext) -> (Vec3, Vec3, Vec3) {
    (
        texture_from_world.transform_point3(ctx.p),
        texture_from_world.transform_vector3(ctx.dpdx),
        texture_from_world.transform_vector3(ctx.dpdy),
    )
}

/// pbrt-v4's filtered 1D checkerboard: the square wave ±1 (+1 on even cells) averaged over
/// [x − r, x + r] (its closed-form integral); the point value where that stays in one cell.
fn filtered_square(x: f32, r: f32) -> f32 {
    if (x - r).floor() == (x + r).floor() {
        return 1.0 - 2.0 * (x.floor() as i64 & 1) as f32;
    }
    let d = |x: f32| {
        let y = x / 2.0 - (x / 2.0).floor() - 0.5;
        x / 2.0 + y * (1.0 - 2.0 * y.abs())
    };
    (d(x + r) - 2.0 * d(x) + d(x - r)) / (r * r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_and_mix() {
        let mut t = Textures::default();
        t.nodes.push(TexNode::Checkerboard {
            a: Tex::Const(SpectrumValue::constant(1.0)),
            b: Tex::Const(SpectrumValue::constant(0.0)),
            mapping: TexMapping::Uv { s: Vec2::splat(2.0), d: Vec2::ZERO },
        });
        t.nodes.push(TexNode::Mix {
            a: Tex::Node(0),
            b: Tex::Const(SpectrumValue::constant(0.5)),
            amount: Tex::Const(SpectrumValue::constant(0.5)),
        });
        let at = |u: f32, v: f32| TexContext::at(Vec3::ZERO, Vec2::new(u, v), Vec3::Z);
        assert_eq!(t.eval_rgb(Tex::Node(0), &at(0.25, 0.25)), Rgb::ONE);
        assert_eq!(t.eval_rgb(Tex::Node(0), &at(0.75, 0.25)), Rgb::ZERO);
        assert_eq!(t.eval_rgb(Tex::Node(1), &at(0.25, 0.25)), Rgb::splat(0.75));
        // With a (u, v) footprint the squares blur as pbrt-v4 blurs them: gray when it spans
        // many squares, a linear blend across an edge (u = 0.5 is one at scale 2).
        let wide = TexContext { duvdx: Vec2::splat(5.0), ..at(0.25, 0.25) };
        assert!((t.eval_rgb(Tex::Node(0), &wide).x - 0.5).abs() < 0.01);
        let edge = TexContext { duvdx: Vec2::new(0.01, 0.0), ..at(0.5, 0.25) };
        assert!((t.eval_rgb(Tex::Node(0), &edge).x - 0.5).abs() < 1e-3);
    }

    #[test]
    fn mappings_carry_the_footprint_into_s_and_t() {
        let ctx = TexContext {
            dpdx: Vec3::new(0.1, 0.0, 0.0),
            dpdy: Vec3::new(0.0, 0.0, 0.2),
            ..TexContext::at(Vec3::new(1.0, 0.0, 0.5), Vec2::ZERO, Vec3::Z)
        };
        let planar =
            TexMapping::Planar { texture_from_world: Affine3A::IDENTITY, vs: Vec3::X, vt: Vec3::Z, d: Vec2::ZERO };
        assert_eq!(planar.footprint(&ctx), (Vec2::new(0.1, 0.0), Vec2::new(0.0, 0.2)));
        // Cylindrical: φ/2π turns by 1/(2π r) per unit along the circle, t is z.
        let cylinder = TexMapping::Cylindrical { texture_from_world: Affine3A::IDENTITY };
        let (dx, dy) = cylinder.footprint(&ctx);
        assert!(dx.abs_diff_eq(Vec2::ZERO, 1e-7) && dy.abs_diff_eq(Vec2::new(0.0, 0.2), 1e-7), "{dx} {dy}");
        let along_circle = TexContext { dpdx: Vec3::new(0.0, 0.1, 0.0), ..ctx };
        let (dx, _) = cylinder.footprint(&along_circle);
        assert!((dx.x - 0.1 / (2.0 * PI)).abs() < 1e-6, "{dx}");
        // On the axis the derivatives are infinite: no footprint rather than NaN.
        let on_axis = TexContext { p: Vec3::new(0.0, 0.0, 0.5), ..ctx };
        assert_eq!(cylinder.footprint(&on_axis), (Vec2::ZERO, Vec2::ZERO));
    }

    /// pbrt-v4's 3D checkerboard: the parity of ⌊x⌋ + ⌊y⌋ + ⌊z⌋ of the texture-space point
    /// (here world space scaled by 4), negative coordinates included.
    #[test]
    fn checkerboard_in_three_dimensions() {
        let mut t = Textures::default();
        t.nodes.push(TexNode::Checkerboard3D {
            a: Tex::Const(SpectrumValue::constant(1.0)),
            b: Tex::Const(SpectrumValue::constant(0.0)),
            texture_from_world: Affine3A::from_scale(Vec3::splat(4.0)),
        });
        let at = |x: f32, y: f32, z: f32| {
            t.eval_rgb(Tex::Node(0), &TexContext::at(Vec3::new(x, y, z), Vec2::ZERO, Vec3::Z)).x
        };
        assert_eq!(at(0.1, 0.1, 0.1), 1.0);
        assert_eq!(at(0.3, 0.1, 0.1), 0.0);
        assert_eq!(at(0.3, 0.3, 0.1), 1.0);
        assert_eq!(at(0.3, 0.3, 0.3), 0.0);
        assert_eq!(at(-0.1, 0.1, 0.1), 0.0);
        assert_eq!(at(-0.1, -0.1, 0.1), 1.0);
        assert_eq!(at(-0.3, -0.1, -0.1), 1.0);
        // With a footprint, pbrt-v4 box-filters each axis over 1.5× it: a footprint far wider
        // than a cell averages to gray, a narrow one away from the edges changes nothing, and
        // across an edge it blends linearly (x = 0.25 is the edge in x at texture scale 4).
        let filtered = |p: Vec3, d: f32| {
            let ctx =
                TexContext { dpdx: Vec3::splat(d), dpdy: Vec3::splat(d), ..TexContext::at(p, Vec2::ZERO, Vec3::Z) };
            t.eval_rgb(Tex::Node(0), &ctx).x
        };
        assert!((filtered(Vec3::splat(0.1), 10.0) - 0.5).abs() < 0.01);
        assert_eq!(filtered(Vec3::splat(0.125), 0.01), 1.0);
        let edge = filtered(Vec3::new(0.25, 0.125, 0.125), 0.01);
        assert!((edge - 0.5).abs() < 1e-3, "{edge}");
    }

    #[test]
    fn image_lookup_is_bilinear_and_flipped() {
        let mut img = Image::new(2, 1);
        img.pixels = vec![Rgb::ZERO, Rgb::ONE];
        let mut t = Textures::default();
        t.nodes.push(TexNode::Image {
            image: Arc::new(MipMap::new(img, Wrap::Clamp, MipFilter::Bilinear)),
            mapping: TexMapping::Uv { s: Vec2::ONE, d: Vec2::ZERO },
            scale: 1.0,
            invert: false,
            space: ColorSpace::Srgb,
            gray: true,
            float: false,
        });
        let v = t.eval_rgb(Tex::Node(0), &TexContext::at(Vec3::ZERO, Vec2::new(0.5, 0.5), Vec3::Z));
        assert!((v.x - 0.5).abs() < 1e-6);
    }
}
