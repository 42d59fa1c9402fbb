//! Executing a resolved pipeline: physical resources for a screen size, one pass object
//! per scheduled pass, per-pass GPU timestamps (and wall time per pass on request).

use std::collections::HashMap;
use std::time::Instant;

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{
    Access, ResolvedPipeline, ResourceDesc, ResourceUsage, ScheduledPass, SlotClass,
};
use ssbvb_voxel::camera::Camera;

use crate::gpu_scene::GpuScene;
use crate::{PassError, PassNode, create_pass};

/// A texture resource with the views passes need.
pub struct FrameTexture {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Default view (all aspects).
    pub view: wgpu::TextureView,
    /// Depth-only view for sampling depth(-stencil) textures.
    pub depth_view: Option<wgpu::TextureView>,
}

/// One live resource's GPU object (aliases share one). Few exist per frame, so the
/// size difference of the variants does not matter.
#[allow(clippy::large_enum_variant)]
pub enum FrameResource {
    /// A texture.
    Texture(FrameTexture),
    /// A buffer.
    Buffer(wgpu::Buffer),
}

/// The physical resources of one pipeline at one screen size.
pub struct FrameResources {
    physical: Vec<FrameResource>,
    /// `of_resource[i]`: physical index of resolved resource `i`.
    of_resource: Vec<usize>,
}

impl FrameResources {
    /// Creates every physical resource of `pipeline` at `screen`.
    pub fn new(
        ctx: &GpuContext,
        pipeline: &ResolvedPipeline,
        screen: (u32, u32),
    ) -> Result<Self, PassError> {
        Self::with_imports(ctx, pipeline, screen, &[])
    }

    /// Like [`FrameResources::new`], but the named resources are the caller's textures
    /// (their size must be the resource's size at `screen`, their format its format, their
    /// usage at least what the graph derived). An imported resource must not be aliased.
    pub fn with_imports(
        ctx: &GpuContext,
        pipeline: &ResolvedPipeline,
        screen: (u32, u32),
        imports: &[(&str, wgpu::Texture)],
    ) -> Result<Self, PassError> {
        let mut physical = Vec::new();
        for (i, p) in pipeline.physical.iter().enumerate() {
            let name = pipeline.resources[p.aliases[0]].name.clone();
            let label = format!("{name} (physical {i})");
            if let Some((_, tex)) = imports.iter().find(|(n, _)| *n == name) {
                physical.push(FrameResource::Texture(import(ctx, tex, &name, p, screen)?));
                continue;
            }
            let r = match (&p.desc, p.usage) {
                (ResourceDesc::Texture { format, size }, ResourceUsage::Texture(usage)) => {
                    let (w, h) = size.resolve(screen);
                    let format = texture_format(ctx, *format);
                    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
                        label: Some(&label),
                        size: wgpu::Extent3d {
                            width: w,
                            height: h,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        // Copies for readback in tests, tools and the embedding API.
                        usage: usage | wgpu::TextureUsages::COPY_SRC,
                        view_formats: &[],
                    });
                    let view = texture.create_view(&Default::default());
                    let depth_view = format.is_depth_stencil_format().then(|| {
                        texture.create_view(&wgpu::TextureViewDescriptor {
                            aspect: wgpu::TextureAspect::DepthOnly,
                            ..Default::default()
                        })
                    });
                    FrameResource::Texture(FrameTexture {
                        texture,
                        view,
                        depth_view,
                    })
                }
                (ResourceDesc::Buffer { layout, count }, ResourceUsage::Buffer(usage)) => {
                    let size = count.resolve(screen) * layout.element_size();
                    let max = ctx.device.limits().max_storage_buffer_binding_size;
                    if size > max {
                        return Err(PassError::TooLarge(format!(
                            "resource `{name}` needs {size} bytes, the device binds at most {max}"
                        )));
                    }
                    FrameResource::Buffer(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(&label),
                        size: size.max(16),
                        usage,
                        mapped_at_creation: false,
                    }))
                }
                _ => unreachable!("graph usages match descriptors"),
            };
            physical.push(r);
        }
        let of_resource = pipeline.resources.iter().map(|r| r.physical).collect();
        Ok(Self {
            physical,
            of_resource,
        })
    }

    /// The GPU object of resolved resource `i`.
    pub fn get(&self, i: usize) -> &FrameResource {
        &self.physical[self.of_resource[i]]
    }

    /// The texture of resolved resource `i` (panics if it is a buffer: the graph checked).
    pub fn texture(&self, i: usize) -> &FrameTexture {
        match self.get(i) {
            FrameResource::Texture(t) => t,
            FrameResource::Buffer(_) => panic!("resource {i} is a buffer"),
        }
    }

    /// The buffer of resolved resource `i`.
    pub fn buffer(&self, i: usize) -> &wgpu::Buffer {
        match self.get(i) {
            FrameResource::Buffer(b) => b,
            FrameResource::Texture(_) => panic!("resource {i} is a texture"),
        }
    }
}

