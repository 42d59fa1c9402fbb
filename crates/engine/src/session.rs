//! The GPU side of a render: the device, the scene on it and the renderer
//! ([`GpuSession`]), opened from what stays on the CPU for the whole render
//! ([`SessionSource`]: the scene, the resolved pipeline, the budget, the animated
//! objects), so that it can be opened again when the device is lost or an allocation is
//! refused.
//!
//! Out of memory: an allocation the driver refuses is [`ssbvb_gpu::GpuError::OutOfMemory`]
//! naming the resource and its size. Under a budget the session is opened again under half
//! the budget (so the level cap falls where the view's pages no longer fit) until it fits;
//! without one the error says to set one.

use ssbvb_gpu::scene::{GpuScene, Scene};
use ssbvb_gpu::{ContextOptions, DeviceLimits, GpuContext, wgpu};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::Renderer;
use ssbvb_voxel::camera::Camera;

use crate::EngineError;
use crate::animation::AnimationReport;
use crate::budget::PageSourceRef;
use crate::choice::requirements_of;
use crate::upload::{Residency, upload_scene};

/// A device a host program already has: the engine draws with it instead of making its
/// own (the host keeps its features, limits and error handler), optionally into the host's
/// own texture.
#[derive(Clone)]
pub struct HostDevice {
    /// The host's instance.
    pub instance: wgpu::Instance,
    /// The adapter of its device.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The host's texture the frame is drawn into, as the pipeline's output (its size and
    /// format those of the output, its usage at least what the pipeline needs); `None`:
    /// the engine's own.
    pub target: Option<wgpu::Texture>,
}

/// What a GPU session is made from.
pub struct SessionSource {
    /// What to draw.
    pub scene: Scene,
    /// The pipeline.
    pub pipeline: ResolvedPipeline,
    /// GPU budget (MiB) under which pages stream.
    pub budget: Option<u64>,
    /// Per object, the cache file its pages stream from.
    pub page_sources: Vec<Option<PageSourceRef>>,
    /// The scene's animated objects, drawn at `time`.
    pub animated: Vec<ssbvb_gpu_build::animated::AnimatedMesh>,
    /// Seconds at which the animated objects are drawn.
    pub time: f64,
    /// Image size.
    pub size: (u32, u32),
    /// Time each GPU submission alone.
    pub time_submissions: bool,
    /// Rays find the instances they may meet in their screen tile's list (`false`: the
    /// hierarchy over every visible instance's box; the image is the same).
    pub instance_lists: bool,
    /// Count each frame's work (march steps, rays: [`Renderer::counters`]).
    pub counting: bool,
    /// The limits an own device is made with.
    pub limits: DeviceLimits,
    /// The host's device (`None`: the engine makes its own on the best adapter that fits).
    pub host: Option<HostDevice>,
}

/// A device with the scene and the renderer on it.
pub struct GpuSession {
    /// The device.
    pub ctx: GpuContext,
    /// The scene on the device.
    pub scene: GpuScene,
    /// The pipeline's renderer.
    pub renderer: Renderer,
    /// The animated objects' update at `time` (`None` without any).
    pub animation: Option<AnimationReport>,
}

/// A session opened and the out-of-memory steps it took (`warnings` for the report).
pub struct Opened {
    /// The session.
    pub session: GpuSession,
    /// One line per allocation the driver refused and the budget it lowered.
    pub warnings: Vec<String>,
}

/// The size from which a refusal armed for tests refuses an allocation: small buffers are
/// not what runs a device out of memory, the scene's streams and the frame's targets are.
pub const INJECTED_OOM_MIN_BYTES: u64 = 64 << 10;

