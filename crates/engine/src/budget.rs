//! A GPU memory budget (`--gpu-budget`, `gpu_budget_mib`): a scene uploaded under it, its
//! pages streamed from the assets' cache files (`ssbvb_gpu::scene::streaming`), and what a
//! render reports about it.

use std::path::PathBuf;
use std::sync::Arc;

use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{GpuScene, StreamingOptions, StreamingStats};
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::cache::{PageFile, PrepareOutcome};
use ssbvb_voxel::camera::Camera;

use crate::EngineError;

/// Largest budget accepted (MiB): 1 TiB, as in scene files.
pub const MAX_BUDGET_MIB: u64 = ssbvb_scene_file::MAX_GPU_BUDGET_MIB;

/// Where one object's pages can be read: its asset's cache file.
#[derive(Debug, Clone)]
pub struct PageSourceRef {
    path: PathBuf,
    key: u128,
    level: u32,
}

impl PageSourceRef {
    /// The cache file an asset was read from or written to (`None` when it could not be
    /// written: its pages then come from the asset in memory).
    pub fn of(outcome: &PrepareOutcome, level: u32) -> Option<Self> {
        outcome.cache_write_error.is_none().then(|| Self {
            path: outcome.cache_path.clone(),
            key: outcome.cache_key,
            level,
        })
    }
}

/// Streaming options for a budget of `mib` MiB with pages from the objects' cache files
/// (an object whose file cannot be opened streams from memory, and `notes` says why).
pub fn options(
    mib: u64,
    sources: &[Option<PageSourceRef>],
    max_pages_per_frame: usize,
    notes: &mut Vec<String>,
) -> Result<StreamingOptions, EngineError> {
    if mib == 0 || mib > MAX_BUDGET_MIB {
        return Err(EngineError::Invalid(format!(
            "--gpu-budget must be 1..={MAX_BUDGET_MIB} MiB, got {mib}"
        )));
    }
    let page_files = sources
        .iter()
        .map(|s| {
            let s = s.as_ref()?;
            match PageFile::open(&s.path, s.key, s.level) {
                Ok(f) => Some(Arc::new(f)),
                Err(e) => {
                    notes.push(format!("pages streamed from memory: {e}"));
                    None
                }
            }
        })
        .collect();
    Ok(StreamingOptions {
        page_files,
        ..StreamingOptions::mib(mib).with_pages_per_frame(max_pages_per_frame)
    })
}

/// `render --json`'s `streaming`.
#[derive(Debug, Clone, Serialize)]
pub struct StreamingReport {
    /// Frames rendered until one needed no missing page (the image written is the next,
    /// identical, measured frame); when `converged` is false, the frame limit.
    pub frames_to_converge: usize,
    /// Whether a frame needed no missing page within the frame limit.
    pub converged: bool,
    /// Pages resident at the end.
    pub pages_resident: u64,
    /// Pages streamed in, in all.
    pub pages_streamed: u64,
    /// GPU bytes of the voxel scene at the end (the fixed part plus the resident pages).
    pub bytes_resident: u64,
    /// Everything else the page cache counted.
    #[serde(flatten)]
    pub stats: StreamingStats,
    /// Pages refused (failed to read or check), with why; their rays kept a coarser level.
    pub page_errors: Vec<String>,
}

impl StreamingReport {
    /// The report of a streamed scene after `frames` frames.
    pub fn of(scene: &GpuScene, frames: usize, converged: bool) -> Option<Self> {
        let stats = scene.streaming_stats()?.clone();
        Some(Self {
            frames_to_converge: frames,
            converged,
            pages_resident: stats.pages_resident,
            pages_streamed: stats.pages_streamed,
            bytes_resident: stats.bytes_resident,
            stats,
            page_errors: scene.page_errors(),
        })
    }
}

/// Warnings about a budgeted render that did not settle at the levels asked for.
pub fn streaming_warnings(
    streaming: Option<&StreamingReport>,
    frames: usize,
    warnings: &mut Vec<String>,
) {
    let Some(s) = streaming else {
        return;
    };
    if !s.converged {
        warnings.push(format!(
            "not converged in {frames} frames under a {} MiB GPU budget: {} pages \
             still missing{}; those rays show coarser voxels",
            s.stats.budget_bytes >> 20,
            s.stats.pages_missing,
            if s.stats.over_budget {
                " (the view needs more pages than the budget holds)"
            } else {
                " (raise --max-frames)"
            }
        ));
    }
    if let Some(cap) = s.stats.level_cap {
        warnings.push(format!(
            "the view's pages do not fit a {} MiB GPU budget at the levels asked for: \
             drawn at level {cap} at most",
            s.stats.budget_bytes >> 20
        ));
    }
    if s.stats.pages_failed > 0 {
        warnings.push(format!(
            "{} pages refused (damaged cache file?); their rays show coarser voxels: {}",
            s.stats.pages_failed,
            s.page_errors.first().map_or("", String::as_str)
        ));
    }
}

/// Renders frames of `camera` until one needs no missing page, at most `max_frames`,
/// streaming between them (waiting for each frame's feedback: offline rendering). Returns
/// how many frames it took and whether it converged. Without a budget: one frame.
pub fn converge(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    scene: &mut GpuScene,
    camera: &Camera,
    max_frames: usize,
) -> Result<(usize, bool), EngineError> {
    let mut frames = 0;
    loop {
        renderer.render(ctx, scene, camera, Profiling::Off)?;
        frames += 1;
        scene.sync_streaming(ctx)?;
        let Some(st) = scene.streaming_stats() else {
            return Ok((frames, true));
        };
        if st.pages_missing == 0 {
            return Ok((frames, true));
        }
        if frames >= max_frames.max(1) {
            return Ok((frames, false));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_out_of_range_are_refused_and_unopenable_files_stream_from_memory() {
        let mut notes = Vec::new();
        for bad in [0, MAX_BUDGET_MIB + 1] {
            let e = options(bad, &[], 8, &mut notes).unwrap_err().to_string();
            assert!(e.contains("--gpu-budget must be 1..="), "{e}");
        }
        let missing = Some(PageSourceRef {
            path: PathBuf::from("/nonexistent/ssbvb/x.ssbvbast"),
            key: 1,
            level: 5,
        });
        let o = options(64, &[missing, None], 8, &mut notes).unwrap();
        assert_eq!(o.budget_bytes, 64 << 20);
        assert_eq!(o.max_pages_per_frame, 8);
        assert!(o.page_files.iter().all(Option::is_none));
        assert_eq!(notes.len(), 1);
        assert!(
            notes[0].contains("/nonexistent/ssbvb/x.ssbvbast"),
            "{notes:?}"
        );
    }
}
