//! Render search ranges (thesis Sec. 4.3.2, Eq. 4.21): each node's range is the mean, over
//! the node and its k nearest nodes, of their mean distance to their own k nearest nodes,
//! so ranges grow where the graph is sparse without flooding empty space.

use glam::Vec3;
use kiddo::SquaredEuclidean;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use rayon::prelude::*;
use std::num::NonZero;

/// A k-d tree over node positions for nearest-node queries (kiddo's immutable tree: 32-point
/// buckets, built once the graph's nodes are fixed).
pub type NodeTree = ImmutableKdTree<f32, u32, 3, 32>;

/// Builds the tree over `points` (item = index).
pub fn node_tree(points: &[Vec3]) -> NodeTree {
    let raw: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    NodeTree::new_from_slice(&raw)
}

/// searchR of Eq. 4.21 for every node, with `k` neighbours. Fails when the graph has no more
/// than `k` nodes (the thesis stops there too).
pub fn search_ranges(points: &[Vec3], k: usize) -> crate::Result<Vec<f32>> {
    if k == 0 || points.len() <= k {
        return Err(crate::Error::Invalid(format!(
            "the graph has {} nodes, too few for {k} neighbours per node",
            points.len()
        )));
    }
    let tree = node_tree(points);
    // avgD(a) and NN(a, 1..=k), in parallel, into flat arrays (k entries per node).
    let mut avg = vec![0.0f32; points.len()];
    let mut nn = vec![0u32; points.len() * k];
    avg.par_iter_mut().zip(nn.par_chunks_mut(k)).enumerate().for_each(|(a, (avg, nn))| {
        let found = tree.nearest_n::<SquaredEuclidean>(&points[a].to_array(), NonZero::new(k + 1).unwrap());
        let mut sum = 0.0;
        let mut j = 0;
        for n in found.into_iter().filter(|n| n.item as usize != a).take(k) {
            nn[j] = n.item;
            sum += n.distance.sqrt();
            j += 1;
        }
        *avg = sum / j as f32;
    });
    Ok((0..points.len())
        .map(|a| (avg[a] + nn[a * k..(a + 1) * k].iter().map(|&b| avg[b as usize]).sum::<f32>()) / (k + 1) as f32)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 4.21 on four points on a line at 0, 1, 3, 7 with k = 1: nearest distances give
    /// avgD = (1, 1, 2, 4), NN = (1, 0, 1, 2), so searchR = ((1+1)/2, (1+1)/2, (2+1)/2, (4+2)/2)
    /// = (1, 1, 1.5, 3). With k = 2: avgD = ((1+3)/2, (1+2)/2, (2+3)/2, (4+6)/2) = (2, 1.5, 2.5, 5),
    /// NN = ({1,2}, {0,2}, {1,0}, {2,1}), searchR = ((2+1.5+2.5)/3, (1.5+2+2.5)/3,
    /// (2.5+1.5+2)/3, (5+2.5+1.5)/3) = (2, 2, 2, 3).
    #[test]
    fn eq_4_21_on_a_known_point_set() {
        let points = [0.0, 1.0, 3.0, 7.0].map(|x| Vec3::new(x, 0.0, 0.0));
        let r1 = search_ranges(&points, 1).unwrap();
        assert_eq!(r1, [1.0, 1.0, 1.5, 3.0]);
        let r2 = search_ranges(&points, 2).unwrap();
        for (g, w) in r2.iter().zip([2.0, 2.0, 2.0, 3.0]) {
            assert!((g - w).abs() < 1e-6, "{r2:?}");
        }
    }

    #[test]
    fn too_few_nodes_is_an_error() {
        let points = [Vec3::ZERO, Vec3::X];
        assert!(search_ranges(&points, 2).unwrap_err().to_string().contains("2 nodes, too few for 2 neighbours"));
    }
}
