//! Camera settings with pbrt-v4's parameter names and defaults.

use nimbus_parser::{CameraEntity, Error};

use super::values::checked_float;

/// The kind of projection.
#[derive(Clone, Debug, PartialEq)]
pub enum Projection {
    /// `perspective`: `fov` is the full angle (degrees) spanned by the shorter image axis.
    Perspective {
        /// Field of view in degrees.
        fov: f32,
    },
    /// `orthographic`
    Orthographic,
    /// `spherical`: every direction around the camera, by pbrt-v4's `mapping`.
    Spherical {
        /// `"equalarea"` (pbrt-v4's default: the equal-area octahedral square) rather than
        /// `"equirectangular"`.
        equal_area: bool,
    },
}

/// Everything a camera entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSettings {
    /// Projection.
    pub projection: Projection,
    /// Thin-lens radius (0: pinhole).
    pub lens_radius: f32,
    /// Distance to the plane in focus.
    pub focal_distance: f32,
    /// Screen window \[xmin, xmax, ymin, ymax\] if given.
    pub screen_window: Option<[f32; 4]>,
    /// Aspect ratio overriding the film's, if given.
    pub frame_aspect_ratio: Option<f32>,
    /// Shutter open time.
    pub shutter_open: f32,
    /// Shutter close time.
    pub shutter_close: f32,
}

impl CameraSettings {
    /// Reads a camera entity. Camera types other than perspective and orthographic are
    /// reported by name.
    pub fn from_entity(camera: &CameraEntity) -> Result<CameraSettings, Error> {
        let e = &camera.entity;
        let p = &e.params;
        let shutter_open = p.get_one_float("shutteropen", 0.0)?;
        let shutter_close = p.get_one_float("shutterclose", 1.0)?;
        if shutter_close < shutter_open {
            return Err(Error::new(
                &e.loc,
                format!("shutterclose ({shutter_close}) is before shutteropen ({shutter_open})"),
            ));
        }
        if shutter_close == shutter_open {
            return Err(Error::new(
                &e.loc,
                "the shutter never opens (shutteropen equals shutterclose): the image would be black",
            ));
        }
        let projection = match e.name.as_str() {
            "perspective" => Projection::Perspective {
                fov: checked_float(
                    p,
                    "fov",
                    90.0,
                    |f| f > 0.0 && f < 180.0,
                    "the field of view must be between 0 and 180 degrees",
                )?,
            },
            "orthographic" => Projection::Orthographic,
            "spherical" => Projection::Spherical {
                equal_area: match p.get_one_string("mapping", "equalarea")? {
                    "equalarea" => true,
                    "equirectangular" => false,
                    other => {
                        return Err(Error::new(
                            p.loc("mapping").unwrap_or(&e.loc),
                            format!("spherical camera mapping \"{other}\" is unknown (equalarea or equirectangular)"),
                        ));
                    }
                },
            },
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "camera \"{other}\" is not supported by nimbus (it has perspective, orthographic and spherical)"
                    ),
                ));
            }
        };
        let lens_radius = checked_float(p, "lensradius", 0.0, |r| r >= 0.0, "the lens radius cannot be negative")?;
        let focal_distance =
            checked_float(p, "focaldistance", 1e6, |d| d > 0.0, "the focal distance must be positive")?;
        let screen_window = match p.get_floats("screenwindow")? {
            [] => None,
            [a, b, c, d] => Some([*a, *b, *c, *d]),
            other => {
                return Err(Error::new(
                    p.loc("screenwindow").unwrap_or(&e.loc),
                    format!("\"screenwindow\" takes 4 values (xmin xmax ymin ymax), not {}", other.len()),
                ));
            }
        };
        let frame_aspect_ratio = p.get_opt_float("frameaspectratio")?;
        if let Some(a) = frame_aspect_ratio
            && a <= 0.0
        {
            return Err(Error::new(
                p.loc("frameaspectratio").unwrap_or(&e.loc),
                "\"frameaspectratio\" must be positive",
            ));
        }
        Ok(CameraSettings {
            projection,
            lens_radius,
            focal_distance,
            screen_window,
            frame_aspect_ratio,
            shutter_open,
            shutter_close,
        })
    }
}
