//! `volpath` parameters, with pbrt-v4's names and defaults.

use nimbus_parser::{Entity, Error};

pub use crate::lights::LightSamplerKind;

/// `volpath` parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct VolPathSettings {
    /// Maximum number of scattering events.
    pub max_depth: u32,
    /// Roughen near-specular BSDFs after the first diffuse bounce.
    pub regularize: bool,
    /// Light selection for next-event estimation.
    pub light_sampler: LightSamplerKind,
}

impl VolPathSettings {
    /// Reads the parameters.
    pub fn from_entity(e: &Entity) -> Result<VolPathSettings, Error> {
        let p = &e.params;
        let max_depth = p.get_one_int("maxdepth", 5)?;
        if max_depth < 0 {
            return Err(Error::new(p.loc("maxdepth").unwrap_or(&e.loc), "\"maxdepth\" cannot be negative"));
        }
        let light_sampler = match p.get_one_string("lightsampler", "bvh")? {
            "uniform" => LightSamplerKind::Uniform,
            "power" => LightSamplerKind::Power,
            "bvh" => LightSamplerKind::Bvh,
            other => {
                return Err(Error::new(
                    p.loc("lightsampler").unwrap_or(&e.loc),
                    format!("unknown light sampler \"{other}\" (uniform, power or bvh)"),
                ));
            }
        };
        Ok(VolPathSettings {
            max_depth: max_depth as u32,
            regularize: p.get_one_bool("regularize", false)?,
            light_sampler,
        })
    }
}
