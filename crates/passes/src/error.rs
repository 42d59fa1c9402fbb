//! What building or running passes can fail with.

use ssbvb_gpu::{GpuError, ResourceError};

/// Errors of building or running passes.
#[derive(Debug, thiserror::Error)]
pub enum PassError {
    /// wgpu reported an error.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// Building or updating a GPU resource (the scene, its pools, a kernel, a shader
    /// source) failed.
    #[error(transparent)]
    Resource(#[from] ResourceError),
    /// A kind has no implementation yet.
    #[error("pass `{pass}`: pass kind {kind} has no GPU implementation yet")]
    NotImplemented {
        /// Pass name.
        pass: String,
        /// Kind name.
        kind: &'static str,
    },
    /// The pass cannot run on this backend (the message says why, and what can).
    #[error("unsupported here: {0}")]
    Unsupported(String),
    /// Something exceeds a device or index limit.
    #[error("too large for the GPU: {0}")]
    TooLarge(String),
    /// A pass's bind group was asked for without the resources its declaration names (a
    /// bug in the pass, reported rather than a panic).
    #[error("bindings: {0}")]
    Bindings(String),
    /// The scene is unusable for this pass.
    #[error("bad scene: {0}")]
    BadScene(String),
    /// A frame's work counters contradict each other (a bug in the pass's shader: the
    /// numbers are refused rather than reported).
    #[error("the frame's work counters are inconsistent: {0}")]
    InconsistentCounters(String),
    /// A pass reads whole levels and cannot run on paged ones.
    #[error(
        "pass `{pass}` (kind {kind}) reads every voxel of a level and cannot run under a GPU budget (--gpu-budget pages levels above {pinned}); only the SSBVB filter's pipelines stream"
    )]
    NeedsWholeLevels {
        /// Pass name.
        pass: String,
        /// Kind name.
        kind: &'static str,
        /// The finest level resident whole.
        pinned: u32,
    },
}

impl PassError {
    /// Whether something exceeded a device or index limit, in a pass or in a resource it
    /// builds on.
    pub fn is_too_large(&self) -> bool {
        matches!(
            self,
            PassError::TooLarge(_) | PassError::Resource(ResourceError::TooLarge(_))
        )
    }

    /// Whether the scene was refused, by a pass or by the resources it builds on.
    pub fn is_bad_scene(&self) -> bool {
        matches!(
            self,
            PassError::BadScene(_) | PassError::Resource(ResourceError::BadScene(_))
        )
    }
}
