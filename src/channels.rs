//! The channels light is carried in. nimbus transports either linear RGB in the film's
//! color space ([`Rgb`]) or pbrt-v4's sampled spectra (four wavelengths per path), chosen per
//! scene; everything that multiplies light — BSDFs, media, lights, the path loop — is
//! written once, generic over [`Channels`], and monomorphised for each representation. Above
//! both `color` (RGB) and `spectra`, which it joins.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, DivAssign, Index, Mul, MulAssign, Sub};

use crate::color::Rgb;
use nimbus_parser::ColorSpace;

use crate::spectra::{
    BlackbodyRgbTable, CIE_Y_INTEGRAL, N_SPECTRUM_SAMPLES, RgbRole, Sampled, SampledSpectrum, SampledWavelengths,
    SigmoidPolynomial, SigmoidTable, SpectrumValue, illuminant_table,
};

/// A value carried along light paths, one float per channel: RGB (three channels in the film's
/// color space) or sampled spectra (one channel per wavelength of the path). Arithmetic is per
/// channel. Each representation also says how to sample its wavelengths and how to evaluate
/// the scene's spectra at them, so code generic over `Channels` never asks which one it has.
pub trait Channels:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Mul<f32, Output = Self>
    + Div<f32, Output = Self>
    + AddAssign
    + MulAssign
    + DivAssign
    + MulAssign<f32>
    + DivAssign<f32>
    + Index<usize, Output = f32>
{
    /// The wavelengths a path carries (nothing for RGB).
    type Lambda: Copy + Debug + Send + Sync;

    /// Number of channels.
    const CHANNELS: usize;
    /// Zero in every channel.
    const ZERO: Self;
    /// One in every channel.
    const ONE: Self;
    /// Name of the representation, for `--stats` and image metadata.
    const NAME: &'static str;
    /// Whether [`Self::sample_lambda`] reads its sample (RGB has no wavelengths to draw).
    const SAMPLES_WAVELENGTHS: bool;

    /// `v` in every channel.
    fn splat(v: f32) -> Self;

    /// The wavelengths of a new camera path from one uniform sample (pbrt-v4 draws this
    /// sample first at every pixel sample; RGB draws it too, so both representations see the
    /// same random numbers after it).
    fn sample_lambda(u: f32) -> Self::Lambda;

    /// Wavelengths sampled uniformly over [min, max] nm (pbrt-v4's spectral film).
    fn sample_lambda_uniform(u: f32, min: f32, max: f32) -> Self::Lambda;

    /// Keeps only the first wavelength (pbrt-v4's `TerminateSecondary`, for dispersion).
    fn terminate_secondary(lambda: &mut Self::Lambda);

    /// The channel that drives distance sampling in chromatic media (spectral MIS) from a
    /// uniform sample: a random RGB channel, or pbrt-v4's first wavelength, already random.
    fn hero_channel(u: f32) -> usize;

    /// The scene spectrum `v` in these channels.
    fn eval(v: &SpectrumValue, lambda: &Self::Lambda) -> Self;

    /// A voxel's spectrum packed in four floats for this representation (see
    /// [`pack_voxel`]): RGB reads its first three, sampled spectra its sigmoid polynomial and
    /// scale.
    fn from_voxel(v: glam::Vec4, role: RgbRole, space: ColorSpace, lambda: &Self::Lambda) -> Self;

    /// The key under which voxel values converted by [`Channels::from_voxel`] may be
    /// memoised (the path's wavelengths as four lanes), or `None` where a conversion is just a
    /// load and memoising it would cost more than it saves.
    fn voxel_memo_key(lambda: &Self::Lambda) -> Option<glam::Vec4>;

    /// The path's wavelengths in nm (four lanes), or `None` for RGB, whose channels are
    /// (r, g, b): for tabulated spectral data with an RGB version of its own.
    fn wavelengths(lambda: &Self::Lambda) -> Option<glam::Vec4>;

    /// The channels in four lanes (the last ones zero), for memoised values.
    fn to_lanes(self) -> glam::Vec4;

    /// The inverse of [`Channels::to_lanes`].
    fn from_lanes(v: glam::Vec4) -> Self;

    /// A real index of refraction from the scene spectrum `eta`: the spectrum's value for RGB
    /// (pbrt-v3 style, read once at 550 nm), the first wavelength's value for sampled spectra,
    /// which then drop their other wavelengths if η varies (dispersion; pbrt-v4's
    /// `TerminateSecondary`). Zero becomes 1, as in pbrt-v4.
    fn eta(eta: &SpectrumValue, lambda: &mut Self::Lambda) -> f32;

    /// A per-texel or per-voxel RGB of color space `space`, standing for a spectrum of kind
    /// `role`, in these channels: RGB passes it through, sampled spectra convert it as
    /// pbrt-v4 does at lookup time.
    fn from_rgb(rgb: Rgb, role: RgbRole, space: ColorSpace, lambda: &Self::Lambda) -> Self;

    /// The blackbody at `t` K normalised to a peak of 1 (pbrt-v4's `BlackbodySpectrum`), as
    /// emission: RGB transport reads it from `table`, built for the scene's film.
    fn blackbody(t: f32, table: &BlackbodyRgbTable, lambda: &Self::Lambda) -> Self;

    /// Mean over channels.
    fn average(self) -> f32;
    /// Largest channel.
    fn max_element(self) -> f32;
    /// Smallest channel.
    fn min_element(self) -> f32;
    /// True when no channel is infinite or NaN.
    fn is_finite(self) -> bool;
    /// Per-channel maximum.
    fn max(self, o: Self) -> Self;
    /// Per-channel minimum.
    fn min(self, o: Self) -> Self;
    /// `f` applied to every channel.
    fn map(self, f: impl Fn(f32) -> f32) -> Self;
    /// `f` applied channel by channel to `self` and `o`.
    fn zip_map(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self;

    /// Each channel clamped to [lo, hi].
    #[inline]
    fn clamp(self, lo: f32, hi: f32) -> Self {
        self.max(Self::splat(lo)).min(Self::splat(hi))
    }

    /// e^(−x) per channel: transmittance for an optical depth.
    #[inline]
    fn exp_neg(self) -> Self {
        self.map(|x| (-x).exp())
    }

    /// True when every channel is zero.
    #[inline]
    fn is_zero(self) -> bool {
        self == Self::ZERO
    }
}

impl Channels for Rgb {
    type Lambda = ();

    const CHANNELS: usize = 3;
    const ZERO: Rgb = Rgb::ZERO;
    const ONE: Rgb = Rgb::ONE;
    const NAME: &'static str = "rgb";
    const SAMPLES_WAVELENGTHS: bool = false;

    #[inline]
    fn splat(v: f32) -> Rgb {
        Rgb::splat(v)
    }

    #[inline]
    fn sample_lambda(_u: f32) {}

    #[inline]
    fn sample_lambda_uniform(_u: f32, _min: f32, _max: f32) {}

    #[inline]
    fn terminate_secondary(_lambda: &mut ()) {}

    #[inline]
    fn hero_channel(u: f32) -> usize {
        ((u * 3.0) as usize).min(2)
    }

    #[inline]
    fn eval(v: &SpectrumValue, _lambda: &()) -> Rgb {
        v.rgb
    }

    #[inline]
    fn eta(eta: &SpectrumValue, _lambda: &mut ()) -> f32 {
        if eta.rgb.x == 0.0 { 1.0 } else { eta.rgb.x }
    }

    #[inline]
    fn from_rgb(rgb: Rgb, _role: RgbRole, _space: ColorSpace, _lambda: &()) -> Rgb {
        rgb
    }

    #[inline]
    fn from_voxel(v: glam::Vec4, _role: RgbRole, _space: ColorSpace, _lambda: &()) -> Rgb {
        v.truncate()
    }

    #[inline]
    fn voxel_memo_key(_lambda: &()) -> Option<glam::Vec4> {
        None
    }

    #[inline]
    fn wavelengths(_lambda: &()) -> Option<glam::Vec4> {
        None
    }

    #[inline]
    fn to_lanes(self) -> glam::Vec4 {
        self.extend(0.0)
    }

    #[inline]
    fn from_lanes(v: glam::Vec4) -> Rgb {
        v.truncate()
    }

    #[inline]
    fn blackbody(t: f32, table: &BlackbodyRgbTable, _lambda: &()) -> Rgb {
        table.lookup(t)
    }

    #[inline]
    fn average(self) -> f32 {
        (self.x + self.y + self.z) / 3.0
    }

    #[inline]
    fn max_element(self) -> f32 {
        Rgb::max_element(self)
    }

    #[inline]
    fn min_element(self) -> f32 {
        Rgb::min_element(self)
    }

    #[inline]
    fn is_finite(self) -> bool {
        Rgb::is_finite(self)
    }

    #[inline]
    fn max(self, o: Rgb) -> Rgb {
        Rgb::max(self, o)
    }

    #[inline]
    fn min(self, o: Rgb) -> Rgb {
        Rgb::min(self, o)
    }

    #[inline]
    fn map(self, f: impl Fn(f32) -> f32) -> Rgb {
        Rgb::new(f(self.x), f(self.y), f(self.z))
    }

    #[inline]
    fn exp_neg(self) -> Rgb {
        crate::math::exp4(-self.extend(0.0)).truncate()
    }

    #[inline]
    fn zip_map(self, o: Rgb, f: impl Fn(f32, f32) -> f32) -> Rgb {
        Rgb::new(f(self.x, o.x), f(self.y, o.y), f(self.z, o.z))
    }
}

impl Channels for SampledSpectrum {
    type Lambda = SampledWavelengths;

    const CHANNELS: usize = N_SPECTRUM_SAMPLES;
    const ZERO: SampledSpectrum = SampledSpectrum::ZERO;
    const ONE: SampledSpectrum = SampledSpectrum::ONE;
    const NAME: &'static str = "spectral";
    const SAMPLES_WAVELENGTHS: bool = true;

    #[inline]
    fn splat(v: f32) -> SampledSpectrum {
        SampledSpectrum::splat(v)
    }

    #[inline]
    fn sample_lambda(u: f32) -> SampledWavelengths {
        SampledWavelengths::sample_visible(u)
    }

    #[inline]
    fn sample_lambda_uniform(u: f32, min: f32, max: f32) -> SampledWavelengths {
        SampledWavelengths::sample_uniform_in(u, min, max)
    }

    #[inline]
    fn terminate_secondary(lambda: &mut SampledWavelengths) {
        lambda.terminate_secondary();
    }

    /// pbrt-v4's hero is the first wavelength, itself random.
    #[inline]
    fn hero_channel(_u: f32) -> usize {
        0
    }

    #[inline]
    fn eval(v: &SpectrumValue, lambda: &SampledWavelengths) -> SampledSpectrum {
        v.sampled.sample(lambda)
    }

    #[inline]
    fn eta(eta: &SpectrumValue, lambda: &mut SampledWavelengths) -> f32 {
        let e = eta.sampled.sample(lambda).x;
        if !eta.is_constant() {
            lambda.terminate_secondary();
        }
        if e == 0.0 { 1.0 } else { e }
    }

    #[inline]
    fn from_rgb(rgb: Rgb, role: RgbRole, space: ColorSpace, lambda: &SampledWavelengths) -> SampledSpectrum {
        rgb_spectrum(rgb, role, space).sample(lambda)
    }

    #[inline]
    fn from_voxel(v: glam::Vec4, role: RgbRole, space: ColorSpace, lambda: &SampledWavelengths) -> SampledSpectrum {
        // Empty voxels (most of a smoke grid) cost nothing.
        if v.w == 0.0 {
            return SampledSpectrum::ZERO;
        }
        let poly = SigmoidPolynomial { c0: v.x, c1: v.y, c2: v.z };
        let s = poly.eval4(lambda.lambda) * v.w;
        match role {
            RgbRole::Illuminant => s * illuminant_table(space).sample(lambda.lambda) * (1.0 / CIE_Y_INTEGRAL as f32),
            _ => s,
        }
    }

    /// A voxel's value depends on the wavelengths only (not on their densities, which change
    /// when secondary wavelengths terminate).
    #[inline]
    fn voxel_memo_key(lambda: &SampledWavelengths) -> Option<glam::Vec4> {
        Some(lambda.lambda)
    }

    #[inline]
    fn wavelengths(lambda: &SampledWavelengths) -> Option<glam::Vec4> {
        Some(lambda.lambda)
    }

    #[inline]
    fn to_lanes(self) -> glam::Vec4 {
        self
    }

    #[inline]
    fn from_lanes(v: glam::Vec4) -> SampledSpectrum {
        v
    }

    #[inline]
    fn blackbody(t: f32, _table: &BlackbodyRgbTable, lambda: &SampledWavelengths) -> SampledSpectrum {
        Sampled::blackbody(t).sample(lambda)
    }

    #[inline]
    fn average(self) -> f32 {
        self.element_sum() * 0.25
    }

    #[inline]
    fn max_element(self) -> f32 {
        SampledSpectrum::max_element(self)
    }

    #[inline]
    fn min_element(self) -> f32 {
        SampledSpectrum::min_element(self)
    }

    #[inline]
    fn is_finite(self) -> bool {
        SampledSpectrum::is_finite(self)
    }

    #[inline]
    fn max(self, o: SampledSpectrum) -> SampledSpectrum {
        SampledSpectrum::max(self, o)
    }

    #[inline]
    fn min(self, o: SampledSpectrum) -> SampledSpectrum {
        SampledSpectrum::min(self, o)
    }

    #[inline]
    fn map(self, f: impl Fn(f32) -> f32) -> SampledSpectrum {
        SampledSpectrum::new(f(self.x), f(self.y), f(self.z), f(self.w))
    }

    #[inline]
    fn exp_neg(self) -> SampledSpectrum {
        crate::math::exp4(-self)
    }

    #[inline]
    fn zip_map(self, o: SampledSpectrum, f: impl Fn(f32, f32) -> f32) -> SampledSpectrum {
        SampledSpectrum::new(f(self.x, o.x), f(self.y, o.y), f(self.z, o.z), f(self.w, o.w))
    }
}

/// The spectrum pbrt-v4 makes of a per-texel or per-voxel RGB (`RGBAlbedoSpectrum`,
/// `RGBUnboundedSpectrum`, `RGBIlluminantSpectrum`), its coefficients from the color space's
/// table. Illuminants are normalised so their film RGB is `rgb`, as RGB transport reads them.
#[inline]
pub fn rgb_spectrum(rgb: Rgb, role: RgbRole, space: ColorSpace) -> Sampled {
    let table = SigmoidTable::get(space);
    match role {
        RgbRole::Albedo => {
            Sampled::Sigmoid { poly: table.lookup(rgb.clamp(Rgb::ZERO, Rgb::ONE).to_array()), scale: 1.0 }
        }
        RgbRole::Unbounded | RgbRole::Illuminant => {
            let m = rgb.max_element();
            let poly = if m > 0.0 {
                table.lookup((rgb / (2.0 * m)).max(Rgb::ZERO).to_array())
            } else {
                SigmoidPolynomial::constant(0.0)
            };
            match role {
                RgbRole::Unbounded => Sampled::Sigmoid { poly, scale: 2.0 * m },
                _ => Sampled::Illuminant {
                    poly,
                    scale: 2.0 * m / CIE_Y_INTEGRAL as f32,
                    illuminant: illuminant_table(space),
                },
            }
        }
    }
}

/// A voxel's RGB `rgb` (color space `space`, kind `role`) packed in four floats for one
/// representation: `(r, g, b, 0)` for RGB transport (`rgb` already in film RGB), the sigmoid
/// polynomial and scale of its spectrum for sampled spectra, fitted once so lookups need no
/// table ([`Channels::from_voxel`] unpacks it).
pub fn pack_voxel(rgb: Rgb, role: RgbRole, space: ColorSpace, spectral: bool) -> glam::Vec4 {
    if !spectral {
        return rgb.extend(0.0);
    }
    match rgb_spectrum(rgb, role, space) {
        Sampled::Sigmoid { poly, scale } => glam::Vec4::new(poly.c0, poly.c1, poly.c2, scale),
        Sampled::Illuminant { poly, scale, .. } => {
            glam::Vec4::new(poly.c0, poly.c1, poly.c2, scale * CIE_Y_INTEGRAL as f32)
        }
        other => unreachable!("rgb_spectrum makes sigmoid spectra, not {other:?}"),
    }
}
