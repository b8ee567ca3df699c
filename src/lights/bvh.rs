//! pbrt-v4's light BVH (`BVHLightSampler`, pbrt-v4 book §12.6.3): lights with bounds are
//! organised in a binary tree whose nodes bound position, emission direction and power; a
//! light is chosen by descending from the root, at each node picking a child in proportion to
//! its importance for the shading point. Lights without bounds (distant, image infinite) are
//! chosen uniformly with probability `n_inf / (n_inf + 1)`.
//!
//! Differences from pbrt-v4, none of which changes an expected value: node bounds are kept in
//! full precision instead of quantised to 32 bytes, the probability of a light is computed by
//! walking from its leaf up to the root (any depth, no 32-bit trail), a uniform infinite light
//! gets no share (pbrt-v4 gives it one and then returns no sample), and a tree of one light
//! whose importance is zero reports probability 0 for it, as its sampling does.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::{Light, LightKind};
use crate::accel::{Geometry, NONE, ShapeStore};
use crate::geometry::Bounds3;
use crate::shapes::triangle_sample;

/// Where and how strongly a light (or a set of lights) can emit: pbrt-v4's `LightBounds`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Spatial bounds of the emitters.
    pub bounds: Bounds3,
    /// Central emission direction.
    pub w: Vec3,
    /// Emitted power (an upper bound's scale; only ratios matter).
    pub phi: f32,
    /// cos of the cone of normals around `w`.
    pub cos_theta_o: f32,
    /// cos of the angle beyond the normals over which light is emitted.
    pub cos_theta_e: f32,
    /// Emits on both sides of the normals.
    pub two_sided: bool,
}

impl LightBounds {
    /// Union of two bounds (pbrt-v4's `Union(LightBounds, LightBounds)`).
    fn union(a: &LightBounds, b: &LightBounds) -> LightBounds {
        if a.phi == 0.0 {
            return *b;
        }
        if b.phi == 0.0 {
            return *a;
        }
        let (w, cos_theta_o) = cone_union((a.w, a.cos_theta_o), (b.w, b.cos_theta_o));
        LightBounds {
            bounds: a.bounds.union(&b.bounds),
            w,
            phi: a.phi + b.phi,
            cos_theta_o,
            cos_theta_e: a.cos_theta_e.min(b.cos_theta_e),
            two_sided: a.two_sided | b.two_sided,
        }
    }

    fn centroid(&self) -> Vec3 {
        (self.bounds.min + self.bounds.max) * 0.5
    }

    /// The importance of these lights for a point `p` with normal `n` (zero in media).
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        NodeBounds::new(self).importance(p, n)
    }

    /// pbrt-v4's `EvaluateCost` for the split heuristic: power × solid-angle measure of the
    /// emission cone × surface area, with a penalty for thin splits along `dim`.
    fn cost(&self, parent: &Bounds3, dim: usize) -> f32 {
        let theta_o = self.cos_theta_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_theta_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = safe_sqrt(1.0 - self.cos_theta_o * self.cos_theta_o);
        let m_omega = 2.0 * PI * (1.0 - self.cos_theta_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + self.cos_theta_o);
        let d = parent.max - parent.min;
        let kr = d.max_element() / d[dim];
        let e = self.bounds.max - self.bounds.min;
        let area = 2.0 * (e.x * e.y + e.x * e.z + e.y * e.z);
        self.phi * m_omega * kr * area
    }
}

/// A node's bounds as its importance needs them, with everything that does not depend on the
/// shading point computed once.
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    /// Centre of the spatial bounds.
    pc: Vec3,
    /// Central emission direction.
    w: Vec3,
    phi: f32,
    cos_o: f32,
    sin_o: f32,
    cos_e: f32,
    /// pbrt-v4's lower clamp on the squared distance: half the diagonal's length.
    d2_min: f32,
    /// Squared radius of the bounds' bounding sphere.
    r2: f32,
    two_sided: bool,
}

