//! The registry of methods: one [`Method`] entry per integrator, defined in the method's own
//! folder and listed once in [`METHODS`]. Everything outside the methods' folders — the scene
//! builder, the commands, `nimbus cluster` — asks the registry or a method's
//! [`MethodSettings`] instead of matching names. Adding a method is its folder and one line in
//! [`METHODS`].

use std::any::Any;
use std::path::Path;

use nimbus_parser::{Entity, Error};

use super::volpath::LightSamplerKind;
use super::{Integrator, guided, pathgraph, radiancegraph, simplevolpath, volpath};
use crate::scene::Scene;

/// One method: its names and its settings reader.
pub struct Method {
    /// The name scenes and `--integrator` use.
    pub name: &'static str,
    /// Other names scenes use for it (the radiance-graph thesis's scenes call its method
    /// `graph` and their VolPath reference `volpathcustom`).
    pub aliases: &'static [&'static str],
    /// Reads the `Integrator` entity's parameters.
    pub read: fn(&Entity) -> Result<Box<dyn MethodSettings>, Error>,
}

/// Every method nimbus has, the reference first.
pub const METHODS: &[Method] =
    &[volpath::METHOD, simplevolpath::METHOD, radiancegraph::METHOD, pathgraph::METHOD, guided::METHOD];

/// The reference every method is judged against (pbrt-v4's algorithm).
pub const REFERENCE: &str = METHODS[0].name;

/// The methods' names, in [`METHODS`] order.
pub const INTEGRATOR_NAMES: &[&str] = &names();

const fn names() -> [&'static str; METHODS.len()] {
    let mut out = [""; METHODS.len()];
    let mut i = 0;
    while i < METHODS.len() {
        out[i] = METHODS[i].name;
        i += 1;
    }
    out
}

/// The method `name` stands for, by its name or an alias.
pub fn find(name: &str) -> Option<&'static Method> {
    METHODS.iter().find(|m| m.name == name || m.aliases.contains(&name))
}

/// The method's name for `name` (an alias's method's, or `name` itself when no method has it).
pub fn canonical_name(name: &str) -> &str {
    find(name).map_or(name, |m| m.name)
}

/// Files from outside the scene a method may read before rendering.
#[derive(Clone, Copy, Debug, Default)]
pub struct MethodInputs<'a> {
    /// The scene file (methods look for their own files beside it: the radiance graph's
    /// `.json` config).
    pub scene_file: Option<&'a Path>,
    /// `--precomputed` (`--graph-data`, `--guide-cache`): what the method prepared before,
    /// loaded when it exists, else prepared and saved there (the same rule for every method:
    /// [`super::prepared::load_or_prepare`]).
    pub precomputed: Option<&'a Path>,
}

/// What `nimbus cluster` runs before a method's render tasks: a job whose output every task
/// reads with `--precomputed`.
#[derive(Clone, Debug, PartialEq)]
pub enum Precompute {
    /// nimbus itself with `args` followed by the folder `file` is in (under the cluster's
    /// output folder) writes `file` there.
    Command {
        /// nimbus's arguments (the subcommand first), up to the output folder.
        args: Vec<String>,
        /// The file it writes, relative to the cluster's output folder.
        file: String,
    },
    /// The method's first render prepares `file` (relative to the cluster's output folder)
    /// when it is missing: one pixel at one sample renders it.
    FirstRender {
        /// The file, relative to the cluster's output folder.
        file: String,
    },
}

/// Copying and downcasting boxed settings, for every settings type that is `Clone`.
pub trait SettingsBox {
    /// A copy.
    fn clone_box(&self) -> Box<dyn MethodSettings>;

    /// For downcasting to the method's own settings type.
    fn as_any(&self) -> &dyn Any;
}