impl SessionSource {
    /// The device: the host's, or a new one on the best adapter that fits the pipeline. A
    /// host device that lacks what the pipeline needs is refused, naming what it lacks.
    fn device(&self) -> Result<GpuContext, EngineError> {
        let req = requirements_of(&[&self.pipeline]);
        let Some(h) = &self.host else {
            return Ok(GpuContext::new_headless(&ContextOptions {
                requirements: Some(req),
                limits: self.limits,
                ..Default::default()
            })?);
        };
        let verdict = req.check_under(&h.adapter, &h.device.limits());
        if !verdict.fits() {
            return Err(EngineError::Invalid(format!(
                "the host's device ({}) cannot run this pipeline: it lacks {}",
                h.adapter.get_info().name,
                verdict.missing.join("; ")
            )));
        }
        Ok(GpuContext::from_parts(
            h.instance.clone(),
            h.adapter.clone(),
            h.device.clone(),
            h.queue.clone(),
        ))
    }

    /// Creates the device, uploads the scene (under the budget, the pages streaming from
    /// their cache files; `notes` says where they cannot), poses the animated objects and
    /// builds the renderer. With `refuse`, the device refuses the first large allocation
    /// (how tests run a device out of memory). A scene allocation the driver refuses
    /// lowers a budget to half (kept in `self.budget`, so later sessions open under it too)
    /// and the upload starts again; without a budget it is an error naming the resource,
    /// its size and the budget to set. A refused frame target is an error naming the size.
    pub fn open_refusing(
        &mut self,
        notes: &mut Vec<String>,
        refuse: bool,
    ) -> Result<Opened, EngineError> {
        let ctx = self.device()?;
        ctx.time_submissions(self.time_submissions);
        if refuse {
            ctx.refuse_allocation(INJECTED_OOM_MIN_BYTES);
        }
        let mut warnings = Vec::new();
        // Notes are of the first attempt (a retry would repeat them).
        let mut retry_notes = Vec::new();
        let mut notes = Some(notes);
        loop {
            let e = match self.upload(&ctx, notes.take().unwrap_or(&mut retry_notes)) {
                Ok((scene, renderer, animation)) => {
                    ctx.clear_refusal();
                    let session = GpuSession {
                        ctx,
                        scene,
                        renderer,
                        animation,
                    };
                    return Ok(Opened { session, warnings });
                }
                Err(e) => e,
            };
            let Some((resource, bytes)) = e.refused_allocation() else {
                return Err(e);
            };
            let refused = format!(
                "out of GPU memory: the driver refused {} for {resource}",
                ssbvb_gpu::alloc::mib_text(bytes)
            );
            if !is_scene_resource(&resource) {
                return Err(EngineError::OutOfMemory(format!(
                    "{}: {e}",
                    frame_out_of_memory_hint()
                )));
            }
            match self.budget {
                Some(mib) if mib > 1 => {
                    let lower = mib / 2;
                    let w = format!(
                        "{refused}; --gpu-budget lowered from {mib} to {lower} MiB (finer levels \
                         of the view may stay coarser)"
                    );
                    log::warn!("{w}");
                    warnings.push(w);
                    self.budget = Some(lower);
                }
                Some(mib) => {
                    return Err(EngineError::OutOfMemory(format!(
                        "the scene does not fit the GPU's memory even under a {mib} MiB \
                         budget: {e}"
                    )));
                }
                None => {
                    return Err(EngineError::OutOfMemory(format!(
                        "the scene does not fit the GPU's memory; {}: {e}",
                        out_of_memory_hint()
                    )));
                }
            }
        }
    }

    /// The scene, the renderer and the animation update on `ctx`.
    fn upload(
        &self,
        ctx: &GpuContext,
        notes: &mut Vec<String>,
    ) -> Result<(GpuScene, Renderer, Option<AnimationReport>), EngineError> {
        let scene = self.scene.clone();
        let mut gpu_scene = match self.budget {
            Some(mib) => {
                // Offline: stream every page a frame asks for before the next one.
                let options = crate::budget::options(mib, &self.page_sources, usize::MAX, notes)?;
                upload_scene(ctx, scene, Residency::Streamed(&options))?
            }
            None => {
                let rooms = crate::animation::rooms(&self.animated);
                upload_scene(ctx, scene, Residency::Dynamic(&rooms))?
            }
        };
        gpu_scene.instance_lists = self.instance_lists;
        let animation = if self.animated.is_empty() {
            None
        } else {
            let animator = ssbvb_gpu_build::animated::Animator::new(ctx)?;
            Some(crate::animation::update_all(
                ctx,
                &mut gpu_scene,
                &animator,
                &self.animated,
                self.time,
            )?)
        };
        let renderer = self.build_renderer(ctx, &gpu_scene)?;
        Ok((gpu_scene, renderer, animation))
    }

