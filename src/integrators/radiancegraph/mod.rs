//! The radiance-graph method of van den Hurk's thesis (2026): light paths grouped into a graph
//! of volume nodes, direct light per node, transport through the graph by a Neumann series,
//! and rendering from the nodes' radiance. See this folder's README for the map from the
//! thesis's sections and equations to files.
//!

pub mod build;

pub mod config;
pub mod edges;
pub mod file;
pub mod graph;
pub mod lighting;
pub mod render;
pub mod search_range;
pub mod sh;
pub mod similarity;
pub mod sizing;
pub mod transport;
pub mod volume;

use std::path::Path;
use std::time::Instant;

use config::GraphConfig;
use glam::Vec3;
use render::RadianceCache;
use volume::Volume;

use super::prepared::load_or_prepare;
use super::registry::{Method, MethodInputs, MethodSettings, Precompute};
use crate::scene::Scene;

/// The registry's entry (`graph` is the thesis's name for it).
pub const METHOD: Method = Method { name: "radiancegraph", aliases: &["graph"], read };

fn read(e: &nimbus_parser::Entity) -> Result<Box<dyn MethodSettings>, nimbus_parser::Error> {
    Ok(Box::new(RadianceGraphSettings::from_entity(e)?))
}

impl MethodSettings for RadianceGraphSettings {
    fn method(&self) -> &'static Method {
        &METHOD
    }

    /// The method has no such parameter: its light paths' depth is the graph config's, and
    /// saying so beats ignoring the flag.
    fn set_max_depth(&mut self, _depth: u32) -> crate::Result<()> {
        Err(crate::Error::Invalid(
            "--maxdepth: radiancegraph has no maxdepth; its light paths' depth is the graph config's \
             graphBuilder.maxDepth"
                .into(),
        ))
    }

    fn prepares(&self) -> bool {
        true
    }

    /// The precomputed file is a graph (`nimbus graph build` writes them): loaded when it
    /// exists, else built and saved there. The graph is built with the scene's config,
    /// graph_maker's default: the scene's name with `.json`.
    fn set_inputs(&mut self, inputs: &MethodInputs<'_>) {
        self.graph_data = inputs.precomputed.map(Path::to_path_buf);
        self.config = inputs.scene_file.map(|f| f.with_extension("json")).filter(|c| c.exists());
    }

    /// `nimbus graph build` with the scene's config, writing the graph of its largest bounce
    /// count as graph_maker names it.
    fn precompute(&self, scene_file: &Path) -> crate::Result<Option<Precompute>> {
        let config_path = scene_file.with_extension("json");
        let config = if config_path.exists() {
            GraphConfig::from_file(&config_path).map_err(|e| crate::Error::Invalid(e.to_string()))?
        } else {
            GraphConfig::default()
        };
        let depth = config.lighting_calculator.bounces.iter().max().copied().unwrap_or(0) + 1;
        let stem = config_path.file_stem().map_or("graph".into(), |s| s.to_string_lossy().into_owned());
        let args = ["graph", "build", &scene_file.display().to_string(), "--quiet", "--out"].map(String::from).to_vec();
        Ok(Some(Precompute::Command { args, file: format!("graph/{stem}_d{depth}.txt") }))
    }

    /// The thesis's constraints (one gray isotropic medium, its lights), every violated one
    /// named.
    fn check(&self, scene: &Scene) -> crate::Result<()> {
        check_estimator(self.estimator, &Volume::new(scene)?)
    }

    fn create(&self, scene: &Scene) -> crate::Result<Box<dyn super::Integrator>> {
        Ok(Box::new(create(self, scene)?))
    }
}

/// What `Integrator "radiancegraph"` (or the thesis's `"graph"`) renders from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RadianceGraphSettings {
    /// `--graph-data`: a graph built by `nimbus graph build`.
    pub graph_data: Option<std::path::PathBuf>,
    /// The config to build with when there is no graph file (the scene's `.json`).
    pub config: Option<std::path::PathBuf>,
    /// How camera rays integrate through the medium (`"string estimator"`).
    pub estimator: render::Estimator,
    /// The scene's `"integer maxdepth"`, when it gives one: a graph sized without a config
    /// transports as many bounces as a path of that depth has (`maxdepth − 1`).
    pub max_depth: Option<u32>,
}

impl RadianceGraphSettings {
    /// Reads the integrator's parameters: `"string estimator"`, `"deltatracking"` (the
    /// thesis's, default) or `"collision"`.
    pub fn from_entity(e: &nimbus_parser::Entity) -> Result<RadianceGraphSettings, nimbus_parser::Error> {
        let p = &e.params;
        let estimator = match p.get_one_string("estimator", "deltatracking")? {
            "deltatracking" => render::Estimator::DeltaTracking,
            "collision" => render::Estimator::Collision,
            other => {
                return Err(nimbus_parser::Error::new(
                    p.loc("estimator").unwrap_or(&e.loc),
                    format!("unknown estimator \"{other}\" (deltatracking or collision)"),
                ));
            }
        };
        Ok(RadianceGraphSettings { estimator, max_depth: scene_max_depth(e)?, ..Default::default() })
    }
}

