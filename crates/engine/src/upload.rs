//! The one way a scene goes to the GPU and a pipeline becomes a renderer, for every front
//! end that drives frames itself (the viewer, the page, the bench's presets) and for the
//! engine's own session: whole, streamed under a budget, or with room for changing
//! objects.

use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{DynamicRoom, GpuScene, Scene, StreamingOptions};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::Renderer;

use crate::EngineError;

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

/// `scene` uploaded to `ctx` with `residency`.
pub fn upload_scene(
    ctx: &GpuContext,
    scene: Scene,
    residency: Residency<'_>,
) -> Result<GpuScene, EngineError> {
    Ok(match residency {
        Residency::Whole => GpuScene::new(ctx, scene)?,
        Residency::Streamed(options) => GpuScene::streamed(ctx, scene, options)?,
        Residency::Dynamic([]) => GpuScene::new(ctx, scene)?,
        Residency::Dynamic(rooms) => GpuScene::with_dynamic(ctx, scene, rooms)?,
    })
}

/// The renderer of `pipeline` over `scene` at `size` (its pipelines compiled here).
pub fn renderer(
    ctx: &GpuContext,
    scene: &GpuScene,
    pipeline: ResolvedPipeline,
    size: (u32, u32),
) -> Result<Renderer, EngineError> {
    Ok(Renderer::new(ctx, scene, pipeline, size)?)
}

/// [`upload_scene`] then [`renderer`].
pub fn scene_and_renderer(
    ctx: &GpuContext,
    scene: Scene,
    residency: Residency<'_>,
    pipeline: ResolvedPipeline,
    size: (u32, u32),
) -> Result<(GpuScene, Renderer), EngineError> {
    let scene = upload_scene(ctx, scene, residency)?;
    let renderer = renderer(ctx, &scene, pipeline, size)?;
    Ok((scene, renderer))
}
