//! `ssbvb bench --preset memory`: pages by demand under a GPU budget. The bunny at each
//! level (default 7-13) is rendered unbudgeted (when the device holds it) and under each
//! budget (`--gpu-budget`, default 32, 128 and 512 MiB): frames to converge, pages
//! streamed, resident MiB, the frame time once converged (and its ratio to the
//! unbudgeted frame of the same run) and the coverage IoU against the CPU reference at
//! that level. Then a fly-through (an orbit that closes in on the bunny, level 11 under
//! 64 MiB by default) streams without waiting, at most [`FLY_PAGES_PER_FRAME`] pages per
//! frame, and reports the worst frame against the median: streaming must not stall.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use glam::DVec3;
use serde::Serialize;
use ssbvb_gpu::scene::{LodPolicy, StreamingOptions};
use ssbvb_gpu::{GpuContext, ResourceError};
use ssbvb_passes::{PassError, Profiling};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::ReferenceImage;

use crate::args::BenchArgs;
use crate::harness::{
    bench_camera, bundled_bunny, bundled_pipeline, median, one_object, reference_at, timed_frames,
};
use crate::table::{Column, Fmt, Table, write_report};

const DEFAULT_LEVELS: [u32; 7] = [7, 8, 9, 10, 11, 12, 13];
const DEFAULT_BUDGETS: [u64; 3] = [32, 128, 512];
/// Most frames rendered to converge.
const MAX_FRAMES: usize = 64;
/// Fly-through: level, budget (MiB), frames.
const FLY: (u32, u64, usize) = (11, 64, 72);
/// Pages streamed before one fly-through frame at most (as the viewer).
pub const FLY_PAGES_PER_FRAME: usize = 512;

/// One level under one budget (`None`: unbudgeted).
#[derive(Debug)]
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

#[derive(Serialize)]
struct MemoryReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    width: u32,
    height: u32,
    camera: Camera,
    rows: Table<'a, MemoryRow>,
    skipped: Vec<String>,
    fly_through: Option<FlyThrough>,
}

/// What one configuration gave.
struct Measured {
    frames: usize,
    converged: bool,
    times: Vec<f64>,
    iou: f64,
    stats: Option<ssbvb_gpu::scene::StreamingStats>,
    full: u64,
}

fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

/// The median of `v` (see `harness::median`), `v` left as it is.
fn median_of(v: &[f64]) -> f64 {
    median(&mut v.to_vec())
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
    reference: &ReferenceImage,
) -> Result<Measured> {
    let mut s = match options {
        Some(o) => ssbvb_engine::upload::upload_scene(
            ctx,
            one_object(asset, LodPolicy::Fixed(level)),
            ssbvb_engine::upload::Residency::Streamed(o),
        )?,
        None => ssbvb_engine::upload::upload_scene(
            ctx,
            one_object(asset, LodPolicy::Fixed(level)),
            ssbvb_engine::upload::Residency::Whole,
        )?,
    };
    let full = s.total_memory();
    let mut r =
        ssbvb_engine::upload::renderer(ctx, &s, bundled_pipeline("ssbvb_unique.ron")?, size)?;
    let (n, converged) = ssbvb_engine::budget::converge(ctx, &mut r, &mut s, camera, MAX_FRAMES)?;
    let times = timed_frames(ctx, &mut r, &mut s, camera, frames)?;
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
        let resource = |e: &ResourceError| {
            matches!(
                e,
                ResourceError::TooLarge(_) | ResourceError::BudgetTooSmall { .. }
            )
        };
        match c.downcast_ref::<PassError>() {
            Some(PassError::TooLarge(_)) => true,
            Some(PassError::Resource(e)) => resource(e),
            _ => c.downcast_ref::<ResourceError>().is_some_and(resource),
        }
    })
}

/// What one run of the preset measures with: the levels' common settings.
struct Config<'a> {
    ctx: &'a GpuContext,
    budgets: &'a [u64],
    size: (u32, u32),
    frames: usize,
    camera: &'a Camera,
    log: bool,
}

/// What the levels gave.
#[derive(Default)]
struct Outcome {
    rows: Vec<MemoryRow>,
    skipped: Vec<String>,
    fly: Option<FlyThrough>,
}