/// Checks a caller's texture against a physical resource and wraps it.
fn import(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    name: &str,
    p: &ssbvb_graph::PhysicalResource,
    screen: (u32, u32),
) -> Result<FrameTexture, PassError> {
    if p.aliases.len() > 1 {
        return Err(PassError::BadScene(format!(
            "imported resource `{name}` shares memory with another resource"
        )));
    }
    let (ResourceDesc::Texture { size, format }, ResourceUsage::Texture(usage)) =
        (&p.desc, p.usage)
    else {
        return Err(PassError::BadScene(format!(
            "imported resource `{name}` is not a texture"
        )));
    };
    let want_format = texture_format(ctx, *format);
    if tex.format() != want_format {
        return Err(PassError::BadScene(format!(
            "imported `{name}` has format {:?}; the pipeline needs {want_format:?}",
            tex.format()
        )));
    }
    let want = size.resolve(screen);
    if (tex.width(), tex.height()) != want || !tex.usage().contains(usage) {
        return Err(PassError::BadScene(format!(
            "imported `{name}` is {}x{} with usage {:?}; the pipeline needs {}x{} with {usage:?}",
            tex.width(),
            tex.height(),
            tex.usage(),
            want.0,
            want.1
        )));
    }
    let view = tex.create_view(&Default::default());
    let depth_view = tex.format().is_depth_stencil_format().then(|| {
        tex.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        })
    });
    Ok(FrameTexture {
        texture: tex.clone(),
        view,
        depth_view,
    })
}

/// The wgpu format of a pipeline format on this device (Depth32FloatStencil8 falls back
/// to Depth24PlusStencil8 where the feature is missing).
pub fn texture_format(ctx: &GpuContext, format: ssbvb_graph::Format) -> wgpu::TextureFormat {
    match format.to_wgpu() {
        wgpu::TextureFormat::Depth32FloatStencil8
            if !ctx.has(wgpu::Features::DEPTH32FLOAT_STENCIL8) =>
        {
            wgpu::TextureFormat::Depth24PlusStencil8
        }
        f => f,
    }
}

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

/// How much timing to collect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Profiling {
    /// None: one submission per frame.
    #[default]
    Off,
    /// GPU timestamps per pass (when the device has them), one submission.
    Timestamps,
    /// Timestamps plus each pass submitted and waited for alone: per-pass wall time (what
    /// to trust on software adapters, whose timestamps are unreliable).
    TimestampsAndWall,
}

/// Timing of one pass.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PassTiming {
    /// Pass name.
    pub name: String,
    /// GPU time from timestamp queries, in ms.
    pub gpu_ms: Option<f64>,
    /// Wall time of its own submit + wait, in ms.
    pub wall_ms: Option<f64>,
}

/// What one frame did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Per-pass timings (empty with profiling off).
    pub passes: Vec<PassTiming>,
    /// Wall time from the first record to the end of the wait, in ms.
    pub frame_wall_ms: f64,
    /// Instances drawn after culling.
    pub visible_instances: usize,
}

