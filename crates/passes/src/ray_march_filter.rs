//! `ray_march_filter`: the voxel filter (`RayMarchFilter`; `shaders/ray_march_filter.wgsl`).
//!
//! A compute pass, one thread per pixel: from the empty-space prepass's entry point it
//! marches the sparse lookup of the pixel's instance with a hierarchical voxel DDA (empty
//! coarse blocks of 64³ cells and non-resident 16³ pages are crossed in one step) to the
//! first voxel, and appends that voxel to the SSBVB (`ssbvb`) with an atomic counter that
//! is also the instance count of the billboard pass's indirect draw (`billboard_draw`).
//! Hits are compacted: slots `0..count` are valid, one per covered pixel, so
//! `count <= width * height`.
//!
//! The march follows the CPU reference's rules (`ssbvb_voxel::reference::dda`) in f32:
//! crossing times per plane, mirrored axes, the reference's tie and face rules; the WGSL
//! file's header explains how it stays robust. With several visible instances each covered
//! pixel also box-tests every other instance and marches those whose box entry is nearer
//! than its best hit: O(instances) per covered pixel, the price of exact results where
//! objects overlap.
//!
//! Two dispatches in one compute pass: `clear_draw` (one thread) resets the draw to
//! `{6, 0, 0, 0}`, then `main` over `ceil(w / 8) × ceil(h / 8)` workgroups of 8 × 8.

use bytemuck::{Pod, Zeroable};
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{PassKind, ResolvedPipeline, ScheduledPass};
use ssbvb_voxel::asset::PackedVoxel;

use crate::frame::{Recorder, Renderer};
use crate::gpu_scene::GpuScene;
use crate::{PassError, PassNode, shaders};

/// Workgroup edge of `main` (`@workgroup_size(8, 8)`).
pub const WORKGROUP: u32 = 8;

/// Mirror of WGSL `VoxelSlot` (32 bytes): one SSBVB entry.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct VoxelSlot {
    /// The hit voxel, copied from its LOD's point cloud.
    pub voxel: PackedVoxel,
    /// Index of the instance in the frame's visible instances.
    pub instance: u32,
    /// `y * width + x` of the pixel whose ray found it.
    pub pixel: u32,
    /// World distance from the eye along the pixel's normalized ray to the entered face.
    pub t: f32,
    /// Entered face: 0..=2 the -X/-Y/-Z side (normal towards -axis), 3..=5 the +X/+Y/+Z
    /// side.
    pub face: u32,
}

impl VoxelSlot {
    /// The object-space unit normal of the entered face.
    pub fn face_normal(&self) -> [f32; 3] {
        let mut n = [0.0; 3];
        n[(self.face % 3) as usize] = if self.face >= 3 { 1.0 } else { -1.0 };
        n
    }
}

/// Mirror of the indirect draw arguments in `billboard_draw`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct DrawArgs {
    /// Vertices per billboard (6).
    pub vertex_count: u32,
    /// Filled SSBVB slots.
    pub instance_count: u32,
    /// Always 0.
    pub first_vertex: u32,
    /// Always 0.
    pub first_instance: u32,
}

/// The compiled filter.
pub struct RayMarchFilter {
    clear: wgpu::ComputePipeline,
    main: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl RayMarchFilter {
    /// Compiles both entry points; `max_steps` becomes the WGSL override `MAX_STEPS`.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        _pipeline: &ResolvedPipeline,
        pass: &ScheduledPass,
    ) -> Result<Self, PassError> {
        let PassKind::RayMarchFilter { max_steps } = pass.kind else {
            return Err(PassError::Shader(format!(
                "pass `{}` is not a RayMarchFilter",
                pass.name
            )));
        };
        let module = ctx.shader(
            "ray_march_filter.wgsl",
            &shaders::source("ray_march_filter.wgsl")?,
        )?;
        let label = format!("pass `{}`: ray_march_filter pipelines", pass.name);
        let built = ctx.validated(&label, |d| {
            let storage = |binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("ray_march_filter"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::Texture {
                            // Rgba32Float is not filterable everywhere; textureLoad only.
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                    storage(1),
                    storage(2),
                ],
            });
            let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("ray_march_filter"),
                bind_group_layouts: &[Some(&scene.layout), Some(&layout)],
                immediate_size: 0,
            });
            let constants = [("MAX_STEPS", f64::from(max_steps))];
            let make = |entry: &str| {
                d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pl),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    cache: None,
                })
            };
            (make("clear_draw"), make("main"), layout)
        })?;
        let (clear, main, layout) = built;
        Ok(Self {
            clear,
            main,
            layout,
        })
    }
}

impl PassNode for RayMarchFilter {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let bind_group = rec
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ray_march_filter"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&rec.texture("entry").view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: rec.buffer("ssbvb").as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: rec.buffer("billboard_draw").as_entire_binding(),
                    },
                ],
            });
        let (w, h) = rec.screen;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&rec.pass.name),
            timestamp_writes: rec.compute_timestamps(),
        });
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_pipeline(&self.clear);
        pass.dispatch_workgroups(1, 1, 1);
        // wgpu orders the two dispatches (the draw arguments are written, then counted).
        pass.set_pipeline(&self.main);
        pass.dispatch_workgroups(w.div_ceil(WORKGROUP), h.div_ceil(WORKGROUP), 1);
        Ok(())
    }
}

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

/// Reads back the indirect draw written by the filter of `renderer`'s last frame: the SSBVB
/// fill count is its `instance_count`. Meaningful after `Renderer::render` while the
/// `billboard_draw` resource is still intact (the pipeline's output, in `keep`, or not
/// aliased by a later pass).
pub fn draw_args(ctx: &GpuContext, renderer: &Renderer) -> Result<DrawArgs, PassError> {
    let i = filter_resource(renderer, "billboard_draw")?;
    let bytes = ctx.read_buffer(renderer.resources.buffer(i))?;
    let args: &[DrawArgs] = bytemuck::try_cast_slice(&bytes[..16.min(bytes.len())])
        .map_err(|e| PassError::BadScene(format!("billboard_draw readback: {e}")))?;
    args.first()
        .copied()
        .ok_or_else(|| PassError::BadScene("billboard_draw readback is empty".into()))
}

/// The number of SSBVB slots the filter filled in `renderer`'s last frame (see
/// [`draw_args`] for when it can be read).
pub fn fill_count(ctx: &GpuContext, renderer: &Renderer) -> Result<u32, PassError> {
    Ok(draw_args(ctx, renderer)?.instance_count)
}

/// The filled SSBVB slots of `renderer`'s last frame (the first [`fill_count`] entries of
/// the `ssbvb` resource, clamped to its capacity).
pub fn read_slots(ctx: &GpuContext, renderer: &Renderer) -> Result<Vec<VoxelSlot>, PassError> {
    let count = fill_count(ctx, renderer)? as usize;
    let i = filter_resource(renderer, "ssbvb")?;
    let bytes = ctx.read_buffer(renderer.resources.buffer(i))?;
    let all: Vec<VoxelSlot> = bytemuck::pod_collect_to_vec(&bytes[..bytes.len() / 32 * 32]);
    Ok(all.into_iter().take(count).collect())
}
