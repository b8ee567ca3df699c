//! Radiance transport through the graph (thesis Sec. 4.5): the sparse transport matrix T of
//! Eq. 4.8 with the sampled edge weights of Eq. 4.20, and the Neumann series of Eq. 4.23
//! computed as Algorithm 1 does, one sparse matrix–vector product per bounce.

use glam::Vec3;
use rayon::prelude::*;

use super::edges::EdgeLists;
use super::sh;

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
    /// L'_n of Eq. 4.23 per node (per node [`sh::COEFFS`] coefficients of directional
    /// transport, [`Transport::neumann_directional`]).
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
    /// With a `tail`, the series also ends once the bounces still to come follow the
    /// transport's slowest mode (power iteration: the ratio of consecutive bounces' totals
    /// has settled, to [`SETTLED`] for [`SETTLED_BOUNCES`] bounces in a row): they are then
    /// the last bounce times r/(1 − r), added node by node. It ends too where they would add
    /// less than `tail` of the sum so far. Counts beyond get that sum, as after an overflow.
    /// In a dense cloud of albedo 1 light lingers in the core for thousands of bounces, each
    /// losing a fraction of a per cent; this sums them in tens.
    pub fn neumann(&self, direct: &[f32], bounces: &[u32], tail: Option<f64>) -> Vec<Transported> {
        assert_eq!(direct.len(), self.nodes());
        series(bounces, direct.to_vec(), tail, |_, current, next| self.apply(current, next))
    }
}

/// A ratio of consecutive bounces' totals has settled when it moves by less than this (times
/// 1 − r, which the extrapolated rest divides by) from one bounce to the next …
pub const SETTLED: f64 = 1e-3;
/// … for this many bounces in a row.
pub const SETTLED_BOUNCES: u32 = 4;

/// Algorithm 1's loop for each bounce count in `bounces`: `step(done, current, next)` computes
/// the next bounce from the current one (`done` bounces so far: 0 from the direct light), and
/// the running sum starts at `total` (the current bounce's values too). A bounce whose values
/// overflow to ∞ or NaN ends the series (the thesis's "numerical limits reached"): counts
/// beyond it get the last finite sum; so does a `tail` reached ([`Transport::neumann`]).
fn series(
    bounces: &[u32],
    total: Vec<f32>,
    tail: Option<f64>,
    mut step: impl FnMut(u32, &[f32], &mut [f32]),
) -> Vec<Transported> {
    let max = bounces.iter().copied().max().unwrap_or(0);
    let mut current = total.clone();
    let mut next = vec![0.0; total.len()];
    let mut total = total;
    // Snapshots of the running sum after each bounce a caller asked for.
    let mut out: Vec<Transported> = Vec::with_capacity(bounces.len());
    let snapshot = |done: u32, total: &Vec<f32>, out: &mut Vec<Transported>| {
        for &b in bounces.iter().filter(|&&b| b == done) {
            out.push(Transported { bounces: b, bounces_done: done, radiance: total.clone() });
        }
    };
    snapshot(0, &total, &mut out);
    let mut done = 0;
    let sum = |v: &[f32]| v.iter().map(|&x| f64::from(x)).sum::<f64>();
    let mut before = sum(&current);
    let (mut last_ratio, mut settled) = (f64::NAN, 0);
    while done < max {
        step(done, &current, &mut next);
        if next.iter().any(|v| !v.is_finite()) {
            break;
        }
        std::mem::swap(&mut current, &mut next);
        total.iter_mut().zip(&current).for_each(|(t, c)| *t += c);
        done += 1;
        snapshot(done, &total, &mut out);
        if let Some(tail) = tail {
            // The rest as a geometric series of ratio now/before.
            let now = sum(&current);
            let ratio = now / before;
            if ratio < 1.0 && now * ratio / (1.0 - ratio) < tail * sum(&total) {
                break;
            }
            settled = if (ratio - last_ratio).abs() < SETTLED * (1.0 - ratio) { settled + 1 } else { 0 };
            if ratio < 1.0 && settled >= SETTLED_BOUNCES {
                let rest = (ratio / (1.0 - ratio)) as f32;
                total.iter_mut().zip(&current).for_each(|(t, c)| *t += c * rest);
                break;
            }
            (before, last_ratio) = (now, ratio);
        }
    }
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

/// Bounces transported with direction; later ones carry each node's mean only. Directional
/// transport is no contraction: a light path meets a node from a few directions, read at the
/// nodes' centres, and light can go back and forth along one line with more than the phase
/// function's share (the stress matrix's g = −0.5 sphere, its coarse graph, 100 bounces: +182 %
/// all directional; +2.4 % with 10 directional, +2.3 % with 25, where 25 bounces alone give
/// +2.2 %). After ten bounces at |g| ≤ 0.75 the light has scattered through more than two
/// transport mean free paths and forgotten its direction; the scalar series of the thesis,
/// whose rows sum below 1, carries the rest.
pub const DIRECTIONAL_BOUNCES: u32 = 10;

/// Where a light's direct radiance at the nodes comes from, for directional transport.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A distant light travelling along this unit direction: scattered by the phase function.
    Along(Vec3),
    /// Light from every direction: the direct values are, per node, the coefficients of the
    /// light it scatters toward each direction.
    Everywhere,
    /// A point light at this position: light reaches a node along the line from it.
    Point(Vec3),
    /// Area lights (these scene lights, chosen by area): the direct values are, per node,
    /// coefficients as for [`Source::Everywhere`].
    Area(std::sync::Arc<[u32]>),
    /// A light's light reflected once by the surfaces beside the medium: coefficients as for
    /// [`Source::Everywhere`].
    Reflected(std::sync::Arc<super::volume::GraphLight>),
}

