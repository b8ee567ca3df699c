//! BxDFs with pbrt-v4's semantics (`src/pbrt/bxdfs.h`, `bxdfs.cpp`, `util/scattering.h`).
//!
//! Every function works in the local shading frame: the normal is +z, and both `wo` and `wi`
//! are unit vectors pointing away from the surface. `f` is the BSDF value (without the cosine
//! factor), `pdf` is the solid-angle density with which `sample_f` produces `wi`. Specular
//! lobes are Dirac deltas: `f` and `pdf` are zero for them and `sample_f` returns their value
//! and discrete probability with [`BxdfFlags::SPECULAR`] set, as in pbrt-v4.
//!
//! The models:
//! - [`DiffuseBxdf`]: Lambertian reflection, R/π.
//! - [`ConductorBxdf`]: smooth or Trowbridge-Reitz microfacet reflection with the complex
//!   Fresnel term, per RGB channel.
//! - [`DielectricBxdf`]: smooth or rough reflection and transmission at a real index of
//!   refraction.
//! - [`ThinDielectricBxdf`]: a thin slab with inter-reflection, specular only.
//! - [`DiffuseTransmissionBxdf`]: Lambertian reflection R/π and transmission T/π.
//! - [`HairBxdf`]: pbrt-v4's hair scattering model (a rough dielectric cylinder).
//! - [`CoatedDiffuseBxdf`] and [`CoatedConductorBxdf`]: pbrt-v4's `LayeredBxDF` with a
//!   dielectric coating over a diffuse or a conductor base, a stochastic evaluation by random
//!   walks between the two.
//!
//! [`Bxdf`] is the closed set of these models. Nothing here allocates.
//!
//! # Differences from pbrt-v4
//! - Light is RGB, not sampled spectra: conductor η and k are per RGB channel, and a
//!   dielectric has one real η (choosing it for a dispersive glass is the material's job).
//! - [`Bxdf`]'s methods add the guards of pbrt-v4's `BSDF` wrapper (see [`Bxdf`]); the
//!   models' own methods behave like pbrt-v4's BxDFs.
//! - [`CoatedDiffuseBxdf::sample_f`] and [`CoatedDiffuseBxdf::pdf`] accept any flags that
//!   include reflection (pbrt-v4 asserts `All`); the surface never transmits.
//! - The layered BxDF's generator is pbrt-v4's (PCG32 seeded by MurmurHash64A of the same
//!   bytes, with pbrt-v4's default `--seed` 0), but C++ leaves the order of the two `r()`
//!   calls in `Point2f(r(), r())` unspecified; nimbus draws them left to right.
//! - Kept on purpose for parity: the layered `f` estimate's inconsistent MIS weights (see
//!   [`CoatedDiffuseBxdf::f`]), and a rough dielectric with η = 1 reporting glossy flags
//!   while it passes light straight through.

mod conductor;
mod dielectric;
mod diffuse;
mod diffuse_transmission;
mod fresnel;
mod hair;
mod layered;
mod measured;
mod microfacet;
mod thin_dielectric;

#[cfg(test)]
pub(crate) mod testing;

use std::fmt;
use std::ops::{BitAnd, BitOr, BitOrAssign, Not};

use glam::{Vec2, Vec3};

use crate::channels::Channels;
use crate::color::Rgb;

pub use conductor::ConductorBxdf;
pub use dielectric::DielectricBxdf;
pub use diffuse::DiffuseBxdf;
pub use diffuse_transmission::DiffuseTransmissionBxdf;
pub use fresnel::{fr_complex, fr_complex_channels, fr_dielectric};
pub use hair::HairBxdf;
pub use layered::{CoatedConductorBase, CoatedConductorBxdf, CoatedDiffuseBxdf};
pub use measured::MeasuredBxdf;
pub use microfacet::TrowbridgeReitz;
pub use thin_dielectric::ThinDielectricBxdf;

/// What kinds of scattering a BxDF (or one of its samples) has: pbrt-v4's `BxDFFlags`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BxdfFlags(u8);

