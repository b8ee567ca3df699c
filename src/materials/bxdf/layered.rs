//! A dielectric coating over a base: pbrt-v4's `LayeredBxDF<DielectricBxDF, Base, twoSided =
//! true>` (pbrt-v4 §14.3; Guo et al. 2018, "Position-Free Monte Carlo Simulation for
//! Arbitrary Layered BSDFs"), instantiated as `CoatedDiffuseBxDF` (a diffuse base) and
//! `CoatedConductorBxDF` (a conductor base).
//!
//! The two interfaces are separated by a slab of thickness `thickness` filled with a medium
//! of unit extinction, single-scattering albedo `albedo` and Henyey-Greenstein asymmetry `g`.
//! `f`, `sample_f` and `pdf` are Monte Carlo estimates from random walks between the
//! interfaces. Each call seeds its own PCG32 generator from a hash of its arguments exactly as
//! pbrt-v4 does (`Hash(seed, wo)` with `Hash(wi)`, `Hash(uc, u)` or `Hash(wo)`), so repeated
//! calls with the same arguments give the same estimate.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::{BsdfSample, BxdfFlags, ConductorBxdf, DielectricBxdf, DiffuseBxdf, ReflTransFlags, TransportMode};
use crate::channels::Channels;
use crate::color::Rgb;
use crate::math::{abs_cos_theta, same_hemisphere};
use crate::media::phase::HenyeyGreenstein;
use crate::sampling::rng::{Pcg32, hash_sample, hash_seed_vec3, hash_vec3};
use crate::sampling::warp::{ONE_MINUS_EPSILON, power_heuristic};

/// pbrt-v4's `Options->seed` default, which it hashes into every layered-BSDF generator.
const PBRT_SEED: i32 = 0;

/// pbrt-v4 instantiates both coated BxDFs with `twoSided = true`: directions below the
/// surface are mirrored above it, so both faces show the coating.
const TWO_SIDED: bool = true;

/// The BxDF under the coating: what the random walks need of it.
pub trait LayerBase: Copy {
    /// The channels it scatters.
    type C: Channels;
    /// pbrt-v4's `f`.
    fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Self::C;
    /// pbrt-v4's `Sample_f`.
    fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        flags: ReflTransFlags,
    ) -> Option<BsdfSample<Self::C>>;
    /// pbrt-v4's `PDF`.
    fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode, flags: ReflTransFlags) -> f32;
    /// pbrt-v4's `Flags`.
    fn flags(&self) -> BxdfFlags;
    /// pbrt-v4's `Regularize`.
    fn regularize(&mut self);
}

impl<C: Channels> LayerBase for DiffuseBxdf<C> {
    type C = C;

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        DiffuseBxdf::f(self, wo, wi, mode)
    }
    #[inline]
    fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        DiffuseBxdf::sample_f(self, wo, uc, u, mode, flags)
    }
    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode, flags: ReflTransFlags) -> f32 {
        DiffuseBxdf::pdf(self, wo, wi, mode, flags)
    }
    #[inline]
    fn flags(&self) -> BxdfFlags {
        DiffuseBxdf::flags(self)
    }
    /// A diffuse base has nothing to roughen.
    #[inline]
    fn regularize(&mut self) {}
}

/// A dielectric coating over a diffuse base (pbrt-v4's `CoatedDiffuseBxDF`).
pub type CoatedDiffuseBxdf<C = Rgb> = LayeredBxdf<DiffuseBxdf<C>, C>;

/// A dielectric coating over a conductor (pbrt-v4's `CoatedConductorBxDF`); the conductor's
/// η and k are relative to the coating (the material divides them by its η).
pub type CoatedConductorBxdf<C = Rgb> = LayeredBxdf<CoatedConductorBase<C>, C>;

/// The conductor under a coating: η, k and roughness only. (A [`ConductorBxdf`]'s Fresnel
/// scale corrects an RGB fit of spectral constants at an air interface; under a coating of
/// another η that fit does not hold, and dropping it keeps every [`super::Bxdf`] smaller.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatedConductorBase<C = Rgb> {
    distrib: super::TrowbridgeReitz,
    eta: C,
    k: C,
}

impl<C: Channels> CoatedConductorBase<C> {
    /// The conductor `c` without its Fresnel scale.
    pub fn new(c: &ConductorBxdf<C>) -> CoatedConductorBase<C> {
        let (distrib, eta, k) = c.constants();
        CoatedConductorBase { distrib, eta, k }
    }

