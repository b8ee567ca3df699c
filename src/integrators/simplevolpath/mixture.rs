//! The mixture density of the paper's §3 ("Directional Sampling"). At a scattering vertex
//! one direction ω' is drawn from
//!
//! ```text
//! p(ω') = c_s p_s(ω') + c_l p_l(ω') + c_e p_e(ω')
//! ```
//!
//! - p_s: the BSDF's sampling density, or the phase function's inside a medium (Eq. 5);
//! - p_l: the luminaires: one chosen in proportion to its power, then a point on it, as a
//!   density per solid angle ([`crate::lights::Light::sample_li`]);
//! - p_e: the environment by luminance ([`crate::lights::EnvironmentMap`]), or the uniform
//!   sphere for a constant environment,
//!
//! and Equation 2 divides by the whole p(ω'), every component evaluated at ω' whichever one
//! drew it: the densities overlap (a glossy lobe and a bright patch of sky, a phase function
//! and a lamp), which is the paper's point about evaluating p_1 and p_2 "regardless of which
//! distribution the sample is taken from". One number R picks the component and, rescaled
//! (the paper's `R = 2R`), drives it, so stratification of R carries over.
//!
//! # The luminaire density without shadow rays
//!
//! As a density over directions, p_l(ω') = Σ_i P(i) p_i(ω') would need the ray's intersection
//! with every light, behind whatever blocks it. The path traces the continuation ray anyway,
//! so p_l is evaluated where that ray arrives: p_l*(ω') = P(i) p_i(ω') for the light i whose
//! surface is the ray's first event (0 when a surface, a medium 'hit' or nothing comes first).
//! p_l* is not the density of light sampling (that one ignores occluders), so dividing by
//! c_s p_s + c_l p_l* + c_e p_e is the one-sample multiple importance sampling estimator of
//! Veach (1997, §9.2.4) with balance weights w_k = c_k p_k*/Σ_j c_j p_j*, one technique per
//! light. Those weights sum to 1 for every direction and every outcome of the probabilistic
//! intersection, and the estimator is unbiased, provided a light sample whose ray does not
//! reach the sampled point first gets weight 0: [`Mixture::pdf_along`] returns `None` for it
//! and the path ends there. Where nothing blocks the light, p_l* = p_l and the estimator is
//! exactly the paper's mixture estimator (the unit tests check it integrates to 1 and matches
//! the sampled directions).

use glam::{Vec2, Vec3};

use super::settings::SimpleVolPathSettings;
use crate::accel::{Hit, NONE};
use crate::channels::Channels;
use crate::color::Rgb;
use crate::lights::{LightContext, LightKind};
use crate::materials::bxdf::{Bxdf, ReflTransFlags, TransportMode};
use crate::math::Frame;
use crate::media::phase::HenyeyGreenstein;
use crate::sampling::distribution::AliasTable;
use crate::sampling::warp::ONE_MINUS_EPSILON;
use crate::scene::Scene;

/// The mixture coefficients c_s, c_l, c_e at a vertex; they sum to 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// BSDF or phase function.
    pub scatter: f32,
    /// Luminaires.
    pub light: f32,
    /// Environment.
    pub env: f32,
}

impl Weights {
    /// The degenerate mixture: the BSDF or phase function alone.
    pub const SCATTER_ONLY: Weights = Weights { scatter: 1.0, light: 0.0, env: 0.0 };
}

/// What scatters at a vertex: the source of p_s, and of the ρ cos θ' (Eq. 2) or Λ p (Eq. 5)
/// factor.
#[derive(Clone, Copy, Debug)]
pub enum Scatterer<'a, C = Rgb> {
    /// A BSDF in its shading frame; `wo` is local.
    Surface {
        /// The BSDF.
        bxdf: &'a Bxdf<C>,
        /// Shading frame.
        frame: Frame,
        /// Direction towards the previous vertex, in the shading frame.
        wo: Vec3,
    },
    /// A phase function; `wo` points towards the previous vertex.
    Medium {
        /// Henyey-Greenstein phase function.
        phase: HenyeyGreenstein,
        /// Direction towards the previous vertex.
        wo: Vec3,
    },
}

/// A direction drawn from p_s.
#[derive(Clone, Copy, Debug)]
pub struct ScatterSample<C = Rgb> {
    /// Direction (world space).
    pub wi: Vec3,
    /// ρ·|cos θ'| or the phase function value.
    pub f: C,
    /// Its density, or the discrete probability of a specular lobe.
    pub pdf: f32,
    /// True for a sample of a Dirac delta lobe.
    pub specular: bool,
    /// Relative index of refraction for transmission samples, else 1.
    pub eta: f32,
}

