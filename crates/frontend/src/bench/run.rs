//! Measuring the main matrix: every technique on every cell (a model at a level, seen at
//! one size), each giving one [`Row`] of timings, memory and accuracy against the CPU
//! reference. Cells the device cannot hold, or levels a technique does not support, are
//! recorded as skipped rather than failing the run.

use std::sync::Arc;

use anyhow::Result;
use serde::Serialize;
use ssbvb_graph::PassKind;
use ssbvb_passes::LodPolicy;
use ssbvb_voxel::camera::Camera;

use super::matrix::Matrix;
use super::sweep::{Setup, bundled_pipeline, measure, reference_at, with_kind_edit};
use super::techniques::Technique;

/// One row of results.
#[derive(Debug, Serialize)]
pub(super) struct Row {
    pub(super) technique: &'static str,
    pub(super) model: String,
    /// Occupied cells at this level.
    pub(super) level: u32,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) frames: usize,
    pub(super) frame_ms_median: f64,
    pub(super) frame_ms_min: f64,
    pub(super) frame_ms_max: f64,
    pub(super) passes: Vec<ssbvb_passes::PassTiming>,
    pub(super) fill_count: Option<u32>,
    /// Pixels the reference covers (what the fill count is compared with).
    pub(super) covered_pixels: usize,
    pub(super) voxels: usize,
    pub(super) gpu_memory_bytes: u64,
    pub(super) coverage_iou: f64,
    /// `None` for techniques that keep no per-pixel voxel ids (all but the per-pixel
    /// SSBVB).
    pub(super) same_voxel_rate: Option<f64>,
    pub(super) depth_error_voxels_median: f64,
    pub(super) normal_error_deg_median: f64,
    /// PSNR (dB) of the composite over the pixels either covers (`None`: identical).
    pub(super) psnr_db: Option<f64>,
    /// Mean SSIM of the composite (see `sweep::Measured::ssim`).
    pub(super) ssim: Option<f64>,
    /// Hardware-independent counts of the profiled frame.
    pub(super) counters: ssbvb_passes::FrameCounters,
}

impl Row {
    /// Traversal steps per ray of the technique's ray walk: march steps of the filter,
    /// DDA cells or octree nodes of the ray casters (`None` for rasterizers).
    pub(super) fn steps_per_ray(&self) -> Option<f64> {
        let c = &self.counters;
        c.march_steps_mean
            .or(c.dda_steps_per_ray)
            .or(c.octree_nodes_per_ray)
    }
}

/// Frames of one renderer: its median frame time over `frames` timed frames after one
/// warm-up, then one profiled frame (per-pass wall times on a software adapter, whose
/// timestamps are unreliable; GPU timestamps elsewhere).
pub(super) struct TimedFrames {
    /// Median wall time of the timed frames (ms).
    pub(super) frame_ms: f64,
    /// The profiled frame.
    pub(super) stats: ssbvb_passes::FrameStats,
    software: bool,
}

impl TimedFrames {
    /// Renders and times (see the type).
    pub(super) fn run(
        ctx: &ssbvb_gpu::GpuContext,
        renderer: &mut ssbvb_passes::Renderer,
        gpu_scene: &mut ssbvb_passes::GpuScene,
        camera: &ssbvb_voxel::camera::Camera,
        frames: usize,
    ) -> anyhow::Result<Self> {
        use ssbvb_passes::Profiling;
        renderer.render(ctx, gpu_scene, camera, Profiling::Off)?;
        ctx.wait_idle()?;
        let mut times = Vec::new();
        for _ in 0..frames.max(1) {
            let t0 = std::time::Instant::now();
            renderer.render(ctx, gpu_scene, camera, Profiling::Off)?;
            ctx.wait_idle()?;
            times.push(t0.elapsed().as_secs_f64() * 1e3);
        }
        let software = ctx.report().is_software;
        let profiling = if software {
            Profiling::TimestampsAndWall
        } else {
            Profiling::Timestamps
        };
        let stats = renderer.render(ctx, gpu_scene, camera, profiling)?;
        Ok(Self {
            frame_ms: median(&mut times),
            stats,
            software,
        })
    }

    /// The time of pass `name` in the profiled frame (ms).
    pub(super) fn pass_ms(&self, name: &str) -> Option<f64> {
        let p = self.stats.passes.iter().find(|p| p.name == name)?;
        if self.software {
            p.wall_ms
        } else {
            p.gpu_ms.or(p.wall_ms)
        }
    }
}

/// The median of `v` (sorts it; the upper one of an even count).
pub(super) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// What the matrix gave.
#[derive(Default)]
pub(super) struct Results {
    /// One row per measured cell and technique, in measuring order.
    pub(super) rows: Vec<Row>,
    /// Why cells were not measured.
    pub(super) skipped: Vec<String>,
}

/// Measures every technique on every cell of `m`; `log` prints a line per cell.
pub(super) fn run_matrix(
    ctx: &ssbvb_gpu::GpuContext,
    m: &Matrix,
    techniques: &[&Technique],
    budget_mib: Option<u64>,
    log: bool,
) -> Result<Results> {
    let mut out = Results::default();
    for model in &m.models {
        for &level in &m.levels {
            let asset = model.asset(level)?;
            if asset.lods.len() as u32 <= level {
                out.skipped
                    .push(format!("{} has no level {level}", model.name()));
                continue;
            }
            let voxels = asset.lods[level as usize].point_cloud.voxels.len();
            for &size in &m.sizes {
                let reference = reference_at(&asset, level, &m.camera, size);
                let cell = Cell {
                    model: model.name(),
                    asset: &asset,
                    level,
                    size,
                    camera: &m.camera,
                    reference: &reference,
                    warmup: m.warmup,
                    frames: m.frames,
                    voxels,
                    budget_mib,
                };
                run_cell(ctx, &cell, techniques, log, &mut out)?;
            }
        }
    }
    Ok(out)
}

