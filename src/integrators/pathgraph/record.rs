//! Recording a path graph through the shared path loop's observer (Sec. 3.4, Fig. 3).
//!
//! The loop reports each scattering vertex (throughput β before it, f and the sampling
//! density of the continuation), each next-event estimate and each emission it adds. At the
//! end of a path these become graph vertices whose quantities are per unit of β, so that a
//! vertex's scattered radiance is
//!
//! L̄ᵢ = Eᵢ + Rᵢ + wᵢ ∘ L⁺ᵢ,    L⁺ᵢ = cᵢ + Pᵢ ∘ L̄ₙₑₓₜ₍ᵢ₎
//!
//! with E the light-sampled direct light (the NEE contribution / β), R the emission the
//! continuation direction found with an MIS partner (its contribution / β), w = f/p the
//! continuation weight, P = β_next/(β ∘ w) the continuation edge's factor per RGB channel
//! (transmittance over the distance pdf, Eq. 27, chromatic extinction and Russian roulette
//! included) and c the radiance found along the edge that no other technique could find
//! (medium emission, lights behind specular bounces, next-event estimates at specular
//! vertices). Medium vertices and diffuse/glossy surface vertices are graph vertices;
//! vertices that continued by a specular sample fold into the continuation edge. Without
//! any aggregation these quantities give back the path-traced pixel exactly.

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::NONE;
use crate::channels::Channels;
use crate::color::Rgb;
use crate::integrators::common::{EmissionEvent, NeeEvent, PathRecorder, PathStrategy, VertexEvent};

/// Graph vertices, struct of arrays.
#[derive(Debug, Default)]
pub struct Vertices {
    /// Position. Only clustering reads it: the solve takes the array to hold L⁺.
    pub p: Vec<Vec3>,
    /// Direction back along the incoming ray.
    pub wo: Vec<Vec3>,
    /// Continuation direction (the phase- or BSDF-sampled direction).
    pub wi: Vec<Vec3>,
    /// Henyey-Greenstein asymmetry of a medium vertex; NaN at surface vertices.
    pub g: Vec<f32>,
    /// Shading normal of a Lambertian surface vertex, on the side of `wo`; zero at medium
    /// vertices and at other surfaces (which are not clustered: their BSDF is not stored).
    pub n: Vec<Vec3>,
    /// f/p of the continuation direction.
    pub w: Vec<Rgb>,
    /// Light-sampled direct light, MIS-weighted, per unit of β. Only the first pass reads it:
    /// the solve then keeps in this array, at each path's first vertex, the path-traced
    /// indirect light there (for the pixel's unbiased estimate).
    pub direct_light: Vec<Rgb>,
    /// Direction of the light sample.
    pub light_wi: Vec<Vec3>,
    /// Light-sampling density of the light sample (light choice × solid angle).
    pub light_pdf: Vec<f32>,
    /// Phase density of the light sample's direction (0 for a delta light).
    pub light_pdf_scatter: Vec<f32>,
    /// Emission found along the continuation direction with an MIS partner, per unit of β.
    pub direct_scatter: Vec<Rgb>,
    /// Light-sampling density of that emission's direction.
    pub scatter_pdf_light: Vec<f32>,
    /// Radiance along the continuation edge found by no other technique (L⁺ units).
    pub edge_const: Vec<Rgb>,
    /// Continuation edge factor P (Eq. 27), per channel.
    pub edge: Vec<Rgb>,
    /// The next graph vertex on the path, or NONE.
    pub next: Vec<u32>,
}

