//! The spatial part of an SD-tree (Müller et al. 2017, Sec. 3.1; Deng et al. 2020, Sec. 4.1):
//! a binary tree over a medium's bounds, split at the middle along x, y, z in turn, with a
//! directional quadtree ([`DTree`]) in each leaf.

use glam::Vec3;

use super::dtree::DTree;
use crate::geometry::Bounds3;

/// A node of the spatial tree: a leaf holds a directional tree, an inner node two children
/// (at `child` and `child + 1`) split at the middle of axis `axis`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    axis: u8,
    /// First child, or 0 for a leaf (the root is node 0).
    child: u32,
    /// The leaf's directional tree.
    dtree: u32,
}

/// An SD-tree over one medium.
#[derive(Clone, Debug, PartialEq)]
pub struct SdTree {
    bounds: Bounds3,
    nodes: Vec<Node>,
    dtrees: Vec<DTree>,
}

impl SdTree {
    /// One leaf over `bounds`.
    pub fn new(bounds: Bounds3) -> SdTree {
        SdTree { bounds, nodes: vec![Node { axis: 0, child: 0, dtree: 0 }], dtrees: vec![DTree::new()] }
    }

    /// The box the tree covers.
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// The leaves' directional trees.
    pub fn dtrees(&self) -> &[DTree] {
        &self.dtrees
    }

    /// The leaves' directional trees, to deposit into.
    pub fn dtrees_mut(&mut self) -> &mut [DTree] {
        &mut self.dtrees
    }

    /// The nodes as (axis, first child, directional tree) and the directional trees, for
    /// saving.
    pub fn parts(&self) -> (Vec<(u8, u32, u32)>, &[DTree]) {
        (self.nodes.iter().map(|n| (n.axis, n.child, n.dtree)).collect(), &self.dtrees)
    }

    /// A tree from [`SdTree::parts`], checked: axes are x, y or z, children come after their
    /// parent and exist, leaves name existing directional trees.
    pub fn from_parts(bounds: Bounds3, nodes: Vec<(u8, u32, u32)>, dtrees: Vec<DTree>) -> crate::Result<SdTree> {
        if nodes.is_empty() || !(bounds.min.is_finite() && bounds.max.is_finite() && bounds.min.cmple(bounds.max).all())
        {
            return Err(crate::Error::invalid("a spatial tree has no nodes or invalid bounds"));
        }
        for (i, &(axis, child, dtree)) in nodes.iter().enumerate() {
            let bad_child = child != 0 && (child as usize <= i || child as usize + 1 >= nodes.len());
            if axis > 2 || bad_child || (child == 0 && dtree as usize >= dtrees.len()) {
                return Err(crate::Error::Invalid(format!("spatial node {i} is invalid")));
            }
        }
        let nodes = nodes.into_iter().map(|(axis, child, dtree)| Node { axis, child, dtree }).collect();
        Ok(SdTree { bounds, nodes, dtrees })
    }

