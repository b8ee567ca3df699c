//! The RGB values nimbus renders with, from every spectrum a pbrt-v4 scene can give, with
//! pbrt-v4's meaning for each kind of quantity.
//!
//! pbrt-v4's film records Σ L(λ)·x̄ȳz̄(λ) over 360–830 nm and converts that XYZ to the film's
//! RGB. nimbus multiplies RGB instead of spectra, so each quantity is projected once:
//! reflectances under the film space's illuminant, lights by their luminance-normalised
//! colour, unnormalised emission in the film's own units.

use nimbus_parser::ColorSpace;

use super::SpectrumError;
use super::cie::{CIE_Y_INTEGRAL, integrate_xyz, integrate_y};
use super::colorspace::{convert_reflectance_rgb, convert_rgb, rgb_color_space};
use super::spectrum::{ResolvedSpectrum, Spectrum, resolve};
use crate::color::Rgb;
use crate::spectra::spec::SpectrumSpec;

/// RGB of a reflectance, albedo or other unbounded quantity (σa, σs, …) for a film in
/// `film`: the spectrum as seen under `film`'s illuminant, normalised so a constant
/// spectrum of 1 gives (1, 1, 1). An `rgb` value passes through, adapted from the entity's
/// space `entity` if that differs (see [`convert_reflectance_rgb`]); values are not
/// clamped (pbrt-v4 rejects RGB albedos outside [0, 1], a check left to the caller).
pub fn reflectance_rgb(spec: &SpectrumSpec, entity: ColorSpace, film: ColorSpace) -> Result<Rgb, SpectrumError> {
    Ok(match resolve(spec)? {
        ResolvedSpectrum::Rgb(rgb) => convert_reflectance_rgb(rgb, entity, film),
        ResolvedSpectrum::Spectral(s) => spectrum_reflectance_rgb(&s, film),
    })
}

/// [`reflectance_rgb`] of a spectrum: M·Σ s(λ)I(λ)x̄ȳz̄(λ) / Σ I(λ)ȳ(λ), with I the film
/// space's illuminant and M its XYZ→RGB matrix.
pub fn spectrum_reflectance_rgb(s: &Spectrum, film: ColorSpace) -> Rgb {
    let cs = rgb_color_space(film);
    let illum = cs.illuminant;
    let xyz = integrate_xyz(|l| s.eval(l) * illum.eval(l)) / integrate_y(|l| illum.eval(l));
    cs.rgb_from_xyz(xyz).as_vec3()
}

/// RGB of a light's emission (`L`, `I` of lights; `Le` of homogeneous and `uniformgrid`
/// media) as pbrt-v4 renders it: pbrt-v4 divides the light's scale by the spectrum's
/// luminance (`SpectrumToPhotometric`). For `rgb` only the color space's illuminant counts
/// there, so `rgb L [r g b]` renders exactly (r, g, b) (converted colorimetrically if the
/// entity's space differs from the film's); blackbody, sampled, named and file spectra give
/// the RGB of the spectrum scaled to luminance Y = 1. A spectrum without luminance is black.
pub fn illuminant_rgb(spec: &SpectrumSpec, entity: ColorSpace, film: ColorSpace) -> Result<Rgb, SpectrumError> {
    Ok(match resolve(spec)? {
        ResolvedSpectrum::Rgb(rgb) => convert_rgb(rgb, entity, film),
        ResolvedSpectrum::Spectral(s) => spectrum_illuminant_rgb(&s, film),
    })
}

/// [`illuminant_rgb`] of a spectrum: its RGB scaled to luminance 1.
pub fn spectrum_illuminant_rgb(s: &Spectrum, film: ColorSpace) -> Rgb {
    let y = spectrum_to_photometric(s);
    if y.is_nan() || y <= 0.0 {
        return Rgb::ZERO;
    }
    rgb_color_space(film).rgb_from_xyz(s.film_xyz() / y).as_vec3()
}