impl Source {
    /// Whether the direct values are per-node coefficients of the scattered light (light
    /// arrives from many directions) rather than one scalar.
    pub fn by_direction(&self) -> bool {
        matches!(self, Source::Everywhere | Source::Area(_) | Source::Reflected(_))
    }
}

impl Transport {
    /// Eq. 4.23 in an anisotropic medium (HG with asymmetry `g`), for each bounce count in
    /// `bounces`: per node the SH coefficients ([`sh::COEFFS`]) of the radiance scattered
    /// there after 1 to k bounces through the graph, as a function of the direction it
    /// leaves in. The direct light (bounce 0) is not included: a render computes it with the
    /// exact phase function, which band 2 cannot hold at g = 0.9.
    ///
    /// Row a gathers from the nodes b its segments landed in, so light travels from b to a
    /// along d = (x_a − x_b)/|x_a − x_b|; what leaves b along d is the direct light scattered
    /// by the exact phase function (first bounce) or b's coefficients evaluated at d (later
    /// ones), and a scatters it into 4π g^l Y_lm(d) per unit (`sh`). An edge from a node to
    /// itself has no direction: the mean over directions of what b sends is gathered
    /// isotropically (band 0 only).
    pub fn neumann_directional(
        &self,
        positions: &[Vec3],
        direct: &[f32],
        source: Source,
        g: f32,
        bounces: &[u32],
    ) -> Vec<Transported> {
        let n = self.nodes();
        let k = sh::COEFFS;
        let per_node = if source.by_direction() { k } else { 1 };
        assert_eq!(direct.len(), n * per_node);
        let bands = sh::bands(g);
        let y00 = sh::basis(Vec3::Z)[0];
        // The direct light is not part of the sum; the first step reads it, not `current`.
        series(bounces, vec![0.0; n * k], None, |done, current, next| {
            let first = done == 0;
            next.par_chunks_mut(k).enumerate().with_min_len(1024).for_each(|(a, acc)| {
                acc.fill(0.0);
                if done >= DIRECTIONAL_BOUNCES {
                    // Past them, the scalar transport of each node's mean (band 0).
                    acc[0] = self.row(a).map(|(b, w)| w * current[b as usize * k]).sum();
                    return;
                }
                for (b, w) in self.row(a) {
                    let b = b as usize;
                    let v = positions[a] - positions[b];
                    let len = v.length();
                    if b == a || len <= 0.0 {
                        // Isotropic: the mean of what b sends, into band 0.
                        let mean = match (first, &source) {
                            (true, Source::Along(_) | Source::Point(_)) => direct[b],
                            (true, Source::Everywhere | Source::Area(_) | Source::Reflected(_)) => direct[b * k] * y00,
                            (false, _) => current[b * k] * y00,
                        };
                        acc[0] += w * mean / y00;
                        continue;
                    }
                    let d = v / len;
                    let y = sh::basis(d);
                    let sent = if first {
                        match &source {
                            Source::Along(dir) => direct[b] * 4.0 * std::f32::consts::PI * sh::hg(dir.dot(d), g),
                            Source::Everywhere | Source::Area(_) | Source::Reflected(_) => {
                                sh::eval(&direct[b * k..(b + 1) * k], d)
                            }
                            Source::Point(pos) => {
                                let dir = (positions[b] - pos).normalize_or_zero();
                                direct[b] * 4.0 * std::f32::consts::PI * sh::hg(dir.dot(d), g)
                            }
                        }
                    } else {
                        current[b * k..(b + 1) * k].iter().zip(&y).map(|(c, y)| c * y).sum()
                    };
                    for i in 0..k {
                        acc[i] += w * sent * bands[i] * y[i];
                    }
                }
            });
        })
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
        let r = t.neumann(&[0.1, 0.2, 0.3, 0.4], &[2], None);
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
        let r = t.neumann(&[1.0, 2.0, 4.0], &[3, 0, 200, 1], None);
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

    /// With a tail the cycle's series stops once the bounces to come are estimated below 10⁻³
    /// of the sum, well before 200, and lands within that of the full solution.
    #[test]
    fn a_tail_ends_the_series_where_the_rest_is_negligible() {
        let t = Transport::from_counts(&[e(0, 1, 1), e(1, 2, 2), e(2, 0, 1)], &[2, 4, 4]);
        let r = t.neumann(&[1.0, 2.0, 4.0], &[200], Some(1e-3));
        assert!(r[0].bounces_done < 40, "{}", r[0].bounces_done);
        let (got, want) = (r[0].radiance.iter().sum::<f32>(), 3.2 + 4.4 + 4.8);
        assert!(got < want && got > want * (1.0 - 2e-3), "{got} against {want}");
    }

    /// A node that keeps 0.99 of its light each bounce (a self-edge of weight 0.99, its other
    /// paths lost): the series is 1/(1 − 0.99) = 100, which the settled ratio's rest reaches
    /// in a few bounces where the plain series would need hundreds.
    #[test]
    fn a_settled_ratio_sums_the_rest_of_the_series() {
        let t = Transport::from_counts(&[e(0, 0, 99)], &[100]);
        let r = t.neumann(&[1.0], &[5000], Some(1e-3));
        assert!((r[0].radiance[0] - 100.0).abs() < 1e-2, "{:?}", r[0].radiance);
        let plain = t.neumann(&[1.0], &[200], None);
        assert!(plain[0].radiance[0] < 90.0);
    }

    /// A row summing above 1 (impossible from one build, possible from a corrupt file)
    /// diverges; the series stops at the last finite sum and says so.
    #[test]
    fn divergence_stops_at_the_numerical_limit() {
        let t = Transport::from_counts(&[e(0, 0, 1000)], &[1]);
        let r = t.neumann(&[1.0], &[50], None);
        assert!(r[0].bounces_done < 50 && r[0].radiance[0].is_finite(), "{:?}", r[0]);
    }

    /// At g = 0 directional transport is the thesis's scalar one less its direct term: band 0
    /// holds the radiance (over Y_00), the other bands are zero, for either source.
    #[test]
    fn directional_transport_at_g_0_is_the_thesis() {
        let t = Transport::from_counts(&[e(0, 1, 1), e(1, 2, 2), e(2, 0, 1), e(1, 1, 1)], &[2, 4, 4]);
        let positions = [Vec3::ZERO, Vec3::new(1.0, 0.5, 0.0), Vec3::new(-0.3, 2.0, 1.0)];
        let direct = [1.0, 2.0, 4.0];
        let scalar = t.neumann(&direct, &[3], None);
        // Isotropic direct light as coefficients: band 0 only, value / Y_00.
        let y00 = sh::basis(Vec3::Z)[0];
        let iso: Vec<f32> =
            direct.iter().flat_map(|&v| (0..sh::COEFFS).map(move |i| if i == 0 { v / y00 } else { 0.0 })).collect();
        for (source, values) in
            [(Source::Along(Vec3::new(0.0, -1.0, 0.0)), &direct[..]), (Source::Everywhere, &iso[..])]
        {
            let r = t.neumann_directional(&positions, values, source, 0.0, &[3]);
            assert_eq!(r[0].bounces_done, 3);
            for (a, c) in r[0].radiance.chunks_exact(sh::COEFFS).enumerate() {
                let want = scalar[0].radiance[a] - direct[a];
                assert!((c[0] * sh::basis(Vec3::Z)[0] - want).abs() < 1e-5, "{a}: {c:?} vs {want}");
                assert!(c[1..].iter().all(|v| v.abs() < 1e-6), "{c:?}");
            }
        }
    }

    /// Two nodes by hand: node 0 gathers from node 1 (weight ½, one bounce). Node 1's direct
    /// light travels along +x; what it sends to node 0 travels along −x, backwards, so it is
    /// 4π p(−1) of it; node 0 scatters that into 1 + 3gμ + 5g² P₂(μ) toward ω, μ = −x·ω.
    #[test]
    fn one_directional_bounce_by_hand() {
        let g = 0.5;
        let t = Transport::from_counts(&[e(0, 1, 1)], &[2, 1]);
        let positions = [Vec3::ZERO, Vec3::X];
        let r = t.neumann_directional(&positions, &[0.0, 1.0], Source::Along(Vec3::X), g, &[1, 4]);
        let sent = 4.0 * std::f32::consts::PI * sh::hg(-1.0, g);
        for w in [Vec3::X, -Vec3::X, Vec3::Y, Vec3::new(0.6, 0.0, 0.8)] {
            let mu = -w.x;
            let want = 0.5 * sent * (1.0 + 3.0 * g * mu + 5.0 * g * g * 0.5 * (3.0 * mu * mu - 1.0));
            let got = sh::eval(&r[0].radiance[..sh::COEFFS], w);
            assert!((got - want).abs() < 1e-4 * want.abs().max(1.0), "{w}: {got} vs {want}");
        }
        // Nothing reaches node 1, and a longer series adds nothing to this chain.
        assert!(r[0].radiance[sh::COEFFS..].iter().all(|&v| v == 0.0));
        assert_eq!(r[1].radiance, r[0].radiance);
    }

    /// Two nodes that send each other light back along one line: at g = −0.5 band 2 returns
    /// 3.75 of each unit to where it came from, so with weights 0.45 each way a round trip
    /// gains 2.8×. Past DIRECTIONAL_BOUNCES only the nodes' means travel (a gain of 0.2 per
    /// round trip), so 300 bounces stay within a few times 10 bounces' light.
    #[test]
    fn a_resonant_line_stays_bounded() {
        let t = Transport::from_counts(&[e(0, 1, 9), e(1, 0, 9)], &[20, 20]);
        let positions = [Vec3::ZERO, Vec3::X];
        let r =
            t.neumann_directional(&positions, &[1.0, 0.0], Source::Along(Vec3::X), -0.5, &[DIRECTIONAL_BOUNCES, 300]);
        let band0 = |i: usize| r[i].radiance[0] + r[i].radiance[sh::COEFFS];
        assert_eq!(r[1].bounces_done, 300);
        assert!(band0(0) > 0.0 && band0(1) < 3.0 * band0(0), "{} then {}", band0(0), band0(1));
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
            pool.install(|| t.neumann(&x, &[5], None)[0].radiance.clone())
        };
        assert_eq!(run(1), run(2));
    }
}
