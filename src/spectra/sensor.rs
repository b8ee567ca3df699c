//! Camera sensors as pbrt-v4's `PixelSensor` models them (`film.h`, `film.cpp`): the film
//! records sensor RGB — the radiance spectrum integrated against the sensor's three response
//! curves, times the imaging ratio exposure × ISO / 100 — and converts it to the output color
//! space through an XYZ-from-sensor matrix. For the `cie1931` sensor the curves are the CIE
//! matching functions and the matrix is a white balance (or nothing); for a named camera the
//! matrix is the least-squares fit that maps the 24 ColorChecker swatches seen by the camera
//! under the white-balance illuminant to their XYZ under the output space's illuminant.
//!
//! The response curves of the 17 cameras are published measurements, carried over from
//! pbrt-v4 as data (`data/sensors/`, provenance in `data/README.md`).

use std::sync::OnceLock;

use glam::{DMat3, DVec2, DVec3, Mat3, Vec3, Vec4};
use nimbus_parser::ColorSpace;

use super::blackbody::BlackbodySpectrum;
use super::cie::{LAMBDA_MIN, cie_xyz_bar};
use super::colorspace::rgb_color_space;
use super::piecewise::{PiecewiseLinearSpectrum, parse_numbers};
use super::sampled::SampledWavelengths;

/// Integer wavelengths pbrt-v4's sensors are tabulated at (360–830 nm).
const N: usize = 471;

macro_rules! curves {
    ($($name:literal),* $(,)?) => {
        &[$(($name, [
            include_str!(concat!("data/sensors/", $name, "_r.spd")),
            include_str!(concat!("data/sensors/", $name, "_g.spd")),
            include_str!(concat!("data/sensors/", $name, "_b.spd")),
        ])),*]
    };
}

/// The camera sensors pbrt-v4 knows besides `cie1931`, with their curves' data files.
const CURVE_DATA: &[(&str, [&str; 3])] = curves![
    "canon_eos_100d",
    "canon_eos_1dx_mkii",
    "canon_eos_200d",
    "canon_eos_200d_mkii",
    "canon_eos_5d",
    "canon_eos_5d_mkii",
    "canon_eos_5d_mkiii",
    "canon_eos_5d_mkiv",
    "canon_eos_5ds",
    "canon_eos_m",
    "hasselblad_l1d_20c",
    "nikon_d810",
    "nikon_d850",
    "sony_ilce_6400",
    "sony_ilce_7m3",
    "sony_ilce_7rm3",
    "sony_ilce_9",
];

/// The names of the camera sensors pbrt-v4 knows besides `cie1931`.
pub fn camera_sensors() -> impl Iterator<Item = &'static str> {
    CURVE_DATA.iter().map(|(name, _)| *name)
}

/// A response curve tabulated at every integer wavelength (pbrt-v4's `DenselySampledSpectrum`,
/// which a sample at λ reads at the nearest integer).
type Dense = [f32; N];

fn dense(f: impl Fn(f64) -> f64) -> Box<Dense> {
    let mut d = Box::new([0.0f32; N]);
    for (i, v) in d.iter_mut().enumerate() {
        *v = f(LAMBDA_MIN + i as f64) as f32;
    }
    d
}

#[inline]
fn lookup(d: &Dense, lambda: f32) -> f32 {
    let i = (lambda - LAMBDA_MIN as f32).round();
    if (0.0..N as f32).contains(&i) { d[i as usize] } else { 0.0 }
}

/// The (r̄, ḡ, b̄) curves of camera `name`, as pbrt-v4's named spectra `<name>_r/_g/_b`
/// (extended as constants to 360–830 nm, not normalised).
fn camera_curves(name: &str) -> Option<[PiecewiseLinearSpectrum; 3]> {
    let (_, texts) = CURVE_DATA.iter().find(|(n, _)| *n == name)?;
    Some(texts.map(|t| {
        let mut s = PiecewiseLinearSpectrum::parse(t, name).expect("embedded sensor curve parses");
        s.extend_to(LAMBDA_MIN, super::cie::LAMBDA_MAX);
        s
    }))
}