/// pbrt-v4's `SpectrumToXYZ` of a spectrum given for a portal light's `L`, as sRGB: the
/// RGB of the 1×1 image pbrt-v4 makes of it (Σ s(λ)·x̄ȳz̄(λ) / ∫ȳ, not normalised to luminance
/// 1 as a light's spectrum otherwise is). Only for non-RGB spectra.
pub fn srgb_of_spectrum(spec: &SpectrumSpec) -> Result<Rgb, SpectrumError> {
    let xyz = match resolve(spec)? {
        ResolvedSpectrum::Rgb(rgb) => rgb_color_space(ColorSpace::Srgb).xyz_from_rgb(rgb.as_dvec3()),
        ResolvedSpectrum::Spectral(s) => s.film_xyz() / CIE_Y_INTEGRAL,
    };
    Ok(rgb_color_space(ColorSpace::Srgb).rgb_from_xyz(xyz).as_vec3())
}

/// pbrt-v4's `SpectrumToPhotometric` of a spectrum: Σ s(λ)ȳ(λ) over 360..=830 nm, the
/// factor pbrt-v4 divides a light's `scale` by. For an `rgb` light it is that of the color
/// space's illuminant alone, [`CIE_Y_INTEGRAL`].
pub fn spectrum_to_photometric(s: &Spectrum) -> f64 {
    integrate_y(|l| s.eval(l))
}

/// Film RGB of an emission spectrum that pbrt-v4 does *not* normalise, in its film's units
/// (Σ s(λ)·x̄ȳz̄(λ), iso 100, exposure 1): e.g. `rgbgrid` `Le`, where pbrt-v4 emits `rgb`
/// times the color space's illuminant (luminance ∫ȳ), so `rgb` comes back multiplied by
/// [`CIE_Y_INTEGRAL`] ≈ 106.86. For blackbody temperatures see
/// [`blackbody_emission_rgb`](super::blackbody_emission_rgb) and
/// [`BlackbodyRgbTable`](super::BlackbodyRgbTable).
pub fn emission_rgb(spec: &SpectrumSpec, entity: ColorSpace, film: ColorSpace) -> Result<Rgb, SpectrumError> {
    Ok(match resolve(spec)? {
        ResolvedSpectrum::Rgb(rgb) => convert_rgb(rgb, entity, film) * CIE_Y_INTEGRAL as f32,
        ResolvedSpectrum::Spectral(s) => spectrum_emission_rgb(&s, film),
    })
}

/// [`emission_rgb`] of a spectrum: M·Σ s(λ)·x̄ȳz̄(λ).
pub fn spectrum_emission_rgb(s: &Spectrum, film: ColorSpace) -> Rgb {
    rgb_color_space(film).rgb_from_xyz(s.film_xyz()).as_vec3()
}

/// The wavelength (nm) at which [`dielectric_eta`] reads a spectral index of refraction.
pub const DIELECTRIC_ETA_WAVELENGTH: f64 = 550.0;

