//! `ssbvb bench`: technique × model × level × resolution on one adapter, with warm-up
//! frames, timed frames (median and spread), per-pass times, the SSBVB fill count, GPU
//! memory, and accuracy against the CPU reference. Writes CSV, JSON and a Markdown table.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use glam::{DAffine3, DVec3};
use serde::Serialize;
use ssbvb_passes::{GpuScene, LodPolicy, Profiling, Renderer, Scene, VoxelObject};
use ssbvb_voxel::camera::Camera;

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
}

fn median(v: &mut [f64]) -> f64 {
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
    };
    write_outputs(&args.out, &report)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", markdown(&report));
        println!("wrote {}/bench.{{csv,json,md}}", args.out.display());
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
    let path = assets_dir().join("pipelines").join(file);
    let mut src =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    if !mode.is_empty() {
        src = src.replace("Billboards(mode: Flat", &format!("Billboards(mode: {mode}"));
    }
    let pipeline = ssbvb_graph::resolve_str(&src, &path.display().to_string())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let scene = Scene {
        objects: vec![VoxelObject {
            asset: asset.clone(),
            instances: vec![DAffine3::IDENTITY],
            lod: LodPolicy::Fixed(level),
        }],
        ..Default::default()
    };
    let mut gpu_scene = GpuScene::new(ctx, scene)?;
    let mut renderer = Renderer::new(ctx, &gpu_scene, pipeline, size)?;
    for _ in 0..warmup {
        renderer.render(ctx, &mut gpu_scene, camera, Profiling::Off)?;
    }
    ctx.wait_idle()?;
    let mut times = Vec::new();
    for _ in 0..frames.max(1) {
        let t0 = Instant::now();
        renderer.render(ctx, &mut gpu_scene, camera, Profiling::Off)?;
        ctx.wait_idle()?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let profiling = if ctx.report().is_software {
        Profiling::TimestampsAndWall
    } else {
        Profiling::Timestamps
    };
    let stats = renderer.render(ctx, &mut gpu_scene, camera, profiling)?;
    let fill = renderer.fill_count(ctx)?;
    let hits = ssbvb_passes::measure::gbuffer_hits(ctx, &renderer)?;
    let acc = ssbvb_voxel::accuracy::compare(reference, &hits, &[2.0 / (1u64 << level) as f64])
        .map_err(|e| anyhow::anyhow!("{e}"))?;
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
        passes: stats.passes,
        fill_count: fill,
        voxels,
        gpu_memory_bytes: gpu_scene.total_memory(),
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
    s
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
    for (name, body) in [
        ("bench.csv", csv),
        ("bench.json", serde_json::to_string_pretty(r)?),
        ("bench.md", markdown(r)),
    ] {
        let path = dir.join(name);
        let tmp = dir.join(format!(".{name}.tmp"));
        std::fs::write(&tmp, body).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, &path).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
