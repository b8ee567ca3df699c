//! RGB color spaces as pbrt-v4's `RGBColorSpace` builds them: primaries, a white point taken
//! from the space's standard illuminant *spectrum*, and the XYZ↔RGB matrices that follow.

use std::sync::OnceLock;

use glam::{DMat3, DVec2, DVec3};
use nimbus_parser::ColorSpace;

use super::PiecewiseLinearSpectrum;
use super::cie::{CIE_Y_INTEGRAL, integrate_xyz};
use super::named::named_spectrum;
use crate::color::Rgb;

/// One RGB color space: where its primaries and white lie, and its matrices.
#[derive(Clone, Debug)]
pub struct RgbColorSpace {
    /// Which space this is.
    pub space: ColorSpace,
    /// Chromaticities (x, y) of the red, green and blue primaries.
    pub primaries: [DVec2; 3],
    /// Chromaticity (x, y) of the white point: that of `illuminant`.
    pub white: DVec2,
    /// The space's standard illuminant (D65, or ACES D60), normalised to luminance 1.
    pub illuminant: &'static PiecewiseLinearSpectrum,
    /// Linear RGB → XYZ; maps (1, 1, 1) to the illuminant's XYZ with Y = 1.
    pub xyz_from_rgb: DMat3,
    /// XYZ → linear RGB.
    pub rgb_from_xyz: DMat3,
}

impl RgbColorSpace {
    fn new(space: ColorSpace) -> RgbColorSpace {
        let (primaries, illuminant) = match space {
            ColorSpace::Srgb => ([(0.64, 0.33), (0.3, 0.6), (0.15, 0.06)], "stdillum-D65"),
            ColorSpace::DciP3 => ([(0.68, 0.32), (0.265, 0.69), (0.15, 0.06)], "stdillum-D65"),
            ColorSpace::Rec2020 => ([(0.708, 0.292), (0.170, 0.797), (0.131, 0.046)], "stdillum-D65"),
            ColorSpace::Aces2065_1 => ([(0.7347, 0.2653), (0.0, 1.0), (0.0001, -0.077)], "illum-acesD60"),
        };
        let primaries = primaries.map(|(x, y)| DVec2::new(x, y));
        let illuminant = named_spectrum(illuminant).expect("color space illuminant exists");
        // pbrt-v4 takes the white point from the illuminant spectrum, not from a published xy.
        let w = integrate_xyz(|l| illuminant.eval(l)) / CIE_Y_INTEGRAL;
        let white = DVec2::new(w.x, w.y) / (w.x + w.y + w.z);
        let w = xyz_from_xy(white);
        let rgb = DMat3::from_cols(xyz_from_xy(primaries[0]), xyz_from_xy(primaries[1]), xyz_from_xy(primaries[2]));
        let c = rgb.inverse() * w;
        let xyz_from_rgb = rgb * DMat3::from_diagonal(c);
        RgbColorSpace { space, primaries, white, illuminant, xyz_from_rgb, rgb_from_xyz: xyz_from_rgb.inverse() }
    }

    /// Linear RGB of `xyz`.
    pub fn rgb_from_xyz(&self, xyz: DVec3) -> DVec3 {
        self.rgb_from_xyz * xyz
    }

    /// XYZ of linear RGB `rgb`.
    pub fn xyz_from_rgb(&self, rgb: DVec3) -> DVec3 {
        self.xyz_from_rgb * rgb
    }

    /// Luminance (Y) of `rgb` in this space.
    pub fn luminance(&self, rgb: Rgb) -> f32 {
        self.xyz_from_rgb.row(1).dot(rgb.as_dvec3()) as f32
    }
}

/// XYZ with Y = 1 of chromaticity `xy`.
fn xyz_from_xy(xy: DVec2) -> DVec3 {
    DVec3::new(xy.x / xy.y, 1.0, (1.0 - xy.x - xy.y) / xy.y)
}

/// The color space `space`, built once.
pub fn rgb_color_space(space: ColorSpace) -> &'static RgbColorSpace {
    static SPACES: OnceLock<[RgbColorSpace; 4]> = OnceLock::new();
    let spaces = SPACES.get_or_init(|| {
        [ColorSpace::Srgb, ColorSpace::Rec2020, ColorSpace::Aces2065_1, ColorSpace::DciP3].map(RgbColorSpace::new)
    });
    match space {
        ColorSpace::Srgb => &spaces[0],
        ColorSpace::Rec2020 => &spaces[1],
        ColorSpace::Aces2065_1 => &spaces[2],
        ColorSpace::DciP3 => &spaces[3],
    }
}

/// Converts `rgb` from space `from` to space `to` keeping its XYZ: right for light, where
/// pbrt-v4 emits `rgb` times `from`'s illuminant and the film sees exactly that XYZ.
pub fn convert_rgb(rgb: Rgb, from: ColorSpace, to: ColorSpace) -> Rgb {
    if from == to {
        return rgb;
    }
    let xyz = rgb_color_space(from).xyz_from_rgb(rgb.as_dvec3());
    rgb_color_space(to).rgb_from_xyz(xyz).as_vec3()
}

