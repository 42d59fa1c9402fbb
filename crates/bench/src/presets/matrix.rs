//! The main matrix of `--preset quick`, `full` and `study`: what each of them covers (the
//! models, levels, image sizes, frame counts and camera, with `--levels`, `--sizes` and
//! `--frames` applied; changing what a preset covers happens here only), and measuring it:
//! every technique on every cell (a model at a level, seen at one size), each giving one
//! [`Row`] of timings, memory and accuracy against the CPU reference. Cells the device
//! cannot hold, or levels a technique does not support, are recorded as skipped rather
//! than failing the run.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, Result};
use glam::DVec3;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::LodPolicy;
use ssbvb_graph::PassKind;
use ssbvb_voxel::camera::Camera;

use crate::args::{BenchArgs, Preset};
use crate::harness::techniques::{self, Technique};
use crate::harness::{
    Setup, bench_camera, measure, median, reference_at, supersampled_reference_at,
    technique_pipeline,
};
use crate::report::{Results, Row};
use ssbvb_engine::assets::assets_dir;

/// The main matrix measured, and what its report needs besides.
pub(crate) struct Measured {
    /// The context every technique ran on (the knob sweeps run on it too).
    pub(crate) ctx: GpuContext,
    /// The camera of every cell.
    pub(crate) camera: Camera,
    pub(crate) results: Results,
}

/// Measures the preset's matrix (every selected technique on every cell).
pub(crate) fn run(args: &BenchArgs) -> Result<Measured> {
    let m = matrix(args);
    let techniques = techniques::select(args)?;
    let mut device = Device {
        ctx: open_context(&techniques)?,
        faults: &args.inject_fault,
        rows: 0,
        lost_last_row: false,
    };
    let budget = args.gpu_budget.as_ref().and_then(|b| b.first().copied());
    let results = run_matrix(&mut device, &m, &techniques, budget, !args.json)?;
    let ctx = device.ctx;
    Ok(Measured {
        ctx,
        camera: m.camera,
        results,
    })
}

/// The matrix's device: replaced by a new one when it is lost while a row is measured.
struct Device<'a> {
    ctx: GpuContext,
    /// Faults to inject (`--inject-fault device-lost@ROW`).
    faults: &'a [ssbvb_engine::faults::Fault],
    /// Rows begun so far.
    rows: usize,
    /// Whether the last row lost the device (a second loss in a row ends the run).
    lost_last_row: bool,
}

/// A headless GPU context that can run every technique's pipeline.
fn open_context(techniques: &[&Technique]) -> Result<GpuContext> {
    let pipelines = techniques
        .iter()
        .map(|t| technique_pipeline(t))
        .collect::<Result<Vec<_>>>()?;
    Ok(ssbvb_engine::choice::headless_context(
        &pipelines.iter().collect::<Vec<_>>(),
    )?)
}

/// A benchmarked model.
#[derive(Debug, Clone)]
enum BenchModel {
    /// A model file, voxelized (and cached) per level.
    File(PathBuf),
    /// A procedural voxel set.
    Procedural(&'static str, ssbvb_voxel::procedural::ProceduralModel),
}

impl BenchModel {
    /// Name in reports (the file name, or the procedural model's name).
    fn name(&self) -> String {
        match self {
            BenchModel::File(p) => p
                .file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into()),
            BenchModel::Procedural(n, _) => (*n).to_string(),
        }
    }

    /// The voxel asset for `level` (voxelized and cached, or generated); it may lack that
    /// level, which the caller checks.
    fn asset(&self, level: u32) -> Result<Arc<ssbvb_voxel::asset::VoxelAsset>> {
        let asset = match self {
            BenchModel::File(path) => {
                ssbvb_voxel::cache::load_or_prepare(
                    path,
                    level,
                    None,
                    &ssbvb_voxel::progress::NoProgress,
                )
                .with_context(|| format!("preparing {}", path.display()))?
                .0
            }
            BenchModel::Procedural(name, m) => {
                let set = m
                    .voxels(level)
                    .with_context(|| format!("generating {name} at level {level}"))?;
                ssbvb_voxel::prepare::prepare_voxel_set(set, &ssbvb_voxel::progress::NoProgress).0
            }
        };
        Ok(Arc::new(asset))
    }
}