/// The 24 ColorChecker reflectances (`PixelSensor::swatchReflectances`).
fn swatches() -> &'static [PiecewiseLinearSpectrum] {
    static SWATCHES: OnceLock<Vec<PiecewiseLinearSpectrum>> = OnceLock::new();
    SWATCHES.get_or_init(|| {
        include_str!("data/colorchecker-swatches.txt")
            .lines()
            .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
            .map(|l| {
                let numbers = parse_numbers(l).expect("embedded swatch parses");
                let mut s = PiecewiseLinearSpectrum::from_interleaved(&numbers, "swatch").expect("swatch is valid");
                s.extend_to(LAMBDA_MIN, super::cie::LAMBDA_MAX);
                s
            })
            .collect()
    })
}

/// pbrt-v4's `Spectra::D`: the CIE daylight illuminant of correlated color temperature `t`
/// K from the S0/S1/S2 basis (a blackbody below 4000 K, where CIE D is ill-defined), at
/// integer wavelengths.
pub fn daylight_spectrum(t: f64) -> impl Fn(f64) -> f64 {
    static BASIS: OnceLock<Vec<[f64; 4]>> = OnceLock::new();
    let basis = BASIS.get_or_init(|| {
        let n = parse_numbers(include_str!("data/cie-daylight-basis.txt")).expect("embedded basis parses");
        n.chunks_exact(4).map(|r| [r[0], r[1], r[2], r[3]]).collect()
    });
    // pbrt-v4 corrects for the revised second radiation constant.
    let cct = t * 1.4388 / 1.4380;
    let table: Option<PiecewiseLinearSpectrum> = (cct >= 4000.0).then(|| {
        let x = if cct <= 7000.0 {
            -4.607e9 / cct.powi(3) + 2.9678e6 / (cct * cct) + 0.09911e3 / cct + 0.244063
        } else {
            -2.0064e9 / cct.powi(3) + 1.9018e6 / (cct * cct) + 0.24748e3 / cct + 0.23704
        };
        let y = -3.0 * x * x + 2.870 * x - 0.275;
        let m = 0.0241 + 0.2562 * x - 0.7341 * y;
        let m1 = (-1.3515 - 1.7703 * x + 5.9114 * y) / m;
        let m2 = (0.0300 - 31.4424 * x + 30.0717 * y) / m;
        PiecewiseLinearSpectrum::from_pairs(
            basis.iter().map(|r| (r[0], (r[1] + r[2] * m1 + r[3] * m2) * 0.01)),
            "CIE daylight",
        )
        .expect("daylight basis is valid")
    });
    let bb = BlackbodySpectrum::new(cct);
    move |l: f64| match &table {
        Some(s) => s.eval(l),
        None => bb.eval(l),
    }
}

/// pbrt-v4's `WhiteBalance`: von Kries adaptation in Bradford's LMS space from white
/// chromaticity `src` to `dst`, with pbrt-v4's matrices.
pub fn white_balance(src: DVec2, dst: DVec2) -> DMat3 {
    let lms_from_xyz =
        DMat3::from_cols_array(&[0.8951, -0.7502, 0.0389, 0.2664, 1.7135, -0.0685, -0.1614, 0.0367, 1.0296]);
    let xyz_from_lms = DMat3::from_cols_array(&[
        0.986993,
        0.432305,
        -0.00852866,
        -0.147054,
        0.51836,
        0.0400428,
        0.159963,
        0.0492912,
        0.968487,
    ]);
    let xyz = |xy: DVec2| DVec3::new(xy.x / xy.y, 1.0, (1.0 - xy.x - xy.y) / xy.y);
    let (s, d) = (lms_from_xyz * xyz(src), lms_from_xyz * xyz(dst));
    xyz_from_lms * DMat3::from_diagonal(d / s) * lms_from_xyz
}

/// Σ f(λ)g(λ) over the integer wavelengths 360–830 (pbrt-v4's `InnerProduct`).
fn inner(f: impl Fn(f64) -> f64, g: impl Fn(f64) -> f64) -> f64 {
    (0..N).map(|i| LAMBDA_MIN + i as f64).map(|l| f(l) * g(l)).sum()
}

/// A film's sensor.
#[derive(Clone, Debug)]
pub struct PixelSensor {
    name: String,
    curves: [Box<Dense>; 3],
    xyz_from_sensor_rgb: DMat3,
    output_rgb_from_sensor_rgb: DMat3,
    imaging_ratio: f32,
    /// True for `cie1931` without white balance: sensor RGB is XYZ and the output is plain
    /// XYZ → RGB, so RGB inputs reach the film unchanged.
    passthrough: bool,
}

