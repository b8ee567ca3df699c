//! Medium settings with pbrt-v4's parameter names and defaults, plus nimbus's `vdb`
//! extension (OpenVDB files read directly). Grid arrays are borrowed from the description.

use std::path::PathBuf;

use nimbus_parser::loc_shown as shown;
use nimbus_parser::{Error, MediumEntity, ParameterDictionary};

use crate::spectra::spec::{SpectrumSpec, spectrum};

/// Measured scattering coefficients pbrt-v4 knows by name (`"string preset"`), in mm⁻¹:
/// (name, σ′s, σa). From Jensen et al. 2001, "A Practical Model for Subsurface Light
/// Transport", and Narasimhan et al. 2006, "Acquiring Scattering Properties of Participating
/// Media by Dilution".
pub const MEDIUM_PRESETS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("Apple", [2.29, 2.39, 1.97], [0.0030, 0.0034, 0.046]),
    ("Chicken1", [0.15, 0.21, 0.38], [0.015, 0.077, 0.19]),
    ("Chicken2", [0.19, 0.25, 0.32], [0.018, 0.088, 0.20]),
    ("Cream", [7.38, 5.47, 3.15], [0.0002, 0.0028, 0.0163]),
    ("Ketchup", [0.18, 0.07, 0.03], [0.061, 0.97, 1.45]),
    ("Marble", [2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
    ("Potato", [0.68, 0.70, 0.55], [0.0024, 0.0090, 0.12]),
    ("Skimmilk", [0.70, 1.22, 1.90], [0.0014, 0.0025, 0.0142]),
    ("Skin1", [0.74, 0.88, 1.01], [0.032, 0.17, 0.48]),
    ("Skin2", [1.09, 1.59, 1.79], [0.013, 0.070, 0.145]),
    ("Spectralon", [11.6, 20.4, 14.9], [0.00, 0.00, 0.00]),
    ("Wholemilk", [2.55, 3.21, 3.77], [0.0011, 0.0024, 0.014]),
    ("Lowfat Milk", [0.89187, 1.5136, 2.532], [0.002875, 0.00575, 0.0115]),
    ("Reduced Milk", [2.4858, 3.1669, 4.5214], [0.0025556, 0.0051111, 0.012778]),
    ("Regular Milk", [4.5513, 5.8294, 7.136], [0.0015333, 0.0046, 0.019933]),
    ("Espresso", [0.72378, 0.84557, 1.0247], [4.7984, 6.5751, 8.8493]),
    ("Mint Mocha Coffee", [0.31602, 0.38538, 0.48131], [3.772, 5.8228, 7.82]),
    ("Lowfat Soy Milk", [0.30576, 0.34233, 0.61664], [0.0014375, 0.0071875, 0.035937]),
    ("Regular Soy Milk", [0.59223, 0.73866, 1.4693], [0.0019167, 0.0095833, 0.065167]),
    ("Lowfat Chocolate Milk", [0.64925, 0.83916, 1.1057], [0.0115, 0.0368, 0.1564]),
    ("Regular Chocolate Milk", [1.4585, 2.1289, 2.9527], [0.010063, 0.043125, 0.14375]),
    ("Coke", [8.9053e-05, 8.372e-05, 0.0], [0.10014, 0.16503, 0.2468]),
    ("Pepsi", [6.1697e-05, 4.2564e-05, 0.0], [0.091641, 0.14158, 0.20729]),
    ("Sprite", [6.0306e-06, 6.4139e-06, 6.5504e-06], [0.001886, 0.0018308, 0.0020025]),
    ("Gatorade", [0.0024574, 0.003007, 0.0037325], [0.024794, 0.019289, 0.008878]),
    ("Chardonnay", [1.7982e-05, 1.3758e-05, 1.2023e-05], [0.010782, 0.011855, 0.023997]),
    ("White Zinfandel", [1.7501e-05, 1.9069e-05, 1.288e-05], [0.012072, 0.016184, 0.019843]),
    ("Merlot", [2.1129e-05, 0.0, 0.0], [0.11632, 0.25191, 0.29434]),
    ("Budweiser Beer", [2.4356e-05, 2.4079e-05, 1.0564e-05], [0.011492, 0.024911, 0.057786]),
    ("Coors Light Beer", [5.0922e-05, 4.301e-05, 0.0], [0.006164, 0.013984, 0.034983]),
    ("Clorox", [0.0024035, 0.0031373, 0.003991], [0.0033542, 0.014892, 0.026297]),
    ("Apple Juice", [0.00013612, 0.00015836, 0.000227], [0.012957, 0.023741, 0.052184]),
    ("Cranberry Juice", [0.00010402, 0.00011646, 7.8139e-05], [0.039437, 0.094223, 0.12426]),
    ("Grape Juice", [5.382e-05, 0.0, 0.0], [0.10404, 0.23958, 0.29325]),
    ("Ruby Grapefruit Juice", [0.011002, 0.010927, 0.011036], [0.085867, 0.18314, 0.25262]),
    ("White Grapefruit Juice", [0.22826, 0.23998, 0.32748], [0.0138, 0.018831, 0.056781]),
    ("Shampoo", [0.0007176, 0.0008303, 0.0009016], [0.014107, 0.045693, 0.061717]),
    ("Strawberry Shampoo", [0.00015671, 0.00015947, 1.518e-05], [0.01449, 0.05796, 0.075823]),
    ("Head & Shoulders Shampoo", [0.023805, 0.028804, 0.034306], [0.084621, 0.15688, 0.20365]),
    ("Lemon Tea Powder", [0.040224, 0.045264, 0.051081], [2.4288, 4.5757, 7.2127]),
    ("Orange Powder", [0.00015617, 0.00017482, 0.0001762], [0.001449, 0.003441, 0.007863]),
    ("Pink Lemonade Powder", [0.00012103, 0.00013073, 0.00012528], [0.001165, 0.002366, 0.003195]),
    ("Cappuccino Powder", [1.8436, 2.5851, 2.1662], [35.844, 49.547, 61.084]),
    ("Salt Powder", [0.027333, 0.032451, 0.031979], [0.28415, 0.3257, 0.34148]),
    ("Sugar Powder", [0.00022272, 0.00025513, 0.000271], [0.012638, 0.031051, 0.050124]),
    ("Suisse Mocha Powder", [2.7979, 3.5452, 4.3365], [17.502, 27.004, 35.433]),
    ("Pacific Ocean Surface Water", [0.0001764, 0.00032095, 0.00019617], [0.031845, 0.031324, 0.030147]),
];

/// Emission from a temperature grid (blackbody), pbrt-v4's `temperature` parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Temperature<'a> {
    /// Per-voxel temperatures (before offset and scale), for grids given inline.
    pub values: Option<&'a [f32]>,
    /// Subtracted from each temperature (`temperatureoffset`, formerly `temperaturecutoff`).
    pub offset: f32,
    /// Multiplies each temperature after the offset (`temperaturescale`).
    pub scale: f32,
}