/// The collision estimator walks the camera ray through the boundary alone: surfaces beside
/// the medium need the path loop of the default estimator.
fn check_estimator(estimator: render::Estimator, volume: &Volume) -> crate::Result<()> {
    if estimator == render::Estimator::Collision && volume.has_opaque {
        return Err(crate::Error::Unsupported(
            "the radiance-graph method's \"collision\" estimator needs surfaces only as the medium's boundary \
             (the scene has others; the default \"deltatracking\" shades them)"
                .into(),
        ));
    }
    if let (render::Estimator::Collision, Some(s)) = (estimator, volume.similarity) {
        return Err(crate::Error::Unsupported(format!(
            "the radiance-graph method's \"collision\" estimator reads the graph all along the camera ray; a medium \
             with g = {} is read after {} exact scattering events (the similar medium), which only the default \
             \"deltatracking\" estimator does",
            s.g, s.read_at
        )));
    }
    Ok(())
}

/// pbrt-v4's `maxdepth` default: what bounds a camera path's surface bounces before it
/// reaches the medium when the scene gives none.
const DEFAULT_MAX_DEPTH: u32 = 5;

/// The `"integer maxdepth"` of the scene's `Integrator`, if it gives one.
pub fn scene_max_depth(e: &nimbus_parser::Entity) -> Result<Option<u32>, nimbus_parser::Error> {
    if e.params.loc("maxdepth").is_none() {
        return Ok(None);
    }
    Ok(Some(e.params.get_one_int("maxdepth", 5)?.max(1) as u32))
}

/// The integrator for `scene`: from the graph file when it exists (`--precomputed`, the
/// thesis's `--graph-data`: it must be this scene's), else from a graph built now with the
/// scene's config (or the defaults), keeping the largest bounce count it asks for, and saved
/// to that file when one was named ([`load_or_prepare`]).
pub fn create(settings: &RadianceGraphSettings, scene: &Scene) -> crate::Result<render::RadianceGraphIntegrator> {
    let volume = Volume::new(scene)?;
    check_estimator(settings.estimator, &volume)?;
    let scene_hash = file::scene_hash(&volume);
    let mut build_peak = 0;
    let load = |path: &Path| {
        let f = file::GraphFile::read(path, Some(scene_hash))?;
        if f.radiance.len() != volume.lights.len() {
            return Err(crate::Error::mismatch(
                path,
                format!("the graph has {} lights, the scene {}", f.radiance.len(), volume.lights.len()),
            ));
        }
        if f.coefficients as usize != coefficients(&volume) {
            return Err(crate::Error::mismatch(
                path,
                "the graph's radiance is not directional as the medium's phase function needs",
            ));
        }
        Ok(f)
    };
    let mut coarse = None;
    let prepare = || {
        let seed = scene.sampler.seed as u64;
        let (config, radius) = match &settings.config {
            Some(path) => (GraphConfig::from_file(path).map_err(|e| crate::Error::Invalid(e.to_string()))?, None),
            None => {
                let s = sizing::size(&volume, seed, settings.max_depth);
                coarse = s.coarse();
                (s.config, Some(s.radius))
            }
        };
        let (graphs, stats) = build(scene, &config, radius, seed)?;
        build_peak = stats.stages.iter().map(|s| s.peak_bytes).max().unwrap_or(0);
        let largest = (0..graphs.graphs.len()).max_by_key(|&i| graphs.graphs[i].bounces).expect("bounces has an entry");
        Ok(graphs.file(largest, scene_hash, file::config_hash(&config), stats.node_radius))
    };
    let (f, _) = load_or_prepare(settings.graph_data.as_deref(), load, prepare, |path, f| f.write(path))?;
    let cache = RadianceCache::new(f.positions, f.ranges, f.radiance);
    Ok(render_integrator(&volume, cache)
        .with_note(coarse)
        .with_estimator(settings.estimator)
        .with_build_peak(build_peak)
        .with_max_depth(settings.max_depth.unwrap_or(DEFAULT_MAX_DEPTH)))
}

/// Radiance values per node and light: 1 in an isotropic medium (the thesis's scalar), the
/// directional coefficients ([`sh::COEFFS`]) otherwise.
pub fn coefficients(volume: &Volume) -> usize {
    if volume.medium.g == 0.0 { 1 } else { sh::COEFFS }
}

