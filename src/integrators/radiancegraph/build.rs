//! Building the graph (thesis Sec. 4.3): light paths traced from a grid over each light,
//! grouped into nodes; then reinforcement from nodes with too few edges or neighbours.
//!
//! Paths are traced in parallel (tracing does not look at the graph) and grouped in a fixed
//! order afterwards, each path with its own random stream: the same graph at any thread count.

use glam::Vec3;
use rayon::prelude::*;

use super::config::GraphBuilder as Config;
use super::graph::BuildGraph;
use super::volume::{Event, GraphLight, Volume, pick_area_light};
use crate::geometry::{Ray, spawn_ray};
use crate::math::Frame;
use crate::sampling::rng::Pcg32;
use crate::sampling::warp;

/// Traced paths, flat: all scattering points in order, and per path its start node, its
/// number of points and whether its last segment was sampled. One per parallel chunk, so
/// tracing allocates per chunk, not per path.
#[derive(Default)]
pub(super) struct Traced {
    pub(super) points: Vec<Vec3>,
    pub(super) paths: Vec<(Option<u32>, u32, bool)>,
}

impl Traced {
    /// Groups the paths into the graph, in order.
    fn add_to(&self, graph: &mut BuildGraph) {
        let mut at = 0;
        for &(start, n, last_sampled) in &self.paths {
            graph.add_path(start, &self.points[at..at + n as usize], last_sampled);
            at += n as usize;
        }
    }
}

/// Paths per parallel chunk.
const CHUNK: usize = 256;

/// Where a batch of paths starts.
#[derive(Clone, Copy)]
pub(super) struct Start {
    ray: Ray,
    /// Distance to the medium's boundary along `ray` (its origin is inside).
    t_max: f32,
    /// The node a reinforcement path starts from.
    node: Option<u32>,
}

/// What the build did, for the stats file.
#[derive(Clone, Debug, Default)]
pub struct BuildReport {
    /// Light paths traced.
    pub light_paths: u64,
    /// Reinforcement rounds run.
    pub reinforcement_rounds: u32,
    /// Reinforcement paths traced.
    pub reinforcement_paths: u64,
    /// Final unsatisfied ratios (edges, neighbours), when reinforcement ran.
    pub unsatisfied: (f32, f32),
    /// Bytes the graph held at its largest: (per-node structures, edge lists).
    pub peak: (usize, usize),
}

impl BuildReport {
    fn note_memory(&mut self, graph: &BuildGraph) {
        let m = graph.memory_bytes();
        if m.0 + m.1 > self.peak.0 + self.peak.1 {
            self.peak = m;
        }
    }
}

/// Rounds of reinforcement after which the build stops even if the ratios are not met (a
/// node that can never be satisfied, such as one alone in a thin wisp, would otherwise
/// keep the thesis's loop running forever).
const MAX_ROUNDS: u32 = 64;

/// Bytes the graph may hold (its own count) before the build stops: half the memory the
/// system has available when the build starts (Linux's `MemAvailable`), so that a node radius
/// far too small for the volume ends in a message instead of the out-of-memory killer.
pub fn default_memory_limit() -> usize {
    let available = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        let line = m.lines().find(|l| l.starts_with("MemAvailable:"))?;
        line.split_whitespace().nth(1)?.parse::<usize>().ok()
    });
    available.map_or(usize::MAX, |kib| kib * 1024 / 2)
}

/// The message for a graph that outgrew `limit` bytes.
fn too_large(graph: &BuildGraph, limit: usize, paths: (u64, u64), volume: &Volume) -> String {
    format!(
        "the radiance graph outgrew {:.1} GiB ({} nodes after {} of {} light paths): its node radius {} is \
         1/{:.0} of the medium's diameter; raise graphBuilder.radiusModifier in the config or give \
         --node-radius (the thesis's default radius builds tens of millions of nodes in a dense medium)",
        limit as f64 / (1u64 << 30) as f64,
        graph.len(),
        paths.0,
        paths.1,
        graph.radius(),
        2.0 * volume.radius / graph.radius()
    )
}

