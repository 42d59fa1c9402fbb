//! The one timing path: per-pass times come from a frame that does exactly the work of an
//! untimed frame (no counters compiled in), and the work counters from a frame of their own
//! drawn after it. `ssbvb render`, the bench and [`crate::Engine`] all measure this way, so
//! the same frame gives the same numbers everywhere.
//!
//! Counting variants of a pass pay for atomics per ray; a profiled frame that also counted
//! reported the counting's cost as the pass's (the filter of the default form at level 9,
//! 1280×720 on lavapipe: several times its uncounted time).

use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::GpuScene;
use ssbvb_passes::{FrameCounters, FrameStats, Profiling, Renderer};
use ssbvb_voxel::camera::Camera;

use crate::EngineError;

/// The profiling of a measured frame: per-pass wall times on a software adapter, whose
/// timestamps are unreliable; GPU timestamps elsewhere.
pub fn profiling(ctx: &GpuContext) -> Profiling {
    if ctx.report().is_software {
        Profiling::TimestampsAndWall
    } else {
        Profiling::Timestamps
    }
}

/// One frame with its pass times ([`profiling`]), counting nothing: the work of every
/// untimed frame.
pub fn profiled_frame(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    scene: &mut GpuScene,
    camera: &Camera,
) -> Result<FrameStats, EngineError> {
    renderer.set_counting(false);
    Ok(renderer.render(ctx, scene, camera, profiling(ctx))?)
}

/// What a frame counted: its work counters and the SSBVB fill count.
#[derive(Debug, Clone, Default)]
pub struct Counted {
    /// March steps, rays, boxes tested, billboards drawn, ….
    pub counters: FrameCounters,
    /// Billboards the pass that fills the SSBVB appended (`None` without one).
    pub fill_count: Option<u32>,
}

/// One more frame of the same view, untimed, counting its work; the renderer stops
/// counting after it. Its image is the profiled frame's (a temporal pipeline's jitter
/// moves on by a frame).
pub fn counted_frame(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    scene: &mut GpuScene,
    camera: &Camera,
) -> Result<Counted, EngineError> {
    renderer.set_counting(true);
    let drawn = renderer.render(ctx, scene, camera, Profiling::Off);
    renderer.set_counting(false);
    drawn?;
    Ok(Counted {
        counters: renderer.counters(ctx)?,
        fill_count: renderer.fill_count(ctx)?,
    })
}