/// The matrix a preset runs.
struct Matrix {
    /// Models, in report order.
    models: Vec<BenchModel>,
    /// Levels (2^level cells per axis).
    levels: Vec<u32>,
    /// Image sizes.
    sizes: Vec<(u32, u32)>,
    /// Untimed frames per cell.
    warmup: usize,
    /// Timed frames per cell.
    frames: usize,
    /// The camera of every cell.
    camera: Camera,
    /// Samples per pixel of the reference FLIP is measured against.
    flip_samples: ssbvb_voxel::reference::SampleGrid,
}

/// The models of `--preset paper`: the bunny first (the paper's Table 2 row), then the
/// other models of `assets/models/`.
pub(crate) const PAPER_MODELS: &[&str] = &[
    "bunny.obj",
    "cow.obj",
    "teapot.obj",
    "igea.ply",
    "T-Rex.vox",
    "chr_knight.vox",
    "monu1.vox",
];

/// The preset's matrix with the command line's overrides.
fn matrix(args: &BenchArgs) -> Matrix {
    let bunny = BenchModel::File(assets_dir().join("models/bunny.obj"));
    let mut m = match args.preset {
        Preset::Quick
        | Preset::Scale
        | Preset::Memory
        | Preset::Rastavox
        | Preset::Dynamic
        | Preset::Vct
        | Preset::Volumes
        | Preset::Quality => Matrix {
            models: vec![bunny],
            levels: vec![5, 6],
            sizes: vec![(160, 120)],
            warmup: 1,
            frames: 3,
            camera: bench_camera(),
            // Set from the command line below.
            flip_samples: ssbvb_voxel::reference::SampleGrid::CENTRE,
        },
        // Table 2 of the seed paper: its bunny row and every other bundled model, at level
        // 9 and 720p.
        Preset::Paper => Matrix {
            models: PAPER_MODELS
                .iter()
                .map(|m| assets_dir().join("models").join(m))
                // Only the bunny is embedded in the binary; the others come with a checkout.
                .filter(|p| p.is_file())
                .map(BenchModel::File)
                .collect(),
            levels: vec![9],
            sizes: vec![(1280, 720)],
            warmup: 2,
            frames: 5,
            camera: bench_camera(),
            // Set from the command line below.
            flip_samples: ssbvb_voxel::reference::SampleGrid::CENTRE,
        },
        Preset::Full => Matrix {
            models: vec![bunny],
            levels: vec![7, 8, 9, 10, 11, 12],
            sizes: vec![(640, 480), (1280, 720)],
            warmup: 3,
            frames: 10,
            camera: bench_camera(),
            // Set from the command line below.
            flip_samples: ssbvb_voxel::reference::SampleGrid::CENTRE,
        },
        Preset::Study => Matrix {
            models: vec![
                BenchModel::Procedural(
                    "ball",
                    ssbvb_voxel::procedural::ProceduralModel::FilledBall,
                ),
                BenchModel::Procedural(
                    "random50",
                    ssbvb_voxel::procedural::ProceduralModel::Random {
                        fraction: 0.5,
                        seed: 2,
                    },
                ),
                bunny,
            ],
            levels: (3..=9).collect(),
            sizes: vec![
                (640, 480),
                (800, 600),
                (1280, 720),
                (1366, 768),
                (1600, 1024),
                (1920, 1200),
                (2560, 1440),
            ],
            warmup: 1,
            frames: 5,
            // The grid's cube seen from above a corner, filling most of the view's height.
            camera: Camera::new(DVec3::new(2.2, 1.7, 2.9), DVec3::ZERO),
            // Set from the command line below.
            flip_samples: ssbvb_voxel::reference::SampleGrid::CENTRE,
        },
    };
    if let Some(l) = &args.levels {
        m.levels = l.clone();
    }
    if let Some(s) = &args.sizes {
        m.sizes = s.clone();
    }
    if let Some(f) = args.frames {
        m.frames = f.max(1);
    }
    m.flip_samples = args.flip_samples_grid();
    m
}

/// Measures every technique on every cell of `m`; `log` prints a line per cell.
fn run_matrix(
    device: &mut Device<'_>,
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
                let supersampled =
                    supersampled_reference_at(&asset, level, &m.camera, size, m.flip_samples);
                let cell = Cell {
                    model: model.name(),
                    asset: &asset,
                    level,
                    size,
                    camera: &m.camera,
                    reference: &reference,
                    supersampled: &supersampled,
                    warmup: m.warmup,
                    frames: m.frames,
                    voxels,
                    budget_mib,
                };
                run_cell(device, &cell, techniques, log, &mut out)?;
            }
        }
    }
    Ok(out)
}

