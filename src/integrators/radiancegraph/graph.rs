//! The graph while it is built (thesis Secs. 4.1 and 4.3): nodes with positions and counts of
//! segments sampled from them, a hash grid over the nodes for fixed-radius queries, and each
//! node's outgoing edges with their sample counts.
//!
//! Memory, per node: position 12 B, sample count 4 B, next-in-cell link 4 B, edge-list row
//! 8 B, kept scattering points for the direct light 52 B ([`Members`]), in arrays that grow
//! by fixed chunks, and a hash grid with cells of twice the radius (a few nodes per cell);
//! per edge: target and count, 8 B, in slots at most twice a list's
//! length ([`EdgeLists`]). The thesis keeps `std::map`s of nodes, edges and per-node edge maps
//! (≈ 190 B per edge).

use glam::{IVec3, Vec3};

use super::edges::EdgeLists;
use super::transport::Transport;
use crate::math::cell_map::CellMap;

type Cells = CellMap<u32>;

const NONE: u32 = u32::MAX;

/// Scattering points kept per node (a uniform reservoir of the light-path vertices that joined
/// it), where its direct light is estimated.
pub const MEMBERS: usize = 8;

/// A kept point as its offset from the node's position in 1/32767ths of the node radius (a
/// joined point lies within the radius): 6 bytes instead of 12.
type Offset = [i16; 3];

/// Each node's kept points ([`MEMBERS`] at most).
pub struct Members {
    offsets: Vec<[Offset; MEMBERS]>,
    counts: Vec<u32>,
    radius: f32,
}

impl Members {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.counts.len()
    }

    /// True without nodes.
    pub fn is_empty(&self) -> bool {
        self.counts.is_empty()
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.offsets.len() * std::mem::size_of::<[Offset; MEMBERS]>() + self.counts.len() * 4
    }

    /// The points kept for node `a` at `position` (at least one: a node is made by a point),
    /// in the first entries of the array, and their number.
    #[inline]
    pub fn of(&self, a: usize, position: Vec3) -> ([Vec3; MEMBERS], usize) {
        let n = (self.counts[a] as usize).clamp(1, MEMBERS);
        let scale = self.radius / f32::from(i16::MAX);
        let mut out = [position; MEMBERS];
        for (o, q) in out[..n].iter_mut().zip(&self.offsets[a]) {
            *o += Vec3::new(f32::from(q[0]), f32::from(q[1]), f32::from(q[2])) * scale;
        }
        (out, n)
    }
}

/// A growable array in fixed chunks of 2¹⁶ elements: pushing never copies or doubles.
struct Chunked<T> {
    chunks: Vec<Box<[T]>>,
    len: usize,
}

const CHUNK_BITS: usize = 16;

impl<T: Copy + Default> Chunked<T> {
    fn new() -> Chunked<T> {
        Chunked { chunks: Vec::new(), len: 0 }
    }

    fn push(&mut self, v: T) {
        if self.len >> CHUNK_BITS == self.chunks.len() {
            self.chunks.push(vec![T::default(); 1 << CHUNK_BITS].into_boxed_slice());
        }
        self.chunks[self.len >> CHUNK_BITS][self.len & ((1 << CHUNK_BITS) - 1)] = v;
        self.len += 1;
    }

    #[inline]
    fn get(&self, i: usize) -> T {
        self.chunks[i >> CHUNK_BITS][i & ((1 << CHUNK_BITS) - 1)]
    }

    #[inline]
    fn get_mut(&mut self, i: usize) -> &mut T {
        &mut self.chunks[i >> CHUNK_BITS][i & ((1 << CHUNK_BITS) - 1)]
    }

    fn bytes(&self) -> usize {
        self.chunks.len() * (std::mem::size_of::<T>() << CHUNK_BITS) + self.chunks.capacity() * 16
    }

    /// The elements in one contiguous vector, freeing chunks as they are copied.
    fn into_vec(self) -> Vec<T> {
        let mut v = Vec::with_capacity(self.len);
        let mut left = self.len;
        for c in self.chunks {
            let k = left.min(c.len());
            v.extend_from_slice(&c[..k]);
            left -= k;
        }
        v
    }
}

/// Mean and spread of the lengths of runs of a path inside one node (the thesis's
/// `in_node_path_length` statistic).
#[derive(Clone, Copy, Debug, Default)]
pub struct RunStats {
    n: u64,
    sum: f64,
    sum_sq: f64,
}

