//! Sampler settings with pbrt-v4's defaults.

use nimbus_parser::{Entity, Error, Warning};

use super::values::checked_int;

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
}

impl SamplerSettings {
    /// Reads a sampler entity. pbrt-v4 samplers nimbus lacks (halton, paddedsobol, pmj02bn)
    /// are replaced by zsobol with a warning: the image converges to the same result.
    pub fn from_entity(
        e: &Entity,
        option_seed: Option<i32>,
        warnings: &mut Vec<Warning>,
    ) -> Result<SamplerSettings, Error> {
        let p = &e.params;
        let seed = p.get_one_int("seed", option_seed.unwrap_or(0))?;
        let positive = |v: i32| v > 0;
        let (kind, pixel_samples) = match e.name.as_str() {
            "stratified" => {
                let x = checked_int(p, "xsamples", 4, positive, "must be positive")? as u32;
                let y = checked_int(p, "ysamples", 4, positive, "must be positive")? as u32;
                let jitter = p.get_one_bool("jitter", true)?;
                (SamplerKind::Stratified { x, y, jitter }, x * y)
            }
            name => {
                let spp = checked_int(p, "pixelsamples", 16, positive, "must be positive")? as u32;
                let kind = match name {
                    "independent" => SamplerKind::Independent,
                    "sobol" => SamplerKind::Sobol,
                    "zsobol" => SamplerKind::ZSobol,
                    "halton" | "paddedsobol" | "pmj02bn" => {
                        // These read "randomization"; accept it so it is not reported unused.
                        p.get_opt_string("randomization")?;
                        warnings.push(Warning::new(&e.loc, format!("sampler \"{name}\" is not in nimbus; using \"zsobol\" (same expected image)")));
                        SamplerKind::ZSobol
                    }
                    other => {
                        return Err(Error::new(
                            &e.loc,
                            format!(
                                "sampler \"{other}\" unknown (nimbus has independent, stratified, sobol and zsobol)"
                            ),
                        ));
                    }
                };
                if matches!(kind, SamplerKind::Sobol | SamplerKind::ZSobol) {
                    let r = p.get_one_string("randomization", "owen")?;
                    if !matches!(r, "owen" | "fastowen") {
                        return Err(Error::new(
                            p.loc("randomization").unwrap_or(&e.loc),
                            format!(
                                "randomization \"{r}\" is not supported by nimbus (it uses Owen scrambling)"
                            ),
                        ));
                    }
                }
                (kind, spp)
            }
        };
        Ok(SamplerSettings {
            kind,
            pixel_samples,
            seed,
        })
    }
}
