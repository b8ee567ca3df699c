//! Integrators: one folder per method, each with its settings. The registry maps the names
//! scenes and `--integrator` use to settings readers.

pub mod volpath;

use nimbus_parser::{Entity, Error};

/// Settings of the integrator a scene asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum IntegratorSettings {
    /// `volpath`
    VolPath(volpath::VolPathSettings),
}

/// Names of the integrators nimbus has.
pub const INTEGRATOR_NAMES: &[&str] = &["volpath"];

impl IntegratorSettings {
    /// Reads the integrator entity; `name_override` replaces the scene's choice (the
    /// parameters that method shares with the scene's are kept).
    pub fn from_entity(
        e: &Entity,
        name_override: Option<&str>,
    ) -> Result<IntegratorSettings, Error> {
        match name_override.unwrap_or(&e.name) {
            "volpath" => Ok(IntegratorSettings::VolPath(
                volpath::VolPathSettings::from_entity(e)?,
            )),
            other => Err(Error::new(
                &e.loc,
                format!(
                    "integrator \"{other}\" is not available in nimbus (it has: {})",
                    INTEGRATOR_NAMES.join(", ")
                ),
            )),
        }
    }

    /// The method's name.
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorSettings::VolPath(_) => "volpath",
        }
    }
}