/// Builds the graph of `volume` with node radius `radius`; `seed` picks the random streams.
/// Stops with a message once the graph holds more than `memory_limit` bytes.
pub fn build_graph(
    volume: &Volume,
    config: &Config,
    radius: f32,
    seed: u64,
    memory_limit: usize,
) -> crate::Result<(BuildGraph, BuildReport)> {
    let mut graph = BuildGraph::new(radius);
    let mut report = BuildReport::default();
    let max_depth = config.max_depth as usize;
    let starts = light_starts(volume, config, seed);
    let per_start = config.iterations_per_step as u64;
    report.light_paths = starts.len() as u64 * per_start;
    // Batches bound the memory of traced-but-ungrouped paths.
    let batch = (1 << 16) / per_start.max(1) as usize + 1;
    let per_chunk = CHUNK.div_ceil(per_start as usize).max(1);
    let trace_batch = |b: usize, chunk: &[Start]| -> Vec<Traced> {
        let base = (b * batch) as u64 * per_start;
        chunk
            .par_chunks(per_chunk)
            .enumerate()
            .map(|(c, starts)| {
                let mut t = Traced::default();
                for (j, s) in starts.iter().enumerate() {
                    let i = (c * per_chunk + j) as u64;
                    for k in 0..per_start {
                        let mut rng = Pcg32::new(base + i * per_start + k, seed);
                        trace(volume, s, max_depth, &mut rng, &mut t);
                    }
                }
                t
            })
            .collect()
    };
    // Grouping is sequential (each path sees the nodes of the paths before it); it runs on one
    // thread while the others trace the next batch.
    let mut pending: Option<Vec<Traced>> = None;
    let total = report.light_paths;
    for (b, chunk) in starts.chunks(batch).enumerate() {
        let (traced, ()) = rayon::join(
            || trace_batch(b, chunk),
            || {
                if let Some(p) = pending.take() {
                    p.iter().for_each(|t| t.add_to(&mut graph));
                    report.note_memory(&graph);
                }
            },
        );
        if report.peak.0 + report.peak.1 > memory_limit {
            return Err(crate::Error::Invalid(too_large(
                &graph,
                memory_limit,
                ((b * batch) as u64 * per_start, total),
                volume,
            )));
        }
        pending = Some(traced);
    }
    if let Some(p) = pending.take() {
        p.iter().for_each(|t| t.add_to(&mut graph));
        report.note_memory(&graph);
    }
    reinforce(volume, config, &mut graph, seed, report.light_paths, &mut report);
    report.note_memory(&graph);
    if report.peak.0 + report.peak.1 > memory_limit {
        return Err(crate::Error::Invalid(too_large(&graph, memory_limit, (total, total), volume)));
    }
    Ok((graph, report))
}

/// The first segments of light paths: for a distant light, `dimensionSteps`² parallel rays on
/// a grid over the volume's bounding square, 2R before its centre (the thesis's
/// `BuildGraph`); for a uniform infinite light as many rays with uniformly random
/// directions through uniformly random points of the volume's bounding disk (the
/// distribution of lines a constant radiance field sends through the volume).
pub(super) fn light_starts(volume: &Volume, config: &Config, seed: u64) -> Vec<Start> {
    let r = volume.radius;
    let c = volume.center();
    let n = config.dimension_steps;
    let step = 2.0 * r / (n + 1) as f32;
    let mut rays = Vec::new();
    for (li, light) in volume.lights.iter().enumerate() {
        match light {
            GraphLight::Distant { dir, .. } => {
                let f = Frame::from_z(*dir);
                let origin = c - *dir * (2.0 * r) - (f.x + f.y) * r;
                for x in 1..=n {
                    for y in 1..=n {
                        rays.push(Ray::new(origin + f.x * (step * x as f32) + f.y * (step * y as f32), *dir));
                    }
                }
            }
            GraphLight::Uniform { .. } => {
                let mut rng = Pcg32::new(u64::MAX - li as u64, seed);
                for _ in 0..n * n {
                    let d = warp::uniform_sphere(glam::Vec2::new(rng.uniform(), rng.uniform()));
                    let f = Frame::from_z(d);
                    let q = warp::concentric_disk(glam::Vec2::new(rng.uniform(), rng.uniform())) * r;
                    rays.push(Ray::new(c - d * (2.0 * r) + f.x * q.x + f.y * q.y, d));
                }
            }
            // As many rays from a point light (beyond the thesis), toward the medium.
            GraphLight::Point { pos, .. } => {
                let mut rng = Pcg32::new(u64::MAX - li as u64, seed);
                for _ in 0..n * n {
                    let u = glam::Vec2::new(rng.uniform(), rng.uniform());
                    rays.push(Ray::new(*pos, toward_volume(volume, *pos, u)));
                }
            }
            // A light's reflection has the light's own paths.
            GraphLight::Reflected { .. } => {}
            // As many rays from the medium's emitting points: uniform points of its bounds
            // (kept where it emits, up to 64 tries each), uniform directions.
            GraphLight::Emission { .. } => {
                let mut rng = Pcg32::new(u64::MAX - li as u64, seed);
                let b = volume.bounds;
                for _ in 0..n * n {
                    for _ in 0..64 {
                        let u = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                        let p = b.min + (b.max - b.min) * u;
                        let mp = volume.medium.sample_point::<crate::color::Rgb>(p, &());
                        if mp.le.max_element() > 0.0 && mp.sigma_a.max_element() > 0.0 && volume.contains(p) {
                            let d = warp::uniform_sphere(glam::Vec2::new(rng.uniform(), rng.uniform()));
                            rays.push(Ray::new(p, d));
                            break;
                        }
                    }
                }
            }
            // As many rays from area lights: a light chosen by area, a uniform point of it, a
            // direction toward the medium on a side it emits from.
            GraphLight::Area { lights, .. } => {
                let mut rng = Pcg32::new(u64::MAX - li as u64, seed);
                let scene = volume.scene;
                for _ in 0..n * n {
                    let light = &scene.lights[pick_area_light(scene, lights, rng.uniform()) as usize];
                    let u = glam::Vec2::new(rng.uniform(), rng.uniform());
                    let Some(s) = light.sample_area_point(&scene.surfaces.shapes, u) else { continue };
                    let two_sided = matches!(light.kind, crate::lights::LightKind::Area { two_sided: true, .. });
                    let d = toward_volume(volume, s.p, glam::Vec2::new(rng.uniform(), rng.uniform()));
                    let n = if d.dot(s.n) >= 0.0 { s.n } else { -s.n };
                    if two_sided || n == s.n {
                        rays.push(spawn_ray(s.p, n, d));
                    }
                }
            }
        }
    }
    // Rays that enter the medium start at their entry point (a point light inside it: at
    // the light).
    rays.par_iter()
        .filter_map(|ray| {
            let (t_in, t_out) = volume.span_from(ray)?;
            Some(Start { ray: Ray::new(ray.at(t_in), ray.d), t_max: t_out - t_in, node: None })
        })
        .collect()
}