impl NodeBounds {
    fn new(b: &LightBounds) -> NodeBounds {
        let pc = b.centroid();
        NodeBounds {
            pc,
            w: b.w,
            phi: b.phi,
            cos_o: b.cos_theta_o,
            sin_o: safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o),
            cos_e: b.cos_theta_e,
            d2_min: (b.bounds.max - b.bounds.min).length() * 0.5,
            r2: (b.bounds.max - pc).length_squared(),
            two_sided: b.two_sided,
        }
    }

    /// pbrt-v4's `LightBounds::Importance`: a conservative bound on what the lights can
    /// contribute at `p` (normal `n`, zero in media), phi cos θ' / d² with θ' the smallest
    /// angle between the direction to `p` and any emitter's normal cone, times the bounded
    /// cosine at a receiving surface.
    #[inline]
    fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        let to_p = p - self.pc;
        let dist2 = to_p.length_squared();
        let wi = if dist2 > 0.0 { to_p / dist2.sqrt() } else { self.w };
        let mut cos_w = self.w.dot(wi);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        // The half-angle the bounds' sphere subtends at p (everything when p is inside it).
        let (cos_b, sin_b) = if dist2 < self.r2 {
            (-1.0, 0.0)
        } else {
            let sin2 = if dist2 > 0.0 { self.r2 / dist2 } else { 0.0 };
            (safe_sqrt(1.0 - sin2), sin2.sqrt())
        };
        // θ' = max(0, θ_w − θ_o − θ_b).
        let cos_x = cos_sub_clamped(sin_w, cos_w, self.sin_o, self.cos_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, self.sin_o, self.cos_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        if cos_p <= self.cos_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / dist2.max(self.d2_min);
        if n != Vec3::ZERO {
            let cos_i = wi.dot(n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        }
        if importance.is_finite() { importance.max(0.0) } else { 0.0 }
    }
}

#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// cos(max(0, a − b)) from the sines and cosines of a and b.
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
}

/// sin(max(0, a − b)) from the sines and cosines of a and b.
#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
}

/// The smallest cone holding two cones (pbrt-v4's `Union(DirectionCone, DirectionCone)`).
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let theta_a = a.1.clamp(-1.0, 1.0).acos();
    let theta_b = b.1.clamp(-1.0, 1.0).acos();
    let theta_d = angle_between(a.0, b.0);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = (theta_a + theta_d + theta_b) / 2.0;
    if theta_o >= PI {
        return (a.0, -1.0);
    }
    // Rotate a's axis towards b's by θ_o − θ_a.
    let theta_r = theta_o - theta_a;
    let wr = a.0.cross(b.0);
    if wr.length_squared() == 0.0 {
        return (a.0, -1.0);
    }
    let w = glam::Quat::from_axis_angle(wr.normalize(), theta_r) * a.0;
    (w, theta_o.cos())
}

/// Angle between unit vectors, accurate near 0 and π (pbrt-v4's `AngleBetween`).
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() / 2.0).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).clamp(-1.0, 1.0).asin()
    }
}