impl<C: Channels> Scatterer<'_, C> {
    /// ρ(ω, ω')·|cos θ'| at a surface or p(ω, ω') in a medium, and p_s(ω').
    #[inline]
    pub fn eval(&self, wi: Vec3) -> (C, f32) {
        match self {
            Scatterer::Surface { bxdf, frame, wo } => {
                let wl = frame.to_local(wi);
                let f = bxdf.f(*wo, wl, TransportMode::Radiance) * wl.z.abs();
                (f, bxdf.pdf(*wo, wl, TransportMode::Radiance, ReflTransFlags::ALL))
            }
            Scatterer::Medium { phase, wo } => {
                let p = phase.p(*wo, wi);
                (C::splat(p), phase.pdf(*wo, wi))
            }
        }
    }

    /// Draws ω' from p_s with `uc` (lobe choice) and `u`.
    #[inline]
    pub fn sample(&self, uc: f32, u: Vec2) -> Option<ScatterSample<C>> {
        match self {
            Scatterer::Surface { bxdf, frame, wo } => {
                let bs = bxdf.sample_f(*wo, uc, u, TransportMode::Radiance, ReflTransFlags::ALL)?;
                Some(ScatterSample {
                    wi: frame.to_world(bs.wi),
                    f: bs.f * bs.wi.z.abs(),
                    pdf: bs.pdf,
                    specular: bs.is_specular(),
                    eta: if bs.is_transmission() { bs.eta } else { 1.0 },
                })
            }
            Scatterer::Medium { phase, wo } => {
                let ps = phase.sample_p(*wo, u)?;
                Some(ScatterSample { wi: ps.wi, f: C::splat(ps.p), pdf: ps.pdf, specular: false, eta: 1.0 })
            }
        }
    }

    /// Whether other densities may be mixed in. Not for purely specular BSDFs (the mixture
    /// degenerates to the BSDF: no other density can produce a delta direction), nor for the
    /// coated (layered) BSDFs, whose `f` and `pdf` are stochastic estimates (Eq. 2 needs the exact
    /// density; its own sample weight f/pdf is unbiased, so it is sampled alone).
    #[inline]
    pub fn mixes(&self) -> bool {
        match self {
            Scatterer::Surface { bxdf, .. } => {
                bxdf.flags().is_non_specular() && !matches!(bxdf, Bxdf::CoatedDiffuse(_) | Bxdf::CoatedConductor(_))
            }
            Scatterer::Medium { .. } => true,
        }
    }

    /// Whether there is a non-delta part that a connection to a delta light can evaluate.
    #[inline]
    pub fn is_non_specular(&self) -> bool {
        match self {
            Scatterer::Surface { bxdf, .. } => bxdf.flags().is_non_specular(),
            Scatterer::Medium { .. } => true,
        }
    }
}

/// Which density drew a direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Component {
    /// p_s.
    Scatter,
    /// p_l: scene light `light`, at point `p` on it.
    Light {
        /// Index into `Scene::lights`.
        light: u32,
        /// The sampled point.
        p: Vec3,
    },
    /// p_e.
    Environment,
}

/// A direction drawn from the mixture, with what Equation 2 needs except the luminaire
/// density, which depends on where the ray goes ([`Mixture::pdf_along`]).
#[derive(Clone, Copy, Debug)]
pub struct MixtureSample<C = Rgb> {
    /// Direction (world space).
    pub wi: Vec3,
    /// The density that drew it.
    pub component: Component,
    /// ρ·|cos θ'| or the phase function value at `wi`.
    pub f: C,
    /// p_s(wi) (the discrete probability for a specular sample).
    pub scatter_pdf: f32,
    /// True for a specular sample of p_s.
    pub specular: bool,
    /// Relative index of refraction when p_s sampled transmission, else 1.
    pub eta: f32,
    /// The coefficients used at this vertex.
    pub weights: Weights,
}

/// The densities a scene offers and their coefficients.
#[derive(Clone, Debug)]
pub struct Mixture {
    /// c_s, c_l, c_e renormalised over the densities the scene has.
    base: Weights,
    /// Area lights by power, indexed like `Scene::lights` (other lights weigh 0).
    lights: Option<AliasTable>,
    /// Infinite lights by power, indexed like `Scene::lights`.
    envs: Option<AliasTable>,
}

