//! `ssbvb render --frames N`: a soak. Renders N frames with the camera moving along a path
//! and samples process RSS and the device's memory and object counts (wgpu's internal
//! counters) during the run, so a leak per frame (a buffer, a bind group, a staging copy)
//! shows as growth between the start and the end. Every frame runs with validation; any
//! wgpu error fails the soak.
//!
//! The start sample is taken after a warm-up (1 % of the frames, at least 10): the first
//! frames fill allocator caches and pipeline caches that are not leaks.
//!
//! A frame whose device is lost (a driver reset, or `--inject-fault device-lost@FRAME`)
//! opens a new session from the CPU-side state and is drawn again
//! (`ssbvb_engine::faults`); the report counts the recoveries. `oom@FRAME` rebuilds the session
//! at that frame with its first large allocation refused.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::{DQuat, DVec3};
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::GpuScene;
use ssbvb_passes::Profiling;
use ssbvb_voxel::camera::Camera;

use ssbvb_engine::faults::{Fault, Recoveries, loses_device_at, runs_out_of_memory_at};
use ssbvb_engine::session::{GpuSession, SessionSource};

/// How the camera moves during a soak.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CameraPath {
    /// One turn around the look-at point, about the up axis, at the camera's distance.
    Orbit,
    /// The camera stays where it is.
    Still,
}

/// The camera of frame `i` of `n` on `path`, starting at `base`.
pub fn camera_at(base: &Camera, path: CameraPath, i: usize, n: usize) -> Camera {
    match path {
        CameraPath::Still => *base,
        CameraPath::Orbit => {
            let angle = std::f64::consts::TAU * i as f64 / n.max(1) as f64;
            let up = base.up.normalize_or(DVec3::Y);
            let offset = DQuat::from_axis_angle(up, angle) * (base.position - base.look_at);
            Camera {
                position: base.look_at + offset,
                ..*base
            }
        }
    }
}

/// What the process and the device hold at one frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// Frames rendered before the sample.
    pub frame: usize,
    /// Process resident memory (`None` where the platform does not say).
    pub rss_bytes: Option<u64>,
    /// Device memory of buffers and textures (0 on backends without counters).
    pub gpu_bytes: u64,
    /// Live buffers.
    pub buffers: u64,
    /// Live textures.
    pub textures: u64,
    /// Live bind groups.
    pub bind_groups: u64,
    /// Under a GPU budget: pages streamed in and evicted so far (`None` without a budget).
    pub pages_streamed: Option<u64>,
    /// Pages evicted so far.
    pub pages_evicted: Option<u64>,
}

impl Sample {
    /// Samples now; `frame` frames were rendered before. Waits for the device first: wgpu
    /// frees a dropped buffer only once the work using it is done and the device is
    /// polled, so without the wait the count depends on whether a read-back happened to
    /// poll just before (two buffers more or less at the same state).
    pub fn take(ctx: &GpuContext, scene: &GpuScene, frame: usize) -> Result<Self> {
        ctx.wait_idle()?;
        let c = ctx.memory_counters();
        let st = scene.streaming_stats();
        Ok(Self {
            pages_streamed: st.map(|s| s.pages_streamed),
            pages_evicted: st.map(|s| s.pages_evicted),
            frame,
            rss_bytes: memory_stats::memory_stats().map(|m| m.physical_mem as u64),
            gpu_bytes: c.buffer_bytes + c.texture_bytes,
            buffers: c.buffers,
            textures: c.textures,
            bind_groups: c.bind_groups,
        })
    }
}

/// Memory over a run: the samples and the growth from the first to the last.
#[derive(Debug, Clone, Serialize)]
pub struct MemoryTrend {
    /// The sample after the warm-up, the one growth is measured from.
    pub start: Sample,
    /// The sample after the last frame.
    pub end: Sample,
    /// About ten samples spread over the run (start and end included).
    pub samples: Vec<Sample>,
    /// `end / start − 1` of the RSS, in percent.
    pub rss_growth_percent: Option<f64>,
    /// `end / start − 1` of the device bytes, in percent (0 when nothing is counted).
    pub gpu_growth_percent: f64,
}