impl Vertices {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.wo.len()
    }

    /// Bytes per vertex of these arrays.
    pub const BYTES_PER_VERTEX: usize = 3 * 12 + 4 + 12 + 12 + 12 + 12 + 4 + 4 + 12 + 4 + 12 + 12 + 4;

    /// Room for at least `n` vertices in every array.
    pub fn reserve_total(&mut self, n: usize) {
        let more = n.saturating_sub(self.len());
        self.p.reserve(more);
        self.wo.reserve(more);
        self.wi.reserve(more);
        self.g.reserve(more);
        self.n.reserve(more);
        self.w.reserve(more);
        self.direct_light.reserve(more);
        self.light_wi.reserve(more);
        self.light_pdf.reserve(more);
        self.light_pdf_scatter.reserve(more);
        self.direct_scatter.reserve(more);
        self.scatter_pdf_light.reserve(more);
        self.edge_const.reserve(more);
        self.edge.reserve(more);
        self.next.reserve(more);
    }

    /// Removes every vertex, keeping the arrays' memory for the next sample.
    pub fn clear(&mut self) {
        self.p.clear();
        self.wo.clear();
        self.wi.clear();
        self.g.clear();
        self.n.clear();
        self.w.clear();
        self.direct_light.clear();
        self.light_wi.clear();
        self.light_pdf.clear();
        self.light_pdf_scatter.clear();
        self.direct_scatter.clear();
        self.scatter_pdf_light.clear();
        self.edge_const.clear();
        self.edge.clear();
        self.next.clear();
    }

    /// Appends `o`, whose `next` indices are relative to its own start. `o` is left empty
    /// with its memory.
    pub fn append(&mut self, o: &mut Vertices) {
        let base = self.len() as u32;
        self.p.append(&mut o.p);
        self.wo.append(&mut o.wo);
        self.wi.append(&mut o.wi);
        self.g.append(&mut o.g);
        self.n.append(&mut o.n);
        self.w.append(&mut o.w);
        self.direct_light.append(&mut o.direct_light);
        self.light_wi.append(&mut o.light_wi);
        self.light_pdf.append(&mut o.light_pdf);
        self.light_pdf_scatter.append(&mut o.light_pdf_scatter);
        self.direct_scatter.append(&mut o.direct_scatter);
        self.scatter_pdf_light.append(&mut o.scatter_pdf_light);
        self.edge_const.append(&mut o.edge_const);
        self.edge.append(&mut o.edge);
        self.next.extend(o.next.drain(..).map(|n| if n == NONE { NONE } else { n + base }));
    }

    /// Reorders the vertices (all but their positions, which the caller has taken: only
    /// clustering needs them) and `extra` (one more value per vertex) to `order` (a
    /// permutation; `rank` its inverse), renumbering `next`. One array at a time through
    /// `spare`, which ends holding old arrays' memory (one array of each element size, free
    /// for the solve to use), so the reordering needs one array's worth of memory extra and,
    /// from the second sample on, allocates none.
    pub fn permute(&mut self, extra: &mut Vec<Rgb>, order: &[u32], rank: &[u32], spare: &mut Spare) {
        assert!(self.p.is_empty(), "positions are not reordered");
        fn gather<T: Copy + Send + Sync>(v: &mut Vec<T>, spare: &mut Vec<T>, order: &[u32]) {
            spare.clear();
            spare.par_extend(order.par_iter().with_min_len(4096).map(|&i| v[i as usize]));
            std::mem::swap(v, spare);
        }
        let Spare { v3, f, u } = spare;
        gather(extra, v3, order);
        gather(&mut self.wo, v3, order);
        gather(&mut self.wi, v3, order);
        gather(&mut self.g, f, order);
        gather(&mut self.n, v3, order);
        gather(&mut self.w, v3, order);
        gather(&mut self.direct_light, v3, order);
        gather(&mut self.light_wi, v3, order);
        gather(&mut self.light_pdf, f, order);
        gather(&mut self.light_pdf_scatter, f, order);
        gather(&mut self.direct_scatter, v3, order);
        gather(&mut self.scatter_pdf_light, f, order);
        gather(&mut self.edge_const, v3, order);
        gather(&mut self.edge, v3, order);
        u.clear();
        u.par_extend(order.par_iter().with_min_len(4096).map(|&i| {
            let n = self.next[i as usize];
            if n == NONE { NONE } else { rank[n as usize] }
        }));
        std::mem::swap(&mut self.next, u);
    }
}

/// One spare array per element size, for [`Vertices::permute`]; between permutations the
/// solve borrows them.
#[derive(Debug, Default)]
pub struct Spare {
    pub v3: Vec<Vec3>,
    pub f: Vec<f32>,
    pub u: Vec<u32>,
}

/// Recorded paths, one per camera ray, struct of arrays.
#[derive(Debug, Default)]
pub struct Paths {
    /// The pixel's film index.
    pub pixel: Vec<u32>,
    /// The camera sample's filter weight.
    pub weight: Vec<f32>,
    /// Radiance the graph does not refine: what the path found before its first graph vertex
    /// (seen emitters, and everything when the path has no graph vertex) and the
    /// non-aggregated direct light there (Sec. 4; the extra light samples' when `extradirect`
    /// asked for them), times the throughput arriving there. The solve ends by adding the
    /// refined indirect light, leaving each pixel's value here.
    pub before: Vec<Rgb>,
    /// The first graph vertex, or NONE.
    pub first: Vec<u32>,
    /// Throughput arriving at the first graph vertex. The solve ends by replacing it with
    /// the path-traced estimate's difference from the pixel's value (U − G), when pixels are
    /// combined with it.
    pub beta: Vec<Rgb>,
}

