//! `ssbvb bench`: technique × model × level × resolution on one adapter, with warm-up
//! frames, timed frames (median and spread), per-pass times, the SSBVB fill count, GPU
//! memory, and accuracy against the CPU reference. Writes CSV, JSON and a Markdown table,
//! PNG plots, and with `--sweep` (or `--preset full`) speed–accuracy knob sweeps.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use glam::{DAffine3, DVec3};
use serde::Serialize;
use ssbvb_passes::LodPolicy;
use ssbvb_voxel::camera::Camera;

use crate::bench_plot::{PlotInfo, Series};
use crate::bench_sweep::{SweepConfig, SweepRow};
use crate::render_cmd::assets_dir;

/// Benchmark presets.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Preset {
    /// Small: CI-sized (bunny levels 5-6, 160x120, few frames).
    Quick,
    /// The measurement run: bunny levels 7-9 at 640x480 and 1280x720.
    Full,
}

/// Arguments of `ssbvb bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Which matrix to run.
    #[arg(long, value_enum, default_value = "quick")]
    pub preset: Preset,
    /// Output folder for bench.csv, bench.json and bench.md.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
    /// Print the results as one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// Also sweep the knobs of the default SSBVB pipeline one at a time (ray-march
    /// max_steps, billboard size_scale, smoothing max_i, LOD bias) and write sweeps.csv
    /// and trade_<knob>.png; always on with `--preset full`.
    #[arg(long)]
    pub sweep: bool,
}

#[derive(Debug, Clone, Copy)]
struct Technique {
    name: &'static str,
    pipeline: &'static str,
    /// Highest level the technique supports.
    max_level: u32,
}

const TECHNIQUES: &[Technique] = &[
    Technique {
        name: "ssbvb-flat",
        pipeline: "ssbvb.ron",
        max_level: 16,
    },
    Technique {
        name: "ssbvb-raybox",
        pipeline: "ssbvb.ron#RayBox",
        max_level: 16,
    },
    Technique {
        name: "dense-dda",
        pipeline: "dense_dda.ron",
        max_level: 8,
    },
    Technique {
        name: "octree",
        pipeline: "octree_ray_cast.ron",
        max_level: 16,
    },
];

/// One row of results.
#[derive(Debug, Serialize)]
struct Row {
    technique: &'static str,
    model: String,
    level: u32,
    width: u32,
    height: u32,
    frames: usize,
    frame_ms_median: f64,
    frame_ms_min: f64,
    frame_ms_max: f64,
    passes: Vec<ssbvb_passes::PassTiming>,
    fill_count: Option<u32>,
    voxels: usize,
    gpu_memory_bytes: u64,
    coverage_iou: f64,
    /// `None` for techniques that keep no voxel ids (no SSBVB).
    same_voxel_rate: Option<f64>,
    depth_error_voxels_median: f64,
    normal_error_deg_median: f64,
}

#[derive(Debug, Serialize)]
struct Report {
    adapter: String,
    adapter_is_software: bool,
    timing: &'static str,
    preset: String,
    camera: Camera,
    rows: Vec<Row>,
    skipped: Vec<String>,
    /// Knob sweeps (empty without `--sweep`).
    sweeps: Vec<SweepRow>,
    /// The PNG plots written next to the report.
    plots: Vec<PlotInfo>,
}

pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs `ssbvb bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    let (levels, sizes, warmup, frames): (&[u32], &[(u32, u32)], usize, usize) = match args.preset {
        Preset::Quick => (&[5, 6], &[(160, 120)], 1, 3),
        Preset::Full => (&[7, 8, 9], &[(640, 480), (1280, 720)], 3, 10),
    };
    let model = assets_dir().join("models/bunny.obj");
    let camera = Camera::new(DVec3::new(0.0, 0.3, 2.6), DVec3::ZERO);
    let ctx = ssbvb_gpu::GpuContext::new_headless(&Default::default())?;
    let software = ctx.report().is_software;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for &level in levels {
        let (asset, _) = ssbvb_voxel::cache::load_or_prepare(
            &model,
            level,
            None,
            &ssbvb_voxel::progress::NoProgress,
        )
        .with_context(|| format!("preparing {}", model.display()))?;
        let asset = Arc::new(asset);
        let voxels = asset.lods[level as usize].point_cloud.voxels.len();
        for &size in sizes {
            let reference = {
                let inst = [ssbvb_voxel::reference::Instance {
                    lod: &asset.lods[level as usize],
                    object_to_world: DAffine3::IDENTITY,
                }];
                ssbvb_voxel::reference::render(&inst, &camera, size.0, size.1, &Default::default())
            };
            for t in TECHNIQUES {
                if level > t.max_level {
                    skipped.push(format!(
                        "{} at level {level}: supports levels up to {}",
                        t.name, t.max_level
                    ));
                    continue;
                }
                let row = run_one(
                    &ctx, t, &asset, level, size, &camera, &reference, warmup, frames, voxels,
                )
                .with_context(|| format!("{} level {level} {}x{}", t.name, size.0, size.1))?;
                if !args.json {
                    eprintln!(
                        "{:<13} L{level} {}x{}: {:.2} ms median, IoU {:.4}",
                        t.name, size.0, size.1, row.frame_ms_median, row.coverage_iou
                    );
                }
                rows.push(row);
            }
        }
    }
    let sweeps = if args.sweep || matches!(args.preset, Preset::Full) {
        let cfg = sweep_config(args.preset);
        let (asset, _) = ssbvb_voxel::cache::load_or_prepare(
            &model,
            cfg.level,
            None,
            &ssbvb_voxel::progress::NoProgress,
        )
        .with_context(|| format!("preparing {}", model.display()))?;
        crate::bench_sweep::run_sweeps(&ctx, &Arc::new(asset), &camera, &cfg, !args.json)?
    } else {
        Vec::new()
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let plots = write_plots(&args.out, &rows, &sweeps)?;
    let report = Report {
        adapter: ctx.report().to_string(),
        adapter_is_software: software,
        timing: if software {
            "frame ms = wall time of submit + wait per frame; per-pass = wall time of each pass submitted alone (software adapter: timestamps unreliable)"
        } else {
            "frame ms = wall time of submit + wait per frame; per-pass = GPU timestamps"
        },
        preset: format!("{:?}", args.preset),
        camera,
        rows,
        skipped,
        sweeps,
        plots,
    };
    write_outputs(&args.out, &report)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", markdown(&report));
        println!("wrote {}/bench.{{csv,json,md}}", args.out.display());
        if !report.sweeps.is_empty() {
            println!("wrote {}/sweeps.csv", args.out.display());
        }
        for p in &report.plots {
            println!("wrote {}/{}", args.out.display(), p.file);
        }
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn run_one(
    ctx: &ssbvb_gpu::GpuContext,
    t: &Technique,
    asset: &Arc<ssbvb_voxel::asset::VoxelAsset>,
    level: u32,
    size: (u32, u32),
    camera: &Camera,
    reference: &ssbvb_voxel::reference::ReferenceImage,
    warmup: usize,
    frames: usize,
    voxels: usize,
) -> Result<Row> {
    let (file, mode) = t.pipeline.split_once('#').unwrap_or((t.pipeline, ""));
    let (mut src, label) = crate::bench_sweep::pipeline_source(file)?;
    if !mode.is_empty() {
        src = src.replace("Billboards(mode: Flat", &format!("Billboards(mode: {mode}"));
    }
    let setup = crate::bench_sweep::Setup {
        ctx,
        asset,
        lod: LodPolicy::Fixed(level),
        level,
        size,
        camera,
        reference,
        warmup,
        frames,
    };
    let m = crate::bench_sweep::measure(&setup, &src, &label, false)?;
    let (fill, acc, mut times) = (m.fill, m.acc, m.times);
    let (min, max) = times
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    Ok(Row {
        technique: t.name,
        model: "bunny.obj".into(),
        level,
        width: size.0,
        height: size.1,
        frames: times.len(),
        frame_ms_median: median(&mut times),
        frame_ms_min: min,
        frame_ms_max: max,
        passes: m.passes,
        fill_count: fill,
        voxels,
        gpu_memory_bytes: m.gpu_memory,
        coverage_iou: acc.coverage_iou,
        same_voxel_rate: fill.map(|_| acc.same_voxel_rate),
        depth_error_voxels_median: acc.depth_error_voxels.median,
        normal_error_deg_median: acc.normal_error_deg.median,
    })
}

fn markdown(r: &Report) -> String {
    let mut s = format!("adapter: {}\ntiming: {}\n\n", r.adapter, r.timing);
    s.push_str("| technique | level | size | frame ms (median [min, max]) | fill | voxels | GPU MiB | IoU | same voxel | depth err (vox) |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for x in &r.rows {
        s.push_str(&format!(
            "| {} | {} | {}x{} | {:.2} [{:.2}, {:.2}] | {} | {} | {:.1} | {:.4} | {} | {:.3} |\n",
            x.technique,
            x.level,
            x.width,
            x.height,
            x.frame_ms_median,
            x.frame_ms_min,
            x.frame_ms_max,
            x.fill_count.map_or("-".into(), |f| f.to_string()),
            x.voxels,
            x.gpu_memory_bytes as f64 / (1 << 20) as f64,
            x.coverage_iou,
            x.same_voxel_rate.map_or("-".into(), |v| format!("{v:.4}")),
            x.depth_error_voxels_median
        ));
    }
    for k in &r.skipped {
        s.push_str(&format!("\nskipped: {k}"));
    }
    s.push('\n');
    s.push_str(&crate::bench_sweep::markdown(&r.sweeps));
    if !r.plots.is_empty() {
        s.push_str(&crate::bench_plot::markdown(&r.plots));
    }
    s
}

/// Sweep sizes of a preset.
fn sweep_config(preset: Preset) -> SweepConfig {
    match preset {
        Preset::Quick => SweepConfig {
            size: (160, 120),
            level: 6,
            warmup: 1,
            frames: 2,
            max_steps: &[8, 32, 1024],
            size_scale: &[0.9, 1.0, 1.3],
            max_i: &[0.0, 1.0, 3.0],
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
            lod_bias: &[-3, -2, -1, 0],
        },
    }
}

/// time_vs_level.png, time_vs_resolution.png (main matrix) and trade_<knob>.png (sweeps).
fn write_plots(dir: &Path, rows: &[Row], sweeps: &[SweepRow]) -> Result<Vec<PlotInfo>> {
    use std::collections::BTreeMap;
    let mut plots = Vec::new();
    type Points = Vec<(f64, f64)>;
    let mut by_size: BTreeMap<(&str, u32, u32), Points> = BTreeMap::new();
    let mut by_level: BTreeMap<(&str, u32), Points> = BTreeMap::new();
    for r in rows {
        by_size
            .entry((r.technique, r.width, r.height))
            .or_default()
            .push((r.level as f64, r.frame_ms_median));
        by_level
            .entry((r.technique, r.level))
            .or_default()
            .push(((r.width * r.height) as f64 / 1e6, r.frame_ms_median));
    }
    let sorted = |mut p: Vec<(f64, f64)>| {
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p
    };
    if !rows.is_empty() {
        let series: Vec<Series> = by_size
            .into_iter()
            .map(|((t, w, h), p)| Series {
                name: format!("{t} {w}x{h}"),
                points: sorted(p),
            })
            .collect();
        plots.push(crate::bench_plot::plot(
            dir,
            "time_vs_level.png",
            "Frame time vs level (per technique and resolution)",
            ("level", "frame ms (median)"),
            &series,
        )?);
        let series: Vec<Series> = by_level
            .into_iter()
            .map(|((t, l), p)| Series {
                name: format!("{t} level {l}"),
                points: sorted(p),
            })
            .collect();
        plots.push(crate::bench_plot::plot(
            dir,
            "time_vs_resolution.png",
            "Frame time vs resolution (per technique and level)",
            ("megapixels", "frame ms (median)"),
            &series,
        )?);
    }
    let mut knobs: Vec<&str> = sweeps.iter().map(|r| r.knob).collect();
    knobs.dedup();
    for knob in knobs {
        let pts: Vec<&SweepRow> = sweeps
            .iter()
            .filter(|r| r.knob == knob && r.psnr_pixels > 0)
            .collect();
        let values: Vec<String> = pts.iter().map(|r| r.value.to_string()).collect();
        // RMSE in 8-bit levels from the PSNR (0 where the images are identical).
        let points = pts
            .iter()
            .map(|r| {
                let rmse = r.psnr_db.map_or(0.0, |p| 255.0 * 10f64.powf(-p / 20.0));
                (r.frame_ms_median, rmse)
            })
            .collect();
        plots.push(crate::bench_plot::plot(
            dir,
            &format!("trade_{knob}.png"),
            &format!("Shaded error vs frame time, {knob} swept"),
            (
                "frame ms (median)",
                "composite RMSE vs reference (8-bit levels, pixels both cover)",
            ),
            &[Series {
                name: format!("{knob} = {} (in this order)", values.join(", ")),
                points,
            }],
        )?);
    }
    Ok(plots)
}

/// Writes bench.csv, bench.json and bench.md atomically into `dir`.
fn write_outputs(dir: &Path, r: &Report) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut csv = String::from(
        "technique,model,level,width,height,frames,frame_ms_median,frame_ms_min,frame_ms_max,fill_count,voxels,gpu_memory_bytes,coverage_iou,same_voxel_rate,depth_error_voxels_median,normal_error_deg_median\n",
    );
    for x in &r.rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{:.4},{:.4},{:.4},{},{},{},{:.6},{},{:.6},{:.4}\n",
            x.technique,
            x.model,
            x.level,
            x.width,
            x.height,
            x.frames,
            x.frame_ms_median,
            x.frame_ms_min,
            x.frame_ms_max,
            x.fill_count.map_or(String::new(), |f| f.to_string()),
            x.voxels,
            x.gpu_memory_bytes,
            x.coverage_iou,
            x.same_voxel_rate
                .map_or(String::new(), |v| format!("{v:.6}")),
            x.depth_error_voxels_median,
            x.normal_error_deg_median
        ));
    }
    let mut files = vec![
        ("bench.csv", csv),
        ("bench.json", serde_json::to_string_pretty(r)?),
        ("bench.md", markdown(r)),
    ];
    if !r.sweeps.is_empty() {
        files.push(("sweeps.csv", crate::bench_sweep::csv(&r.sweeps)));
    }
    for (name, body) in files {
        let path = dir.join(name);
        let tmp = dir.join(format!(".{name}.tmp"));
        std::fs::write(&tmp, body).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
