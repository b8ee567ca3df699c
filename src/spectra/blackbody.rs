//! Blackbody emission: Planck's law, pbrt-v4's peak-normalised `BlackbodySpectrum`, and a
//! table of its film RGB against temperature for per-voxel lookups (temperature grids).

use glam::{DVec3, Vec4};
use nimbus_parser::ColorSpace;

use super::cie::integrate_xyz;
use super::colorspace::rgb_color_space;
use crate::color::Rgb;
use crate::math::exp4;

/// Spectral radiance of a blackbody at `lambda` nm and `t` Kelvin (W·sr⁻¹·m⁻³), with the
/// constants pbrt-v4 uses; 0 for non-positive temperatures.
pub fn planck(lambda: f64, t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    const C: f64 = 299792458.0;
    const H: f64 = 6.62606957e-34;
    const KB: f64 = 1.3806488e-23;
    let l = lambda * 1e-9;
    (2.0 * H * C * C) / (l.powi(5) * ((H * C / (l * KB * t)).exp_m1()))
}

/// Wien's displacement constant b (m·K): the peak is at λmax = b / T.
const WIEN_B: f64 = 2.8977721e-3;
/// hc/k (m·K) with [`planck`]'s constants: the exponent hc/(λkT) is this over λT.
const HC_OVER_K: f64 = 6.62606957e-34 * 299792458.0 / 1.3806488e-23;
/// e^{hc/(λmax k T)} − 1 = e^{hc/(k b)} − 1, the same at every temperature.
const PEAK_EXPM1: f32 = 142.324_93;

/// pbrt-v4's peak-normalised blackbody at four wavelengths (nm) and `t` Kelvin, in single
/// precision as pbrt-v4 evaluates it: (λmax/λ)⁵ (e^{hc/(λmax kT)} − 1) / (e^{hc/(λkT)} − 1),
/// Planck's law divided by its value at Wien's λmax, written as a ratio so that no f32 goes
/// near its range's ends (Planck's law itself is about 10¹³ at the peak of a 6000 K body).
/// Four exponentials on four lanes: as four f64 `exp_m1`, plus the peak's, they were 6 % of
/// a spectral render of a temperature grid. Zero for non-positive (or NaN) temperatures.
#[inline]
pub fn normalized_planck4(lambda: Vec4, t: f32) -> Vec4 {
    if t.is_nan() || t <= 0.0 {
        return Vec4::ZERO;
    }
    let r = Vec4::splat((WIEN_B * 1e9) as f32 / t) / lambda;
    let x = Vec4::splat((HC_OVER_K * 1e9) as f32 / t) / lambda;
    // e^x overflows to ∞ past x ≈ 88, where the value is below 1e-35: zero.
    (r * r) * (r * r) * r * PEAK_EXPM1 / (exp4(x) - Vec4::ONE)
}

/// pbrt-v4's `BlackbodySpectrum`: Planck's law at temperature `t`, scaled so its peak (at
/// Wien's wavelength) is 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlackbodySpectrum {
    t: f64,
    normalization: f64,
}

impl BlackbodySpectrum {
    /// The normalised blackbody at `t` Kelvin (non-positive temperatures emit nothing).
    pub fn new(t: f64) -> BlackbodySpectrum {
        let lambda_max = 2.8977721e-3 / t * 1e9;
        let peak = planck(lambda_max, t);
        let normalization = if peak > 0.0 { 1.0 / peak } else { 0.0 };
        BlackbodySpectrum { t, normalization }
    }

    /// The temperature in Kelvin.
    pub fn temperature(&self) -> f64 {
        self.t
    }

    /// The value at `lambda` nm (1 at the peak).
    pub fn eval(&self, lambda: f64) -> f64 {
        planck(lambda, self.t) * self.normalization
    }
}

/// Film RGB (in `film`'s space, pbrt-v4 sensor units: Σ B(λ)·x̄ȳz̄(λ)) of the peak-normalised
/// blackbody at `t` Kelvin — what a voxel of temperature `t` emits per unit `Lescale` in
/// pbrt-v4's `uniformgrid`/`nanovdb` media, which do not normalise it photometrically.
pub fn blackbody_emission_rgb(t: f64, film: ColorSpace) -> Rgb {
    rgb_color_space(film).rgb_from_xyz(blackbody_xyz(t)).as_vec3()
}

