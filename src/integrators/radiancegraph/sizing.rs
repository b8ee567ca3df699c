//! A graph sized for the scene when the scene brings no config.
//!
//! The thesis's defaults (Sec. 4.3.1, App. B) are one node radius for every scene, the
//! medium's diameter / 1000, and 16 million light paths per light. In a dense cloud that makes
//! tens of millions of nodes: graph-cloud ran 7 minutes and reached 1.9 GB before it was
//! stopped. Radiance in a medium changes over the distance light travels between events, and
//! the camera resolves nothing finer than a pixel, so nimbus sizes a config-less graph from a
//! pilot of light paths:
//!
//! - the node radius is a fifth of the mean free path the pilot's light travels between
//!   scattering events (the scale over which radiance decorrelates), no smaller than a pixel's
//!   footprint
//!   at the medium's centre, and no smaller than what keeps the expected node count within
//!   [`NODE_BUDGET`] over the volume the pilot's light reaches;
//! - the light paths are as many as make [`VERTEX_BUDGET`] scattering points, which bounds the
//!   build's memory (a node and an edge per point at most) and its time.
//!
//! A config file keeps the thesis's meaning unchanged: only its absence asks for this.

use std::collections::HashSet;

use glam::{IVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::build::{Traced, light_starts, trace};
use super::config::GraphConfig;
use super::volume::Volume;
use crate::sampling::rng::Pcg32;

/// Scattering points the build's light paths make, at most: about 30 s of building on two
/// cores and well under 1 GB, whatever the medium.
pub const VERTEX_BUDGET: f64 = 12.0e6;
/// Nodes the radius aims at, at most (direct light and transport cost per node and edge).
pub const NODE_BUDGET: f64 = 400.0e3;
/// Nodes the build makes per radius-sized cube of occupied volume: a new node's centre keeps
/// a radius from every other, so the nodes pack looser than one per r³. Measured (built
/// against expected at one per r³): the Disney cloud 0.50 at r = 3.48 (about 200 000 nodes) and
/// 0.48 at 2.45, graph-cloud 0.50 at 0.0217. Counting one per r³ had the node budget set a
/// radius 1.26 times too large, for half the budget's nodes.
pub const NODES_PER_RADIUS_CUBE: f64 = 0.5;
/// Node radius per mean free path. The hand-sized configs of the results agree: the cloud's
/// best radii (0.017–0.035; 0.069 was 3.9 % bright) around its free path 0.123 / 5, the
/// cube's radius 0.173 against its 0.82 / 5.
const RADIUS_PER_FREE_PATH: f32 = 0.2;
/// Node radius per mean free path above which the graph is coarse: its bias grows with the
/// nodes' size in free paths (the real Disney cloud at g = 0, README: +8.1 % at 0.73 and
/// +14.7 % at 1.5 free paths), and the pixel footprint or the node budget can set a radius this
/// large in a dense cloud.
pub const COARSE_RADIUS_PER_FREE_PATH: f32 = 0.5;
/// Grid rays per side over each light in the pilot, and paths per ray.
const PILOT_STEPS: u32 = 64;
const PILOT_PATHS_PER_RAY: u64 = 4;
/// Pilot points an occupancy cell needs, on average, for its count to be trusted.
const POINTS_PER_CELL: f64 = 8.0;

/// What the sizing chose, and the measurements it chose from.
#[derive(Clone, Debug, PartialEq)]
pub struct Sizing {
    /// The config to build with: the thesis's defaults, with its path counts and radius
    /// modifier set by the sizing.
    pub config: GraphConfig,
    /// The node radius.
    pub radius: f32,
    /// Mean distance between the pilot paths' consecutive scattering points.
    pub free_path: f32,
    /// A pixel's footprint at the medium's centre (0 when the camera gives none).
    pub footprint: f32,
    /// Volume the pilot's points occupy.
    pub occupied_volume: f32,
    /// Scattering points per light path in the pilot.
    pub points_per_path: f32,
    /// Light paths the config traces: paths per grid ray times the grid rays the pilot
    /// expects to meet the medium.
    pub light_paths: f64,
    /// Which bound set the radius: "free path", "pixel footprint" or "node budget".
    pub radius_from: &'static str,
}

impl Sizing {
    /// Nodes expected at the chosen radius, [`NODES_PER_RADIUS_CUBE`] per radius-sized cube of
    /// occupied volume.
    pub fn expected_nodes(&self) -> f64 {
        NODES_PER_RADIUS_CUBE * f64::from(self.occupied_volume) / f64::from(self.radius).powi(3)
    }

    /// Said when the radius is over [`COARSE_RADIUS_PER_FREE_PATH`] free paths: how coarse
    /// the graph is and what that has cost elsewhere.
    pub fn coarse(&self) -> Option<String> {
        let r = self.radius / self.free_path;
        (r > COARSE_RADIUS_PER_FREE_PATH).then(|| {
            format!(
                "the graph's nodes span {r:.2} free paths (radius set by the {}): a graph this coarse is biased \
                 (the real Disney cloud at g = 0: +8 % at 0.73 free paths, +15 % at 1.5); a config with a smaller \
                 radius builds longer and is less so",
                self.radius_from
            )
        })
    }

    /// One line per choice, for `--stats`, and the warning of [`Sizing::coarse`].
    pub fn explain(&self) -> String {
        let warning = self.coarse().map_or(String::new(), |w| format!("\n  warning: {w}"));
        format!(
            "no config: graph sized from a pilot of light paths\n  node radius {:.4} (set by the {}): mean free \
             path {:.4}, pixel footprint {:.4}, node budget {:.0} over {:.3} occupied\n  {} x {} paths per \
             light ({:.1} scattering points each, budget {:.0} points); about {:.0} nodes; {} bounces",
            self.radius,
            self.radius_from,
            self.free_path,
            self.footprint,
            NODE_BUDGET,
            self.occupied_volume,
            self.config.graph_builder.dimension_steps.pow(2),
            self.config.graph_builder.iterations_per_step,
            self.points_per_path,
            VERTEX_BUDGET,
            self.expected_nodes(),
            self.config.lighting_calculator.bounces[0],
        ) + &warning
    }
}

/// A pixel's footprint at distance `distance` from the camera of `volume`'s scene: the angle
/// between the rays through the two pixels at the image's centre, times the distance.
fn pixel_footprint(volume: &Volume) -> f32 {
    let camera = &volume.scene.camera;
    let [x0, x1, y0, y1] = volume.scene.film_bounds;
    let centre = Vec2::new((x0 + x1) as f32 / 2.0, (y0 + y1) as f32 / 2.0);
    let ray = |p: Vec2| camera.generate_ray(p, Vec2::splat(0.5), 0.0).map(|r| r.ray.d.normalize());
    let (Some(a), Some(b)) = (ray(centre), ray(centre + Vec2::X)) else {
        return 0.0;
    };
    let angle = a.dot(b).clamp(-1.0, 1.0).acos();
    angle * camera.position().distance(volume.center())
}

/// The radius at which `occupied` volume holds [`NODE_BUDGET`] nodes.
pub fn budget_radius(occupied: f32) -> f32 {
    (NODES_PER_RADIUS_CUBE * f64::from(occupied) / NODE_BUDGET).cbrt() as f32
}

/// The volume `points` occupy: at the finest of cell sizes (the medium's radius / 2, / 4, …)
/// where each touched cell holds [`POINTS_PER_CELL`] points on average, the touched cells'
/// volume.
fn occupied_volume(points: &[Vec3], radius: f32) -> f32 {
    let mut best = (2.0 * radius).powi(3);
    let mut h = radius / 2.0;
    for _ in 0..12 {
        let cells: HashSet<IVec3> = points.iter().map(|p| (*p / h).floor().as_ivec3()).collect();
        if (points.len() as f64) < POINTS_PER_CELL * cells.len() as f64 {
            break;
        }
        best = cells.len() as f32 * h.powi(3);
        h /= 2.0;
    }
    best
}

/// The config and radius for `volume` (whose scene brings no graph config), from a pilot of
/// light paths with random streams from `seed`; `max_depth`, the scene's path depth when it
/// gives one, sets the bounces transported and the light paths' length (the thesis's 9 and 10
/// otherwise).
pub fn size(volume: &Volume, seed: u64, max_depth: Option<u32>) -> Sizing {
    let mut config = GraphConfig::default();
    // The similar medium's graph transports light to convergence, whatever the scene's depth.
    let max_depth = if volume.similarity.is_some() { Some(super::similarity::BOUNCES + 1) } else { max_depth };
    if let Some(d) = max_depth {
        config.lighting_calculator.bounces = vec![d.saturating_sub(1)];
        // Light paths as long as the scene's paths: truncated ones leave the light that has
        // scattered long (deep in a dense cloud, on its far sides) out of where each node's
        // points and edges are drawn. The real Disney cloud at g = 0 (maxdepth 100): +14.7 %
        // with the thesis's 10, +12.8 % with 30, +5.2 % with 100 (README).
        config.graph_builder.max_depth = d.max(2);
    }
    let defaults = config.graph_builder.clone();
    let pilot_config = super::config::GraphBuilder { dimension_steps: PILOT_STEPS, ..defaults.clone() };
    // Streams apart from the build's (which count up from 0).
    let pilot_seed = seed ^ 0x005e_ed0f_9170;
    let starts = light_starts(volume, &pilot_config, pilot_seed);
    let max_depth = defaults.max_depth as usize;
    let traced: Vec<Traced> = starts
        .par_chunks(64)
        .enumerate()
        .map(|(c, chunk)| {
            let mut t = Traced::default();
            for (j, s) in chunk.iter().enumerate() {
                for k in 0..PILOT_PATHS_PER_RAY {
                    let stream = ((c * 64 + j) as u64) * PILOT_PATHS_PER_RAY + k;
                    trace(volume, s, max_depth, &mut Pcg32::new(stream, pilot_seed), &mut t);
                }
            }
            t
        })
        .collect();
    let (mut length, mut segments, mut paths) = (0.0f64, 0u64, 0u64);
    let mut points = Vec::new();
    for t in &traced {
        let mut at = 0;
        for &(_, n, _) in &t.paths {
            let path = &t.points[at..at + n as usize];
            for w in path.windows(2) {
                length += f64::from(w[0].distance(w[1]));
                segments += 1;
            }
            at += n as usize;
            paths += 1;
        }
        points.extend_from_slice(&t.points);
    }
    let scene_radius = volume.radius;
    // Without two events on a path (a thin medium) light crosses the medium in one flight:
    // the medium's own size is the scale.
    let free_path = if segments > 0 { (length / segments as f64) as f32 } else { scene_radius };
    let footprint = pixel_footprint(volume);
    let occupied = if points.len() > 1 { occupied_volume(&points, scene_radius) } else { (2.0 * scene_radius).powi(3) };
    let budget_radius = budget_radius(occupied);
    let (radius, radius_from) = [
        (free_path * RADIUS_PER_FREE_PATH, "free path"),
        (footprint, "pixel footprint"),
        (budget_radius, "node budget"),
    ]
    .into_iter()
    .fold((0.0, "free path"), |best, c| if c.0 > best.0 { c } else { best });
    let points_per_path = if paths > 0 { points.len() as f32 / paths as f32 } else { 1.0 };
    // Paths per grid ray so that the build makes the budget's points: the pilot's starts that
    // met the medium, scaled to the build's grid.
    let steps = defaults.dimension_steps;
    let pilot_rays = f64::from(PILOT_STEPS).powi(2) * volume.lights.len().max(1) as f64;
    let hit = (starts.len() as f64 / pilot_rays).max(1e-3);
    let rays = f64::from(steps).powi(2) * volume.lights.len().max(1) as f64 * hit;
    let per_ray = (VERTEX_BUDGET / f64::from(points_per_path.max(1.0)) / rays).round().clamp(1.0, 1e4) as u32;
    config.graph_builder.iterations_per_step = per_ray;
    // The radius as the config states it (the thesis's diameter / 1000 times the modifier).
    config.graph_builder.radius_modifier = radius / (scene_radius * 2.0 / 1000.0);
    Sizing {
        config,
        radius,
        free_path,
        footprint,
        occupied_volume: occupied,
        points_per_path,
        light_paths: f64::from(per_ray) * rays,
        radius_from,
    }
}