/// A light's bounds, or `None` for lights at infinity (and lights that emit nothing).
pub fn light_bounds(light: &Light, shapes: &ShapeStore) -> Option<LightBounds> {
    // pbrt-v4 emits over a hemisphere beyond the normals: cos(π/2) as it computes it.
    let cos_half_pi = (PI / 2.0).cos();
    let b = match &light.kind {
        LightKind::Point { p, i } => LightBounds {
            bounds: Bounds3::new(*p, *p),
            w: Vec3::Z,
            phi: 4.0 * PI * i.rgb.max_element(),
            cos_theta_o: -1.0,
            cos_theta_e: cos_half_pi,
            two_sided: false,
        },
        // Bounded as an isotropic point light of its power (as pbrt-v4 bounds it).
        LightKind::Goniometric { p, i, image } => LightBounds {
            bounds: Bounds3::new(*p, *p),
            w: Vec3::Z,
            phi: 4.0 * PI * i.rgb.max_element() * image.mean(),
            cos_theta_o: -1.0,
            cos_theta_e: cos_half_pi,
            two_sided: false,
        },
        LightKind::Projection { p, scale, image } => LightBounds {
            bounds: Bounds3::new(*p, *p),
            w: Vec3::Z,
            phi: scale * image.power_rgb().max_element(),
            cos_theta_o: -1.0,
            cos_theta_e: cos_half_pi,
            two_sided: false,
        },
        LightKind::Spot { p, frame, i, cos_falloff_start, cos_falloff_end } => LightBounds {
            bounds: Bounds3::new(*p, *p),
            w: frame.z,
            // As for a point light: importance only compares lights.
            phi: 4.0 * PI * i.rgb.max_element(),
            cos_theta_o: *cos_falloff_start,
            cos_theta_e: (cos_falloff_end.clamp(-1.0, 1.0).acos() - cos_falloff_start.clamp(-1.0, 1.0).acos()).cos(),
            two_sided: false,
        },
        LightKind::Distant { .. }
        | LightKind::UniformInfinite { .. }
        | LightKind::ImageInfinite(_)
        | LightKind::PortalInfinite(_) => {
            return None;
        }
        LightKind::Area { geometry, l, image, two_sided, area, .. } => {
            // The cone of normals on the emitting side: flat shapes have one normal, the
            // others pbrt-v4 bounds by the whole sphere.
            let (w, cos_theta_o) = match *geometry {
                Geometry::Triangle { mesh, tri } => {
                    (triangle_sample(&shapes.meshes[mesh as usize], tri, Vec2::splat(1.0 / 3.0)).n, 1.0)
                }
                Geometry::Disk(i) => match shapes.disks[i as usize].sample_area(Vec2::splat(0.5)) {
                    Some(s) => (s.n, 1.0),
                    None => (Vec3::Z, -1.0),
                },
                // A patch's normals lie within the cone of its corners' (pbrt-v4's
                // BilinearPatch::NormalBounds).
                Geometry::Bilinear { mesh, patch } => {
                    let m = &shapes.bilinear_meshes[mesh as usize];
                    let corners =
                        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|(u, v)| m.hit(patch, 0.0, u, v).n);
                    let w = corners.iter().sum::<Vec3>().normalize_or_zero();
                    if w == Vec3::ZERO {
                        (Vec3::Z, -1.0)
                    } else {
                        (w, corners.iter().map(|n| n.dot(w)).fold(1.0, f32::min))
                    }
                }
                _ => (Vec3::Z, -1.0),
            };
            LightBounds {
                bounds: shapes.bounds(*geometry),
                w,
                // An image counts by its mean texel (pbrt-v4's `DiffuseAreaLight::Bounds`).
                phi: l.rgb.max_element()
                    * image.as_ref().map_or(1.0, |i| i.mean_channel())
                    * area
                    * PI
                    * if *two_sided { 2.0 } else { 1.0 },
                cos_theta_o,
                cos_theta_e: cos_half_pi,
                two_sided: *two_sided,
            }
        }
    };
    (b.phi.is_finite() && b.phi > 0.0 && !b.bounds.is_empty()).then_some(b)
}

/// A node: an interior node's first child follows it, `child` is the second; a leaf's
/// `child` is its light's index.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: NodeBounds,
    child: u32,
    parent: u32,
    leaf: bool,
}

/// The tree, the lights it leaves out and where each light sits.
#[derive(Clone, Debug)]
pub struct LightBvh {
    nodes: Vec<Node>,
    /// Lights sampled uniformly beside the tree (distant and image infinite lights).
    infinite: Vec<u32>,
    /// Per light: its leaf, or NONE when it is not in the tree.
    leaf_of: Vec<u32>,
    /// Per light: it is one of `infinite`.
    is_infinite: Vec<bool>,
}