/// Measures every technique on one cell.
fn run_cell(
    device: &mut Device<'_>,
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
        if ssbvb_engine::faults::loses_device_at(device.faults, device.rows) {
            device.ctx.inject_device_loss();
        }
        if ssbvb_engine::faults::runs_out_of_memory_at(device.faults, device.rows) {
            device
                .ctx
                .refuse_allocation(ssbvb_engine::faults::INJECTED_OOM_MIN_BYTES);
        }
        device.rows += 1;
        let result = run_one(&device.ctx, t, cell);
        // An injected refusal is the row's: one that did not fire goes with it.
        device.ctx.clear_refusal();
        if result.is_err()
            && let Some(reason) = device.ctx.lost()
        {
            if device.lost_last_row {
                anyhow::bail!(
                    "{what}: the GPU device was lost again on the row after the last loss \
                     ({reason}); giving up rather than retrying"
                );
            }
            let why = format!(
                "{what}: the GPU device was lost ({reason}); the rows after it ran on a new device"
            );
            if log {
                eprintln!("failed {why}");
            }
            out.failed.push(why);
            device.ctx = open_context(techniques)
                .with_context(|| format!("a new GPU device after losing it on {what}"))?;
            device.lost_last_row = true;
            continue;
        }
        device.lost_last_row = false;
        let row = match result {
            Ok(row) => row,
            // What the device cannot hold is a result, not a failure of the run.
            // A refused allocation fails the row, with the resource named; the next row
            // asks again.
            Err(e) if ssbvb_engine::faults::out_of_memory(e.as_ref()).is_some() => {
                if log {
                    eprintln!("failed {what}: {e:#}");
                }
                out.failed.push(format!("{what}: {e:#}"));
                continue;
            }
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
        c.downcast_ref::<ssbvb_passes::PassError>()
            .is_some_and(ssbvb_passes::PassError::is_too_large)
            || matches!(
                c.downcast_ref::<ssbvb_gpu::ResourceError>(),
                Some(ssbvb_gpu::ResourceError::TooLarge(_))
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
    /// The reference at `Matrix::flip_samples` per pixel (FLIP's).
    supersampled: &'a ssbvb_voxel::reference::ReferenceImage,
    warmup: usize,
    frames: usize,
    voxels: usize,
    /// Upload under this GPU budget (MiB).
    budget_mib: Option<u64>,
}

/// Measures technique `t` on cell `c`.
fn run_one(ctx: &GpuContext, t: &Technique, c: &Cell) -> Result<Row> {
    let pipeline = technique_pipeline(t)?;
    let streaming = c
        .budget_mib
        .map(|mib| ssbvb_gpu::scene::StreamingOptions::mib(mib).with_pages_per_frame(usize::MAX));
    let setup = Setup {
        ctx,
        asset: c.asset,
        lod: LodPolicy::Fixed(c.level),
        level: c.level,
        size: c.size,
        camera: c.camera,
        reference: c.reference,
        supersampled: Some(c.supersampled),
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
    let frame_gpu_ms_median = m.gpu_times.map(|mut g| median(&mut g));
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
        frame_gpu_ms_median,
        passes: m.passes,
        fill_count: fill,
        covered_pixels: acc.covered_reference,
        voxels: c.voxels,
        gpu_memory_bytes: m.gpu_memory + cube_bytes + surface_bytes,
        coverage_iou: acc.coverage_iou,
        // Voxel ids per pixel come from the slot each pixel's ray filled; with unique_voxels
        // (one slot per voxel, at the pixel that claimed it) over those pixels only; none
        // without an SSBVB (the direct form).
        same_voxel_rate: if matches!(
            t.name,
            "ssbvb"
                | "ssbvb-unique"
                | "ssbvb-splat"
                | "ssbvb-pixel"
                | "ssbvb-direct"
                | "ssbvb-compute"
                | "ssbvb-all-compute"
                | "ssbvb-aa"
        ) {
            m.slot_same_voxel_rate
        } else {
            fill.map(|_| acc.same_voxel_rate)
        },
        depth_error_voxels_median: acc.depth_error_voxels.median,
        normal_error_deg_median: acc.normal_error_deg.median,
        psnr_db: m.psnr.map(|p| p.0).filter(|p| p.is_finite()),
        ssim: m.ssim,
        flip_mean: m.flip_mean,
        counters: m.counters,
    })
}
