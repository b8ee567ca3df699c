//! Aggregation (Eqs. 17 and 22) and propagation (Eqs. 12 and 27), iterated as Eq. 28.
//!
//! The vertices arrive sorted by cluster, so each cluster is a contiguous range and the
//! clusters are solved in parallel without sharing anything. Marginal densities depend only
//! on directions, so they and the aggregated direct light A⁰L⁰ are computed once (first
//! pass); every iteration then aggregates L⁺ (A⁺L⁺, second pass) and propagates along the
//! continuation edges. Surface vertices are clusters of one (nimbus stores no BSDF per
//! vertex, README: deviations): their aggregate is their own path-traced estimate.

use glam::Vec3;
use rayon::prelude::*;

use super::lanes::{Hg, Phases, Samples, SwapSamples};
use super::record::{Vertices, div};
use crate::accel::NONE;
use crate::color::Rgb;

/// Clusters per parallel work item.
const BATCH: usize = 256;

/// A path graph ready to iterate: vertices in cluster order with their clusters.
///
/// The sampling techniques of a cluster are its paths, each represented by its earliest
/// vertex in the cluster: a later vertex of the same path is there *because* of the earlier
/// one's sampled direction (a short free flight kept the path inside), so counting it as an
/// independent technique would make the set of techniques depend on the samples and bias the
/// MIS weights — low wherever a sample led deeper into the medium (README: deviations, with
/// the measured effect). A vertex aggregates over the other paths' techniques and itself.
pub struct Solver<'a> {
    v: &'a Vertices,
    /// Cluster start offsets (plus the end).
    offsets: &'a [u32],
    /// Each vertex's path's earliest vertex in its cluster (itself when it is that vertex).
    earliest: Vec<u32>,
    /// Σ over the cluster's techniques of the phase density of each vertex's continuation
    /// direction (the marginal p_m of Eq. 17); NaN for surface vertices.
    marginal: Vec<f32>,
    /// Aggregated scattered direct light A⁰L⁰ (Eq. 22), constant over iterations.
    direct: Vec<Rgb>,
    /// Batches of clusters, as ranges of cluster indices.
    batches: Vec<(usize, usize)>,
}

