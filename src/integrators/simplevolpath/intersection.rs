//! The probabilistic intersection of the paper's §4: surfaces and media through one
//! interface. A ray either hits a surface, 'hits' a medium (meets a particle, with the
//! probability per unit length σt, Eq. 3–4) or leaves the scene; [`intersect`] returns the
//! nearest of these events.
//!
//! The paper accumulates the probability of a hit along the ray, P_i = P_{i−1} + (1 − P_{i−1})
//! σt Δs (Eq. 6), and compares it with a stratified seed R; for constant σt this is the closed
//! form s = −ln(1 − R)/σt. Here the walk runs over the medium's majorant segments
//! ([`crate::media::Medium::segments`]): a homogeneous medium is one segment whose majorant
//! is σt, so the seed gives exactly the paper's closed form; a grid medium is walked by delta
//! tracking (Woodcock et al. 1965), the exact, unbiased form of Eq. 6 — tentative collisions
//! at the majorant's rate, each one a real 'hit' with probability σt/σmaj. The seed R is the
//! sampler's 1D value and drives the first tentative collision, so pixels stratify; later
//! collisions (and the real-or-null choices) use a generator seeded from the sampler.
//!
//! `interface` surfaces only mark where media change: the walk crosses them inside
//! [`intersect`] (an emissive one is returned, so its emission is counted).
//!
//! Chromatic media (σt differing between RGB channels) are walked with one channel's
//! coefficients, the hero channel of the path, and the event carries the per-channel ratios
//! of pbrt-v4's spectral MIS (its rescaled path probabilities `r_u`): `beta` multiplies the
//! path throughput by f_c/p_hero and `r_u` by p_c/p_hero, so dividing by the average of `r_u`
//! at the end weights the three channels' sampling densities by the balance heuristic and
//! stays unbiased in every channel. In gray media both ratios are exactly 1 and are skipped.

use glam::{Vec2, Vec3};

use crate::accel::{Hit, NONE};
use crate::channels::Channels;
use crate::color::Rgb;
use crate::geometry::Ray;
use crate::integrators::common::media::sample_t_maj;
use crate::integrators::common::medium_after;
use crate::media::{Medium, MediumPoint};
use crate::samplers::Sampler;
use crate::sampling::rng::{Pcg32, hash_sample};
use crate::scene::Scene;

/// The stratified seed of one probabilistic intersection: R drives the first tentative
/// collision; the generator (seeded from another sampler value, created only when the ray
/// enters a medium) the rest.
#[derive(Clone, Copy, Debug)]
pub struct Seed {
    /// The paper's R, in [0, 1).
    pub r: f32,
    /// Seeds the generator for later decisions.
    pub u_rng: f32,
}

impl Seed {
    /// Two sampler dimensions, drawn only when the scene has media (so surface-only scenes
    /// use the sampler exactly as without this step).
    #[inline]
    pub fn draw(scene: &Scene, sampler: &mut Sampler) -> Seed {
        if scene.media.is_empty() {
            Seed { r: 0.5, u_rng: 0.5 }
        } else {
            Seed { r: sampler.get_1d(), u_rng: sampler.get_1d() }
        }
    }

    fn rng(&self) -> Pcg32 {
        Pcg32::new(hash_sample(self.u_rng, Vec2::ZERO), hash_sample(self.r, Vec2::ONE))
    }
}

/// What a ray meets first.
#[derive(Clone, Copy, Debug)]
pub enum Event<C = Rgb> {
    /// Nothing before `t_max`: the ray left the scene (or reached its target).
    Escape,
    /// A surface (never a non-emissive `interface`).
    Surface(Hit),
    /// A particle of medium `medium` at `p`: the medium is 'hit' (§4).
    Medium {
        /// Where.
        p: Vec3,
        /// σa, σs and Le there.
        point: MediumPoint<C>,
        /// Index of the medium.
        medium: u32,
    },
}