impl Paths {
    /// Bytes per path of these arrays.
    pub const BYTES_PER_PATH: usize = 4 + 4 + 12 + 4 + 12;

    /// Room for at least `n` paths in every array.
    pub fn reserve_total(&mut self, n: usize) {
        let more = n.saturating_sub(self.len());
        self.pixel.reserve(more);
        self.weight.reserve(more);
        self.before.reserve(more);
        self.first.reserve(more);
        self.beta.reserve(more);
    }

    /// Removes every path, keeping the arrays' memory.
    pub fn clear(&mut self) {
        self.pixel.clear();
        self.weight.clear();
        self.before.clear();
        self.first.clear();
        self.beta.clear();
    }

    /// Appends `o`, whose vertex indices start at `vertex_base` in the combined vertices.
    /// `o` is left empty with its memory.
    pub fn append(&mut self, o: &mut Paths, vertex_base: u32) {
        self.pixel.append(&mut o.pixel);
        self.weight.append(&mut o.weight);
        self.before.append(&mut o.before);
        self.first.extend(o.first.drain(..).map(|f| if f == NONE { NONE } else { f + vertex_base }));
        self.beta.append(&mut o.beta);
    }

    /// Number of paths.
    pub fn len(&self) -> usize {
        self.pixel.len()
    }

    /// Scales the last path's radiance by `w` (a realistic camera's ray weight): what the graph
    /// does not refine and the throughput arriving at its first graph vertex, which every
    /// other quantity of the path is relative to.
    pub fn scale_last(&mut self, w: f32) {
        if let (Some(before), Some(beta)) = (self.before.last_mut(), self.beta.last_mut()) {
            *before *= w;
            *beta *= w;
        }
    }
}

/// The path loop's observer: collects one path's events (per-thread scratch, reused), in the
/// channels the path carries.
pub struct Recorder<C: Channels> {
    vertices: Vec<VertexEvent<C>>,
    nee: Vec<NeeEvent<C>>,
    emission: Vec<EmissionEvent<C>>,
    extra: Option<(u32, C)>,
    /// The extra first vertices' direct light along the camera line, each stretch's sum over
    /// its samples and the path's own vertex (`PathConfig::line_direct`), and the share left
    /// to the own first vertex's direct light when it was on such a stretch (else 1).
    line: C,
    line_share: f32,
    /// The extra samples' sample variances so far, summed over stretches and paths: the
    /// variance of one first vertex's direct light, which decides how many to take.
    pub line_spread: f64,
    /// Graph vertex (index into the per-path arrays below) of each scattering vertex, by
    /// depth; NONE for folded ones.
    graph: Vec<u32>,
    /// Per graph vertex of the path: depth, E, R, c, w, P, L⁺ and L̄ in the path's channels.
    depth: Vec<usize>,
    e: Vec<C>,
    r: Vec<C>,
    c: Vec<C>,
    w: Vec<C>,
    edge: Vec<C>,
    l_plus: Vec<C>,
    scattered: Vec<C>,
    /// Σ weight and Σ weight × light pdf of each vertex's MIS-partnered emission.
    scatter_weights: Vec<(f32, f32)>,
    /// Each vertex's light sample: direction, light density, phase density.
    light: Vec<(Vec3, f32, f32)>,
}

impl<C: Channels> Default for Recorder<C> {
    fn default() -> Self {
        Recorder {
            vertices: Vec::new(),
            nee: Vec::new(),
            emission: Vec::new(),
            extra: None,
            line: C::ZERO,
            line_share: 1.0,
            line_spread: 0.0,
            graph: Vec::new(),
            depth: Vec::new(),
            e: Vec::new(),
            r: Vec::new(),
            c: Vec::new(),
            w: Vec::new(),
            edge: Vec::new(),
            l_plus: Vec::new(),
            scattered: Vec::new(),
            scatter_weights: Vec::new(),
            light: Vec::new(),
        }
    }
}

impl<C: Channels> PathStrategy for Recorder<C> {}

impl<C: Channels> PathRecorder<C> for Recorder<C> {
    #[inline]
    fn on_vertex(&mut self, v: &VertexEvent<C>) {
        self.vertices.push(*v);
    }
    #[inline]
    fn on_nee(&mut self, e: &NeeEvent<C>) {
        self.nee.push(*e);
    }
    #[inline]
    fn on_emission(&mut self, e: &EmissionEvent<C>) {
        self.emission.push(*e);
    }
    #[inline]
    fn on_extra_direct(&mut self, depth: u32, contribution: C) {
        self.extra = Some((depth, contribution));
    }
    #[inline]
    fn on_line_direct(&mut self, sum: C, spread: f32, samples: u32, own: bool) {
        self.line_spread += f64::from(spread);
        let share = 1.0 / (samples + 1) as f32;
        self.line += sum * share;
        if own {
            self.line_share = share;
        }
    }
}