const BUCKETS: usize = 12;

impl LightBvh {
    /// Builds the tree over `lights` with pbrt-v4's split heuristic (12 buckets per axis).
    pub fn new(lights: &[Light], shapes: &ShapeStore) -> LightBvh {
        let mut infinite = Vec::new();
        let mut is_infinite = vec![false; lights.len()];
        let mut items = Vec::new();
        for (i, l) in lights.iter().enumerate() {
            if !l.samples_directly() {
                continue;
            }
            match light_bounds(l, shapes) {
                Some(b) => items.push((i as u32, b)),
                None if l.is_infinite() || matches!(l.kind, LightKind::Distant { .. }) => {
                    infinite.push(i as u32);
                    is_infinite[i] = true;
                }
                None => {}
            }
        }
        let mut bvh = LightBvh { nodes: Vec::new(), infinite, leaf_of: vec![NONE; lights.len()], is_infinite };
        if !items.is_empty() {
            let n = items.len();
            bvh.build(&mut items, 0, n, NONE);
        }
        bvh
    }

    fn build(&mut self, items: &mut [(u32, LightBounds)], start: usize, end: usize, parent: u32) -> (LightBounds, u32) {
        let index = self.nodes.len() as u32;
        if end - start == 1 {
            let (light, b) = items[start];
            self.nodes.push(Node { bounds: NodeBounds::new(&b), child: light, parent, leaf: true });
            self.leaf_of[light as usize] = index;
            return (b, index);
        }
        let mut bounds = Bounds3::EMPTY;
        let mut centroids = Bounds3::EMPTY;
        for (_, b) in &items[start..end] {
            bounds = bounds.union(&b.bounds);
            centroids.extend(b.centroid());
        }
        let bucket = |c: Vec3, dim: usize| -> usize {
            let extent = centroids.max[dim] - centroids.min[dim];
            let b = (BUCKETS as f32 * (c[dim] - centroids.min[dim]) / extent) as usize;
            b.min(BUCKETS - 1)
        };
        let mut best: Option<(f32, usize, usize)> = None;
        for dim in 0..3 {
            if centroids.max[dim] == centroids.min[dim] {
                continue;
            }
            let mut buckets = [None::<LightBounds>; BUCKETS];
            for (_, b) in &items[start..end] {
                let k = bucket(b.centroid(), dim);
                buckets[k] = Some(buckets[k].map_or(*b, |a| LightBounds::union(&a, b)));
            }
            let union_of = |range: &[Option<LightBounds>]| {
                range
                    .iter()
                    .flatten()
                    .fold(None::<LightBounds>, |acc, b| Some(acc.map_or(*b, |a| LightBounds::union(&a, b))))
            };
            // pbrt-v4 considers splits after buckets 1..=10 (never after bucket 0).
            for split in 1..BUCKETS - 1 {
                let cost = union_of(&buckets[..=split]).map_or(0.0, |b| b.cost(&bounds, dim))
                    + union_of(&buckets[split + 1..]).map_or(0.0, |b| b.cost(&bounds, dim));
                if cost > 0.0 && best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, dim, split));
                }
            }
        }
        let mut mid = (start + end) / 2;
        if let Some((_, dim, split)) = best {
            let slice = &mut items[start..end];
            let mut left = 0;
            for k in 0..slice.len() {
                if bucket(slice[k].1.centroid(), dim) <= split {
                    slice.swap(left, k);
                    left += 1;
                }
            }
            if left != 0 && left != slice.len() {
                mid = start + left;
            }
        }
        self.nodes.push(Node { bounds: NodeBounds::new(&items[start].1), child: NONE, parent, leaf: false });
        let (b0, _) = self.build(items, start, mid, index);
        let (b1, second) = self.build(items, mid, end, index);
        let b = LightBounds::union(&b0, &b1);
        let node = &mut self.nodes[index as usize];
        node.bounds = NodeBounds::new(&b);
        node.child = second;
        (b, index)
    }

    fn p_infinite(&self) -> f32 {
        let n = self.infinite.len() as f32;
        n / (n + if self.nodes.is_empty() { 0.0 } else { 1.0 })
    }

    /// Picks a light for a point `p` with normal `n` (zero in media): (index, probability).
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(usize, f32)> {
        let p_inf = self.p_infinite();
        if u < p_inf {
            let k = ((u / p_inf * self.infinite.len() as f32) as usize).min(self.infinite.len() - 1);
            return Some((self.infinite[k] as usize, p_inf / self.infinite.len() as f32));
        }
        if self.nodes.is_empty() {
            return None;
        }
        let mut u = ((u - p_inf) / (1.0 - p_inf)).min(1.0 - f32::EPSILON / 2.0);
        let mut pmf = 1.0 - p_inf;
        let mut index = 0usize;
        loop {
            let node = &self.nodes[index];
            if node.leaf {
                if index > 0 || node.bounds.importance(p, n) > 0.0 {
                    return Some((node.child as usize, pmf));
                }
                return None;
            }
            let c0 = self.nodes[index + 1].bounds.importance(p, n);
            let c1 = self.nodes[node.child as usize].bounds.importance(p, n);
            if c0 == 0.0 && c1 == 0.0 {
                return None;
            }
            let p0 = c0 / (c0 + c1);
            if u < p0 {
                u = (u / p0).min(1.0 - f32::EPSILON / 2.0);
                pmf *= p0;
                index += 1;
            } else {
                u = ((u - p0) / (1.0 - p0)).min(1.0 - f32::EPSILON / 2.0);
                pmf *= 1.0 - p0;
                index = node.child as usize;
            }
        }
    }

    /// Whether [`LightBvh::sample`] reads its `u`: with one light or none to choose from it
    /// does not (a tree of n leaves has 2n − 1 nodes).
    pub fn reads_sample(&self) -> bool {
        self.infinite.len() + self.nodes.len() > 1
    }

    /// The probability that [`LightBvh::sample`] picks light `light` for `p` and `n`.
    pub fn pmf(&self, p: Vec3, n: Vec3, light: usize) -> f32 {
        if self.is_infinite[light] {
            return 1.0 / (self.infinite.len() as f32 + if self.nodes.is_empty() { 0.0 } else { 1.0 });
        }
        let leaf = self.leaf_of[light];
        if leaf == NONE {
            return 0.0;
        }
        if leaf == 0 {
            return if self.nodes[0].bounds.importance(p, n) > 0.0 { 1.0 - self.p_infinite() } else { 0.0 };
        }
        let mut pmf = 1.0 - self.p_infinite();
        let mut index = leaf;
        while index != 0 {
            let parent = self.nodes[index as usize].parent;
            let pn = &self.nodes[parent as usize];
            let c0 = self.nodes[parent as usize + 1].bounds.importance(p, n);
            let c1 = self.nodes[pn.child as usize].bounds.importance(p, n);
            let c = if index == parent + 1 { c0 } else { c1 };
            if c == 0.0 {
                return 0.0;
            }
            pmf *= c / (c0 + c1);
            index = parent;
        }
        pmf
    }

    /// Number of tree nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