/// Measures every technique on one cell.
fn run_cell(
    ctx: &ssbvb_gpu::GpuContext,
    cell: &Cell,
    techniques: &[&Technique],
    log: bool,
    out: &mut Results,
) -> Result<()> {
    let level = cell.level;
    for t in techniques {
        if level > t.max_level {
            out.skipped.push(format!(
                "{} at level {level}: supports levels up to {}",
                t.name, t.max_level
            ));
            continue;
        }
        let what = format!(
            "{} on {} level {level} {}x{}",
            t.name, cell.model, cell.size.0, cell.size.1
        );
        let row = match run_one(ctx, t, cell) {
            Ok(row) => row,
            // What the device cannot hold is a result, not a failure of the run.
            Err(e) if too_large(&e) || needs_whole_levels(&e) => {
                if log {
                    eprintln!("skipped {what}: {e:#}");
                }
                out.skipped.push(format!("{what}: {e:#}"));
                continue;
            }
            Err(e) => return Err(e.context(what)),
        };
        if log {
            eprintln!(
                "{:<13} {} L{level} {}x{}: {:.2} ms median, IoU {:.4}",
                t.name, cell.model, cell.size.0, cell.size.1, row.frame_ms_median, row.coverage_iou
            );
        }
        out.rows.push(row);
    }
    Ok(())
}

/// Whether `e` says the scene does not fit the device's limits.
fn too_large(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<ssbvb_passes::PassError>(),
            Some(ssbvb_passes::PassError::TooLarge(_))
        )
    })
}

/// Whether `e` says a technique cannot run on a scene paged under a budget.
fn needs_whole_levels(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<ssbvb_passes::PassError>(),
            Some(ssbvb_passes::PassError::NeedsWholeLevels { .. })
        )
    })
}

/// One cell of the matrix: a model at a level, seen at one size.
struct Cell<'a> {
    model: String,
    asset: &'a Arc<ssbvb_voxel::asset::VoxelAsset>,
    level: u32,
    size: (u32, u32),
    camera: &'a Camera,
    reference: &'a ssbvb_voxel::reference::ReferenceImage,
    warmup: usize,
    frames: usize,
    voxels: usize,
    /// Upload under this GPU budget (MiB).
    budget_mib: Option<u64>,
}

/// Measures technique `t` on cell `c`.
fn run_one(ctx: &ssbvb_gpu::GpuContext, t: &Technique, c: &Cell) -> Result<Row> {
    let mut pipeline = bundled_pipeline(t.pipeline)?;
    if let Some(edit) = t.edit {
        pipeline = with_kind_edit(&pipeline, t.name, edit)?;
    }
    let streaming = c
        .budget_mib
        .map(|mib| ssbvb_passes::StreamingOptions::mib(mib).with_pages_per_frame(usize::MAX));
    let setup = Setup {
        ctx,
        asset: c.asset,
        lod: LodPolicy::Fixed(c.level),
        level: c.level,
        size: c.size,
        camera: c.camera,
        reference: c.reference,
        warmup: c.warmup,
        frames: c.frames,
        streaming: streaming.as_ref(),
    };
    // The cube rasterizer's instance buffer comes on top of the scene's buffers (whose
    // lookup it reads for voxel attributes).
    let cube_merge = pipeline.passes.iter().find_map(|p| match &p.kind {
        PassKind::CubeRaster(c) => Some(c.merge_full_nodes),
        _ => None,
    });
    let cube_bytes = match cube_merge {
        Some(merge) => {
            ssbvb_voxel::cube_list::CubeList::from_lod(&c.asset.lods[c.level as usize], merge)
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .bytes() as u64
        }
        None => 0,
    };
    // RastaVox's surface model (all its LODs) likewise.
    let surface_bytes = if pipeline
        .passes
        .iter()
        .any(|p| matches!(p.kind, PassKind::RastaVox(_)))
    {
        ssbvb_voxel::surface::SurfaceModel::extract(&c.asset.lods[c.level as usize])
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .bytes()
            .total()
    } else {
        0
    };
    let m = measure(&setup, pipeline, true)?;
    let (fill, acc, mut times) = (m.fill, m.acc, m.times);
    let (min, max) = times
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    Ok(Row {
        technique: t.name,
        model: c.model.clone(),
        level: c.level,
        width: c.size.0,
        height: c.size.1,
        frames: times.len(),
        frame_ms_median: median(&mut times),
        frame_ms_min: min,
        frame_ms_max: max,
        passes: m.passes,
        fill_count: fill,
        covered_pixels: acc.covered_reference,
        voxels: c.voxels,
        gpu_memory_bytes: m.gpu_memory + cube_bytes + surface_bytes,
        coverage_iou: acc.coverage_iou,
        // Voxel ids per pixel come from the slot each pixel's ray filled: not available
        // with unique_voxels (one slot per voxel, not per pixel).
        same_voxel_rate: fill
            .filter(|_| !matches!(t.name, "ssbvb-unique" | "ssbvb-splat"))
            .map(|_| acc.same_voxel_rate),
        depth_error_voxels_median: acc.depth_error_voxels.median,
        normal_error_deg_median: acc.normal_error_deg.median,
        psnr_db: m.psnr.map(|p| p.0).filter(|p| p.is_finite()),
        ssim: m.ssim,
        counters: m.counters,
    })
}
