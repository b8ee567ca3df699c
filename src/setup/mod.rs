//! A render's set-up: the scene and the method that renders it, paired. The scene knows no
//! method and the methods build no scene; this is where the two meet. The method is read
//! first (with the command line's `--integrator` and `--maxdepth`), says what it needs of the
//! scene ([`SceneNeeds`]: its light sampler, whether it can fill a spectral film), and the
//! scene is built for it. [`Setup::prepare`] then runs the method's own timed phase.

mod check;

pub use check::{FullCheck, SceneCheck, check_scene, check_scene_full, unused_parameters};

use nimbus_parser::{Error, SceneDescription, Warning};

use crate::integrators::IntegratorSettings;
use crate::integrators::registry::{self, MethodInputs, Prepared};
use crate::scene::{BuildOptions, Scene, SceneNeeds, build_scene};

/// A scene and the settings of the method that renders it.
pub struct Setup {
    /// The render-time scene.
    pub scene: Scene,
    /// The method and its parameters.
    pub integrator: IntegratorSettings,
}

/// A set-up reads as its scene (`setup.film`, `render(&setup, ..)`): the method is the one
/// thing it adds.
impl std::ops::Deref for Setup {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        &self.scene
    }
}

impl Setup {
    /// Prepares the method for the scene: its own timed phase between building the scene and
    /// rendering it (see [`registry::prepare`]).
    pub fn prepare(&self) -> crate::Result<Prepared> {
        registry::prepare(&*self.integrator, &self.scene)
    }
}

/// A method's refusal of a scene (its constraints, a failed preparation), placed at the
/// scene's `Integrator` directive when it has one.
pub fn method_error(desc: &SceneDescription, e: &crate::Error) -> Error {
    let loc = &desc.integrator.loc;
    Error { loc: (loc.line > 0).then(|| loc.clone()), message: e.to_string() }
}

/// Reads the method, then builds the scene it needs.
pub fn build(desc: &SceneDescription, opts: &BuildOptions) -> Result<Setup, Error> {
    let mut warnings = Vec::new();
    let integrator = integrator(desc, opts, &mut warnings)?;
    let needs = SceneNeeds {
        light_sampler: integrator.light_sampler(),
        spectral_film_refusal: integrator.spectral_film_refusal(),
    };
    let mut scene = build_scene(desc, opts, &needs)?;
    scene.warnings.extend(warnings);
    Ok(Setup { scene, integrator })
}

/// The integrator's settings, with `opts`' overrides (`--integrator`, `--maxdepth`) and the
/// files from outside the scene it reads.
fn integrator(
    desc: &SceneDescription,
    opts: &BuildOptions,
    warnings: &mut Vec<Warning>,
) -> Result<IntegratorSettings, Error> {
    let mut integrator = IntegratorSettings::from_entity(&desc.integrator, opts.integrator.as_deref())?;
    warnings.extend(IntegratorSettings::substitution_note(&desc.integrator, opts.integrator.as_deref()));
    integrator
        .set_inputs(&MethodInputs { scene_file: opts.scene_file.as_deref(), precomputed: opts.precomputed.as_deref() });
    if let Some(file) = opts.precomputed.as_deref().filter(|_| !integrator.prepares()) {
        warnings.push(Warning {
            loc: None,
            message: format!(
                "--precomputed {}: {} prepares nothing before rendering, so the file is neither read nor written",
                file.display(),
                integrator.method().name
            ),
        });
    }
    if let Some(depth) = opts.max_depth {
        integrator.set_max_depth(depth).map_err(|m| Error::new(&desc.integrator.loc, m))?;
    }
    Ok(integrator)
}
