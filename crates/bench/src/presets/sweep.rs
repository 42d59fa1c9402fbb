//! Speed–accuracy knob sweeps of `ssbvb bench --sweep` (always on with `--preset full`):
//! each knob of the paper's SSBVB frame (`assets/pipelines/ssbvb_flat.ron`: one billboard
//! per covered pixel, so the resolution and size knobs act on every pixel's billboard)
//! changed alone, the frame timed and compared with the CPU reference (coverage, depth,
//! and the shaded composite as PSNR). The rows go into the main report.

use std::sync::Arc;

use anyhow::{Context, Result};
use glam::DAffine3;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::LodPolicy;
use ssbvb_graph::{PassKind, ResolvedPipeline};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;

use crate::args::{BenchArgs, Preset};
use crate::harness::{
    Measured, Setup, bundled_bunny, bundled_pipeline, measure, median, reference_at,
    with_filter_scale, with_kind_edit,
};
use crate::report::SweepRow;

/// The knob sweeps on the bunny, with `--sweep` or the full preset (never for the study),
/// on `ctx` seen from `camera`; empty otherwise.
pub(crate) fn run(args: &BenchArgs, ctx: &GpuContext, camera: &Camera) -> Result<Vec<SweepRow>> {
    if !((args.sweep || matches!(args.preset, Preset::Full))
        && !matches!(args.preset, Preset::Study))
    {
        return Ok(Vec::new());
    }
    let cfg = sweep_config(args.preset);
    let (asset, _) = bundled_bunny(cfg.level)?;
    run_sweeps(ctx, &asset, camera, &cfg, !args.json)
}

/// Sweep sizes.
struct SweepConfig {
    size: (u32, u32),
    /// Level of the fixed-level knobs, and the finest level the LOD-bias sweep may pick.
    level: u32,
    warmup: usize,
    frames: usize,
    max_steps: &'static [u32],
    size_scale: &'static [f64],
    max_i: &'static [f64],
    min_dist: &'static [f64],
    /// Fractions of the screen the empty-space prepass and the ray-march filter run at.
    resolution_scale: &'static [f64],
    lod_bias: &'static [i32],
}

/// Sweep sizes of a preset.
fn sweep_config(preset: Preset) -> SweepConfig {
    match preset {
        Preset::Quick
        | Preset::Study
        | Preset::Scale
        | Preset::Memory
        | Preset::Rastavox
        | Preset::Dynamic
        | Preset::Vct
        | Preset::Volumes
        | Preset::Paper
        | Preset::Quality => SweepConfig {
            size: (160, 120),
            level: 6,
            warmup: 1,
            frames: 2,
            max_steps: &[8, 32, 1024],
            size_scale: &[0.9, 1.0, 1.3],
            max_i: &[0.0, 1.0, 3.0],
            min_dist: &[0.0, 0.5, 2.0],
            resolution_scale: &[0.5, 1.0],
            lod_bias: &[-2, -1, 0],
        },
        Preset::Full => SweepConfig {
            size: (640, 480),
            level: 9,
            warmup: 3,
            frames: 10,
            max_steps: &[4, 8, 16, 32, 64, 1024],
            size_scale: &[0.8, 0.9, 1.0, 1.1, 1.3],
            max_i: &[0.0, 1.0, 2.0, 3.0],
            min_dist: &[0.0, 0.25, 0.5, 1.0, 2.0, 4.0],
            resolution_scale: &[0.25, 0.5, 0.75, 1.0],
            lod_bias: &[-3, -2, -1, 0],
        },
    }
}