/// A direction from `o` toward the medium: uniform in the cone its bounding sphere subtends
/// (uniform over all directions from inside the sphere). Only where light paths go matters
/// (the first segment makes no edge), and rays that miss the medium make nothing.
fn toward_volume(volume: &Volume, o: Vec3, u: glam::Vec2) -> Vec3 {
    let to = volume.center() - o;
    let (d2, r2) = (to.length_squared(), volume.radius * volume.radius);
    if d2 <= r2 {
        return warp::uniform_sphere(u);
    }
    Frame::from_z(to / d2.sqrt()).to_world(warp::uniform_cone(u, (1.0 - r2 / d2).sqrt()))
}

/// Traces one path from `start` (thesis `TracePath`): delta tracking to the next event,
/// isotropic scattering, at most `max_depth` vertices counting a reinforcement path's node.
/// Appends it to `out`.
pub(super) fn trace(volume: &Volume, start: &Start, max_depth: usize, rng: &mut Pcg32, out: &mut Traced) {
    let max_points = max_depth - usize::from(start.node.is_some());
    let first = out.points.len();
    let done = |out: &mut Traced, last_sampled: bool| {
        let n = (out.points.len() - first) as u32;
        out.paths.push((start.node, n, last_sampled));
    };
    if max_points == 0 {
        return done(out, false);
    }
    let (mut ray, mut t_max) = (start.ray, start.t_max);
    loop {
        match volume.sample_scatter(&ray, t_max, rng) {
            Event::Absorb => return done(out, true),
            // Left the medium or met a surface inside it: surfaces beside the medium may
            // reflect the path back in (Russian roulette on their albedo keeps edges counts).
            Event::Pass => match volume.reflect_back(&ray, rng) {
                Some((r, t)) => (ray, t_max) = (r, t),
                None => return done(out, true),
            },
            Event::Scatter(p) => {
                out.points.push(p);
                if out.points.len() - first == max_points {
                    return done(out, false);
                }
                let d = warp::uniform_sphere(glam::Vec2::new(rng.uniform(), rng.uniform()));
                ray = Ray::new(p, d);
                match volume.exit(&ray) {
                    Some(t) => t_max = t,
                    // Numerically outside already: the segment leaves at once.
                    None => return done(out, true),
                }
            }
        }
    }
}

