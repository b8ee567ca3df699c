//! Building an [`Accel`]. Up to [`SPLIT_ABOVE`] primitives get one BVH. Above that the
//! primitives are put in Morton order of their centroids and cut into parts of [`PART_SIZE`],
//! each with a BVH of its own under a BVH over the parts. obvhs's PLOC builder needs about
//! 260 bytes per primitive while it runs (Morton codes, two node buffers); built a part at a
//! time, that is the parts' size, not the scene's: a displaced mesh of millions of triangles
//! peaks at the primitives, their bounds and the finished BVH.

use std::time::Duration;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::{Boundable, BvhBuildParams};
use rayon::prelude::*;

use super::{Accel, Part, Primitive};
use crate::geometry::Bounds3;

/// Primitives per part of a BVH built in parts.
const PART_SIZE: usize = 1 << 16;

/// Above this many primitives a BVH is built in parts. Below it the builder's temporaries are
/// under 70 MB, and one BVH traverses a little faster.
const SPLIT_ABOVE: usize = 4 * PART_SIZE;

/// obvhs's medium build's leaf size (it allows at most 3).
const PRIMS_PER_LEAF: u32 = 8;

struct Bound(Aabb);

impl Boundable for Bound {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// A BVH over `bounds` with at most `per_leaf` of them in a leaf, and the leaf order of their
/// indices (its own copy of the order is dropped: traversal reports leaf positions).
fn bvh_over(bounds: &[Bounds3], per_leaf: u32) -> (CwBvh, Vec<u32>) {
    let aabbs: Vec<Bound> = bounds.iter().map(|b| Bound(Aabb::new(Vec3A::from(b.min), Vec3A::from(b.max)))).collect();
    let params = BvhBuildParams { max_prims_per_leaf: per_leaf, ..BvhBuildParams::medium_build() };
    let mut bvh = build_cwbvh(&aabbs, params, &mut Duration::default());
    let order = std::mem::take(&mut bvh.primitive_indices);
    (bvh, order)
}

impl Accel {
    /// Builds a BVH over `prims` whose bounds are `bounds[i]`. `None` for no primitives.
    pub fn build(prims: Vec<Primitive>, bounds: Vec<Bounds3>) -> Option<Accel> {
        let part_size = if prims.len() > SPLIT_ABOVE { PART_SIZE } else { usize::MAX };
        Accel::build_in_parts(prims, bounds, part_size)
    }

    /// [`Accel::build`] with parts of `part_size` primitives when there are more than that.
    pub(super) fn build_in_parts(
        mut prims: Vec<Primitive>,
        mut bounds: Vec<Bounds3>,
        part_size: usize,
    ) -> Option<Accel> {
        if prims.is_empty() {
            return None;
        }
        let total = bounds.iter().fold(Bounds3::EMPTY, |t, b| t.union(b));
        if prims.len() <= part_size {
            let (bvh, order) = bvh_over(&bounds, PRIMS_PER_LEAF);
            let prims = order.iter().map(|&i| prims[i as usize]).collect();
            return Some(Accel { bvh, prims, parts: Vec::new(), bounds: total });
        }
        morton_order(&mut prims, &mut bounds, &total);
        // Each part's primitives are put in its leaf order where they are.
        let built: Vec<(CwBvh, Bounds3)> = prims
            .par_chunks_mut(part_size)
            .zip(bounds.par_chunks(part_size))
            .map(|(p, b)| {
                let (bvh, order) = bvh_over(b, PRIMS_PER_LEAF);
                let before = p.to_vec();
                for (dst, &i) in p.iter_mut().zip(&order) {
                    *dst = before[i as usize];
                }
                (bvh, b.iter().fold(Bounds3::EMPTY, |t, b| t.union(b)))
            })
            .collect();
        drop(bounds);
        let part_bounds: Vec<Bounds3> = built.iter().map(|(_, b)| *b).collect();
        // One part per leaf: a leaf's primitives are visited in their stored order, not nearest
        // first, and a part is worth its own box test.
        let (bvh, order) = bvh_over(&part_bounds, 1);
        let mut built: Vec<Option<CwBvh>> = built.into_iter().map(|(b, _)| Some(b)).collect();
        // The top BVH's leaves name the parts in its leaf order.
        let parts = order
            .iter()
            .map(|&k| Part { bvh: built[k as usize].take().expect("each part once"), start: k * part_size as u32 })
            .collect();
        Some(Accel { bvh, prims, parts, bounds: total })
    }
}

/// Sorts `prims` and `bounds` together by the Morton code of the bounds' centroids in `total`,
/// in place (the permutation is the only copy: 8 bytes per primitive).
fn morton_order(prims: &mut [Primitive], bounds: &mut [Bounds3], total: &Bounds3) {
    // One scale for all axes: cells are cubes, so a flat mesh is cut across its plane, not
    // into layers that overlap along it.
    let extent = (total.max - total.min).max_element().max(f32::MIN_POSITIVE);
    let mut keys: Vec<u64> = bounds
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let c = ((b.min + b.max) * 0.5 - total.min) / extent;
            let q = (c * 1023.0).clamp(glam::Vec3::ZERO, glam::Vec3::splat(1023.0)).as_uvec3();
            (morton3(q.x) | morton3(q.y) << 1 | morton3(q.z) << 2) << 32 | i as u64
        })
        .collect();
    keys.par_sort_unstable();
    // Cycle by cycle: position j takes what was at keys[j]'s index; a done position's key is
    // marked with u64::MAX.
    const DONE: u64 = u64::MAX;
    for start in 0..keys.len() {
        if keys[start] == DONE {
            continue;
        }
        let (p0, b0) = (prims[start], bounds[start]);
        let mut j = start;
        loop {
            let from = (keys[j] & 0xffff_ffff) as usize;
            keys[j] = DONE;
            if from == start {
                prims[j] = p0;
                bounds[j] = b0;
                break;
            }
            prims[j] = prims[from];
            bounds[j] = bounds[from];
            j = from;
        }
    }
}

