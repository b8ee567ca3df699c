//! A spectrum a scene gives, resolved from its `SpectrumSpec` into something that can be
//! evaluated at any wavelength — or kept as RGB, which nimbus uses directly.

use glam::DVec3;

use super::blackbody::BlackbodySpectrum;
use super::cie::integrate_xyz;
use super::named::named_spectrum;
use super::{PiecewiseLinearSpectrum, SpectrumError};
use crate::color::Rgb;
use crate::spectra::spec::SpectrumSpec;

/// A spectral distribution: value as a function of wavelength in nm.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Constant(f64),
    /// Samples, linearly interpolated (inline `"spectrum"`, `.spd` files, named spectra).
    PiecewiseLinear(PiecewiseLinearSpectrum),
    /// A blackbody normalised to peak 1.
    Blackbody(BlackbodySpectrum),
}

impl Spectrum {
    /// The value at `lambda` nm.
    pub fn eval(&self, lambda: f64) -> f64 {
        match self {
            Spectrum::Constant(c) => *c,
            Spectrum::PiecewiseLinear(s) => s.eval(lambda),
            Spectrum::Blackbody(b) => b.eval(lambda),
        }
    }

    /// Σ s(λ)·(x̄, ȳ, z̄)(λ) over 360..=830 nm: the XYZ pbrt-v4's film records for this
    /// spectrum as radiance (not divided by ∫ȳ).
    pub fn film_xyz(&self) -> DVec3 {
        integrate_xyz(|l| self.eval(l))
    }
}

/// A scene spectrum after resolution: RGB stays RGB, everything else becomes a [`Spectrum`].
#[derive(Clone, Debug, PartialEq)]
pub enum ResolvedSpectrum {
    /// RGB in the entity's color space.
    Rgb(Rgb),
    /// A spectral distribution.
    Spectral(Spectrum),
}

/// Resolves `spec`: looks up named spectra, reads `.spd` files, checks inline samples.
pub fn resolve(spec: &SpectrumSpec) -> Result<ResolvedSpectrum, SpectrumError> {
    Ok(match spec {
        SpectrumSpec::Rgb(rgb) => ResolvedSpectrum::Rgb(Rgb::from_array(*rgb)),
        SpectrumSpec::Blackbody(t) => {
            ResolvedSpectrum::Spectral(Spectrum::Blackbody(BlackbodySpectrum::new(f64::from(*t))))
        }
        SpectrumSpec::Samples(pairs) => {
            ResolvedSpectrum::Spectral(Spectrum::PiecewiseLinear(PiecewiseLinearSpectrum::from_pairs(
                pairs.iter().map(|p| (f64::from(p[0]), f64::from(p[1]))),
                "inline spectrum",
            )?))
        }
        SpectrumSpec::Named(name) => ResolvedSpectrum::Spectral(Spectrum::PiecewiseLinear(
            named_spectrum(name).ok_or_else(|| SpectrumError::UnknownName(name.clone()))?.clone(),
        )),
        SpectrumSpec::File(path) => {
            ResolvedSpectrum::Spectral(Spectrum::PiecewiseLinear(PiecewiseLinearSpectrum::read(path)?))
        }
    })
}

/// Resolves `spec` to a [`Spectrum`], or `None` for RGB (which has no spectrum of its own in
/// nimbus).
pub fn resolve_spectral(spec: &SpectrumSpec) -> Result<Option<Spectrum>, SpectrumError> {
    Ok(match resolve(spec)? {
        ResolvedSpectrum::Rgb(_) => None,
        ResolvedSpectrum::Spectral(s) => Some(s),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolves_every_kind() {
        let rgb = resolve(&SpectrumSpec::Rgb([0.1, 0.2, 0.3])).unwrap();
        assert_eq!(rgb, ResolvedSpectrum::Rgb(Rgb::new(0.1, 0.2, 0.3)));
        let bb = resolve_spectral(&SpectrumSpec::Blackbody(3000.0)).unwrap().unwrap();
        assert!(bb.eval(966.0) > 0.99);
        let samples = SpectrumSpec::Samples(vec![[400.0, 1.0], [700.0, 2.0]]);
        let s = resolve_spectral(&samples).unwrap().unwrap();
        assert_eq!(s.eval(550.0), 1.5);
        for name in super::super::named_spectrum_names() {
            let s = resolve_spectral(&SpectrumSpec::Named(name.to_string()));
            assert!(matches!(s, Ok(Some(_))), "{name}");
        }
    }

    #[test]
    fn errors_are_reported() {
        let bad = SpectrumSpec::Samples(vec![[700.0, 1.0], [400.0, 2.0]]);
        let err = resolve(&bad).unwrap_err().to_string();
        assert!(err.contains("inline spectrum") && err.contains("increase"), "{err}");
        let unknown = resolve(&SpectrumSpec::Named("metal-Pt-eta".into())).unwrap_err();
        assert!(unknown.to_string().contains("metal-Pt-eta"));
        let missing = resolve(&SpectrumSpec::File("/nonexistent/x.spd".into())).unwrap_err();
        assert!(missing.to_string().contains("x.spd"), "{missing}");
    }
}
