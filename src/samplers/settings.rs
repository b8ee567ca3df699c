//! Sampler settings with pbrt-v4's defaults.

use nimbus_parser::{Entity, Error, Warning};

use crate::params::checked_int;

/// Which sample generator to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerKind {
    /// `independent`: uniform random samples.
    Independent,
    /// `stratified`: jittered strata (`xsamples` × `ysamples` per pixel).
    Stratified {
        /// Strata along x.
        x: u32,
        /// Strata along y.
        y: u32,
        /// Jitter within strata.
        jitter: bool,
    },
    /// `sobol`: Owen-scrambled Sobol' points per pixel.
    Sobol,
    /// `zsobol`: Sobol' points in Morton order across pixels (pbrt-v4's default).
    ZSobol,
    /// `halton`: the Halton sequence over the image.
    Halton(crate::samplers::HaltonRandomization),
    /// `paddedsobol`: independently scrambled 2D Sobol' sets per dimension pair.
    PaddedSobol,
    /// `pmj02bn`: progressive multi-jittered (0,2) blue-noise points.
    Pmj02bn,
}

/// How the Sobol' samplers randomize their points (pbrt-v4's `randomization` parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Randomization {
    /// `owen`: exact nested uniform (Owen) scrambling, one hash per bit.
    Owen,
    /// `fastowen`: Burley's hash-based approximation of Owen scrambling (pbrt-v4's default).
    FastOwen,
}

/// Everything a sampler entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerSettings {
    /// The generator.
    pub kind: SamplerKind,
    /// Samples per pixel.
    pub pixel_samples: u32,
    /// Seed (the scene's `Option "seed"` or the sampler's `seed`).
    pub seed: i32,
    /// Scrambling of the Sobol' samplers (ignored by the others).
    pub randomization: Randomization,
}

impl SamplerSettings {
    /// Reads a sampler entity, with pbrt-v4's defaults and warnings.
    pub fn from_entity(
        e: &Entity,
        option_seed: Option<i32>,
        warnings: &mut Vec<Warning>,
    ) -> Result<SamplerSettings, Error> {
        let p = &e.params;
        let seed = p.get_one_int("seed", option_seed.unwrap_or(0))?;
        let positive = |v: i32| v > 0;
        let mut randomization = Randomization::FastOwen;
        let (kind, pixel_samples) = match e.name.as_str() {
            "stratified" => {
                let x = checked_int(p, "xsamples", 4, positive, "must be positive")? as u32;
                let y = checked_int(p, "ysamples", 4, positive, "must be positive")? as u32;
                let jitter = p.get_one_bool("jitter", true)?;
                (SamplerKind::Stratified { x, y, jitter }, x * y)
            }
            name => {
                // pbrt-v4's independent sampler defaults to 4 samples, all others to 16.
                let default_spp = if name == "independent" { 4 } else { 16 };
                let spp = checked_int(p, "pixelsamples", default_spp, positive, "must be positive")? as u32;
                let kind = match name {
                    "independent" => SamplerKind::Independent,
                    "sobol" => SamplerKind::Sobol,
                    "zsobol" => SamplerKind::ZSobol,
                    "halton" => {
                        let r = p.get_one_string("randomization", "permutedigits")?;
                        SamplerKind::Halton(match r {
                            "none" => crate::samplers::HaltonRandomization::None,
                            "permutedigits" => crate::samplers::HaltonRandomization::PermuteDigits,
                            "owen" => crate::samplers::HaltonRandomization::Owen,
                            _ => {
                                return Err(Error::new(
                                    p.loc("randomization").unwrap_or(&e.loc),
                                    format!(
                                        "randomization \"{r}\" is not one the Halton sampler has (none, permutedigits, owen)"
                                    ),
                                ));
                            }
                        })
                    }
                    "paddedsobol" => SamplerKind::PaddedSobol,
                    "pmj02bn" => SamplerKind::Pmj02bn,
                    other => {
                        return Err(Error::new(
                            &e.loc,
                            format!(
                                "sampler \"{other}\" unknown (nimbus has independent, stratified, sobol, zsobol, halton, paddedsobol and pmj02bn)"
                            ),
                        ));
                    }
                };
                // Only the Sobol' samplers read it (Halton's is read above).
                if matches!(name, "sobol" | "zsobol" | "paddedsobol") {
                    let r = p.get_one_string("randomization", "fastowen")?;
                    randomization = match r {
                        "owen" => Randomization::Owen,
                        "fastowen" => Randomization::FastOwen,
                        _ => {
                            return Err(Error::new(
                                p.loc("randomization").unwrap_or(&e.loc),
                                format!("randomization \"{r}\" is not supported by nimbus (it has owen and fastowen)"),
                            ));
                        }
                    };
                }
                if kind == SamplerKind::Pmj02bn {
                    check_pmj02bn_samples(spp, p.loc("pixelsamples").unwrap_or(&e.loc))?;
                    if !spp.is_power_of_two() || spp.trailing_zeros() % 2 == 1 {
                        warnings.push(Warning::new(
                            p.loc("pixelsamples").unwrap_or(&e.loc),
                            "pmj02bn results are best with power-of-4 samples per pixel (1, 4, 16, 64, ...), as pbrt-v4 warns",
                        ));
                    }
                }
                if kind == SamplerKind::ZSobol && !spp.is_power_of_two() {
                    let used = 1u32 << spp.ilog2();
                    warnings.push(Warning::new(
                        p.loc("pixelsamples").unwrap_or(&e.loc),
                        format!(
                            "zsobol takes a power-of-two sample count: {spp} samples per pixel become {used}, as in pbrt-v4"
                        ),
                    ));
                }
                (kind, spp)
            }
        };
        Ok(SamplerSettings { kind, pixel_samples, seed, randomization })
    }
}

