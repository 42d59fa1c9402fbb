//! Frame statistics for the overlay: smoothed frame time, per-pass timings sampled at a
//! rate that does not distort what they measure, and the SSBVB fill count.

use std::time::Instant;

use ssbvb_gpu::AdapterReport;
use ssbvb_passes::{FrameStats, PassTiming, Profiling};

/// Frames between two samples of GPU timestamps (each sample waits for the GPU).
pub const TIMESTAMP_EVERY: u64 = 10;
/// Frames between two per-pass wall-time samples (each pass is submitted and waited for
/// alone, which slows that frame down: sample rarely) and between fill-count readbacks.
pub const SLOW_SAMPLE_EVERY: u64 = 30;

/// Where per-pass times come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimingSource {
    /// GPU timestamp queries (a hardware adapter that has them).
    Timestamps,
    /// Each pass submitted and waited for alone (software adapters, whose timestamps are
    /// unreliable, or adapters without timestamp queries).
    Wall,
}

/// What the overlay shows about performance.
#[derive(Debug, Clone)]
pub struct Stats {
    /// Where pass times come from on this adapter.
    pub source: TimingSource,
    /// Exponentially smoothed time between presented frames, in ms.
    pub frame_ms: Option<f64>,
    /// Smoothed CPU-side time of `Renderer::render` (record + submit), in ms.
    pub render_ms: Option<f64>,
    /// Last sampled per-pass timings.
    pub passes: Vec<PassTiming>,
    /// Last sampled SSBVB fill count (`None`: no filter pass, or not sampled yet).
    pub fill: Option<u32>,
    /// Pixels showing a voxel when the fill count was sampled.
    pub covered: Option<usize>,
    /// Instances drawn in the last frame.
    pub visible_instances: usize,
    last_present: Option<Instant>,
}

/// Exponential moving average; `None` starts at the first sample.
fn ema(old: Option<f64>, sample: f64) -> Option<f64> {
    Some(match old {
        Some(o) => o + 0.1 * (sample - o),
        None => sample,
    })
}

impl Stats {
    /// Statistics for a device on `adapter`.
    pub fn new(adapter: &AdapterReport) -> Self {
        Self {
            source: if adapter.timestamps && !adapter.is_software {
                TimingSource::Timestamps
            } else {
                TimingSource::Wall
            },
            frame_ms: None,
            render_ms: None,
            passes: Vec::new(),
            fill: None,
            covered: None,
            visible_instances: 0,
            last_present: None,
        }
    }

    /// The profiling to ask of `Renderer::render` for frame number `frame`.
    pub fn profiling(&self, frame: u64) -> Profiling {
        match self.source {
            TimingSource::Timestamps if frame.is_multiple_of(TIMESTAMP_EVERY) => {
                Profiling::Timestamps
            }
            TimingSource::Wall if frame.is_multiple_of(SLOW_SAMPLE_EVERY) => {
                Profiling::TimestampsAndWall
            }
            _ => Profiling::Off,
        }
    }

    /// Whether frame `frame` counts its work and reads the fill count back: the frame after
    /// a wall-time sample, never a profiled frame, so pass times are of frames that do the
    /// work of every other frame (`ssbvb_engine::timing`).
    pub fn samples_fill(frame: u64) -> bool {
        frame % SLOW_SAMPLE_EVERY == 1
    }

    /// Takes in what `Renderer::render` returned.
    pub fn record(&mut self, stats: &FrameStats, profiling: Profiling) {
        self.visible_instances = stats.visible_instances;
        if profiling == Profiling::Off {
            self.render_ms = ema(self.render_ms, stats.frame_wall_ms);
        } else {
            self.passes = stats.passes.clone();
        }
    }

    /// Marks a presented frame (frame time is measured between presents).
    pub fn presented(&mut self, now: Instant) {
        if let Some(last) = self.last_present {
            self.frame_ms = ema(self.frame_ms, (now - last).as_secs_f64() * 1e3);
        }
        self.last_present = Some(now);
    }

    /// Forgets timings that belong to another pipeline (after a switch or reload).
    pub fn reset_pipeline(&mut self) {
        self.passes.clear();
        self.fill = None;
        self.covered = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adapter(timestamps: bool, is_software: bool) -> AdapterReport {
        AdapterReport {
            name: "x".into(),
            backend: "Vulkan".into(),
            device_type: "Cpu".into(),
            driver: String::new(),
            is_software,
            timestamps,
            fallbacks: Vec::new(),
            limits: "adapter",
        }
    }

    #[test]
    fn software_adapters_sample_wall_time_rarely() {
        let s = Stats::new(&adapter(true, true));
        assert_eq!(s.source, TimingSource::Wall);
        let sampled = (0..300)
            .filter(|f| s.profiling(*f) != Profiling::Off)
            .count();
        assert_eq!(sampled, 10);
        assert_eq!(s.profiling(0), Profiling::TimestampsAndWall);
    }

    /// No frame is both timed and counted: the counted variants' atomics never reach the
    /// pass times shown.
    #[test]
    fn counted_frames_are_never_profiled_frames() {
        for software in [true, false] {
            let s = Stats::new(&adapter(true, software));
            let counted: Vec<u64> = (0..300).filter(|f| Stats::samples_fill(*f)).collect();
            assert_eq!(counted.len(), 10);
            assert!(
                counted.iter().all(|f| s.profiling(*f) == Profiling::Off),
                "software {software}"
            );
        }
    }

    #[test]
    fn hardware_adapters_use_timestamps() {
        let s = Stats::new(&adapter(true, false));
        assert_eq!(s.source, TimingSource::Timestamps);
        assert_eq!(s.profiling(10), Profiling::Timestamps);
        assert_eq!(s.profiling(11), Profiling::Off);
    }

    #[test]
    fn frame_time_is_smoothed() {
        let mut s = Stats::new(&adapter(false, false));
        let t0 = Instant::now();
        s.presented(t0);
        assert_eq!(s.frame_ms, None);
        s.presented(t0 + std::time::Duration::from_millis(10));
        assert!((s.frame_ms.unwrap() - 10.0).abs() < 1e-6);
        s.presented(t0 + std::time::Duration::from_millis(30));
        // 10 + 0.1 * (20 - 10)
        assert!((s.frame_ms.unwrap() - 11.0).abs() < 1e-6);
    }
}