impl<T: MethodSettings + Clone> SettingsBox for T {
    fn clone_box(&self) -> Box<dyn MethodSettings> {
        Box::new(self.clone())
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// A method's settings, read from the scene's `Integrator` entity: what the rest of nimbus
/// may ask a method before and while it prepares to render.
pub trait MethodSettings: SettingsBox + std::fmt::Debug + Send + Sync + Any {
    /// The method's entry in [`METHODS`].
    fn method(&self) -> &'static Method;

    /// Sets the longest path (`--maxdepth`); methods without one say so.
    fn set_max_depth(&mut self, depth: u32) -> crate::Result<()>;

    /// Takes the files from outside the scene it reads (none by default).
    fn set_inputs(&mut self, _inputs: &MethodInputs<'_>) {}

    /// Whether the method prepares something before rendering (a graph, a guide) that
    /// `--precomputed` keeps in a file; methods that do not never read one.
    fn prepares(&self) -> bool {
        false
    }

    /// Light selection for next-event estimation (pbrt-v4's default: the light BVH).
    fn light_sampler(&self) -> LightSamplerKind {
        LightSamplerKind::Bvh
    }

    /// Why the method cannot write a spectral film, if it cannot.
    fn spectral_film_refusal(&self) -> Option<&'static str> {
        None
    }

    /// Whether the method can render `scene` at all (its constraints), without preparing
    /// anything: what `nimbus check` asks. The error is the one [`MethodSettings::create`]
    /// would give.
    fn check(&self, _scene: &Scene) -> crate::Result<()> {
        Ok(())
    }

    /// The job `nimbus cluster` runs before the method's render tasks, for `scene_file`.
    fn precompute(&self, _scene_file: &Path) -> crate::Result<Option<Precompute>> {
        Ok(None)
    }

    /// Creates the integrator for `scene` (as pbrt-v4's `Integrator::Create` receives the
    /// scene's lights: methods may build per-scene tables here, and methods that precompute
    /// do it here: the radiance graph loads or builds its graph, guiding trains). Fails with
    /// a message for the user when the precomputation cannot run.
    fn create(&self, scene: &Scene) -> crate::Result<Box<dyn Integrator>>;
}

/// A method ready to render a scene, and what preparing it took.
pub struct Prepared {
    /// The integrator.
    pub integrator: Box<dyn Integrator>,
    /// Wall seconds the preparation took (training, building or loading a graph; next to
    /// nothing for methods that prepare nothing).
    pub seconds: f64,
}

impl Prepared {
    /// What is left of a budget of `total` seconds once preparing is counted in it: every
    /// command that compares methods at equal time counts preparation this one way (scene
    /// building, the same for every method, is not counted).
    pub fn remaining(&self, total: Option<f64>) -> Option<f64> {
        total.map(|t| (t - self.seconds).max(0.0))
    }
}

/// Prepares the scene's method: the pipeline's own timed phase between building the scene
/// and rendering it (`nimbus render`, `compare`, `bench`; `stress` and `cluster` run
/// `render`).
pub fn prepare(settings: &dyn MethodSettings, scene: &Scene) -> crate::Result<Prepared> {
    let t = std::time::Instant::now();
    let integrator = settings.create(scene)?;
    Ok(Prepared { integrator, seconds: t.elapsed().as_secs_f64() })
}

/// What nimbus says about a pbrt-v4 integrator it does not have: `Ok(note)` when the scene
/// renders with the reference instead (the note says why that is the same image),
/// `Err(reason)` when it is refused (the reason names the nimbus integrator that computes its
/// image). `None` for names nimbus has or does not know.
pub fn pbrt_v4_substitute(name: &str) -> Option<Result<&'static str, &'static str>> {
    Some(match name {
        "path" | "simplepath" => {
            Ok("pbrt-v4's surface path tracer runs as \"volpath\", which computes the same image for surfaces \
             (and, unlike it, also renders the scene's participating media)")
        }
        "randomwalk" => Ok("pbrt-v4's random-walk integrator runs as \"volpath\": the same image (the random walk's \
             expectation) with next-event estimation and far less noise"),
        "bdpt" => Err("bidirectional path tracing is not in nimbus; \"volpath\" converges to the same image"),
        "mlt" => Err("Metropolis light transport is not in nimbus; \"volpath\" converges to the same image"),
        "sppm" => {
            Err("stochastic progressive photon mapping is not in nimbus; \"volpath\" converges to the same image")
        }
        "lightpath" => Err("light tracing is not in nimbus; \"volpath\" converges to the same image"),
        "ambientocclusion" => {
            Err("ambient occlusion is not light transport and nimbus has no integrator that computes it")
        }
        "function" => Err("pbrt-v4's function-integration test harness is not a renderer; nimbus has none"),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_aliases_find_their_method() {
        assert_eq!(INTEGRATOR_NAMES, ["volpath", "simplevolpath", "radiancegraph", "pathgraph", "guided"]);
        assert_eq!(REFERENCE, "volpath");
        assert_eq!(canonical_name("graph"), "radiancegraph");
        assert_eq!(canonical_name("volpathcustom"), "volpath");
        assert_eq!(canonical_name("nosuch"), "nosuch");
        for m in METHODS {
            assert_eq!(find(m.name).map(|f| f.name), Some(m.name));
        }
    }

    #[test]
    fn no_two_methods_share_a_name() {
        let mut all: Vec<&str> =
            METHODS.iter().flat_map(|m| std::iter::once(m.name).chain(m.aliases.iter().copied())).collect();
        let n = all.len();
        all.sort();
        all.dedup();
        assert_eq!(all.len(), n, "{all:?}");
    }
}