#[cfg(test)]
mod tests {
    use glam::Affine3A;

    use super::*;
    use crate::math::Frame;
    use crate::sampling::rng::Pcg32;
    use crate::shapes::Mesh;
    use crate::spectra::SpectrumValue;

    /// A mix of point, spot, one- and two-sided triangle lights and two infinite ones.
    fn many_lights(rng: &mut Pcg32) -> (Vec<Light>, ShapeStore) {
        let mut shapes = ShapeStore::default();
        let mut lights = Vec::new();
        let mut v = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 8.0 - 4.0;
        for k in 0..40 {
            let p = v();
            let i = SpectrumValue::constant(0.5 + (k % 7) as f32);
            let kind = match k % 4 {
                0 => LightKind::Point { p, i },
                1 => LightKind::Spot {
                    p,
                    frame: Frame::from_z(v().normalize()),
                    i,
                    cos_falloff_start: 0.9,
                    cos_falloff_end: 0.6,
                },
                _ => {
                    let (a, b) = (v() * 0.1, v() * 0.1);
                    let mesh = Mesh::new(
                        &Affine3A::IDENTITY,
                        false,
                        &[p.into(), (p + a).into(), (p + b).into()],
                        &[],
                        &[],
                        vec![0, 1, 2],
                    );
                    let area = mesh.triangle_area(0);
                    shapes.meshes.push(mesh);
                    LightKind::Area {
                        geometry: Geometry::Triangle { mesh: shapes.meshes.len() as u32 - 1, tri: 0 },
                        l: i,
                        image: None,
                        two_sided: k % 4 == 3,
                        area,
                        interface: NONE,
                        alpha: NONE,
                        invisible: false,
                    }
                }
            };
            lights.push(Light { kind, medium: NONE });
        }
        lights.push(Light { kind: LightKind::Distant { w: Vec3::Z, l: SpectrumValue::constant(1.0) }, medium: NONE });
        lights.push(Light { kind: LightKind::UniformInfinite { l: SpectrumValue::constant(1.0) }, medium: NONE });
        (lights, shapes)
    }

