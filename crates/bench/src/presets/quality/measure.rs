//! Drawing a view's frames: by a technique on the GPU, or by the CPU reference; and the
//! FLIP numbers of a row.

use std::collections::HashMap;
use std::time::Instant;

use anyhow::Result;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::choose_level_held;
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::Profiling;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{self, SampleGrid};

use super::views::QualityView;
use crate::flip::{flip_rgb8, over_black};
use crate::harness::median;

/// Per frame, the level each instance was drawn at (by scene index; `None`: not drawn).
pub(super) type Levels = Vec<Option<u32>>;

/// What one technique (or reference) drew of a view: the still frame and its levels, each
/// frame of the path and its levels, and the median time of a path frame.
pub(super) struct Drawn {
    pub still: Vec<u8>,
    pub still_levels: Levels,
    pub frames: Vec<Vec<u8>>,
    pub levels: Vec<Levels>,
    pub frame_ms_median: f64,
    /// With a temporal pass: per path frame, the share of pixels whose history it
    /// rejected.
    pub rejected: Vec<Option<f64>>,
}

/// Frames the camera holds still at the path's start before the still frame is taken (a
/// temporal pass's whole jitter sequence).
const STILL_FRAMES: usize = ssbvb_passes::kinds::temporal::JITTER_PERIOD as usize;

/// What `pipeline` draws of `view` over black (RGB8): the still frame (the first camera
/// after [`STILL_FRAMES`] frames), then each frame of the path, which starts there. The
/// scene's Auto LOD keeps `hysteresis` ([`GpuScene::lod_hysteresis`]).
pub(super) fn technique_frames(
    ctx: &GpuContext,
    view: &QualityView,
    pipeline: ResolvedPipeline,
    size: (u32, u32),
    hysteresis: f64,
) -> Result<Drawn> {
    let mut gpu_scene = ssbvb_engine::upload::upload_scene(
        ctx,
        view.scene.clone(),
        ssbvb_engine::upload::Residency::Whole,
    )?;
    gpu_scene.lod_hysteresis = hysteresis;
    let mut renderer = ssbvb_engine::upload::renderer(ctx, &gpu_scene, pipeline, size)?;
    let instances = view
        .scene
        .objects
        .iter()
        .map(|o| o.instances.len())
        .sum::<usize>();
    let mut draw = |camera: &Camera| -> Result<(Vec<u8>, Levels, f64, Option<f64>)> {
        let t0 = Instant::now();
        renderer.render(ctx, &mut gpu_scene, camera, Profiling::Off)?;
        ctx.wait_idle()?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let out = ctx.read_texture(
            &renderer.output().texture,
            ssbvb_gpu::wgpu::TextureAspect::All,
        )?;
        let mut levels = vec![None; instances];
        for v in &gpu_scene.visible {
            levels[v.scene_index as usize] = Some(v.level);
        }
        let rejected = renderer.history_rejected_share(ctx)?;
        Ok((
            over_black(&crate::harness::engine::to_rgba8(&out)?),
            levels,
            ms,
            rejected,
        ))
    };
    let mut still = (Vec::new(), Vec::new(), 0.0, None);
    for _ in 0..STILL_FRAMES {
        still = draw(&view.cameras[0])?;
    }
    let mut frames = Vec::new();
    let mut levels = Vec::new();
    let mut times = Vec::new();
    let mut rejected = Vec::new();
    for c in &view.cameras {
        let (f, l, ms, r) = draw(c)?;
        frames.push(f);
        levels.push(l);
        times.push(ms);
        rejected.push(r);
    }
    Ok(Drawn {
        still: still.0,
        still_levels: still.1,
        frames,
        levels,
        frame_ms_median: median(&mut times),
        rejected,
    })
}

/// Which levels a reference frame draws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum ReferenceLevels {
    /// Every instance at the asset's finest level (the ground truth).
    Finest,
    /// The levels the renderer's Auto LOD picks along the path, with `hysteresis`.
    Auto { hysteresis: f64 },
}

/// The levels of each instance of `view`'s object along its cameras.
fn reference_levels(view: &QualityView, size: (u32, u32), which: ReferenceLevels) -> Vec<Levels> {
    let max = view.asset.lods.len() as u32 - 1;
    let obj = &view.scene.objects[0];
    let mut held: Levels = vec![None; obj.instances.len()];
    view.cameras
        .iter()
        .map(|camera| {
            held = obj
                .instances
                .iter()
                .zip(&held)
                .map(|(xf, &previous)| {
                    Some(match which {
                        ReferenceLevels::Finest => max,
                        ReferenceLevels::Auto { hysteresis } => {
                            choose_level_held(obj.lod, xf, camera, size, max, previous, hysteresis)
                        }
                    })
                })
                .collect();
            held.clone()
        })
        .collect()
}

