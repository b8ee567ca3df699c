//! Samples without a graph. The film combines each pixel's graph estimate L with the
//! unbiased estimate U its paths carry, and as samples accumulate the graph's bias takes
//! its weight away (`render/combine.rs`): the image tends to Ū, and a graph sample then
//! buys little more than its U, at the cost of recording, clustering and solving. From the
//! film's [`Outlook`] and the graph samples' measured work, each sample either builds a
//! graph or traces U alone, whichever takes more off the image's squared error per unit of
//! time; the film pools the unpaired samples' U with the paired ones'.

use crate::channels::Channels;
use crate::integrators::Outlook;
use crate::integrators::common::{EmissionEvent, NeeEvent, PathRecorder, PathStrategy};

/// What a graph sample costs beyond its paths, in units of one ray its paths traced: per
/// recorded vertex (recording, clustering, the solve) and per camera path (the paths'
/// arrays, the film's pairs and their outlook). Fitted to two clouds at 2 threads, where a
/// graph sample cost k times a sample of the paths' own estimate alone:
/// - back-lit cloud, 128², 16 spp: 0.081 s against 0.036 s (k − 1 = 1.23); per sample 229k rays,
///   62.7k vertices, 16.4k paths;
/// - Disney cloud, 320×180, 8 spp: 0.960 s against 0.631 s (k − 1 = 0.52); 2.51M rays, 1.09M
///   vertices, 57.6k paths.
///
/// Counted, not timed, so that the image does not depend on the machine's speed or load.
const RAYS_PER_VERTEX: f64 = 0.36;
const RAYS_PER_PATH: f64 = 15.8;

/// A graph sample's cost over a sample of the paths' own estimate, less 1, from the graph
/// samples' work so far: `rays` traced, `vertices` recorded, `paths` traced.
pub(super) fn extra_cost(rays: f64, vertices: f64, paths: f64) -> f64 {
    (RAYS_PER_VERTEX * vertices + RAYS_PER_PATH * paths) / rays.max(1.0)
}

/// Graph samples a render takes before it may stop taking them. The film's moments treat a
/// pixel's samples as independent; ZSobol's are stratified, and the graph's smooth estimate
/// gains more from that than the paths' own (README: stratification), most at few samples.
/// Stopping as soon as the moments allowed took the test cube's MSE at 32 spp from 4.4× below
/// volpath's to 2.2× (stopped after 4), and a furnace sphere's at 16 spp from 2.38e-3 to
/// 3.68e-3 (8 seeds); the back-lit cloud, which stops after 44 by the moments, loses nothing
/// that matters by waiting (README: consistency).
pub(super) const MIN_GRAPH_SAMPLES: u32 = 64;

/// Whether the next sample should build a graph, after `samples` graph samples: while the
/// graph's share of a paired sample's gain pays for what the graph costs beyond its paths
/// (`extra`, from [`extra_cost`]), and always until the film can tell and for the first
/// [`MIN_GRAPH_SAMPLES`].
pub(super) fn graph_pays(outlook: &dyn Fn() -> Option<Outlook>, samples: u32, extra: f64) -> bool {
    if samples < MIN_GRAPH_SAMPLES {
        return true;
    }
    let Some(o) = outlook() else { return true };
    // A paired sample costs 1 + extra unpaired ones; it pays while paired > extra·unpaired.
    o.paired > extra * o.unpaired
}

/// After graph samples stop paying, at most one sample in this many still builds a graph.
/// The film judges the graph's bias from the paired samples alone (D̄ = L̄ − Ū over them), so
/// with none after the stop that judgement froze at the stop's precision while Ū_N kept
/// sharpening: on cloud-sun-sky (stopped after about 250 of 5070 samples in 60 s) the graph
/// kept its weight and its bias, and the image's relMSE at 60 s was 7.4e-5, 1.64× volpath's
/// 4.5e-5. One in 8: 4.9e-5 (one in 4: 5.1e-5, the graph samples' cost); the back-lit cloud
/// of the README at 60 s: 3.99e-4, volpath's 4.2e-4 (README: consistency).
pub(super) const THIN: u32 = 8;

