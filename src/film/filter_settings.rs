//! Pixel filter settings with pbrt-v4's defaults.

use nimbus_parser::{Entity, Error};

use crate::params::checked_float;

/// A pixel reconstruction filter.
#[derive(Clone, Debug, PartialEq)]
pub enum FilterSettings {
    /// `box` (default radius 0.5)
    Box {
        /// Radius in pixels.
        radius: [f32; 2],
    },
    /// `gaussian` (default radius 1.5, sigma 0.5)
    Gaussian {
        /// Radius in pixels.
        radius: [f32; 2],
        /// Standard deviation in pixels.
        sigma: f32,
    },
    /// `triangle` (default radius 2)
    Triangle {
        /// Radius in pixels.
        radius: [f32; 2],
    },
    /// `mitchell` (default radius 2, B = C = 1/3)
    Mitchell {
        /// Radius in pixels.
        radius: [f32; 2],
        /// B parameter.
        b: f32,
        /// C parameter.
        c: f32,
    },
    /// `sinc` (Lanczos-windowed; default radius 4, tau 3)
    LanczosSinc {
        /// Radius in pixels.
        radius: [f32; 2],
        /// Number of sinc cycles before the window cuts off.
        tau: f32,
    },
}

impl FilterSettings {
    /// Reads a filter entity.
    pub fn from_entity(e: &Entity) -> Result<FilterSettings, Error> {
        let p = &e.params;
        let radius = |default: f32| -> Result<[f32; 2], Error> {
            Ok([
                checked_float(p, "xradius", default, |r| r > 0.0, "filter radius must be positive")?,
                checked_float(p, "yradius", default, |r| r > 0.0, "filter radius must be positive")?,
            ])
        };
        Ok(match e.name.as_str() {
            "box" => FilterSettings::Box { radius: radius(0.5)? },
            "gaussian" => FilterSettings::Gaussian {
                radius: radius(1.5)?,
                sigma: checked_float(p, "sigma", 0.5, |s| s > 0.0, "sigma must be positive")?,
            },
            "triangle" => FilterSettings::Triangle { radius: radius(2.0)? },
            "mitchell" => FilterSettings::Mitchell {
                radius: radius(2.0)?,
                b: p.get_one_float("B", 1.0 / 3.0)?,
                c: p.get_one_float("C", 1.0 / 3.0)?,
            },
            "sinc" => FilterSettings::LanczosSinc { radius: radius(4.0)?, tau: p.get_one_float("tau", 3.0)? },
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "pixel filter \"{other}\" is not supported by nimbus (it has box, gaussian, triangle, mitchell and sinc)"
                    ),
                ));
            }
        })
    }
}
