//! Timing frames: wall time of each frame's submit and wait, the median over the timed
//! ones, and one profiled frame for per-pass times.

use std::time::Instant;

use anyhow::Result;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::GpuScene;
use ssbvb_passes::{FrameStats, Profiling, Renderer};
use ssbvb_voxel::camera::Camera;

/// The median of `v` (sorts it; the upper one of an even count).
pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Renders `frames` frames (at least one), each waited for, and returns their wall times
/// (ms) in order.
pub(crate) fn timed_frames(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    gpu_scene: &mut GpuScene,
    camera: &Camera,
    frames: usize,
) -> Result<Vec<f64>> {
    let mut times = Vec::new();
    for _ in 0..frames.max(1) {
        let t0 = Instant::now();
        renderer.render(ctx, gpu_scene, camera, Profiling::Off)?;
        ctx.wait_idle()?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    Ok(times)
}

/// On a hardware adapter with timestamp queries, renders `frames` more frames (at least
/// one) each profiled with GPU timestamps and returns each frame's GPU time (ms): the sum of
/// its passes' times, without the host's submission, waiting and readback that the wall
/// time of [`timed_frames`] includes. `None` on a software adapter (its timestamps are not
/// GPU time) or without timestamps.
pub(crate) fn gpu_timed_frames(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    gpu_scene: &mut GpuScene,
    camera: &Camera,
    frames: usize,
) -> Result<Option<Vec<f64>>> {
    if ctx.report().is_software || !ctx.report().timestamps {
        return Ok(None);
    }
    let mut times = Vec::new();
    for _ in 0..frames.max(1) {
        let stats = renderer.render(ctx, gpu_scene, camera, Profiling::Timestamps)?;
        let passes: Option<Vec<f64>> = stats.passes.iter().map(|p| p.gpu_ms).collect();
        match passes {
            Some(p) => times.push(p.iter().sum()),
            // A pass without a timestamp pair: no GPU time for this technique.
            None => return Ok(None),
        }
    }
    Ok(Some(times))
}

/// Frames of one renderer: its median frame time over `frames` timed frames after one
/// warm-up, one profiled frame doing the same work (`ssbvb_engine::timing`), then one
/// frame of its own that counts the work (`Renderer::counters` and the fill count read
/// after [`TimedFrames::run`] are that frame's).
pub(crate) struct TimedFrames {
    /// Median wall time of the timed frames (ms).
    pub(crate) frame_ms: f64,
    /// Median GPU time of as many frames timed by timestamps ([`gpu_timed_frames`]; `None`
    /// on software adapters).
    pub(crate) frame_gpu_ms: Option<f64>,
    /// The profiled frame.
    pub(crate) stats: FrameStats,
    software: bool,
}

impl TimedFrames {
    /// Renders and times (see the type).
    pub(crate) fn run(
        ctx: &GpuContext,
        renderer: &mut Renderer,
        gpu_scene: &mut GpuScene,
        camera: &Camera,
        frames: usize,
    ) -> Result<Self> {
        // Neither the timed nor the profiled frames pay for counters.
        renderer.set_counting(false);
        renderer.render(ctx, gpu_scene, camera, Profiling::Off)?;
        ctx.wait_idle()?;
        let mut times = timed_frames(ctx, renderer, gpu_scene, camera, frames)?;
        let frame_gpu_ms =
            gpu_timed_frames(ctx, renderer, gpu_scene, camera, frames)?.map(|mut g| median(&mut g));
        let stats = ssbvb_engine::timing::profiled_frame(ctx, renderer, gpu_scene, camera)?;
        // Counted last, so what callers read back after this is the counted frame's.
        ssbvb_engine::timing::counted_frame(ctx, renderer, gpu_scene, camera)?;
        Ok(Self {
            frame_ms: median(&mut times),
            frame_gpu_ms,
            stats,
            software: ctx.report().is_software,
        })
    }

    /// The time of pass `name` in the profiled frame (ms).
    pub(crate) fn pass_ms(&self, name: &str) -> Option<f64> {
        let p = self.stats.passes.iter().find(|p| p.name == name)?;
        if self.software {
            p.wall_ms
        } else {
            p.gpu_ms.or(p.wall_ms)
        }
    }
}
