//! Neighbour edges: nearest-centre clustering of the shading points (Sec. 3.1, Sec. 4).
//!
//! About N/K points are chosen as centres by hashing their index with the sample's seed (so
//! the choice does not depend on the thread count), a hash grid over the centres answers
//! nearest-centre queries, and clusters larger than 2K are halved at the median of their
//! longest axis until they are not ("repeated for large clusters until the number of shading
//! points per cluster is relatively even").

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::math::cell_map::CellMap;

/// Clusters as ranges of a permutation of the points.
#[derive(Debug, Default)]
pub struct Clusters {
    /// Point indices, cluster by cluster.
    pub order: Vec<u32>,
    /// Start of each cluster in `order`, plus `order.len()` at the end.
    pub offsets: Vec<u32>,
}

impl Clusters {
    /// Number of clusters.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The range of cluster `c` in `order`.
    pub fn range(&self, c: usize) -> std::ops::Range<usize> {
        self.offsets[c] as usize..self.offsets[c + 1] as usize
    }
}

/// Rings of the hash grid searched before falling back to scanning every centre.
const MAX_RING: i32 = 12;

/// Clusters the points `p` by kind (`kind` 1, 2, ...: points of one kind only share clusters
/// with each other), about `k(kind)` per cluster; points of kind 0 are clusters of their own
/// (after the others). `seed` picks the centres.
pub fn cluster(p: &[Vec3], kind: impl Fn(usize) -> u32, k: impl Fn(u32) -> u32, seed: u64) -> Clusters {
    let mut out = Clusters { order: Vec::with_capacity(p.len()), offsets: vec![0] };
    // Kinds in increasing order, each kind's points in index order.
    let mut kinds: std::collections::BTreeMap<u32, Vec<u32>> = std::collections::BTreeMap::new();
    for i in 0..p.len() {
        kinds.entry(kind(i)).or_default().push(i as u32);
    }
    for (&kd, idx) in kinds.range(1..) {
        cluster_kind(p, idx, k(kd), seed ^ u64::from(kd), &mut out);
    }
    for &i in kinds.get(&0).map_or(&[][..], Vec::as_slice) {
        out.order.push(i);
        out.offsets.push(out.order.len() as u32);
    }
    out
}

/// Appends the clusters of the points `idx`.
fn cluster_kind(p: &[Vec3], idx: &[u32], k: u32, seed: u64, out: &mut Clusters) {
    if idx.is_empty() {
        return;
    }
    if k <= 1 {
        for &i in idx {
            out.order.push(i);
            out.offsets.push(out.order.len() as u32);
        }
        return;
    }
    let threshold = u64::MAX / k as u64;
    let mut centres: Vec<u32> = idx.iter().copied().filter(|&i| mix(seed, i as u64) < threshold).collect();
    if centres.is_empty() {
        centres.push(idx[0]);
    }
    let grid = CentreGrid::new(p, idx, &centres);
    let nearest: Vec<u32> = idx.par_iter().map(|&i| grid.nearest(p, p[i as usize])).collect();
    // Counting sort by centre: members stay in index order within a cluster.
    let mut count = vec![0u32; centres.len() + 1];
    for &c in &nearest {
        count[c as usize + 1] += 1;
    }
    for c in 0..centres.len() {
        count[c + 1] += count[c];
    }
    let starts = count.clone();
    let mut members = vec![0u32; idx.len()];
    for (&i, &c) in idx.iter().zip(&nearest) {
        members[count[c as usize] as usize] = i;
        count[c as usize] += 1;
    }
    for c in 0..centres.len() {
        let m = &mut members[starts[c] as usize..starts[c + 1] as usize];
        split(p, m, 2 * k as usize, out);
    }
}

/// Appends `members` as one cluster, or halves it at the median of its longest axis until
/// the pieces hold at most `max` points.
fn split(p: &[Vec3], members: &mut [u32], max: usize, out: &mut Clusters) {
    if members.is_empty() {
        return;
    }
    if members.len() <= max {
        out.order.extend_from_slice(members);
        out.offsets.push(out.order.len() as u32);
        return;
    }
    let (lo, hi) = members
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| (lo.min(p[i as usize]), hi.max(p[i as usize])));
    let axis = (hi - lo).max_position();
    let mid = members.len() / 2;
    // Ties broken by index, so the split does not depend on the input order.
    members.select_nth_unstable_by(mid, |&a, &b| p[a as usize][axis].total_cmp(&p[b as usize][axis]).then(a.cmp(&b)));
    let (a, b) = members.split_at_mut(mid);
    a.sort_unstable();
    b.sort_unstable();
    split(p, a, max, out);
    split(p, b, max, out);
}

/// A 64-bit mix of the seed and an index (SplitMix64's finaliser).
#[inline]
fn mix(seed: u64, i: u64) -> u64 {
    let mut z = seed ^ i.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform hash grid over the cluster centres.
struct CentreGrid<'a> {
    cell: f32,
    origin: Vec3,
    /// Centre ranks sorted by cell.
    sorted: Vec<u32>,
    /// Their positions, in the same order (the search reads them contiguously).
    sorted_p: Vec<Vec3>,
    cells: CellMap<(u32, u32)>,
    centres: &'a [u32],
}

