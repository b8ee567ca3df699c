//! Observing the path loop: research integrators (path graphs, guiding, radiance graphs)
//! record vertices, next-event samples and emission without copying the loop. Every method
//! has an empty default and the loop is generic over the observer, so `volpath` pays
//! nothing for the hooks.

use glam::Vec3;

use crate::channels::Channels;
use crate::color::Rgb;
use crate::media::phase::HenyeyGreenstein;

/// A scattering vertex: where the path scattered and how it continued.
#[derive(Clone, Copy, Debug)]
pub struct VertexEvent<C = Rgb> {
    /// Number of scattering events before this one (0 for the first vertex).
    pub depth: u32,
    /// Position.
    pub p: Vec3,
    /// Shading normal (zero inside media).
    pub n: Vec3,
    /// Direction back along the incoming ray (towards the previous vertex).
    pub wo: Vec3,
    /// Sampled continuation direction.
    pub wi: Vec3,
    /// Density of `wi` under the sampling technique used.
    pub pdf: f32,
    /// BSDF or phase value × |cos| for `wi` (value only for phase functions).
    pub f: C,
    /// Throughput arriving at the vertex (before this scattering).
    pub beta: C,
    /// True when the continuation was a specular (delta) sample.
    pub specular: bool,
    /// True for a vertex inside a medium.
    pub in_medium: bool,
    /// The medium's Henyey-Greenstein asymmetry at a medium vertex (0 on surfaces): with `wo`
    /// it is all a path graph needs to evaluate the phase function for other directions.
    pub g: f32,
    /// True at a surface whose BSDF is Lambertian reflection: f = R|cos|/π, sampled by the
    /// cosine, so the shading normal `n` is all a path graph needs besides f/p = R.
    pub lambertian: bool,
}

/// A next-event estimate at a vertex.
#[derive(Clone, Copy, Debug)]
pub struct NeeEvent<C = Rgb> {
    /// Scattering events before the vertex.
    pub depth: u32,
    /// The vertex position.
    pub p: Vec3,
    /// Direction to the light sample.
    pub wi: Vec3,
    /// Light sample density (light choice × direction, solid angle).
    pub pdf_light: f32,
    /// BSDF/phase density of `wi` (MIS partner).
    pub pdf_scatter: f32,
    /// Contribution added to the pixel (already MIS-weighted, transmittance included).
    pub contribution: C,
}

/// Emission found by the path (hit area light, escaped to the environment, medium
/// emission).
#[derive(Clone, Copy, Debug)]
pub struct EmissionEvent<C = Rgb> {
    /// Scattering events before it.
    pub depth: u32,
    /// Contribution added to the pixel (MIS-weighted).
    pub contribution: C,
    /// Density with which light sampling at the previous vertex would have chosen this
    /// emission's direction (light choice × direction, solid angle): the MIS partner. 0 when
    /// the emission had none (seen from the camera, after a specular bounce, medium emission,
    /// or next-event estimation off).
    pub pdf_light: f32,
}

/// A continuation direction drawn by path guiding at a medium vertex instead of by the phase
/// function.
#[derive(Clone, Copy, Debug)]
pub struct GuidedSample {
    /// The direction, pointing away from the vertex.
    pub wi: Vec3,
    /// The estimator's factor for it: the phase value over the effective density of the
    /// technique (for resampling, p·W/q: Deng et al. 2020, Eq. 5). β is multiplied by it.
    pub weight: f32,
    /// The density that MIS with light sampling uses for `wi` (the same function as
    /// [`PathStrategy::guide_medium_pdf`]).
    pub pdf: f32,
}