    /// Spatial nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes of the spatial and directional nodes.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.dtrees.iter().map(DTree::memory_bytes).sum::<usize>()
    }

    /// The index of the leaf holding `p` (points outside the bounds go to the nearest leaf).
    #[inline]
    pub fn leaf(&self, p: Vec3) -> usize {
        let (mut lo, mut hi) = (self.bounds.min, self.bounds.max);
        let p = p.clamp(lo, hi);
        let mut node = self.nodes[0];
        while node.child != 0 {
            let a = node.axis as usize;
            let mid = 0.5 * (lo[a] + hi[a]);
            if p[a] < mid {
                hi[a] = mid;
                node = self.nodes[node.child as usize];
            } else {
                lo[a] = mid;
                node = self.nodes[node.child as usize + 1];
            }
        }
        node.dtree as usize
    }

    /// Splits every leaf holding more than `threshold` photons (Müller et al.: c·√(2^k) in
    /// iteration k) in two, the children starting from copies of the parent's directional
    /// tree with half its count, until no leaf holds more or the tree would exceed
    /// `max_bytes`.
    pub fn split(&mut self, threshold: u64, max_bytes: usize) {
        let mut bytes = self.memory_bytes();
        let mut stack: Vec<usize> = (0..self.nodes.len()).filter(|&i| self.nodes[i].child == 0).collect();
        while let Some(i) = stack.pop() {
            let node = self.nodes[i];
            let parent = &self.dtrees[node.dtree as usize];
            if parent.count() <= threshold {
                continue;
            }
            let extra = 2 * std::mem::size_of::<Node>() + parent.memory_bytes();
            if bytes + extra > max_bytes {
                continue;
            }
            bytes += extra;
            let half = parent.with_count(parent.count() / 2);
            let first = self.nodes.len();
            let axis = (node.axis + 1) % 3;
            // The left child keeps the parent's directional tree slot, the right one gets a
            // new slot.
            self.dtrees[node.dtree as usize] = half.clone();
            self.dtrees.push(half);
            self.nodes.push(Node { axis, child: 0, dtree: node.dtree });
            self.nodes.push(Node { axis, child: 0, dtree: (self.dtrees.len() - 1) as u32 });
            self.nodes[i].child = first as u32;
            stack.push(first);
            stack.push(first + 1);
        }
    }

    /// The volume of each directional tree's leaf (by directional tree index).
    pub fn leaf_volumes(&self) -> Vec<f32> {
        let mut out = vec![0.0; self.dtrees.len()];
        let mut stack = vec![(0usize, self.bounds)];
        while let Some((i, b)) = stack.pop() {
            let n = self.nodes[i];
            if n.child == 0 {
                let d = b.max - b.min;
                out[n.dtree as usize] = d.x * d.y * d.z;
                continue;
            }
            let a = n.axis as usize;
            let mid = 0.5 * (b.min[a] + b.max[a]);
            let (mut lo, mut hi) = (b, b);
            lo.max[a] = mid;
            hi.min[a] = mid;
            stack.push((n.child as usize, lo));
            stack.push((n.child as usize + 1, hi));
        }
        out
    }

    /// Rebuilds every directional tree for the next round of learning
    /// ([`DTree::refined`]).
    pub fn refine(&mut self, threshold: f32) {
        for d in &mut self.dtrees {
            *d = d.refined(threshold);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaves_split_where_the_photons_are() {
        let b = Bounds3::new(Vec3::ZERO, Vec3::ONE);
        let mut t = SdTree::new(b);
        // 1000 photons in the corner near the origin.
        for i in 0..1000 {
            let p = Vec3::splat(0.1 + 0.0001 * i as f32);
            let l = t.leaf(p);
            t.dtrees_mut()[l].deposit(Vec3::Z, 1.0);
        }
        t.split(100, usize::MAX);
        // Children inherit half the parent's count whatever the photons' positions (the next
        // round counts anew): halving 1000 down to ≤ 100 takes 4 splits, everywhere.
        let corner = t.leaf(Vec3::splat(0.1));
        assert_eq!(t.dtrees()[corner].count(), 1000 / 16);
        assert_eq!(t.dtrees().len(), 16);
        assert_ne!(t.leaf(Vec3::splat(0.9)), corner);
        // Leaves partition space: every point finds one, points outside clamp.
        assert_eq!(t.leaf(Vec3::splat(-5.0)), corner);
        // A memory limit stops the splitting.
        let mut small = SdTree::new(b);
        small.dtrees_mut()[0].deposit(Vec3::Z, 1.0);
        let before = small.memory_bytes();
        let mut s2 = small.clone();
        s2.split(0, before);
        assert_eq!(s2.node_count(), 1);
        small.split(0, usize::MAX);
        assert_eq!(small.node_count(), 3, "one photon, threshold 0: one split, to halves of count 0");
    }
}
