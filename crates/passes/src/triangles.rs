//! `triangles`: the scene's ordinary triangle meshes drawn into the G-buffer with
//! stencil = triangle (see `shaders/triangles.wgsl`), plus the G-buffer attachment setup it
//! shares with [`crate::billboards`].
//!
//! # The G-buffer (written by both passes)
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

use crate::bindings::{OwnBinding, OwnKind, PassBindings};
use crate::frame::{Recorder, slot_format};
use crate::gpu_scene::GpuScene;
use crate::{PassError, PassNode, shaders};

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

/// The render pipeline of a G-buffer writer that pulls its own vertices (`vs_main`, no
/// vertex buffers, no culling) and writes the G-buffer in `fs_main`: group 0 the scene,
/// group 1 `pass_layout`; `constants` are the fragment stage's overrides.
#[allow(clippy::too_many_arguments)]
pub(crate) fn gbuffer_pipeline(
    d: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    scene_layout: &wgpu::BindGroupLayout,
    pass_layout: &wgpu::BindGroupLayout,
    constants: &[(&str, f64)],
    targets: &[Option<wgpu::ColorTargetState>],
    depth_stencil: wgpu::DepthStencilState,
) -> wgpu::RenderPipeline {
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(scene_layout), Some(pass_layout)],
        immediate_size: 0,
    });
    d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pl),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_main"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            targets,
        }),
        // Default: triangle list, no culling.
        primitive: Default::default(),
        depth_stencil: Some(depth_stencil),
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// Begins a render pass on the G-buffer slots of `rec.pass` (clearing the slots this pass
/// writes first in the frame) with `stencil` as the stencil reference.
pub(crate) fn begin_gbuffer_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    rec: &Recorder<'_>,
    stencil: u32,
) -> wgpu::RenderPass<'e> {
    let color = |slot: &'static str| {
        Some(wgpu::RenderPassColorAttachment {
            view: &rec.texture(slot).view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: rec.load_op(slot, wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })
    };
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(&rec.pass.name),
        color_attachments: &GBUFFER_COLOR_SLOTS.map(color),
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

/// What the triangles pass binds itself: the uniform of the mesh being drawn.
pub const OWN: &[OwnBinding] = &[OwnBinding {
    name: "mesh",
    kind: OwnKind::Uniform,
}];

/// The triangles pass: one indexed draw per scene mesh.
pub struct Triangles {
    pipeline: wgpu::RenderPipeline,
    bindings: PassBindings,
}

impl Triangles {
    /// Compiles the pipeline for the formats bound to `pass`.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        pipeline: &ResolvedPipeline,
        pass: &ScheduledPass,
    ) -> Result<Self, PassError> {
        let d = &ctx.device;
        let module = ctx.shader("triangles.wgsl", &shaders::source("triangles.wgsl")?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, OWN);
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("triangles"),
            bind_group_layouts: &[Some(&scene.layout), Some(&bindings.layout)],
            immediate_size: 0,
        });
        let targets = gbuffer_targets(ctx, pipeline, pass);
        let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("triangles"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 24,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                })],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            // Two-sided: open meshes (a ground plane, the teapot) are visible from both
            // sides; the shader turns the normal towards the camera.
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(gbuffer_depth_stencil(ctx, pipeline, pass)),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        Ok(Self { pipeline, bindings })
    }
}

impl PassNode for Triangles {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let meshes: Vec<_> = rec
            .scene
            .meshes
            .iter()
            .filter(|m| m.index_count > 0 && m.vertices.size() > 0)
            .map(|m| {
                let bg = self
                    .bindings
                    .bind_group(rec, &[("mesh", m.uniform.as_entire_binding())]);
                bg.map(|bg| (m, bg))
            })
            .collect::<Result<_, _>>()?;
        let mut pass = begin_gbuffer_pass(encoder, rec, STENCIL_TRIANGLE);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        for (m, bg) in &meshes {
            pass.set_bind_group(1, bg, &[]);
            pass.set_vertex_buffer(0, m.vertices.slice(..));
            pass.set_index_buffer(m.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..m.index_count, 0, 0..1);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_triangle_stencil_matches_the_shader() {
        // The Mesh layout is checked by `cargo xtask validate-shaders`.
        let src = shaders::source("triangles.wgsl").unwrap();
        assert!(src.contains("const STENCIL_TRIANGLE: u32 = 2u;"));
        assert_eq!(STENCIL_TRIANGLE, 2);
    }
}