/// A pipeline ready to draw a scene: resources, passes, profiler.
pub struct Renderer {
    /// The resolved pipeline.
    pub pipeline: ResolvedPipeline,
    /// Screen size.
    pub screen: (u32, u32),
    /// The frame's resources.
    pub resources: FrameResources,
    passes: Vec<Box<dyn PassNode>>,
    first_writes: Vec<Vec<&'static str>>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
}

impl Renderer {
    /// Creates resources and pass objects (pipelines are compiled here, not per frame).
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        pipeline: ResolvedPipeline,
        screen: (u32, u32),
    ) -> Result<Self, PassError> {
        Self::with_imports(ctx, scene, pipeline, screen, &[])
    }

    /// Like [`Renderer::new`], drawing into the caller's textures for the named resources
    /// (see [`FrameResources::with_imports`]). Imported resources keep their contents: no
    /// pass clears them, so the frame composes onto what the caller drew.
    pub fn with_imports(
        ctx: &GpuContext,
        scene: &GpuScene,
        pipeline: ResolvedPipeline,
        screen: (u32, u32),
        imports: &[(&str, wgpu::Texture)],
    ) -> Result<Self, PassError> {
        let resources = FrameResources::with_imports(ctx, &pipeline, screen, imports)?;
        let mut passes = Vec::new();
        for p in &pipeline.passes {
            let node = ctx
                .validated(&format!("creating pass `{}`", p.name), |_| {
                    create_pass(ctx, scene, &pipeline, p)
                })
                .map_err(PassError::Gpu)??;
            passes.push(node);
        }
        // Physical resources already written earlier in the frame (aliases included: a
        // reused physical resource starts over for its new alias).
        let mut written: Vec<Option<usize>> = vec![None; pipeline.physical.len()];
        let mut first_writes = Vec::new();
        for p in &pipeline.passes {
            let mut firsts = Vec::new();
            for b in p.bindings.iter().filter(|b| b.slot.access == Access::Write) {
                let phys = pipeline.resources[b.resource].physical;
                let imported = imports
                    .iter()
                    .any(|(n, _)| *n == pipeline.resources[b.resource].name);
                if written[phys] != Some(b.resource) && !imported {
                    firsts.push(b.slot.name);
                    written[phys] = Some(b.resource);
                }
            }
            first_writes.push(firsts);
        }
        let n = (pipeline.passes.len() * 2) as u32;
        let queries = ctx.report().timestamps.then(|| {
            let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: n,
            });
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: n as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, buf)
        });
        Ok(Self {
            pipeline,
            screen,
            resources,
            passes,
            first_writes,
            queries,
        })
    }

    /// Index of a live resource by name.
    pub fn resource(&self, name: &str) -> Option<usize> {
        self.pipeline.resource(name)
    }

    /// The SSBVB fill count of the last frame: billboards the ray-march filter emitted (the
    /// `instance_count` of the draw it fills). `None` when the pipeline has no filter.
    pub fn fill_count(&self, ctx: &GpuContext) -> Result<Option<u32>, PassError> {
        let has_filter = self
            .pipeline
            .passes
            .iter()
            .any(|p| matches!(p.kind, ssbvb_graph::PassKind::RayMarchFilter { .. }));
        if !has_filter {
            return Ok(None);
        }
        crate::ray_march_filter::fill_count(ctx, self).map(Some)
    }

    /// What the passes counted in the last frame (reads back from the GPU), with the
    /// SSBVB fill count as the billboards drawn and the billboard fragments per pixel
    /// showing a voxel (stencil).
    pub fn counters(&self, ctx: &GpuContext) -> Result<crate::FrameCounters, PassError> {
        let mut out = crate::FrameCounters::default();
        for p in &self.passes {
            p.counters(ctx, &mut out)?;
        }
        out.billboards_drawn = self.fill_count(ctx)?.map(u64::from);
        if let Some(f) = out.billboard_fragments {
            let covered = crate::measure::voxel_pixels(ctx, self)?;
            out.fragments_per_covered_pixel =
                covered.filter(|&c| c > 0).map(|c| f as f64 / c as f64);
        }
        Ok(out)
    }

    /// The output texture.
    pub fn output(&self) -> &FrameTexture {
        self.resources.texture(self.pipeline.output)
    }

    /// Draws one frame of `scene` seen by `camera`; waits for the GPU when profiling.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        scene: &mut GpuScene,
        camera: &Camera,
        profiling: Profiling,
    ) -> Result<FrameStats, PassError> {
        if profiling != Profiling::Off {
            // Earlier unwaited frames must not be billed to this one.
            ctx.wait_idle().map_err(PassError::Gpu)?;
        }
        let start = Instant::now();
        scene.stream_pages(ctx)?;
        scene.update(ctx, camera, self.screen);
        let use_ts = profiling != Profiling::Off && self.queries.is_some();
        let mut walls = vec![None; self.passes.len()];
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        scene.begin_frame(&mut encoder);
        let scene_ref: &GpuScene = scene;
        let visible_instances = scene_ref.visible.len();
        for (i, (node, pass)) in self
            .passes
            .iter_mut()
            .zip(&self.pipeline.passes)
            .enumerate()
        {
            let t0 = Instant::now();
            let mut rec = Recorder {
                gpu: ctx,
                scene: scene_ref,
                resources: &self.resources,
                pass,
                screen: self.screen,
                timestamps: if use_ts {
                    self.queries.as_ref().map(|(q, _)| (q, 2 * i as u32))
                } else {
                    None
                },
                first_writes: &self.first_writes[i],
            };
            ctx.validated(&format!("pass `{}`", pass.name), |_| {
                node.record(&mut encoder, &mut rec)
            })
            .map_err(PassError::Gpu)??;
            if profiling == Profiling::TimestampsAndWall {
                let done = std::mem::replace(
                    &mut encoder,
                    ctx.device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                            label: Some("frame"),
                        }),
                );
                ctx.queue.submit([done.finish()]);
                ctx.wait_idle().map_err(PassError::Gpu)?;
                walls[i] = Some(t0.elapsed().as_secs_f64() * 1e3);
            }
        }
        if use_ts {
            let (set, buf) = self.queries.as_ref().expect("queries exist");
            encoder.resolve_query_set(set, 0..(self.passes.len() * 2) as u32, buf, 0);
        }
        scene.end_frame(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        scene.after_submit();
        let mut gpu_ms = vec![None; self.passes.len()];
        if use_ts {
            let (_, buf) = self.queries.as_ref().expect("queries exist");
            let raw: Vec<u64> =
                bytemuck::pod_collect_to_vec(&ctx.read_buffer(buf).map_err(PassError::Gpu)?);
            let period = ctx.queue.get_timestamp_period() as f64;
            for (i, ms) in gpu_ms.iter_mut().enumerate() {
                let (a, b) = (raw[2 * i], raw[2 * i + 1]);
                *ms = (b >= a).then(|| (b - a) as f64 * period / 1e6);
            }
        } else if profiling != Profiling::Off {
            ctx.wait_idle().map_err(PassError::Gpu)?;
        }
        let errors = ctx.take_uncaptured_errors();
        if !errors.is_empty() {
            return Err(PassError::Gpu(ssbvb_gpu::GpuError::Wgpu {
                label: "frame".into(),
                kind: "uncaptured",
                message: errors.join("; "),
            }));
        }
        let passes = if profiling == Profiling::Off {
            Vec::new()
        } else {
            self.pipeline
                .passes
                .iter()
                .enumerate()
                .map(|(i, p)| PassTiming {
                    name: p.name.clone(),
                    gpu_ms: gpu_ms[i],
                    wall_ms: walls[i],
                })
                .collect()
        };
        Ok(FrameStats {
            passes,
            frame_wall_ms: start.elapsed().as_secs_f64() * 1e3,
            visible_instances,
        })
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