impl RunStats {
    fn add(&mut self, v: f64) {
        self.n += 1;
        self.sum += v;
        self.sum_sq += v * v;
    }

    /// Mean (0 without data).
    pub fn mean(&self) -> f64 {
        if self.n == 0 { 0.0 } else { self.sum / self.n as f64 }
    }

    /// Standard deviation (0 without data).
    pub fn std(&self) -> f64 {
        if self.n == 0 {
            return 0.0;
        }
        let m = self.mean();
        (self.sum_sq / self.n as f64 - m * m).max(0.0).sqrt()
    }
}

/// The graph under construction.
pub struct BuildGraph {
    radius: f32,
    cell_size: f32,
    positions: Chunked<Vec3>,
    samples: Chunked<u32>,
    next_in_cell: Chunked<u32>,
    members: Chunked<[Offset; MEMBERS]>,
    joins: Chunked<u32>,
    cells: Cells,
    out: EdgeLists,
    /// Runs of consecutive path vertices in one node.
    pub in_node: RunStats,
}

impl BuildGraph {
    /// An empty graph with node radius `radius`.
    pub fn new(radius: f32) -> BuildGraph {
        BuildGraph {
            radius,
            // Twice the radius: a radius query touches 8 cells, and a cell holds a few
            // nodes, so the grid costs a few bytes per node.
            cell_size: 2.0 * radius,
            positions: Chunked::new(),
            samples: Chunked::new(),
            next_in_cell: Chunked::new(),
            members: Chunked::new(),
            joins: Chunked::new(),
            cells: Cells::default(),
            out: EdgeLists::default(),
            in_node: RunStats::default(),
        }
    }