impl<'a> Solver<'a> {
    /// The first aggregation pass: techniques, marginal densities and the aggregated direct
    /// light. `earliest` is [`earliest`]'s answer; `marginal` is storage to fill (its
    /// contents do not matter); `direct` comes in as the vertices' `direct_scatter` (which
    /// `v` no longer holds: no later pass needs it) and is replaced by the aggregated direct
    /// light A⁰L⁰, so the graph needs no array of its own for it. [`Solver::into_direct`]
    /// gives that array back. `direct_light` is the vertices' light-sampled direct light,
    /// which only this pass reads (so the caller may hold it apart from `v` and reuse it).
    pub fn new(
        v: &'a Vertices,
        direct_light: &[Rgb],
        offsets: &'a [u32],
        earliest: Vec<u32>,
        mut marginal: Vec<f32>,
        mut direct: Vec<Rgb>,
    ) -> Solver<'a> {
        let n = v.len();
        assert_eq!(direct.len(), n, "direct: one value per vertex");
        let clusters = offsets.len() - 1;
        let batches: Vec<(usize, usize)> =
            (0..clusters).step_by(BATCH).map(|c| (c, (c + BATCH).min(clusters))).collect();
        marginal.clear();
        marginal.resize(n, 0.0);
        {
            let parts = split_by_batches(&batches, offsets, &mut marginal, &mut direct);
            parts.into_par_iter().for_each(|(range, marginal, direct)| {
                let mut scratch = Scratch::default();
                let base = offsets[range.0] as usize;
                for c in range.0..range.1 {
                    let r = offsets[c] as usize..offsets[c + 1] as usize;
                    let local = r.start - base..r.end - base;
                    first_pass(
                        v,
                        direct_light,
                        &earliest,
                        r,
                        &mut marginal[local.clone()],
                        &mut direct[local],
                        &mut scratch,
                    );
                }
            });
        }
        Solver { v, offsets, earliest, marginal, direct, batches }
    }

    /// The array `new` took as `direct` (now holding A⁰L⁰), for the vertices to keep as
    /// their `direct_scatter` storage.
    pub fn into_direct(self) -> Vec<Rgb> {
        self.direct
    }

    /// Aggregated scattered radiance L̄ = A⁰L⁰ + A⁺L⁺ (Eq. 25) of every vertex, into `out`.
    pub fn aggregate(&self, l_plus: &[Rgb], out: &mut [Rgb]) {
        let parts = split_one(&self.batches, self.offsets, out);
        parts.into_par_iter().for_each(|(range, out)| {
            let mut samples = (Samples::default(), SwapSamples::default());
            let base = self.offsets[range.0] as usize;
            for c in range.0..range.1 {
                let r = self.offsets[c] as usize..self.offsets[c + 1] as usize;
                let local = r.start - base..r.end - base;
                self.aggregate_cluster(r, l_plus, &mut out[local], &mut samples);
            }
        });
    }

    /// A⁺L⁺ + A⁰L⁰ for the cluster `r`.
    fn aggregate_cluster(
        &self,
        r: std::ops::Range<usize>,
        l_plus: &[Rgb],
        out: &mut [Rgb],
        (samples, swap): &mut (Samples, SwapSamples),
    ) {
        let v = self.v;
        if v.g[r.start].is_nan() {
            // Surface vertices: Lambertian clusters one term at a time, others their own estimate.
            for (o, i) in out.iter_mut().zip(r.clone()) {
                *o = self.direct[i] + self.indirect_in(r.clone(), i, l_plus);
            }
            return;
        }
        // Eq. 17: L̄⁺(xᵢ) = Σⱼ fᵢ(ωⱼ)/p_m(ωⱼ) L⁺ⱼ over the techniques; their values over their
        // marginal first.
        samples.clear();
        swap.clear();
        for j in r.clone() {
            if self.earliest[j] as usize == j {
                samples.push(v.wi[j], l_plus[j] / self.marginal[j]);
                swap.push(v.wi[j], self.marginal[j], l_plus[j]);
            }
        }
        samples.seal();
        swap.seal();
        for (o, i) in out.iter_mut().zip(r.clone()) {
            let hg = Hg::new(v.g[i], v.wo[i]);
            let e = self.earliest[i] as usize;
            let indirect = if e == i {
                samples.weighted_sum(&hg)
            } else {
                // i stands in for its path's earliest vertex e: the marginal swaps p_e for p_i,
                // e's own term leaves the sum and i's joins it.
                let he = Hg::new(v.g[e], v.wo[e]);
                let term = |j: usize| {
                    let f = hg.eval(v.wi[j]);
                    let d = self.marginal[j] - he.eval(v.wi[j]) + f;
                    if d > 0.0 && l_plus[j] != Rgb::ZERO { f / d * l_plus[j] } else { Rgb::ZERO }
                };
                swap.swapped_sum(&hg, &he) - term(e) + term(i)
            };
            *o = self.direct[i] + indirect;
        }
    }

    /// A⁺L⁺ at vertex `i` of the medium cluster `r`, one term at a time.
    fn indirect_in(&self, r: std::ops::Range<usize>, i: usize, l_plus: &[Rgb]) -> Rgb {
        let v = self.v;
        if v.g[i].is_nan() {
            if v.n[i] == Vec3::ZERO {
                return v.w[i] * l_plus[i];
            }
            return v.w[i] * lambertian_indirect(v, &self.earliest, &self.marginal, r, i, l_plus);
        }
        let hg = Hg::new(v.g[i], v.wo[i]);
        let e = self.earliest[i] as usize;
        let mut sum = Rgb::ZERO;
        if e == i {
            for j in r {
                if self.earliest[j] as usize == j && l_plus[j] != Rgb::ZERO {
                    sum += hg.eval(v.wi[j]) / self.marginal[j] * l_plus[j];
                }
            }
            return sum;
        }
        // i stands in for its path's earliest vertex e: the marginal swaps p_e for p_i.
        let he = Hg::new(v.g[e], v.wo[e]);
        for j in r {
            let is_technique = self.earliest[j] as usize == j && j != e;
            if (is_technique || j == i) && l_plus[j] != Rgb::ZERO {
                let f = hg.eval(v.wi[j]);
                let m = self.marginal[j] - he.eval(v.wi[j]) + f;
                if m > 0.0 {
                    sum += f / m * l_plus[j];
                }
            }
        }
        sum
    }

    /// The aggregated scattered indirect light A⁺L⁺ at vertex `i` alone.
    pub fn indirect_at(&self, i: usize, l_plus: &[Rgb]) -> Rgb {
        // The cluster holding i: the last one starting at or before it.
        let cluster = self.offsets.partition_point(|&o| o as usize <= i) - 1;
        let r = self.offsets[cluster] as usize..self.offsets[cluster + 1] as usize;
        self.indirect_in(r, i, l_plus)
    }

    /// Propagation (Eq. 26): L⁺ᵢ = cᵢ + Pᵢ ∘ L̄ₙₑₓₜ₍ᵢ₎ for every vertex.
    pub fn propagate(&self, scattered: &[Rgb], l_plus: &mut [Rgb]) {
        let v = self.v;
        l_plus.par_iter_mut().enumerate().with_min_len(4096).for_each(|(i, l)| {
            let next = v.next[i];
            *l = if next == NONE { v.edge_const[i] } else { v.edge_const[i] + v.edge[i] * scattered[next as usize] };
        });
    }
}