fn blackbody_xyz(t: f64) -> DVec3 {
    let b = BlackbodySpectrum::new(t);
    integrate_xyz(|l| b.eval(l))
}

/// [`blackbody_emission_rgb`] tabulated against temperature for fast per-sample lookups.
///
/// pbrt-v4 emits nothing from voxels at or below 100 K, and the visible emission of a
/// peak-normalised blackbody falls like exp(−c/λT) as T drops, so the table stores ln XYZ
/// against ln T (both smooth there) from 100 K to 100 000 K and interpolates linearly;
/// relative error is below 1e-3 above 500 K. Temperatures above the range are computed
/// exactly.
#[derive(Clone, Debug)]
pub struct BlackbodyRgbTable {
    rgb_from_xyz: glam::DMat3,
    ln_xyz: Vec<DVec3>,
    /// Sensor RGB instead of XYZ when built for a camera sensor.
    sensor: Option<Box<super::PixelSensor>>,
}

impl BlackbodyRgbTable {
    const T_MIN: f64 = 100.0;
    const T_MAX: f64 = 100_000.0;
    const N: usize = 2048;

    /// Builds the table for a film in color space `film` (a few milliseconds).
    pub fn new(film: ColorSpace) -> BlackbodyRgbTable {
        Self::build(rgb_color_space(film).rgb_from_xyz, None)
    }

    /// Builds the table for the film of `sensor` (its output space and response curves).
    pub fn for_sensor(sensor: &super::PixelSensor) -> BlackbodyRgbTable {
        if sensor.is_passthrough() {
            return Self::build(sensor.output_rgb_from_sensor_rgb(), None);
        }
        Self::build(sensor.output_rgb_from_sensor_rgb(), Some(Box::new(sensor.clone())))
    }

    fn build(rgb_from_xyz: glam::DMat3, sensor: Option<Box<super::PixelSensor>>) -> BlackbodyRgbTable {
        let step = (Self::T_MAX / Self::T_MIN).ln() / (Self::N - 1) as f64;
        // 2048 projections of ~470 wavelengths each: about 30 ms on one core, which scenes
        // of one emitting grid otherwise wait for before rendering.
        use rayon::prelude::*;
        let ln_xyz = (0..Self::N)
            .into_par_iter()
            .map(|i| {
                let t = Self::T_MIN * (step * i as f64).exp();
                // XYZ are positive sums; the floor keeps ln finite where f64 underflows.
                let xyz = Self::project(&sensor, t).max(DVec3::splat(1e-300));
                DVec3::new(xyz.x.ln(), xyz.y.ln(), xyz.z.ln())
            })
            .collect();
        BlackbodyRgbTable { rgb_from_xyz, ln_xyz, sensor }
    }

    /// XYZ (or the sensor's RGB) of the peak-normalised blackbody at `t`.
    fn project(sensor: &Option<Box<super::PixelSensor>>, t: f64) -> DVec3 {
        match sensor {
            None => blackbody_xyz(t),
            Some(s) => {
                let b = BlackbodySpectrum::new(t);
                s.project(|l| b.eval(l))
            }
        }
    }