/// One fixed-level sweep point: knob, value, whether it is the default, and the pipeline.
type Point = (&'static str, f64, bool, ResolvedPipeline);

/// The points of the knobs swept at the fixed level: `base` with one knob changed each.
fn knob_points(base: &ResolvedPipeline, cfg: &SweepConfig) -> Result<Vec<Point>> {
    let mut points: Vec<Point> = Vec::new();
    for &v in cfg.max_steps {
        let p = with_kind_edit(base, "max_steps", |k| match k {
            PassKind::RayMarchFilter(f) => {
                f.max_steps = v;
                true
            }
            _ => false,
        })?;
        points.push(("max_steps", v as f64, v == 1024, p));
    }
    for &v in cfg.size_scale {
        let p = with_kind_edit(base, "size_scale", |k| match k {
            PassKind::Billboards(b) => {
                b.size_scale = v as f32;
                true
            }
            _ => false,
        })?;
        points.push(("size_scale", v, v == 1.0, p));
    }
    for &v in cfg.max_i {
        let p = with_kind_edit(base, "max_i", |k| match k {
            PassKind::Smooth(s) => {
                s.max_i = v as f32;
                true
            }
            _ => false,
        })?;
        points.push(("max_i", v, v == 1.0, p));
    }
    for &v in cfg.min_dist {
        let p = with_kind_edit(base, "min_dist", |k| match k {
            PassKind::Smooth(s) => {
                s.min_dist = v as f32;
                true
            }
            _ => false,
        })?;
        points.push(("min_dist", v, v == 0.5, p));
    }
    for &v in cfg.resolution_scale {
        points.push(("resolution_scale", v, v == 1.0, with_filter_scale(base, v)?));
    }
    Ok(points)
}

/// The row of one measured point at `level` and `size`; `log` prints it.
fn sweep_row(
    (knob, value, is_default): (&'static str, f64, bool),
    level: u32,
    size: (u32, u32),
    m: Measured,
    log: bool,
) -> SweepRow {
    let mut t = m.times.clone();
    let row = SweepRow {
        knob,
        value,
        is_default,
        level,
        width: size.0,
        height: size.1,
        frames: m.times.len(),
        frame_ms_median: median(&mut t),
        fill_count: m.fill,
        coverage_iou: m.acc.coverage_iou,
        depth_error_voxels_median: m.acc.depth_error_voxels.median,
        psnr_db: m.psnr.map(|p| p.0).filter(|p| p.is_finite()),
        psnr_pixels: m.psnr.map_or(0, |p| p.1),
        ssim: m.ssim,
    };
    if log {
        eprintln!(
            "sweep {knob:<10} = {value:<6} L{level}: {:.2} ms, IoU {:.4}, depth err {:.3}, PSNR {}",
            row.frame_ms_median,
            row.coverage_iou,
            row.depth_error_voxels_median,
            row.psnr_db.map_or("-".into(), |p| format!("{p:.2} dB"))
        );
    }
    row
}

/// Runs every knob sweep; `log` prints a line per point.
fn run_sweeps(
    ctx: &GpuContext,
    asset: &Arc<VoxelAsset>,
    camera: &Camera,
    cfg: &SweepConfig,
    log: bool,
) -> Result<Vec<SweepRow>> {
    let base = bundled_pipeline("ssbvb_flat.ron")?;
    let size = cfg.size;
    let fixed_ref = reference_at(asset, cfg.level, camera, size);
    let points = knob_points(&base, cfg)?;
    let mut rows = Vec::new();
    let fixed = Setup {
        ctx,
        asset,
        lod: LodPolicy::Fixed(cfg.level),
        level: cfg.level,
        size,
        camera,
        reference: &fixed_ref,
        supersampled: None,
        warmup: cfg.warmup,
        frames: cfg.frames,
        streaming: None,
    };
    for (knob, value, is_default, pipeline) in points {
        let m =
            measure(&fixed, pipeline, true).with_context(|| format!("sweep {knob} = {value}"))?;
        rows.push(sweep_row(
            (knob, value, is_default),
            cfg.level,
            size,
            m,
            log,
        ));
    }
    let max_level = asset.lods.len() as u32 - 1;
    for &bias in cfg.lod_bias {
        let lod = LodPolicy::Auto {
            bias,
            pixel_error: 1.0,
        };
        let level =
            ssbvb_gpu::scene::choose_level(lod, &DAffine3::IDENTITY, camera, size, max_level);
        let reference = reference_at(asset, level, camera, size);
        let setup = Setup {
            lod,
            level,
            reference: &reference,
            ..fixed
        };
        let m = measure(&setup, base.clone(), true)
            .with_context(|| format!("sweep lod_bias = {bias}"))?;
        rows.push(sweep_row(
            ("lod_bias", bias as f64, bias == 0),
            level,
            size,
            m,
            log,
        ));
    }
    Ok(rows)
}