/// Each vertex's path's earliest vertex in its cluster (itself when it is that vertex), into
/// `out`: the vertices are in cluster order (clusters start at `offsets`), each cluster's
/// members in recording order, and `path(i)` names vertex i's path.
pub fn earliest(offsets: &[u32], path: impl Fn(usize) -> u32 + Sync, out: &mut Vec<u32>) {
    let n = *offsets.last().unwrap_or(&0) as usize;
    out.clear();
    out.par_extend((0..n as u32).into_par_iter().with_min_len(4096));
    let clusters = offsets.len().saturating_sub(1);
    // Members of a cluster are in recording order, so a path's first member is its earliest.
    let batches: Vec<(usize, usize)> = (0..clusters).step_by(BATCH).map(|c| (c, (c + BATCH).min(clusters))).collect();
    split_one(&batches, offsets, out).into_par_iter().for_each(|((c0, c1), out)| {
        let base = offsets[c0] as usize;
        for c in c0..c1 {
            let r = offsets[c] as usize..offsets[c + 1] as usize;
            for i in r.clone() {
                if let Some(e) = (r.start..i).find(|&e| path(e) == path(i)) {
                    out[i - base] = e as u32;
                }
            }
        }
    });
}

/// Per-batch scratch of the first pass.
#[derive(Default)]
struct Scratch {
    hg: Vec<Hg>,
    phases: Phases,
    light: Vec<Rgb>,
    light_marginal: Vec<f32>,
    scatter: Vec<Rgb>,
    light_samples: Samples,
    scatter_samples: Samples,
}

