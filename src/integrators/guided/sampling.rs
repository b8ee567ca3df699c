//! Choosing a scattering direction from the phase function and a learned radiance
//! distribution (Deng et al. 2020): resampled importance sampling of their product
//! (Sec. 4.3, Eqs. 4–6) for anisotropic media, one-sample MIS of the two for nearly
//! isotropic ones (Sec. 4.4).

use glam::{Vec2, Vec3};

use super::dtree::DTree;
use crate::integrators::common::GuidedSample;
use crate::media::phase::HenyeyGreenstein;
use crate::sampling::rng::Pcg32;
use crate::sampling::warp::{UNIFORM_SPHERE_PDF, uniform_sphere};

/// How directions are drawn (the integrator's parameters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strategy {
    /// Candidates per resampled direction, M (`integer candidates`, 6 in the paper).
    pub candidates: u32,
    /// Weight of the phase function in the candidates' source density, λ (`float lambda`,
    /// 0.9).
    pub lambda: f32,
    /// Probability of sampling the phase function in MIS mode, μ (`float mixprob`, 0.5).
    pub mix_prob: f32,
    /// |g| from which resampling replaces MIS (`float selectivethreshold`, 0.5): 0 always
    /// resamples, above 1 never does.
    pub selective_threshold: f32,
    /// Share of the guide's density spread uniformly over the sphere, ε (`float defensive`,
    /// 0.3; not in the paper): it keeps the resampling target positive wherever the phase
    /// function is, so no direction that carries light is impossible, and bounds the factor
    /// W/q where the guide underestimates the light (README).
    pub defensive: f32,
}

impl Strategy {
    /// Whether a medium with asymmetry `g` is sampled by resampling (else by MIS).
    #[inline]
    pub fn resamples(&self, g: f32) -> bool {
        g.abs() >= self.selective_threshold
    }
}

/// The guide's density with its defensive share: (1 − ε)·tree + ε/4π.
#[inline]
fn guide_pdf(tree: &DTree, eps: f32, d: Vec3) -> f32 {
    (1.0 - eps) * tree.pdf(d) + eps * UNIFORM_SPHERE_PDF
}

/// A direction from the guide's density (with its defensive share) and that density.
#[inline]
fn sample_guide(tree: &DTree, eps: f32, rng: &mut Pcg32) -> Option<(Vec3, f32)> {
    let u = Vec2::new(rng.uniform(), rng.uniform());
    if rng.uniform() < eps {
        let d = uniform_sphere(u);
        return Some((d, guide_pdf(tree, eps, d)));
    }
    // The tree's own density comes with its sample (one descent instead of two).
    let (d, pdf) = tree.sample(u)?;
    Some((d, (1.0 - eps) * pdf + eps * UNIFORM_SPHERE_PDF))
}

/// Draws the continuation at a medium vertex with phase function `phase` (`wo` pointing back
/// along the path) from `tree`, which must hold energy.
pub fn sample(
    tree: &DTree,
    phase: &HenyeyGreenstein,
    g: f32,
    wo: Vec3,
    s: &Strategy,
    rng: &mut Pcg32,
) -> Option<GuidedSample> {
    let eps = s.defensive;
    if !s.resamples(g) {
        // One-sample MIS (Sec. 4.4): the phase function with probability μ, else the guide;
        // the estimator divides by the mixture's density.
        let mu = s.mix_prob;
        let wi = if rng.uniform() < mu {
            phase.sample_p(wo, Vec2::new(rng.uniform(), rng.uniform()))?.wi
        } else {
            sample_guide(tree, eps, rng)?.0
        };
        let p = phase.p(wo, wi);
        let pdf = mu * p + (1.0 - mu) * guide_pdf(tree, eps, wi);
        return (pdf > 0.0).then_some(GuidedSample { wi, weight: p / pdf, pdf });
    }
    // Resampling (Sec. 4.3): M candidates from the source λ·p + (1 − λ)·guide, weighted by
    // target / source with the target p·guide (Eq. 4); one kept in proportion to its weight
    // (a streaming choice, so nothing is stored); the estimator's factor is p·W/target with
    // W the mean weight (Eqs. 5–6), i.e. W / guide.
    let lambda = s.lambda;
    // The candidates first (direction, phase value, guide density or NaN where the tree's
    // density is still to be looked up, and the uniform number that decides whether it
    // replaces the choice so far), then the phase-sampled ones' guide densities in one
    // batch, then the weights and the streaming choice. The random numbers are drawn in the
    // order of one candidate after another, choice included (with ε > 0 every candidate's
    // weight is positive, so each draws its choice number), so the images are those of
    // drawing and choosing each candidate in turn.
    const MAX: usize = 16;
    let mut dirs = [Vec3::ZERO; MAX];
    let mut phases = [0.0f32; MAX];
    let mut guides = [0.0f32; MAX];
    let mut choice = [0.0f32; MAX];
    let mut w_sum = 0.0f32;
    let mut chosen: Option<(Vec3, f32, f32)> = None;
    let mut left = s.candidates as usize;
    while left > 0 {
        let m = left.min(MAX);
        left -= m;
        let mut n = 0;
        for _ in 0..m {
            let (wi, p, gp) = if rng.uniform() < lambda {
                match phase.sample_p(wo, Vec2::new(rng.uniform(), rng.uniform())) {
                    Some(ps) => (ps.wi, ps.p, f32::NAN),
                    None => continue,
                }
            } else {
                match sample_guide(tree, eps, rng) {
                    Some((d, gp)) => (d, phase.p(wo, d), gp),
                    None => continue,
                }
            };
            (dirs[n], phases[n], guides[n], choice[n]) = (wi, p, gp, rng.uniform());
            n += 1;
        }
        // The tree's densities of the phase-sampled candidates, gathered for one batch.
        let mut lookup = [Vec3::ZERO; MAX];
        let mut at = [0usize; MAX];
        let mut k = 0;
        for j in 0..n {
            if guides[j].is_nan() {
                (lookup[k], at[k]) = (dirs[j], j);
                k += 1;
            }
        }
        let mut tree_pdf = [0.0f32; MAX];
        tree.pdf_batch(&lookup[..k], &mut tree_pdf[..k]);
        for (&j, &t) in at[..k].iter().zip(&tree_pdf[..k]) {
            guides[j] = (1.0 - eps) * t + eps * UNIFORM_SPHERE_PDF;
        }
        for j in 0..n {
            let (wi, p, gp) = (dirs[j], phases[j], guides[j]);
            let source = lambda * p + (1.0 - lambda) * gp;
            if source <= 0.0 {
                continue;
            }
            let w = p * gp / source;
            w_sum += w;
            if w > 0.0 && choice[j] * w_sum < w {
                chosen = Some((wi, gp, source));
            }
        }
    }
    let (wi, gp, source) = chosen?;
    let big_w = w_sum / s.candidates as f32;
    Some(GuidedSample { wi, weight: big_w / gp, pdf: source })
}