/// What a medium is.
#[derive(Clone, Debug, PartialEq)]
pub enum MediumKind<'a> {
    /// `homogeneous`
    Homogeneous,
    /// `uniformgrid`: a density grid over the box p0–p1 (medium space).
    UniformGrid {
        /// Grid resolution.
        n: [u32; 3],
        /// Box corners.
        bounds: [[f32; 3]; 2],
        /// nx·ny·nz densities, x fastest.
        density: &'a [f32],
        /// Blackbody emission from a temperature grid, if given.
        temperature: Option<Temperature<'a>>,
        /// Per-voxel emission scale, if given as an array.
        le_scale_grid: Option<&'a [f32]>,
    },
    /// `rgbgrid`: per-voxel RGB coefficients.
    RgbGrid {
        /// Grid resolution.
        n: [u32; 3],
        /// Box corners.
        bounds: [[f32; 3]; 2],
        /// Per-voxel σa (RGB), if given.
        sigma_a: Option<&'a [[f32; 3]]>,
        /// Per-voxel σs (RGB), if given.
        sigma_s: Option<&'a [[f32; 3]]>,
        /// Per-voxel emitted radiance (RGB), if given.
        le: Option<&'a [[f32; 3]]>,
    },
    /// `cloud`: pbrt-v4's procedural cloud.
    Cloud {
        /// Box corners.
        bounds: [[f32; 3]; 2],
        /// Overall density.
        density: f32,
        /// Strength of the wisps.
        wispiness: f32,
        /// Noise frequency.
        frequency: f32,
    },
    /// `nanovdb` (pbrt-v4) or `vdb` (nimbus extension: OpenVDB).
    Vdb {
        /// True for an OpenVDB `.vdb` file, false for NanoVDB `.nvdb`.
        openvdb: bool,
        /// The file.
        filename: PathBuf,
        /// Name of the density grid.
        grid_name: String,
        /// Name of the temperature grid (emission), used when the file has it.
        temperature_name: String,
        /// Temperature offset and scale.
        temperature: Temperature<'a>,
    },
}