impl MemoryTrend {
    /// The trend of `samples` followed by `last`, the end sample.
    pub fn of(mut samples: Vec<Sample>, last: Sample) -> Self {
        samples.push(last);
        let start = samples[0];
        Self {
            start,
            end: last,
            rss_growth_percent: start
                .rss_bytes
                .zip(last.rss_bytes)
                .map(|(a, b)| growth(a, b)),
            gpu_growth_percent: growth(start.gpu_bytes, last.gpu_bytes),
            samples,
        }
    }
}

/// `render --json`'s `soak`.
#[derive(Debug, Clone, Serialize)]
pub struct SoakReport {
    /// Frames rendered.
    pub frames: usize,
    /// The camera's path.
    pub camera_path: CameraPath,
    /// Memory after the warm-up, over the run and at the end.
    #[serde(flatten)]
    pub memory: MemoryTrend,
    /// Median and worst frame wall time (submission to completion), milliseconds.
    pub frame_ms_median: f64,
    /// Worst frame.
    pub frame_ms_max: f64,
    /// Times the device was lost and the session opened again.
    pub device_recoveries: usize,
    /// Sessions rebuilt by `oom@FRAME` (each with its first large allocation refused).
    pub out_of_memory_rebuilds: usize,
    /// What the rebuilds lowered (`render --json` lists these under `warnings` too).
    pub warnings: Vec<String>,
}

/// The viewer's `--memory-report`: memory after the warm-up and at the end of a
/// `--frames` run, with the pipeline reloads seen (the soak of hot reload).
#[derive(Debug, Clone, Serialize)]
pub struct ViewMemoryReport {
    /// Frames presented.
    pub frames: u64,
    /// Pipeline reloads that succeeded.
    pub reloads_ok: u64,
    /// Reloads of a file with errors (the last good pipeline kept rendering).
    pub reloads_failed: u64,
    /// Memory after the warm-up, over the run and now.
    #[serde(flatten)]
    pub memory: MemoryTrend,
}

/// Writes `value` as JSON to `path` (a temporary file, then a rename).
pub fn write_json(path: &std::path::Path, value: &impl Serialize) -> Result<()> {
    use anyhow::Context;
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, serde_json::to_string_pretty(value)?)
        .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// Frames before the start sample of a run of `n`: 1 %, at least 10 (fewer for a short run).
pub fn warmup_frames(n: usize) -> usize {
    (n / 100).max(10).min(n.saturating_sub(1))
}

fn growth(start: u64, end: u64) -> f64 {
    if start == 0 {
        0.0
    } else {
        (end as f64 / start as f64 - 1.0) * 100.0
    }
}