/// The integrator over `cache` for `volume`'s lights.
pub fn render_integrator(volume: &Volume, cache: RadianceCache) -> render::RadianceGraphIntegrator {
    let lights = volume.lights.iter().map(|l| *l.radiance()).collect();
    let sky = volume
        .lights
        .iter()
        .filter(|l| matches!(l, volume::GraphLight::Uniform { .. }))
        .map(|l| *l.radiance())
        .collect();
    let integrator = render::RadianceGraphIntegrator::new(cache, lights, sky);
    if let Some(s) = volume.similarity {
        return integrator.with_similarity(s);
    }
    if volume.medium.g == 0.0 {
        return integrator;
    }
    integrator.with_phase(volume.medium.g, volume.lights.iter().map(source).collect())
}

/// Where a light's direct radiance comes from, for directional transport.
fn source(light: &volume::GraphLight) -> transport::Source {
    match light {
        volume::GraphLight::Distant { dir, .. } => transport::Source::Along(*dir),
        volume::GraphLight::Uniform { .. } => transport::Source::Everywhere,
        volume::GraphLight::Point { pos, .. } => transport::Source::Point(*pos),
        volume::GraphLight::Area { lights, .. } => transport::Source::Area(lights.as_slice().into()),
        // From every direction (only in an isotropic medium: Volume refuses the others).
        volume::GraphLight::Emission { .. } => transport::Source::Everywhere,
        volume::GraphLight::Reflected { of } => transport::Source::Reflected(std::sync::Arc::new((**of).clone())),
    }
}

/// Time and memory of one stage of the build.
#[derive(Clone, Debug, PartialEq)]
pub struct Stage {
    /// Stage name.
    pub name: &'static str,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Largest bytes the stage's own structures held.
    pub peak_bytes: usize,
}

/// The thesis's graph statistics (its `<cfg>_stats.json`) and nimbus's own.
#[derive(Clone, Debug)]
pub struct GraphStats {
    /// Nodes.
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
    /// Edges sampled more than once.
    pub edges_more_than_once: usize,
    /// Mean and standard deviation of path runs inside one node.
    pub in_node_path_length: (f64, f64),
    /// Mean and standard deviation of the render search ranges.
    pub render_search_range: Option<(f64, f64)>,
    /// Node radius.
    pub node_radius: f32,
    /// Scene radius (half the medium's bounds diagonal).
    pub scene_radius: f32,
    /// Light paths and reinforcement paths traced, reinforcement rounds.
    pub paths: (u64, u64, u32),
    /// Per stage.
    pub stages: Vec<Stage>,
    /// At the build's peak: bytes of per-node structures and of edge lists.
    pub build_peak: (usize, usize),
}

/// The transported radiance for one requested bounce count.
pub struct BuiltGraph {
    /// Bounces asked for.
    pub bounces: u32,
    /// Bounces reached (fewer at the numerical limit).
    pub bounces_done: u32,
    /// Per light, per node: transported radiance scalars (L'_n of Eq. 4.23), or in an
    /// anisotropic medium the directional coefficients of its bounces after the first
    /// ([`transport::Transport::neumann_directional`]), node-major.
    pub radiance: Vec<Vec<f32>>,
}

/// What a build produces: the nodes, and their radiance for each requested bounce count.
pub struct Graphs {
    /// Node positions.
    pub positions: Vec<Vec3>,
    /// Render search ranges (the node radius when they are off).
    pub ranges: Vec<f32>,
    /// One per entry of `lightingCalculator.bounces`, in its order.
    pub graphs: Vec<BuiltGraph>,
    /// Values per node and light ([`coefficients`]).
    pub coefficients: usize,
}

impl Graphs {
    /// The radiance cache of graph `i`, to render from.
    pub fn cache(&self, i: usize) -> RadianceCache {
        RadianceCache::new(self.positions.clone(), self.ranges.clone(), self.graphs[i].radiance.clone())
    }

    /// Graph `i` as a graph file: the nodes, its radiance, and what it was built for and with.
    pub fn file(&self, i: usize, scene_hash: u64, config_hash: u64, node_radius: f32) -> file::GraphFile {
        let g = &self.graphs[i];
        file::GraphFile {
            scene_hash,
            config_hash,
            bounces: g.bounces,
            bounces_done: g.bounces_done,
            node_radius,
            coefficients: self.coefficients as u32,
            positions: self.positions.clone(),
            ranges: self.ranges.clone(),
            radiance: g.radiance.clone(),
        }
    }

    /// The radiance cache of the graph with the most bounces, consuming the build.
    pub fn into_largest(mut self) -> RadianceCache {
        let i = (0..self.graphs.len()).max_by_key(|&i| self.graphs[i].bounces).expect("bounces has an entry");
        RadianceCache::new(self.positions, self.ranges, self.graphs.swap_remove(i).radiance)
    }
}

