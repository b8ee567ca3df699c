//! Film settings (pbrt-v4's `rgb` and `gbuffer` films and their sensors).

use nimbus_parser::{ColorSpace, Entity, Error};

use crate::params::checked_float;

/// Which film: pbrt-v4's `rgb`, or `gbuffer` (the same image plus the first visible
/// surface's albedo, position, normals, uv, depth derivatives and the samples' variance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilmKind {
    /// `rgb`.
    Rgb,
    /// `gbuffer`, with positions and normals in camera space (`"coordinatesystem"
    /// "camera"`, the default) or world space (`"world"`).
    GBuffer {
        /// World-space output.
        world: bool,
    },
    /// `spectral`: the same image plus radiance in `buckets` equal wavelength bands over
    /// [`lambda_min`, `lambda_max`] nm (wavelengths sampled uniformly there, as pbrt-v4 does).
    Spectral {
        /// Number of bands (`nbuckets`).
        buckets: u32,
        /// Shortest wavelength (`lambdamin`).
        lambda_min: f32,
        /// Longest wavelength (`lambdamax`).
        lambda_max: f32,
    },
}

/// Everything a film entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSettings {
    /// The film type.
    pub kind: FilmKind,
    /// Full image resolution.
    pub resolution: [u32; 2],
    /// Crop window in NDC \[xmin, xmax, ymin, ymax\].
    pub crop_window: Option<[f32; 4]>,
    /// Pixel bounds \[x0, x1, y0, y1\] (overrides the crop window).
    pub pixel_bounds: Option<[i32; 4]>,
    /// Output file name as written in the scene.
    pub filename: String,
    /// Sensor diagonal in mm (used by realistic cameras only).
    pub diagonal: f32,
    /// Clamp on each sample's RGB components.
    pub max_component_value: f32,
    /// Write half floats.
    pub save_fp16: bool,
    /// Sensor ISO: the imaging ratio is exposure time × ISO / 100.
    pub iso: f32,
    /// White balance temperature (0: none for `cie1931`, 6500 K for a camera).
    pub white_balance: f32,
    /// The sensor: `cie1931` or one of pbrt-v4's camera sensors.
    pub sensor: String,
    /// Color space of the output.
    pub color_space: ColorSpace,
}

impl FilmSettings {
    /// Reads a film entity: `rgb`, `gbuffer` or `spectral`.
    pub fn from_entity(e: &Entity) -> Result<FilmSettings, Error> {
        let p = &e.params;
        let kind = match e.name.as_str() {
            "rgb" => FilmKind::Rgb,
            "gbuffer" => match p.get_one_string("coordinatesystem", "camera")? {
                "camera" => FilmKind::GBuffer { world: false },
                "world" => FilmKind::GBuffer { world: true },
                other => {
                    return Err(Error::new(
                        p.loc("coordinatesystem").unwrap_or(&e.loc),
                        format!("unknown coordinate system \"{other}\" for the gbuffer film (\"camera\" or \"world\")"),
                    ));
                }
            },
            "spectral" => {
                let buckets = p.get_one_int("nbuckets", 16)?;
                if buckets <= 0 {
                    return Err(Error::new(p.loc("nbuckets").unwrap_or(&e.loc), "\"nbuckets\" must be positive"));
                }
                let lambda_min = p.get_one_float("lambdamin", 360.0)?;
                let lambda_max = p.get_one_float("lambdamax", 830.0)?;
                if !(360.0..=830.0).contains(&lambda_min)
                    || !(360.0..=830.0).contains(&lambda_max)
                    || lambda_min >= lambda_max
                {
                    return Err(Error::new(
                        p.loc("lambdamin").or(p.loc("lambdamax")).unwrap_or(&e.loc),
                        format!(
                            "the spectral film's range [{lambda_min}, {lambda_max}] nm must be increasing within pbrt-v4's [360, 830]"
                        ),
                    ));
                }
                FilmKind::Spectral { buckets: buckets as u32, lambda_min, lambda_max }
            }
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "film \"{other}\" is not supported by nimbus (it has \"rgb\", \"gbuffer\" and \"spectral\")"
                    ),
                ));
            }
        };
        let x = p.get_one_int("xresolution", 1280)?;
        let y = p.get_one_int("yresolution", 720)?;
        if x <= 0 || y <= 0 {
            return Err(Error::new(&e.loc, format!("film resolution {x}x{y} must be positive")));
        }
        let crop_window = match p.get_floats("cropwindow")? {
            [] => None,
            [a, b, c, d] => {
                if !(0.0..=1.0).contains(a)
                    || !(0.0..=1.0).contains(b)
                    || !(0.0..=1.0).contains(c)
                    || !(0.0..=1.0).contains(d)
                    || a >= b
                    || c >= d
                {
                    return Err(Error::new(
                        p.loc("cropwindow").unwrap_or(&e.loc),
                        "\"cropwindow\" must be xmin < xmax, ymin < ymax within [0, 1]",
                    ));
                }
                Some([*a, *b, *c, *d])
            }
            v => {
                return Err(Error::new(
                    p.loc("cropwindow").unwrap_or(&e.loc),
                    format!("\"cropwindow\" takes 4 values, not {}", v.len()),
                ));
            }
        };
        let pixel_bounds = match p.get_ints("pixelbounds")? {
            [] => None,
            [a, b, c, d] => {
                if a >= b || c >= d {
                    return Err(Error::new(
                        p.loc("pixelbounds").unwrap_or(&e.loc),
                        "\"pixelbounds\" is empty (need x0 < x1 and y0 < y1)",
                    ));
                }
                Some([*a, *b, *c, *d])
            }
            v => {
                return Err(Error::new(
                    p.loc("pixelbounds").unwrap_or(&e.loc),
                    format!("\"pixelbounds\" takes 4 values, not {}", v.len()),
                ));
            }
        };
        let filename = p.get_one_string("filename", "pbrt.exr")?.to_string();
        if kind != FilmKind::Rgb && !filename.to_ascii_lowercase().ends_with(".exr") {
            return Err(Error::new(
                p.loc("filename").unwrap_or(&e.loc),
                format!("{filename}: EXR is the only format the {} film writes", e.name),
            ));
        }
        let diagonal = p.get_one_float("diagonal", 35.0)?;
        let max_component_value =
            checked_float(p, "maxcomponentvalue", f32::INFINITY, |v| v > 0.0, "must be positive")?;
        let save_fp16 = p.get_one_bool("savefp16", true)?;
        let iso = checked_float(p, "iso", 100.0, |v| v > 0.0, "ISO must be positive")?;
        let white_balance = checked_float(p, "whitebalance", 0.0, |v| v >= 0.0, "must not be negative")?;
        let sensor = p.get_one_string("sensor", "cie1931")?.to_string();
        if sensor != "cie1931" && !crate::spectra::camera_sensors().any(|c| c == sensor) {
            return Err(Error::new(
                p.loc("sensor").unwrap_or(&e.loc),
                format!(
                    "unknown sensor \"{sensor}\" (pbrt-v4's sensors: cie1931, {})",
                    crate::spectra::camera_sensors().collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        Ok(FilmSettings {
            kind,
            resolution: [x as u32, y as u32],
            crop_window,
            pixel_bounds,
            filename,
            diagonal,
            max_component_value,
            save_fp16,
            iso,
            white_balance,
            sensor,
            color_space: e.color_space,
        })
    }
}
