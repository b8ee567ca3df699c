//! Strongly forward-scattering media (beyond the thesis): the graph holds the similar isotropic
//! medium, read after a few exact events.
//!
//! The graph's directional radiance (spherical harmonics to band 2, [`super::sh`]) cannot
//! hold HG's forward peak beyond |g| ≈ 0.75: on the Disney cloud (g = 0.877) each bounce sends
//! band 2's spread of the peak sideways and back, and the image came out +26.8 % off volpath
//! at the scene's maxdepth (README). Light that has scattered many times has forgotten its
//! direction, and for it the similarity relation holds (Zhao, Ramamoorthi and Bala, "High-Order
//! Similarity Relations in Radiative Transfer", ACM TOG (SIGGRAPH) 2014; its first order is
//! the classic σs' = σs(1 − g), g' = 0): a medium that scatters isotropically with σs(1 − g)
//! carries the same diffuse light. So where g > [`super::volume::MAX_G`] the graph is built
//! on that medium, isotropic as the thesis's, and a camera path reads it only at its
//! [`exact_events`]-th scattering event: the events before it are traced exactly (HG, next
//! event estimation) by the shared path loop, and carry the low orders whose angular
//! structure the camera sees (the bright rim, the forward glow).
//!
//! Measured on the Disney cloud (160×90, sun, sky and ground; volpath with the
//! read-after-K hybrid's limit, i.e. the real medium for K events and the similar one after,
//! against volpath to depth 10 000): +1.9 %, +1.3 %, +0.5 %, 0.0 %, −0.6 % at K = 1, 2, 4, 8,
//! 16 (64 spp each, ±0.4 %).
//!
//! The similar medium has no counterpart of a path depth: one of its events stands for about
//! 1/(1 − g) of the real medium's, but the count that reproduces volpath's cut at the scene's
//! `maxdepth` is not the one the relation predicts (on the Disney cloud, after 8 exact events,
//! 8 similar ones matched maxdepth 100 within noise; the 11 that (100 − 8)(1 − g) gives came
//! out +4.9 %, 14 +8.5 %), and one that matches one cloud need not match another. So such a
//! graph transports light to convergence ([`BOUNCES`]): it renders what volpath renders with
//! paths long enough to end by themselves, and says so in the render's summary. On the Disney cloud,
//! maxdepth 100 cuts off 26 % of that light.
//!
//! Everything the graph's build computes goes through the similar medium, the light the
//! surfaces reflect into it included (through the scene's medium the Disney cloud came out
//! 3.5 % dark). With that, the Disney cloud at 160×90 and 128 spp: image mean +1.0 %, MAE 4.9 %
//! of the mean, volpath to depth 10 000 80× slower to the same MAE (README).

use crate::media::{Medium, MediumKind};

/// The largest g the similar medium stands in for (measured: the Disney cloud at 0.877, the
/// σs = 8 cube at 0.85 and 0.95, `tests/radiancegraph.rs`; beyond it a camera path would
/// trace more than 28 exact events before reading the graph).
pub const MAX_G: f32 = 0.95;

/// Bounces the similar medium's graph transports when no config says otherwise: enough for
/// light to leave a dense cloud of albedo 1 (the Disney cloud's similar medium lost 4–5 %
/// at 92–96 events, none at 1000).
pub const BOUNCES: u32 = 1000;

/// The transport of the similar medium's graph stops when the bounces still to come, taken
/// as the geometric series of the last two, would add less than this fraction of the light.
pub const TAIL: f64 = 1e-3;

/// How the graph stands in for a strongly forward-scattering medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// The real medium's HG asymmetry.
    pub g: f32,
    /// The camera path's scattering event that reads the graph (1 for the first).
    pub read_at: u32,
}

impl Similarity {
    /// For a medium with asymmetry `g` in (0.75, [`MAX_G`]].
    pub fn new(g: f32) -> Similarity {
        Similarity { g, read_at: exact_events(g) }
    }
}

/// The events a camera path takes exactly before it reads the graph, counting the one that
/// reads it: the first at which the path remembers at most a quarter of its direction (g^k ≤
/// 1/4, the mean cosine between the camera ray's direction and the path's after k events).
/// The similarity relation's error falls about as g^k: on the σs = 8 cube at g = 0.85 (optical
/// side 16, 2.4 in the similar medium; the hybrid's limit against volpath, 4096 spp) +6.3 %,
/// +3.0 %, +2.0 %, +1.2 % at k = 1, 3, 5, 8, about 4.5 % · g^k; on the Disney cloud, far deeper,
/// +1.9 %, +0.5 %, 0.0 % at 1, 4, 8. So at most about 1 % on a small cube, and 11 events at
/// g = 0.877.
pub fn exact_events(g: f32) -> u32 {
    let g = g.clamp(0.0, 0.99);
    let mut k = 1;
    while g.powi(k as i32) > 0.25 {
        k += 1;
    }
    k
}

/// The similar isotropic medium: σs(1 − g), σa unchanged, g = 0; `None` for a medium whose
/// coefficients are per voxel (its majorants are in σ, not density, and would not follow).
pub fn similar(medium: &Medium) -> Option<Medium> {
    let keep = 1.0 - medium.g;
    let kind = match &medium.kind {
        MediumKind::Homogeneous { sigma_a, sigma_s, le } => {
            MediumKind::Homogeneous { sigma_a: *sigma_a, sigma_s: sigma_s.scaled(keep), le: *le }
        }
        MediumKind::Grid(grid) => {
            let mut grid = grid.clone();
            // The majorant grid holds densities and multiplies them by σt, which follows.
            grid.sigma_s = grid.sigma_s.scaled(keep);
            MediumKind::Grid(grid)
        }
        MediumKind::RgbGrid(_) => return None,
    };
    Some(Medium { kind, g: 0.0, ..medium.clone() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::spectra::SpectrumValue;

    #[test]
    fn exact_events_until_three_quarters_of_the_direction_are_forgotten() {
        assert_eq!(exact_events(0.877), 11);
        assert_eq!(exact_events(0.85), 9);
        assert_eq!(exact_events(0.8), 7);
        assert_eq!(exact_events(0.9), 14);
        // 0.9^14 = 0.229 ≤ 1/4 < 0.9^13 = 0.254.
        assert!(0.9f32.powi(14) <= 0.25 && 0.9f32.powi(13) > 0.25);
        // At MAX_G: 0.95^28 = 0.238 ≤ 1/4 < 0.95^27 = 0.250 3.
        assert_eq!(exact_events(MAX_G), 28);
    }

    #[test]
    fn the_similar_medium_scatters_isotropically_with_the_reduced_coefficient() {
        let m = Medium::homogeneous(
            "m".into(),
            SpectrumValue::constant(0.5),
            SpectrumValue::constant(2.0),
            SpectrumValue::ZERO,
            0.8,
        );
        let s = similar(&m).expect("homogeneous");
        assert_eq!(s.g, 0.0);
        let p = s.sample_point::<Rgb>(glam::Vec3::ZERO, &());
        assert!((p.sigma_a.x - 0.5).abs() < 1e-6);
        // σs(1 − g) = 2 · 0.2.
        assert!((p.sigma_s.x - 0.4).abs() < 1e-6, "{}", p.sigma_s.x);
    }
}