impl BxdfFlags {
    /// No scattering.
    pub const UNSET: BxdfFlags = BxdfFlags(0);
    /// Scattering into the hemisphere of `wo`.
    pub const REFLECTION: BxdfFlags = BxdfFlags(1);
    /// Scattering into the opposite hemisphere.
    pub const TRANSMISSION: BxdfFlags = BxdfFlags(2);
    /// A broad, diffuse lobe.
    pub const DIFFUSE: BxdfFlags = BxdfFlags(4);
    /// A glossy (non-delta, but possibly peaked) lobe.
    pub const GLOSSY: BxdfFlags = BxdfFlags(8);
    /// A Dirac delta lobe.
    pub const SPECULAR: BxdfFlags = BxdfFlags(16);
    /// Diffuse reflection.
    pub const DIFFUSE_REFLECTION: BxdfFlags = BxdfFlags(4 | 1);
    /// Diffuse transmission.
    pub const DIFFUSE_TRANSMISSION: BxdfFlags = BxdfFlags(4 | 2);
    /// Glossy reflection.
    pub const GLOSSY_REFLECTION: BxdfFlags = BxdfFlags(8 | 1);
    /// Glossy transmission.
    pub const GLOSSY_TRANSMISSION: BxdfFlags = BxdfFlags(8 | 2);
    /// Specular reflection.
    pub const SPECULAR_REFLECTION: BxdfFlags = BxdfFlags(16 | 1);
    /// Specular transmission.
    pub const SPECULAR_TRANSMISSION: BxdfFlags = BxdfFlags(16 | 2);
    /// Every flag.
    pub const ALL: BxdfFlags = BxdfFlags(31);

    /// The raw bits.
    #[inline]
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// True when every flag of `other` is set.
    #[inline]
    pub const fn contains(self, other: BxdfFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// True when some flag of `other` is set.
    #[inline]
    pub const fn intersects(self, other: BxdfFlags) -> bool {
        self.0 & other.0 != 0
    }

    /// True when no flag is set.
    #[inline]
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// pbrt-v4's `IsReflective`.
    #[inline]
    pub const fn is_reflective(self) -> bool {
        self.intersects(Self::REFLECTION)
    }

    /// pbrt-v4's `IsTransmissive`.
    #[inline]
    pub const fn is_transmissive(self) -> bool {
        self.intersects(Self::TRANSMISSION)
    }

    /// pbrt-v4's `IsDiffuse`.
    #[inline]
    pub const fn is_diffuse(self) -> bool {
        self.intersects(Self::DIFFUSE)
    }

    /// pbrt-v4's `IsGlossy`.
    #[inline]
    pub const fn is_glossy(self) -> bool {
        self.intersects(Self::GLOSSY)
    }

    /// pbrt-v4's `IsSpecular`.
    #[inline]
    pub const fn is_specular(self) -> bool {
        self.intersects(Self::SPECULAR)
    }

    /// pbrt-v4's `IsNonSpecular`: some diffuse or glossy lobe.
    #[inline]
    pub const fn is_non_specular(self) -> bool {
        self.intersects(BxdfFlags(4 | 8))
    }
}

impl BitOr for BxdfFlags {
    type Output = BxdfFlags;
    #[inline]
    fn bitor(self, rhs: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 | rhs.0)
    }
}

impl BitOrAssign for BxdfFlags {
    #[inline]
    fn bitor_assign(&mut self, rhs: BxdfFlags) {
        self.0 |= rhs.0;
    }
}

impl BitAnd for BxdfFlags {
    type Output = BxdfFlags;
    #[inline]
    fn bitand(self, rhs: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 & rhs.0)
    }
}

impl fmt::Debug for BxdfFlags {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("UNSET");
        }
        let names = [
            (Self::REFLECTION, "REFLECTION"),
            (Self::TRANSMISSION, "TRANSMISSION"),
            (Self::DIFFUSE, "DIFFUSE"),
            (Self::GLOSSY, "GLOSSY"),
            (Self::SPECULAR, "SPECULAR"),
        ];
        let mut first = true;
        for (flag, name) in names {
            if self.contains(flag) {
                if !first {
                    f.write_str(" | ")?;
                }
                f.write_str(name)?;
                first = false;
            }
        }
        Ok(())
    }
}

/// Which hemispheres `sample_f` and `pdf` may consider: pbrt-v4's `BxDFReflTransFlags`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct ReflTransFlags(u8);

impl ReflTransFlags {
    /// Neither (nothing can be sampled).
    pub const UNSET: ReflTransFlags = ReflTransFlags(0);
    /// Only reflection.
    pub const REFLECTION: ReflTransFlags = ReflTransFlags(1);
    /// Only transmission.
    pub const TRANSMISSION: ReflTransFlags = ReflTransFlags(2);
    /// Reflection and transmission.
    pub const ALL: ReflTransFlags = ReflTransFlags(3);

    /// True when reflection is allowed.
    #[inline]
    pub const fn reflection(self) -> bool {
        self.0 & 1 != 0
    }