    /// The node radius.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.positions.len
    }

    /// True without nodes.
    pub fn is_empty(&self) -> bool {
        self.positions.len == 0
    }

    /// Position of node `a`.
    #[inline]
    pub fn position(&self, a: u32) -> Vec3 {
        self.positions.get(a as usize)
    }

    /// Segments sampled from node `a` (s_n of Eq. 4.20).
    pub fn samples(&self, a: u32) -> u32 {
        self.samples.get(a as usize)
    }

    /// Outgoing edges of node `a`.
    pub fn out_degree(&self, a: u32) -> usize {
        self.out.len(a)
    }

    fn cell(&self, p: Vec3) -> IVec3 {
        (p / self.cell_size).floor().as_ivec3()
    }

    /// Calls `f` with every node in the cells the box of half-size `range` around `p`
    /// touches: with cells of twice the radius, 8 cells for a radius query.
    fn for_nearby(&self, p: Vec3, range: f32, mut f: impl FnMut(u32)) {
        let lo = self.cell(p - Vec3::splat(range));
        let hi = self.cell(p + Vec3::splat(range));
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let mut i = self.cells.get(&IVec3::new(x, y, z)).copied().unwrap_or(NONE);
                    while i != NONE {
                        f(i);
                        i = self.next_in_cell.get(i as usize);
                    }
                }
            }
        }
    }

    /// The node closest to `p` within the node radius (lowest index on ties).
    pub fn closest_within_radius(&self, p: Vec3) -> Option<u32> {
        let r2 = self.radius * self.radius;
        let mut best: Option<(f32, u32)> = None;
        self.for_nearby(p, self.radius, |i| {
            let d2 = self.positions.get(i as usize).distance_squared(p);
            if d2 <= r2 && best.is_none_or(|(bd, bi)| d2 < bd || (d2 == bd && i < bi)) {
                best = Some((d2, i));
            }
        });
        best.map(|b| b.1)
    }

    /// Nodes within `range` of `p`, `p`'s own node included (the thesis's `CountInRadius`).
    pub fn count_within(&self, p: Vec3, range: f32) -> usize {
        let r2 = range * range;
        let mut n = 0;
        self.for_nearby(p, range, |i| n += usize::from(self.positions.get(i as usize).distance_squared(p) <= r2));
        n
    }

    fn add_node(&mut self, p: Vec3) -> u32 {
        let i = self.positions.len as u32;
        let c = self.cell(p);
        let head = self.cells.entry(c).or_insert(NONE);
        self.next_in_cell.push(*head);
        *head = i;
        self.positions.push(p);
        self.samples.push(0);
        self.members.push([[0; 3]; MEMBERS]);
        self.joins.push(0);
        self.out.push_node();
        i
    }

    /// Offers scattering point `p` to node `a`'s reservoir: each of the node's points so far
    /// is kept with the same probability (Vitter's algorithm R, its random choice a hash of
    /// the node and the count, so the graph stays the same at any thread count).
    fn join(&mut self, a: u32, p: Vec3) {
        let k = self.joins.get(a as usize);
        *self.joins.get_mut(a as usize) = k.saturating_add(1);
        let slot = if (k as usize) < MEMBERS {
            k as usize
        } else {
            // SplitMix64's finaliser of (node, count).
            let mut h = (u64::from(a) << 32 | u64::from(k)).wrapping_add(0x9e37_79b9_7f4a_7c15);
            h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            h ^= h >> 31;
            (h % (u64::from(k) + 1)) as usize
        };
        if slot < MEMBERS {
            let q = ((p - self.positions.get(a as usize)) / self.radius * f32::from(i16::MAX)).round();
            let q = q.clamp(Vec3::splat(-f32::from(i16::MAX)), Vec3::splat(f32::from(i16::MAX)));
            self.members.get_mut(a as usize)[slot] = [q.x as i16, q.y as i16, q.z as i16];
        }
    }

    /// Groups one traced path into the graph (thesis Sec. 4.3): each scattering point joins
    /// the closest node within the radius or becomes a new node; each segment counts as a
    /// sample of the node it was sampled from and, if it scattered, of the edge to the node
    /// it scattered in. `start` is the node a reinforcement path starts from; `last_sampled`
    /// is false when the path stopped at the maximum depth (its last segment was never
    /// sampled, so it counts for nothing).
    pub fn add_path(&mut self, start: Option<u32>, points: &[Vec3], last_sampled: bool) {
        let mut prev = start;
        // In-node run lengths over the path's vertices (start included).
        let mut run = 0u32;
        let mut vertices = u32::from(start.is_some());
        if start.is_some() {
            run = 1;
        }
        for &p in points {
            let node = match self.closest_within_radius(p) {
                Some(n) => n,
                None => self.add_node(p),
            };
            self.join(node, p);
            if let Some(v) = prev {
                *self.samples.get_mut(v as usize) += 1;
                self.out.add(v, node);
                if v == node {
                    run += 1;
                } else {
                    self.in_node.add(run as f64);
                    run = 1;
                }
            } else {
                run = 1;
            }
            vertices += 1;
            prev = Some(node);
        }
        if last_sampled {
            if let Some(v) = prev {
                *self.samples.get_mut(v as usize) += 1;
            }
            if vertices > 0 {
                self.in_node.add(run as f64);
            }
        }
    }

    /// Number of edges.
    pub fn edge_count(&self) -> usize {
        self.out.edges()
    }

    /// Edges sampled more than once.
    pub fn edges_more_than_once(&self) -> usize {
        self.out.more_than_once()
    }

    /// Bytes held, as (per-node structures, edge storage).
    pub fn memory_bytes(&self) -> (usize, usize) {
        let (rows, pools) = self.out.memory_bytes();
        let nodes = self.positions.bytes()
            + self.samples.bytes()
            + self.next_in_cell.bytes()
            + self.members.bytes()
            + self.joins.bytes()
            + rows
            // hashbrown: key, value and one control byte per bucket.
            + self.cells.capacity() * (std::mem::size_of::<IVec3>() + 4 + 1);
        (nodes, pools)
    }

    /// The node positions, the transport matrix (Eq. 4.8 with Eq. 4.20's weights, made from
    /// the edge lists in place), the in-node run statistics and the points each node kept.
    pub fn into_parts(self) -> (Vec<Vec3>, Transport, RunStats, Members) {
        let BuildGraph { positions, samples, out, in_node, members, joins, radius, .. } = self;
        let samples = samples.into_vec();
        let t = Transport::from_lists(out, &samples);
        let members = Members { offsets: members.into_vec(), counts: joins.into_vec(), radius };
        (positions.into_vec(), t, in_node, members)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each node keeps the points that joined it, up to [`MEMBERS`], each with the same
    /// chance: over 200 nodes joined by 100 points each (the k-th at k/100 of the radius along
    /// x), the kept points' mean position is the joined points' (0.495 of the radius), and
    /// every kept point is a joined one to the offsets' precision.
    #[test]
    fn nodes_keep_a_uniform_sample_of_their_points() {
        let mut g = BuildGraph::new(1.0);
        let centre = |i: usize| Vec3::new(0.0, 0.0, 10.0 * i as f32);
        for i in 0..200 {
            let points: Vec<Vec3> = (0..100).map(|k| centre(i) + Vec3::X * (k as f32 / 100.0)).collect();
            g.add_path(None, &points, true);
        }
        assert_eq!(g.len(), 200);
        let (positions, _, _, members) = g.into_parts();
        let (mut sum, mut n) = (0.0f64, 0);
        for (a, &p) in positions.iter().enumerate() {
            assert_eq!(p, centre(a));
            let (kept, count) = members.of(a, p);
            assert_eq!(count, MEMBERS);
            for x in &kept[..count] {
                let d = *x - p;
                let k = d.x * 100.0;
                assert!((k - k.round()).abs() < 0.01 && d.y.abs() < 1e-4 && d.z.abs() < 1e-4, "{d}");
                sum += f64::from(d.x);
                n += 1;
            }
        }
        // 1600 draws of a uniform over {0, …, 0.99}: standard error 0.0072.
        let mean = sum / f64::from(n);
        assert!((mean - 0.495).abs() < 0.03, "kept points' mean {mean}");
        // A node with fewer points than slots keeps them all.
        let mut g = BuildGraph::new(1.0);
        g.add_path(None, &[Vec3::ZERO, Vec3::new(0.5, 0.0, 0.0)], true);
        let (positions, _, _, members) = g.into_parts();
        let (kept, count) = members.of(0, positions[0]);
        assert_eq!(count, 2);
        assert!((kept[1] - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-4);
    }

    #[test]
    fn points_join_the_closest_node_within_the_radius() {
        let mut g = BuildGraph::new(1.0);
        g.add_path(None, &[Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)], true);
        // 0.5 joins node 0; the path is 0 -> 1 -> 0 with three sampled segments.
        assert_eq!(g.len(), 2);
        assert_eq!([g.samples(0), g.samples(1)], [2, 1]);
        g.add_path(None, &[Vec3::new(2.2, 0.0, 0.0)], false);
        // 2.2 is within 1 of node 1 (at 3) only: no new node, no sample (forced end).
        assert_eq!(g.len(), 2);
        assert_eq!([g.samples(0), g.samples(1)], [2, 1]);
        // Closest, not first: 1.6 is 1.6 from node 0 (out of range) and 1.4 from node 1.
        assert_eq!(g.closest_within_radius(Vec3::new(1.6, 0.0, 0.0)), None);
        assert_eq!(g.closest_within_radius(Vec3::new(2.1, 0.0, 0.0)), Some(1));
        assert_eq!(g.count_within(Vec3::ZERO, 3.0), 2);
        assert_eq!(g.count_within(Vec3::ZERO, 2.9), 1);
        let (pos, t, runs, _) = g.into_parts();
        assert_eq!(pos.len(), 2);
        // w(0,1) = 1/2, w(1,0) = 1/1.
        assert_eq!(t.row(0).collect::<Vec<_>>(), [(1, 0.5)]);
        assert_eq!(t.row(1).collect::<Vec<_>>(), [(0, 1.0)]);
        // Runs: path 1 has three runs of 1; path 2 ended at max depth and adds none.
        assert_eq!(runs.mean(), 1.0);
    }

    #[test]
    fn in_node_runs_and_reinforcement_starts() {
        let mut g = BuildGraph::new(1.0);
        g.add_path(None, &[Vec3::ZERO, Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.2, 0.0, 0.0)], true);
        // One run of 3 in node 0, with a self-edge sampled twice and 3 samples.
        assert_eq!(g.samples(0), 3);
        assert_eq!(g.edges_more_than_once(), 1);
        assert_eq!(g.in_node.mean(), 3.0);
        g.add_path(Some(0), &[Vec3::new(5.0, 0.0, 0.0)], true);
        assert_eq!([g.samples(0), g.samples(1)], [4, 1]);
        assert_eq!(g.edge_count(), 2);
        assert!(g.memory_bytes().0 > 0 && g.memory_bytes().1 >= 2 * 8);
    }
}
