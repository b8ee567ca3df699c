//! The thesis's graph configuration (`scene.json`, thesis Appendix B), read unchanged.
//!
//! The thesis's `graph_maker` requires every key except the two reinforcement blocks; nimbus
//! lets any key be missing and takes the value most of the thesis's 15 published configs
//! (repository tsvdh/PbrtScenes) use. An unknown key or a value of the wrong type is an error
//! naming the key's JSON path, so a typo never silently falls back to a default.

use std::fmt;
use std::path::Path;

use serde_json::{Map, Value};

/// `graphBuilder.renderSearchRange` (thesis Sec. 4.3.2).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSearchRange {
    /// Compute per-node render search ranges (Eq. 4.21); otherwise the node radius is used.
    pub active: bool,
    /// k of Eq. 4.21.
    pub neighbours_to_use: u32,
    /// Compute in parallel.
    pub run_in_parallel: bool,
}

/// `graphBuilder.edgeReinforcement`: trace from nodes with few outgoing edges.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeReinforcement {
    /// Enabled.
    pub active: bool,
    /// Stop once fewer than this fraction of the initial nodes are sparse.
    pub unsatisfied_allowed_ratio: f32,
    /// Rays per sparse node per round.
    pub reinforcement_rays: u32,
    /// Outgoing edges a node needs to be satisfied.
    pub edges_for_not_sparse: u32,
}

/// `graphBuilder.neighbourReinforcement`: trace from nodes with few nearby nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct NeighbourReinforcement {
    /// Enabled.
    pub active: bool,
    /// Stop once fewer than this fraction of the initial nodes are sparse.
    pub unsatisfied_allowed_ratio: f32,
    /// Rays per sparse node per round.
    pub reinforcement_rays: u32,
    /// Nodes within range a node needs to be satisfied.
    pub neighbours_for_not_sparse: u32,
    /// The range, in node radii.
    pub neighbour_range_modifier: f32,
}

/// `graphBuilder` (thesis Sec. 4.3).
#[derive(Clone, Debug, PartialEq)]
pub struct GraphBuilder {
    /// Light rays per side of the grid over the distant light.
    pub dimension_steps: u32,
    /// Paths traced per grid ray.
    pub iterations_per_step: u32,
    /// Largest number of nodes on a traced path.
    pub max_depth: u32,
    /// Multiplier of the default node radius (scene radius / 500, Sec. 4.3.1).
    pub radius_modifier: f32,
    /// Render search ranges.
    pub render_search_range: RenderSearchRange,
    /// Edge reinforcement.
    pub edge_reinforcement: EdgeReinforcement,
    /// Neighbour reinforcement.
    pub neighbour_reinforcement: NeighbourReinforcement,
}

/// `lightingCalculator` (thesis Secs. 4.4–4.5).
#[derive(Clone, Debug, PartialEq)]
pub struct LightingCalculator {
    /// Transmittance estimates per disk point (Eq. 4.22).
    pub light_iterations: u32,
    /// Disk points per radius (0: the node centre only).
    pub points_on_radius_light: u32,
    /// Bounce counts to write a graph for (depth = bounces + 1, Eq. 4.23).
    pub bounces: Vec<u32>,
    /// Compute in parallel.
    pub run_in_parallel: bool,
}

/// A whole configuration file.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphConfig {
    /// Graph building.
    pub graph_builder: GraphBuilder,
    /// Direct light and transport.
    pub lighting_calculator: LightingCalculator,
}

impl Default for GraphConfig {
    /// The value most of the thesis's published configs use for each key.
    fn default() -> GraphConfig {
        GraphConfig {
            graph_builder: GraphBuilder {
                dimension_steps: 400,
                iterations_per_step: 100,
                max_depth: 10,
                radius_modifier: 1.0,
                render_search_range: RenderSearchRange { active: true, neighbours_to_use: 5, run_in_parallel: true },
                edge_reinforcement: EdgeReinforcement {
                    active: true,
                    unsatisfied_allowed_ratio: 0.001,
                    reinforcement_rays: 2,
                    edges_for_not_sparse: 5,
                },
                neighbour_reinforcement: NeighbourReinforcement {
                    active: true,
                    unsatisfied_allowed_ratio: 0.01,
                    reinforcement_rays: 10,
                    neighbours_for_not_sparse: 5,
                    neighbour_range_modifier: 2.0,
                },
            },
            lighting_calculator: LightingCalculator {
                light_iterations: 5,
                points_on_radius_light: 1,
                bounces: vec![9],
                run_in_parallel: true,
            },
        }
    }
}