    /// True when transmission is allowed.
    #[inline]
    pub const fn transmission(self) -> bool {
        self.0 & 2 != 0
    }
}

impl BitOr for ReflTransFlags {
    type Output = ReflTransFlags;
    #[inline]
    fn bitor(self, rhs: ReflTransFlags) -> ReflTransFlags {
        ReflTransFlags(self.0 | rhs.0)
    }
}

/// Whether a path carries radiance (from the camera) or importance (from lights). Only
/// transmission through an interface between different indices of refraction cares: radiance
/// is scaled by 1/η² there (pbrt-v4 §9.5, "non-symmetric scattering and refraction").
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum TransportMode {
    /// Paths traced from the camera.
    Radiance,
    /// Paths traced from lights.
    Importance,
}

impl Not for TransportMode {
    type Output = TransportMode;
    /// The adjoint mode (pbrt-v4's `!mode`).
    #[inline]
    fn not(self) -> TransportMode {
        match self {
            TransportMode::Radiance => TransportMode::Importance,
            TransportMode::Importance => TransportMode::Radiance,
        }
    }
}

/// A sampled direction with the BSDF value and density there: pbrt-v4's `BSDFSample`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample<C = Rgb> {
    /// BSDF value for (wo, wi); for specular samples the delta's weight divided by |cos θi|.
    pub f: C,
    /// Sampled incident direction (local frame, pointing away from the surface).
    pub wi: Vec3,
    /// Solid-angle density, or the discrete probability of a specular lobe.
    pub pdf: f32,
    /// The kind of lobe that was sampled.
    pub flags: BxdfFlags,
    /// Relative index of refraction along the path for transmission (η_t/η_i), else 1.
    pub eta: f32,
    /// True when `pdf` is only proportional to the density (stochastic layered BSDFs): use
    /// `f·|cos|/pdf` as the path weight, but evaluate `pdf()` for MIS.
    pub pdf_is_proportional: bool,
}

impl<C> BsdfSample<C> {
    /// A sample with η = 1 and an exact pdf.
    #[inline]
    pub fn new(f: C, wi: Vec3, pdf: f32, flags: BxdfFlags) -> BsdfSample<C> {
        BsdfSample { f, wi, pdf, flags, eta: 1.0, pdf_is_proportional: false }
    }

    /// A transmission sample that records the relative index of refraction.
    #[inline]
    pub fn with_eta(f: C, wi: Vec3, pdf: f32, flags: BxdfFlags, eta: f32) -> BsdfSample<C> {
        BsdfSample { eta, ..BsdfSample::new(f, wi, pdf, flags) }
    }

    /// True for reflection samples.
    #[inline]
    pub fn is_reflection(&self) -> bool {
        self.flags.is_reflective()
    }

    /// True for transmission samples.
    #[inline]
    pub fn is_transmission(&self) -> bool {
        self.flags.is_transmissive()
    }

    /// True for samples of a Dirac delta lobe.
    #[inline]
    pub fn is_specular(&self) -> bool {
        self.flags.is_specular()
    }
}

/// The closed set of BxDFs nimbus supports.
///
/// Its methods dispatch to the models and add the guards of pbrt-v4's `BSDF` wrapper
/// (`bsdf.h`), so callers never see degenerate samples: nothing scatters for a grazing
/// `wo` (z = 0), `sample_f` returns `None` when the BxDF has no lobe of the requested kinds,
/// and samples with zero f, zero pdf or a grazing `wi` are dropped. The models' own methods
/// keep pbrt-v4's BxDF-level behaviour.
#[derive(Clone, Debug, PartialEq)]
pub enum Bxdf<C = Rgb> {
    /// Lambertian reflection.
    Diffuse(DiffuseBxdf<C>),
    /// Metal.
    Conductor(ConductorBxdf<C>),
    /// Glass and other dielectric interfaces.
    Dielectric(DielectricBxdf),
    /// A thin dielectric slab.
    ThinDielectric(ThinDielectricBxdf),
    /// A dielectric coating over a diffuse base.
    CoatedDiffuse(CoatedDiffuseBxdf<C>),
    /// A dielectric coating over a conductor.
    CoatedConductor(CoatedConductorBxdf<C>),
    /// Lambertian reflection and transmission.
    DiffuseTransmission(DiffuseTransmissionBxdf<C>),
    /// Hair fibres.
    Hair(HairBxdf<C>),
    /// A measured BRDF (pbrt-v4's `.bsdf` tables).
    Measured(MeasuredBxdf<C>),
}