/// Marginals and Eq. 22 for the cluster `r` (outputs indexed from the cluster's start;
/// `direct` holds the cluster's `direct_scatter` on the way in).
fn first_pass(
    v: &Vertices,
    direct_light: &[Rgb],
    earliest: &[u32],
    r: std::ops::Range<usize>,
    marginal: &mut [f32],
    direct: &mut [Rgb],
    s: &mut Scratch,
) {
    let i0 = r.start;
    if v.g[i0].is_nan() {
        if v.n[i0] != Vec3::ZERO {
            return lambertian_first_pass(v, direct_light, earliest, r, marginal, direct, s);
        }
        for (k, i) in r.enumerate() {
            marginal[k] = f32::NAN;
            direct[k] += direct_light[i];
        }
        return;
    }
    let technique = |j: usize| earliest[j] as usize == j;
    let n = r.clone().filter(|&j| technique(j)).count() as f32;
    s.hg.clear();
    s.hg.extend(r.clone().map(|i| Hg::new(v.g[i], v.wo[i])));
    s.phases.clear();
    for (h, l) in s.hg.iter().zip(r.clone()) {
        if technique(l) {
            s.phases.push(h);
        }
    }
    s.phases.seal();
    s.light.clear();
    s.scatter.clear();
    s.light_marginal.clear();
    for (k, j) in r.clone().enumerate() {
        let own = &s.hg[k];
        // Phase-sampled directions: the marginal of Eq. 17 (its techniques' phase densities);
        // with K light densities that of Eq. 22's second sum.
        let p_phase = s.phases.sum(v.wi[j]);
        marginal[k] = p_phase;
        // Incoming direct radiance L⁰ recovered from the path's MIS-weighted value (so that a
        // cluster of one gives the path-traced value back exactly).
        let scatter = if direct[k] == Rgb::ZERO {
            Rgb::ZERO
        } else {
            let f = own.eval(v.wi[j]);
            direct[k] * ((f + v.scatter_pdf_light[j]) / f)
        };
        s.scatter.push(scatter);
        // Light-sampled directions (Eq. 22's first sum); a delta light (phase density 0) can
        // only be found by light sampling.
        let (light, light_marginal) = if direct_light[j] == Rgb::ZERO {
            (Rgb::ZERO, 0.0)
        } else {
            let w = v.light_wi[j];
            let f = own.eval(w);
            let (pl, ps) = (v.light_pdf[j], v.light_pdf_scatter[j]);
            (direct_light[j] * ((ps + pl) / f), if ps == 0.0 { f32::NAN } else { s.phases.sum(w) })
        };
        s.light.push(light);
        s.light_marginal.push(light_marginal);
    }
    // The techniques' samples over their marginals, for the vertices that are techniques.
    s.light_samples.clear();
    s.scatter_samples.clear();
    for (m, j) in r.clone().enumerate() {
        if !technique(j) {
            continue;
        }
        if s.light[m] != Rgb::ZERO {
            let pl = n * v.light_pdf[j];
            let p_m = if s.light_marginal[m].is_nan() { pl } else { s.light_marginal[m] + pl };
            s.light_samples.push(v.light_wi[j], s.light[m] / p_m);
        }
        if s.scatter[m] != Rgb::ZERO {
            s.scatter_samples.push(v.wi[j], s.scatter[m] / (marginal[m] + n * v.scatter_pdf_light[j]));
        }
    }
    s.light_samples.seal();
    s.scatter_samples.seal();
    for (k, i) in r.clone().enumerate() {
        let own = &s.hg[k];
        let e = earliest[i] as usize;
        if e == i {
            direct[k] = s.light_samples.weighted_sum(own) + s.scatter_samples.weighted_sum(own);
            continue;
        }
        // i stands in for its path's earliest vertex e, one term at a time.
        let swap = Some(&s.hg[e - r.start]);
        let mut sum = Rgb::ZERO;
        for (m, j) in r.clone().enumerate() {
            if !(technique(j) && j != e) && j != i {
                continue;
            }
            if s.light[m] != Rgb::ZERO {
                let w = v.light_wi[j];
                let f = own.eval(w);
                let pl = n * v.light_pdf[j];
                let p_m = match (s.light_marginal[m].is_nan(), swap) {
                    (true, _) => pl,
                    (false, None) => s.light_marginal[m] + pl,
                    (false, Some(h)) => s.light_marginal[m] - h.eval(w) + f + pl,
                };
                if p_m > 0.0 {
                    sum += f / p_m * s.light[m];
                }
            }
            if s.scatter[m] != Rgb::ZERO {
                let w = v.wi[j];
                let f = own.eval(w);
                let p_m = match swap {
                    None => marginal[m],
                    Some(h) => marginal[m] - h.eval(w) + f,
                } + n * v.scatter_pdf_light[j];
                if p_m > 0.0 {
                    sum += f / p_m * s.scatter[m];
                }
            }
        }
        direct[k] = sum;
    }
}

