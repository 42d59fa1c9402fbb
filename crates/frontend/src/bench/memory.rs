//! `ssbvb bench --preset memory`: pages by demand under a GPU budget. The bunny at each
//! level (default 7-13) is rendered unbudgeted (when the device holds it) and under each
//! budget (`--gpu-budget`, default 32, 128 and 512 MiB): frames to converge, pages
//! streamed, resident MiB, the frame time once converged (and its ratio to the
//! unbudgeted frame of the same run) and the coverage IoU against the CPU reference at
//! that level. Then a fly-through (an orbit that closes in on the bunny, level 11 under
//! 64 MiB by default) streams without waiting, at most [`FLY_PAGES_PER_FRAME`] pages per
//! frame, and reports the worst frame against the median: streaming must not stall.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use glam::{DAffine3, DVec3};
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_passes::{
    GpuScene, LodPolicy, PassError, Profiling, Renderer, Scene, StreamingOptions, VoxelObject,
};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;

use super::BenchArgs;
use super::sweep::{bundled_pipeline, reference_at};

const DEFAULT_LEVELS: [u32; 7] = [7, 8, 9, 10, 11, 12, 13];
const DEFAULT_BUDGETS: [u64; 3] = [32, 128, 512];
/// Most frames rendered to converge.
const MAX_FRAMES: usize = 64;
/// Fly-through: level, budget (MiB), frames.
const FLY: (u32, u64, usize) = (11, 64, 72);
/// Pages streamed before one fly-through frame at most (as the viewer).
pub const FLY_PAGES_PER_FRAME: usize = 512;

/// One level under one budget (`None`: unbudgeted).
#[derive(Debug, Serialize)]
struct MemoryRow {
    level: u32,
    budget_mib: Option<u64>,
    /// GPU bytes of the whole asset, unbudgeted (MiB).
    full_mib: f64,
    /// Bytes that never leave under a budget (MiB).
    fixed_mib: Option<f64>,
    /// GPU MiB of the voxel scene once converged (the full size unbudgeted).
    resident_mib: f64,
    frames_to_converge: usize,
    converged: bool,
    pages_total: Option<u64>,
    pages_resident: Option<u64>,
    pages_streamed: Option<u64>,
    pages_streamed_per_frame: Option<f64>,
    pages_evicted: Option<u64>,
    over_budget: Option<bool>,
    /// The finest level streaming let the bunny use (`None`: its own, `level`).
    level_cap: Option<u32>,
    frame_ms_median: f64,
    /// Against the unbudgeted frame of the same level in this run.
    frame_ms_ratio: Option<f64>,
    coverage_iou: f64,
}

/// The fly-through.
#[derive(Debug, Serialize)]
struct FlyThrough {
    level: u32,
    budget_mib: u64,
    width: u32,
    height: u32,
    frames: usize,
    frame_ms_median: f64,
    frame_ms_worst: f64,
    worst_over_median: f64,
    pages_streamed_per_frame_mean: f64,
    pages_streamed_per_frame_max: u64,
    resident_mib_max: f64,
}

#[derive(Debug, Serialize)]
struct MemoryReport {
    adapter: String,
    adapter_is_software: bool,
    width: u32,
    height: u32,
    camera: Camera,
    rows: Vec<MemoryRow>,
    skipped: Vec<String>,
    fly_through: Option<FlyThrough>,
}

/// What one configuration gave.
struct Measured {
    frames: usize,
    converged: bool,
    times: Vec<f64>,
    iou: f64,
    stats: Option<ssbvb_passes::StreamingStats>,
    full: u64,
}

fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

fn scene(asset: &Arc<VoxelAsset>, level: u32) -> Scene {
    Scene {
        objects: vec![VoxelObject {
            asset: asset.clone(),
            instances: vec![DAffine3::IDENTITY],
            lod: LodPolicy::Fixed(level),
        }],
        ..Default::default()
    }
}

