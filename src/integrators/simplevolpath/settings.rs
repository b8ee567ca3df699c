//! `simplevolpath` parameters: pbrt-v4's `maxdepth` (its SimpleVolPathIntegrator's only
//! parameter) and the paper's mixture coefficients (§3, Figure 2: 0.75 for the BRDF and 0.25
//! for the environment map).

use nimbus_parser::{Entity, Error};

/// `simplevolpath` parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct SimpleVolPathSettings {
    /// Maximum number of scattering events (`integer maxdepth`, default 5 as in pbrt-v4).
    pub max_depth: u32,
    /// Mixture weight of the BSDF or phase function (`float bsdffraction`, default 0.75).
    pub bsdf_fraction: f32,
    /// Mixture weight of the luminaires, sampled by solid angle (`float lightfraction`,
    /// default 0.25).
    pub light_fraction: f32,
    /// Mixture weight of the environment, sampled by luminance (`float envfraction`,
    /// default 0.25).
    pub env_fraction: f32,
}

impl Default for SimpleVolPathSettings {
    fn default() -> Self {
        SimpleVolPathSettings { max_depth: 5, bsdf_fraction: 0.75, light_fraction: 0.25, env_fraction: 0.25 }
    }
}

impl SimpleVolPathSettings {
    /// Reads the parameters. The fractions are weights: they are renormalised over the
    /// densities a scene has (no luminaires, no environment), so only their ratios matter.
    pub fn from_entity(e: &Entity) -> Result<SimpleVolPathSettings, Error> {
        let p = &e.params;
        let d = SimpleVolPathSettings::default();
        let max_depth = p.get_one_int("maxdepth", d.max_depth as i32)?;
        if max_depth < 0 {
            return Err(Error::new(p.loc("maxdepth").unwrap_or(&e.loc), "\"maxdepth\" cannot be negative"));
        }
        let fraction = |name: &str, default: f32| -> Result<f32, Error> {
            let v = p.get_one_float(name, default)?;
            if !v.is_finite() || v < 0.0 {
                return Err(Error::new(
                    p.loc(name).unwrap_or(&e.loc),
                    format!("\"{name}\" must be a non-negative number (it is {v})"),
                ));
            }
            Ok(v)
        };
        let s = SimpleVolPathSettings {
            max_depth: max_depth as u32,
            bsdf_fraction: fraction("bsdffraction", d.bsdf_fraction)?,
            light_fraction: fraction("lightfraction", d.light_fraction)?,
            env_fraction: fraction("envfraction", d.env_fraction)?,
        };
        if s.bsdf_fraction + s.light_fraction + s.env_fraction == 0.0 {
            return Err(Error::new(
                &e.loc,
                "\"bsdffraction\", \"lightfraction\" and \"envfraction\" are all 0: the mixture density needs one \
                 positive weight",
            ));
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(params: &str) -> Result<SimpleVolPathSettings, Error> {
        let text = format!("Integrator \"simplevolpath\" {params}\nWorldBegin\n");
        let desc = nimbus_parser::load_str(&text, "test.pbrt").unwrap();
        SimpleVolPathSettings::from_entity(&desc.integrator)
    }

    #[test]
    fn defaults_are_pbrt_v4_maxdepth_and_the_papers_weights() {
        assert_eq!(read("").unwrap(), SimpleVolPathSettings::default());
        let s = read(r#""integer maxdepth" 12 "float bsdffraction" 0.5 "float envfraction" 0"#).unwrap();
        assert_eq!((s.max_depth, s.bsdf_fraction, s.light_fraction, s.env_fraction), (12, 0.5, 0.25, 0.0));
    }

    #[test]
    fn rejects_negative_and_all_zero_weights() {
        let e = read(r#""float lightfraction" -0.1"#).unwrap_err();
        assert!(e.to_string().contains("lightfraction"), "{e}");
        let e = read(r#""float bsdffraction" 0 "float lightfraction" 0 "float envfraction" 0"#).unwrap_err();
        assert!(e.to_string().contains("all 0"), "{e}");
        assert!(read(r#""integer maxdepth" -1"#).is_err());
    }
}
