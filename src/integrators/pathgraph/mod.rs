//! `pathgraph`: volume path graphs (Hu, Deng, Luan, Hašan and Marschner 2024), solved on the
//! CPU. One sample of the image = one 1-spp pass of the shared path loop with a recording
//! observer ([`record`]) + clustering ([`cluster`]) + aggregation and propagation iterated as
//! Eq. 28 ([`solve`]); each pixel takes the refined indirect radiance of its path's first
//! vertex plus the path's own (non-aggregated) direct light there (Sec. 4). More spp average
//! independent graph samples, which the film combines with the paths' own unbiased estimate;
//! once the graph no longer pays for its cost, the rest of the samples are that estimate
//! alone, per camera ray ([`unpaired`]).

mod cluster;
mod lanes;
mod line;
mod nearest;
mod record;
mod settings;
mod solve;
mod unpaired;

pub use settings::PathGraphSettings;

use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

use super::common::{PathConfig, RayStats, trace_path};
use super::image_pass::{ImagePass, RenderChannels};
use super::registry::{Method, MethodSettings};
use super::{ImageIntegrator, Integrator, Outlook, PixelValue};
use crate::accel::NONE;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::samplers::Sampler;
use crate::scene::Scene;
use crate::scene::transport::Transport;
use crate::spectra::{SampledSpectrum, SampledWavelengths};
use record::{Paths, Recorder, Vertices};

/// The registry's entry.
pub const METHOD: Method = Method { name: "pathgraph", aliases: &[], read };

fn read(e: &nimbus_parser::Entity) -> Result<Box<dyn MethodSettings>, nimbus_parser::Error> {
    Ok(Box::new(PathGraphSettings::from_entity(e)?))
}

impl MethodSettings for PathGraphSettings {
    fn method(&self) -> &'static Method {
        &METHOD
    }

    fn set_max_depth(&mut self, depth: u32) -> crate::Result<()> {
        self.max_depth = depth;
        Ok(())
    }

    fn spectral_film_refusal(&self) -> Option<&'static str> {
        Some("pathgraph accumulates RGB and cannot write the spectral film (use \"rgb\" or \"gbuffer\")")
    }

    fn create(&self, scene: &Scene) -> crate::Result<Box<dyn Integrator>> {
        Ok(Box::new(create(self, scene)?))
    }
}

/// The path-graph integrator.
pub struct PathGraph {
    settings: PathGraphSettings,
    config: PathConfig,
    /// The scene has no media: surface vertices are clusters of one, so the graph would give
    /// back each path's own estimate at the cost of recording it. Such scenes are rendered
    /// per camera ray, as volpath renders them.
    without_media: bool,
    report: Mutex<Report>,
    /// Extra first vertices per camera ray, measured and chosen over the first samples.
    line: Mutex<line::LineTuning>,
    /// The recording arrays, kept from one graph sample to the next: allocating them afresh
    /// faulted in every page again (a tenth of a sample's time on fog-emitter at 512×384).
    stores: Mutex<Stores>,
}

/// Arrays a graph sample fills and the next one reuses.
#[derive(Default)]
struct Stores {
    /// The graph: each tile's vertices and paths, appended as soon as the tile is traced (so
    /// the image's graph exists once, not also as per-tile parts), in the order tiles finish.
    vertices: Vertices,
    paths: Paths,
    /// Per running tile, the vertices and paths of its pixels until the tile is done.
    staging: Vec<(Vertices, Paths)>,
}

/// Bytes per vertex the solve adds to the recorded arrays: L̄, the marginal and the technique
/// index (L⁺ takes the place of the positions, the aggregated direct light that of
/// `direct_scatter`).
const SOLVE_BYTES_PER_VERTEX: usize = 12 + 4 + 4;

