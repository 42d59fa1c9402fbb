//! The G-buffer every geometry pass writes (billboards, triangles and the baselines):
//! attachments, formats, stencil values, and how a writer begins its render pass.
//!
//!
//! | location | slot               | format                     | contents                                          |
//! |----------|--------------------|----------------------------|---------------------------------------------------|
//! | 0        | `gbuffer_albedo`   | `Rgba8Unorm`               | linear albedo, alpha 1 where something was drawn  |
//! | 1        | `gbuffer_normal`   | `Rgba16Float` (or 32-bit)  | world-space unit normal, w = 1                    |
//! | 2        | `gbuffer_position` | `Rgba32Float`              | camera-relative world position, w = linear depth  |
//! | depth    | `depth_stencil`    | `Depth32FloatStencil8` (else `Depth24PlusStencil8`) | reversed-Z depth, stencil 1 voxel / 2 triangle |
//!
//! Linear depth is the distance along the camera's forward axis (the reference's
//! `view_depth`). The first pass of the frame that writes a slot clears it (colours to 0,
//! depth to 0 = infinitely far in reversed Z, stencil to 0); later ones load. Depth is tested
//! with `Greater` and written.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{ResolvedPipeline, ScheduledPass};

use crate::PassError;
use crate::bindings::PassBindings;
use crate::frame::{Recorder, slot_format};
use crate::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::registry::{PassImpl, PassInit};
use crate::shaders;

/// Stencil value of voxel pixels (`STENCIL_VOXEL` in common.inc.wgsl).
pub const STENCIL_VOXEL: u32 = 1;

/// Stencil value of triangle pixels (`STENCIL_TRIANGLE` in common.inc.wgsl).
pub const STENCIL_TRIANGLE: u32 = 2;

/// The three colour slots of the G-buffer, in location order.
pub const GBUFFER_COLOR_SLOTS: [&str; 3] = ["gbuffer_albedo", "gbuffer_normal", "gbuffer_position"];

/// Colour target states of the G-buffer (locations 0..2) with the formats bound to `pass`.
pub(crate) fn gbuffer_targets(
    ctx: &GpuContext,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
) -> [Option<wgpu::ColorTargetState>; 3] {
    GBUFFER_COLOR_SLOTS.map(|s| Some(slot_format(ctx, pipeline, pass, s).into()))
}

/// Depth `Greater` with write; stencil always passes and replaces with the reference.
pub(crate) fn gbuffer_depth_stencil(
    ctx: &GpuContext,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
) -> wgpu::DepthStencilState {
    let face = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: wgpu::StencilOperation::Replace,
    };
    wgpu::DepthStencilState {
        format: slot_format(ctx, pipeline, pass, "depth_stencil"),
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Greater),
        stencil: wgpu::StencilState {
            front: face,
            back: face,
            read_mask: 0xff,
            write_mask: 0xff,
        },
        bias: Default::default(),
    }
}

/// Begins a render pass on the G-buffer slots of `rec.pass` (clearing the slots this pass
/// writes first in the frame) with `stencil` as the stencil reference.
pub(crate) fn begin_gbuffer_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    rec: &Recorder<'_>,
    stencil: u32,
) -> wgpu::RenderPass<'e> {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(&rec.pass.name),
        color_attachments: &GBUFFER_COLOR_SLOTS.map(|s| rec.color_attachment(s)),
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &rec.texture("depth_stencil").view,
            depth_ops: Some(wgpu::Operations {
                load: rec.load_op("depth_stencil", 0.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: Some(wgpu::Operations {
                load: rec.load_op("depth_stencil", 0),
                store: wgpu::StoreOp::Store,
            }),
        }),
        timestamp_writes: rec.render_timestamps(),
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_stencil_reference(stencil);
    pass
}

/// The compiled pipeline of a G-buffer writer that pulls its own vertices (`vs_main`, no
/// vertex buffers) and writes the G-buffer in `fs_main`: the ray-casting baselines and the
/// cube rasterizer. Group 1 holds only the pass's own resources.
pub(crate) struct PulledPipeline {
    /// The render pipeline.
    pub pipeline: wgpu::RenderPipeline,
    /// Its group-1 layout (own bindings).
    pub bindings: PassBindings,
}

impl PulledPipeline {
    /// Compiles pass `P`'s shader for the formats bound to `init.pass`, with `constants`
    /// as WGSL overrides and `P`'s own bindings as group 1.
    pub fn new<P: PassImpl>(
        init: &PassInit<'_>,
        constants: &[(&str, f64)],
    ) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = init.parts();
        let (shader, own) = (P::SHADER, P::OWN);
        let module = ctx.shader(shader, &shaders::source(shader)?)?;
        let targets = gbuffer_targets(ctx, pipeline, pass);
        let depth_stencil = gbuffer_depth_stencil(ctx, pipeline, pass);
        let label = format!("pass `{}`: {shader} pipeline", pass.name);
        Ok(ctx.validated(&label, |d| {
            let bindings = PassBindings::new(ctx, pipeline, pass, own);
            let layout = pipeline_layout(d, &label, scene, Some(&bindings));
            let pipeline = render_pipeline(
                d,
                &RenderSpec {
                    constants,
                    depth_stencil: Some(depth_stencil),
                    ..RenderSpec::new(&label, &module, &layout, &targets)
                },
            );
            Self { pipeline, bindings }
        })?)
    }

    /// Records a ray-casting baseline's frame: the G-buffer pass begins in any case (its
    /// clears happen even when nothing is visible) and one fullscreen triangle is drawn
    /// when there is something to cast against (`bind_group`).
    pub fn record_fullscreen(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        bind_group: Option<&wgpu::BindGroup>,
    ) {
        let mut pass = begin_gbuffer_pass(encoder, rec, STENCIL_VOXEL);
        if let Some(bg) = bind_group {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, bg, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
