//! `guided` parameters: the path loop's `maxdepth` and `regularize` (shared with `volpath`),
//! the training schedule and the SD-tree thresholds (Müller et al. 2017; Deng et al. 2020,
//! Sec. 4.2), and the sampling strategy (Sec. 4.3–4.4).

use nimbus_parser::{Entity, Error};

use super::sampling::Strategy;

/// `guided` parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct GuidedSettings {
    /// Maximum number of scattering events (`integer maxdepth`, 5 as volpath); photons
    /// scatter at most as often.
    pub max_depth: u32,
    /// Roughen near-specular BSDFs after the first non-specular bounce (`bool regularize`).
    pub regularize: bool,
    /// Rounds of photon tracing (`integer trainingiterations`; the paper uses 3–6).
    pub training_iterations: u32,
    /// Photons of the first round, doubling each round (`integer photons`).
    pub photons: u32,
    /// c of the spatial split threshold c·√(2^k) photons per leaf in round k
    /// (`integer streethreshold`, 12000 as Müller et al. and Deng et al.).
    pub stree_threshold: u32,
    /// Share of a directional tree's energy above which a quadrant is subdivided
    /// (`float dtreethreshold`, 0.01).
    pub dtree_threshold: f32,
    /// How directions are drawn (`candidates`, `lambda`, `mixprob`, `selectivethreshold`,
    /// and nimbus's `defensive`).
    pub strategy: Strategy,
    /// A medium is guided when at least this share of the light it learned came in through a
    /// refractive boundary (`float refractedshare`, 0.5; 0 guides every medium). Not in the
    /// paper, whose media are all bounded by dielectrics: where next-event estimation reaches
    /// the lights (a cloud under the sun), guiding costs more than it saves (README).
    pub refracted_share: f32,
    /// Memory budget of the trees in MiB (`integer maxmemory`): spatial splitting stops there.
    pub max_memory_mib: u32,
    /// A guided path splits at a medium vertex once its expected contribution (β times the
    /// learned fluence there) exceeds this multiple of its value at the path's first guided
    /// vertex (`float splitthreshold`, 2; not in the paper: README).
    pub split_threshold: f32,
    /// Most continuations one split makes (`integer maxsplit`, 8; 1 turns splitting off).
    pub max_split: u32,
    /// `--guide-cache`: trained trees are loaded from this file when it matches the scene,
    /// else trained and saved to it.
    pub cache: Option<std::path::PathBuf>,
}

impl Default for GuidedSettings {
    fn default() -> Self {
        GuidedSettings {
            max_depth: 5,
            regularize: false,
            training_iterations: 4,
            photons: 1 << 16,
            stree_threshold: 12000,
            dtree_threshold: 0.01,
            strategy: Strategy { candidates: 6, lambda: 0.9, mix_prob: 0.5, selective_threshold: 0.5, defensive: 0.3 },
            refracted_share: 0.5,
            max_memory_mib: 64,
            split_threshold: 2.0,
            max_split: 8,
            cache: None,
        }
    }
}

impl GuidedSettings {
    /// Reads the parameters.
    pub fn from_entity(e: &Entity) -> Result<GuidedSettings, Error> {
        let p = &e.params;
        let d = GuidedSettings::default();
        let out_of_range = |name: &str, range: &str, v: String| {
            Error::new(p.loc(name).unwrap_or(&e.loc), format!("\"{name}\" must be {range} (it is {v})"))
        };
        let count = |name: &str, default: u32, min: i32, max: i32| -> Result<u32, Error> {
            let v = p.get_one_int(name, default as i32)?;
            if v < min || v > max {
                return Err(out_of_range(name, &format!("between {min} and {max}"), v.to_string()));
            }
            Ok(v as u32)
        };
        let real = |name: &str, default: f32, min: f32, max: f32| -> Result<f32, Error> {
            let v = p.get_one_float(name, default)?;
            if !(v >= min && v <= max) {
                return Err(out_of_range(name, &format!("between {min} and {max}"), v.to_string()));
            }
            Ok(v)
        };
        Ok(GuidedSettings {
            max_depth: count("maxdepth", d.max_depth, 0, 100_000)?,
            regularize: p.get_one_bool("regularize", d.regularize)?,
            training_iterations: count("trainingiterations", d.training_iterations, 1, 16)?,
            photons: count("photons", d.photons, 1, 1 << 26)?,
            stree_threshold: count("streethreshold", d.stree_threshold, 1, i32::MAX)?,
            dtree_threshold: real("dtreethreshold", d.dtree_threshold, 1e-6, 1.0)?,
            strategy: Strategy {
                candidates: count("candidates", d.strategy.candidates, 1, 1024)?,
                lambda: real("lambda", d.strategy.lambda, 0.0, 1.0)?,
                mix_prob: real("mixprob", d.strategy.mix_prob, 0.0, 1.0)?,
                selective_threshold: real("selectivethreshold", d.strategy.selective_threshold, 0.0, 2.0)?,
                defensive: real("defensive", d.strategy.defensive, 1e-3, 1.0)?,
            },
            refracted_share: real("refractedshare", d.refracted_share, 0.0, 1.0)?,
            max_memory_mib: count("maxmemory", d.max_memory_mib, 1, 1 << 20)?,
            split_threshold: real("splitthreshold", d.split_threshold, 1.0, 1e6)?,
            max_split: count("maxsplit", d.max_split, 1, 16)?,
            cache: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(params: &str) -> Result<GuidedSettings, Error> {
        let text = format!("Integrator \"guided\" {params}\nWorldBegin\n");
        let desc = nimbus_parser::load_str(&text, "test.pbrt").unwrap();
        GuidedSettings::from_entity(&desc.integrator)
    }

    #[test]
    fn defaults_and_overrides() {
        assert_eq!(read("").unwrap(), GuidedSettings::default());
        let s = read(
            r#""integer trainingiterations" 6 "integer photons" 1000 "integer candidates" 12 "float lambda" 0.5
               "float mixprob" 0.3 "float selectivethreshold" 0 "integer maxmemory" 8 "float dtreethreshold" 0.02"#,
        )
        .unwrap();
        assert_eq!((s.training_iterations, s.photons, s.strategy.candidates, s.max_memory_mib), (6, 1000, 12, 8));
        assert_eq!((s.strategy.lambda, s.strategy.mix_prob, s.strategy.selective_threshold), (0.5, 0.3, 0.0));
        assert_eq!(s.dtree_threshold, 0.02);
        let s = read(r#""float splitthreshold" 3 "integer maxsplit" 1"#).unwrap();
        assert_eq!((s.split_threshold, s.max_split), (3.0, 1));
    }

    #[test]
    fn out_of_range_and_wrong_types_name_the_parameter() {
        for (params, name) in [
            (r#""float lambda" 1.5"#, "lambda"),
            (r#""integer candidates" 0"#, "candidates"),
            (r#""float mixprob" -0.1"#, "mixprob"),
            (r#""integer trainingiterations" 0"#, "trainingiterations"),
            (r#""float photons" 10"#, "photons"),
            (r#""float splitthreshold" 0.5"#, "splitthreshold"),
            (r#""integer maxsplit" 17"#, "maxsplit"),
        ] {
            let e = read(params).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("test.pbrt:1"), "{e}");
        }
    }
}
