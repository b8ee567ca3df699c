//! The directional part of an SD-tree (Müller et al. 2017, Sec. 3.1; Deng et al. 2020,
//! Sec. 4.1): a quadtree over the square that the cylindrical equal-area map takes the sphere
//! to, holding the energy of the photons that arrived from each direction. Sampling descends
//! by energy (hierarchical sample warping); the density is constant inside a leaf.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

/// Deepest level a quadtree node may reach (Müller et al.: 20).
const MAX_DEPTH: u32 = 20;

/// Cylindrical equal-area map from the unit sphere to [0, 1)²: (cos θ, φ) → ((cos θ + 1)/2,
/// φ/2π). Its Jacobian is constant, so a density on the square is 1/(4π) of one on the sphere.
#[inline]
pub fn sphere_to_square(d: Vec3) -> Vec2 {
    let cos_theta = d.z.clamp(-1.0, 1.0);
    let mut phi = crate::math::trig::atan2(d.y, d.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    Vec2::new((cos_theta + 1.0) * 0.5, phi / (2.0 * PI)).clamp(Vec2::ZERO, Vec2::splat(1.0 - f32::EPSILON / 2.0))
}

/// The inverse of [`sphere_to_square`].
#[inline]
pub fn square_to_sphere(p: Vec2) -> Vec3 {
    let cos_theta = 2.0 * p.x - 1.0;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * PI * p.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// One quadtree node: its four quadrants' energies and children (0: the quadrant is a leaf;
/// the root is node 0, so no child is 0). Quadrant i covers x half `i & 1`, y half `i >> 1`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Node {
    sums: [f32; 4],
    children: [u32; 4],
}

/// A node as saved: its quadrants' energies and children (0: none).
pub type NodeParts = ([f32; 4], [u32; 4]);

/// A directional quadtree.
#[derive(Clone, Debug, PartialEq)]
pub struct DTree {
    nodes: Vec<Node>,
    /// Photons deposited (the spatial tree splits on it).
    count: u64,
}

impl Default for DTree {
    fn default() -> Self {
        DTree::new()
    }
}

/// The quadrant of `p` in a node and `p` in that quadrant's own [0, 1)².
#[inline]
fn quadrant(p: Vec2) -> (usize, Vec2) {
    let (qx, qy) = ((p.x >= 0.5) as usize, (p.y >= 0.5) as usize);
    let q = Vec2::new(p.x * 2.0 - qx as f32, p.y * 2.0 - qy as f32);
    (qx | (qy << 1), q.clamp(Vec2::ZERO, Vec2::splat(1.0 - f32::EPSILON / 2.0)))
}

impl DTree {
    /// One node, no energy.
    pub fn new() -> DTree {
        DTree { nodes: vec![Node::default()], count: 0 }
    }

    /// Nodes (for memory reports).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes of node data.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
    }

    /// Photons deposited.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The photon count and the nodes as (quadrant energies, children), for saving.
    pub fn parts(&self) -> (u64, Vec<NodeParts>) {
        (self.count, self.nodes.iter().map(|n| (n.sums, n.children)).collect())
    }

    /// A tree from [`DTree::parts`], checked: children come after their parent and exist,
    /// energies are finite and not negative.
    pub fn from_parts(count: u64, nodes: Vec<NodeParts>) -> crate::Result<DTree> {
        if nodes.is_empty() {
            return Err(crate::Error::invalid("a directional tree has no nodes"));
        }
        for (i, (sums, children)) in nodes.iter().enumerate() {
            if sums.iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
                return Err(crate::Error::Invalid(format!("directional node {i} has an invalid energy")));
            }
            if children.iter().any(|&c| c != 0 && (c as usize <= i || c as usize >= nodes.len())) {
                return Err(crate::Error::Invalid(format!("directional node {i} has an invalid child")));
            }
        }
        Ok(DTree { nodes: nodes.into_iter().map(|(sums, children)| Node { sums, children }).collect(), count })
    }

    /// The same tree with another photon count.
    pub fn with_count(&self, count: u64) -> DTree {
        DTree { nodes: self.nodes.clone(), count }
    }

    /// Total energy.
    pub fn total(&self) -> f32 {
        self.nodes[0].sums.iter().sum()
    }

    /// Adds `energy` arriving from direction `d` (pointing away from the point, towards
    /// where the light came from).
    pub fn deposit(&mut self, d: Vec3, energy: f32) {
        self.count += 1;
        if !(energy > 0.0 && energy.is_finite()) {
            return;
        }
        let mut p = sphere_to_square(d);
        let mut node = 0usize;
        loop {
            let (q, pq) = quadrant(p);
            self.nodes[node].sums[q] += energy;
            let child = self.nodes[node].children[q];
            if child == 0 {
                return;
            }
            node = child as usize;
            p = pq;
        }
    }

    /// Density (per solid angle) of [`DTree::sample`] at direction `d`; 0 for a tree
    /// without energy.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let total = self.total();
        if total <= 0.0 {
            return 0.0;
        }
        let mut p = sphere_to_square(d);
        let mut node = 0usize;
        let mut pdf = 1.0f32;
        loop {
            let n = &self.nodes[node];
            let sum: f32 = n.sums.iter().sum();
            let (q, pq) = quadrant(p);
            if sum <= 0.0 {
                return 0.0;
            }
            pdf *= 4.0 * n.sums[q] / sum;
            if n.children[q] == 0 || pdf == 0.0 {
                return pdf / (4.0 * PI);
            }
            node = n.children[q] as usize;
            p = pq;
        }
    }

    /// [`DTree::pdf`] of each of `dirs` into `out` (the same values), the descents taken
    /// level by level side by side: each level's loads of the different directions do not
    /// wait on each other, where one descent after another waits on every load in turn
    /// (resampling asks for several candidates' densities at once).
    pub fn pdf_batch(&self, dirs: &[Vec3], out: &mut [f32]) {
        const LANES: usize = 8;
        assert_eq!(dirs.len(), out.len());
        let total = self.total();
        for (dirs, out) in dirs.chunks(LANES).zip(out.chunks_mut(LANES)) {
            if total <= 0.0 {
                out.fill(0.0);
                continue;
            }
            let mut p = [Vec2::ZERO; LANES];
            let mut node = [0usize; LANES];
            let mut live = [false; LANES];
            for k in 0..dirs.len() {
                p[k] = sphere_to_square(dirs[k]);
                out[k] = 1.0;
                live[k] = true;
            }
            let mut any = true;
            while any {
                any = false;
                for k in 0..dirs.len() {
                    if !live[k] {
                        continue;
                    }
                    let n = &self.nodes[node[k]];
                    let sum: f32 = n.sums.iter().sum();
                    let (q, pq) = quadrant(p[k]);
                    if sum <= 0.0 {
                        out[k] = 0.0;
                        live[k] = false;
                        continue;
                    }
                    out[k] *= 4.0 * n.sums[q] / sum;
                    if n.children[q] == 0 || out[k] == 0.0 {
                        out[k] /= 4.0 * PI;
                        live[k] = false;
                        continue;
                    }
                    node[k] = n.children[q] as usize;
                    p[k] = pq;
                    any = true;
                }
            }
        }
    }

    /// A direction drawn in proportion to the energy (the tree must have some), from `u` in
    /// [0, 1)², and its density.
    pub fn sample(&self, mut u: Vec2) -> Option<(Vec3, f32)> {
        if self.total() <= 0.0 {
            return None;
        }
        let mut node = 0usize;
        // The square of the current node: origin and size.
        let mut origin = Vec2::ZERO;
        let mut size = 1.0f32;
        let mut pdf = 1.0f32;
        loop {
            let n = &self.nodes[node];
            let s = n.sums;
            let sum: f32 = s.iter().sum();
            // Choose the x half, then the y half within it (hierarchical warping: the
            // leftover of each choice is the next uniform number).
            let left = s[0] + s[2];
            let px = left / sum;
            let qx = if u.x < px {
                u.x /= px;
                0
            } else {
                u.x = (u.x - px) / (1.0 - px);
                1
            };
            let (a, b) = (s[qx], s[qx + 2]);
            let py = a / (a + b);
            let qy = if u.y < py {
                u.y /= py;
                0
            } else {
                u.y = (u.y - py) / (1.0 - py);
                1
            };
            u = u.clamp(Vec2::ZERO, Vec2::splat(1.0 - f32::EPSILON / 2.0));
            let q = qx | (qy << 1);
            size *= 0.5;
            origin += Vec2::new(qx as f32, qy as f32) * size;
            pdf *= 4.0 * s[q] / sum;
            if n.children[q] == 0 {
                let d = square_to_sphere(origin + u * size);
                return (pdf > 0.0).then_some((d, pdf / (4.0 * PI)));
            }
            node = n.children[q] as usize;
        }
    }

    /// The tree for the next round of learning (Müller et al. 2017, Sec. 3.2): quadrants
    /// holding more than `threshold` of the total energy are subdivided (down to depth 20),
    /// the rest become leaves, energies start at zero. A tree without energy stays as it is.
    pub fn refined(&self, threshold: f32) -> DTree {
        let total = self.total();
        if total <= 0.0 {
            return DTree { nodes: self.nodes.iter().map(|n| Node { sums: [0.0; 4], ..*n }).collect(), count: 0 };
        }
        let mut out = DTree { nodes: vec![Node::default()], count: 0 };
        // (node in the old tree or None past its leaves, energy of the new node's region,
        // new node index, depth)
        let mut stack = vec![(Some(0usize), total, 0usize, 1u32)];
        while let Some((old, energy, new, depth)) = stack.pop() {
            for q in 0..4 {
                // The quadrant's energy: the old tree's, or a quarter of a leaf's.
                let (e, old_child) = match old {
                    Some(o) => {
                        let n = &self.nodes[o];
                        (n.sums[q], (n.children[q] != 0).then_some(n.children[q] as usize))
                    }
                    None => (energy / 4.0, None),
                };
                if depth < MAX_DEPTH && e > threshold * total {
                    let child = out.nodes.len();
                    out.nodes.push(Node::default());
                    out.nodes[new].children[q] = child as u32;
                    stack.push((old_child, e, child, depth + 1));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    #[test]
    fn the_map_is_a_bijection() {
        let mut rng = Pcg32::new(1, 2);
        for _ in 0..1000 {
            let p = Vec2::new(rng.uniform(), rng.uniform());
            let d = square_to_sphere(p);
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!((sphere_to_square(d) - p).abs().max_element() < 1e-4, "{p}");
        }
    }

    /// A tree refined around a bright cone.
    fn cone_tree() -> DTree {
        let mut rng = Pcg32::new(3, 4);
        let axis = Vec3::new(0.3, -0.5, 0.8).normalize();
        let mut t = DTree::new();
        for round in 0..4 {
            for _ in 0..20000 {
                let d = crate::sampling::warp::uniform_sphere(Vec2::new(rng.uniform(), rng.uniform()));
                let e = if d.dot(axis) > 0.9 { 10.0 } else { 0.1 };
                t.deposit(d, e);
            }
            if round < 3 {
                t = t.refined(0.01);
            }
        }
        t
    }

    /// The density integrates to one over the sphere and concentrates where the energy is.
    /// The batched densities are the one-at-a-time ones, bit for bit, for any batch size.
    #[test]
    fn batched_density_is_the_density() {
        let t = cone_tree();
        let mut rng = Pcg32::new(5, 6);
        let dirs: Vec<Vec3> = (0..37).map(|_| square_to_sphere(Vec2::new(rng.uniform(), rng.uniform()))).collect();
        let mut out = vec![f32::NAN; dirs.len()];
        t.pdf_batch(&dirs, &mut out);
        for (d, got) in dirs.iter().zip(&out) {
            assert_eq!(*got, t.pdf(*d));
        }
        let mut none = [1.0f32; 3];
        DTree::new().pdf_batch(&dirs[..3], &mut none);
        assert_eq!(none, [0.0; 3]);
    }

    #[test]
    fn density_integrates_to_one() {
        let t = cone_tree();
        assert!(t.node_count() > 20, "{}", t.node_count());
        // Fine enough for the tree's small cells (at 400² the midpoint rule was off by 0.5 %
        // for some trees).
        let n = 1600;
        let mut integral = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let p = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                integral += t.pdf(square_to_sphere(p)) as f64 * 4.0 * std::f64::consts::PI / (n * n) as f64;
            }
        }
        assert!((integral - 1.0).abs() < 1e-4, "{integral}");
        let axis = Vec3::new(0.3, -0.5, 0.8).normalize();
        assert!(t.pdf(axis) > 10.0 * t.pdf(-axis));
    }

    /// Samples follow the density: a χ²-style check on a 16×16 histogram of the square.
    #[test]
    fn samples_follow_the_density() {
        let t = cone_tree();
        let mut rng = Pcg32::new(5, 6);
        let (n, bins) = (200_000, 16usize);
        let mut hist = vec![0.0f64; bins * bins];
        // The density the descent reports is the one `pdf` finds, but for samples that round
        // onto a leaf's edge.
        let mut mismatched = 0;
        for _ in 0..n {
            let (d, pdf) = t.sample(Vec2::new(rng.uniform(), rng.uniform())).unwrap();
            mismatched += ((pdf - t.pdf(d)).abs() > 1e-3 * pdf) as u32;
            let p = sphere_to_square(d);
            hist[(p.y * bins as f32) as usize * bins + (p.x * bins as f32) as usize] += 1.0;
        }
        // Expected counts by integrating the density over each bin.
        let sub = 8;
        for by in 0..bins {
            for bx in 0..bins {
                let mut e = 0.0f64;
                for sy in 0..sub {
                    for sx in 0..sub {
                        let p =
                            Vec2::new((bx * sub + sx) as f32 + 0.5, (by * sub + sy) as f32 + 0.5) / (bins * sub) as f32;
                        e += t.pdf(square_to_sphere(p)) as f64;
                    }
                }
                let expected = e * 4.0 * std::f64::consts::PI / (bins * bins * sub * sub) as f64 * n as f64;
                let got = hist[by * bins + bx];
                assert!((got - expected).abs() < 5.0 * expected.sqrt() + 5.0, "bin {bx},{by}: {got} vs {expected}");
            }
        }
        assert!(mismatched < n / 1000, "{mismatched}");
    }

    #[test]
    fn empty_trees_neither_sample_nor_have_density() {
        let t = DTree::new();
        assert!(t.sample(Vec2::splat(0.3)).is_none());
        assert_eq!(t.pdf(Vec3::Z), 0.0);
        assert_eq!(t.refined(0.01).node_count(), 1);
    }
}
