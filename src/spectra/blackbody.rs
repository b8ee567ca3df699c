//! Blackbody emission: Planck's law, pbrt-v4's peak-normalised `BlackbodySpectrum`, and a
//! table of its film RGB against temperature for per-voxel lookups (temperature grids).

use glam::DVec3;
use nimbus_parser::ColorSpace;

use super::cie::integrate_xyz;
use super::colorspace::rgb_color_space;
use crate::color::Rgb;

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
        let ln_xyz = (0..Self::N)
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