impl<C: Channels> Bxdf<C> {
    /// The BSDF value f(wo, wi). Zero for specular BxDFs.
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        if wo.z == 0.0 {
            return C::ZERO;
        }
        match self {
            Bxdf::Diffuse(b) => b.f(wo, wi, mode),
            Bxdf::Conductor(b) => b.f(wo, wi, mode),
            Bxdf::Dielectric(b) => b.f(wo, wi, mode),
            Bxdf::ThinDielectric(b) => b.f(wo, wi, mode),
            Bxdf::CoatedDiffuse(b) => b.f(wo, wi, mode),
            Bxdf::CoatedConductor(b) => b.f(wo, wi, mode),
            Bxdf::DiffuseTransmission(b) => b.f(wo, wi, mode),
            Bxdf::Hair(b) => b.f(wo, wi, mode),
            Bxdf::Measured(b) => b.f(wo, wi, mode),
        }
    }

    /// Whether [`Self::sample_f`] reads its lobe sample `uc`: BxDFs of one lobe do not.
    #[inline]
    pub fn reads_uc(&self) -> bool {
        !matches!(self, Bxdf::Diffuse(_) | Bxdf::Conductor(_) | Bxdf::Measured(_))
    }

    /// Samples an incident direction for `wo` from the uniform samples `uc` (lobe choice) and
    /// `u` (direction), restricted to `sample_flags`.
    #[inline]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        if wo.z == 0.0 || self.flags().bits() & sample_flags.0 == 0 {
            return None;
        }
        let s = match self {
            Bxdf::Diffuse(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::Conductor(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::Dielectric(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::ThinDielectric(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::CoatedDiffuse(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::CoatedConductor(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::DiffuseTransmission(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::Hair(b) => b.sample_f(wo, uc, u, mode, sample_flags),
            Bxdf::Measured(b) => b.sample_f(wo, uc, u, mode, sample_flags),
        }?;
        (!s.f.is_zero() && s.pdf != 0.0 && s.wi.z != 0.0).then_some(s)
    }

    /// Density with which [`Bxdf::sample_f`] returns `wi` (zero for specular lobes).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode, sample_flags: ReflTransFlags) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        match self {
            Bxdf::Diffuse(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::Conductor(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::Dielectric(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::ThinDielectric(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::CoatedDiffuse(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::CoatedConductor(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::DiffuseTransmission(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::Hair(b) => b.pdf(wo, wi, mode, sample_flags),
            Bxdf::Measured(b) => b.pdf(wo, wi, mode, sample_flags),
        }
    }

    /// The kinds of scattering this BxDF has.
    #[inline]
    pub fn flags(&self) -> BxdfFlags {
        match self {
            Bxdf::Diffuse(b) => b.flags(),
            Bxdf::Conductor(b) => b.flags(),
            Bxdf::Dielectric(b) => b.flags(),
            Bxdf::ThinDielectric(b) => b.flags(),
            Bxdf::CoatedDiffuse(b) => b.flags(),
            Bxdf::CoatedConductor(b) => b.flags(),
            Bxdf::DiffuseTransmission(b) => b.flags(),
            Bxdf::Hair(b) => b.flags(),
            Bxdf::Measured(b) => b.flags(),
        }
    }

    /// Roughens near-specular microfacet distributions (pbrt-v4's `Regularize`, used after a
    /// path has scattered diffusely when the integrator's `regularize` option is on).
    #[inline]
    pub fn regularize(&mut self) {
        match self {
            Bxdf::Diffuse(_)
            | Bxdf::ThinDielectric(_)
            | Bxdf::DiffuseTransmission(_)
            | Bxdf::Hair(_)
            | Bxdf::Measured(_) => {}
            Bxdf::Conductor(b) => b.regularize(),
            Bxdf::Dielectric(b) => b.regularize(),
            Bxdf::CoatedDiffuse(b) => b.regularize(),
            Bxdf::CoatedConductor(b) => b.regularize(),
        }
    }
}

impl<C: Channels> From<DiffuseBxdf<C>> for Bxdf<C> {
    fn from(b: DiffuseBxdf<C>) -> Bxdf<C> {
        Bxdf::Diffuse(b)
    }
}

impl<C: Channels> From<ConductorBxdf<C>> for Bxdf<C> {
    fn from(b: ConductorBxdf<C>) -> Bxdf<C> {
        Bxdf::Conductor(b)
    }
}

impl<C: Channels> From<DielectricBxdf> for Bxdf<C> {
    fn from(b: DielectricBxdf) -> Bxdf<C> {
        Bxdf::Dielectric(b)
    }
}

impl<C: Channels> From<ThinDielectricBxdf> for Bxdf<C> {
    fn from(b: ThinDielectricBxdf) -> Bxdf<C> {
        Bxdf::ThinDielectric(b)
    }
}

impl<C: Channels> From<CoatedDiffuseBxdf<C>> for Bxdf<C> {
    fn from(b: CoatedDiffuseBxdf<C>) -> Bxdf<C> {
        Bxdf::CoatedDiffuse(b)
    }
}

impl<C: Channels> From<CoatedConductorBxdf<C>> for Bxdf<C> {
    fn from(b: CoatedConductorBxdf<C>) -> Bxdf<C> {
        Bxdf::CoatedConductor(b)
    }
}

impl<C: Channels> From<DiffuseTransmissionBxdf<C>> for Bxdf<C> {
    fn from(b: DiffuseTransmissionBxdf<C>) -> Bxdf<C> {
        Bxdf::DiffuseTransmission(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_combine_and_query() {
        let f = BxdfFlags::REFLECTION | BxdfFlags::GLOSSY;
        assert_eq!(f, BxdfFlags::GLOSSY_REFLECTION);
        assert!(f.is_reflective() && f.is_glossy() && f.is_non_specular());
        assert!(!f.is_transmissive() && !f.is_specular() && !f.is_diffuse());
        assert!(BxdfFlags::ALL.contains(BxdfFlags::SPECULAR_TRANSMISSION));
        assert_eq!(format!("{:?}", BxdfFlags::SPECULAR_TRANSMISSION), "TRANSMISSION | SPECULAR");
        assert_eq!(format!("{:?}", BxdfFlags::UNSET), "UNSET");
        assert!(ReflTransFlags::ALL.reflection() && ReflTransFlags::ALL.transmission());
        assert!(!ReflTransFlags::REFLECTION.transmission());
        assert_eq!(ReflTransFlags::REFLECTION | ReflTransFlags::TRANSMISSION, ReflTransFlags::ALL);
        assert_eq!(!TransportMode::Radiance, TransportMode::Importance);
    }

    #[test]
    fn bxdf_applies_the_bsdf_guards() {
        let d = Bxdf::from(DiffuseBxdf::new(Rgb::splat(0.5)));
        let grazing = Vec3::X;
        assert_eq!(d.f(grazing, Vec3::Z, TransportMode::Radiance), Rgb::ZERO);
        assert_eq!(d.pdf(grazing, Vec3::Z, TransportMode::Radiance, ReflTransFlags::ALL), 0.0);
        let u = Vec2::splat(0.5);
        assert!(d.sample_f(grazing, 0.5, u, TransportMode::Radiance, ReflTransFlags::ALL).is_none());
        assert!(d.sample_f(Vec3::Z, 0.5, u, TransportMode::Radiance, ReflTransFlags::ALL).is_some());
        // No lobe of the requested kind, or nothing at all.
        let t = ReflTransFlags::TRANSMISSION;
        assert!(d.sample_f(Vec3::Z, 0.5, u, TransportMode::Radiance, t).is_none());
        let black = Bxdf::from(DiffuseBxdf::new(Rgb::ZERO));
        assert!(black.sample_f(Vec3::Z, 0.5, u, TransportMode::Radiance, ReflTransFlags::ALL).is_none());
        // A rough dielectric's sample through a grazing microfacet has D = 0: dropped here,
        // returned (with f = 0 and pdf = 0) by the model itself, as by pbrt-v4's BxDF.
        let glass = DielectricBxdf::new(1.0 / 1.33, TrowbridgeReitz::new(0.4, 0.4));
        let wo = Vec3::new(-0.6, -0.5, -0.4).normalize();
        let found = stratified_cells(256).find_map(|u| {
            glass
                .sample_f::<Rgb>(wo, 0.99, u, TransportMode::Radiance, ReflTransFlags::ALL)
                .filter(|s| s.pdf == 0.0)
                .map(|_| u)
        });
        let u = found.expect("some microfacet sample is grazing");
        let b: Bxdf = Bxdf::from(glass);
        assert!(b.sample_f(wo, 0.99, u, TransportMode::Radiance, ReflTransFlags::ALL).is_none());
    }

    fn stratified_cells(n: usize) -> impl Iterator<Item = Vec2> {
        (0..n * n).map(move |k| Vec2::new((k % n) as f32 + 0.999, (k / n) as f32 + 0.5) / n as f32)
    }
}