/// What the graph samples cost, for `--stats`.
#[derive(Clone, Copy, Debug, Default)]
struct Report {
    samples: u32,
    vertices: u64,
    clusters: u64,
    paths: u64,
    record_seconds: f64,
    solve_seconds: f64,
    peak_bytes: usize,
    /// The process's resident memory before the first graph sample, and its peak after the
    /// latest one: what the graph really costs, allocator and temporaries included.
    resident_before: Option<usize>,
    resident_peak: Option<usize>,
    /// The most vertices one sample recorded.
    max_vertices: usize,
    /// This render's graph samples, the rays they traced, the vertices they recorded and
    /// their paths: their work, which sets what a graph costs beyond its paths ([`unpaired`]).
    work: (u32, u64, u64, u64),
    /// The graph samples this render took before the rest were left to the paths' own
    /// estimate alone ([`unpaired`]), if it did.
    stopped_after: Option<u32>,
}

impl Report {
    /// A graph sample's cost beyond its paths, over theirs, from this render's graph samples.
    fn extra_cost(&self) -> f64 {
        let (_, rays, vertices, paths) = self.work;
        unpaired::extra_cost(rays as f64, vertices as f64, paths as f64)
    }
}

/// Creates the integrator.
pub fn create(settings: &PathGraphSettings, scene: &Scene) -> crate::Result<PathGraph> {
    Ok(PathGraph {
        settings: settings.clone(),
        config: PathConfig {
            extra_direct: settings.extra_direct,
            hero_per_segment: true,
            // It estimates area lights seen through media; without any, it only costs.
            camera_line: scene.lights.iter().any(|l| matches!(l.kind, crate::lights::LightKind::Area { .. })),
            ..PathConfig::volpath(settings.max_depth, settings.regularize)
        },
        without_media: scene.media.is_empty(),
        report: Mutex::new(Report::default()),
        line: Mutex::new(line::LineTuning::default()),
        stores: Mutex::new(Stores::default()),
    })
}

impl PathGraph {
    /// Records one 1-spp pass in the channels `C` into `stores`: graph vertices (in film RGB)
    /// and one path per pixel, each tile's in one block, with the path loop's `config`.
    /// Returns the blocks (start and length in the vertex store) in tile order: the canonical
    /// vertex order, which does not depend on the thread count, while the store's order does;
    /// and the paths' Σ of the extra first vertices' sample variances, summed in that order.
    fn record<C: RenderChannels>(
        &self,
        scene: &Scene,
        pass: &ImagePass<'_>,
        config: &PathConfig,
        stores: &mut Stores,
    ) -> (RayStats, Vec<(u32, u32)>, f64) {
        let (mut vertices, mut paths) = (std::mem::take(&mut stores.vertices), std::mem::take(&mut stores.paths));
        vertices.clear();
        paths.clear();
        // One path per pixel and at least as many vertices, reserved before the first tile
        // appends: arrays grown from small sizes left their earlier, smaller copies behind in
        // the heap (7 MiB at 512x384).
        let pixels = pass.pixel_count();
        vertices.reserve_total(pixels);
        paths.reserve_total(pixels);
        let graph = Mutex::new((vertices, paths));
        let staging = Mutex::new(std::mem::take(&mut stores.staging));
        let (blocks, stats) = pass.trace_pixels::<C, _, _>(
            |_| {
                let (v, p) = lock(&staging).pop().unwrap_or_default();
                (Recorder::<C>::default(), v, p)
            },
            |(rec, v, p), px, lambda, sampler, stats| {
                // A ray a realistic camera's lens stopped records an empty path: the pixel
                // still counts the sample, with nothing found.
                if let Some(c) = px.ray {
                    trace_path::<C, Recorder<C>>(
                        scene,
                        c.ray,
                        scene.camera_medium,
                        lambda,
                        sampler,
                        config,
                        rec,
                        stats,
                    );
                }
                let lambda = *lambda;
                rec.finish(px.index, px.weight, |x: C| x.to_film(&lambda, &scene.sensor), v, p);
                if let Some(c) = px.ray
                    && c.weight != 1.0
                {
                    p.scale_last(c.weight);
                }
            },
            |_, (rec, mut v, mut p)| {
                let len = v.len() as u32;
                let start = {
                    let mut g = lock(&graph);
                    let (gv, gp) = &mut *g;
                    let start = gv.len() as u32;
                    gp.append(&mut p, start);
                    gv.append(&mut v);
                    start
                };
                lock(&staging).push((v, p));
                ((start, len), rec.line_spread)
            },
        );
        let spread = blocks.iter().map(|b| b.1).sum();
        let blocks = blocks.into_iter().map(|b| b.0).collect();
        let (vertices, paths) = graph.into_inner().unwrap_or_else(|e| e.into_inner());
        stores.vertices = vertices;
        stores.paths = paths;
        stores.staging = staging.into_inner().unwrap_or_else(|e| e.into_inner());
        (stats, blocks, spread)
    }
}