/// The nearest event along a ray and the throughput factor of reaching it.
#[derive(Clone, Copy, Debug)]
pub struct Intersection<C = Rgb> {
    /// The event.
    pub event: Event<C>,
    /// The last straight piece of the ray (after crossing interfaces): its direction is the
    /// ray's, its origin where the last piece started.
    pub ray: Ray,
    /// The medium the ray travelled through to reach the event.
    pub medium: u32,
    /// Throughput factor f_c/p_hero per channel (1 in gray media).
    pub beta: C,
    /// Spectral-MIS ratio p_c/p_hero per channel (1 in gray media).
    pub r_u: C,
}

/// The nearest event along `ray` (unit direction) before `t_max`, starting in `medium`:
/// surfaces and media through one interface. `segments` counts the straight pieces traced
/// (one plus one per interface crossed).
#[allow(clippy::too_many_arguments)]
pub fn intersect<C: Channels>(
    scene: &Scene,
    mut ray: Ray,
    mut medium: u32,
    mut t_max: f32,
    seed: Seed,
    hero: usize,
    lambda: &C::Lambda,
    segments: &mut u64,
) -> Intersection<C> {
    let mut beta = C::ONE;
    let mut r_u = C::ONE;
    let mut r = Some(seed.r);
    let mut rng: Option<Pcg32> = None;
    loop {
        *segments += 1;
        let hit = scene.surfaces.intersect(&ray, t_max);
        if medium != NONE {
            let m = &scene.media[medium as usize];
            let t_end = hit.as_ref().map_or(t_max, |h| h.surface.t);
            let rng = rng.get_or_insert_with(|| seed.rng());
            let u = r.take().unwrap_or_else(|| rng.uniform());
            if let Some((p, point)) = medium_hit(m, &ray, t_end, u, rng, hero, lambda, &mut beta, &mut r_u) {
                return Intersection { event: Event::Medium { p, point, medium }, ray, medium, beta, r_u };
            }
        }
        let Some(h) = hit else {
            return Intersection { event: Event::Escape, ray, medium, beta, r_u };
        };
        if !scene.materials[h.prim.material as usize].is_interface() || h.prim.area_light != NONE {
            return Intersection { event: Event::Surface(h), ray, medium, beta, r_u };
        }
        // A medium boundary and nothing else: cross it.
        medium = medium_after(scene, &h, ray.d, medium);
        let next = h.spawn_ray(ray.d);
        t_max -= (next.o - ray.o).dot(ray.d);
        if t_max <= 0.0 {
            return Intersection { event: Event::Escape, ray, medium, beta, r_u };
        }
        ray = next;
    }
}