impl PixelSensor {
    /// pbrt-v4's `PixelSensor::Create`: sensor `name` (`cie1931` or one of
    /// [`camera_sensors`]), white balance temperature `white_balance` K (0: none for
    /// `cie1931`, 6500 K for cameras), `iso` and exposure time, for output space `output`.
    pub fn new(
        name: &str,
        white_balance_k: f32,
        iso: f32,
        exposure_time: f32,
        output: ColorSpace,
    ) -> crate::error::Result<PixelSensor> {
        let cs = rgb_color_space(output);
        let imaging_ratio = exposure_time * iso / 100.0;
        let wb = if name != "cie1931" && white_balance_k == 0.0 { 6500.0 } else { white_balance_k };
        if name == "cie1931" {
            let xyz_from_sensor_rgb = if wb != 0.0 {
                let d = daylight_spectrum(f64::from(wb));
                let xyz = DVec3::new(
                    inner(&d, |l| cie_xyz_bar(l).x),
                    inner(&d, |l| cie_xyz_bar(l).y),
                    inner(&d, |l| cie_xyz_bar(l).z),
                );
                let src = DVec2::new(xyz.x, xyz.y) / xyz.element_sum();
                white_balance(src, cs.white)
            } else {
                DMat3::IDENTITY
            };
            return Ok(PixelSensor {
                name: name.to_string(),
                curves: [dense(|l| cie_xyz_bar(l).x), dense(|l| cie_xyz_bar(l).y), dense(|l| cie_xyz_bar(l).z)],
                xyz_from_sensor_rgb,
                output_rgb_from_sensor_rgb: cs.rgb_from_xyz * xyz_from_sensor_rgb,
                imaging_ratio,
                passthrough: wb == 0.0,
            });
        }
        let [r, g, b] = camera_curves(name).ok_or_else(|| {
            crate::error::Error::Unsupported(format!(
                "unknown sensor \"{name}\" (pbrt-v4's sensors: cie1931, {})",
                camera_sensors().collect::<Vec<_>>().join(", ")
            ))
        })?;
        let curves = [dense(|l| r.eval(l)), dense(|l| g.eval(l)), dense(|l| b.eval(l))];
        let at = |c: &Dense, l: f64| f64::from(c[(l - LAMBDA_MIN) as usize]);
        let illum = daylight_spectrum(f64::from(wb));
        // pbrt-v4's ProjectReflectance: Σ curve·refl·illum / Σ (second curve)·illum.
        let camera: Vec<DVec3> = swatches()
            .iter()
            .map(|s| {
                let g_integral = inner(|l| at(&curves[1], l), &illum);
                DVec3::new(
                    inner(|l| at(&curves[0], l) * s.eval(l), &illum),
                    inner(|l| at(&curves[1], l) * s.eval(l), &illum),
                    inner(|l| at(&curves[2], l) * s.eval(l), &illum),
                ) / g_integral
            })
            .collect();
        let sensor_white_g = inner(&illum, |l| at(&curves[1], l));
        let sensor_white_y = inner(&illum, |l| cie_xyz_bar(l).y);
        let out_illum = |l: f64| cs.illuminant.eval(l);
        let y_integral = inner(out_illum, |l| cie_xyz_bar(l).y);
        let target: Vec<DVec3> = swatches()
            .iter()
            .map(|s| {
                DVec3::new(
                    inner(|l| cie_xyz_bar(l).x * s.eval(l), out_illum),
                    inner(|l| cie_xyz_bar(l).y * s.eval(l), out_illum),
                    inner(|l| cie_xyz_bar(l).z * s.eval(l), out_illum),
                ) / y_integral
                    * (sensor_white_y / sensor_white_g)
            })
            .collect();
        let xyz_from_sensor_rgb = least_squares(&camera, &target).ok_or_else(|| {
            crate::error::Error::Invalid(format!("sensor \"{name}\": the XYZ-from-sensor matrix could not be solved"))
        })?;
        Ok(PixelSensor {
            name: name.to_string(),
            curves,
            xyz_from_sensor_rgb,
            output_rgb_from_sensor_rgb: cs.rgb_from_xyz * xyz_from_sensor_rgb,
            imaging_ratio,
            passthrough: false,
        })
    }

    /// The sensor's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Exposure time × ISO / 100.
    pub fn imaging_ratio(&self) -> f32 {
        self.imaging_ratio
    }

    /// pbrt-v4's `XYZFromSensorRGB`.
    pub fn xyz_from_sensor_rgb(&self) -> DMat3 {
        self.xyz_from_sensor_rgb
    }

