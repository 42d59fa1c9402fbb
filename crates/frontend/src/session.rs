//! The GPU state of one `ssbvb render`: the device, the scene on it and the renderer,
//! opened from what stays on the CPU for the whole command ([`SessionSource`]: the scene,
//! the resolved pipeline, the budget, the animated objects), so that a soak can open it
//! again when the device is lost (`crate::device_loss`).

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

impl SessionSource {
    /// Creates a device that fits the pipeline, uploads the scene (under the budget, the
    /// pages streaming from their cache files; `notes` says where they cannot), poses the
    /// animated objects and builds the renderer.
    pub fn open(&self, notes: &mut Vec<String>) -> Result<GpuSession> {
        let ctx = crate::adapter_cmd::headless_context(&[&self.pipeline])?;
        let scene = self.scene.clone();
        let mut gpu_scene = match self.budget {
            Some(mib) => {
                // Offline: stream every page a frame asks for before the next one.
                let options = crate::budget::options(mib, &self.page_sources, usize::MAX, notes)?;
                GpuScene::streamed(&ctx, scene, &options)?
            }
            None if !self.animated.is_empty() => {
                GpuScene::with_dynamic(&ctx, scene, &crate::animation::rooms(&self.animated))?
            }
            None => GpuScene::new(&ctx, scene)?,
        };
        let animation = if self.animated.is_empty() {
            None
        } else {
            let animator = ssbvb_gpu_build::animated::Animator::new(&ctx)?;
            Some(crate::animation::update_all(
                &ctx,
                &mut gpu_scene,
                &animator,
                &self.animated,
                self.time,
            )?)
        };
        let mut renderer = Renderer::new(&ctx, &gpu_scene, self.pipeline.clone(), self.size)?;
        renderer.set_counting(true);
        Ok(GpuSession {
            ctx,
            scene: gpu_scene,
            renderer,
            animation,
        })
    }

    /// [`SessionSource::open`] after a device loss: the same, then frames of `camera`
    /// until no page is missing (as the command's warm-up did), so that the next frame is
    /// what it would have been on the lost device.
    pub fn reopen(&self, camera: &Camera, max_frames: usize) -> Result<GpuSession> {
        let mut s = self.open(&mut Vec::new())?;
        crate::budget::converge(&s.ctx, &mut s.renderer, &mut s.scene, camera, max_frames)?;
        Ok(s)
    }
}