/// `m` locked, whether or not a thread panicked while holding it (the stores hold no
/// invariant a panic could break: they are emptied before use).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Each vertex's place along its path among the graph vertices (0: the pixel's first).
fn path_positions(v: &Vertices, paths: &Paths) -> Vec<u32> {
    let mut depth = vec![0u32; v.len()];
    for &f in &paths.first {
        let (mut i, mut d) = (f, 0);
        while i != NONE {
            depth[i as usize] = d;
            d += 1;
            i = v.next[i as usize];
        }
    }
    depth
}

/// Whether `maxdepth` cuts enough paths that a vertex's estimate depends on how deep it is:
/// at least 1 % of the paths that have a graph vertex reach `max_depth` graph vertices (a
/// lower bound on the paths the limit ended, as specular events are not graph vertices).
fn truncation_binds(depth: &[u32], max_depth: u32) -> bool {
    let first = depth.iter().filter(|&&d| d == 0).count();
    let last = depth.iter().filter(|&&d| d + 1 >= max_depth).count();
    last * 100 >= first
}

/// The path-traced L⁺ of every vertex (the iteration's start, Sec. 4), into `out`: a backward
/// sweep, as each path's vertices are recorded in order.
fn path_traced(v: &Vertices, out: &mut Vec<Rgb>) {
    let n = v.len();
    out.clear();
    out.resize(n, Rgb::ZERO);
    let mut scattered = Rgb::ZERO;
    for i in (0..n).rev() {
        let next = v.next[i];
        // The next vertex is i + 1 when there is one (a path's vertices are stored together).
        debug_assert!(next == NONE || next as usize == i + 1);
        let lp = if next == NONE { v.edge_const[i] } else { v.edge_const[i] + v.edge[i] * scattered };
        out[i] = lp;
        scattered = v.direct_light[i] + v.direct_scatter[i] + v.w[i] * lp;
    }
}

/// A memory figure of the process from `/proc/self/status` in bytes: `VmRSS` (resident
/// now) or `VmHWM` (resident at the peak so far). None where there is no such file.
fn resident_bytes(field: &str) -> Option<usize> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    let kb: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

impl ImageIntegrator for PathGraph {
    /// While the graph's share of the combined image pays for what the graph costs beyond its
    /// paths, counted from this render's graph samples (rays traced, vertices recorded), not
    /// timed, so that the image does not depend on the machine's speed ([`unpaired`]). Once it
    /// stops paying, graph samples thin out rather than stop: at most one sample in
    /// [`unpaired::THIN`] still builds a graph, so that the film's judgement of the graph's bias
    /// keeps sharpening with the unbiased estimate it is weighed against.
    fn image_sample_pays(&self, sample_index: u32, outlook: &dyn Fn() -> Option<Outlook>) -> bool {
        if !self.settings.combine {
            return true;
        }
        let mut r = lock(&self.report);
        if r.stopped_after.is_some() {
            return unpaired::thinned_graph_sample(outlook, sample_index, r.work.0, r.extra_cost());
        }
        let pays = unpaired::graph_pays(outlook, r.work.0, r.extra_cost());
        if !pays {
            r.stopped_after = Some(r.work.0);
        }
        pays
    }