    #[test]
    fn sampling_frequencies_match_the_pmf() {
        let mut rng = Pcg32::new(7, 11);
        let (lights, shapes) = many_lights(&mut rng);
        let bvh = LightBvh::new(&lights, &shapes);
        assert!(bvh.node_count() == 2 * 40 - 1);
        for trial in 0..8 {
            let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0 - 5.0;
            let n = if trial % 2 == 0 { Vec3::ZERO } else { Frame::from_z(p.normalize()).z };
            let pmfs: Vec<f64> = (0..lights.len()).map(|i| bvh.pmf(p, n, i) as f64).collect();
            let total: f64 = pmfs.iter().sum();
            assert!(total <= 1.0 + 1e-5, "{total}");
            assert_eq!(pmfs[lights.len() - 1], 0.0, "a uniform environment is not sampled");
            assert!((pmfs[lights.len() - 2] - 0.5).abs() < 1e-6, "one infinite light beside the tree");
            const N: usize = 200_000;
            let mut counts = vec![0usize; lights.len()];
            let mut none = 0;
            for k in 0..N {
                let u = (k as f32 + rng.uniform()) / N as f32;
                match bvh.sample(p, n, u) {
                    Some((i, pmf)) => {
                        assert!((pmf as f64 - pmfs[i]).abs() <= 1e-4 * pmfs[i], "{pmf} vs {}", pmfs[i]);
                        counts[i] += 1;
                    }
                    None => none += 1,
                }
            }
            // Stratified u: frequencies are within a few counts of N × pmf.
            for (i, &c) in counts.iter().enumerate() {
                let expected = N as f64 * pmfs[i];
                assert!((c as f64 - expected).abs() <= 3.0 + 1e-3 * expected, "light {i}: {c} vs {expected}");
            }
            assert!((none as f64 - N as f64 * (1.0 - total)).abs() <= 3.0 + 1e-3 * N as f64);
        }
    }