/// Reinforcement (thesis Sec. 4.3, App. B): while more than the allowed ratio of the nodes
/// present before it have fewer outgoing edges or fewer nodes nearby than required, trace
/// `reinforcementRays` paths from each such node, from uniform points in its sphere in
/// uniform directions.
fn reinforce(
    volume: &Volume,
    config: &Config,
    graph: &mut BuildGraph,
    seed: u64,
    first: u64,
    report: &mut BuildReport,
) {
    let (er, nr) = (&config.edge_reinforcement, &config.neighbour_reinforcement);
    if !er.active && !nr.active {
        return;
    }
    let initial = graph.len();
    if initial == 0 {
        return;
    }
    let range = graph.radius() * nr.neighbour_range_modifier;
    let mut few_edges: Vec<u32> = if er.active { (0..initial as u32).collect() } else { Vec::new() };
    let mut few_neighbours: Vec<u32> = if nr.active { (0..initial as u32).collect() } else { Vec::new() };
    let check_edges = |g: &BuildGraph, list: &mut Vec<u32>| {
        list.retain(|&a| g.out_degree(a) < er.edges_for_not_sparse as usize);
        list.len() as f32 / initial as f32
    };
    let check_neighbours = |g: &BuildGraph, list: &mut Vec<u32>| {
        let keep: Vec<bool> = list
            .par_iter()
            .map(|&a| g.count_within(g.position(a), range) < nr.neighbours_for_not_sparse as usize)
            .collect();
        let mut k = keep.iter();
        list.retain(|_| *k.next().unwrap());
        list.len() as f32 / initial as f32
    };
    let mut edge_ratio = if er.active { check_edges(graph, &mut few_edges) } else { 0.0 };
    let mut neighbour_ratio = if nr.active { check_neighbours(graph, &mut few_neighbours) } else { 0.0 };
    let mut next_stream = first;
    let max_depth = config.max_depth as usize;
    let mut round = 0;
    loop {
        let edges_ok = !er.active || edge_ratio < er.unsatisfied_allowed_ratio;
        let neighbours_ok = !nr.active || neighbour_ratio < nr.unsatisfied_allowed_ratio;
        if (edges_ok && neighbours_ok) || round == MAX_ROUNDS {
            break;
        }
        if !edges_ok {
            report.reinforcement_paths +=
                trace_from(volume, graph, &few_edges, er.reinforcement_rays, max_depth, seed, &mut next_stream);
            edge_ratio = check_edges(graph, &mut few_edges);
        }
        if !neighbours_ok {
            report.reinforcement_paths +=
                trace_from(volume, graph, &few_neighbours, nr.reinforcement_rays, max_depth, seed, &mut next_stream);
            neighbour_ratio = check_neighbours(graph, &mut few_neighbours);
        }
        round += 1;
        report.note_memory(graph);
    }
    report.reinforcement_rounds = round;
    report.unsatisfied = (edge_ratio, neighbour_ratio);
}

/// Traces `rays` paths from each node of `nodes` and groups them; returns how many were traced.
fn trace_from(
    volume: &Volume,
    graph: &mut BuildGraph,
    nodes: &[u32],
    rays: u32,
    max_depth: usize,
    seed: u64,
    next_stream: &mut u64,
) -> u64 {
    let radius = graph.radius();
    let base = *next_stream;
    *next_stream += nodes.len() as u64 * rays as u64;
    // The nodes' centres, copied so tracing needs no access to the graph being grouped into.
    let centers: Vec<Vec3> = nodes.iter().map(|&a| graph.position(a)).collect();
    let per_chunk = CHUNK.div_ceil(rays as usize).max(1);
    let trace_batch = |first: usize, nodes: &[u32]| -> Vec<Traced> {
        nodes
            .par_chunks(per_chunk)
            .enumerate()
            .map(|(c, chunk)| {
                let mut t = Traced::default();
                for (j, &a) in chunk.iter().enumerate() {
                    let i = first + c * per_chunk + j;
                    for k in 0..rays as u64 {
                        let mut rng = Pcg32::new(base + i as u64 * rays as u64 + k, seed);
                        // A uniform point in the node's sphere (rejection, as the thesis).
                        let offset = loop {
                            let v = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - Vec3::ONE;
                            if v.length_squared() < 1.0 {
                                break v * radius;
                            }
                        };
                        let d = warp::uniform_sphere(glam::Vec2::new(rng.uniform(), rng.uniform()));
                        let ray = Ray::new(centers[i] + offset, d);
                        // Rays that miss the medium sample nothing (the thesis skips them too).
                        if let Some((t_in, t_out)) = volume.span_from(&ray) {
                            let start = Start { ray: Ray::new(ray.at(t_in), d), t_max: t_out - t_in, node: Some(a) };
                            trace(volume, &start, max_depth, &mut rng, &mut t);
                        }
                    }
                }
                t
            })
            .collect()
    };
    // As for light paths: group one batch while the next is traced.
    let batch = (1 << 16) / (rays as usize).max(1) + 1;
    let mut traced_paths = 0u64;
    let mut pending: Option<Vec<Traced>> = None;
    let mut group = |p: Vec<Traced>, graph: &mut BuildGraph| {
        p.iter().for_each(|t| t.add_to(graph));
        traced_paths += p.iter().map(|t| t.paths.len() as u64).sum::<u64>();
    };
    for (b, chunk) in nodes.chunks(batch).enumerate() {
        let (traced, ()) = rayon::join(
            || trace_batch(b * batch, chunk),
            || {
                if let Some(p) = pending.take() {
                    group(p, graph);
                }
            },
        );
        pending = Some(traced);
    }
    if let Some(p) = pending.take() {
        group(p, graph);
    }
    traced_paths
}