impl<'a> CentreGrid<'a> {
    fn new(p: &[Vec3], points: &[u32], centres: &'a [u32]) -> CentreGrid<'a> {
        let (lo, hi) = points
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| (lo.min(p[i as usize]), hi.max(p[i as usize])));
        let extent = (hi - lo).max(Vec3::splat((hi - lo).max_element() * 1e-3 + 1e-6));
        // One centre per cell if they were spread evenly; finer while cells are crowded
        // (points, and so centres, gather where paths scatter most).
        let mut cell = (extent.x * extent.y * extent.z / centres.len() as f32).cbrt();
        loop {
            let mut grid = CentreGrid {
                cell,
                origin: lo,
                sorted: Vec::new(),
                sorted_p: Vec::new(),
                cells: CellMap::default(),
                centres,
            };
            grid.fill(p);
            let crowded = centres.len() as f32 / grid.cells.len() as f32 > 4.0;
            if !crowded || cell < extent.max_element() * 1e-4 {
                return grid;
            }
            cell *= 0.5;
        }
    }

    fn fill(&mut self, p: &[Vec3]) {
        let mut keyed: Vec<(IVec3, u32)> =
            (0..self.centres.len() as u32).map(|c| (self.cell_of(p[self.centres[c as usize] as usize]), c)).collect();
        keyed.sort_unstable_by_key(|&(k, c)| (k.x, k.y, k.z, c));
        self.sorted = keyed.iter().map(|&(_, c)| c).collect();
        self.sorted_p = self.sorted.iter().map(|&c| p[self.centres[c as usize] as usize]).collect();
        let mut start = 0;
        while start < keyed.len() {
            let key = keyed[start].0;
            let mut end = start;
            while end < keyed.len() && keyed[end].0 == key {
                end += 1;
            }
            self.cells.insert(key, (start as u32, end as u32));
            start = end;
        }
    }

    #[inline]
    fn cell_of(&self, q: Vec3) -> IVec3 {
        ((q - self.origin) / self.cell).floor().as_ivec3()
    }

    /// Rank of the centre nearest to `q` (the lowest rank among equally near ones).
    fn nearest(&self, p: &[Vec3], q: Vec3) -> u32 {
        let c = self.cell_of(q);
        // How far q is from the faces of its own cell: every unsearched cell is at least this
        // plus the searched rings away.
        let local = (q - self.origin) / self.cell - c.as_vec3();
        let margin = local.min(Vec3::ONE - local).min_element().max(0.0) * self.cell;
        let mut best = (f32::INFINITY, u32::MAX);
        let consider = |d: f32, rank: u32, best: &mut (f32, u32)| {
            if d < best.0 || (d == best.0 && rank < best.1) {
                *best = (d, rank);
            }
        };
        for r in 0..=MAX_RING {
            for dz in -r..=r {
                for dy in -r..=r {
                    let on_face = dz.abs() == r || dy.abs() == r;
                    let step = if on_face { 1 } else { (2 * r).max(1) };
                    let mut dx = -r;
                    while dx <= r {
                        if let Some(&(s, e)) = self.cells.get(&(c + IVec3::new(dx, dy, dz))) {
                            let (s, e) = (s as usize, e as usize);
                            for (&rank, &cp) in self.sorted[s..e].iter().zip(&self.sorted_p[s..e]) {
                                consider(cp.distance_squared(q), rank, &mut best);
                            }
                        }
                        dx += step;
                    }
                }
            }
            let reach = r as f32 * self.cell + margin;
            if best.0 <= reach * reach {
                return best.1;
            }
        }
        // Not proven nearest within the rings searched (a sparse region): scan every centre.
        for rank in 0..self.centres.len() as u32 {
            consider(p[self.centres[rank as usize] as usize].distance_squared(q), rank, &mut best);
        }
        best.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let h = mix(7, i as u64);
                Vec3::new((h & 0xffff) as f32, ((h >> 16) & 0xffff) as f32, ((h >> 32) & 0xffff) as f32) / 65536.0
            })
            .collect()
    }

    #[test]
    fn every_point_once_and_clusters_near_k() {
        let p = points(20_000);
        let c = cluster(&p, |i| u32::from(i % 10 != 0), |_| 16, 3);
        let mut seen = c.order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..20_000).collect::<Vec<u32>>());
        let sizes: Vec<usize> = (0..c.len()).map(|k| c.range(k).len()).collect();
        assert!(sizes.iter().all(|&s| s <= 32), "oversized cluster");
        // 18,000 clustered points in about 18,000/16 clusters (a few more from splits), plus
        // 2,000 singletons.
        let mean = 18_000.0 / (c.len() - 2_000) as f64;
        assert!((8.0..=20.0).contains(&mean), "mean cluster size {mean}");
    }

    #[test]
    fn members_are_assigned_to_their_nearest_centre() {
        let p = points(3_000);
        let centres: Vec<u32> = (0..3_000u32).filter(|&i| mix(5, i as u64) < u64::MAX / 30).collect();
        let idx: Vec<u32> = (0..3_000).collect();
        let grid = CentreGrid::new(&p, &idx, &centres);
        for (i, &q) in p.iter().enumerate() {
            let brute = (0..centres.len() as u32)
                .min_by(|&a, &b| {
                    p[centres[a as usize] as usize]
                        .distance_squared(q)
                        .total_cmp(&p[centres[b as usize] as usize].distance_squared(q))
                        .then(a.cmp(&b))
                })
                .unwrap();
            assert_eq!(grid.nearest(&p, q), brute, "point {i}");
        }
    }

    #[test]
    fn k_one_is_one_point_per_cluster() {
        let p = points(100);
        let c = cluster(&p, |_| 1, |_| 1, 0);
        assert_eq!(c.len(), 100);
    }
}