    fn sample_image(&self, scene: &Scene, pass: &ImagePass<'_>, out: &mut dyn FnMut(PixelValue)) -> RayStats {
        if let Ok(mut r) = self.report.lock()
            && r.samples == 0
        {
            r.resident_before = resident_bytes("VmRSS:");
        }
        let start = Instant::now();
        if pass.sample_index() == 0 {
            let mut r = lock(&self.report);
            (r.work, r.stopped_after) = ((0, 0, 0, 0), None);
        }
        // Taken, not held: a concurrent sample (none today) would record into fresh arrays.
        let mut stores = std::mem::take(&mut *lock(&self.stores));
        // A render's first sample measures afresh: rendering the same image again gives it again.
        if pass.sample_index() == 0 {
            *lock(&self.line) = line::LineTuning::default();
        }
        let line_direct = self.settings.line_samples.unwrap_or_else(|| lock(&self.line).samples());
        let config = PathConfig { line_direct, ..self.config };
        let (stats, blocks, spread) = match scene.transport.transport {
            Transport::Rgb => self.record::<Rgb>(scene, pass, &config, &mut stores),
            Transport::Spectral => self.record::<SampledSpectrum>(scene, pass, &config, &mut stores),
        };
        let Stores { vertices: v, paths, .. } = &mut stores;
        let recorded = Instant::now();

        let seed = (scene.sampler.seed as u32 as u64) << 32 | pass.sample_index() as u64;
        // Medium vertices cluster with medium vertices, Lambertian surface vertices with
        // Lambertian ones; other surface vertices are clusters of one. Within a class,
        // vertices cluster by their place along the path (README: depth classes). Clustering
        // sees the vertices in canonical order (tile by tile), so that the graph does not
        // depend on which tile finished first.
        let canon: Vec<u32> = blocks.iter().flat_map(|&(s, n)| s..s + n).collect();
        let depth = path_positions(v, paths);
        let iterations = self.settings.iterations;
        let binding = truncation_binds(&depth, self.settings.max_depth);
        let kind = |j: usize| {
            let i = canon[j] as usize;
            let class = if !v.g[i].is_nan() {
                1
            } else if v.n[i] != glam::Vec3::ZERO {
                2
            } else {
                return 0;
            };
            let level = match depth[i] {
                0 => 0,
                _ if !binding => 1,
                // Aggregates deeper than the iterations reach never reach a pixel.
                d if d <= iterations => d,
                _ => return 0,
            };
            class + 2 * level
        };
        let k = self.settings.cluster_size;
        let first_k = (k / 2).max(1);
        let mut clusters = cluster::cluster(
            canon.len(),
            |j| v.p[canon[j as usize] as usize],
            kind,
            |kd| if kd <= 2 { first_k } else { k },
            seed,
        );
        drop(depth);
        for o in clusters.order.iter_mut() {
            *o = canon[*o as usize];
        }
        drop(canon);
        let order = std::mem::take(&mut clusters.order);
        // The techniques (a path's earliest vertex in each cluster), found while each path's
        // vertices are still stored together: a vertex continues the path of the one before
        // it exactly when that one's next is it, so a path is named by its first vertex.
        let mut path = vec![0u32; v.len()];
        for i in 0..v.len() {
            path[i] = if i > 0 && v.next[i - 1] as usize == i { path[i - 1] } else { i as u32 };
        }
        let mut earliest = Vec::new();
        solve::earliest(&clusters.offsets, |i| path[order[i] as usize], &mut earliest);
        drop(path);
        let mut rank = vec![0u32; order.len()];
        for (new, &old) in order.iter().enumerate() {
            rank[old as usize] = new as u32;
        }
        // The positions have done their work: their array holds L⁺ from here on (and is given
        // back at the end), so the solve allocates no 12-byte array of its own.
        let mut l_plus = std::mem::take(&mut v.p);
        path_traced(v, &mut l_plus);
        // The permutation's spare arrays, which the solve then uses for L̄ and the marginals.
        // Not kept from one sample to the next: kept, they were idle through the next
        // sample's recording and clustering (20 bytes per vertex more at the process's peak),
        // and allocating them costs a few milliseconds.
        let mut spare = record::Spare::default();
        v.permute(&mut l_plus, &order, &rank, &mut spare);
        for f in paths.first.iter_mut() {
            if *f != NONE {
                *f = rank[*f as usize];
            }
        }
        drop(rank);
        drop(order);
        spare.u = Vec::new();
        // The solve's peak: the vertex arrays, L⁺, L̄, the solver's marginal and techniques;
        // the paths; the cluster offsets.
        let peak = (Vertices::BYTES_PER_VERTEX + SOLVE_BYTES_PER_VERTEX) * v.len()
            + Paths::BYTES_PER_PATH * paths.len()
            + 4 * clusters.offsets.len();

        let direct = std::mem::take(&mut v.direct_scatter);
        let mut direct_light = std::mem::take(&mut v.direct_light);
        let solver =
            solve::Solver::new(v, &direct_light, &clusters.offsets, earliest, std::mem::take(&mut spare.f), direct);
        // Only the first pass reads the light-sampled direct light: its array now holds, at each
        // path's first vertex f, the path-traced indirect light there (w ∘ L⁺ before any
        // iteration), from which the path's own unbiased estimate is made at the end.
        if self.settings.combine {
            for &f in paths.first.iter().filter(|&&f| f != NONE) {
                direct_light[f as usize] = v.w[f as usize] * l_plus[f as usize];
            }
        }
        let mut scattered = std::mem::take(&mut spare.v3);
        scattered.clear();
        scattered.resize(v.len(), Rgb::ZERO);
        for _ in 0..self.settings.iterations {
            solver.aggregate(&l_plus, &mut scattered);
            solver.propagate(&scattered, &mut l_plus);
        }
        // Each pixel's value replaces its path's unrefined radiance (no image-sized list), and
        // the throughput, whose work is then done, the path-traced estimate's difference from
        // it (V − G: the refined indirect light swapped for the path's own).
        let combine = self.settings.combine;
        let Paths { before, first, beta, .. } = &mut *paths;
        before.par_iter_mut().zip(first.par_iter().zip(beta.par_iter_mut())).with_min_len(1024).for_each(
            |(l, (&f, beta))| {
                if f == NONE {
                    *beta = Rgb::ZERO;
                    return;
                }
                let indirect = solver.indirect_at(f as usize, &l_plus);
                *l += *beta * indirect;
                if combine {
                    *beta *= direct_light[f as usize] - indirect;
                }
            },
        );
        if self.settings.line_samples.is_none() {
            // Each pixel's L and U (NaN without the combination: no U to measure).
            let pixels = paths.pixel.iter().zip(paths.before.iter().zip(&paths.beta)).map(|(&i, (l, d))| {
                let u = if combine { (*l + *d).element_sum() / 3.0 } else { f32::NAN };
                (i, [l.element_sum() / 3.0, u])
            });
            lock(&self.line).observe(spread, paths.len(), pixels);
        }
        for (((&index, &weight), &l), &d) in paths.pixel.iter().zip(&paths.weight).zip(&paths.before).zip(&paths.beta) {
            out(PixelValue { index, weight, l, unbiased: combine.then_some(l + d) });
        }
        let solved = Instant::now();
        drop(scattered);
        (v.direct_scatter, v.p, v.direct_light) = (solver.into_direct(), l_plus, direct_light);
        let (vertices, npaths, clusters) = (v.len(), paths.len(), clusters.len());
        *lock(&self.stores) = stores;
        if let Ok(mut r) = self.report.lock() {
            r.samples += 1;
            r.work.0 += 1;
            r.work.1 += stats.total();
            r.work.2 += vertices as u64;
            r.work.3 += npaths as u64;
            r.vertices += vertices as u64;
            r.clusters += clusters as u64;
            r.paths += npaths as u64;
            r.record_seconds += (recorded - start).as_secs_f64();
            r.solve_seconds += (solved - recorded).as_secs_f64();
            r.peak_bytes = r.peak_bytes.max(peak);
            r.max_vertices = r.max_vertices.max(vertices);
            r.resident_peak = resident_bytes("VmHWM:");
        }
        stats
    }
}

