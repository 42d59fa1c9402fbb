//! Reading a frame's SSBVB back: the indirect draw the filter wrote and its filled slots
//! (tests and the accuracy measures).

use ssbvb_gpu::GpuContext;
use ssbvb_graph::PassKind;

use crate::error::PassError;
use crate::kinds::ray_march_filter::{DrawArgs, VoxelSlot, parse_draw_args};
use crate::runtime::renderer::Renderer;

/// The scheduled `RayMarchFilter` pass of a renderer's pipeline and the resource bound to
/// one of its slots.
fn filter_resource(renderer: &Renderer, slot: &str) -> Result<usize, PassError> {
    renderer
        .pipeline
        .passes
        .iter()
        .find(|p| matches!(p.kind, PassKind::RayMarchFilter { .. }))
        .and_then(|p| p.resource_of(slot))
        .ok_or_else(|| {
            PassError::BadScene(format!(
                "the pipeline has no live RayMarchFilter pass with a `{slot}` slot"
            ))
        })
}

/// Whether `renderer`'s pipeline has an SSBVB: a `RayMarchFilter` pass whose slots can be
/// read back (`RayMarchGBuffer` writes its hits into the G-buffer, and has none).
pub fn has_ssbvb(renderer: &Renderer) -> bool {
    filter_resource(renderer, "ssbvb").is_ok()
}

/// Reads back the indirect draw written by the filter of `renderer`'s last frame: the SSBVB
/// fill count is its `instance_count`. Meaningful after `Renderer::render` while the
/// `billboard_draw` resource is still intact (the pipeline's output, in `keep`, or not
/// aliased by a later pass).
pub fn draw_args(ctx: &GpuContext, renderer: &Renderer) -> Result<DrawArgs, PassError> {
    let i = filter_resource(renderer, "billboard_draw")?;
    parse_draw_args(&ctx.read_buffer(renderer.resources.buffer(i))?)
}

/// The filled SSBVB slots of `renderer`'s last frame (the first fill-count entries of the
/// `ssbvb` resource, clamped to its capacity).
pub fn read_slots(ctx: &GpuContext, renderer: &Renderer) -> Result<Vec<VoxelSlot>, PassError> {
    let count = draw_args(ctx, renderer)?.instance_count as usize;
    let i = filter_resource(renderer, "ssbvb")?;
    let bytes = ctx.read_buffer(renderer.resources.buffer(i))?;
    let all: Vec<VoxelSlot> = bytemuck::pod_collect_to_vec(&bytes[..bytes.len() / 32 * 32]);
    Ok(all.into_iter().take(count).collect())
}