/// Converts a reflectance-like `rgb` (albedo, σ, …) from space `from` to space `to` with a
/// Bradford chromatic adaptation between their white points, so (1, 1, 1) — a constant
/// spectrum in every space — stays (1, 1, 1). pbrt-v4 instead upsamples `rgb` to a smooth
/// spectrum in `from` and the film projects it; the adaptation approximates that.
pub fn convert_reflectance_rgb(rgb: Rgb, from: ColorSpace, to: ColorSpace) -> Rgb {
    if from == to {
        return rgb;
    }
    let (src, dst) = (rgb_color_space(from), rgb_color_space(to));
    let m = dst.rgb_from_xyz * bradford(src.white, dst.white) * src.xyz_from_rgb;
    (m * rgb.as_dvec3()).as_vec3()
}

/// XYZ → XYZ adaptation from white `src` to white `dst` (von Kries in Bradford's LMS, the
/// cone space pbrt-v4's `WhiteBalance` uses).
fn bradford(src: DVec2, dst: DVec2) -> DMat3 {
    let lms_from_xyz = DMat3::from_cols_array(&[
        0.8951, -0.7502, 0.0389, // column 1
        0.2664, 1.7135, -0.0685, // column 2
        -0.1614, 0.0367, 1.0296, // column 3
    ]);
    let s = lms_from_xyz * xyz_from_xy(src);
    let d = lms_from_xyz * xyz_from_xy(dst);
    lms_from_xyz.inverse() * DMat3::from_diagonal(d / s) * lms_from_xyz
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_mat_close(m: DMat3, rows: [[f64; 3]; 3], tol: f64) {
        for (r, row) in rows.iter().enumerate() {
            for (c, want) in row.iter().enumerate() {
                let got = m.row(r)[c];
                assert!((got - want).abs() < tol, "[{r}][{c}] {got} vs {want}\n{m}");
            }
        }
    }

    #[test]
    fn srgb_matrix_matches_the_published_one() {
        // IEC 61966-2-1 linear sRGB from XYZ, as given to 7 digits for the D65 white
        // (0.3127, 0.3290); pbrt-v4's white comes from the D65 spectrum and lands within 1e-4.
        let m = rgb_color_space(ColorSpace::Srgb).rgb_from_xyz;
        assert_mat_close(
            m,
            [
                [3.2404542, -1.5371385, -0.4985314],
                [-0.9692660, 1.8760108, 0.0415560],
                [0.0556434, -0.2040259, 1.0572252],
            ],
            1e-4,
        );
    }

    #[test]
    fn white_points() {
        let d65 = rgb_color_space(ColorSpace::Srgb).white;
        assert!((d65 - DVec2::new(0.3127, 0.3290)).abs().max_element() < 1e-4, "{d65}");
        let d60 = rgb_color_space(ColorSpace::Aces2065_1).white;
        assert!((d60 - DVec2::new(0.32168, 0.33767)).abs().max_element() < 3e-4, "{d60}");
    }

    #[test]
    fn white_maps_to_one_in_every_space() {
        for space in [ColorSpace::Srgb, ColorSpace::Rec2020, ColorSpace::Aces2065_1, ColorSpace::DciP3] {
            let cs = rgb_color_space(space);
            let w = cs.rgb_from_xyz(cs.xyz_from_rgb(DVec3::ONE));
            assert!((w - DVec3::ONE).abs().max_element() < 1e-12);
            let y = cs.xyz_from_rgb(DVec3::ONE).y;
            assert!((y - 1.0).abs() < 1e-12, "{space:?}: {y}");
            assert!((cs.luminance(Rgb::ONE) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn conversions_round_trip() {
        let c = Rgb::new(0.2, 0.5, 0.9);
        for (a, b) in [
            (ColorSpace::Srgb, ColorSpace::Rec2020),
            (ColorSpace::Srgb, ColorSpace::Aces2065_1),
            (ColorSpace::DciP3, ColorSpace::Aces2065_1),
        ] {
            let there = convert_rgb(c, a, b);
            assert!((convert_rgb(there, b, a) - c).abs().max_element() < 1e-5);
            let there = convert_reflectance_rgb(c, a, b);
            assert!((convert_reflectance_rgb(there, b, a) - c).abs().max_element() < 1e-5);
        }
    }

    #[test]
    fn reflectance_conversion_keeps_white_and_light_conversion_keeps_xyz() {
        let w = convert_reflectance_rgb(Rgb::ONE, ColorSpace::Aces2065_1, ColorSpace::Srgb);
        assert!((w - Rgb::ONE).abs().max_element() < 1e-5, "{w}");
        // ACES white light is D60: warmer than sRGB's D65 white.
        let l = convert_rgb(Rgb::ONE, ColorSpace::Aces2065_1, ColorSpace::Srgb);
        assert!(l.x > l.y && l.y > l.z, "{l}");
        let y = rgb_color_space(ColorSpace::Srgb).luminance(l);
        assert!((y - 1.0).abs() < 1e-5);
        // Within one white point (sRGB, Rec.2020 and P3 all use D65) both agree.
        let c = Rgb::new(0.3, 0.6, 0.1);
        let a = convert_rgb(c, ColorSpace::Srgb, ColorSpace::Rec2020);
        let b = convert_reflectance_rgb(c, ColorSpace::Srgb, ColorSpace::Rec2020);
        assert!((a - b).abs().max_element() < 1e-6);
    }
}