    /// With one light to choose (in the tree or beside it) or none, the pick does not depend
    /// on `u` and the sampler says it does not read it (the path loop then skips the
    /// dimension); with two it does.
    #[test]
    fn a_single_light_is_picked_whatever_u() {
        let mut rng = Pcg32::new(5, 9);
        let (all, shapes) = many_lights(&mut rng);
        let (distant, uniform) = (all[all.len() - 2].clone(), all[all.len() - 1].clone());
        let (point, spot) = (all[0].clone(), all[1].clone());
        let p = Vec3::new(0.3, -0.2, 0.1);
        for (lights, reads) in [
            (vec![], false),
            (vec![uniform.clone()], false),
            (vec![distant.clone(), uniform.clone()], false),
            (vec![uniform.clone(), point.clone()], false),
            (vec![point.clone(), distant.clone()], true),
            (vec![point.clone(), spot.clone()], true),
        ] {
            let bvh = LightBvh::new(&lights, &shapes);
            assert_eq!(bvh.reads_sample(), reads, "{} lights", lights.len());
            if !reads {
                let first = bvh.sample(p, Vec3::ZERO, 0.5);
                for k in 0..100 {
                    assert_eq!(bvh.sample(p, Vec3::ZERO, k as f32 / 100.0), first);
                }
            }
        }
    }

    #[test]
    fn nothing_is_chosen_behind_a_one_sided_emitter() {
        let mut shapes = ShapeStore::default();
        shapes.meshes.push(Mesh::new(
            &Affine3A::IDENTITY,
            false,
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[],
            &[],
            vec![0, 1, 2],
        ));
        let area = |two_sided| Light {
            kind: LightKind::Area {
                geometry: Geometry::Triangle { mesh: 0, tri: 0 },
                l: SpectrumValue::constant(1.0),
                image: None,
                two_sided,
                area: 0.5,
                interface: NONE,
                alpha: NONE,
                invisible: false,
            },
            medium: NONE,
        };
        let one = LightBvh::new(&[area(false)], &shapes);
        let (front, back) = (Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.2, 0.2, -1.0));
        assert_eq!(one.sample(front, Vec3::ZERO, 0.5), Some((0, 1.0)));
        assert_eq!(one.pmf(front, Vec3::ZERO, 0), 1.0);
        assert_eq!(one.sample(back, Vec3::ZERO, 0.5), None);
        assert_eq!(one.pmf(back, Vec3::ZERO, 0), 0.0);
        let two = LightBvh::new(&[area(true)], &shapes);
        assert_eq!(two.pmf(back, Vec3::ZERO, 0), 1.0);
    }

    #[test]
    fn importance_prefers_near_and_facing_lights() {
        let point = |p: Vec3| LightBounds {
            bounds: Bounds3::new(p, p),
            w: Vec3::Z,
            phi: 1.0,
            cos_theta_o: -1.0,
            cos_theta_e: (PI / 2.0).cos(),
            two_sided: false,
        };
        // Inverse square falloff for points.
        let (near, far) = (point(Vec3::new(0.0, 0.0, 1.0)), point(Vec3::new(0.0, 0.0, 2.0)));
        assert!((near.importance(Vec3::ZERO, Vec3::ZERO) / far.importance(Vec3::ZERO, Vec3::ZERO) - 4.0).abs() < 1e-5);
        // A receiving surface's cosine, exact for a point.
        let side = point(Vec3::new(1.0, 0.0, 1.0));
        let i = side.importance(Vec3::ZERO, Vec3::Z);
        assert!((i - 0.5 * std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6, "{i}");
        assert!(side.importance(Vec3::ZERO, Vec3::X) > 0.0);
    }

    #[test]
    fn cone_union_holds_both_cones() {
        let mut rng = Pcg32::new(3, 5);
        for _ in 0..1000 {
            let d = |rng: &mut Pcg32| {
                Frame::from_z(Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5).normalize()).z
            };
            let a = (d(&mut rng), rng.uniform() * 2.0 - 1.0);
            let b = (d(&mut rng), rng.uniform() * 2.0 - 1.0);
            let (w, cos) = cone_union(a, b);
            for (axis, c) in [a, b] {
                // The union's half-angle covers each cone's axis offset plus its half-angle.
                let needed = angle_between(w, axis) + c.acos();
                assert!(cos <= needed.min(PI).cos() + 1e-4, "{cos} vs {needed}");
            }
        }
    }
}
