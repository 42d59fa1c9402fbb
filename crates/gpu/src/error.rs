//! Errors of building and updating GPU resources: the scene on the GPU, its pools and
//! streams, the compute kernels and the shader sources. `ssbvb_passes::PassError` wraps
//! this type.

use crate::GpuError;

/// Errors of GPU resources (the scene, its pools, compute kernels, shader sources).
#[derive(Debug, thiserror::Error)]
pub enum ResourceError {
    /// wgpu reported an error.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// Something exceeds a device or index limit.
    #[error("too large for the GPU: {0}")]
    TooLarge(String),
    /// The scene is unusable.
    #[error("bad scene: {0}")]
    BadScene(String),
    /// A shader could not be assembled.
    #[error("shader {0}")]
    Shader(String),
    /// A GPU budget smaller than what never leaves the GPU plus one page.
    #[error(
        "a GPU budget of {} MiB is too small for this scene: the lookup trees, the pinned \
         coarse levels and the proxies take {} MiB with one page; use --gpu-budget {} or more",
        .budget.div_ceil(1 << 20), .minimum.div_ceil(1 << 20), .minimum.div_ceil(1 << 20)
    )]
    BudgetTooSmall {
        /// The budget asked for (bytes).
        budget: u64,
        /// The smallest budget that works (bytes).
        minimum: u64,
    },
}