/// The probabilistic intersection with one medium up to `t_end` (Eq. 6 by delta tracking):
/// the first real collision, or `None` when the ray passes through. `beta` and `r_u` take the
/// spectral-MIS ratios of chromatic media (for a gray medium they stay 1).
#[allow(clippy::too_many_arguments)]
#[inline]
fn medium_hit<C: Channels>(
    m: &Medium,
    ray: &Ray,
    t_end: f32,
    u: f32,
    rng: &mut Pcg32,
    hero: usize,
    lambda: &C::Lambda,
    beta: &mut C,
    r_u: &mut C,
) -> Option<(Vec3, MediumPoint<C>)> {
    let mut found = None;
    let t_maj =
        sample_t_maj(m.into(), ray, t_end, u, rng, hero, lambda, |p, point: &MediumPoint<C>, sigma_maj, t_maj, rng| {
            let sigma_t = point.sigma_a + point.sigma_s;
            // A tentative collision is a particle with probability σt/σmaj (1 in a homogeneous
            // medium, where no generator value is spent).
            let p_hit = sigma_t[hero] / sigma_maj[hero];
            if p_hit >= 1.0 || rng.uniform() < p_hit {
                if m.chromatic {
                    let ratio = t_maj * sigma_t / (t_maj[hero] * sigma_t[hero]);
                    *beta *= ratio;
                    *r_u *= ratio;
                }
                found = Some((p, *point));
                return false;
            }
            if m.chromatic {
                let sigma_n = (sigma_maj - sigma_t).max(C::ZERO);
                let ratio = t_maj * sigma_n / (t_maj[hero] * sigma_n[hero]);
                *beta *= ratio;
                *r_u *= ratio;
            }
            true
        });
    if found.is_none() && m.chromatic {
        // Passed through: the hero channel's probability of no collision is T_maj[hero].
        let h = t_maj[hero];
        let ratio = if h > 0.0 { t_maj / h } else { C::ZERO };
        *beta *= ratio;
        *r_u *= ratio;
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::average;
    use crate::scene::BuildOptions;

    /// The scene built for RGB transport (these tests trace RGB channels).
    fn scene(text: &str) -> Scene {
        let desc = nimbus_parser::load_str(text, "intersection.pbrt").unwrap_or_else(|e| panic!("{e}"));
        let opts = BuildOptions { spectral: Some(crate::scene::transport::SpectralMode::Off), ..Default::default() };
        crate::setup::build(&desc, &opts).unwrap_or_else(|e| panic!("{e}")).scene
    }

    /// The cube [-1, 1]³ bounding medium "m".
    const CUBE: &str = r#"AttributeBegin
  MediumInterface "m" ""
  Material "interface"
  Shape "trianglemesh" "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  3 7 6 3 6 2  0 4 7 0 7 3  1 2 6 1 6 5 ]
    "point3 P" [ -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ]
AttributeEnd"#;

    /// In a homogeneous medium the seed R gives the paper's closed form s = −ln(1 − R)/σt.
    #[test]
    fn homogeneous_medium_hit_is_the_closed_form() {
        let s = scene(
            r#"MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.5 0.5 0.5] "rgb sigma_s" [1 1 1]
MediumInterface "m" "m"
Camera "perspective"
WorldBegin"#,
        );
        let ray = Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.6, 0.8));
        for k in 0..100 {
            let r = (k as f32 + 0.5) / 100.0;
            let mut n = 0;
            let i = intersect::<Rgb>(&s, ray, s.camera_medium, f32::INFINITY, Seed { r, u_rng: 0.3 }, 0, &(), &mut n);
            let Event::Medium { p, point, .. } = i.event else { panic!("an infinite medium is always hit") };
            let t = -(1.0 - r).ln() / 1.5;
            assert!((p.length() - t).abs() <= 1e-5 * t.max(1.0), "R {r}: {} vs {t}", p.length());
            assert_eq!((point.sigma_a, point.sigma_s), (Rgb::splat(0.5), Rgb::ONE));
            assert_eq!((i.beta, i.r_u, n), (Rgb::ONE, Rgb::ONE, 1));
        }
    }

    /// Through a heterogeneous grid, the probability that the ray passes is the transmittance
    /// exp(−∫σt) (quadrature), and the events are surfaces beyond the medium or particles in it.
    #[test]
    fn grid_medium_is_hit_with_probability_one_minus_transmittance() {
        let density: Vec<String> = (0..27).map(|k| format!("{}", 0.2 + (k * 7 % 11) as f32 * 0.15)).collect();
        let s = scene(&format!(
            r#"Camera "perspective"
WorldBegin
MakeNamedMedium "m" "string type" "uniformgrid" "integer nx" 3 "integer ny" 3 "integer nz" 3
  "float density" [{}] "point3 p0" [-1 -1 -1] "point3 p1" [1 1 1] "rgb sigma_a" [0.3 0.3 0.3] "rgb sigma_s" [0.9 0.9 0.9]
{CUBE}
Material "diffuse"
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-5 -5 3  5 -5 3  5 5 3  -5 5 3]"#,
            density.join(" ")
        ));
        let o = Vec3::new(0.3, -0.2, -4.0);
        let d = (Vec3::new(-0.2, 0.3, 3.0) - o).normalize();
        let ray = Ray::new(o, d);
        // Optical depth by quadrature of the interpolated density along the ray.
        let m = &s.media[0];
        let steps = 20_000;
        let (t0, t1) = (0.0f32, 12.0f32);
        let dt = (t1 - t0) / steps as f32;
        let tau: f64 = (0..steps)
            .map(|k| {
                let p = ray.at(t0 + (k as f32 + 0.5) * dt);
                if p.abs().max_element() < 1.0 {
                    (m.sample_point::<Rgb>(p, &()).sigma_a.x + m.sample_point::<Rgb>(p, &()).sigma_s.x) as f64
                } else {
                    0.0
                }
            })
            .sum::<f64>()
            * dt as f64;
        let exact = (-tau).exp();
        let n = 40_000;
        let mut passed = 0;
        for k in 0..n {
            let seed = Seed { r: (k as f32 + 0.5) / n as f32, u_rng: ((k * 7919) % n) as f32 / n as f32 };
            let mut segs = 0;
            match intersect::<Rgb>(&s, ray, NONE, f32::INFINITY, seed, 0, &(), &mut segs).event {
                Event::Surface(h) => {
                    assert!((h.surface.p.z - 3.0).abs() < 1e-4, "only the back wall is a surface");
                    passed += 1;
                }
                Event::Medium { p, .. } => assert!(p.abs().max_element() <= 1.0 + 1e-4),
                Event::Escape => panic!("the wall is behind the medium"),
            }
        }
        let est = passed as f64 / n as f64;
        let sd = (exact * (1.0 - exact) / n as f64).sqrt();
        assert!((est - exact).abs() < 4.0 * sd, "P(pass) {est} vs T {exact} ± {sd}");
    }

    /// Chromatic media: with a random hero channel, 1{pass}·beta_c / mean(r_u) estimates each
    /// channel's own transmittance (spectral MIS keeps every channel unbiased). The grid
    /// extends past the cube, so σ is constant along the 2 units inside it.
    #[test]
    fn chromatic_pass_weights_estimate_each_channels_transmittance() {
        let grid = ["0.2 0.9 2.0"; 8].join(" ");
        let zero = ["0 0 0"; 8].join(" ");
        let s = scene(&format!(
            r#"Camera "perspective"
WorldBegin
MakeNamedMedium "m" "string type" "rgbgrid" "integer nx" 2 "integer ny" 2 "integer nz" 2
  "rgb sigma_a" [{grid}] "rgb sigma_s" [{zero}] "point3 p0" [-2 -2 -2] "point3 p1" [2 2 2]
{CUBE}"#
        ));
        let ray = Ray::new(Vec3::new(0.1, 0.2, -3.0), Vec3::Z);
        let n = 30_000;
        let mut sum = [0.0f64; 3];
        let mut sum2 = [0.0f64; 3];
        for k in 0..n {
            let hero = k % 3;
            let seed = Seed { r: ((k / 3) as f32 + 0.5) / (n / 3) as f32, u_rng: (k as f32 * 0.618_034).fract() };
            let mut segs = 0;
            let i = intersect::<Rgb>(&s, ray, NONE, f32::INFINITY, seed, hero, &(), &mut segs);
            if let Event::Escape = i.event {
                let w = i.beta / average(i.r_u);
                for c in 0..3 {
                    sum[c] += w[c] as f64;
                    sum2[c] += (w[c] as f64).powi(2);
                }
            }
        }
        for (c, sigma) in [0.2f64, 0.9, 2.0].iter().enumerate() {
            let exact = (-2.0 * sigma).exp();
            let mean = sum[c] / n as f64;
            let sd = ((sum2[c] / n as f64 - mean * mean) / n as f64).sqrt();
            assert!((mean - exact).abs() < 4.0 * sd + 1e-4, "channel {c}: {mean} vs {exact} ± {sd}");
        }
    }
}