/// The reference of `view`'s scene from `camera` with `grid` samples per pixel, over black
/// (RGB8), each instance at its level of `levels` (the finest where `None`).
pub(super) fn reference_rgb(
    view: &QualityView,
    camera: &Camera,
    size: (u32, u32),
    grid: SampleGrid,
    levels: &[Option<u32>],
) -> Vec<u8> {
    let obj = &view.scene.objects[0];
    let finest = view.asset.lods.len() - 1;
    let instances: Vec<reference::Instance> = obj
        .instances
        .iter()
        .enumerate()
        .map(|(i, xf)| reference::Instance {
            lod: &view.asset.lods[levels
                .get(i)
                .copied()
                .flatten()
                .map_or(finest, |l| l as usize)],
            object_to_world: *xf,
            faces: None,
        })
        .collect();
    let img =
        reference::render_supersampled(&instances, camera, size.0, size.1, &view.scene.light, grid);
    over_black(&img.to_rgba8())
}

/// The reference's frames of `view` at `which` levels and `grid` samples per pixel.
pub(super) fn reference_frames(
    view: &QualityView,
    size: (u32, u32),
    grid: SampleGrid,
    which: ReferenceLevels,
) -> Drawn {
    let levels = reference_levels(view, size, which);
    let mut times = Vec::new();
    let frames: Vec<Vec<u8>> = view
        .cameras
        .iter()
        .zip(&levels)
        .map(|(c, l)| {
            let t0 = Instant::now();
            let f = reference_rgb(view, c, size, grid, l);
            times.push(t0.elapsed().as_secs_f64() * 1e3);
            f
        })
        .collect();
    Drawn {
        still: frames[0].clone(),
        still_levels: levels[0].clone(),
        frame_ms_median: median(&mut times),
        rejected: vec![None; frames.len()],
        frames,
        levels,
    }
}

/// The supersampled reference of a view at the levels a technique drew, by (frame,
/// levels): techniques that drew the same levels share one render. Frame `None` is the
/// still frame (the first camera).
pub(super) struct SameLevels<'a> {
    pub view: &'a QualityView,
    pub size: (u32, u32),
    pub grid: SampleGrid,
    cache: HashMap<(usize, Levels), Vec<u8>>,
}

impl<'a> SameLevels<'a> {
    pub(super) fn new(view: &'a QualityView, size: (u32, u32), grid: SampleGrid) -> Self {
        Self {
            view,
            size,
            grid,
            cache: HashMap::new(),
        }
    }

    /// The reference of camera `frame` at `levels`.
    pub(super) fn get(&mut self, frame: usize, levels: &Levels) -> &[u8] {
        let (view, size, grid) = (self.view, self.size, self.grid);
        self.cache
            .entry((frame, levels.clone()))
            .or_insert_with(|| reference_rgb(view, &view.cameras[frame], size, grid, levels))
    }
}

/// Mean FLIP between consecutive frames.
pub(super) fn flicker(frames: &[Vec<u8>], size: (u32, u32)) -> Result<f64> {
    let pairs = frames.len().saturating_sub(1);
    if pairs == 0 {
        return Ok(0.0);
    }
    let mut sum = 0.0;
    for w in frames.windows(2) {
        sum += flip_rgb8(&w[0], &w[1], size)?;
    }
    Ok(sum / pairs as f64)
}

/// Instance level changes between consecutive frames (instances drawn in both).
pub(super) fn lod_switches(levels: &[Levels]) -> usize {
    levels
        .windows(2)
        .map(|w| {
            w[0].iter()
                .zip(&w[1])
                .filter(|(a, b)| matches!((a, b), (Some(a), Some(b)) if a != b))
                .count()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lod_switches_count_changes_of_instances_drawn_in_both_frames() {
        let levels = vec![
            vec![Some(3), Some(4), None, Some(1)],
            vec![Some(4), Some(4), Some(2), None],
            vec![Some(3), Some(5), Some(2), Some(1)],
        ];
        // 0→1: instance 0 (3→4); 1→2: instances 0 and 1.
        assert_eq!(lod_switches(&levels), 3);
        assert_eq!(lod_switches(&levels[..1]), 0);
    }
}
