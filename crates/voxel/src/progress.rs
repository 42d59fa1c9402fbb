//! Progress reporting for long preparation stages.
//!
//! The preparation code is CPU-bound and parallel (rayon), so a reporter must be `Sync`
//! and cheap to call from worker threads. Stages call [`Progress::advance`] per batch of
//! work (a chunk of bricks, a level), never per voxel, so the reporter's own cost is
//! negligible. The CLI implements it with an indicatif bar; tests and library users who
//! do not care pass [`NoProgress`].

/// Receives progress of the preparation stages. All methods default to doing nothing.
pub trait Progress: Sync {
    /// A new stage named `stage` begins with `total` units of work (0 when unknown).
    fn begin(&self, stage: &str, total: u64) {
        let _ = (stage, total);
    }

    /// `units` more units of the current stage are done (may be called from any thread).
    fn advance(&self, units: u64) {
        let _ = units;
    }

    /// The current stage is finished.
    fn end(&self) {}
}

/// A [`Progress`] that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}