/// A single index of refraction for a dielectric's `eta`, pbrt-v3 style: a spectral eta
/// (e.g. `"glass-BK7"`) is read at 550 nm, ignoring dispersion (pbrt-v4 instead follows one
/// wavelength per path when eta varies). An `rgb` eta gives its luminance in the entity's
/// space `entity` (exact for gray values, the only common case).
pub fn dielectric_eta(spec: &SpectrumSpec, entity: ColorSpace) -> Result<f32, SpectrumError> {
    Ok(match resolve(spec)? {
        ResolvedSpectrum::Rgb(rgb) => rgb_color_space(entity).luminance(rgb),
        ResolvedSpectrum::Spectral(s) => s.eval(DIELECTRIC_ETA_WAVELENGTH) as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::BlackbodySpectrum;

    const SPACES: [ColorSpace; 4] = [ColorSpace::Srgb, ColorSpace::Rec2020, ColorSpace::Aces2065_1, ColorSpace::DciP3];

    fn named(name: &str) -> SpectrumSpec {
        SpectrumSpec::Named(name.to_string())
    }

    fn close(a: Rgb, b: Rgb, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    #[test]
    fn d65_light_is_white_in_srgb() {
        let s = ColorSpace::Srgb;
        let rgb = illuminant_rgb(&named("stdillum-D65"), s, s).unwrap();
        assert!(close(rgb, Rgb::ONE, 1e-3), "{rgb}");
        // Unnormalised, the named illuminant has luminance ∫ȳ (pbrt-v4's normalisation).
        let e = emission_rgb(&named("stdillum-D65"), s, s).unwrap() / CIE_Y_INTEGRAL as f32;
        assert!(close(e, Rgb::ONE, 1e-3), "{e}");
        // ACES's own white is D60.
        let a = ColorSpace::Aces2065_1;
        let rgb = illuminant_rgb(&named("illum-acesD60"), a, a).unwrap();
        assert!(close(rgb, Rgb::ONE, 1e-3), "{rgb}");
    }

    #[test]
    fn constant_reflectance_is_one_in_every_space() {
        for space in SPACES {
            let rgb = spectrum_reflectance_rgb(&Spectrum::Constant(1.0), space);
            assert!(close(rgb, Rgb::ONE, 1e-5), "{space:?}: {rgb}");
            let flat = SpectrumSpec::Samples(vec![[300.0, 0.5], [900.0, 0.5]]);
            let rgb = reflectance_rgb(&flat, space, space).unwrap();
            assert!(close(rgb, Rgb::splat(0.5), 1e-5), "{space:?}: {rgb}");
        }
    }

    #[test]
    fn rgb_passes_through() {
        let spec = SpectrumSpec::Rgb([0.2, 0.4, 0.8]);
        let s = ColorSpace::Srgb;
        assert_eq!(reflectance_rgb(&spec, s, s).unwrap(), Rgb::new(0.2, 0.4, 0.8));
        assert_eq!(illuminant_rgb(&spec, s, s).unwrap(), Rgb::new(0.2, 0.4, 0.8));
        let e = emission_rgb(&spec, s, s).unwrap() / CIE_Y_INTEGRAL as f32;
        assert!(close(e, Rgb::new(0.2, 0.4, 0.8), 1e-6));
        // Gray stays gray across spaces as a reflectance.
        let gray = SpectrumSpec::Rgb([0.5; 3]);
        let rgb = reflectance_rgb(&gray, ColorSpace::Aces2065_1, s).unwrap();
        assert!(close(rgb, Rgb::splat(0.5), 1e-5), "{rgb}");
    }

    #[test]
    fn light_spectra_are_normalised_to_unit_luminance() {
        let specs = [
            SpectrumSpec::Blackbody(2700.0),
            SpectrumSpec::Blackbody(6500.0),
            SpectrumSpec::Samples(vec![[400.0, 0.0], [550.0, 5.0], [700.0, 1.0]]),
            named("stdillum-A"),
            named("stdillum-F11"),
        ];
        for space in SPACES {
            for spec in &specs {
                let rgb = illuminant_rgb(spec, space, space).unwrap();
                let y = rgb_color_space(space).luminance(rgb);
                assert!((y - 1.0).abs() < 1e-4, "{spec:?} in {space:?}: Y = {y}");
            }
        }
        // Illuminant A is warm.
        let a = illuminant_rgb(&named("stdillum-A"), ColorSpace::Srgb, ColorSpace::Srgb);
        let a = a.unwrap();
        assert!(a.x > a.y && a.y > a.z, "{a}");
        // Zero spectra stay black rather than dividing by zero.
        let zero = SpectrumSpec::Samples(vec![[400.0, 0.0], [700.0, 0.0]]);
        let s = ColorSpace::Srgb;
        assert_eq!(illuminant_rgb(&zero, s, s).unwrap(), Rgb::ZERO);
    }

    #[test]
    fn blackbody_emission_matches_direct_projection() {
        let s = ColorSpace::Srgb;
        let via_spec = emission_rgb(&SpectrumSpec::Blackbody(1800.0), s, s).unwrap();
        let direct = crate::spectra::blackbody_emission_rgb(1800.0, s);
        assert!(close(via_spec, direct, 1e-4 * direct.max_element()));
        let bb = Spectrum::Blackbody(BlackbodySpectrum::new(1800.0));
        let y = spectrum_to_photometric(&bb);
        let lum = rgb_color_space(s).luminance(direct);
        assert!((f64::from(lum) / y - 1.0).abs() < 1e-5);
    }

    #[test]
    fn dielectric_eta_reads_550nm() {
        let s = ColorSpace::Srgb;
        let bk7 = dielectric_eta(&named("glass-BK7"), s).unwrap();
        // BK7's Sellmeier index at 550 nm is 1.51852.
        assert!((bk7 - 1.51852).abs() < 2e-4, "{bk7}");
        assert_eq!(dielectric_eta(&SpectrumSpec::Rgb([1.5; 3]), s).unwrap(), 1.5);
    }
}