/// The cosine density of a Lambertian vertex with normal `n` (on the side of its ωo).
#[inline]
fn cosine_pdf(n: Vec3, w: Vec3) -> f32 {
    n.dot(w).max(0.0) * std::f32::consts::FRAC_1_PI
}

/// Eq. 17 at a Lambertian vertex `i` of cluster `r`, before its reflectance: Σⱼ pᵢ(ωⱼ) L⁺ⱼ /
/// p_m(ωⱼ) over the other paths' techniques and i itself (f = R·p for cosine sampling, so the
/// reflectance R = w multiplies the sum).
fn lambertian_indirect(
    v: &Vertices,
    earliest: &[u32],
    marginal: &[f32],
    r: std::ops::Range<usize>,
    i: usize,
    l_plus: &[Rgb],
) -> Rgb {
    let e = earliest[i] as usize;
    let mut sum = Rgb::ZERO;
    for j in r {
        let is_technique = earliest[j] as usize == j && j != e;
        if (is_technique || j == i) && l_plus[j] != Rgb::ZERO {
            let p = cosine_pdf(v.n[i], v.wi[j]);
            // i stands in for its path's earliest vertex e in the marginal.
            let m = if e == i { marginal[j] } else { marginal[j] - cosine_pdf(v.n[e], v.wi[j]) + p };
            if p > 0.0 && m > 0.0 {
                sum += p / m * l_plus[j];
            }
        }
    }
    sum
}

/// Marginals and Eq. 22 for a cluster of Lambertian vertices (f = R·p, p the cosine density):
/// the direct light each sample brought, per unit of its own R and p, over the marginal.
/// `direct` holds the cluster's `direct_scatter` on the way in.
fn lambertian_first_pass(
    v: &Vertices,
    direct_light: &[Rgb],
    earliest: &[u32],
    r: std::ops::Range<usize>,
    marginal: &mut [f32],
    direct: &mut [Rgb],
    s: &mut Scratch,
) {
    let (light_marginal, scatter) = (&mut s.light_marginal, &mut s.scatter);
    // The direct light each phase sample found, per unit of its own R and p (zero where it
    // found none), before `direct` is overwritten.
    scatter.clear();
    scatter.extend(r.clone().enumerate().map(|(m, j)| {
        let own = cosine_pdf(v.n[j], v.wi[j]);
        if direct[m] == Rgb::ZERO || own <= 0.0 {
            Rgb::ZERO
        } else {
            div(direct[m] * ((own + v.scatter_pdf_light[j]) / own), v.w[j])
        }
    }));
    let technique = |j: usize| earliest[j] as usize == j;
    let count = r.clone().filter(|&j| technique(j)).count() as f32;
    let sum_pdf = |w: Vec3| -> f32 { r.clone().filter(|&l| technique(l)).map(|l| cosine_pdf(v.n[l], w)).sum() };
    // The marginals of the phase-sampled and of the light-sampled directions (NaN: a delta
    // light, found by light sampling only).
    light_marginal.clear();
    for (k, j) in r.clone().enumerate() {
        marginal[k] = sum_pdf(v.wi[j]);
        light_marginal.push(if v.light_pdf_scatter[j] == 0.0 { f32::NAN } else { sum_pdf(v.light_wi[j]) });
    }
    for (k, i) in r.clone().enumerate() {
        let e = earliest[i] as usize;
        let mut sum = Rgb::ZERO;
        for (m, j) in r.clone().enumerate() {
            if !(technique(j) && j != e) && j != i {
                continue;
            }
            let swap = |w: Vec3, p_i: f32| if e == i { 0.0 } else { p_i - cosine_pdf(v.n[e], w) };
            if direct_light[j] != Rgb::ZERO {
                let w = v.light_wi[j];
                let (pl, ps) = (v.light_pdf[j], v.light_pdf_scatter[j]);
                let own = cosine_pdf(v.n[j], w);
                let l0 = div(direct_light[j] * ((ps + pl) / own), v.w[j]);
                let p_i = cosine_pdf(v.n[i], w);
                let p_m = if ps == 0.0 { count * pl } else { light_marginal[m] + swap(w, p_i) + count * pl };
                if p_i > 0.0 && p_m > 0.0 && own > 0.0 {
                    sum += p_i / p_m * l0;
                }
            }
            if scatter[m] != Rgb::ZERO {
                let w = v.wi[j];
                let p_i = cosine_pdf(v.n[i], w);
                let p_m = marginal[m] + swap(w, p_i) + count * v.scatter_pdf_light[j];
                if p_i > 0.0 && p_m > 0.0 {
                    sum += p_i / p_m * scatter[m];
                }
            }
        }
        direct[k] = v.w[i] * sum;
    }
}

