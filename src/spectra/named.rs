//! pbrt-v4's named spectra (`"spectrum eta" "glass-BK7"`): the names, their data files and
//! the normalisation pbrt-v4 applies when it loads them.

use std::collections::HashMap;
use std::sync::OnceLock;

use super::PiecewiseLinearSpectrum;
use super::cie::{CIE_Y_INTEGRAL, LAMBDA_MAX, LAMBDA_MIN, integrate_y};

/// True when `name` is one of pbrt-v4's named spectra.
pub fn is_named_spectrum(name: &str) -> bool {
    DATA.iter().any(|(n, _)| *n == name)
}

/// Every named spectrum a pbrt-v4 scene may use.
pub fn named_spectrum_names() -> impl Iterator<Item = &'static str> {
    DATA.iter().map(|(n, _)| *n)
}

/// The data file of each named spectrum, embedded in the binary.
macro_rules! data_files {
    ($($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!("data/", $name, ".spd")))),*]
    };
}

const DATA: &[(&str, &str)] = data_files![
    "glass-BK7",
    "glass-BAF10",
    "glass-FK51A",
    "glass-LASF9",
    "glass-F5",
    "glass-F10",
    "glass-F11",
    "metal-Ag-eta",
    "metal-Ag-k",
    "metal-Al-eta",
    "metal-Al-k",
    "metal-Au-eta",
    "metal-Au-k",
    "metal-Cu-eta",
    "metal-Cu-k",
    "metal-CuZn-eta",
    "metal-CuZn-k",
    "metal-MgO-eta",
    "metal-MgO-k",
    "metal-TiO2-eta",
    "metal-TiO2-k",
    "stdillum-A",
    "stdillum-D50",
    "stdillum-D65",
    "stdillum-F1",
    "stdillum-F2",
    "stdillum-F3",
    "stdillum-F4",
    "stdillum-F5",
    "stdillum-F6",
    "stdillum-F7",
    "stdillum-F8",
    "stdillum-F9",
    "stdillum-F10",
    "stdillum-F11",
    "stdillum-F12",
    "illum-acesD60",
];

/// The named spectrum `name` as pbrt-v4 builds it: its samples extended as constants to
/// cover 360–830 nm, and — for the illuminants — scaled so that Σ s(λ)ȳ(λ) = ∫ȳ, i.e. a
/// luminance of 1 (`FromInterleaved(..., normalize = true)`).
pub fn named_spectrum(name: &str) -> Option<&'static PiecewiseLinearSpectrum> {
    static TABLE: OnceLock<HashMap<&'static str, PiecewiseLinearSpectrum>> = OnceLock::new();
    TABLE
        .get_or_init(|| {
            DATA.iter()
                .map(|&(name, text)| {
                    let mut s = PiecewiseLinearSpectrum::parse(text, name).expect("embedded named spectrum parses");
                    s.extend_to(LAMBDA_MIN, LAMBDA_MAX);
                    if name.starts_with("stdillum-") || name.starts_with("illum-") {
                        s.scale(CIE_Y_INTEGRAL / integrate_y(|l| s.eval(l)));
                    }
                    (name, s)
                })
                .collect()
        })
        .get(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_resolves() {
        assert_eq!(DATA.len(), 37);
        for name in named_spectrum_names() {
            let s = named_spectrum(name).unwrap_or_else(|| panic!("{name} missing"));
            // Covers the visible range, so nothing renders black by accident.
            assert!(s.eval(LAMBDA_MIN) > 0.0 || name.ends_with("-k"), "{name}");
            assert!(s.eval(LAMBDA_MAX) > 0.0 || name.ends_with("-k"), "{name}");
        }
        assert!(named_spectrum("metal-Pt-eta").is_none());
    }

    #[test]
    fn illuminants_have_unit_luminance() {
        for name in named_spectrum_names().filter(|n| n.contains("illum-")) {
            let s = named_spectrum(name).unwrap();
            let y = integrate_y(|l| s.eval(l)) / CIE_Y_INTEGRAL;
            assert!((y - 1.0).abs() < 1e-9, "{name}: {y}");
        }
    }

    #[test]
    fn data_spot_values() {
        // Values from pbrt-v4's tables, read back through the data files.
        let au_k = named_spectrum("metal-Au-k").unwrap();
        assert!((au_k.eval(551.040771) - 2.730625).abs() < 1e-9);
        let cu_eta = named_spectrum("metal-Cu-eta").unwrap();
        assert!((cu_eta.eval(590.400818) - 0.468).abs() < 1e-9);
        let bk7 = named_spectrum("glass-BK7").unwrap();
        assert!((bk7.eval(586.0) - 1.516865556749).abs() < 1e-8);
        let brass = named_spectrum("metal-CuZn-k").unwrap();
        assert!((brass.eval(550.0) - 2.765).abs() < 1e-12);
    }
}