/// Renders `level` under `options` (or unbudgeted) until converged, then `frames` timed
/// frames, and compares the last with the reference.
#[allow(clippy::too_many_arguments)]
fn measure(
    ctx: &GpuContext,
    asset: &Arc<VoxelAsset>,
    level: u32,
    size: (u32, u32),
    camera: &Camera,
    options: Option<&StreamingOptions>,
    frames: usize,
    reference: &ssbvb_voxel::reference::ReferenceImage,
) -> Result<Measured> {
    let mut s = match options {
        Some(o) => GpuScene::streamed(ctx, scene(asset, level), o)?,
        None => GpuScene::new(ctx, scene(asset, level))?,
    };
    let full = s.total_memory();
    let mut r = Renderer::new(ctx, &s, bundled_pipeline("ssbvb.ron")?, size)?;
    let (n, converged) = crate::budget::converge(ctx, &mut r, &mut s, camera, MAX_FRAMES)?;
    let mut times = Vec::new();
    for _ in 0..frames.max(1) {
        let t0 = Instant::now();
        r.render(ctx, &mut s, camera, Profiling::Off)?;
        ctx.wait_idle()?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let hits = ssbvb_passes::measure::gbuffer_hits(ctx, &r)?;
    let acc = ssbvb_voxel::accuracy::compare(reference, &hits, &[2.0 / (1u64 << level) as f64])
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(Measured {
        frames: n,
        converged,
        times,
        iou: acc.coverage_iou,
        stats: s.streaming_stats().cloned(),
        full,
    })
}

/// Whether `e` says the scene or budget does not fit (a result, not a failure).
fn does_not_fit(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<PassError>(),
            Some(PassError::TooLarge(_) | PassError::BudgetTooSmall { .. })
        )
    })
}