    /// Film RGB of the peak-normalised blackbody at `t` Kelvin; black at or below 100 K
    /// (where pbrt-v4's grids emit nothing).
    pub fn lookup(&self, t: f32) -> Rgb {
        let t = f64::from(t);
        if t.is_nan() || t <= Self::T_MIN {
            return Rgb::ZERO;
        }
        if t >= Self::T_MAX {
            return (self.rgb_from_xyz * Self::project(&self.sensor, t)).as_vec3();
        }
        let step = (Self::T_MAX / Self::T_MIN).ln() / (Self::N - 1) as f64;
        let u = (t / Self::T_MIN).ln() / step;
        let i = (u as usize).min(Self::N - 2);
        let f = u - i as f64;
        let ln = self.ln_xyz[i].lerp(self.ln_xyz[i + 1], f);
        let xyz = DVec3::new(ln.x.exp(), ln.y.exp(), ln.z.exp());
        (self.rgb_from_xyz * xyz).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::cie::CIE_Y_INTEGRAL;

    /// The constant holds what it names, and the four-lane f32 form is the f64 one.
    #[test]
    fn normalized_planck4_is_the_normalised_blackbody() {
        assert!(((HC_OVER_K / WIEN_B).exp_m1() as f32 / PEAK_EXPM1 - 1.0).abs() < 1e-6);
        for t in [150.0, 500.0, 1000.0, 2856.0, 6504.0, 15000.0, 1e6] {
            let b = BlackbodySpectrum::new(t);
            for l in [[360.0, 400.0, 555.0, 830.0], [450.0, 500.0, 600.0, 700.0]] {
                let v = normalized_planck4(Vec4::from(l), t as f32);
                for k in 0..4 {
                    let want = b.eval(f64::from(l[k]));
                    // f32 rounds the exponent x = hc/(λkT) by about 1e-7 relative, which e^x
                    // turns into about 1e-7·x; e^x − 1 loses 1e-7/x where x is small (a
                    // million kelvin), as pbrt-v4's single-precision form does.
                    let x = HC_OVER_K / (f64::from(l[k]) * 1e-9 * t);
                    let tol = 2e-7 * (x + 10.0 + 1.0 / x) * want + 1e-30;
                    assert!((f64::from(v[k]) - want).abs() <= tol, "{t} K, {} nm: {} vs {want}", l[k], v[k]);
                }
            }
        }
        assert_eq!(normalized_planck4(Vec4::splat(500.0), 0.0), Vec4::ZERO);
        assert_eq!(normalized_planck4(Vec4::splat(500.0), f32::NAN), Vec4::ZERO);
        // Far below the visible peak's temperature the exponential overflows: zero, not NaN.
        assert_eq!(normalized_planck4(Vec4::splat(360.0), 20.0), Vec4::ZERO);
    }

    #[test]
    fn peak_is_one() {
        for t in [1000.0, 2856.0, 6504.0, 15000.0] {
            let b = BlackbodySpectrum::new(t);
            let peak = 2.8977721e-3 / t * 1e9;
            assert!((b.eval(peak) - 1.0).abs() < 1e-12, "{t}");
            // And it is a maximum.
            assert!(b.eval(peak * 0.99) < 1.0 && b.eval(peak * 1.01) < 1.0);
        }
        assert_eq!(BlackbodySpectrum::new(0.0).eval(500.0), 0.0);
    }

    #[test]
    fn d65_temperature_is_near_white_in_srgb() {
        let rgb = blackbody_emission_rgb(6504.0, ColorSpace::Srgb);
        let rgb = rgb / crate::color::luminance(rgb);
        // The Planckian locus passes just below D65 (Δuv ≈ 0.003): a few percent magenta.
        for c in rgb.to_array() {
            assert!((c - 1.0).abs() < 0.06, "{rgb}");
        }
        // 2000 K is orange, 15000 K is blue.
        let warm = blackbody_emission_rgb(2000.0, ColorSpace::Srgb);
        assert!(warm.x > warm.y && warm.y > warm.z, "{warm}");
        let cold = blackbody_emission_rgb(15000.0, ColorSpace::Srgb);
        assert!(cold.z > cold.y && cold.y > cold.x, "{cold}");
    }

    #[test]
    fn unnormalised_units_are_the_film_sums() {
        // Y of the emission is Σ B ȳ, not divided by ∫ȳ: a 6504 K peak-normalised blackbody
        // (≈ 0.9 of its peak across the visible) gives Y of order ∫ȳ.
        let y = crate::color::luminance(blackbody_emission_rgb(6504.0, ColorSpace::Srgb));
        let ratio = f64::from(y) / CIE_Y_INTEGRAL;
        assert!(ratio > 0.8 && ratio < 1.0, "{ratio}");
    }

    #[test]
    fn table_matches_exact_values() {
        let table = BlackbodyRgbTable::new(ColorSpace::Srgb);
        assert_eq!(table.lookup(100.0), Rgb::ZERO);
        assert_eq!(table.lookup(-5.0), Rgb::ZERO);
        let mut t = 500.0;
        while t < 150_000.0 {
            let exact = blackbody_emission_rgb(t, ColorSpace::Srgb);
            let got = table.lookup(t as f32);
            let scale = exact.abs().max_element();
            let err = (got - exact).abs().max_element() / scale;
            assert!(err < 1e-3, "{t} K: {got} vs {exact} ({err})");
            t *= 1.37;
        }
    }
}