/// A table over all scene lights with the given weights, or `None` when all are zero.
fn table(weights: &[f32]) -> Option<AliasTable> {
    weights.iter().any(|w| *w > 0.0).then(|| AliasTable::new(weights))
}

impl Mixture {
    /// The mixture for `scene`: luminaires are its area lights, the environment its infinite
    /// lights (each chosen in proportion to power). A density the scene lacks gets weight 0
    /// and the others are renormalised; if every remaining weight is 0, p_s is used alone.
    pub fn new(scene: &Scene, s: &SimpleVolPathSettings) -> Mixture {
        let power = |keep: fn(&LightKind) -> bool| -> Vec<f32> {
            scene.lights.iter().map(|l| if keep(&l.kind) { l.power(&scene.sphere) } else { 0.0 }).collect()
        };
        let lights = table(&power(|k| matches!(k, LightKind::Area { .. })));
        let envs = table(&power(|k| {
            matches!(k, LightKind::UniformInfinite { .. } | LightKind::ImageInfinite(_) | LightKind::PortalInfinite(_))
        }));
        let light = if lights.is_some() { s.light_fraction } else { 0.0 };
        let env = if envs.is_some() { s.env_fraction } else { 0.0 };
        let sum = s.bsdf_fraction + light + env;
        let base = if sum > 0.0 {
            Weights { scatter: s.bsdf_fraction / sum, light: light / sum, env: env / sum }
        } else {
            Weights::SCATTER_ONLY
        };
        Mixture { base, lights, envs }
    }

    /// The coefficients in the scene (before degenerating at specular vertices).
    #[cfg(test)]
    pub fn base_weights(&self) -> Weights {
        self.base
    }

    /// The coefficients at a vertex, the other densities' shares scaled by `mix` ∈ [0, 1]
    /// (1: the scene's coefficients; 0: the BSDF or phase function alone; below 1 where the
    /// path's throughput has risen above 1, see `tracer.rs`).
    #[inline]
    pub fn weights<C: Channels>(&self, sc: &Scatterer<'_, C>, mix: f32) -> Weights {
        if mix <= 0.0 || !sc.mixes() {
            return Weights::SCATTER_ONLY;
        }
        if mix >= 1.0 {
            return self.base;
        }
        let (light, env) = (self.base.light * mix, self.base.env * mix);
        Weights { scatter: 1.0 - light - env, light, env }
    }

    /// Draws ω' from p (the paper's 1D example: `u_comp` picks a density and, rescaled to
    /// [0, 1), drives it together with `u`). `None` when the chosen density has nothing to
    /// offer here (e.g. the back of a one-sided light): that sample contributes nothing, and
    /// the densities below count only what can be drawn. `mix` as for [`Mixture::weights`].
    #[allow(clippy::too_many_arguments)]
    pub fn sample<C: Channels>(
        &self,
        scene: &Scene,
        x: Vec3,
        sc: &Scatterer<'_, C>,
        mix: f32,
        u_comp: f32,
        u: Vec2,
        lambda: &C::Lambda,
    ) -> Option<MixtureSample<C>> {
        let w = self.weights(sc, mix);
        let rescale = |lo: f32, c: f32| ((u_comp - lo) / c).clamp(0.0, ONE_MINUS_EPSILON);
        if u_comp < w.scatter {
            let s = sc.sample(rescale(0.0, w.scatter), u)?;
            return Some(MixtureSample {
                wi: s.wi,
                component: Component::Scatter,
                f: s.f,
                scatter_pdf: s.pdf,
                specular: s.specular,
                eta: s.eta,
                weights: w,
            });
        }
        let ctx = LightContext { p: x };
        let (component, wi) = if w.env == 0.0 || (w.light > 0.0 && u_comp < w.scatter + w.light) {
            let pick = self.lights.as_ref()?.sample(rescale(w.scatter, w.light))?;
            let ls = scene.lights[pick.index].sample_li::<C>(&ctx, u, &scene.surfaces, &scene.sphere, lambda)?;
            (Component::Light { light: pick.index as u32, p: ls.p }, ls.wi)
        } else {
            let pick = self.envs.as_ref()?.sample(rescale(w.scatter + w.light, w.env))?;
            let ls = scene.lights[pick.index].sample_li::<C>(&ctx, u, &scene.surfaces, &scene.sphere, lambda)?;
            (Component::Environment, ls.wi)
        };
        let (f, scatter_pdf) = sc.eval(wi);
        Some(MixtureSample { wi, component, f, scatter_pdf, specular: false, eta: 1.0, weights: w })
    }