type Batch<'s, T> = ((usize, usize), &'s mut [T]);

/// `out` cut into the vertex ranges of `batches`.
fn split_one<'s, T>(batches: &[(usize, usize)], offsets: &[u32], mut out: &'s mut [T]) -> Vec<Batch<'s, T>> {
    let mut parts = Vec::with_capacity(batches.len());
    for &(c0, c1) in batches {
        let len = (offsets[c1] - offsets[c0]) as usize;
        let (head, tail) = std::mem::take(&mut out).split_at_mut(len);
        parts.push(((c0, c1), head));
        out = tail;
    }
    parts
}

/// Two arrays cut into the vertex ranges of `batches`.
#[allow(clippy::type_complexity)]
fn split_by_batches<'s>(
    batches: &[(usize, usize)],
    offsets: &[u32],
    a: &'s mut [f32],
    b: &'s mut [Rgb],
) -> Vec<((usize, usize), &'s mut [f32], &'s mut [Rgb])> {
    split_one(batches, offsets, a)
        .into_iter()
        .zip(split_one(batches, offsets, b))
        .map(|((r, a), (_, b))| (r, a, b))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::phase::HenyeyGreenstein;
    use glam::Vec2;

    /// Appends a vertex of its own path with no light found: a medium vertex of asymmetry `g`,
    /// or (g NaN) a Lambertian one with normal `n` and reflectance `w`.
    fn push_vertex(v: &mut Vertices, wo: Vec3, wi: Vec3, g: f32, n: Vec3, w: Rgb) {
        v.p.push(Vec3::ZERO);
        v.wo.push(wo);
        v.wi.push(wi);
        v.g.push(g);
        v.n.push(n);
        v.w.push(w);
        v.direct_light.push(Rgb::ZERO);
        v.light_wi.push(Vec3::Z);
        v.light_pdf.push(0.0);
        v.light_pdf_scatter.push(0.0);
        v.direct_scatter.push(Rgb::ZERO);
        v.scatter_pdf_light.push(0.0);
        v.edge_const.push(Rgb::ZERO);
        v.edge.push(Rgb::ZERO);
        v.next.push(NONE);
    }

    /// Aggregates `l_plus` over `v` as one cluster.
    fn aggregate_one_cluster(v: &Vertices, l_plus: &[Rgb]) -> Vec<Rgb> {
        let offsets = [0u32, v.len() as u32];
        let mut out = vec![Rgb::ZERO; v.len()];
        // Every vertex is its own path.
        let earliest = (0..v.len() as u32).collect();
        Solver::new(v, &v.direct_light, &offsets, earliest, Vec::new(), v.direct_scatter.clone())
            .aggregate(l_plus, &mut out);
        out
    }

    /// Two isotropic medium vertices in one cluster, no lights: Eq. 17 by hand. With p = 1/4π
    /// for both, p_m = 2/4π and L̄⁺ᵢ = Σⱼ (1/4π)/(2/4π) L⁺ⱼ = the mean of the two L⁺.
    #[test]
    fn two_point_cluster_averages_indirect_light() {
        let mut v = Vertices::default();
        push_vertex(&mut v, Vec3::Z, Vec3::X, 0.0, Vec3::ZERO, Rgb::ONE);
        push_vertex(&mut v, Vec3::Z, -Vec3::Y, 0.0, Vec3::ZERO, Rgb::ONE);
        let out = aggregate_one_cluster(&v, &[Rgb::new(1.0, 2.0, 3.0), Rgb::new(3.0, 0.0, 1.0)]);
        for o in out {
            assert!((o - Rgb::new(2.0, 1.0, 2.0)).abs().max_element() < 1e-5, "{o}");
        }
    }

    /// Two Lambertian vertices with the same normal and reflectance R: with cosine sampling
    /// both densities agree, p_m = 2p, and each gets R × the mean of the two L⁺.
    #[test]
    fn lambertian_cluster_averages_indirect_light() {
        let (wo, r) = (Vec3::new(0.3, 0.0, 1.0).normalize(), Rgb::new(0.5, 0.25, 1.0));
        let mut v = Vertices::default();
        push_vertex(&mut v, wo, Vec3::new(0.6, 0.0, 0.8), f32::NAN, Vec3::Z, r);
        push_vertex(&mut v, wo, Vec3::new(0.0, -0.28, 0.96), f32::NAN, Vec3::Z, r);
        let out = aggregate_one_cluster(&v, &[Rgb::new(1.0, 2.0, 3.0), Rgb::new(3.0, 0.0, 1.0)]);
        // p(ω₀) ≠ p(ω₁), but both points have the same density: each sample's weight is 1/2.
        let expected = r * Rgb::new(2.0, 1.0, 2.0);
        for o in out {
            assert!((o - expected).abs().max_element() < 1e-5, "{o} vs {expected}");
        }
    }

    /// Light-sampled direct light from a point light (delta: only light sampling finds it)
    /// in a cluster of two isotropic vertices: each vertex gets the mean of the two samples.
    #[test]
    fn delta_light_samples_are_averaged() {
        let mut v = Vertices::default();
        for e in [4.0, 2.0] {
            push_vertex(&mut v, Vec3::Z, Vec3::X, 0.0, Vec3::ZERO, Rgb::ONE);
            *v.direct_light.last_mut().unwrap() = Rgb::splat(e);
            *v.light_wi.last_mut().unwrap() = Vec3::Y;
            *v.light_pdf.last_mut().unwrap() = 1.0;
        }
        for o in aggregate_one_cluster(&v, &[Rgb::ZERO; 2]) {
            assert!((o - Rgb::splat(3.0)).abs().max_element() < 1e-5, "{o}");
        }
    }

    /// Eq. 17 is unbiased when every member sees the same radiance function L(ω): over many
    /// clusters of 4 points with different ωo (g = 0.7; the first always looking along +z)
    /// and ω sampled from each point's phase function, the aggregate at the first point
    /// averages to ∫ p(ωo, ω) L(ω) dω, which for L(ω) = 1 + ω_z is 1 − g ωo_z (the HG lobe's
    /// mean direction is −g ωo).
    #[test]
    fn aggregation_is_unbiased_for_a_shared_radiance_function() {
        let g = 0.7;
        let mut state = 12345u64;
        let mut u = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32 + 0.5) / (1u64 << 24) as f32
        };
        let (mut sum, mut n) = (0.0f64, 0usize);
        for _ in 0..40_000 {
            let mut v = Vertices::default();
            for k in 0..4 {
                let z = 1.0 - 2.0 * u();
                let phi = 2.0 * std::f32::consts::PI * u();
                let r = (1.0 - z * z).max(0.0).sqrt();
                let wo = if k == 0 { Vec3::Z } else { Vec3::new(r * phi.cos(), r * phi.sin(), z) };
                let wi = HenyeyGreenstein::new(g).sample_p(wo, Vec2::new(u(), u())).unwrap().wi;
                push_vertex(&mut v, wo, wi, g, Vec3::ZERO, Rgb::ONE);
            }
            let l: Vec<Rgb> = v.wi.iter().map(|w| Rgb::splat(1.0 + w.z)).collect();
            sum += f64::from(aggregate_one_cluster(&v, &l)[0].x);
            n += 1;
        }
        let (mean, expected) = (sum / n as f64, 1.0 - f64::from(g));
        assert!((mean - expected).abs() < 0.01, "aggregate mean {mean}, expected {expected}");
    }
}