/// Runs the memory preset.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let levels = args
        .levels
        .clone()
        .unwrap_or_else(|| DEFAULT_LEVELS.to_vec());
    let budgets = args
        .gpu_budget
        .clone()
        .unwrap_or_else(|| DEFAULT_BUDGETS.to_vec());
    let size = args.first_size((640, 480));
    let camera = bench_camera();
    let pipeline = bundled_pipeline("ssbvb_unique.ron")?;
    let ctx = ssbvb_engine::choice::headless_context(&[&pipeline])?;
    let cfg = Config {
        ctx: &ctx,
        budgets: &budgets,
        size,
        frames: args.frames.unwrap_or(3),
        camera: &camera,
        log: !args.json,
    };
    let mut out = Outcome::default();
    for &level in &levels {
        measure_level(&cfg, level, &mut out)?;
    }
    let report = MemoryReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        width: size.0,
        height: size.1,
        camera,
        rows: table(&out.rows),
        skipped: out.skipped,
        fly_through: out.fly,
    };
    write_report(
        &args.out,
        "memory",
        report.rows.csv(),
        &report,
        markdown(&report),
    )?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", markdown(&report));
        println!("wrote {}/memory.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// Measures `level` unbudgeted and under each budget, and the fly-through at its level.
fn measure_level(cfg: &Config, level: u32, out: &mut Outcome) -> Result<()> {
    let (ctx, size) = (cfg.ctx, cfg.size);
    let (asset, outcome) = bundled_bunny(level)?;
    let source = [ssbvb_engine::budget::PageSourceRef::of(&outcome, level)];
    let reference = reference_at(&asset, level, cfg.camera, size);
    let mut base_ms = None;
    for budget in std::iter::once(None).chain(cfg.budgets.iter().map(|&b| Some(b))) {
        let mut notes = Vec::new();
        let options = match budget {
            Some(b) => Some(ssbvb_engine::budget::options(
                b,
                &source,
                usize::MAX,
                &mut notes,
            )?),
            None => None,
        };
        let what = format!(
            "level {level}, {}",
            budget.map_or("unbudgeted".into(), |b| format!("{b} MiB"))
        );
        let m = match measure(
            ctx,
            &asset,
            level,
            size,
            cfg.camera,
            options.as_ref(),
            cfg.frames,
            &reference,
        ) {
            Ok(m) => m,
            Err(e) if does_not_fit(&e) => {
                if cfg.log {
                    eprintln!("skipped {what}: {e:#}");
                }
                out.skipped.push(format!("{what}: {e:#}"));
                continue;
            }
            Err(e) => return Err(e.context(what)),
        };
        let ms = median_of(&m.times);
        if budget.is_none() {
            base_ms = Some(ms);
        }
        let row = memory_row(level, budget, &m, ms, base_ms);
        if cfg.log {
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
        out.rows.push(row);
    }
    if level == FLY.0 {
        let mut notes = Vec::new();
        let options =
            ssbvb_engine::budget::options(FLY.1, &source, FLY_PAGES_PER_FRAME, &mut notes)?;
        match fly_through(ctx, &asset, level, size, &options) {
            Ok(f) => out.fly = Some(f),
            Err(e) if does_not_fit(&e) => out.skipped.push(format!("fly-through: {e:#}")),
            Err(e) => return Err(e.context("fly-through")),
        }
    }
    Ok(())
}

/// The row of `level` under `budget` that gave `m` (median frame `ms`; `base_ms`: the
/// unbudgeted median of the level, if measured).
fn memory_row(
    level: u32,
    budget: Option<u64>,
    m: &Measured,
    ms: f64,
    base_ms: Option<f64>,
) -> MemoryRow {
    let st = m.stats.as_ref();
    MemoryRow {
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
    }
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
    let mut s = ssbvb_engine::upload::upload_scene(
        ctx,
        one_object(asset, LodPolicy::Fixed(level)),
        ssbvb_engine::upload::Residency::Streamed(options),
    )?;
    let mut r =
        ssbvb_engine::upload::renderer(ctx, &s, bundled_pipeline("ssbvb_unique.ron")?, size)?;
    // The first view converges first (a start-up, not a stall).
    ssbvb_engine::budget::converge(ctx, &mut r, &mut s, &fly_camera(0, n), MAX_FRAMES)?;
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
    let med = median_of(&times);
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

/// The rows of `memory.csv`, `memory.md` and `memory.json`.
fn table(rows: &[MemoryRow]) -> Table<'_, MemoryRow> {
    // Missing cells are `-` in the CSV too.
    let dash = |f: Fmt| f.or("-");
    Table::new(
        rows,
        vec![
            Column::new("level", |w: &MemoryRow| w.level)
                .csv(Fmt::PLAIN)
                .md("level", Fmt::PLAIN),
            Column::new("budget_mib", |w: &MemoryRow| w.budget_mib)
                .csv(dash(Fmt::PLAIN))
                .md("budget MiB", dash(Fmt::PLAIN)),
            Column::new("full_mib", |w: &MemoryRow| w.full_mib)
                .csv(Fmt::fixed(3))
                .md("full MiB", Fmt::fixed(1)),
            Column::new("fixed_mib", |w: &MemoryRow| w.fixed_mib)
                .csv(dash(Fmt::fixed(3)))
                .md("fixed MiB", dash(Fmt::fixed(1))),
            Column::new("resident_mib", |w: &MemoryRow| w.resident_mib)
                .csv(Fmt::fixed(3))
                .md("resident MiB", Fmt::fixed(1)),
            Column::new("frames_to_converge", |w: &MemoryRow| w.frames_to_converge).csv(Fmt::PLAIN),
            Column::md_only("frames to converge", |w: &MemoryRow| {
                format!(
                    "{}{}",
                    w.frames_to_converge,
                    if w.converged { "" } else { " (not)" }
                )
            }),
            Column::new("converged", |w: &MemoryRow| w.converged).csv(Fmt::PLAIN),
            Column::new("pages_total", |w: &MemoryRow| w.pages_total).csv(dash(Fmt::PLAIN)),
            Column::new("pages_resident", |w: &MemoryRow| w.pages_resident).csv(dash(Fmt::PLAIN)),
            Column::new("pages_streamed", |w: &MemoryRow| w.pages_streamed)
                .csv(dash(Fmt::PLAIN))
                .md("pages streamed", dash(Fmt::PLAIN)),
            Column::new("pages_streamed_per_frame", |w: &MemoryRow| {
                w.pages_streamed_per_frame
            })
            .csv(dash(Fmt::fixed(2)))
            .md("per frame", dash(Fmt::fixed(0))),
            Column::new("pages_evicted", |w: &MemoryRow| w.pages_evicted)
                .csv(dash(Fmt::PLAIN))
                .md("evicted", dash(Fmt::PLAIN)),
            Column::new("over_budget", |w: &MemoryRow| w.over_budget).csv(dash(Fmt::PLAIN)),
            Column::new("level_cap", |w: &MemoryRow| w.level_cap).csv(dash(Fmt::PLAIN)),
            Column::md_only("drawn at", |w: &MemoryRow| w.level_cap.unwrap_or(w.level)),
            Column::new("frame_ms_median", |w: &MemoryRow| w.frame_ms_median)
                .csv(Fmt::fixed(3))
                .md("frame ms", Fmt::fixed(1)),
            Column::new("frame_ms_ratio", |w: &MemoryRow| w.frame_ms_ratio)
                .csv(dash(Fmt::fixed(3)))
                .md("× unbudgeted", dash(Fmt::fixed(2))),
            Column::new("coverage_iou", |w: &MemoryRow| w.coverage_iou)
                .csv(Fmt::fixed(6))
                .md("IoU", Fmt::fixed(4)),
        ],
    )
}

/// `memory.md`: the table, the fly-through and the configurations skipped.
fn markdown(r: &MemoryReport) -> String {
    let mut s = format!(
        "Adapter: {}. Bunny, {}x{}, camera {:?}.\n\n",
        r.adapter, r.width, r.height, r.camera.position
    );
    s.push_str(&r.rows.markdown());
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
