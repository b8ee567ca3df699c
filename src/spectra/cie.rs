//! The CIE 1931 2° colour matching functions and the spectral integrals pbrt-v4 takes with
//! them. pbrt-v4 integrates by summing at every integer wavelength from 360 to 830 nm
//! (`InnerProduct`), and its film records Σ s(λ)·x̄ȳz̄(λ) without dividing by ∫ȳ — so the
//! same sums here reproduce its numbers.

use std::sync::OnceLock;

use glam::DVec3;

use super::piecewise::parse_numbers;

/// Shortest wavelength (nm) pbrt-v4 renders and integrates over.
pub const LAMBDA_MIN: f64 = 360.0;
/// Longest wavelength (nm) pbrt-v4 renders and integrates over.
pub const LAMBDA_MAX: f64 = 830.0;
/// Number of 1 nm steps in `[LAMBDA_MIN, LAMBDA_MAX]`.
const N_LAMBDA: usize = 471;
/// Σ ȳ(λ) over the integer wavelengths 360..=830 (pbrt-v4's `CIE_Y_integral`): the luminance
/// of a constant spectrum of value 1 in the film's units.
pub const CIE_Y_INTEGRAL: f64 = 106.856895;

/// x̄, ȳ, z̄ at 360, 361, …, 830 nm.
fn cmf() -> &'static [DVec3; N_LAMBDA] {
    static CMF: OnceLock<Box<[DVec3; N_LAMBDA]>> = OnceLock::new();
    CMF.get_or_init(|| {
        let text = include_str!("data/cie1931-2deg-1nm.txt");
        let numbers = parse_numbers(text).expect("embedded CIE table parses");
        assert_eq!(numbers.len(), 4 * N_LAMBDA, "embedded CIE table is complete");
        let mut table = Box::new([DVec3::ZERO; N_LAMBDA]);
        for (i, row) in numbers.chunks_exact(4).enumerate() {
            assert_eq!(row[0], LAMBDA_MIN + i as f64, "embedded CIE table is at 1 nm");
            table[i] = DVec3::new(row[1], row[2], row[3]);
        }
        table
    })
}

/// The colour matching functions (x̄, ȳ, z̄) at `lambda` nm, rounded to the nearest integer
/// wavelength as pbrt-v4's `DenselySampledSpectrum` does; zero outside 360–830 nm.
pub fn cie_xyz_bar(lambda: f64) -> DVec3 {
    let i = (lambda - LAMBDA_MIN).round();
    if !(0.0..N_LAMBDA as f64).contains(&i) {
        return DVec3::ZERO;
    }
    cmf()[i as usize]
}

/// Σ f(λ)·(x̄, ȳ, z̄)(λ) over the integer wavelengths 360..=830: the XYZ pbrt-v4's `cie1931`
/// film sensor records for radiance spectrum `f` (at iso 100, exposure 1).
pub fn integrate_xyz(f: impl Fn(f64) -> f64) -> DVec3 {
    cmf().iter().enumerate().map(|(i, bar)| *bar * f(LAMBDA_MIN + i as f64)).sum()
}

/// Σ f(λ)·ȳ(λ) over the integer wavelengths 360..=830: pbrt-v4's `SpectrumToPhotometric`,
/// the factor it divides a light's scale by.
pub fn integrate_y(f: impl Fn(f64) -> f64) -> f64 {
    cmf().iter().enumerate().map(|(i, bar)| bar.y * f(LAMBDA_MIN + i as f64)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_matches_the_published_values() {
        // Spot values of the CIE 1931 2° table (CIE 015:2018).
        assert_eq!(cie_xyz_bar(360.0), DVec3::new(0.0001299, 0.000003917, 0.0006061));
        assert_eq!(cie_xyz_bar(555.0).y, 1.0);
        assert_eq!(cie_xyz_bar(600.0).x, 1.0622);
        assert_eq!(cie_xyz_bar(830.0).x, 0.000001251141);
        assert_eq!(cie_xyz_bar(359.0), DVec3::ZERO);
        assert_eq!(cie_xyz_bar(831.0), DVec3::ZERO);
    }

    #[test]
    fn y_integral_is_pbrts_constant() {
        // pbrt-v4 sums its f32 table in f32; the f64 sum differs in the 7th digit.
        let y = integrate_y(|_| 1.0);
        assert!((y / CIE_Y_INTEGRAL - 1.0).abs() < 1e-6, "{y}");
    }

    #[test]
    fn nearest_integer_lookup() {
        assert_eq!(cie_xyz_bar(554.6), cie_xyz_bar(555.0));
        assert_eq!(cie_xyz_bar(555.4), cie_xyz_bar(555.0));
    }
}