/// Everything a medium entity specifies.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumSettings<'a> {
    /// The medium.
    pub kind: MediumKind<'a>,
    /// Absorption coefficient (multiplied by density and `scale`).
    pub sigma_a: SpectrumSpec,
    /// Scattering coefficient (multiplied by density and `scale`).
    pub sigma_s: SpectrumSpec,
    /// Multiplier on σa and σs.
    pub scale: f32,
    /// Henyey-Greenstein asymmetry.
    pub g: f32,
    /// Emitted radiance, if the medium emits.
    pub le: Option<SpectrumSpec>,
    /// Multiplier on the emission.
    pub le_scale: f32,
}

fn resolution(m: &MediumEntity) -> Result<[u32; 3], Error> {
    let p = &m.entity.params;
    let mut n = [0u32; 3];
    for (i, name) in ["nx", "ny", "nz"].into_iter().enumerate() {
        let v = p.get_one_int(name, 1)?;
        if v <= 0 {
            return Err(Error::new(p.loc(name).unwrap_or(&m.entity.loc), format!("\"{name}\" must be positive")));
        }
        n[i] = v as u32;
    }
    Ok(n)
}

fn bounds(p: &ParameterDictionary, loc: &nimbus_parser::FileLoc) -> Result<[[f32; 3]; 2], Error> {
    let p0 = p.get_one_point3("p0", [0.0; 3])?;
    let p1 = p.get_one_point3("p1", [1.0; 3])?;
    if (0..3).any(|i| p1[i] <= p0[i]) {
        return Err(Error::new(loc, format!("medium bounds p0 {p0:?} .. p1 {p1:?} are empty")));
    }
    Ok([p0, p1])
}

fn grid_len<'a, T>(m: &MediumEntity, name: &str, v: &'a [T], n: [u32; 3]) -> Result<Option<&'a [T]>, Error> {
    if v.is_empty() {
        return Ok(None);
    }
    let expected = n[0] as usize * n[1] as usize * n[2] as usize;
    if v.len() != expected {
        let loc = m.entity.params.loc(name).unwrap_or(&m.entity.loc);
        return Err(Error::new(
            loc,
            format!("\"{name}\" has {} values; nx*ny*nz = {}x{}x{} = {expected}", v.len(), n[0], n[1], n[2]),
        ));
    }
    Ok(Some(v))
}

fn temperature_params(p: &ParameterDictionary) -> Result<(f32, f32), Error> {
    // "temperaturecutoff" is the older name of "temperatureoffset".
    let offset = match p.get_opt_float("temperatureoffset")? {
        Some(v) => v,
        None => p.get_one_float("temperaturecutoff", 0.0)?,
    };
    Ok((offset, p.get_one_float("temperaturescale", 1.0)?))
}

