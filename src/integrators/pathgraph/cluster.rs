//! Neighbour edges: nearest-centre clustering of the shading points (Sec. 3.1, Sec. 4).
//!
//! About N/K points are chosen as centres by hashing their index with the sample's seed (so
//! the choice does not depend on the thread count), a k-d tree over the centres
//! ([`super::nearest`]) answers nearest-centre queries, and clusters larger than 2K are halved at
//! the median of their longest axis until they are not ("repeated for large clusters until the
//! number of shading points per cluster is relatively even").

use glam::Vec3;
use rayon::prelude::*;

use super::nearest::CentreTree;

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
    #[cfg(test)]
    pub fn range(&self, c: usize) -> std::ops::Range<usize> {
        self.offsets[c] as usize..self.offsets[c + 1] as usize
    }
}

/// Clusters the points 0..n, point i at `p(i)`, by kind (`kind` 1, 2, ...: points of one
/// kind only share clusters with each other), about `k(kind)` per cluster; points of kind 0
/// are clusters of their own (after the others). `seed` picks the centres. The clusters
/// depend on the points' indices (the centres are picked by index, members are in index
/// order), not on where the caller keeps them.
pub fn cluster<P: Fn(u32) -> Vec3 + Sync>(
    n: usize,
    p: P,
    kind: impl Fn(usize) -> u32,
    k: impl Fn(u32) -> u32,
    seed: u64,
) -> Clusters {
    let mut out = Clusters { order: Vec::with_capacity(n), offsets: vec![0] };
    // Kinds in increasing order, each kind's points in index order.
    let mut kinds: std::collections::BTreeMap<u32, Vec<u32>> = std::collections::BTreeMap::new();
    for i in 0..n {
        kinds.entry(kind(i)).or_default().push(i as u32);
    }
    for (&kd, idx) in kinds.range(1..) {
        cluster_kind(&p, idx, k(kd), seed ^ u64::from(kd), &mut out);
    }
    for &i in kinds.get(&0).map_or(&[][..], Vec::as_slice) {
        out.order.push(i);
        out.offsets.push(out.order.len() as u32);
    }
    out
}

/// Appends the clusters of the points `idx`.
fn cluster_kind<P: Fn(u32) -> Vec3 + Sync>(p: &P, idx: &[u32], k: u32, seed: u64, out: &mut Clusters) {
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
    let tree = CentreTree::new(&centres.iter().map(|&c| p(c)).collect::<Vec<_>>());
    let nearest: Vec<u32> = idx.par_iter().map(|&i| tree.nearest(p(i))).collect();
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
fn split<P: Fn(u32) -> Vec3>(p: &P, members: &mut [u32], max: usize, out: &mut Clusters) {
    if members.is_empty() {
        return;
    }
    if members.len() <= max {
        out.order.extend_from_slice(members);
        out.offsets.push(out.order.len() as u32);
        return;
    }
    let (lo, hi) =
        members.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| (lo.min(p(i)), hi.max(p(i))));
    let axis = (hi - lo).max_position();
    let mid = members.len() / 2;
    // Ties broken by index, so the split does not depend on the input order.
    members.select_nth_unstable_by(mid, |&a, &b| p(a)[axis].total_cmp(&p(b)[axis]).then(a.cmp(&b)));
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
        let c = cluster(p.len(), |i| p[i as usize], |i| u32::from(i % 10 != 0), |_| 16, 3);
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
        let tree = CentreTree::new(&centres.iter().map(|&c| p[c as usize]).collect::<Vec<_>>());
        for (i, &q) in p.iter().enumerate() {
            let dist = |rank: u32| p[centres[rank as usize] as usize].distance_squared(q);
            let brute = (0..centres.len() as u32).map(dist).fold(f32::INFINITY, f32::min);
            assert_eq!(dist(tree.nearest(q)), brute, "point {i}");
        }
    }

    #[test]
    fn k_one_is_one_point_per_cluster() {
        let p = points(100);
        let c = cluster(p.len(), |i| p[i as usize], |_| 1, |_| 1, 0);
        assert_eq!(c.len(), 100);
    }
}