/// Runs the memory preset.
pub(super) fn run(args: &BenchArgs) -> Result<()> {
    let levels = args
        .levels
        .clone()
        .unwrap_or_else(|| DEFAULT_LEVELS.to_vec());
    let budgets = args
        .gpu_budget
        .clone()
        .unwrap_or_else(|| DEFAULT_BUDGETS.to_vec());
    let size = args
        .sizes
        .as_ref()
        .and_then(|s| s.first().copied())
        .unwrap_or((640, 480));
    let frames = args.frames.unwrap_or(3);
    let camera = Camera::new(DVec3::new(0.0, 0.3, 2.6), DVec3::ZERO);
    let pipeline = bundled_pipeline("ssbvb.ron")?;
    let ctx = crate::adapter_cmd::headless_context(&[&pipeline])?;
    let log = !args.json;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut fly = None;
    for &level in &levels {
        let (asset, outcome) = super::bundled_bunny(level)?;
        let source = [crate::budget::PageSourceRef::of(&outcome, level)];
        let reference = reference_at(&asset, level, &camera, size);
        let mut base_ms = None;
        for budget in std::iter::once(None).chain(budgets.iter().map(|&b| Some(b))) {
            let mut notes = Vec::new();
            let options = match budget {
                Some(b) => Some(crate::budget::options(b, &source, usize::MAX, &mut notes)?),
                None => None,
            };
            let what = format!(
                "level {level}, {}",
                budget.map_or("unbudgeted".into(), |b| format!("{b} MiB"))
            );
            let m = match measure(
                &ctx,
                &asset,
                level,
                size,
                &camera,
                options.as_ref(),
                frames,
                &reference,
            ) {
                Ok(m) => m,
                Err(e) if does_not_fit(&e) => {
                    if log {
                        eprintln!("skipped {what}: {e:#}");
                    }
                    skipped.push(format!("{what}: {e:#}"));
                    continue;
                }
                Err(e) => return Err(e.context(what)),
            };
            let ms = median(&m.times);
            if budget.is_none() {
                base_ms = Some(ms);
            }
            let st = m.stats.as_ref();
            let row = MemoryRow {
                level,
                budget_mib: budget,
                full_mib: mib(m.full),
                fixed_mib: st.map(|s| mib(s.fixed_bytes)),
                resident_mib: st.map_or(mib(m.full), |s| mib(s.bytes_resident)),
                frames_to_converge: m.frames,
                converged: m.converged,
                pages_total: st.map(|s| s.pages_total),
                pages_resident: st.map(|s| s.pages_resident),
                pages_streamed: st.map(|s| s.pages_streamed),
                pages_streamed_per_frame: st.map(|s| s.pages_streamed as f64 / m.frames as f64),
                pages_evicted: st.map(|s| s.pages_evicted),
                over_budget: st.map(|s| s.over_budget),
                level_cap: st.and_then(|s| s.level_cap),
                frame_ms_median: ms,
                frame_ms_ratio: base_ms.filter(|_| budget.is_some()).map(|b| ms / b),
                coverage_iou: m.iou,
            };
            if log {
                eprintln!(
                    "{what}: {:.1} MiB resident, {} frames to converge{}, {:.1} ms, IoU {:.4}",
                    row.resident_mib,
                    row.frames_to_converge,
                    if row.converged {
                        ""
                    } else {
                        " (not converged)"
                    },
                    ms,
                    row.coverage_iou
                );
            }
            rows.push(row);
        }
        if level == FLY.0 {
            let mut notes = Vec::new();
            let options = crate::budget::options(FLY.1, &source, FLY_PAGES_PER_FRAME, &mut notes)?;
            match fly_through(&ctx, &asset, level, size, &options) {
                Ok(f) => fly = Some(f),
                Err(e) if does_not_fit(&e) => skipped.push(format!("fly-through: {e:#}")),
                Err(e) => return Err(e.context("fly-through")),
            }
        }
    }
    let report = MemoryReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        width: size.0,
        height: size.1,
        camera,
        rows,
        skipped,
        fly_through: fly,
    };
    write(&args.out, &report)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", markdown(&report));
        println!("wrote {}/memory.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// The camera of fly-through frame `i` of `n`: one turn round the bunny, closing in from
/// 2.6 to 1.0 units and rising and falling.
fn fly_camera(i: usize, n: usize) -> Camera {
    let f = i as f64 / n as f64;
    let a = f * std::f64::consts::TAU;
    let r = 2.6 - 1.6 * f;
    Camera::new(
        DVec3::new(r * a.sin(), 0.3 + 0.4 * (2.0 * a).sin(), r * a.cos()),
        DVec3::ZERO,
    )
}

/// Renders the fly-through, streaming without waiting (as the viewer does), each frame
/// timed with its streaming work and waited for.
fn fly_through(
    ctx: &GpuContext,
    asset: &Arc<VoxelAsset>,
    level: u32,
    size: (u32, u32),
    options: &StreamingOptions,
) -> Result<FlyThrough> {
    let (_, _, n) = FLY;
    let mut s = GpuScene::streamed(ctx, scene(asset, level), options)?;
    let mut r = Renderer::new(ctx, &s, bundled_pipeline("ssbvb.ron")?, size)?;
    // The first view converges first (a start-up, not a stall).
    crate::budget::converge(ctx, &mut r, &mut s, &fly_camera(0, n), MAX_FRAMES)?;
    let start = s.streaming_stats().map_or(0, |st| st.pages_streamed);
    let (mut times, mut per_frame, mut resident) = (Vec::new(), Vec::new(), 0u64);
    let mut last = start;
    for i in 0..n {
        let t0 = Instant::now();
        r.render(ctx, &mut s, &fly_camera(i, n), Profiling::Off)?;
        ctx.wait_idle()?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        let st = s.streaming_stats().cloned().unwrap_or_default();
        per_frame.push(st.pages_streamed - last);
        last = st.pages_streamed;
        resident = resident.max(st.bytes_resident);
    }
    let med = median(&times);
    let worst = times.iter().copied().fold(0.0, f64::max);
    Ok(FlyThrough {
        level,
        budget_mib: options.budget_bytes >> 20,
        width: size.0,
        height: size.1,
        frames: n,
        frame_ms_median: med,
        frame_ms_worst: worst,
        worst_over_median: worst / med,
        pages_streamed_per_frame_mean: per_frame.iter().sum::<u64>() as f64 / n as f64,
        pages_streamed_per_frame_max: per_frame.iter().copied().max().unwrap_or(0),
        resident_mib_max: mib(resident),
    })
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or("-".into(), |v| v.to_string())
}

fn markdown(r: &MemoryReport) -> String {
    let mut s = format!(
        "Adapter: {}. Bunny, {}x{}, camera {:?}.\n\n| level | budget MiB | full MiB | fixed MiB | resident MiB | frames to converge | pages streamed | per frame | evicted | drawn at | frame ms | × unbudgeted | IoU |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        r.adapter, r.width, r.height, r.camera.position
    );
    for w in &r.rows {
        s.push_str(&format!(
            "| {} | {} | {:.1} | {} | {:.1} | {}{} | {} | {} | {} | {} | {:.1} | {} | {:.4} |\n",
            w.level,
            opt(w.budget_mib),
            w.full_mib,
            opt(w.fixed_mib.map(|v| format!("{v:.1}"))),
            w.resident_mib,
            w.frames_to_converge,
            if w.converged { "" } else { " (not)" },
            opt(w.pages_streamed),
            opt(w.pages_streamed_per_frame.map(|v| format!("{v:.0}"))),
            opt(w.pages_evicted),
            w.level_cap.unwrap_or(w.level),
            w.frame_ms_median,
            opt(w.frame_ms_ratio.map(|v| format!("{v:.2}"))),
            w.coverage_iou
        ));
    }
    if let Some(f) = &r.fly_through {
        s.push_str(&format!(
            "\nFly-through: level {}, {} MiB, {} frames at {}x{}: median {:.1} ms, worst {:.1} ms ({:.2}× the median); pages streamed per frame mean {:.1}, max {}; resident at most {:.1} MiB.\n",
            f.level, f.budget_mib, f.frames, f.width, f.height, f.frame_ms_median, f.frame_ms_worst,
            f.worst_over_median, f.pages_streamed_per_frame_mean, f.pages_streamed_per_frame_max,
            f.resident_mib_max
        ));
    }
    for k in &r.skipped {
        s.push_str(&format!("\nskipped: {k}"));
    }
    s.push('\n');
    s
}

fn csv(r: &MemoryReport) -> String {
    let mut s = String::from(
        "level,budget_mib,full_mib,fixed_mib,resident_mib,frames_to_converge,converged,pages_total,pages_resident,pages_streamed,pages_streamed_per_frame,pages_evicted,over_budget,level_cap,frame_ms_median,frame_ms_ratio,coverage_iou\n",
    );
    for w in &r.rows {
        s.push_str(&format!(
            "{},{},{:.3},{},{:.3},{},{},{},{},{},{},{},{},{},{:.3},{},{:.6}\n",
            w.level,
            opt(w.budget_mib),
            w.full_mib,
            opt(w.fixed_mib.map(|v| format!("{v:.3}"))),
            w.resident_mib,
            w.frames_to_converge,
            w.converged,
            opt(w.pages_total),
            opt(w.pages_resident),
            opt(w.pages_streamed),
            opt(w.pages_streamed_per_frame.map(|v| format!("{v:.2}"))),
            opt(w.pages_evicted),
            opt(w.over_budget),
            opt(w.level_cap),
            w.frame_ms_median,
            opt(w.frame_ms_ratio.map(|v| format!("{v:.3}"))),
            w.coverage_iou
        ));
    }
    s
}

fn write(dir: &Path, r: &MemoryReport) -> Result<()> {
    super::report::write_files(
        dir,
        vec![
            ("memory.csv", csv(r)),
            ("memory.json", serde_json::to_string_pretty(r)?),
            ("memory.md", markdown(r)),
        ],
    )
}
