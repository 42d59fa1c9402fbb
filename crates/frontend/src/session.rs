//! The GPU state of one `ssbvb render`: the device, the scene on it and the renderer,
//! opened from what stays on the CPU for the whole command ([`SessionSource`]: the scene,
//! the resolved pipeline, the budget, the animated objects), so that a soak can open it
//! again when the device is lost (`crate::faults`).

use anyhow::Result;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{GpuScene, Scene};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::Renderer;
use ssbvb_voxel::camera::Camera;

use crate::animation::AnimationReport;
use crate::budget::PageSourceRef;

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
    /// Time each GPU submission alone (`--time-submissions`).
    pub time_submissions: bool,
    /// How rays find the instances they may meet.
    pub instance_walk: crate::cli_values::InstanceWalk,
}

/// A device with the scene and the renderer on it.
pub struct GpuSession {
    /// The device.
    pub ctx: GpuContext,
    /// The scene on the device.
    pub scene: GpuScene,
    /// The pipeline's renderer, counting its work (the report prints the counters).
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

impl SessionSource {
    /// Creates a device that fits the pipeline, uploads the scene (under the budget, the
    /// pages streaming from their cache files; `notes` says where they cannot), poses the
    /// animated objects and builds the renderer. With `refuse`, the device refuses the
    /// first large allocation (`--inject-fault oom@FRAME`). A scene allocation the driver
    /// refuses lowers a budget to half (kept in `self.budget`, so later sessions open under
    /// it too) and the upload starts again; without a budget it is an error naming the
    /// resource, its size and `--gpu-budget`. A refused frame target is an error naming
    /// `--size` (a budget does not size it).
    pub fn open_refusing(&mut self, notes: &mut Vec<String>, refuse: bool) -> Result<Opened> {
        let ctx = crate::adapter_cmd::headless_context(&[&self.pipeline])?;
        ctx.time_submissions(self.time_submissions);
        if refuse {
            ctx.refuse_allocation(crate::faults::INJECTED_OOM_MIN_BYTES);
        }
        let mut warnings = Vec::new();
        // Notes are of the first attempt (a retry would repeat them).
        let mut retry_notes = Vec::new();
        let mut notes = Some(notes);
        loop {
            let attempt = self.upload(&ctx, notes.take().unwrap_or(&mut retry_notes));
            let e = match attempt {
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
            let Some((resource, bytes)) = crate::faults::out_of_memory(&e) else {
                return Err(e);
            };
            let refused = format!(
                "out of GPU memory: the driver refused {} for {resource}",
                ssbvb_gpu::alloc::mib_text(bytes)
            );
            if !crate::faults::is_scene_resource(&resource) {
                return Err(e.context(crate::faults::frame_out_of_memory_hint()));
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
                    return Err(e.context(format!(
                        "the scene does not fit the GPU's memory even under a {mib} MiB budget"
                    )));
                }
                None => {
                    return Err(e.context(format!(
                        "the scene does not fit the GPU's memory; {}",
                        crate::faults::out_of_memory_hint()
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
    ) -> Result<(GpuScene, Renderer, Option<AnimationReport>)> {
        let scene = self.scene.clone();
        let mut gpu_scene = match self.budget {
            Some(mib) => {
                // Offline: stream every page a frame asks for before the next one.
                let options = crate::budget::options(mib, &self.page_sources, usize::MAX, notes)?;
                GpuScene::streamed(ctx, scene, &options)?
            }
            None if !self.animated.is_empty() => {
                GpuScene::with_dynamic(ctx, scene, &crate::animation::rooms(&self.animated))?
            }
            None => GpuScene::new(ctx, scene)?,
        };
        gpu_scene.instance_lists = self.instance_walk == crate::cli_values::InstanceWalk::Lists;
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
        let mut renderer = Renderer::new(ctx, &gpu_scene, self.pipeline.clone(), self.size)?;
        renderer.set_counting(true);
        Ok((gpu_scene, renderer, animation))
    }

    /// [`SessionSource::open_refusing`] after a device loss or a refused allocation: the
    /// same, then frames of `camera` until no page is missing (as the command's warm-up
    /// did), so that the next frame is what it would have been on the lost device.
    pub fn reopen(&mut self, camera: &Camera, max_frames: usize, refuse: bool) -> Result<Opened> {
        let mut o = self.open_refusing(&mut Vec::new(), refuse)?;
        let s = &mut o.session;
        crate::budget::converge(&s.ctx, &mut s.renderer, &mut s.scene, camera, max_frames)?;
        Ok(o)
    }
}