    /// The microfacet distribution.
    pub fn distribution(&self) -> &super::TrowbridgeReitz {
        &self.distrib
    }

    #[inline]
    fn bxdf(&self) -> ConductorBxdf<C> {
        ConductorBxdf::new(self.distrib, self.eta, self.k)
    }
}

impl<C: Channels> LayerBase for CoatedConductorBase<C> {
    type C = C;

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        self.bxdf().f(wo, wi, mode)
    }
    #[inline]
    fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        self.bxdf().sample_f(wo, uc, u, mode, flags)
    }
    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode, flags: ReflTransFlags) -> f32 {
        self.bxdf().pdf(wo, wi, mode, flags)
    }
    #[inline]
    fn flags(&self) -> BxdfFlags {
        self.bxdf().flags()
    }
    #[inline]
    fn regularize(&mut self) {
        self.distrib.regularize();
    }
}

/// A dielectric coating over the base `B`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayeredBxdf<B, C = Rgb> {
    top: DielectricBxdf,
    bottom: B,
    thickness: f32,
    albedo: C,
    g: f32,
    max_depth: u16,
    n_samples: u16,
}

/// One of the two interfaces of the layered BxDF (pbrt-v4's `TopOrBottomBxDF`).
#[derive(Clone, Copy)]
enum Interface<'a, B> {
    Top(&'a DielectricBxdf),
    Bottom(&'a B),
}

impl<B: LayerBase> Interface<'_, B> {
    #[inline]
    fn f(self, wo: Vec3, wi: Vec3, mode: TransportMode) -> B::C {
        match self {
            Interface::Top(b) => b.f(wo, wi, mode),
            Interface::Bottom(b) => b.f(wo, wi, mode),
        }
    }

    #[inline]
    fn sample_f(
        self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        flags: ReflTransFlags,
    ) -> Option<BsdfSample<B::C>> {
        match self {
            Interface::Top(b) => b.sample_f(wo, uc, u, mode, flags),
            Interface::Bottom(b) => b.sample_f(wo, uc, u, mode, flags),
        }
    }

    #[inline]
    fn pdf(self, wo: Vec3, wi: Vec3, mode: TransportMode, flags: ReflTransFlags) -> f32 {
        match self {
            Interface::Top(b) => b.pdf(wo, wi, mode, flags),
            Interface::Bottom(b) => b.pdf(wo, wi, mode, flags),
        }
    }

    #[inline]
    fn flags(self) -> BxdfFlags {
        match self {
            Interface::Top(b) => b.flags(),
            Interface::Bottom(b) => b.flags(),
        }
    }
}

/// pbrt-v4's test for a usable interface sample in the random walks.
#[inline]
fn usable<C: Channels>(s: &BsdfSample<C>) -> bool {
    !s.f.is_zero() && s.pdf != 0.0 && s.wi.z != 0.0
}

/// Transmittance of the unit-extinction slab medium over a vertical distance `dz` along `w`.
#[inline]
fn tr(dz: f32, w: Vec3) -> f32 {
    if dz.abs() <= f32::MIN_POSITIVE {
        return 1.0;
    }
    (-(dz / w.z).abs()).exp()
}

/// Samples a distance with density a·e^(−a·x) (pbrt-v4's `SampleExponential`).
#[inline]
fn sample_exponential(u: f32, a: f32) -> f32 {
    -(1.0 - u).ln() / a
}

/// The random number stream of one layered-BxDF call, clamped below 1 as pbrt-v4 does.
struct Stream(Pcg32);

impl Stream {
    #[inline]
    fn next(&mut self) -> f32 {
        self.0.uniform().min(ONE_MINUS_EPSILON)
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next();
        Vec2::new(x, self.next())
    }
}

impl<C: Channels, B: LayerBase<C = C>> LayeredBxdf<B, C> {
    /// A coating `top` over `bottom`, separated by a medium of the given `thickness`
    /// (clamped to the smallest positive float), `albedo` and asymmetry `g`; the walks stop
    /// after `max_depth` scattering events, and `f`/`pdf` average `n_samples` walks.
    pub fn new(
        top: DielectricBxdf,
        bottom: B,
        thickness: f32,
        albedo: C,
        g: f32,
        max_depth: u32,
        n_samples: u32,
    ) -> LayeredBxdf<B, C> {
        LayeredBxdf {
            top,
            bottom,
            thickness: thickness.max(f32::MIN_POSITIVE),
            albedo,
            g,
            max_depth: max_depth.min(u16::MAX as u32) as u16,
            n_samples: n_samples.min(u16::MAX as u32) as u16,
        }
    }

