//! A compiled pass: what the runtime calls each frame, and what it reads afterwards.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::ScheduledPass;

use super::counters::FrameCounters;
use super::recorder::Recorder;
use super::resources::{FrameResources, FrameTexture};
use crate::error::PassError;

/// Natively a pass is `Send + Sync` (as wgpu's resources are), so a renderer can move to
/// another thread, or render with a caller's lock released (Python's GIL); in the browser
/// wgpu's resources are neither, and neither is a pass.
#[cfg(not(target_arch = "wasm32"))]
pub trait MaybeSendSync: Send + Sync {}
#[cfg(not(target_arch = "wasm32"))]
impl<T: Send + Sync> MaybeSendSync for T {}
/// In the browser, no bound (see the native definition).
#[cfg(target_arch = "wasm32")]
pub trait MaybeSendSync {}
#[cfg(target_arch = "wasm32")]
impl<T> MaybeSendSync for T {}

/// A pass ready to record: pipelines compiled once, bind groups made per frame.
pub trait PassNode: MaybeSendSync {
    /// Records the pass's work for one frame.
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError>;

    /// Adds what this pass counted in the last frame to `out` (reads back from the GPU;
    /// call after the frame, as [`super::renderer::Renderer::counters`] does). Most passes
    /// count nothing.
    fn counters(
        &self,
        _frame: &CounterSource<'_>,
        _out: &mut FrameCounters,
    ) -> Result<(), PassError> {
        Ok(())
    }

    /// The SSBVB fill count of the last frame when this pass fills the SSBVB: the
    /// billboards it appended (`None` for every other pass).
    fn fill_count(&self, _frame: &CounterSource<'_>) -> Result<Option<u32>, PassError> {
        Ok(None)
    }

    /// Whether the frames of a pipeline with this pass are jittered by a sub-pixel offset
    /// (what a temporal pass averages), and then how many levels finer Auto LOD draws
    /// (`Some(lod_bias)`; `None` for every pass that does not ask for jitter).
    fn jittered_lod_bias(&self) -> Option<u32> {
        None
    }

    /// For a temporal pass: the share of the last frame's pixels whose history was
    /// rejected (none to reproject, or clamped away), read back (`None` for every other
    /// pass).
    fn history_rejected_share(&self, _gpu: &GpuContext) -> Result<Option<f64>, PassError> {
        Ok(None)
    }
}

/// What a pass may read back after a frame: the device and the frame's resources bound to
/// its slots.
pub struct CounterSource<'a> {
    /// The device.
    pub gpu: &'a GpuContext,
    /// The frame's resources.
    pub resources: &'a FrameResources,
    /// The pass (slot → resource bindings).
    pub pass: &'a ScheduledPass,
}

impl<'a> CounterSource<'a> {
    /// The buffer bound to `slot`, if the pass has that slot and it is live.
    pub fn buffer(&self, slot: &str) -> Option<&'a wgpu::Buffer> {
        self.pass
            .resource_of(slot)
            .map(|i| self.resources.buffer(i))
    }

    /// The texture bound to `slot`, if the pass has that slot and it is live.
    pub fn texture(&self, slot: &str) -> Option<&'a FrameTexture> {
        self.pass
            .resource_of(slot)
            .map(|i| self.resources.texture(i))
    }
}