/// Component-wise a/b with 0 where b is 0.
#[inline]
pub(super) fn div<C: Channels>(a: C, b: C) -> C {
    a.zip_map(b, |a, b| if b != 0.0 { a / b } else { 0.0 })
}

/// The RGB factor that maps `to_rgb(x)` to `to_rgb(f ∘ x)`, channel by channel: exact for the
/// path's own values (so a cluster of one reproduces the path-traced pixel in any
/// representation), and f's own RGB where x has no signal in a channel. In RGB it is f.
/// `one` is `to_rgb(C::ONE)` (the same for every vertex of a path); f's own RGB is converted
/// only where it is needed (each conversion is a sensor's 3×4 at the path's wavelengths).
#[inline]
fn rgb_factor<C: Channels>(f: C, x: C, to_rgb: &impl Fn(C) -> Rgb, one: Rgb) -> Rgb {
    let (num, den) = (to_rgb(f * x), to_rgb(x));
    let floor = 1e-12 * (den.abs().max_element() + 1e-30);
    let has_signal = |k: usize| den[k].abs() > floor && den[k] != 0.0;
    if (0..3).all(has_signal) {
        return num / den;
    }
    let fr = to_rgb(f);
    Rgb::from_array(std::array::from_fn(|k| {
        if has_signal(k) {
            num[k] / den[k]
        } else if one[k].abs() > 1e-12 {
            fr[k] / one[k]
        } else {
            f.average()
        }
    }))
}