    /// The pipeline's renderer over `gpu_scene` (into the host's target when it has one).
    fn build_renderer(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
    ) -> Result<Renderer, EngineError> {
        let target = self.host.as_ref().and_then(|h| h.target.clone());
        let mut renderer = match target {
            Some(texture) => {
                let output = self.pipeline.resources[self.pipeline.output].name.clone();
                Renderer::with_imports(
                    ctx,
                    gpu_scene,
                    self.pipeline.clone(),
                    self.size,
                    &[(output.as_str(), texture)],
                )?
            }
            None => crate::upload::renderer(ctx, gpu_scene, self.pipeline.clone(), self.size)?,
        };
        renderer.set_counting(self.counting);
        Ok(renderer)
    }

    /// Uploads `self.scene` (which has no animated object) to `gpu`'s device in place of
    /// its scene, keeping the renderer when it draws the new scene as one made for it
    /// would ([`Renderer::draws_as_made_for`]: no pipeline compiled again), else building
    /// one. Returns whether the renderer was kept.
    pub fn replace_scene(
        &self,
        gpu: &mut GpuSession,
        notes: &mut Vec<String>,
    ) -> Result<bool, EngineError> {
        let ctx = &gpu.ctx;
        let scene = self.scene.clone();
        let mut gpu_scene = match self.budget {
            Some(mib) => {
                let options = crate::budget::options(mib, &self.page_sources, usize::MAX, notes)?;
                upload_scene(ctx, scene, Residency::Streamed(&options))?
            }
            None => upload_scene(ctx, scene, Residency::Whole)?,
        };
        gpu_scene.instance_lists = self.instance_lists;
        let kept = gpu.renderer.draws_as_made_for(&gpu_scene);
        if !kept {
            gpu.renderer = self.build_renderer(ctx, &gpu_scene)?;
        }
        gpu.scene = gpu_scene;
        gpu.animation = None;
        Ok(kept)
    }

    /// [`SessionSource::open_refusing`] after a device loss or a refused allocation: the
    /// same, then frames of `camera` until no page is missing (as the first opening's
    /// warm-up did), so that the next frame is what it would have been on the lost device.
    pub fn reopen(
        &mut self,
        camera: &Camera,
        max_frames: usize,
        refuse: bool,
    ) -> Result<Opened, EngineError> {
        let mut o = self.open_refusing(&mut Vec::new(), refuse)?;
        let s = &mut o.session;
        crate::budget::converge(&s.ctx, &mut s.renderer, &mut s.scene, camera, max_frames)?;
        Ok(o)
    }
}

/// Whether a refused `resource` is part of the voxel scene (which a GPU budget sizes)
/// rather than one of the frame's targets (which the image size does).
pub fn is_scene_resource(resource: &str) -> bool {
    !resource.contains(ssbvb_passes::PHYSICAL_LABEL_MARK)
}

/// What to tell a user whose frame target was refused.
pub fn frame_out_of_memory_hint() -> &'static str {
    "the frame's targets do not fit the GPU's memory (a GPU budget does not size them): \
     render a smaller --size or a pipeline with fewer targets"
}

/// What to tell a user whose allocation was refused without a budget.
pub fn out_of_memory_hint() -> &'static str {
    "run with --gpu-budget MIB to keep the voxel scene within MIB MiB on the GPU (its \
     finer levels then stream as rays need them, and a refused allocation lowers the \
     budget instead of ending the run), or render a smaller --size"
}