/// A configuration error: the file, the key's JSON path (`graphBuilder.maxDepth`) and what is
/// wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigError {
    /// The file read (empty for in-memory text).
    pub file: String,
    /// JSON path of the offending key (empty for the whole document).
    pub path: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let file = if self.file.is_empty() { "graph config" } else { &self.file };
        if self.path.is_empty() {
            write!(f, "{file}: {}", self.message)
        } else {
            write!(f, "{file}: {}: {}", self.path, self.message)
        }
    }
}

impl std::error::Error for ConfigError {}

/// Reads one JSON object's keys, each at most once, and reports unknown ones at the end.
struct Object<'a> {
    path: String,
    map: &'a Map<String, Value>,
    used: Vec<&'static str>,
}

type Res<T> = Result<T, (String, String)>;

impl<'a> Object<'a> {
    fn new(path: String, v: &'a Value) -> Res<Object<'a>> {
        match v {
            Value::Object(map) => Ok(Object { path, map, used: Vec::new() }),
            other => Err((path, format!("expected an object, found {}", kind(other)))),
        }
    }

    fn child_path(&self, key: &str) -> String {
        if self.path.is_empty() { key.to_string() } else { format!("{}.{key}", self.path) }
    }

    fn get(&mut self, key: &'static str) -> Option<(String, &'a Value)> {
        self.used.push(key);
        self.map.get(key).map(|v| (self.child_path(key), v))
    }

    fn object(&mut self, key: &'static str) -> Res<Option<Object<'a>>> {
        self.get(key).map(|(p, v)| Object::new(p, v)).transpose()
    }

    fn bool(&mut self, key: &'static str, default: bool) -> Res<bool> {
        match self.get(key) {
            None => Ok(default),
            Some((_, Value::Bool(b))) => Ok(*b),
            Some((p, other)) => Err((p, format!("expected true or false, found {}", kind(other)))),
        }
    }

    fn count(&mut self, key: &'static str, default: u32) -> Res<u32> {
        match self.get(key) {
            None => Ok(default),
            Some((p, v)) => count(&p, v),
        }
    }

    fn float(&mut self, key: &'static str, default: f32) -> Res<f32> {
        match self.get(key) {
            None => Ok(default),
            Some((p, Value::Number(n))) => match n.as_f64() {
                Some(x) if x.is_finite() && x >= 0.0 => Ok(x as f32),
                _ => Err((p, format!("expected a non-negative number, found {n}"))),
            },
            Some((p, other)) => Err((p, format!("expected a number, found {}", kind(other)))),
        }
    }

    fn finish(self) -> Res<()> {
        match self.map.keys().find(|k| !self.used.contains(&k.as_str())) {
            Some(k) => Err((self.child_path(k), format!("unknown key (known here: {})", self.used.join(", ")))),
            None => Ok(()),
        }
    }
}

fn count(path: &str, v: &Value) -> Res<u32> {
    match v {
        Value::Number(n) => match n.as_u64() {
            Some(x) if x <= u32::MAX as u64 => Ok(x as u32),
            _ => Err((path.to_string(), format!("expected a non-negative integer, found {n}"))),
        },
        other => Err((path.to_string(), format!("expected an integer, found {}", kind(other)))),
    }
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

impl GraphConfig {
    /// Reads a configuration file.
    pub fn from_file(path: &Path) -> Result<GraphConfig, ConfigError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError {
            file: file.clone(),
            path: String::new(),
            message: format!("cannot read: {e}"),
        })?;
        GraphConfig::from_json(&text).map_err(|e| ConfigError { file, ..e })
    }

    /// Reads configuration text.
    pub fn from_json(text: &str) -> Result<GraphConfig, ConfigError> {
        let value: Value = serde_json::from_str(text).map_err(|e| ConfigError {
            file: String::new(),
            path: String::new(),
            message: format!("not valid JSON: {e}"),
        })?;
        GraphConfig::from_value(&value).map_err(|(path, message)| ConfigError { file: String::new(), path, message })
    }

    fn from_value(v: &Value) -> Res<GraphConfig> {
        let d = GraphConfig::default();
        let mut root = Object::new(String::new(), v)?;
        let graph_builder = match root.object("graphBuilder")? {
            None => d.graph_builder,
            Some(mut g) => {
                let dg = d.graph_builder;
                let render_search_range = match g.object("renderSearchRange")? {
                    None => dg.render_search_range,
                    Some(mut o) => {
                        let dr = &dg.render_search_range;
                        let r = RenderSearchRange {
                            active: o.bool("active", dr.active)?,
                            neighbours_to_use: o.count("neighboursToUse", dr.neighbours_to_use)?,
                            run_in_parallel: o.bool("runInParallel", dr.run_in_parallel)?,
                        };
                        o.finish()?;
                        r
                    }
                };
                let edge_reinforcement = match g.object("edgeReinforcement")? {
                    None => dg.edge_reinforcement,
                    Some(mut o) => {
                        let de = &dg.edge_reinforcement;
                        let r = EdgeReinforcement {
                            active: o.bool("active", de.active)?,
                            unsatisfied_allowed_ratio: o
                                .float("unsatisfiedAllowedRatio", de.unsatisfied_allowed_ratio)?,
                            reinforcement_rays: o.count("reinforcementRays", de.reinforcement_rays)?,
                            edges_for_not_sparse: o.count("edgesForNotSparse", de.edges_for_not_sparse)?,
                        };
                        o.finish()?;
                        r
                    }
                };
                let neighbour_reinforcement = match g.object("neighbourReinforcement")? {
                    None => dg.neighbour_reinforcement,
                    Some(mut o) => {
                        let dn = &dg.neighbour_reinforcement;
                        let r = NeighbourReinforcement {
                            active: o.bool("active", dn.active)?,
                            unsatisfied_allowed_ratio: o
                                .float("unsatisfiedAllowedRatio", dn.unsatisfied_allowed_ratio)?,
                            reinforcement_rays: o.count("reinforcementRays", dn.reinforcement_rays)?,
                            neighbours_for_not_sparse: o
                                .count("neighboursForNotSparse", dn.neighbours_for_not_sparse)?,
                            neighbour_range_modifier: o.float("neighbourRangeModifier", dn.neighbour_range_modifier)?,
                        };
                        o.finish()?;
                        r
                    }
                };
                let b = GraphBuilder {
                    dimension_steps: g.count("dimensionSteps", dg.dimension_steps)?,
                    iterations_per_step: g.count("iterationsPerStep", dg.iterations_per_step)?,
                    max_depth: g.count("maxDepth", dg.max_depth)?,
                    radius_modifier: g.float("radiusModifier", dg.radius_modifier)?,
                    render_search_range,
                    edge_reinforcement,
                    neighbour_reinforcement,
                };
                g.finish()?;
                b
            }
        };
        let lighting_calculator = match root.object("lightingCalculator")? {
            None => d.lighting_calculator,
            Some(mut o) => {
                let dl = d.lighting_calculator;
                let bounces = match o.get("bounces") {
                    None => dl.bounces,
                    Some((p, Value::Array(items))) => {
                        if items.is_empty() {
                            return Err((p, "expected at least one bounce count".into()));
                        }
                        items.iter().enumerate().map(|(i, v)| count(&format!("{p}[{i}]"), v)).collect::<Res<_>>()?
                    }
                    Some((p, other)) => {
                        return Err((p, format!("expected an array of integers, found {}", kind(other))));
                    }
                };
                let l = LightingCalculator {
                    light_iterations: o.count("lightIterations", dl.light_iterations)?,
                    points_on_radius_light: o.count("pointsOnRadiusLight", dl.points_on_radius_light)?,
                    bounces,
                    run_in_parallel: o.bool("runInParallel", dl.run_in_parallel)?,
                };
                o.finish()?;
                l
            }
        };
        root.finish()?;
        let c = GraphConfig { graph_builder, lighting_calculator };
        c.check()?;
        Ok(c)
    }

    /// Values the method cannot run with (the thesis's program stops on the same ones).
    fn check(&self) -> Res<()> {
        let g = &self.graph_builder;
        let positive = [
            ("graphBuilder.dimensionSteps", g.dimension_steps),
            ("graphBuilder.iterationsPerStep", g.iterations_per_step),
            ("graphBuilder.maxDepth", g.max_depth),
            ("lightingCalculator.lightIterations", self.lighting_calculator.light_iterations),
        ];
        for (path, v) in positive {
            if v == 0 {
                return Err((path.into(), "must be at least 1".into()));
            }
        }
        if g.radius_modifier <= 0.0 {
            return Err(("graphBuilder.radiusModifier".into(), "must be positive".into()));
        }
        if g.render_search_range.active && g.render_search_range.neighbours_to_use == 0 {
            return Err(("graphBuilder.renderSearchRange.neighboursToUse".into(), "must be at least 1".into()));
        }
        let reinforcing = g.edge_reinforcement.active || g.neighbour_reinforcement.active;
        if reinforcing && g.max_depth == 1 {
            return Err(("graphBuilder.maxDepth".into(), "reinforcement needs a maxDepth of at least 2".into()));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis's `cube/sparse-position/cube.json`, verbatim.
    const CUBE: &str = r#"{
        "graphBuilder": {
            "dimensionSteps": 400, "iterationsPerStep": 100, "maxDepth": 10, "radiusModifier": 2,
            "renderSearchRange": { "active": true, "neighboursToUse": 5, "runInParallel": true },
            "edgeReinforcement": { "active": false, "unsatisfiedAllowedRatio": 0.01,
                                   "reinforcementRays": 3, "edgesForNotSparse": 5 },
            "neighbourReinforcement": { "active": false, "unsatisfiedAllowedRatio": 0.05,
                                        "reinforcementRays": 10, "neighboursForNotSparse": 5,
                                        "neighbourRangeModifier": 3 }
        },
        "lightingCalculator": { "lightIterations": 10, "pointsOnRadiusLight": 0, "bounces": [9],
                                "runInParallel": true }
    }"#;

    #[test]
    fn reads_a_thesis_config() {
        let c = GraphConfig::from_json(CUBE).unwrap();
        assert_eq!(c.graph_builder.radius_modifier, 2.0);
        assert!(!c.graph_builder.edge_reinforcement.active);
        assert_eq!(c.graph_builder.neighbour_reinforcement.neighbour_range_modifier, 3.0);
        assert_eq!(c.lighting_calculator.light_iterations, 10);
        assert_eq!(c.lighting_calculator.points_on_radius_light, 0);
        assert_eq!(c.lighting_calculator.bounces, vec![9]);
    }

    #[test]
    fn missing_keys_take_defaults() {
        let c = GraphConfig::from_json(r#"{"graphBuilder": {"maxDepth": 3}}"#).unwrap();
        let d = GraphConfig::default();
        assert_eq!(c.graph_builder.max_depth, 3);
        assert_eq!(c.graph_builder.dimension_steps, d.graph_builder.dimension_steps);
        assert_eq!(c.lighting_calculator, d.lighting_calculator);
        assert_eq!(GraphConfig::from_json("{}").unwrap(), d);
    }

    fn err(text: &str) -> String {
        GraphConfig::from_json(text).unwrap_err().to_string()
    }

    #[test]
    fn errors_name_the_json_path() {
        let e = err(r#"{"graphBuilder": {"renderSearchRange": {"active": 1}}}"#);
        assert!(e.contains("graphBuilder.renderSearchRange.active: expected true or false, found a number"), "{e}");
        let e = err(r#"{"graphBuilder": {"edgeReinforcement": {"edgesForNotSparce": 5}}}"#);
        assert!(e.contains("graphBuilder.edgeReinforcement.edgesForNotSparce: unknown key"), "{e}");
        let e = err(r#"{"lightingCalculator": {"bounces": [9, "x"]}}"#);
        assert!(e.contains("lightingCalculator.bounces[1]: expected an integer, found a string"), "{e}");
        let e = err(r#"{"lightingCalculator": {"bounces": 9}}"#);
        assert!(e.contains("lightingCalculator.bounces: expected an array"), "{e}");
        let e = err(r#"{"graphBuilder": {"maxDepth": -2}}"#);
        assert!(e.contains("graphBuilder.maxDepth: expected a non-negative integer, found -2"), "{e}");
        let e = err(r#"{"graphBuilder": {"dimensionSteps": 2.5}}"#);
        assert!(e.contains("graphBuilder.dimensionSteps: expected a non-negative integer"), "{e}");
        let e = err(r#"{"graphbuilder": {}}"#);
        assert!(e.contains("graphbuilder: unknown key"), "{e}");
        let e = err(r#"{"graphBuilder": {"iterationsPerStep": 0}}"#);
        assert!(e.contains("graphBuilder.iterationsPerStep: must be at least 1"), "{e}");
        let e = err(r#"{"graphBuilder": []}"#);
        assert!(e.contains("graphBuilder: expected an object, found an array"), "{e}");
        assert!(err("{").contains("not valid JSON"));
    }

    #[test]
    fn file_errors_name_the_file() {
        let dir = std::env::temp_dir().join(format!("nimbus-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("bad.json");
        std::fs::write(&f, r#"{"lightingCalculator": {"runInParallel": "yes"}}"#).unwrap();
        let e = GraphConfig::from_file(&f).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(e.starts_with(&f.display().to_string()), "{e}");
        assert!(e.contains("lightingCalculator.runInParallel: expected true or false, found a string"), "{e}");
        let missing = GraphConfig::from_file(Path::new("/nonexistent/x.json")).unwrap_err().to_string();
        assert!(missing.contains("/nonexistent/x.json: cannot read"), "{missing}");
    }
}