    /// The coating.
    pub fn top(&self) -> &DielectricBxdf {
        &self.top
    }

    /// The base.
    pub fn bottom(&self) -> &B {
        &self.bottom
    }

    /// Estimates f(wo, wi) from `n_samples` random walks that enter through `wo`'s interface
    /// and connect to `wi` by next-event estimation through the exit interface, with MIS
    /// between interface and phase-function sampling (pbrt-v4 §14.3, `LayeredBxDF::f`).
    ///
    /// As in pbrt-v4, the MIS weight of a walk direction that leaves through a rough exit uses
    /// the exit's density of sampling `wi` from inside, while next-event estimation sampled
    /// the inside direction from `wi`; the two densities differ for refraction, so the weights
    /// do not sum to one and a rough coating's estimate is biased high (by 3–11% of the
    /// albedo for α = 0.1–0.6 in the tests).
    /// nimbus keeps pbrt-v4's weights for image parity.
    // Out of line: the random walks are long, and inlined into `Bxdf`'s dispatch (once per
    // base) they would crowd the path loop's hot code.
    #[inline(never)]
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        self.f_estimate(wo, wi, mode, false)
    }

    /// [`LayeredBxdf::f`]; with `consistent_mis`, both MIS weights use the density with
    /// which next-event estimation samples the inside direction from `wi`, which makes the
    /// estimate unbiased (used by the tests to validate the walk).
    fn f_estimate(&self, wo: Vec3, wi: Vec3, mode: TransportMode, consistent_mis: bool) -> C {
        // Density of the exit's connection strategy for a walk direction w leaving through it.
        let exit_pdf = |exit: Interface<'_, B>, w: Vec3, wi: Vec3| {
            if consistent_mis {
                exit.pdf(wi, -w, !mode, ReflTransFlags::TRANSMISSION)
            } else {
                exit.pdf(-w, wi, mode, ReflTransFlags::TRANSMISSION)
            }
        };
        let (mut wo, mut wi) = (wo, wi);
        if TWO_SIDED && wo.z < 0.0 {
            wo = -wo;
            wi = -wi;
        }
        // The interface that wo enters, the one wi leaves through, and the exit's height.
        let entered_top = TWO_SIDED || wo.z > 0.0;
        let enter = if entered_top { Interface::Top(&self.top) } else { Interface::Bottom(&self.bottom) };
        let same = same_hemisphere(wo, wi);
        let (exit, non_exit) = if same ^ entered_top {
            (Interface::Bottom(&self.bottom), Interface::Top(&self.top))
        } else {
            (Interface::Top(&self.top), Interface::Bottom(&self.bottom))
        };
        let exit_z = if same ^ entered_top { 0.0 } else { self.thickness };
        let n_samples = self.n_samples as f32;

        // Reflection at the entrance interface.
        let mut f = C::ZERO;
        if same {
            f = enter.f(wo, wi, mode) * n_samples;
        }

        let mut r = Stream(Pcg32::new(hash_seed_vec3(PBRT_SEED, wo), hash_vec3(wi)));
        let phase = HenyeyGreenstein::new(self.g);
        let exit_specular = exit.flags().is_specular();
        let non_exit_specular = non_exit.flags().is_specular();

        for _ in 0..self.n_samples {
            // Transmission into the slab through the entrance...
            let uc = r.next();
            let wos = enter.sample_f(wo, uc, r.next_2d(), mode, ReflTransFlags::TRANSMISSION);
            let Some(wos) = wos.filter(usable) else {
                continue;
            };
            // ...and, for next-event estimation, the adjoint transmission in through wi.
            let uc = r.next();
            let wis = exit.sample_f(wi, uc, r.next_2d(), !mode, ReflTransFlags::TRANSMISSION);
            let Some(wis) = wis.filter(usable) else {
                continue;
            };

            let mut beta = wos.f * abs_cos_theta(wos.wi) / wos.pdf;
            let mut z = if entered_top { self.thickness } else { 0.0 };
            let mut w = wos.wi;

            for depth in 0..self.max_depth {
                // Russian roulette.
                if depth > 3 && beta.max_element() < 0.25 {
                    let q = (1.0 - beta.max_element()).max(0.0);
                    if r.next() < q {
                        break;
                    }
                    beta /= 1.0 - q;
                }

                if self.albedo.is_zero() {
                    // No scattering: cross to the other interface.
                    z = if z == self.thickness { 0.0 } else { self.thickness };
                    beta *= tr(self.thickness, w);
                } else {
                    // Sample a scattering distance in the unit-extinction medium.
                    let dz = sample_exponential(r.next(), 1.0 / w.z.abs());
                    let zp = if w.z > 0.0 { z + dz } else { z - dz };
                    if zp == z {
                        continue;
                    }
                    if 0.0 < zp && zp < self.thickness {
                        // Scattering inside: NEE through the exit along the presampled wis.
                        let wt = if exit_specular { 1.0 } else { power_heuristic(wis.pdf, phase.pdf(-w, -wis.wi)) };
                        f += beta * self.albedo * phase.p(-w, -wis.wi) * wt * tr(zp - exit_z, wis.wi) * wis.f / wis.pdf;
                        // Continue the walk with a phase-function sample.
                        let u = r.next_2d();
                        let Some(ps) = phase.sample_p(-w, u).filter(|ps| ps.pdf != 0.0 && ps.wi.z != 0.0) else {
                            continue;
                        };
                        beta *= self.albedo * ps.p / ps.pdf;
                        w = ps.wi;
                        z = zp;
                        // MIS companion: the phase sample may leave through the exit.
                        if ((z < exit_z && w.z > 0.0) || (z > exit_z && w.z < 0.0)) && !exit_specular {
                            let f_exit = exit.f(-w, wi, mode);
                            if !f_exit.is_zero() {
                                let wt = power_heuristic(ps.pdf, exit_pdf(exit, w, wi));
                                f += beta * tr(zp - exit_z, ps.wi) * f_exit * wt;
                            }
                        }
                        continue;
                    }
                    z = zp.clamp(0.0, self.thickness);
                }

                if z == exit_z {
                    // Internal reflection at the exit interface.
                    let uc = r.next();
                    let u = r.next_2d();
                    let Some(bs) = exit.sample_f(-w, uc, u, mode, ReflTransFlags::REFLECTION).filter(usable) else {
                        break;
                    };
                    beta *= bs.f * abs_cos_theta(bs.wi) / bs.pdf;
                    w = bs.wi;
                } else {
                    // Scattering at the other interface: NEE along wis first.
                    if !non_exit_specular {
                        let wt = if exit_specular {
                            1.0
                        } else {
                            power_heuristic(wis.pdf, non_exit.pdf(-w, -wis.wi, mode, ReflTransFlags::ALL))
                        };
                        f += beta
                            * non_exit.f(-w, -wis.wi, mode)
                            * abs_cos_theta(wis.wi)
                            * wt
                            * tr(self.thickness, wis.wi)
                            * wis.f
                            / wis.pdf;
                    }
                    // Then sample the next direction.
                    let uc = r.next();
                    let u = r.next_2d();
                    let Some(bs) = non_exit.sample_f(-w, uc, u, mode, ReflTransFlags::REFLECTION).filter(usable) else {
                        break;
                    };
                    beta *= bs.f * abs_cos_theta(bs.wi) / bs.pdf;
                    w = bs.wi;
                    // MIS companion: the sampled direction may leave through the exit.
                    if !exit_specular {
                        let f_exit = exit.f(-w, wi, mode);
                        if !f_exit.is_zero() {
                            let wt =
                                if non_exit_specular { 1.0 } else { power_heuristic(bs.pdf, exit_pdf(exit, w, wi)) };
                            f += beta * tr(self.thickness, bs.wi) * f_exit * wt;
                        }
                    }
                }
            }
        }
        f / n_samples
    }

    /// Samples a direction by a random walk through the layers (pbrt-v4 §14.3). The
    /// returned pdf is that of the whole path, so `pdf_is_proportional` is set: use
    /// f·|cos|/pdf as the weight and [`LayeredBxdf::pdf`] for MIS.
    ///
    /// pbrt-v4 only supports `ReflTransFlags::ALL` here; a coated diffuse surface only
    /// reflects, so nimbus treats `REFLECTION` like `ALL` and returns `None` without it.
    // Out of line: the random walks are long, and inlined into `Bxdf`'s dispatch (once per
    // base) they would crowd the path loop's hot code.
    #[inline(never)]
    pub fn sample_f(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        sample_flags: ReflTransFlags,
    ) -> Option<BsdfSample<C>> {
        if !sample_flags.reflection() {
            return None;
        }
        let mut wo = wo;
        let mut flip_wi = false;
        if TWO_SIDED && wo.z < 0.0 {
            wo = -wo;
            flip_wi = true;
        }

        // Sample the entrance interface; a reflection there is the final sample.
        let entered_top = TWO_SIDED || wo.z > 0.0;
        let bs = if entered_top {
            self.top.sample_f(wo, uc, u, mode, ReflTransFlags::ALL)
        } else {
            self.bottom.sample_f(wo, uc, u, mode, ReflTransFlags::ALL)
        };
        let mut bs = bs.filter(usable)?;
        if bs.is_reflection() {
            if flip_wi {
                bs.wi = -bs.wi;
            }
            bs.pdf_is_proportional = true;
            return Some(bs);
        }
        let mut w = bs.wi;
        let mut specular_path = bs.is_specular();

        let mut r = Stream(Pcg32::new(hash_seed_vec3(PBRT_SEED, wo), hash_sample(uc, u)));
        let mut f = bs.f * abs_cos_theta(bs.wi);
        let mut pdf = bs.pdf;
        let mut z = if entered_top { self.thickness } else { 0.0 };
        let phase = HenyeyGreenstein::new(self.g);

        for depth in 0..self.max_depth {
            // Russian roulette on the path's weight.
            let rr_beta = f.max_element() / pdf;
            if depth > 3 && rr_beta < 0.25 {
                let q = (1.0 - rr_beta).max(0.0);
                if r.next() < q {
                    return None;
                }
                pdf *= 1.0 - q;
            }
            if w.z == 0.0 {
                return None;
            }

            if !self.albedo.is_zero() {
                // Possibly scatter in the medium before reaching an interface.
                let dz = sample_exponential(r.next(), 1.0 / abs_cos_theta(w));
                let zp = if w.z > 0.0 { z + dz } else { z - dz };
                if zp == z {
                    return None;
                }
                if 0.0 < zp && zp < self.thickness {
                    let ps = phase.sample_p(-w, r.next_2d()).filter(|ps| ps.pdf != 0.0 && ps.wi.z != 0.0)?;
                    f *= self.albedo * ps.p;
                    pdf *= ps.pdf;
                    specular_path = false;
                    w = ps.wi;
                    z = zp;
                    continue;
                }
                z = zp.clamp(0.0, self.thickness);
            } else {
                z = if z == self.thickness { 0.0 } else { self.thickness };
                f *= tr(self.thickness, w);
            }

            let interface = if z == 0.0 { Interface::Bottom(&self.bottom) } else { Interface::Top(&self.top) };
            let uc = r.next();
            let u = r.next_2d();
            let bs = interface.sample_f(-w, uc, u, mode, ReflTransFlags::ALL).filter(usable)?;
            f *= bs.f;
            pdf *= bs.pdf;
            specular_path &= bs.is_specular();
            w = bs.wi;

            // Transmission through an interface leaves the layers.
            if bs.is_transmission() {
                let mut flags = if same_hemisphere(wo, w) { BxdfFlags::REFLECTION } else { BxdfFlags::TRANSMISSION };
                flags |= if specular_path { BxdfFlags::SPECULAR } else { BxdfFlags::GLOSSY };
                if flip_wi {
                    w = -w;
                }
                return Some(BsdfSample { f, wi: w, pdf, flags, eta: 1.0, pdf_is_proportional: true });
            }
            f *= abs_cos_theta(bs.wi);
        }
        None
    }

    /// An approximate density of [`LayeredBxdf::sample_f`] for MIS: the entrance
    /// reflection plus a stochastic estimate of the TRT (or TT) term, mixed with a uniform
    /// density as 0.9·estimate + 0.1/(4π) (pbrt-v4 §14.3, `LayeredBxDF::PDF`).
    // Out of line: the random walks are long, and inlined into `Bxdf`'s dispatch (once per
    // base) they would crowd the path loop's hot code.
    #[inline(never)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode, sample_flags: ReflTransFlags) -> f32 {
        if !sample_flags.reflection() {
            return 0.0;
        }
        let (mut wo, mut wi) = (wo, wi);
        if TWO_SIDED && wo.z < 0.0 {
            wo = -wo;
            wi = -wi;
        }
        let mut r = Stream(Pcg32::new(hash_seed_vec3(PBRT_SEED, wi), hash_vec3(wo)));
        let entered_top = TWO_SIDED || wo.z > 0.0;
        let n_samples = self.n_samples as f32;
        let same = same_hemisphere(wo, wi);
        let refl = ReflTransFlags::REFLECTION;
        let trans = ReflTransFlags::TRANSMISSION;
        let all = ReflTransFlags::ALL;
        let valid = |s: &BsdfSample<C>| !s.f.is_zero() && s.pdf > 0.0;

        let mut pdf_sum = 0.0;
        if same {
            pdf_sum += n_samples
                * if entered_top { self.top.pdf(wo, wi, mode, refl) } else { self.bottom.pdf(wo, wi, mode, refl) };
        }

        for _ in 0..self.n_samples {
            if same {
                // TRT: transmit in through wo and wi, reflect at the other interface.
                let (r_iface, t_iface) = if entered_top {
                    (Interface::Bottom(&self.bottom), Interface::Top(&self.top))
                } else {
                    (Interface::Top(&self.top), Interface::Bottom(&self.bottom))
                };
                let uc = r.next();
                let wos = t_iface.sample_f(wo, uc, r.next_2d(), mode, trans);
                let uc = r.next();
                let wis = t_iface.sample_f(wi, uc, r.next_2d(), !mode, trans);
                let (Some(wos), Some(wis)) = (wos.filter(valid), wis.filter(valid)) else {
                    continue;
                };
                if !t_iface.flags().is_non_specular() {
                    pdf_sum += r_iface.pdf(-wos.wi, -wis.wi, mode, all);
                } else {
                    // MIS estimate of the product of the three densities.
                    let uc = r.next();
                    let rs = r_iface.sample_f(-wos.wi, uc, r.next_2d(), mode, all);
                    let Some(rs) = rs.filter(valid) else {
                        continue;
                    };
                    if !r_iface.flags().is_non_specular() {
                        pdf_sum += t_iface.pdf(-rs.wi, wi, mode, all);
                    } else {
                        let r_pdf = r_iface.pdf(-wos.wi, -wis.wi, mode, all);
                        pdf_sum += power_heuristic(wis.pdf, r_pdf) * r_pdf;
                        let t_pdf = t_iface.pdf(-rs.wi, wi, mode, all);
                        pdf_sum += power_heuristic(rs.pdf, t_pdf) * t_pdf;
                    }
                }
            } else {
                // TT: transmit through both interfaces.
                let (to_iface, ti_iface) = if entered_top {
                    (Interface::Top(&self.top), Interface::Bottom(&self.bottom))
                } else {
                    (Interface::Bottom(&self.bottom), Interface::Top(&self.top))
                };
                let uc = r.next();
                let u = r.next_2d();
                let Some(wos) = to_iface.sample_f(wo, uc, u, mode, all).filter(|s| usable(s) && !s.is_reflection())
                else {
                    continue;
                };
                let uc = r.next();
                let u = r.next_2d();
                let Some(wis) = ti_iface.sample_f(wi, uc, u, !mode, all).filter(|s| usable(s) && !s.is_reflection())
                else {
                    continue;
                };
                pdf_sum += if to_iface.flags().is_specular() {
                    ti_iface.pdf(-wos.wi, wi, mode, all)
                } else if ti_iface.flags().is_specular() {
                    to_iface.pdf(wo, -wis.wi, mode, all)
                } else {
                    (to_iface.pdf(wo, -wis.wi, mode, all) + ti_iface.pdf(-wos.wi, wi, mode, all)) / 2.0
                };
            }
        }
        // Mix with a uniform density to stay robust where the estimate is poor.
        let uniform = 1.0 / (4.0 * PI);
        0.1 * uniform + 0.9 * (pdf_sum / n_samples)
    }

    /// Reflection; specular if the coating is; diffuse (the base), else glossy.
    pub fn flags(&self) -> BxdfFlags {
        let (top, bottom) = (self.top.flags(), self.bottom.flags());
        let mut flags = BxdfFlags::REFLECTION;
        if top.is_specular() {
            flags |= BxdfFlags::SPECULAR;
        }
        if top.is_diffuse() || bottom.is_diffuse() || !self.albedo.is_zero() {
            flags |= BxdfFlags::DIFFUSE;
        } else if top.is_glossy() || bottom.is_glossy() {
            flags |= BxdfFlags::GLOSSY;
        }
        if top.is_transmissive() && bottom.is_transmissive() {
            flags |= BxdfFlags::TRANSMISSION;
        }
        flags
    }

    /// Roughens both layers (pbrt-v4's `Regularize`).
    pub fn regularize(&mut self) {
        self.top.regularize();
        self.bottom.regularize();
    }
}

#[cfg(test)]
#[path = "layered_tests.rs"]
mod tests;