/// How a method steers the path loop (strategy hooks): guiding scattering in media, the
/// probability of next-event estimation there, splitting. Each default leaves the loop as
/// volpath runs it.
pub trait PathStrategy {
    /// Whether this observer guides scattering in media ([`PathStrategy::guide_medium`]).
    /// The loop draws the guide's random number only then, so observers that do not guide
    /// leave the sampler's dimensions, hence volpath's images, unchanged.
    #[inline]
    fn guides(&self) -> bool {
        false
    }
    /// Path guiding at a real scattering event at `p` in medium `medium`, with phase
    /// function `phase` and `wo` pointing back along the path: a direction from a learned
    /// distribution, or `None` for the phase function's own sampling. `u` seeds the guide's
    /// random numbers.
    #[inline]
    fn guide_medium(
        &mut self,
        _medium: u32,
        _p: Vec3,
        _wo: Vec3,
        _phase: &HenyeyGreenstein,
        _u: f32,
    ) -> Option<GuidedSample> {
        None
    }
    /// The MIS density of direction `wi` under [`PathStrategy::guide_medium`] at the same
    /// vertex, or `None` where it would not guide (the phase density applies).
    #[inline]
    fn guide_medium_pdf(&self, _medium: u32, _p: Vec3, _wo: Vec3, _phase: &HenyeyGreenstein, _wi: Vec3) -> Option<f32> {
        None
    }
    /// The probability of next-event estimation at a real scattering event at `p` in
    /// `medium` (1: always). Asked only where [`PathStrategy::guides`].
    #[inline]
    fn nee_medium_probability(&self, _medium: u32, _p: Vec3) -> f32 {
        1.0
    }
    /// Splitting at a real scattering event at `p` in `medium`, before its continuation is
    /// drawn, for a path whose throughput is `beta` (β over the mean of r_u): how many
    /// independent continuations the path takes, each with β divided by their number (1:
    /// the path goes on as it is). Asked only where [`PathStrategy::guides`].
    #[inline]
    fn split_medium(&mut self, _medium: u32, _p: Vec3, _beta: f32) -> u32 {
        1
    }
    /// Whether this method ends a path at a real scattering event in a medium, the path's
    /// `depth`-th scattering event (surfaces counted; 1 for the first), with its own estimate
    /// of the radiance scattered there ([`PathStrategy::medium_estimate`]): a radiance cache
    /// read where the path enters the medium or after a few events traced exactly, everything
    /// before it (surfaces, their light sampling, emission) traced as volpath traces it.
    #[inline]
    fn ends_in_medium(&self, _depth: u32) -> bool {
        false
    }
    /// Where [`PathStrategy::ends_in_medium`]: the radiance scattered at `p` in `medium`
    /// toward `wo` (the phase function's integral of the incident light, every bounce
    /// included), in the path's channels at `lambda`. `u` seeds the estimate's random
    /// numbers. The loop adds it times the path's throughput and ends the path.
    #[inline]
    fn medium_estimate<C: Channels>(&mut self, _medium: u32, _p: Vec3, _wo: Vec3, _lambda: &C::Lambda, _u: f32) -> C {
        C::ZERO
    }
}

/// What a method learns from the path loop as it happens (observing hooks: they change
/// nothing), in the channels the path carries (RGB or the path's sampled wavelengths).
pub trait PathRecorder<C: Channels> {
    /// Whether this recorder sees the vertex a path leaves after its last counted scattering
    /// event. Where it does not, and nothing can add to the path after that event (no light
    /// is found by hitting or escaping, no subsurface medium scatters for free), the loop ends
    /// the path there instead of tracing a continuation that cannot contribute.
    #[inline]
    fn records_vertices(&self) -> bool {
        true
    }
    /// A scattering vertex was sampled.
    #[inline]
    fn on_vertex(&mut self, _v: &VertexEvent<C>) {}
    /// A next-event estimate was made.
    #[inline]
    fn on_nee(&mut self, _e: &NeeEvent<C>) {}
    /// Emission was added.
    #[inline]
    fn on_emission(&mut self, _e: &EmissionEvent<C>) {}
    /// The mean of [`super::PathConfig::extra_direct`] light samples at the vertex `depth`
    /// (not added to the path's estimate).
    #[inline]
    fn on_extra_direct(&mut self, _depth: u32, _contribution: C) {}
    /// The sum of `samples` extra first vertices' light samples on a stretch of the camera
    /// line through a medium ([`super::PathConfig::line_direct`]; not added to the path's
    /// estimate) and their sample variance (`spread`, of the channels' mean); `own` when the
    /// path's own first vertex is on the same stretch (a medium vertex at depth 0), so that
    /// its direct light is one estimate of `samples + 1`.
    #[inline]
    fn on_line_direct(&mut self, _sum: C, _spread: f32, _samples: u32, _own: bool) {}
}

/// A method's view of the path loop: what it records and how it steers. Implement
/// [`PathRecorder`] and [`PathStrategy`] (either may be empty); this follows.
pub trait PathObserver<C: Channels>: PathRecorder<C> + PathStrategy {}

impl<C: Channels, T: PathRecorder<C> + PathStrategy> PathObserver<C> for T {}

/// The observer that records nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoObserver;

impl PathStrategy for NoObserver {}

impl<C: Channels> PathRecorder<C> for NoObserver {
    #[inline]
    fn records_vertices(&self) -> bool {
        false
    }
}
