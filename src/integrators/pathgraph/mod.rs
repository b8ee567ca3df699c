//! `pathgraph`: volume path graphs (Hu, Deng, Luan, Hašan and Marschner 2024), solved on the
//! CPU. One sample of the image = one 1-spp pass of the shared path loop with a recording
//! observer ([`record`]) + clustering ([`cluster`]) + aggregation and propagation iterated as
//! Eq. 28 ([`solve`]); each pixel takes the refined indirect radiance of its path's first
//! vertex plus the path's own (non-aggregated) direct light there (Sec. 4). More spp average
//! independent graph samples.

mod cluster;
mod lanes;
mod record;
mod settings;
mod solve;

pub use settings::PathGraphSettings;

use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

use super::common::{NoObserver, PathConfig, RayStats, trace_path};
use super::{ImageIntegrator, Integrator, PixelValue};
use crate::accel::NONE;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::render::{FilmChannels, ImagePass};
use crate::samplers::Sampler;
use crate::scene::Scene;
use crate::scene::transport::Transport;
use crate::spectra::{SampledSpectrum, SampledWavelengths};
use record::{Paths, Recorder, Vertices};

/// The path-graph integrator.
pub struct PathGraph {
    settings: PathGraphSettings,
    config: PathConfig,
    /// The scene has no media: surface vertices are clusters of one, so the graph would give
    /// back each path's own estimate at the cost of recording it. Such scenes are rendered
    /// per camera ray, as volpath renders them.
    without_media: bool,
    report: Mutex<Report>,
    /// The recording arrays, kept from one graph sample to the next: allocating them afresh
    /// faulted in every page again (a tenth of a sample's time on fog-emitter at 512×384).
    stores: Mutex<Stores>,
}

/// Arrays a graph sample fills and the next one reuses.
#[derive(Default)]
struct Stores {
    /// Each tile's recording, emptied into the merged store but not freed.
    tiles: Vec<Mutex<(Vertices, Paths)>>,
    vertices: Vertices,
    paths: Paths,
    spare: record::Spare,
}

/// Bytes per vertex the solve adds to the recorded arrays: L⁺, L̄, the marginal, the aggregated
/// direct light, the technique index and the cluster index.
const SOLVE_BYTES_PER_VERTEX: usize = 12 + 12 + 4 + 12 + 4 + 4;

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
}

/// Creates the integrator.
pub fn create(settings: &PathGraphSettings, scene: &Scene) -> Result<PathGraph, String> {
    Ok(PathGraph {
        settings: settings.clone(),
        config: PathConfig {
            extra_direct: settings.extra_direct,
            hero_per_segment: true,
            camera_line: true,
            ..PathConfig::volpath(settings.max_depth, settings.regularize)
        },
        without_media: scene.media.is_empty(),
        report: Mutex::new(Report::default()),
        stores: Mutex::new(Stores::default()),
    })
}

impl PathGraph {
    /// Records one 1-spp pass in the channels `C` into `stores`: graph vertices (in film RGB)
    /// and one path per pixel.
    fn record<C: FilmChannels>(&self, scene: &Scene, pass: &ImagePass<'_>, stores: &mut Stores) -> RayStats {
        let tiles = std::mem::take(&mut stores.tiles);
        let (parts, stats) = pass.trace_pixels::<C, _>(
            |i| {
                let (v, p) = tiles.get(i).map(|t| std::mem::take(&mut *lock(t))).unwrap_or_default();
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
                        &self.config,
                        rec,
                        stats,
                    );
                }
                let lambda = *lambda;
                rec.finish(px.index, px.weight, |x: C| x.to_film(&lambda, scene), v, p);
                if let Some(c) = px.ray
                    && c.weight != 1.0
                {
                    p.scale_last(c.weight);
                }
            },
        );
        // Sized once: growing by doubling copied the vertex store again and faulted in fresh
        // pages for every copy.
        let Stores { vertices, paths, .. } = stores;
        vertices.clear();
        paths.clear();
        vertices.reserve(parts.iter().map(|(_, v, _)| v.len()).sum());
        paths.reserve(parts.iter().map(|(_, _, p)| p.len()).sum());
        stores.tiles = parts
            .into_iter()
            .map(|(_, mut v, mut p)| {
                let path_base = paths.len() as u32;
                paths.append(&mut p, vertices.len() as u32);
                vertices.append(&mut v, path_base);
                Mutex::new((v, p))
            })
            .collect();
        stats
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

/// The path-traced L⁺ of every vertex (the iteration's start, Sec. 4): a backward sweep, as
/// each path's vertices are recorded in order.
fn path_traced(v: &Vertices) -> Vec<Rgb> {
    let n = v.len();
    let mut l_plus = vec![Rgb::ZERO; n];
    let mut scattered = vec![Rgb::ZERO; n];
    for i in (0..n).rev() {
        let next = v.next[i];
        let lp = if next == NONE { v.edge_const[i] } else { v.edge_const[i] + v.edge[i] * scattered[next as usize] };
        l_plus[i] = lp;
        scattered[i] = v.direct_light[i] + v.direct_scatter[i] + v.w[i] * lp;
    }
    l_plus
}

