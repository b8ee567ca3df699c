//! Nearest-centre queries for clustering (Sec. 4: every shading point joins its nearest
//! centre): a k-d tree over the centres, searched exactly.
//!
//! Points gather where paths scatter most (near a camera, an emitter, a dense core), which a
//! uniform hash grid handled with crowded or empty cells (its search was 22 % of a
//! fog-emitter render). The tree splits each node at the median of its centres' widest axis.
//! kiddo's trees, used before, cycle through the axes: on points of a floor every third split
//! is across the floor's own axis with every point on the split plane, so each query searched
//! both sides there and floor points cost 4× a medium point (fog-emitter at 512×384: the
//! floor's 124 k points took 54 ms per sample, now 14 ms; the medium's 864 k, 147 ms, now
//! 148–157 ms with 24 centres per leaf).

use glam::Vec3;

/// Centres per leaf, at most.
const LEAF: usize = 24;

#[derive(Clone, Copy, Debug)]
enum Node {
    /// Points with `p[axis] < at` belong to `left`, the others to `right`.
    Split { axis: u8, at: f32, left: u32, right: u32 },
    /// Centres `start..end` of the leaf-ordered arrays.
    Leaf { start: u32, end: u32 },
}

/// A k-d tree over cluster centres.
pub struct CentreTree {
    nodes: Vec<Node>,
    /// Centre positions and ranks in leaf order.
    pos: Vec<Vec3>,
    rank: Vec<u32>,
}

impl CentreTree {
    /// A tree over the centres at `pos` (rank = index).
    pub fn new(pos: &[Vec3]) -> CentreTree {
        assert!(!pos.is_empty(), "no centres");
        let mut order: Vec<u32> = (0..pos.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * pos.len() / LEAF + 1);
        build(pos, &mut order, 0, &mut nodes);
        CentreTree { nodes, pos: order.iter().map(|&r| pos[r as usize]).collect(), rank: order }
    }

    /// The rank of the centre nearest to `q` (of equally near ones, the one first in leaf
    /// order).
    #[inline]
    pub fn nearest(&self, q: Vec3) -> u32 {
        let mut best = (f32::INFINITY, 0u32);
        self.search(0, q, &mut best);
        self.rank[best.1 as usize]
    }

    fn search(&self, i: usize, q: Vec3, best: &mut (f32, u32)) {
        match self.nodes[i] {
            Node::Leaf { start, end } => {
                for k in start..end {
                    let d = (self.pos[k as usize] - q).length_squared();
                    if d < best.0 {
                        *best = (d, k);
                    }
                }
            }
            Node::Split { axis, at, left, right } => {
                let d = q[axis as usize] - at;
                let (near, far) = if d < 0.0 { (left, right) } else { (right, left) };
                self.search(near as usize, q, best);
                if d * d < best.0 {
                    self.search(far as usize, q, best);
                }
            }
        }
    }
}

/// Appends the subtree over `order` (centre ranks; `base` is its offset in the leaf order)
/// to `nodes`, returning its index.
fn build(pos: &[Vec3], order: &mut [u32], base: usize, nodes: &mut Vec<Node>) -> u32 {
    let id = nodes.len() as u32;
    let (lo, hi) = order
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &r| (lo.min(pos[r as usize]), hi.max(pos[r as usize])));
    let extent = hi - lo;
    // Coincident centres cannot be told apart by splitting: one leaf holds them all.
    if order.len() <= LEAF || extent.max_element() <= 0.0 {
        nodes.push(Node::Leaf { start: base as u32, end: (base + order.len()) as u32 });
        return id;
    }
    nodes.push(Node::Leaf { start: 0, end: 0 });
    let axis = extent.max_position();
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| pos[a as usize][axis].total_cmp(&pos[b as usize][axis]).then(a.cmp(&b)));
    let at = pos[order[mid] as usize][axis];
    let (a, b) = order.split_at_mut(mid);
    let left = build(pos, a, base, nodes);
    let right = build(pos, b, base + mid, nodes);
    nodes[id as usize] = Node::Split { axis: axis as u8, at, left, right };
    id
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(i: u64) -> f32 {
        let mut z = i.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }

    fn check(centres: &[Vec3], queries: &[Vec3]) {
        let tree = CentreTree::new(centres);
        for (k, &q) in queries.iter().enumerate() {
            let brute = centres.iter().map(|c| (*c - q).length_squared()).fold(f32::INFINITY, f32::min);
            let got = (centres[tree.nearest(q) as usize] - q).length_squared();
            assert_eq!(got, brute, "query {k} at {q}");
        }
    }

    #[test]
    fn nearest_in_a_clumped_volume() {
        let p = |i: u64| Vec3::new(unit(3 * i), unit(3 * i + 1), unit(3 * i + 2));
        // Half the points squeezed towards a corner, as paths gather near a camera.
        let pick = |i: u64| if i.is_multiple_of(2) { p(i) } else { p(i) * p(i) * 0.1 };
        let centres: Vec<Vec3> = (0..2_000).map(pick).collect();
        let queries: Vec<Vec3> = (10_000..30_000).map(pick).collect();
        check(&centres, &queries);
    }

    #[test]
    fn nearest_on_a_plane_and_beyond_the_centres() {
        let centres: Vec<Vec3> = (0..500).map(|i| Vec3::new(unit(2 * i), 0.0, unit(2 * i + 1))).collect();
        let queries: Vec<Vec3> =
            (1000..6000).map(|i| Vec3::new(3.0 * unit(2 * i) - 1.0, 0.0, 3.0 * unit(2 * i + 1) - 1.0)).collect();
        check(&centres, &queries);
    }

    #[test]
    fn coincident_centres_and_a_single_centre() {
        let tree = CentreTree::new(&[Vec3::ONE; 20]);
        assert!(tree.nearest(Vec3::ZERO) < 20);
        assert_eq!(CentreTree::new(&[Vec3::X]).nearest(Vec3::new(5.0, -3.0, 2.0)), 0);
    }
}