impl PathGraph {
    /// The paths' own estimate along `ray`: U as a graph sample makes it, the path's first
    /// direct light averaged with the camera line's extra first vertices, for the samples the
    /// graph no longer pays for (and scenes without media).
    fn own_estimate<C: RenderChannels>(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut C::Lambda,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> C {
        let line_direct = match self.settings.line_samples {
            Some(n) => n,
            None => lock(&self.line).own_samples(),
        };
        let config = PathConfig { extra_direct: 0, line_direct, ..self.config };
        let mut own = unpaired::OwnEstimate::<C>::default();
        let l = trace_path::<C, _>(scene, ray, scene.camera_medium, lambda, sampler, &config, &mut own, stats);
        own.finish(l)
    }
}

impl Integrator for PathGraph {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    /// Per-ray callers get the paths' own estimate (the samples the graph no longer pays for).
    fn li_rgb(&self, scene: &Scene, ray: Ray, lambda: &mut (), sampler: &mut Sampler, stats: &mut RayStats) -> Rgb {
        self.own_estimate::<Rgb>(scene, ray, lambda, sampler, stats)
    }

    fn li_spectral(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> SampledSpectrum {
        self.own_estimate::<SampledSpectrum>(scene, ray, lambda, sampler, stats)
    }

    fn whole_image(&self) -> Option<&dyn ImageIntegrator> {
        (!self.without_media).then_some(self as &dyn ImageIntegrator)
    }

    fn report(&self) -> Vec<String> {
        if self.without_media {
            return vec!["pathgraph   the scene has no media: nothing to cluster, rendered by path tracing".into()];
        }
        let Ok(r) = self.report.lock() else { return Vec::new() };
        if r.samples == 0 {
            return Vec::new();
        }
        let n = r.samples as f64;
        let verts = r.vertices as f64 / n;
        let mut lines = vec![
            format!(
                "pathgraph   {} graph samples (K {}, {} iterations, extradirect {}): {:.0} vertices and {:.0} clusters \
                 per sample ({:.2} vertices per path)",
                r.samples,
                self.settings.cluster_size,
                self.settings.iterations,
                self.settings.extra_direct,
                verts,
                r.clusters as f64 / n,
                r.vertices as f64 / r.paths.max(1) as f64
            ),
            format!(
                "pathgraph   record {:.3} s, solve {:.3} s per sample; arrays {:.1} MiB at the peak: {} bytes per vertex \
                 ({} recorded + {} solving), {} per path",
                r.record_seconds / n,
                r.solve_seconds / n,
                r.peak_bytes as f64 / (1 << 20) as f64,
                Vertices::BYTES_PER_VERTEX + SOLVE_BYTES_PER_VERTEX,
                Vertices::BYTES_PER_VERTEX,
                SOLVE_BYTES_PER_VERTEX,
                Paths::BYTES_PER_PATH
            ),
        ];
        if let (Some(before), Some(peak)) = (r.resident_before, r.resident_peak) {
            let added = peak.saturating_sub(before);
            lines.push(format!(
                "pathgraph   process resident peak {:.1} MiB, {:.1} MiB above its size before the first graph sample: \
                 {:.0} bytes per vertex of the largest graph",
                peak as f64 / (1 << 20) as f64,
                added as f64 / (1 << 20) as f64,
                added as f64 / r.max_vertices.max(1) as f64
            ));
        }
        if let Some(n) = r.stopped_after {
            lines.push(format!(
                "pathgraph   graph samples thinned after {n}: the graph's share of the combined image no longer paid for \
                 its own work ({:.2} times its paths', counted), so from then on at most one sample in {} builds a graph, \
                 and only while the graph's share still pays an {}th of its cost ({} in all); the rest are the paths' own estimate alone, per camera ray",
                r.extra_cost(),
                unpaired::THIN,
                unpaired::THIN,
                r.work.0
            ));
        }
        let line = lock(&self.line);
        lines.push(match (self.settings.line_samples, line.chosen(), line.measured) {
            (Some(n), ..) => format!("pathgraph   {n} extra first vertices per camera ray (linesamples)"),
            (None, Some(n), Some((v_d, total))) => format!(
                "pathgraph   {n} extra first vertices per camera ray ({} for the paths' own estimate alone), chosen \
                 after the first two samples (with {} each): one first vertex's direct light has variance {v_d:.3e}, \
                 the pixels {total:.3e} per sample",
                line.own_samples(),
                line::PROBE
            ),
            _ => format!("pathgraph   {} extra first vertices per camera ray (measuring)", line.samples()),
        });
        lines
    }
}
