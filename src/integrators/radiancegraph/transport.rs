//! Radiance transport through the graph (thesis Sec. 4.5): the sparse transport matrix T of
//! Eq. 4.8 with the sampled edge weights of Eq. 4.20, and the Neumann series of Eq. 4.23
//! computed as Algorithm 1 does, one sparse matrix–vector product per bounce.

use rayon::prelude::*;

use super::edges::EdgeLists;

/// T by rows. Row `a` holds w_s(a, b) = s_e(a, b) / s_n(a) for every node `b` a sampled
/// segment from `a` landed in: a point in `a` gathers the radiance of `b` with that weight, so
/// transport runs against the edges' direction (thesis Sec. 4.5.1). The rows are the build's
/// edge lists with their counts turned into weights in place ([`EdgeLists`]): 8 bytes per
/// entry in slots at most twice a row's length, and 8 per node; the thesis's `std::map`
/// graph plus Eigen triplets needed about 190 bytes per edge.
pub struct Transport {
    lists: EdgeLists,
}

/// One edge's sample count: segments sampled from node `from` that scattered in node `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct EdgeCount {
    /// Node the segment was sampled from.
    pub from: u32,
    /// Node it scattered in.
    pub to: u32,
    /// How often (s_e of Eq. 4.20).
    pub samples: u32,
}

/// The radiance after a Neumann series: per node, and the bounce count actually reached.
#[derive(Clone, Debug, PartialEq)]
pub struct Transported {
    /// Bounces asked for.
    pub bounces: u32,
    /// Bounces computed: fewer than asked when a product overflowed to ∞ or NaN (the
    /// thesis's "numerical limits reached"); the radiance is then the sum up to the last
    /// finite product.
    pub bounces_done: u32,
    /// L'_n of Eq. 4.23 per node.
    pub radiance: Vec<f32>,
}

impl Transport {
    /// T from the build's edge lists and each node's count of sampled segments s_n (which
    /// includes segments that were absorbed or left the volume, so a row sums to the node's
    /// probability of scattering again).
    pub fn from_lists(lists: EdgeLists, node_samples: &[u32]) -> Transport {
        assert_eq!(lists.nodes(), node_samples.len());
        Transport { lists: lists.into_weights(node_samples) }
    }

    /// T from edge sample counts (each (from, to) once).
    pub fn from_counts(edges: &[EdgeCount], node_samples: &[u32]) -> Transport {
        let mut lists = EdgeLists::default();
        node_samples.iter().for_each(|_| lists.push_node());
        for e in edges {
            for _ in 0..e.samples {
                lists.add(e.from, e.to);
            }
        }
        Transport::from_lists(lists, node_samples)
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.lists.nodes()
    }

    /// Number of edges (non-zero entries).
    pub fn edges(&self) -> usize {
        self.lists.edges()
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        let (rows, pools) = self.lists.memory_bytes();
        rows + pools
    }