impl<C: Channels> Recorder<C> {
    /// Turns the recorded path of the camera ray for film pixel `pixel` into graph vertices
    /// and a path entry, and clears the scratch for the next path. `to_rgb` is the film's
    /// linear map from the path's channels to RGB (the sensor at the path's wavelengths):
    /// the graph aggregates across paths, so it stores what the film would see.
    pub fn finish(
        &mut self,
        pixel: u32,
        weight: f32,
        to_rgb: impl Fn(C) -> Rgb,
        vertices: &mut Vertices,
        paths: &mut Paths,
    ) {
        // The map is linear: its columns once per path, then each conversion is a 3×4 product.
        let columns: [Rgb; 4] = std::array::from_fn(|k| {
            if k < C::CHANNELS {
                let mut e = glam::Vec4::ZERO;
                e[k] = 1.0;
                to_rgb(C::from_lanes(e))
            } else {
                Rgb::ZERO
            }
        });
        let to_rgb = |x: C| {
            let l = x.to_lanes();
            columns[0] * l.x + columns[1] * l.y + columns[2] * l.z + columns[3] * l.w
        };
        self.graph.clear();
        self.depth.clear();
        for (d, v) in self.vertices.iter().enumerate() {
            debug_assert_eq!(v.depth as usize, d);
            if v.specular || v.pdf == 0.0 {
                self.graph.push(NONE);
                continue;
            }
            self.graph.push(self.depth.len() as u32);
            self.depth.push(d);
        }
        let n = self.depth.len();
        for a in [&mut self.e, &mut self.r, &mut self.c, &mut self.edge, &mut self.l_plus, &mut self.scattered] {
            a.clear();
            a.resize(n, C::ZERO);
        }
        self.w.clear();
        self.w.extend(self.depth.iter().map(|&d| div(self.vertices[d].f, C::splat(self.vertices[d].pdf))));
        self.scatter_weights.clear();
        self.scatter_weights.resize(n, (0.0, 0.0));
        self.light.clear();
        self.light.resize(n, (Vec3::Z, 0.0, 0.0));
        // Eq. 27 per channel: what the path multiplied β by between consecutive graph vertices,
        // after the continuation weight at the first.
        for k in 1..n {
            let (a, b) = (&self.vertices[self.depth[k - 1]], &self.vertices[self.depth[k]]);
            self.edge[k - 1] = div(b.beta, a.beta * self.w[k - 1]);
        }
        // The latest graph vertex at a depth below `depth`.
        let graph = &self.graph;
        let before_depth =
            |depth: usize| -> Option<usize> { (0..depth.min(graph.len())).rev().find(|&d| graph[d] != NONE) };
        let mut before = self.line;
        let vs = &self.vertices;
        // Radiance found after graph vertex at depth `d` by no technique the graph aggregates.
        let mut fold = |d: Option<usize>, x: C, c: &mut [C], w: &[C]| match d {
            Some(d) => {
                let k = graph[d] as usize;
                c[k] += div(x, vs[d].beta * w[k]);
            }
            None => before += x,
        };
        for e in &self.nee {
            let d = e.depth as usize;
            match graph.get(d) {
                Some(&k) if k != NONE => {
                    let k = k as usize;
                    self.e[k] += div(e.contribution, vs[d].beta);
                    self.light[k] = (e.wi, e.pdf_light, e.pdf_scatter);
                }
                // The own first vertex's direct light is one of the camera line's estimates.
                _ => {
                    let share = if d == 0 { self.line_share } else { 1.0 };
                    fold(before_depth(d), e.contribution * share, &mut self.c, &self.w)
                }
            }
        }
        for e in &self.emission {
            let d = e.depth as usize;
            let owner = d.checked_sub(1).and_then(|j| graph.get(j).map(|&k| (j, k)));
            match owner {
                Some((j, k)) if k != NONE && e.pdf_light > 0.0 => {
                    let k = k as usize;
                    self.r[k] += div(e.contribution, vs[j].beta);
                    // Several lights can be found along one direction (infinite lights): their
                    // densities are averaged by weight, which keeps the path-traced sum.
                    let y = e.contribution.average().abs().max(1e-30);
                    let sw = &mut self.scatter_weights[k];
                    sw.0 += y;
                    sw.1 += y * e.pdf_light;
                }
                _ => {
                    let share = if d == 1 && e.pdf_light > 0.0 { self.line_share } else { 1.0 };
                    fold(before_depth(d), e.contribution * share, &mut self.c, &self.w)
                }
            }
        }
        // The path-traced L⁺ and L̄ of each graph vertex, backwards along the path.
        for k in (0..n).rev() {
            let next = if k + 1 < n { self.edge[k] * self.scattered[k + 1] } else { C::ZERO };
            self.l_plus[k] = self.c[k] + next;
            self.scattered[k] = self.e[k] + self.r[k] + self.w[k] * self.l_plus[k];
        }
        let one = if n > 0 { to_rgb(C::ONE) } else { Rgb::ZERO };
        let base = vertices.len() as u32;
        for k in 0..n {
            let v = &vs[self.depth[k]];
            vertices.p.push(v.p);
            vertices.wo.push(v.wo);
            vertices.wi.push(v.wi);
            vertices.g.push(if v.in_medium { v.g } else { f32::NAN });
            vertices.n.push(if v.lambertian { if v.n.dot(v.wo) < 0.0 { -v.n } else { v.n } } else { Vec3::ZERO });
            vertices.w.push(rgb_factor(self.w[k], self.l_plus[k], &to_rgb, one));
            vertices.direct_light.push(to_rgb(self.e[k]));
            let (light_wi, light_pdf, light_pdf_scatter) = self.light[k];
            vertices.light_wi.push(light_wi);
            vertices.light_pdf.push(light_pdf);
            vertices.light_pdf_scatter.push(light_pdf_scatter);
            vertices.direct_scatter.push(to_rgb(self.r[k]));
            let (sw, swp) = self.scatter_weights[k];
            vertices.scatter_pdf_light.push(if sw > 0.0 { swp / sw } else { 0.0 });
            vertices.edge_const.push(to_rgb(self.c[k]));
            if k + 1 < n {
                vertices.edge.push(rgb_factor(self.edge[k], self.scattered[k + 1], &to_rgb, one));
                vertices.next.push(base + k as u32 + 1);
            } else {
                vertices.edge.push(Rgb::ZERO);
                vertices.next.push(NONE);
            }
        }
        paths.pixel.push(pixel);
        paths.weight.push(weight);
        if n == 0 {
            paths.before.push(to_rgb(before));
            paths.first.push(NONE);
            paths.beta.push(Rgb::ZERO);
        } else {
            let beta = vs[self.depth[0]].beta;
            let beta_rgb = rgb_factor(beta, self.scattered[0], &to_rgb, one);
            // The pixel's own direct light at its first graph vertex (E + R as the vertex
            // stores them), or the extra light samples' taken there.
            let mut direct = match self.extra {
                Some((depth, c)) if depth as usize == self.depth[0] => to_rgb(div(c, beta)),
                _ => to_rgb(self.e[0]) + to_rgb(self.r[0]),
            };
            if self.depth[0] == 0 {
                direct *= self.line_share;
            }
            paths.before.push(to_rgb(before) + beta_rgb * direct);
            paths.first.push(base);
            paths.beta.push(beta_rgb);
        }
        self.extra = None;
        (self.line, self.line_share) = (C::ZERO, 1.0);
        self.vertices.clear();
        self.nee.clear();
        self.emission.clear();
    }
}