/// The density that MIS with light sampling uses for `wi` at this vertex: the mixture's in
/// MIS mode (its true density), the candidates' source density in resampling mode (the
/// resampled density has no closed form; any positive function used alike by both techniques
/// keeps MIS unbiased, and the source is the closest one at hand).
pub fn mis_pdf(tree: &DTree, phase: &HenyeyGreenstein, g: f32, wo: Vec3, wi: Vec3, s: &Strategy) -> f32 {
    let p = phase.p(wo, wi);
    let gp = guide_pdf(tree, s.defensive, wi);
    let mix = if s.resamples(g) { s.lambda } else { s.mix_prob };
    mix * p + (1.0 - mix) * gp
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Solid angle of the sphere.
    const SPHERE: f32 = 4.0 * std::f32::consts::PI;

    /// A guide learned towards a small bright cone.
    fn tree() -> DTree {
        let axis = Vec3::new(0.0, 0.6, 0.8);
        let mut rng = Pcg32::new(7, 8);
        let mut t = DTree::new();
        for round in 0..3 {
            for _ in 0..20000 {
                let d = uniform_sphere(Vec2::new(rng.uniform(), rng.uniform()));
                t.deposit(d, if d.dot(axis) > 0.95 { 20.0 } else { 0.05 });
            }
            if round < 2 {
                t = t.refined(0.01);
            }
        }
        t
    }

    /// Both strategies are unbiased for ∫ p(wo, ω) h(ω) dω: the guided estimate
    /// weight·h(ωi) averages to it for any h (here the indicator of a cap the guide favours,
    /// and of its complement), at several asymmetries.
    #[test]
    fn guided_estimates_are_unbiased() {
        let t = tree();
        let wo = Vec3::new(0.0, 0.0, 1.0);
        let cap = Vec3::new(0.0, 0.6, 0.8);
        let base = Strategy { candidates: 6, lambda: 0.9, mix_prob: 0.5, selective_threshold: 0.5, defensive: 0.1 };
        for g in [0.0f32, 0.3, 0.8, -0.6] {
            let phase = HenyeyGreenstein::new(g);
            // Exact ∫ over the cap by quadrature of the phase function on a fine grid.
            let n = 1000;
            let mut exact = [0.0f64; 2];
            for i in 0..n {
                for j in 0..n {
                    let d = super::super::dtree::square_to_sphere(Vec2::new(
                        (i as f32 + 0.5) / n as f32,
                        (j as f32 + 0.5) / n as f32,
                    ));
                    let k = (d.dot(cap) > 0.95) as usize;
                    exact[k] += (phase.p(wo, d) * SPHERE) as f64 / (n * n) as f64;
                }
            }
            for threshold in [0.0, 2.0] {
                let s = Strategy { selective_threshold: threshold, ..base };
                let mut rng = Pcg32::new(11, 12);
                let m = 400_000;
                let mut sum = [0.0f64; 2];
                let mut sq = [0.0f64; 2];
                for _ in 0..m {
                    let Some(gs) = sample(&t, &phase, g, wo, &s, &mut rng) else { continue };
                    assert!(gs.weight.is_finite() && gs.pdf > 0.0);
                    let k = (gs.wi.dot(cap) > 0.95) as usize;
                    sum[k] += gs.weight as f64;
                    sq[k] += (gs.weight as f64).powi(2);
                }
                for k in 0..2 {
                    let mean = sum[k] / m as f64;
                    let se = ((sq[k] / m as f64 - mean * mean) / m as f64).sqrt();
                    assert!(
                        (mean - exact[k]).abs() < 4.5 * se + 1e-4,
                        "g {g}, threshold {threshold}, region {k}: {mean} vs {} ± {se}",
                        exact[k]
                    );
                }
            }
        }
    }

    /// In MIS mode the reported density is the density the directions follow.
    #[test]
    fn mis_density_is_the_mixture() {
        let t = tree();
        let phase = HenyeyGreenstein::new(0.2);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let s = Strategy { candidates: 6, lambda: 0.9, mix_prob: 0.5, selective_threshold: 0.5, defensive: 0.1 };
        let mut rng = Pcg32::new(1, 1);
        for _ in 0..100 {
            let gs = sample(&t, &phase, 0.2, wo, &s, &mut rng).unwrap();
            let want = mis_pdf(&t, &phase, 0.2, wo, gs.wi, &s);
            assert!((gs.pdf - want).abs() <= 1e-5 * want);
            assert!((gs.weight - phase.p(wo, gs.wi) / want).abs() <= 1e-4 * gs.weight);
        }
    }
}