/// Whether sample `sample_index` of a render whose graph samples stopped paying after
/// `graph_samples` of them should still build a graph: while they are fewer than one in
/// [`THIN`] of all samples taken, and the graph's share of a paired sample's gain is still
/// worth at least 1/[`THIN`] of its cost (`extra`, as in [`graph_pays`]). Where the film has
/// taken the graph's weight away (a bias it can see) the share is near zero and no more
/// graphs are built; where the graph still carries the image, its bias keeps being judged
/// from paired samples as the unbiased side sharpens.
pub(super) fn thinned_graph_sample(
    outlook: &dyn Fn() -> Option<Outlook>,
    sample_index: u32,
    graph_samples: u32,
    extra: f64,
) -> bool {
    sample_index >= THIN * graph_samples && outlook().is_some_and(|o| o.paired * f64::from(THIN) > extra * o.unpaired)
}

/// The path loop's observer for an unpaired sample: U as the graph samples make it, the
/// path's own first-vertex direct light averaged with the camera line's extra first
/// vertices (`PathConfig::line_direct`), as `record.rs` averages them.
pub(super) struct OwnEstimate<C: Channels> {
    /// The path's direct light at its first scattering vertex: its light sample and the
    /// MIS-weighted emission its continuation found.
    first: C,
    /// The extra first vertices' share of the direct light, and the share left to the path's own.
    line: C,
    share: f32,
}

impl<C: Channels> Default for OwnEstimate<C> {
    fn default() -> Self {
        OwnEstimate { first: C::ZERO, line: C::ZERO, share: 1.0 }
    }
}

impl<C: Channels> PathStrategy for OwnEstimate<C> {}

impl<C: Channels> PathRecorder<C> for OwnEstimate<C> {
    #[inline]
    fn on_nee(&mut self, e: &NeeEvent<C>) {
        if e.depth == 0 {
            self.first += e.contribution;
        }
    }
    #[inline]
    fn on_emission(&mut self, e: &EmissionEvent<C>) {
        if e.depth == 1 && e.pdf_light > 0.0 {
            self.first += e.contribution;
        }
    }
    #[inline]
    fn on_line_direct(&mut self, sum: C, _spread: f32, samples: u32, own: bool) {
        let share = 1.0 / (samples + 1) as f32;
        self.line += sum * share;
        if own {
            self.share = share;
        }
    }
}

impl<C: Channels> OwnEstimate<C> {
    /// U from the path loop's estimate `l`, the own first vertex's direct light given its
    /// share of the camera line's; clears the observer for the next path.
    pub fn finish(&mut self, l: C) -> C {
        let u = l - self.first * (1.0 - self.share) + self.line;
        *self = OwnEstimate::default();
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outlook(unpaired: f64, paired: f64) -> impl Fn() -> Option<Outlook> {
        move || Some(Outlook { unpaired, paired })
    }

    /// Before the minimum the graph always pays; after it, while its share pays its cost.
    #[test]
    fn graph_samples_pay_by_their_share() {
        assert!(graph_pays(&|| None, MIN_GRAPH_SAMPLES - 1, 1.0));
        assert!(graph_pays(&|| None, MIN_GRAPH_SAMPLES, 1.0));
        assert!(graph_pays(&outlook(1.0, 1.3), MIN_GRAPH_SAMPLES, 1.2));
        assert!(!graph_pays(&outlook(1.0, 1.1), MIN_GRAPH_SAMPLES, 1.2));
    }

    /// After the stop a graph is built for at most one sample in THIN, and only while the
    /// graph's share is worth a THIN-th of its cost.
    #[test]
    fn thinned_graph_samples_keep_a_share() {
        let held = outlook(1.0, 0.5);
        assert!(thinned_graph_sample(&held, THIN * 100, 100, 1.2));
        assert!(!thinned_graph_sample(&held, THIN * 100 - 1, 100, 1.2));
        // The film has taken the graph's weight away: no more graphs.
        assert!(!thinned_graph_sample(&outlook(1.0, 0.1), THIN * 100, 100, 1.2));
        assert!(!thinned_graph_sample(&|| None, THIN * 100, 100, 1.2));
    }
}
