//! The one way a scene goes to the GPU and a pipeline becomes a renderer, for every front
//! end that drives frames itself (the viewer, the page, the bench's presets) and for the
//! engine's own session: whole, streamed under a budget, or with room for changing
//! objects.

use ssbvb_gpu::scene::{DynamicRoom, GpuScene, Scene, StreamingOptions};
use ssbvb_gpu::{GpuContext, ResourceError};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::{PassError, Renderer};

/// How a scene's voxels live on the GPU.
#[derive(Clone, Copy)]
pub enum Residency<'a> {
    /// Every level resident.
    Whole,
    /// Levels above the coarsest paged in under a budget as rays need them.
    Streamed(&'a StreamingOptions),
    /// Room reserved for objects whose voxels change (animated, brushed).
    Dynamic(&'a [DynamicRoom]),
}

/// `scene` uploaded to `ctx` with `residency`. The error is the resource error itself, so
/// a caller can tell a scene too large or a budget too small from other failures.
pub fn upload_scene(
    ctx: &GpuContext,
    scene: Scene,
    residency: Residency<'_>,
) -> Result<GpuScene, ResourceError> {
    match residency {
        Residency::Whole | Residency::Dynamic([]) => GpuScene::new(ctx, scene),
        Residency::Streamed(options) => GpuScene::streamed(ctx, scene, options),
        Residency::Dynamic(rooms) => GpuScene::with_dynamic(ctx, scene, rooms),
    }
}

/// The renderer of `pipeline` over `scene` at `size` (its pipelines compiled here); the
/// error is the pass error itself (a pipeline that needs whole levels, one too large).
pub fn renderer(
    ctx: &GpuContext,
    scene: &GpuScene,
    pipeline: ResolvedPipeline,
    size: (u32, u32),
) -> Result<Renderer, PassError> {
    Renderer::new(ctx, scene, pipeline, size)
}
