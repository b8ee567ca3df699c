//! What a path carries from event to event: its throughput and pbrt-v4's rescaled path
//! probabilities, the ratios a collision in a medium applies to them, Russian roulette on
//! them and the end of a segment's spectral MIS.

use crate::channels::Channels;
use crate::media::MediumPoint;
use crate::samplers::Sampler;

/// Per-path state shared by the loop and its helpers.
#[derive(Clone, Copy)]
pub(super) struct PathState<C: Channels> {
    pub(super) beta: C,
    pub(super) r_u: C,
    pub(super) r_l: C,
    pub(super) hero: usize,
    /// What Russian roulette multiplies β by: the inverse of the factors path guiding put
    /// into β. Roulette on a guided path's β would kill the paths guiding sent towards the
    /// light (their factor is small because the guide's density there is high) and undo the
    /// guiding; on β·scale it survives as an unguided path would. 1 on unguided paths.
    pub(super) rr_scale: f32,
    /// The path's time (its camera ray's): every ray of the path sees moving shapes there.
    pub(super) time: f32,
    /// The coefficients of the medium the path is in when that medium takes them from where
    /// the path entered it ([`crate::media::Medium::from_entry`], a textured `subsurface`).
    pub(super) entered: Option<MediumPoint<C>>,
}

impl<C: Channels> PathState<C> {
    /// A real-scattering collision, chosen with the hero channel's probability: in chromatic
    /// media β and r_u take each channel's ratio to it (spectral MIS); in gray media they are 1.
    #[inline]
    pub(super) fn scatter_collision(&mut self, t_maj: C, sigma_s: C, chromatic: bool) {
        if chromatic {
            let pdf = t_maj[self.hero] * sigma_s[self.hero];
            self.beta *= t_maj * sigma_s / pdf;
            self.r_u *= t_maj * sigma_s / pdf;
        }
    }

    /// A null collision (σn the null coefficient), chosen with the hero channel's
    /// probability: β and r_u as [`PathState::scatter_collision`]'s. Returns that probability
    /// density; where it is 0, β is 0 and the path ends.
    #[inline]
    pub(super) fn null_collision(&mut self, t_maj: C, sigma_n: C, chromatic: bool) -> f32 {
        let pdf = t_maj[self.hero] * sigma_n[self.hero];
        if pdf == 0.0 {
            self.beta = C::ZERO;
        } else if chromatic {
            self.beta *= t_maj * sigma_n / pdf;
            self.r_u *= t_maj * sigma_n / pdf;
        }
        pdf
    }
}

/// Ends a segment of a path in chromatic media ([`super::PathConfig::hero_per_segment`]): the spectral
/// MIS over the segment's hero choice (the balance heuristic, f / mean of the channels'
/// densities = β / mean of r_u), then a new hero for the next segment.
#[inline]
pub(super) fn end_segment<C: Channels>(st: &mut PathState<C>, sampler: &mut Sampler) {
    let a = st.r_u.average();
    if a > 0.0 {
        st.beta /= a;
    }
    // The segment's densities are accounted for: the next one starts its own ratios, with a
    // hero drawn uniformly among the channels (the path's wavelengths are fixed by now, so
    // the next segment's one-sample MIS needs its own uniform choice; for the first segment
    // pbrt's random first wavelength is that choice).
    st.r_u = C::ONE;
    st.hero = ((sampler.get_1d() * C::CHANNELS as f32) as usize).min(C::CHANNELS - 1);
}

/// Russian roulette on the throughput with refraction's radiance scaling undone; true
/// when the path ends.
#[inline]
pub(super) fn rr<C: Channels>(st: &mut PathState<C>, eta_scale: f32, depth: u32, sampler: &mut Sampler) -> bool {
    if st.beta.is_zero() || !st.beta.is_finite() {
        return true;
    }
    let rr_beta = st.beta * (eta_scale * st.rr_scale) / st.r_u.average();
    let rr_max = rr_beta.max_element();
    // pbrt-v4 draws the roulette's dimension at every vertex; where no roulette is played it
    // is skipped, not generated.
    if rr_max < 1.0 && depth > 1 {
        let q = (1.0 - rr_max).max(0.0);
        if sampler.get_1d() < q {
            return true;
        }
        st.beta /= 1.0 - q;
    } else {
        sampler.skip_1d();
    }
    false
}