    /// p_e(ω'): Σ over infinite lights of P(light) × its density. Exact everywhere: the
    /// environment's density does not depend on the geometry.
    #[inline]
    pub fn env_pdf(&self, scene: &Scene, wi: Vec3) -> f32 {
        let Some(t) = &self.envs else { return 0.0 };
        let mut pdf = 0.0;
        for &i in &scene.infinite_lights {
            let pmf = t.pmf(i as usize);
            if pmf > 0.0 {
                pdf += pmf
                    * scene.lights[i as usize].pdf_li(
                        &LightContext { p: Vec3::ZERO },
                        wi,
                        None,
                        &scene.surfaces.shapes,
                    );
            }
        }
        pdf
    }

    /// p_l*(ω') for the ray from `x` along `wi` whose first event is the surface `first`
    /// (`None` for a medium 'hit' or an escape): P(i) p_i(ω') when `first` is a point of light
    /// i that emits towards `x` (`sample_li` never returns other points), else 0.
    #[inline]
    pub fn light_pdf(&self, scene: &Scene, x: Vec3, wi: Vec3, first: Option<&Hit>) -> f32 {
        let (Some(t), Some(h)) = (&self.lights, first) else { return 0.0 };
        if h.prim.area_light == NONE {
            return 0.0;
        }
        let i = h.prim.area_light as usize;
        let pmf = t.pmf(i);
        let light = &scene.lights[i];
        if pmf == 0.0 || !light.emits(&h.surface, -wi, &scene.surfaces) {
            return 0.0;
        }
        pmf * light.pdf_li(&LightContext { p: x }, wi, Some(&h.surface), &scene.surfaces.shapes)
    }

    /// Equation 2's p(ω') for an arbitrary direction, every component evaluated, given the
    /// ray's first event (`first`, as for [`Mixture::light_pdf`]). The tests check it against
    /// the sampled directions; the shading loop uses [`Mixture::pdf_along`], which reuses the
    /// sample's p_s.
    #[cfg(test)]
    pub fn pdf_at<C: Channels>(
        &self,
        scene: &Scene,
        x: Vec3,
        sc: &Scatterer<'_, C>,
        wi: Vec3,
        first: Option<&Hit>,
    ) -> f32 {
        let w = self.weights(sc, 1.0);
        let light = if w.light > 0.0 { self.light_pdf(scene, x, wi, first) } else { 0.0 };
        let env = if w.env > 0.0 { self.env_pdf(scene, wi) } else { 0.0 };
        w.scatter * sc.eval(wi).1 + w.light * light + w.env * env
    }