/// pmj02bn's points come from sequences of 65,536: more samples per pixel are an error, as in
/// pbrt-v4 (`loc`: where the count was given).
pub fn check_pmj02bn_samples(spp: u32, loc: &nimbus_parser::FileLoc) -> Result<(), Error> {
    let max = crate::samplers::PMJ02BN_MAX_SAMPLES;
    if spp > max {
        return Err(Error::new(loc, format!("pmj02bn takes at most {max} samples per pixel ({spp} asked for)")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(directive: &str) -> Result<SamplerSettings, Error> {
        let scene = nimbus_parser::load_str(&format!("{directive}\nWorldBegin\n"), "t.pbrt").expect("scene parses");
        SamplerSettings::from_entity(&scene.sampler, scene.options.seed, &mut Vec::new())
    }

    #[test]
    fn sampler_defaults_follow_pbrt() {
        let z = settings("").unwrap();
        assert_eq!(z.kind, SamplerKind::ZSobol);
        assert_eq!((z.pixel_samples, z.randomization), (16, Randomization::FastOwen));
        assert_eq!(settings("Sampler \"independent\"").unwrap().pixel_samples, 4);
        let s = settings("Sampler \"sobol\" \"string randomization\" \"owen\"").unwrap();
        assert_eq!((s.kind, s.randomization), (SamplerKind::Sobol, Randomization::Owen));
        assert!(settings("Sampler \"zsobol\" \"string randomization\" \"none\"").is_err());
        // Halton takes its own randomizations (permutedigits by default) and refuses fastowen,
        // as pbrt-v4 does; replaced samplers accept theirs.
        let h = settings("Sampler \"halton\"").unwrap();
        assert_eq!(h.kind, SamplerKind::Halton(crate::samplers::HaltonRandomization::PermuteDigits));
        let h = settings("Sampler \"halton\" \"string randomization\" \"owen\"").unwrap();
        assert_eq!(h.kind, SamplerKind::Halton(crate::samplers::HaltonRandomization::Owen));
        assert!(settings("Sampler \"halton\" \"string randomization\" \"fastowen\"").is_err());
        let p = settings("Sampler \"pmj02bn\"").unwrap();
        assert_eq!((p.kind, p.pixel_samples), (SamplerKind::Pmj02bn, 16));
        assert!(settings("Sampler \"pmj02bn\" \"integer pixelsamples\" 65537").is_err());
        let p = settings("Sampler \"paddedsobol\" \"string randomization\" \"owen\"").unwrap();
        assert_eq!((p.kind, p.randomization), (SamplerKind::PaddedSobol, Randomization::Owen));
    }

    #[test]
    fn zsobol_warns_that_it_rounds_sample_counts_down() {
        let scene =
            nimbus_parser::load_str("Sampler \"zsobol\" \"integer pixelsamples\" 100\nWorldBegin\n", "t.pbrt").unwrap();
        let mut warnings = Vec::new();
        SamplerSettings::from_entity(&scene.sampler, None, &mut warnings).unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(format!("{:?}", warnings[0]).contains("become 64"));
    }
}
