//! What every integrator shares: the path loop (one piece of code that observers watch
//! vertex by vertex), shadow-ray transmittance, and ray statistics.

mod direct;
pub mod media;
pub mod observer;
pub mod path;
mod shadow;

pub use observer::{
    EmissionEvent, GuidedSample, NeeEvent, NoObserver, PathObserver, PathRecorder, PathStrategy, VertexEvent,
};
pub use path::{PathConfig, medium_after, shading_frame, trace_path};

/// Rays traced, for `--stats`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayStats {
    /// Camera rays.
    pub camera: u64,
    /// Rays continuing paths (closest-hit queries).
    pub bounce: u64,
    /// Shadow rays (visibility queries, one per segment through interfaces).
    pub shadow: u64,
}

impl RayStats {
    /// Adds another thread's counts.
    pub fn add(&mut self, o: &RayStats) {
        self.camera += o.camera;
        self.bounce += o.bounce;
        self.shadow += o.shadow;
    }

    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.bounce + self.shadow
    }
}