impl ImageIntegrator for PathGraph {
    fn sample_image(&self, scene: &Scene, pass: &ImagePass<'_>) -> (Vec<PixelValue>, RayStats) {
        let start = Instant::now();
        // Taken, not held: a concurrent sample (none today) would record into fresh arrays.
        let mut stores = std::mem::take(&mut *lock(&self.stores));
        let stats = match scene.transport.transport {
            Transport::Rgb => self.record::<Rgb>(scene, pass, &mut stores),
            Transport::Spectral => self.record::<SampledSpectrum>(scene, pass, &mut stores),
        };
        let (v, paths) = (&mut stores.vertices, &mut stores.paths);
        let recorded = Instant::now();

        let seed = (scene.sampler.seed as u32 as u64) << 32 | pass.sample_index() as u64;
        // Medium vertices cluster with medium vertices, Lambertian surface vertices with
        // Lambertian ones; other surface vertices are clusters of one. Within a class,
        // vertices cluster by their place along the path (README: depth classes).
        let depth = path_positions(v, paths);
        let iterations = self.settings.iterations;
        let binding = truncation_binds(&depth, self.settings.max_depth);
        let kind = |i: usize| {
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
        let mut clusters = cluster::cluster(&v.p, kind, |kd| if kd <= 2 { first_k } else { k }, seed);
        drop(depth);
        let mut rank = vec![0u32; clusters.order.len()];
        for (new, &old) in clusters.order.iter().enumerate() {
            rank[old as usize] = new as u32;
        }
        let l_plus_recorded = path_traced(v);
        let mut l_plus: Vec<Rgb> = clusters.order.iter().map(|&i| l_plus_recorded[i as usize]).collect();
        drop(l_plus_recorded);
        v.permute(&clusters.order, &rank, &mut stores.spare);
        for f in paths.first.iter_mut() {
            if *f != NONE {
                *f = rank[*f as usize];
            }
        }
        drop(rank);
        clusters.order = Vec::new();
        let mut cluster_of = vec![0u32; v.len()];
        for c in 0..clusters.len() {
            cluster_of[clusters.range(c)].fill(c as u32);
        }
        // The solve's peak: the vertex arrays, L⁺, L̄, the solver's marginal, aggregated direct
        // light and techniques, each vertex's cluster; the paths; the cluster offsets.
        let peak = (Vertices::BYTES_PER_VERTEX + SOLVE_BYTES_PER_VERTEX) * v.len()
            + Paths::BYTES_PER_PATH * paths.len()
            + 4 * clusters.offsets.len();

        let solver = solve::Solver::new(v, &clusters.offsets);
        let mut scattered = vec![Rgb::ZERO; v.len()];
        for _ in 0..self.settings.iterations {
            solver.aggregate(&l_plus, &mut scattered);
            solver.propagate(&scattered, &mut l_plus);
        }
        let values: Vec<PixelValue> = (0..paths.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(|k| {
                let f = paths.first[k];
                let l = if f == NONE {
                    paths.before[k]
                } else {
                    let f = f as usize;
                    let extra = paths.extra[k];
                    let direct = if extra.is_nan() { v.direct_light[f] + v.direct_scatter[f] } else { extra };
                    let indirect = solver.indirect_at(cluster_of[f] as usize, f, &l_plus);
                    paths.before[k] + paths.beta[k] * (direct + indirect)
                };
                PixelValue { index: paths.pixel[k], weight: paths.weight[k], l }
            })
            .collect();
        let solved = Instant::now();
        let (vertices, npaths) = (v.len(), paths.len());
        *lock(&self.stores) = stores;
        if let Ok(mut r) = self.report.lock() {
            r.samples += 1;
            r.vertices += vertices as u64;
            r.clusters += clusters.len() as u64;
            r.paths += npaths as u64;
            r.record_seconds += (recorded - start).as_secs_f64();
            r.solve_seconds += (solved - recorded).as_secs_f64();
            r.peak_bytes = r.peak_bytes.max(peak);
        }
        (values, stats)
    }
}

impl Integrator for PathGraph {
    fn name(&self) -> &'static str {
        "pathgraph"
    }

    /// Per-ray callers get the path-traced estimate the graph starts from.
    fn li_rgb(&self, scene: &Scene, ray: Ray, lambda: &mut (), sampler: &mut Sampler, stats: &mut RayStats) -> Rgb {
        let config = PathConfig { extra_direct: 0, ..self.config };
        trace_path(scene, ray, scene.camera_medium, lambda, sampler, &config, &mut NoObserver, stats)
    }

    fn li_spectral(
        &self,
        scene: &Scene,
        ray: Ray,
        lambda: &mut SampledWavelengths,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> SampledSpectrum {
        let config = PathConfig { extra_direct: 0, ..self.config };
        trace_path::<SampledSpectrum, _>(
            scene,
            ray,
            scene.camera_medium,
            lambda,
            sampler,
            &config,
            &mut NoObserver,
            stats,
        )
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
        vec![
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
                "pathgraph   record {:.3} s, solve {:.3} s per sample; peak {:.1} MiB: {} bytes per vertex ({} recorded + {} \
                 solving), {} per path",
                r.record_seconds / n,
                r.solve_seconds / n,
                r.peak_bytes as f64 / (1 << 20) as f64,
                Vertices::BYTES_PER_VERTEX + SOLVE_BYTES_PER_VERTEX,
                Vertices::BYTES_PER_VERTEX,
                SOLVE_BYTES_PER_VERTEX,
                Paths::BYTES_PER_PATH
            ),
        ]
    }
}
