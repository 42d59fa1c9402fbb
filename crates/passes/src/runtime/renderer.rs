//! Executing a resolved pipeline: physical resources for a screen size, one pass object
//! per scheduled pass, per-pass GPU timestamps (and wall time per pass on request).

use web_time::Instant;

use ssbvb_gpu::scene::GpuScene;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{Access, ResolvedPipeline};
use ssbvb_voxel::camera::Camera;

use super::counters::FrameCounters;
use super::node::{CounterSource, PassNode};
use super::recorder::Recorder;
use super::resources::{FrameResources, FrameTexture};
use crate::error::PassError;
use crate::kinds::create_pass;

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
    /// GPU timestamps per pass written and resolved but not waited for: the frame's
    /// [`FrameStats::passes`] are empty and [`Renderer::pass_times_readout`] reads them
    /// later (the browser, whose thread must not block).
    TimestampsUnwaited,
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

/// Whether every pass of `pipeline` is scene-free.
fn pipeline_scene_free(pipeline: &ResolvedPipeline) -> bool {
    pipeline
        .passes
        .iter()
        .all(|p| crate::kinds::registration(&p.kind).is_some_and(|r| r.scene_free))
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
    counting: bool,
    /// With a pass that asks for jittered frames ([`PassNode::jittered_lod_bias`]): the
    /// index of the next frame's jitter ([`super::jitter::jitter`]); `None`: frames are
    /// not jittered.
    jitter_frame: Option<u64>,
    /// Levels finer than Auto LOD's choice this pipeline draws at (its temporal pass's
    /// `lod_bias`; [`GpuScene::lod_bias`]).
    lod_bias: u32,
    /// Every pass is scene-free ([`crate::runtime::registry::PassImpl::SCENE_FREE`]).
    scene_free: bool,
    /// The scene's binding counts and whether it streamed, when the passes were made.
    made_for: (ssbvb_gpu::scene_bindings::SceneBindings, bool),
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
        // The device was chosen for the pipeline before the scene was loaded; a scene whose
        // streams take more bindings than one each may need more than it allows.
        let verdict = crate::pipeline_requirements_for(&pipeline, &scene.bindings)
            .check_under(&ctx.adapter, &ctx.device.limits());
        if !verdict.fits() {
            return Err(PassError::TooLarge(format!(
                "this scene's streams take {} + {} bindings: {}",
                scene.bindings.word_chunks,
                scene.bindings.node_chunks,
                verdict.missing.join("; ")
            )));
        }
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
        // A pass that averages jittered frames asks for them (and for finer levels).
        let jittered_lod_bias = passes.iter().find_map(|n| n.jittered_lod_bias());
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
            screen,
            resources,
            passes,
            first_writes,
            queries,
            counting: false,
            jitter_frame: jittered_lod_bias.map(|_| 0),
            lod_bias: jittered_lod_bias.unwrap_or(0),
            scene_free: pipeline_scene_free(&pipeline),
            made_for: (scene.bindings, scene.streaming.is_some()),
            pipeline,
        })
    }

    /// Whether this renderer draws `scene` as one made for it would: every pass is
    /// scene-free, and `scene` takes the bindings and streams (or not) as the scene it was
    /// made for. Then a program whose content changes keeps the compiled pipelines.
    pub fn draws_as_made_for(&self, scene: &GpuScene) -> bool {
        self.scene_free && self.made_for == (scene.bindings, scene.streaming.is_some())
    }

    /// Index of a live resource by name.
    pub fn resource(&self, name: &str) -> Option<usize> {
        self.pipeline.resource(name)
    }

    /// Whether the next frames count their work (march steps, rays, hierarchy boxes: what
    /// [`Renderer::counters`] reports). Off by default: a pass that counts then runs a
    /// variant without the counting, so frames pay for counters only when a report asks.
    pub fn set_counting(&mut self, on: bool) {
        self.counting = on;
    }

    /// The SSBVB fill count of the last frame: the billboards the pass that fills the SSBVB
    /// appended ([`PassNode::fill_count`]). `None` when no pass of the pipeline fills one.
    pub fn fill_count(&self, ctx: &GpuContext) -> Result<Option<u32>, PassError> {
        for (node, pass) in self.passes.iter().zip(&self.pipeline.passes) {
            if let Some(n) = node.fill_count(&self.counter_source(ctx, pass))? {
                return Ok(Some(n));
            }
        }
        Ok(None)
    }

    /// The share of the last frame's pixels whose history the temporal pass rejected
    /// ([`PassNode::history_rejected_share`]); `None` without a temporal pass.
    pub fn history_rejected_share(&self, ctx: &GpuContext) -> Result<Option<f64>, PassError> {
        for node in &self.passes {
            if let Some(share) = node.history_rejected_share(ctx)? {
                return Ok(Some(share));
            }
        }
        Ok(None)
    }

    /// What the passes counted in the last frame (reads back from the GPU), with the
    /// measures derived from several passes' counts ([`FrameCounters::derive`]).
    pub fn counters(&self, ctx: &GpuContext) -> Result<FrameCounters, PassError> {
        let mut out = FrameCounters::default();
        for (node, pass) in self.passes.iter().zip(&self.pipeline.passes) {
            node.counters(&self.counter_source(ctx, pass), &mut out)?;
        }
        out.derive();
        Ok(out)
    }

    fn counter_source<'a>(
        &'a self,
        ctx: &'a GpuContext,
        pass: &'a ssbvb_graph::ScheduledPass,
    ) -> CounterSource<'a> {
        CounterSource {
            gpu: ctx,
            resources: &self.resources,
            pass,
        }
    }

    /// What reads each pass's GPU time of the last frame drawn with timestamps
    /// ([`Profiling::TimestampsUnwaited`]); `None` when the device has no timestamp
    /// queries. It holds its own handles, so the renderer is free while it reads.
    pub fn pass_times_readout(&self) -> Option<PassTimesReadout> {
        let (_, buffer) = self.queries.as_ref()?;
        Some(PassTimesReadout {
            buffer: buffer.clone(),
            names: self
                .pipeline
                .passes
                .iter()
                .map(|p| p.name.clone())
                .collect(),
        })
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
        let waits = matches!(
            profiling,
            Profiling::Timestamps | Profiling::TimestampsAndWall
        );
        if waits {
            // Earlier unwaited frames must not be billed to this one.
            ctx.wait_idle().map_err(PassError::Gpu)?;
        }
        let start = Instant::now();
        scene.stream_pages(ctx)?;
        scene.jitter = match &mut self.jitter_frame {
            Some(i) => {
                *i += 1;
                super::jitter::jitter(*i - 1)
            }
            None => [0.0; 2],
        };
        scene.lod_bias = self.lod_bias;
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
                counting: self.counting,
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
                ctx.submit("frame, one pass", [done.finish()]);
                ctx.wait_idle().map_err(PassError::Gpu)?;
                walls[i] = Some(t0.elapsed().as_secs_f64() * 1e3);
            }
        }
        if use_ts {
            let (set, buf) = self.queries.as_ref().expect("queries exist");
            encoder.resolve_query_set(set, 0..(self.passes.len() * 2) as u32, buf, 0);
        }
        scene.end_frame(&mut encoder);
        ctx.submit("frame", [encoder.finish()]);
        scene.after_submit();
        let mut gpu_ms = vec![None; self.passes.len()];
        if use_ts && waits {
            let (_, buf) = self.queries.as_ref().expect("queries exist");
            let raw = ctx.read_buffer(buf).map_err(PassError::Gpu)?;
            gpu_ms = pass_ms(ctx, &raw);
        } else if waits {
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
        let passes = if !waits {
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

/// Each pass's time in ms from its begin and end timestamps (`raw`: two `u64` per pass);
/// `None` where the end precedes the begin (a counter that wrapped or was reset).
fn pass_ms(ctx: &GpuContext, raw: &[u8]) -> Vec<Option<f64>> {
    let raw: Vec<u64> = bytemuck::pod_collect_to_vec(raw);
    let period = f64::from(ctx.queue.get_timestamp_period());
    raw.chunks_exact(2)
        .map(|t| (t[1] >= t[0]).then(|| (t[1] - t[0]) as f64 * period / 1e6))
        .collect()
}

/// The resolved timestamps of a frame and its passes' names
/// ([`Renderer::pass_times_readout`]).
pub struct PassTimesReadout {
    buffer: wgpu::Buffer,
    names: Vec<String>,
}

impl PassTimesReadout {
    /// Each pass's GPU time, awaiting the readback (the browser's form).
    pub async fn read(&self, ctx: &GpuContext) -> Result<Vec<PassTiming>, PassError> {
        let raw = ctx
            .read_buffer_async(&self.buffer)
            .await
            .map_err(PassError::Gpu)?;
        Ok(self
            .names
            .iter()
            .zip(pass_ms(ctx, &raw))
            .map(|(name, gpu_ms)| PassTiming {
                name: name.clone(),
                gpu_ms,
                wall_ms: None,
            })
            .collect())
    }
}