    /// Output RGB from sensor RGB (pbrt-v4's `RGBFilm::outputRGBFromSensorRGB`).
    pub fn output_rgb_from_sensor_rgb(&self) -> DMat3 {
        self.output_rgb_from_sensor_rgb
    }

    /// True when RGB inputs reach the film unchanged (`cie1931` without white balance).
    pub fn is_passthrough(&self) -> bool {
        self.passthrough
    }

    /// Σ (r̄, ḡ, b̄)(λ)·f(λ) over the integer wavelengths: the sensor RGB of radiance spectrum
    /// `f`, without the imaging ratio.
    pub fn project(&self, f: impl Fn(f64) -> f64) -> DVec3 {
        let mut s = DVec3::ZERO;
        for i in 0..N {
            let v = f(LAMBDA_MIN + i as f64);
            s += DVec3::new(f64::from(self.curves[0][i]), f64::from(self.curves[1][i]), f64::from(self.curves[2][i]))
                * v;
        }
        s
    }

    /// The output RGB the film records for radiance spectrum `f` (without the imaging ratio):
    /// how RGB transport converts an emitter's spectrum once.
    pub fn film_rgb(&self, f: impl Fn(f64) -> f64) -> Vec3 {
        (self.output_rgb_from_sensor_rgb * self.project(f)).as_vec3()
    }

    /// pbrt-v4's `ToSensorRGB`: the sensor RGB of one sample of radiance `l` at the path's
    /// wavelengths (each divided by its density; dropped wavelengths count zero), times the
    /// imaging ratio.
    #[inline]
    pub fn to_sensor_rgb(&self, l: Vec4, lambda: &SampledWavelengths) -> Vec3 {
        let pdf = lambda.pdf;
        let l = Vec4::select(pdf.cmpne(Vec4::ZERO), l / pdf, Vec4::ZERO);
        let wl = lambda.lambda.to_array();
        let curve = |c: &Dense| Vec4::new(lookup(c, wl[0]), lookup(c, wl[1]), lookup(c, wl[2]), lookup(c, wl[3]));
        Vec3::new(
            (curve(&self.curves[0]) * l).element_sum(),
            (curve(&self.curves[1]) * l).element_sum(),
            (curve(&self.curves[2]) * l).element_sum(),
        ) * (0.25 * self.imaging_ratio)
    }

    /// [`PixelSensor::output_rgb_from_sensor_rgb`] in f32.
    pub fn output_matrix(&self) -> Mat3 {
        self.output_rgb_from_sensor_rgb.as_mat3()
    }
}

