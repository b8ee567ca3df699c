//! How a sample reaches the film, in either representation of light.

use crate::channels::Channels;
use crate::color::Rgb;
use crate::spectra::{CIE_Y_INTEGRAL, N_SPECTRUM_SAMPLES, PixelSensor, SampledSpectrum, SampledWavelengths};

/// The channels a render can carry, as the film takes them: converted to the film's RGB,
/// or binned into the spectral film's bands.
pub trait FilmChannels: Channels {
    /// The sample as the film accumulates it (for spectra, the sensor's RGB).
    fn to_film(self, lambda: &Self::Lambda, sensor: &PixelSensor) -> Rgb;

    /// Adds the sample to a pixel's spectral-film bands `out` (Σ w·L per band, then Σ w per
    /// band) as pbrt-v4's SpectralFilm does: clamped to `max`, scaled by the CIE Y integral
    /// (which undoes the lights' photometric normalisation) and not divided by the uniform
    /// wavelength density. Only spectral transport has bands.
    fn add_to_bands(self, lambda: &Self::Lambda, weight: f32, max: f32, bands: (usize, f32, f32), out: &mut [f64]);
}

impl FilmChannels for Rgb {
    #[inline]
    fn to_film(self, _lambda: &(), _sensor: &PixelSensor) -> Rgb {
        self
    }

    fn add_to_bands(self, _lambda: &(), _weight: f32, _max: f32, _bands: (usize, f32, f32), _out: &mut [f64]) {
        unreachable!("the spectral film forces spectral transport")
    }
}

impl FilmChannels for SampledSpectrum {
    /// pbrt-v4's RGB film: the sample's sensor RGB (imaging ratio included).
    #[inline]
    fn to_film(self, lambda: &SampledWavelengths, sensor: &PixelSensor) -> Rgb {
        sensor.to_sensor_rgb(self, lambda)
    }

    fn add_to_bands(
        self,
        lambda: &SampledWavelengths,
        weight: f32,
        max: f32,
        bands: (usize, f32, f32),
        out: &mut [f64],
    ) {
        let (n, min, range) = (bands.0, bands.1, bands.2 - bands.1);
        let mut l = self;
        if !(0..N_SPECTRUM_SAMPLES).all(|i| l[i].is_finite()) {
            return;
        }
        let m = (0..N_SPECTRUM_SAMPLES).map(|i| l[i]).fold(0.0f32, f32::max);
        if m > max {
            l *= max / m;
        }
        for i in 0..N_SPECTRUM_SAMPLES {
            // A wavelength a dispersive path dropped has no estimate (pbrt-v4 would add its
            // zero and count its weight).
            if lambda.pdf[i] == 0.0 {
                continue;
            }
            let b = ((n as f32 * (lambda.lambda[i] - min) / range) as usize).min(n - 1);
            out[b] += (weight * l[i]) as f64 * CIE_Y_INTEGRAL;
            out[n + b] += weight as f64;
        }
    }
}