/// The 10 bits of `v` spread to every third bit.
fn morton3(v: u32) -> u64 {
    let mut x = (v & 0x3ff) as u64;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    x = (x | x << 2) & 0x0924_9249;
    x
}

#[cfg(test)]
mod tests {
    use glam::{Affine3A, Vec3};

    use super::*;
    use crate::accel::{Geometry, NONE, Surfaces};
    use crate::geometry::Ray;
    use crate::shapes::{Mesh, Sphere};

    /// A BVH built in parts finds the same closest hits and occlusions as one BVH over the same
    /// primitives: a crumpled grid of triangles with spheres among them, 3,000 random rays.
    #[test]
    fn parts_find_what_one_bvh_finds() {
        let mut rng = crate::sampling::rng::Pcg32::new(7, 0);
        let n = 40;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32 * 2.0 - 1.0, j as f32 / n as f32 * 2.0 - 1.0);
                positions.push([x, y, 0.2 * (5.0 * x).sin() * (4.0 * y).cos()]);
            }
        }
        let mut indices = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                indices.extend_from_slice(&[v, v + 1, v + n + 2, v, v + n + 2, v + n + 1]);
            }
        }
        let mut s = Surfaces::default();
        s.shapes.meshes.push(Mesh::new(&Affine3A::IDENTITY, false, &positions, &[], &[], indices));
        let prim =
            |geometry, material| Primitive { geometry, material, area_light: NONE, interface: NONE, alpha: NONE };
        let mut prims: Vec<Primitive> =
            (0..2 * n * n).map(|tri| prim(Geometry::Triangle { mesh: 0, tri }, tri % 7)).collect();
        for k in 0..50 {
            let c = Vec3::new(rng.uniform() * 2.0 - 1.0, rng.uniform() * 2.0 - 1.0, rng.uniform() - 0.5);
            s.shapes.spheres.push(Sphere::new(Affine3A::from_translation(c), false, 0.05, -0.05, 0.05, 360.0));
            prims.push(prim(Geometry::Sphere(k), 100 + k));
        }
        let bounds: Vec<Bounds3> = prims.iter().map(|p| s.shapes.bounds(p.geometry)).collect();
        let one = Accel::build_in_parts(prims.clone(), bounds.clone(), usize::MAX).unwrap();
        let parted = Accel::build_in_parts(prims, bounds, 64).unwrap();
        assert!(one.parts.is_empty() && parted.parts.len() > 40);
        let mut sorted: Vec<Primitive> = parted.primitives().to_vec();
        sorted.sort_by_key(|p| (p.material, format!("{:?}", p.geometry)));
        let mut expected: Vec<Primitive> = one.primitives().to_vec();
        expected.sort_by_key(|p| (p.material, format!("{:?}", p.geometry)));
        assert_eq!(sorted, expected, "every primitive once");
        let (mut hits, mut blocked) = (0, 0);
        for _ in 0..3000 {
            let o = Vec3::new(rng.uniform() * 3.0 - 1.5, rng.uniform() * 3.0 - 1.5, rng.uniform() * 2.0 - 1.0);
            // Two rays in three aimed at the grid, the rest anywhere.
            let target = Vec3::new(rng.uniform() * 2.0 - 1.0, rng.uniform() * 2.0 - 1.0, 0.0);
            let random = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
            let d = if rng.uniform() < 0.67 { target - o } else { random }.normalize();
            let ray = Ray::new(o, d);
            let t_max = rng.uniform() * 3.0;
            let (mut a, mut b) = (None, None);
            one.closest(&s, &ray, f32::INFINITY, NONE, &mut a);
            parted.closest(&s, &ray, f32::INFINITY, NONE, &mut b);
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert_eq!((a.t, a.prim), (b.t, b.prim));
                    hits += 1;
                }
                _ => panic!("{a:?} vs {b:?}"),
            }
            let occluded = one.any(&s, &ray, t_max, NONE);
            assert_eq!(occluded, parted.any(&s, &ray, t_max, NONE));
            blocked += occluded as u32;
        }
        assert!(hits > 1500 && blocked > 1000, "{hits} hits, {blocked} blocked");
    }

    #[test]
    fn morton_spreads_bits() {
        assert_eq!(morton3(0b11), 0b1001);
        assert_eq!(morton3(0x3ff), 0x0924_9249);
    }
}