/// pbrt-v4's `LinearLeastSquares`: the M minimising Σ |M·aᵢ − bᵢ|².
fn least_squares(a: &[DVec3], b: &[DVec3]) -> Option<DMat3> {
    let mut ata = DMat3::ZERO;
    let mut atb = DMat3::ZERO;
    for (x, y) in a.iter().zip(b) {
        // Σ x xᵀ and Σ x yᵀ (as column-major outer products).
        ata += DMat3::from_cols(*x * x.x, *x * x.y, *x * x.z);
        atb += DMat3::from_cols(*x * y.x, *x * y.y, *x * y.z);
    }
    if ata.determinant().abs() < 1e-30 {
        return None;
    }
    Some((ata.inverse() * atb).transpose())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::cie::CIE_Y_INTEGRAL;
    use crate::spectra::sampled::SampledWavelengths;

    #[test]
    fn every_sensor_builds_and_unknown_names_are_refused() {
        assert_eq!(camera_sensors().count(), 17);
        for name in camera_sensors() {
            let s = PixelSensor::new(name, 0.0, 100.0, 1.0, ColorSpace::Srgb).unwrap();
            assert!(s.xyz_from_sensor_rgb().determinant().abs() > 0.0, "{name}");
            assert!(!s.is_passthrough());
        }
        let err = PixelSensor::new("leica_m11", 0.0, 100.0, 1.0, ColorSpace::Srgb).unwrap_err().to_string();
        assert!(err.contains("leica_m11") && err.contains("nikon_d850"), "{err}");
        let cie = PixelSensor::new("cie1931", 0.0, 100.0, 1.0, ColorSpace::Srgb).unwrap();
        assert!(cie.is_passthrough());
        let m = cie.output_rgb_from_sensor_rgb() - rgb_color_space(ColorSpace::Srgb).rgb_from_xyz;
        assert!(m.to_cols_array().iter().all(|v| v.abs() < 1e-12));
        assert_eq!(PixelSensor::new("nikon_d850", 0.0, 90.0, 1.0, ColorSpace::Srgb).unwrap().imaging_ratio(), 0.9);
    }

    /// The per-sample estimate, averaged over stratified wavelength samples, converges to the
    /// sensor's integral of a known spectrum (a Gaussian bump), computed independently here.
    #[test]
    fn sampled_response_matches_the_integral() {
        let sensor = PixelSensor::new("nikon_d850", 0.0, 100.0, 1.0, ColorSpace::Srgb).unwrap();
        let g = |l: f64| (-((l - 560.0) / 40.0).powi(2)).exp();
        let exact = sensor.project(g);
        let [r, gg, b] = camera_curves("nikon_d850").unwrap();
        // Trapezoid integral of the piecewise-linear curves at 0.1 nm.
        let mut direct = DVec3::ZERO;
        let mut l = 360.0;
        while l <= 830.0 {
            direct += DVec3::new(r.eval(l), gg.eval(l), b.eval(l)) * g(l) * 0.1;
            l += 0.1;
        }
        assert!(((exact - direct) / direct).abs().max_element() < 3e-3, "{exact} vs {direct}");
        let n = 20_000;
        let mut sum = DVec3::ZERO;
        for i in 0..n {
            let lambda = SampledWavelengths::sample_visible((i as f32 + 0.5) / n as f32);
            let l = Vec4::from_array(lambda.lambda.to_array().map(|x| g(f64::from(x)) as f32));
            sum += sensor.to_sensor_rgb(l, &lambda).as_dvec3();
        }
        let mean = sum / n as f64;
        assert!(((mean - exact) / exact).abs().max_element() < 2e-3, "{mean} vs {exact}");
    }

    /// White balance maps the white-balance illuminant to the output space's white.
    #[test]
    fn white_balance_maps_the_illuminant_to_white() {
        for t in [3200.0f32, 5000.0, 6500.0] {
            let d = daylight_spectrum(f64::from(t));
            let y = inner(&d, |l| cie_xyz_bar(l).y);
            let cie = PixelSensor::new("cie1931", t, 100.0, 1.0, ColorSpace::Srgb).unwrap();
            let rgb = cie.film_rgb(|l| d(l) / y);
            assert!((rgb - Vec3::ONE).abs().max_element() < 1e-3, "cie1931 at {t} K: {rgb}");
            // A camera's fit over the swatches is least squares, not exact: the illuminant
            // comes out gray to within a few percent of its luminance.
            let cam = PixelSensor::new("nikon_d850", t, 100.0, 1.0, ColorSpace::Srgb).unwrap();
            let rgb = cam.film_rgb(|l| d(l) / y);
            let mean = rgb.element_sum() / 3.0;
            assert!((rgb / mean - Vec3::ONE).abs().max_element() < 0.03, "nikon_d850 at {t} K: {rgb}");
        }
    }

    /// The fitted matrix reproduces the swatches' XYZ (the data it was fitted to) closely.
    #[test]
    fn camera_fit_reproduces_the_swatches() {
        let cs = rgb_color_space(ColorSpace::Srgb);
        let sensor = PixelSensor::new("canon_eos_5d_mkiv", 6500.0, 100.0, 1.0, ColorSpace::Srgb).unwrap();
        let d = daylight_spectrum(6500.0);
        let y = inner(&d, |l| cie_xyz_bar(l).y);
        let mut worst = 0.0f64;
        for s in swatches() {
            // The camera sees the swatch under D65; the output is its XYZ under the space's
            // (D65) illuminant.
            let got = sensor.xyz_from_sensor_rgb() * sensor.project(|l| s.eval(l) * d(l) / y);
            let want = DVec3::new(
                inner(|l| cie_xyz_bar(l).x * s.eval(l), |l| cs.illuminant.eval(l)),
                inner(|l| cie_xyz_bar(l).y * s.eval(l), |l| cs.illuminant.eval(l)),
                inner(|l| cie_xyz_bar(l).z * s.eval(l), |l| cs.illuminant.eval(l)),
            ) / CIE_Y_INTEGRAL;
            // Errors relative to white (Y = 1): the fit is least squares in absolute terms.
            worst = worst.max((got - want).abs().max_element());
        }
        // A camera is not a colorimeter: the 3×3 fit leaves 0.020 on canon_eos_5d_mkiv.
        assert!(worst < 0.03, "worst swatch XYZ error {worst} (white has Y = 1)");
    }
}