impl<'a> MediumSettings<'a> {
    /// Reads a medium entity. Medium types nimbus lacks are reported by name.
    pub fn from_entity(m: &'a MediumEntity) -> Result<MediumSettings<'a>, Error> {
        let e = &m.entity;
        let p = &e.params;
        let mut sigma_a = None;
        let mut sigma_s = None;
        if e.name == "homogeneous"
            && let Some(preset) = p.get_opt_string("preset")?
        {
            let Some((_, ss, sa)) = MEDIUM_PRESETS.iter().find(|(n, _, _)| *n == preset) else {
                return Err(Error::new(
                    p.loc("preset").unwrap_or(&e.loc),
                    format!("unknown medium preset \"{preset}\""),
                ));
            };
            sigma_a = Some(SpectrumSpec::Rgb(*sa));
            sigma_s = Some(SpectrumSpec::Rgb(*ss));
        }
        // rgbgrid gives σa and σs per voxel (read below); the others take one spectrum each,
        // which multiplies the density.
        let per_voxel = e.name == "rgbgrid";
        let sigma_a = match sigma_a {
            Some(s) => s,
            None if per_voxel => SpectrumSpec::Rgb([1.0; 3]),
            None => spectrum(p, "sigma_a")?.unwrap_or(SpectrumSpec::Rgb([1.0; 3])),
        };
        let sigma_s = match sigma_s {
            Some(s) => s,
            None if per_voxel => SpectrumSpec::Rgb([1.0; 3]),
            None => spectrum(p, "sigma_s")?.unwrap_or(SpectrumSpec::Rgb([1.0; 3])),
        };
        let scale = p.get_one_float("scale", 1.0)?;
        let g = p.get_one_float("g", 0.0)?;
        if !(-1.0 < g && g < 1.0) {
            return Err(Error::new(
                p.loc("g").unwrap_or(&e.loc),
                format!("Henyey-Greenstein g = {g} must be in (-1, 1)"),
            ));
        }
        // pbrt-v4 spells the emission scale "Lescale"; older scenes wrote "LeScale".
        let le_scale_name =
            if p.peek("Lescale").is_none() && p.peek("LeScale").is_some() { "LeScale" } else { "Lescale" };
        let kind = match e.name.as_str() {
            "homogeneous" => MediumKind::Homogeneous,
            "uniformgrid" => {
                let n = resolution(m)?;
                let Some(density) = grid_len(m, "density", p.get_floats("density")?, n)? else {
                    return Err(Error::new(&e.loc, "uniformgrid: no \"density\" values"));
                };
                let temperature = match grid_len(m, "temperature", p.get_floats("temperature")?, n)? {
                    Some(values) => {
                        let (offset, scale) = temperature_params(p)?;
                        Some(Temperature { values: Some(values), offset, scale })
                    }
                    None => None,
                };
                let le_scale_values = p.get_floats(le_scale_name)?;
                let le_scale_grid =
                    if le_scale_values.len() > 1 { grid_len(m, le_scale_name, le_scale_values, n)? } else { None };
                MediumKind::UniformGrid { n, bounds: bounds(p, &e.loc)?, density, temperature, le_scale_grid }
            }
            "rgbgrid" => {
                let n = resolution(m)?;
                let sigma_a = grid_len(m, "sigma_a", p.get_rgbs("sigma_a")?, n)?;
                let sigma_s = grid_len(m, "sigma_s", p.get_rgbs("sigma_s")?, n)?;
                let le = grid_len(m, "Le", p.get_rgbs("Le")?, n)?;
                if sigma_a.is_none() && sigma_s.is_none() {
                    return Err(Error::new(&e.loc, "rgbgrid: give \"rgb sigma_a\" and/or \"rgb sigma_s\" grids"));
                }
                MediumKind::RgbGrid { n, bounds: bounds(p, &e.loc)?, sigma_a, sigma_s, le }
            }
            "cloud" => MediumKind::Cloud {
                bounds: bounds(p, &e.loc)?,
                density: p.get_one_float("density", 1.0)?,
                wispiness: p.get_one_float("wispiness", 1.0)?,
                frequency: p.get_one_float("frequency", 5.0)?,
            },
            "nanovdb" | "vdb" => {
                let Some(name) = p.get_opt_string("filename")? else {
                    return Err(Error::new(&e.loc, format!("{}: missing \"string filename\"", e.name)));
                };
                let loc = p.loc("filename").unwrap_or(&e.loc);
                let filename = loc.resolve(name);
                if !filename.is_file() {
                    return Err(Error::new(
                        loc,
                        format!("{}: cannot find \"{name}\" (tried {})", e.name, shown(&filename)),
                    ));
                }
                let (offset, tscale) = temperature_params(p)?;
                MediumKind::Vdb {
                    openvdb: e.name == "vdb",
                    filename,
                    grid_name: p.get_one_string("gridname", "density")?.to_string(),
                    temperature_name: p.get_one_string("temperaturename", "temperature")?.to_string(),
                    temperature: Temperature { values: None, offset, scale: tscale },
                }
            }
            other => {
                return Err(Error::new(
                    &e.loc,
                    format!(
                        "medium \"{other}\" is not supported by nimbus (it has homogeneous, uniformgrid, rgbgrid, cloud, nanovdb and vdb)"
                    ),
                ));
            }
        };
        let le = match &kind {
            // rgbgrid's Le is a per-voxel grid, read above; pbrt-v4's cloud and NanoVDB media
            // take no Le (NanoVDB emits from a temperature grid).
            MediumKind::RgbGrid { .. } | MediumKind::Cloud { .. } | MediumKind::Vdb { .. } => None,
            _ => spectrum(p, "Le")?,
        };
        if le.is_some() && matches!(&kind, MediumKind::UniformGrid { temperature: Some(_), .. }) {
            return Err(Error::new(&e.loc, "uniformgrid: give either \"Le\" or \"temperature\", not both"));
        }
        let le_scale_values = p.get_floats(le_scale_name)?;
        let le_scale = if le_scale_values.len() == 1 { le_scale_values[0] } else { 1.0 };
        Ok(MediumSettings { kind, sigma_a, sigma_s, scale, g, le, le_scale })
    }
}
