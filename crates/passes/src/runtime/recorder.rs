//! What a pass sees while it records: the device, the scene, the frame's resources by
//! slot name, which writes clear, and the pass's timestamp queries.

use std::collections::HashMap;

use ssbvb_gpu::scene::GpuScene;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{Access, ResolvedPipeline, ResourceDesc, ScheduledPass, SlotClass};

use super::resources::{FrameResources, FrameTexture, texture_format};

/// What a pass sees while recording.
pub struct Recorder<'a> {
    /// The device.
    pub gpu: &'a GpuContext,
    /// The scene (group 0 bind group, visible instances, meshes).
    pub scene: &'a GpuScene,
    /// The frame's resources.
    pub resources: &'a FrameResources,
    /// The pass being recorded (slot → resource bindings).
    pub pass: &'a ScheduledPass,
    /// Screen size.
    pub screen: (u32, u32),
    /// Timestamp queries for this pass (begin, end), when profiling.
    pub timestamps: Option<(&'a wgpu::QuerySet, u32)>,
    /// Write slots whose resource no earlier pass of the frame wrote: clear them.
    pub first_writes: &'a [&'static str],
    /// Whether the frame counts its work for [`crate::Renderer::counters`] (passes that
    /// count run a variant without the counting otherwise).
    pub counting: bool,
}

impl<'a> Recorder<'a> {
    fn resource(&self, slot: &str) -> usize {
        self.pass
            .resource_of(slot)
            .unwrap_or_else(|| panic!("pass `{}` has no slot `{slot}`", self.pass.name))
    }

    /// The texture bound to `slot`.
    pub fn texture(&self, slot: &str) -> &'a FrameTexture {
        self.resources.texture(self.resource(slot))
    }

    /// The buffer bound to `slot`.
    pub fn buffer(&self, slot: &str) -> &'a wgpu::Buffer {
        self.resources.buffer(self.resource(slot))
    }

    /// Whether this pass is the first to write `slot`'s resource this frame (then it
    /// clears; later writers load what earlier ones drew).
    pub fn clears(&self, slot: &str) -> bool {
        self.first_writes.contains(&slot)
    }

    /// `Clear(clear)` for the first writer of `slot`, else `Load`.
    pub fn load_op<V>(&self, slot: &str, clear: V) -> wgpu::LoadOp<V> {
        if self.clears(slot) {
            wgpu::LoadOp::Clear(clear)
        } else {
            wgpu::LoadOp::Load
        }
    }

    /// The colour attachment of `slot`: cleared to transparent black by its first writer
    /// of the frame, loaded by later ones, stored.
    pub fn color_attachment(&self, slot: &str) -> Option<wgpu::RenderPassColorAttachment<'a>> {
        Some(wgpu::RenderPassColorAttachment {
            view: &self.texture(slot).view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: self.load_op(slot, wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })
    }

    /// Records a render pass that draws one fullscreen triangle with `pipeline` into
    /// `color_attachments`, with the scene's bind group at group 0 and `bind_group` at
    /// group 1.
    pub fn draw_fullscreen(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        color_attachments: &[Option<wgpu::RenderPassColorAttachment<'_>>],
        pipeline: &wgpu::RenderPipeline,
        bind_group: &wgpu::BindGroup,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.pass.name),
            color_attachments,
            timestamp_writes: self.render_timestamps(),
            ..Default::default()
        });
        pass.set_bind_group(0, &self.scene.bind_group, &[]);
        pass.set_bind_group(1, bind_group, &[]);
        pass.set_pipeline(pipeline);
        pass.draw(0..3, 0..1);
    }

    /// Timestamp writes for a render pass.
    pub fn render_timestamps(&self) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        self.timestamps
            .map(|(q, i)| wgpu::RenderPassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
    }

    /// Timestamp writes for a compute pass.
    pub fn compute_timestamps(&self) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        self.timestamps
            .map(|(q, i)| wgpu::ComputePassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
    }

    /// The beginning of a pass's time in its first (compute) pass, for a pass that records
    /// a compute pass and then a render pass; [`Recorder::span_end_timestamps`] ends it.
    pub fn span_begin_timestamps(&self) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        self.compute_timestamps()
            .map(|t| wgpu::ComputePassTimestampWrites {
                end_of_pass_write_index: None,
                ..t
            })
    }

    /// The end of a pass's time in its last (render) pass.
    pub fn span_end_timestamps(&self) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        self.render_timestamps()
            .map(|t| wgpu::RenderPassTimestampWrites {
                beginning_of_pass_write_index: None,
                ..t
            })
    }
}

/// The wgpu format a pass will see for the texture bound to `slot` (after fallbacks).
pub fn slot_format(
    ctx: &GpuContext,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
    slot: &str,
) -> wgpu::TextureFormat {
    let r = pass
        .resource_of(slot)
        .unwrap_or_else(|| panic!("pass `{}` has no slot `{slot}`", pass.name));
    match &pipeline.resources[r].desc {
        ResourceDesc::Texture { format, .. } => texture_format(ctx, *format),
        ResourceDesc::Buffer { .. } => panic!("slot `{slot}` is a buffer"),
    }
}

/// Which slots of a pass are attachments, by name (helper for pass modules).
pub fn attachments(pass: &ScheduledPass) -> HashMap<&'static str, Access> {
    pass.bindings
        .iter()
        .filter(|b| {
            matches!(
                b.slot.class,
                SlotClass::ColorAttachment(_) | SlotClass::DepthStencilAttachment(_)
            )
        })
        .map(|b| (b.slot.name, b.slot.access))
        .collect()
}
