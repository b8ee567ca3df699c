//! Which representation of light a scene is rendered with. RGB transport gives exactly the
//! answer of sampled spectra when every quantity that scatters or absorbs light is the same
//! at all wavelengths: each emitted spectrum then reaches the film multiplied only by gray
//! factors, and the film is linear, so converting each emitter's spectrum to film RGB once
//! is exact. Anything chromatic along the way (a colored albedo, a chromatic medium, a metal,
//! dispersive glass) needs pbrt-v4's sampled spectra to match it.

use std::fmt;
use std::str::FromStr;

/// The user's choice (`--spectral`, `Option "string spectral"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpectralMode {
    /// RGB when it gives the same answer, sampled spectra otherwise.
    #[default]
    Auto,
    /// Always sampled spectra.
    On,
    /// Always RGB (an approximation where the scene is chromatic).
    Off,
}

impl FromStr for SpectralMode {
    type Err = String;

    fn from_str(s: &str) -> Result<SpectralMode, String> {
        match s {
            "auto" => Ok(SpectralMode::Auto),
            "on" => Ok(SpectralMode::On),
            "off" => Ok(SpectralMode::Off),
            other => Err(format!("unknown spectral mode \"{other}\" (auto, on or off)")),
        }
    }
}

impl fmt::Display for SpectralMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SpectralMode::Auto => "auto",
            SpectralMode::On => "on",
            SpectralMode::Off => "off",
        })
    }
}

/// How light is carried along paths.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Linear RGB in the film's color space.
    Rgb,
    /// pbrt-v4's sampled spectra, four wavelengths per path.
    Spectral,
}

impl Transport {
    /// The name used in `--stats` and image metadata.
    pub fn name(self) -> &'static str {
        match self {
            Transport::Rgb => "rgb",
            Transport::Spectral => "spectral",
        }
    }
}

/// The transport a scene gets and why.
#[derive(Clone, Debug, PartialEq)]
pub struct TransportChoice {
    /// The representation.
    pub transport: Transport,
    /// Why: the mode, and for `auto` the first chromatic quantity found (or that none was).
    pub reason: String,
}

impl TransportChoice {
    /// The choice for `mode` when `chromatic` names the first quantity of the scene that
    /// varies with wavelength (with its location), if any.
    pub fn new(mode: SpectralMode, chromatic: Option<&str>) -> TransportChoice {
        match (mode, chromatic) {
            (SpectralMode::On, _) => TransportChoice { transport: Transport::Spectral, reason: "spectral on".into() },
            (SpectralMode::Off, None) => TransportChoice { transport: Transport::Rgb, reason: "spectral off".into() },
            (SpectralMode::Off, Some(c)) => {
                TransportChoice { transport: Transport::Rgb, reason: format!("spectral off (approximate: {c})") }
            }
            (SpectralMode::Auto, None) => TransportChoice {
                transport: Transport::Rgb,
                reason: "auto: every scattering and absorbing quantity is gray".into(),
            },
            (SpectralMode::Auto, Some(c)) => {
                TransportChoice { transport: Transport::Spectral, reason: format!("auto: {c}") }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_parse_and_choose() {
        assert_eq!("on".parse::<SpectralMode>(), Ok(SpectralMode::On));
        assert!("yes".parse::<SpectralMode>().unwrap_err().contains("auto, on or off"));
        assert_eq!(TransportChoice::new(SpectralMode::Auto, None).transport, Transport::Rgb);
        let c = TransportChoice::new(SpectralMode::Auto, Some("a.pbrt:3:1: material reflectance"));
        assert_eq!(c.transport, Transport::Spectral);
        assert!(c.reason.contains("a.pbrt:3:1"));
        assert_eq!(TransportChoice::new(SpectralMode::Off, Some("x")).transport, Transport::Rgb);
        assert_eq!(TransportChoice::new(SpectralMode::On, None).transport, Transport::Spectral);
    }
}