    /// Equation 2's p(ω') for a sample from [`Mixture::sample`] whose ray from `x` met
    /// `first` first; `None` when the sample has weight 0: a luminaire sample whose ray does
    /// not reach the sampled point before anything else (see the module notes).
    #[inline]
    pub fn pdf_along<C: Channels>(
        &self,
        scene: &Scene,
        x: Vec3,
        s: &MixtureSample<C>,
        first: Option<&Hit>,
    ) -> Option<f32> {
        let w = s.weights;
        if s.specular {
            // A delta direction: only p_s can produce it, chosen with probability c_s.
            return Some(w.scatter * s.scatter_pdf);
        }
        if let Component::Light { light, p } = s.component {
            let h = first?;
            let reached =
                h.prim.area_light == light && h.surface.p.distance_squared(p) <= 1e-6 * x.distance_squared(p).max(1e-6);
            if !reached {
                return None;
            }
        }
        let light = if w.light > 0.0 { self.light_pdf(scene, x, s.wi, first) } else { 0.0 };
        let env = if w.env > 0.0 { self.env_pdf(scene, s.wi) } else { 0.0 };
        Some(w.scatter * s.scatter_pdf + w.light * light + w.env * env)
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use glam::{Affine3A, Vec2, Vec3};

    use super::*;
    use crate::geometry::Ray;
    use crate::imageio::Image;
    use crate::lights::EnvironmentMap;
    use crate::materials::bxdf::DiffuseBxdf;
    use crate::materials::bxdf::testing::integrate_sphere;
    use crate::sampling::chi_square::{TestRng, chi_square_test};
    use crate::scene::BuildOptions;

    /// Lights around the origin in empty space: a quad and a sphere light (different powers)
    /// and an environment image with a bright patch, so all three densities overlap.
    fn scene() -> Scene {
        let text = r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective"
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-1 2 -1  1 2 -1  1 2 1  -1 2 1]
AttributeEnd
AttributeBegin
  Translate 1.5 -1 0.5
  AreaLightSource "diffuse" "rgb L" [9 9 9]
  Shape "sphere" "float radius" 0.5
AttributeEnd"#;
        let desc = nimbus_parser::load_str(text, "mixture.pbrt").unwrap();
        let mut s = crate::setup::build(&desc, &BuildOptions::default()).unwrap().scene;
        let mut img = Image::new(16, 16);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = Rgb::splat(if (k % 16) < 4 && k / 16 < 5 { 40.0 } else { 0.5 + (k % 7) as f32 * 0.1 });
        }
        let env = &scene_env_index(&s);
        s.lights[*env].kind = LightKind::ImageInfinite(Box::new(
            EnvironmentMap::new(&img, nimbus_parser::ColorSpace::Srgb, Affine3A::from_rotation_x(0.7), 1.0).unwrap(),
        ));
        s
    }

    fn scene_env_index(s: &Scene) -> usize {
        s.infinite_lights[0] as usize
    }

    /// The ray's first surface from `x` (the scene is empty apart from the lights).
    fn first_hit(s: &Scene, x: Vec3, wi: Vec3) -> Option<Hit> {
        s.surfaces.intersect(&Ray::new(x, wi), f32::INFINITY)
    }

    fn mixture(s: &Scene) -> Mixture {
        Mixture::new(s, &SimpleVolPathSettings::default())
    }

    /// A medium vertex and a diffuse surface vertex facing both lights.
    fn with_scatterers(test: impl Fn(&Scatterer<'_>)) {
        let wo = Vec3::new(0.3, -0.2, 0.9).normalize();
        test(&Scatterer::Medium { phase: HenyeyGreenstein::new(0.6), wo });
        let bxdf = Bxdf::Diffuse(DiffuseBxdf::new(Rgb::splat(0.8)));
        let frame = Frame::from_z(Vec3::new(0.2, 0.9, 0.3).normalize());
        test(&Scatterer::Surface { bxdf: &bxdf, frame, wo: frame.to_local(wo) });
    }

    #[test]
    fn weights_renormalise_over_the_densities_a_scene_has() {
        let s = scene();
        assert_eq!(mixture(&s).base_weights(), Weights { scatter: 0.6, light: 0.2, env: 0.2 });
        let mut no_env = scene();
        no_env.lights.retain(|l| !l.is_infinite());
        no_env.infinite_lights.clear();
        assert_eq!(mixture(&no_env).base_weights(), Weights { scatter: 0.75, light: 0.25, env: 0.0 });
        let mut nothing = scene();
        nothing.lights.clear();
        nothing.infinite_lights.clear();
        let only_lights = SimpleVolPathSettings { bsdf_fraction: 0.0, ..Default::default() };
        assert_eq!(Mixture::new(&nothing, &only_lights).base_weights(), Weights::SCATTER_ONLY);
    }

    /// ∫ p(ω) dω = 1 over the sphere, with p evaluated from the ray's first hit.
    #[test]
    fn mixture_pdf_integrates_to_one() {
        let s = scene();
        let m = mixture(&s);
        let x = Vec3::new(0.2, 0.1, -0.3);
        with_scatterers(|sc| {
            let integral =
                integrate_sphere(512, 1024, |wi| m.pdf_at(&s, x, sc, wi, first_hit(&s, x, wi).as_ref()) as f64);
            assert!((integral - 1.0).abs() < 5e-3, "{sc:?}: ∫p = {integral}");
        });
    }

    /// Directions drawn by `sample` follow `pdf_at` (χ² over a θ × φ grid, expected counts
    /// by quadrature of the pdf within each cell).
    #[test]
    fn sampled_directions_follow_the_mixture_pdf() {
        const NT: usize = 16;
        const NP: usize = 32;
        const SUB: usize = 12;
        let s = scene();
        let m = mixture(&s);
        let x = Vec3::new(0.2, 0.1, -0.3);
        with_scatterers(|sc| {
            let n = 200_000;
            let mut observed = vec![0u64; NT * NP];
            let mut rng = TestRng::new(17);
            for _ in 0..n {
                let u_comp = rng.uniform();
                let u = Vec2::new(rng.uniform(), rng.uniform());
                let ms = m.sample::<Rgb>(&s, x, sc, 1.0, u_comp, u, &()).expect("every density samples from x");
                let theta = (ms.wi.z as f64).clamp(-1.0, 1.0).acos();
                let phi = (ms.wi.y as f64).atan2(ms.wi.x as f64).rem_euclid(2.0 * PI);
                let i = ((theta / PI * NT as f64) as usize).min(NT - 1);
                let j = ((phi / (2.0 * PI) * NP as f64) as usize).min(NP - 1);
                observed[i * NP + j] += 1;
                // The sample's own density agrees with the evaluated one where it can be
                // compared (nothing blocks these lights).
                let first = first_hit(&s, x, ms.wi);
                let along = m.pdf_along(&s, x, &ms, first.as_ref()).expect("unblocked samples keep their weight");
                let at = m.pdf_at(&s, x, sc, ms.wi, first.as_ref());
                assert!((along - at).abs() <= 1e-3 * at, "{along} vs {at}");
            }
            let mut expected = vec![0.0f64; NT * NP];
            for (i, row) in expected.chunks_mut(NP).enumerate() {
                for (j, e) in row.iter_mut().enumerate() {
                    let (dt, dp) = (PI / NT as f64 / SUB as f64, 2.0 * PI / NP as f64 / SUB as f64);
                    let mut sum = 0.0;
                    for a in 0..SUB {
                        let theta = (i * SUB + a) as f64 * dt + 0.5 * dt;
                        for b in 0..SUB {
                            let phi = (j * SUB + b) as f64 * dp + 0.5 * dp;
                            let wi = Vec3::new(
                                (theta.sin() * phi.cos()) as f32,
                                (theta.sin() * phi.sin()) as f32,
                                theta.cos() as f32,
                            );
                            let p = m.pdf_at(&s, x, sc, wi, first_hit(&s, x, wi).as_ref()) as f64;
                            sum += p * theta.sin() * dt * dp;
                        }
                    }
                    *e = sum * n as f64;
                }
            }
            if let Err(e) = chi_square_test(&observed, &expected) {
                panic!("{sc:?}: {e}");
            }
        });
    }

    /// A luminaire sample whose ray meets something else first has weight 0; a BSDF sample
    /// towards the same light through the same blocker does not count the light's density.
    /// The graded mixture (`tracer.rs`, a throughput above 1): the other shares scaled, the
    /// phase function's taking the rest; 0 leaves it alone.
    #[test]
    fn mixture_shares_scale_with_mix() {
        let s = scene();
        let m = mixture(&s);
        let sc: Scatterer<'_, Rgb> = Scatterer::Medium { phase: HenyeyGreenstein::new(0.0), wo: Vec3::Z };
        let (full, half) = (m.weights(&sc, 1.0), m.weights(&sc, 0.5));
        assert_eq!(full, m.base_weights());
        assert!((half.light - 0.5 * full.light).abs() < 1e-6 && (half.env - 0.5 * full.env).abs() < 1e-6);
        assert!((half.scatter + half.light + half.env - 1.0).abs() < 1e-6);
        assert_eq!(m.weights(&sc, 0.0), Weights::SCATTER_ONLY);
    }

    #[test]
    fn blocked_light_samples_have_no_weight() {
        let s = scene();
        let m = mixture(&s);
        let x = Vec3::new(0.0, 0.0, 0.0);
        let sc = Scatterer::Medium { phase: HenyeyGreenstein::new(0.0), wo: Vec3::Z };
        let w = m.weights(&sc, 1.0);
        let ms = (0..64)
            .find_map(|k| {
                let ms = m.sample::<Rgb>(
                    &s,
                    x,
                    &sc,
                    1.0,
                    w.scatter + 0.5 * w.light,
                    Vec2::new((k as f32 + 0.5) / 64.0, 0.3),
                    &(),
                )?;
                matches!(ms.component, Component::Light { .. }).then_some(ms)
            })
            .expect("a light sample");
        let hit = first_hit(&s, x, ms.wi).expect("the light is hit");
        assert!(m.pdf_along(&s, x, &ms, Some(&hit)).is_some());
        assert!(m.pdf_along(&s, x, &ms, None).is_none(), "a medium 'hit' came first");
        let mut other = hit;
        other.prim.area_light = NONE;
        assert!(m.pdf_along(&s, x, &ms, Some(&other)).is_none(), "another surface came first");
        let bsdf_like = MixtureSample { component: Component::Scatter, ..ms };
        let p = m.pdf_along(&s, x, &bsdf_like, Some(&other)).unwrap();
        assert!((p - (w.scatter * ms.scatter_pdf + w.env * m.env_pdf(&s, ms.wi))).abs() < 1e-6);
    }
}