/// Renders `n` frames along `path` from `base`, streaming pages between frames under a
/// budget; fails on the first wgpu error. A frame whose device was lost (or is made lost
/// by `faults`) opens a new session from `source` (warmed up to that frame's camera, at
/// most `max_frames` frames) and is drawn again, unless the device was lost shortly
/// before too. An `oom@FRAME` fault rebuilds the session at that frame with its first
/// large allocation refused (`ssbvb_engine::faults`). Returns the session the soak ended on.
pub fn run(
    mut session: GpuSession,
    source: &mut SessionSource,
    base: &Camera,
    path: CameraPath,
    n: usize,
    faults: &[Fault],
    max_frames: usize,
) -> Result<(GpuSession, SoakReport)> {
    let warmup = warmup_frames(n);
    let every = (n / 9).max(1);
    let mut samples = Vec::new();
    let mut times = Vec::with_capacity(n);
    let mut recoveries = Recoveries::default();
    let mut warnings = Vec::new();
    let mut oom_rebuilds = 0;
    for i in 0..n {
        if i >= warmup && (i - warmup).is_multiple_of(every) {
            samples.push(Sample::take(&session.ctx, &session.scene, i)?);
        }
        let cam = camera_at(base, path, i, n);
        if runs_out_of_memory_at(faults, i) {
            // The old session's memory goes before the new one asks for its own.
            drop(session);
            let why = format!("rebuilding the GPU session at soak frame {i} (oom@{i})");
            session = reopen(source, &cam, max_frames, true, i, &why, &mut warnings)?;
            oom_rebuilds += 1;
        }
        if loses_device_at(faults, i) {
            session.ctx.inject_device_loss();
        }
        let mut t = Instant::now();
        if let Err(e) = draw(&mut session, &cam, i) {
            let Some(reason) = session.ctx.lost() else {
                return Err(e);
            };
            recoveries.lost_at(i, &reason)?;
            log::warn!("soak frame {i}: the GPU device was lost ({reason}); recreating it");
            drop(session);
            let why = format!("recreating the GPU session after losing it at frame {i}");
            session = reopen(source, &cam, max_frames, false, i, &why, &mut warnings)?;
            // The frame's time is the redraw's: opening a device is not a frame.
            t = Instant::now();
            draw(&mut session, &cam, i)?;
        }
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let end = Sample::take(&session.ctx, &session.scene, n)?;
    times.sort_by(f64::total_cmp);
    let report = SoakReport {
        frames: n,
        camera_path: path,
        memory: MemoryTrend::of(samples, end),
        frame_ms_median: times.get(times.len() / 2).copied().unwrap_or(0.0),
        frame_ms_max: times.last().copied().unwrap_or(0.0),
        device_recoveries: recoveries.count,
        out_of_memory_rebuilds: oom_rebuilds,
        warnings,
    };
    Ok((session, report))
}

/// [`SessionSource::reopen`] at soak frame `i` (`why` names it in an error), its warnings
/// added to `warnings`.
fn reopen(
    source: &mut SessionSource,
    cam: &Camera,
    max_frames: usize,
    refuse: bool,
    i: usize,
    why: &str,
    warnings: &mut Vec<String>,
) -> Result<GpuSession> {
    let o = source
        .reopen(cam, max_frames, refuse)
        .with_context(|| why.to_string())?;
    warnings.extend(
        o.warnings
            .into_iter()
            .map(|w| format!("soak frame {i}: {w}")),
    );
    Ok(o.session)
}

/// One soak frame, waited for; any wgpu error fails it.
fn draw(s: &mut GpuSession, cam: &Camera, i: usize) -> Result<()> {
    s.renderer
        .render(&s.ctx, &mut s.scene, cam, Profiling::Off)?;
    s.ctx.wait_idle()?;
    let errors = s.ctx.take_uncaptured_errors();
    if let Some(e) = errors.first() {
        bail!("wgpu error at soak frame {i}: {e}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orbit_turns_once_around_the_look_at_point() {
        let base = Camera::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, 0.0, 0.0));
        let d = |c: &Camera| (c.position - c.look_at).length();
        for i in 0..8 {
            let c = camera_at(&base, CameraPath::Orbit, i, 8);
            assert!((d(&c) - d(&base)).abs() < 1e-12, "distance kept");
            assert!((c.position.y - 2.0).abs() < 1e-12, "about the up axis");
            assert_eq!(c.look_at, base.look_at);
        }
        let half = camera_at(&base, CameraPath::Orbit, 4, 8);
        assert!((half.position - DVec3::new(1.0, 2.0, -3.0)).length() < 1e-9);
        assert_eq!(camera_at(&base, CameraPath::Still, 5, 8), base);
        assert!((growth(100, 102) - 2.0).abs() < 1e-9);
        assert_eq!(growth(0, 5), 0.0);
    }
}