    /// The entries of row `a`: (column, weight).
    pub fn row(&self, a: usize) -> impl Iterator<Item = (u32, f32)> + '_ {
        self.lists.row(a as u32).iter().map(|&(b, w)| (b, f32::from_bits(w)))
    }

    /// y = T·x. Rows run in parallel, each summed in order: the same bits at any thread count.
    pub fn apply(&self, x: &[f32], y: &mut [f32]) {
        y.par_iter_mut().enumerate().with_min_len(4096).for_each(|(a, ya)| {
            *ya = self.row(a).map(|(b, w)| w * x[b as usize]).sum();
        });
    }

    /// Eq. 4.23 for each bounce count in `bounces` (Algorithm 1, run once up to the largest
    /// count): L'_n = Σ_{i=0}^{k} Tⁱ L_d for k bounces, i.e. paths of up to k + 1 segments.
    pub fn neumann(&self, direct: &[f32], bounces: &[u32]) -> Vec<Transported> {
        assert_eq!(direct.len(), self.nodes());
        let max = bounces.iter().copied().max().unwrap_or(0);
        let mut total = direct.to_vec();
        let mut current = direct.to_vec();
        let mut next = vec![0.0; direct.len()];
        // Snapshots of the running sum after each bounce a caller asked for.
        let mut out: Vec<Transported> = Vec::with_capacity(bounces.len());
        let snapshot = |done: u32, total: &Vec<f32>, out: &mut Vec<Transported>| {
            for &b in bounces.iter().filter(|&&b| b == done) {
                out.push(Transported { bounces: b, bounces_done: done, radiance: total.clone() });
            }
        };
        snapshot(0, &total, &mut out);
        let mut done = 0;
        while done < max {
            self.apply(&current, &mut next);
            if next.iter().any(|v| !v.is_finite()) {
                break;
            }
            std::mem::swap(&mut current, &mut next);
            total.iter_mut().zip(&current).for_each(|(t, c)| *t += c);
            done += 1;
            snapshot(done, &total, &mut out);
        }
        // Counts beyond the numerical limit get the last finite sum.
        for &b in bounces.iter().filter(|&&b| b > done) {
            out.push(Transported { bounces: b, bounces_done: done, radiance: total.clone() });
        }
        // In the order asked.
        let mut ordered = Vec::with_capacity(bounces.len());
        for &b in bounces {
            let i = out.iter().position(|t| t.bounces == b).expect("every count was recorded");
            ordered.push(out.swap_remove(i));
        }
        ordered
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(from: u32, to: u32, samples: u32) -> EdgeCount {
        EdgeCount { from, to, samples }
    }

    /// The thesis's example of Sec. 4.5.1, to path length 3 (2 bounces): [0.1, 0.28, 0.44, 0.54].
    #[test]
    fn thesis_transport_example() {
        // w(1,0) = 0.8 (4 of 5 samples), w(2,1) = w(3,1) = 0.5 (1 of 2).
        let t = Transport::from_counts(&[e(1, 0, 4), e(2, 1, 1), e(3, 1, 1)], &[0, 5, 2, 2]);
        let r = t.neumann(&[0.1, 0.2, 0.3, 0.4], &[2]);
        let want = [0.1, 0.28, 0.44, 0.54];
        for (g, w) in r[0].radiance.iter().zip(want) {
            assert!((g - w).abs() < 1e-6, "{:?}", r[0].radiance);
        }
        assert_eq!(r[0].bounces_done, 2);
    }

    /// A 3-node cycle solved by hand: T = [[0, ½, 0], [0, 0, ½], [¼, 0, 0]], L_d = (1, 2, 4).
    /// TL = (1, 2, ¼), T²L = (1, ⅛, ¼), T³L = (1/16, ⅛, ¼), so 3 bounces give
    /// (3.0625, 4.25, 4.75); the full series solves (I − T)L' = L_d: (3.2, 4.4, 4.8).
    #[test]
    fn three_node_cycle_by_hand() {
        let t = Transport::from_counts(&[e(0, 1, 1), e(1, 2, 2), e(2, 0, 1)], &[2, 4, 4]);
        let r = t.neumann(&[1.0, 2.0, 4.0], &[3, 0, 200, 1]);
        assert_eq!(r.iter().map(|t| t.bounces).collect::<Vec<_>>(), [3, 0, 200, 1]);
        assert_eq!(r[0].radiance, [3.0625, 4.25, 4.75]);
        assert_eq!(r[1].radiance, [1.0, 2.0, 4.0]);
        assert_eq!(r[3].radiance, [2.0, 4.0, 4.25]);
        for (g, w) in r[2].radiance.iter().zip([3.2, 4.4, 4.8]) {
            assert!((g - w).abs() < 1e-5, "{:?}", r[2].radiance);
        }
        assert_eq!(t.nodes(), 3);
        assert_eq!(t.edges(), 3);
        assert!(t.memory_bytes() >= 3 * 8 + 3 * 8);
    }

    /// A row summing above 1 (impossible from one build, possible from a corrupt file)
    /// diverges; the series stops at the last finite sum and says so.
    #[test]
    fn divergence_stops_at_the_numerical_limit() {
        let t = Transport::from_counts(&[e(0, 0, 1000)], &[1]);
        let r = t.neumann(&[1.0], &[50]);
        assert!(r[0].bounces_done < 50 && r[0].radiance[0].is_finite(), "{:?}", r[0]);
    }

    /// Any thread count gives the same bits.
    #[test]
    fn apply_is_deterministic() {
        let n = 20_000u32;
        let edges: Vec<EdgeCount> =
            (0..n).flat_map(|a| [e(a, (a * 7 + 1) % n, 3), e(a, (a * 13 + 5) % n, 1)]).collect();
        let mut edges = edges;
        edges.sort();
        edges.dedup_by_key(|x| (x.from, x.to));
        let t = Transport::from_counts(&edges, &vec![10; n as usize]);
        let x: Vec<f32> = (0..n).map(|i| (i as f32 * 0.37).sin().abs()).collect();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| t.neumann(&x, &[5])[0].radiance.clone())
        };
        assert_eq!(run(1), run(2));
    }
}