/// Builds the graphs of `scene` (thesis Ch. 4: build, direct light, transport) for every
/// entry of `lightingCalculator.bounces`. `node_radius` overrides the config's.
pub fn build(
    scene: &Scene,
    config: &GraphConfig,
    node_radius: Option<f32>,
    seed: u64,
) -> crate::Result<(Graphs, GraphStats)> {
    let volume = Volume::new(scene)?;
    // Sec. 4.3.1: the default radius is the scene's diameter / 1000 (the thesis's code).
    let radius = node_radius.unwrap_or(volume.radius * 2.0 / 1000.0 * config.graph_builder.radius_modifier);
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(crate::Error::Invalid(format!("the node radius must be positive (it is {radius})")));
    }
    let mut stages = Vec::new();
    let t = Instant::now();
    let (graph, report) =
        build::build_graph(&volume, &config.graph_builder, radius, seed, build::default_memory_limit())?;
    let edges_more_than_once = graph.edges_more_than_once();
    stages.push(Stage { name: "build", seconds: t.elapsed().as_secs_f64(), peak_bytes: report.peak.0 + report.peak.1 });
    if graph.is_empty() {
        return Err(crate::Error::invalid("no light path scattered in the medium: the graph is empty"));
    }
    let t = Instant::now();
    let (positions, transport, runs, members) = graph.into_parts();
    let rsr = &config.graph_builder.render_search_range;
    let ranges = if rsr.active {
        search_range::search_ranges(&positions, rsr.neighbours_to_use as usize)?
    } else {
        vec![radius; positions.len()]
    };
    stages.push(Stage {
        name: "search ranges",
        seconds: t.elapsed().as_secs_f64(),
        peak_bytes: positions.len() * (12 + 4) + transport.memory_bytes() + members.memory_bytes(),
    });
    let t = Instant::now();
    let direct = lighting::direct_light(&volume, &positions, radius, &members, &config.lighting_calculator, seed)?;
    stages.push(Stage {
        name: "direct light",
        seconds: t.elapsed().as_secs_f64(),
        peak_bytes: direct.len() * positions.len() * 4 + members.memory_bytes(),
    });
    drop(members);
    let t = Instant::now();
    let bounces = &config.lighting_calculator.bounces;
    let g = volume.medium.g;
    let per_light: Vec<Vec<transport::Transported>> = direct
        .iter()
        .zip(&volume.lights)
        .map(|(d, light)| {
            if g == 0.0 {
                // The similar medium's graph transports light until it has left (`similarity`).
                transport.neumann(d, bounces, volume.similarity.map(|_| similarity::TAIL))
            } else {
                transport.neumann_directional(&positions, d, source(light), g, bounces)
            }
        })
        .collect();
    stages.push(Stage {
        name: "transport",
        seconds: t.elapsed().as_secs_f64(),
        peak_bytes: transport.memory_bytes()
            + per_light.len() * bounces.len() * positions.len() * coefficients(&volume) * 4,
    });
    let stats = GraphStats {
        vertices: positions.len(),
        edges: transport.edges(),
        edges_more_than_once,
        in_node_path_length: (runs.mean(), runs.std()),
        render_search_range: rsr.active.then(|| mean_std(&ranges)),
        node_radius: radius,
        scene_radius: volume.radius,
        paths: (report.light_paths, report.reinforcement_paths, report.reinforcement_rounds),
        stages,
        build_peak: report.peak,
    };
    let mut per_light = per_light;
    let graphs = (0..bounces.len())
        .map(|b| BuiltGraph {
            bounces: bounces[b],
            bounces_done: per_light.iter().map(|l| l[b].bounces_done).min().unwrap_or(bounces[b]),
            radiance: per_light.iter_mut().map(|l| std::mem::take(&mut l[b].radiance)).collect(),
        })
        .collect();
    Ok((Graphs { positions, ranges, graphs, coefficients: coefficients(&volume) }, stats))
}

impl GraphStats {
    /// Per-node bytes at the build's peak.
    pub fn build_peak_bytes_per_node(&self) -> f64 {
        self.build_peak.0 as f64 / self.vertices.max(1) as f64
    }

    /// Edge-list bytes (capacity included) per edge at the build's peak.
    pub fn build_peak_bytes_per_edge(&self) -> f64 {
        self.build_peak.1 as f64 / self.edges.max(1) as f64
    }
}

fn mean_std(v: &[f32]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().map(|&x| f64::from(x)).sum::<f64>() / n;
    let var = v.iter().map(|&x| (f64::from(x) - m).powi(2)).sum::<f64>() / n;
    (m, var.sqrt())
}
