//! Camera settings with pbrt-v4's parameter names and defaults.

use std::path::PathBuf;

use nimbus_parser::loc_shown as shown;
use nimbus_parser::{CameraEntity, Error, FileLoc, Warning};

use crate::params::checked_float;

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
    /// `realistic`: a lens system from a lens file.
    Realistic(RealisticSettings),
}

/// A realistic camera's lens, as its entity and lens file give it.
#[derive(Clone, Debug, PartialEq)]
pub struct RealisticSettings {
    /// The lens file's rows, scene side first: curvature radius (mm; 0 for the aperture
    /// stop), thickness (mm), index of refraction (0 for air), aperture diameter (mm).
    pub elements: Vec<[f32; 4]>,
    /// `aperturediameter` (mm): the stop's opening, at most the lens file's.
    pub aperture_diameter: f32,
    /// `focusdistance`: the distance brought into focus.
    pub focus_distance: f32,
    /// `aperture`: the stop's shape, if not round.
    pub aperture: Option<Aperture>,
}

/// A realistic camera's aperture shape (pbrt-v4's built-in ones or an image).
#[derive(Clone, Debug, PartialEq)]
pub enum Aperture {
    /// `"gaussian"`
    Gaussian,
    /// `"square"`
    Square,
    /// `"pentagon"`
    Pentagon,
    /// `"star"`
    Star,
    /// An image file (its mean of R, G and B).
    Image(PathBuf),
}

impl RealisticSettings {
    /// The aperture stop's diameter in the lens file (mm), if the lens has a stop.
    pub fn stop_diameter(&self) -> Option<f32> {
        self.elements.iter().find(|e| e[0] == 0.0).map(|e| e[3])
    }

    /// Reads the realistic camera's parameters and its lens file.
    fn from_entity(camera: &CameraEntity) -> Result<RealisticSettings, Error> {
        let e = &camera.entity;
        let p = &e.params;
        let Some(name) = p.get_opt_string("lensfile")? else {
            return Err(Error::new(&e.loc, "realistic camera: no \"lensfile\" (the lens description) given"));
        };
        let loc = p.loc("lensfile").unwrap_or(&e.loc);
        let elements = read_lens_file(loc, name)?;
        let aperture_diameter =
            checked_float(p, "aperturediameter", 1.0, |d| d > 0.0, "the aperture diameter must be positive")?;
        let focus_distance =
            checked_float(p, "focusdistance", 10.0, |d| d > 0.0, "the focus distance must be positive")?;
        let aperture = match p.get_opt_string("aperture")? {
            None | Some("") => None,
            Some("gaussian") => Some(Aperture::Gaussian),
            Some("square") => Some(Aperture::Square),
            Some("pentagon") => Some(Aperture::Pentagon),
            Some("star") => Some(Aperture::Star),
            Some(file) => {
                let loc = p.loc("aperture").unwrap_or(&e.loc);
                let path = loc.resolve(file);
                if !path.is_file() {
                    return Err(Error::new(
                        loc,
                        format!(
                            "realistic camera: aperture \"{file}\" is not a built-in shape (gaussian, square, \
                             pentagon, star) nor an image (tried {})",
                            shown(&path)
                        ),
                    ));
                }
                Some(Aperture::Image(path))
            }
        };
        Ok(RealisticSettings { elements, aperture_diameter, focus_distance, aperture })
    }
}

/// A lens description file (pbrt-v4's `ReadFloatFile`: numbers separated by white space, `#`
/// to the end of a line a comment), four numbers per element, checked.
fn read_lens_file(loc: &FileLoc, name: &str) -> Result<Vec<[f32; 4]>, Error> {
    let path = loc.resolve(name);
    let text = std::fs::read_to_string(&path).map_err(|err| {
        Error::new(loc, format!("realistic camera: cannot read lens file \"{name}\" (tried {}): {err}", shown(&path)))
    })?;
    let mut values = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        for token in line.split_whitespace() {
            let v: f32 = token.parse().map_err(|_| {
                Error::new(loc, format!("lens file {}:{}: \"{token}\" is not a number", shown(&path), i + 1))
            })?;
            if !v.is_finite() {
                return Err(Error::new(
                    loc,
                    format!("lens file {}:{}: \"{token}\" is not finite", shown(&path), i + 1),
                ));
            }
            values.push(v);
        }
    }
    if values.is_empty() || values.len() % 4 != 0 {
        return Err(Error::new(
            loc,
            format!(
                "lens file {}: {} numbers; a lens is rows of four (curvature radius, thickness, index of \
                 refraction, aperture diameter)",
                shown(&path),
                values.len()
            ),
        ));
    }
    let elements: Vec<[f32; 4]> = values.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    for (i, e) in elements.iter().enumerate() {
        if e[1] < 0.0 || e[2] < 0.0 || e[3] <= 0.0 {
            return Err(Error::new(
                loc,
                format!(
                    "lens file {}: element {} has a negative thickness or index of refraction, or no aperture",
                    shown(&path),
                    i + 1
                ),
            ));
        }
    }
    Ok(elements)
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
    /// A pinhole perspective camera of `fov` degrees with pbrt-v4's other defaults (the screen
    /// window from the film, the shutter open over [0, 1]).
    pub fn perspective(fov: f32) -> CameraSettings {
        CameraSettings {
            projection: Projection::Perspective { fov },
            lens_radius: 0.0,
            focal_distance: 1e6,
            screen_window: None,
            frame_aspect_ratio: None,
            shutter_open: 0.0,
            shutter_close: 1.0,
        }
    }

    /// pbrt-v4's warning for a realistic camera whose `aperturediameter` is wider than its
    /// lens's stop (which then opens only that far).
    pub fn aperture_warning(&self, camera: &CameraEntity) -> Option<Warning> {
        let Projection::Realistic(r) = &self.projection else { return None };
        let stop = r.stop_diameter()?;
        (r.aperture_diameter > stop).then(|| {
            let e = &camera.entity;
            Warning::new(
                e.params.loc("aperturediameter").unwrap_or(&e.loc),
                format!(
                    "realistic camera: aperture diameter {} mm is greater than the lens's largest, {stop} mm; clamping it",
                    r.aperture_diameter
                ),
            )
        })
    }

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
            "realistic" => Projection::Realistic(RealisticSettings::from_entity(camera)?),
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "camera \"{other}\" is not supported by nimbus (it has perspective, orthographic, spherical \
                         and realistic)"
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
