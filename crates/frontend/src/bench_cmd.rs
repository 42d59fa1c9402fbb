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
use ssbvb_graph::{BillboardMode, PassKind};
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
    /// The measurement run: bunny levels 7-12 at 640x480 and 1280x720, plus knob sweeps.
    Full,
    /// The seed-002 study: a filled ball, 50 % random voxels and the bunny mesh, model
    /// resolutions 8-512 (levels 3-9), targets 640x480-2560x1440, and the fastest technique
    /// per cell (its Table 11).
    Study,
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
    /// and `trade_<knob>.png`; always on with `--preset full`.
    #[arg(long)]
    pub sweep: bool,
    /// Levels to run instead of the preset's (comma-separated, e.g. `3,4,5`).
    #[arg(long, value_delimiter = ',')]
    pub levels: Option<Vec<u32>>,
    /// Image sizes to run instead of the preset's (comma-separated, e.g.
    /// `640x480,1280x720`).
    #[arg(long, value_delimiter = ',', value_parser = crate::pipeline_cmd::parse_size)]
    pub sizes: Option<Vec<(u32, u32)>>,
    /// Techniques to run (comma-separated names; default: all).
    #[arg(long, value_delimiter = ',')]
    pub techniques: Option<Vec<String>>,
    /// Timed frames per cell instead of the preset's.
    #[arg(long)]
    pub frames: Option<usize>,
}

#[derive(Debug, Clone, Copy)]
struct Technique {
    name: &'static str,
    /// Bundled pipeline file.
    pipeline: &'static str,
    /// A parameter changed from the file's (returns whether it changed the kind).
    edit: Option<fn(&mut PassKind) -> bool>,
    /// Highest level the technique supports.
    max_level: u32,
}

const TECHNIQUES: &[Technique] = &[
    Technique {
        name: "ssbvb-flat",
        pipeline: "ssbvb.ron",
        edit: None,
        max_level: 16,
    },
    Technique {
        name: "ssbvb-raybox",
        pipeline: "ssbvb.ron",
        edit: Some(|k| match k {
            PassKind::Billboards(b) => {
                b.mode = BillboardMode::RayBox;
                true
            }
            _ => false,
        }),
        max_level: 16,
    },
    Technique {
        name: "ssbvb-unique",
        pipeline: "ssbvb.ron",
        edit: Some(|k| match k {
            PassKind::RayMarchFilter(f) => {
                f.unique_voxels = true;
                true
            }
            _ => false,
        }),
        max_level: 16,
    },
    Technique {
        name: "dense-dda",
        pipeline: "dense_dda.ron",
        edit: None,
        max_level: 8,
    },
    Technique {
        name: "octree",
        pipeline: "octree_ray_cast.ron",
        edit: None,
        max_level: 16,
    },
    Technique {
        name: "cube-raster",
        pipeline: "cube_raster.ron",
        edit: None,
        max_level: 16,
    },
    Technique {
        name: "cube-raster-array",
        pipeline: "cube_raster.ron",
        edit: Some(|k| match k {
            PassKind::CubeRaster(c) => {
                c.merge_full_nodes = false;
                true
            }
            _ => false,
        }),
        max_level: 16,
    },
];

/// Technique names, for `--techniques`.
fn technique_names() -> Vec<&'static str> {
    TECHNIQUES.iter().map(|t| t.name).collect()
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
    fn name(&self) -> String {
        match self {
            BenchModel::File(p) => p
                .file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into()),
            BenchModel::Procedural(n, _) => (*n).to_string(),
        }
    }

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
    models: Vec<BenchModel>,
    levels: Vec<u32>,
    sizes: Vec<(u32, u32)>,
    warmup: usize,
    frames: usize,
    camera: Camera,
}

fn matrix(args: &BenchArgs) -> Matrix {
    let bunny = BenchModel::File(assets_dir().join("models/bunny.obj"));
    let mut m = match args.preset {
        Preset::Quick => Matrix {
            models: vec![bunny],
            levels: vec![5, 6],
            sizes: vec![(160, 120)],
            warmup: 1,
            frames: 3,
            camera: Camera::new(DVec3::new(0.0, 0.3, 2.6), DVec3::ZERO),
        },
        Preset::Full => Matrix {
            models: vec![bunny],
            levels: vec![7, 8, 9, 10, 11, 12],
            sizes: vec![(640, 480), (1280, 720)],
            warmup: 3,
            frames: 10,
            camera: Camera::new(DVec3::new(0.0, 0.3, 2.6), DVec3::ZERO),
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
    m
}

/// One row of results.
#[derive(Debug, Serialize)]
struct Row {
    technique: &'static str,
    model: String,
    /// Occupied cells at this level.
    level: u32,
    width: u32,
    height: u32,
    frames: usize,
    frame_ms_median: f64,
    frame_ms_min: f64,
    frame_ms_max: f64,
    passes: Vec<ssbvb_passes::PassTiming>,
    fill_count: Option<u32>,
    /// Pixels the reference covers (what the fill count is compared with).
    covered_pixels: usize,
    voxels: usize,
    gpu_memory_bytes: u64,
    coverage_iou: f64,
    /// `None` for techniques that keep no per-pixel voxel ids (all but the per-pixel
    /// SSBVB).
    same_voxel_rate: Option<f64>,
    depth_error_voxels_median: f64,
    normal_error_deg_median: f64,
    /// PSNR (dB) of the composite over the pixels either covers (`None`: identical).
    psnr_db: Option<f64>,
    /// Mean SSIM of the composite (see `bench_sweep::Measured::ssim`).
    ssim: Option<f64>,
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
    /// Fastest technique per model, target size and level (the study's Table 11).
    fastest: Vec<Fastest>,
    /// The PNG plots written next to the report.
    plots: Vec<PlotInfo>,
}

pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The fastest technique of one (model, size, level) cell.
#[derive(Debug, Serialize)]
struct Fastest {
    model: String,
    width: u32,
    height: u32,
    level: u32,
    technique: &'static str,
    frame_ms_median: f64,
    /// The runner-up, and how much slower it was (ratio of medians).
    runner_up: Option<(&'static str, f64)>,
}

/// Runs `ssbvb bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    let m = matrix(args);
    let techniques: Vec<&Technique> = match &args.techniques {
        // The study's coarse models make cells span dozens of pixels: the per-pixel SSBVB
        // then draws each voxel once per pixel it covers (18.6 s a frame for the 8³ ball
        // at 640x480 on lavapipe), so the study runs the unique-voxel SSBVB; name the
        // others with --techniques to include them.
        None if matches!(args.preset, Preset::Study) => TECHNIQUES
            .iter()
            .filter(|t| !matches!(t.name, "ssbvb-flat" | "ssbvb-raybox"))
            .collect(),
        None => TECHNIQUES.iter().collect(),
        Some(names) => names
            .iter()
            .map(|n| {
                TECHNIQUES.iter().find(|t| t.name == n).with_context(|| {
                    format!(
                        "unknown technique `{n}`; known: {}",
                        technique_names().join(", ")
                    )
                })
            })
            .collect::<Result<_>>()?,
    };
    let camera = m.camera;
    let pipelines = techniques
        .iter()
        .map(|t| crate::bench_sweep::bundled_pipeline(t.pipeline))
        .collect::<Result<Vec<_>>>()?;
    let ctx = crate::adapter_cmd::headless_context(&pipelines.iter().collect::<Vec<_>>())?;
    let software = ctx.report().is_software;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for model in &m.models {
        for &level in &m.levels {
            let asset = model.asset(level)?;
            if asset.lods.len() as u32 <= level {
                skipped.push(format!("{} has no level {level}", model.name()));
                continue;
            }
            let voxels = asset.lods[level as usize].point_cloud.voxels.len();
            for &size in &m.sizes {
                let reference = {
                    let inst = [ssbvb_voxel::reference::Instance {
                        lod: &asset.lods[level as usize],
                        object_to_world: DAffine3::IDENTITY,
                    }];
                    ssbvb_voxel::reference::render(
                        &inst,
                        &camera,
                        size.0,
                        size.1,
                        &Default::default(),
                    )
                };
                for t in &techniques {
                    if level > t.max_level {
                        skipped.push(format!(
                            "{} at level {level}: supports levels up to {}",
                            t.name, t.max_level
                        ));
                        continue;
                    }
                    let cell = Cell {
                        model: model.name(),
                        asset: &asset,
                        level,
                        size,
                        camera: &camera,
                        reference: &reference,
                        warmup: m.warmup,
                        frames: m.frames,
                        voxels,
                    };
                    let what = format!(
                        "{} on {} level {level} {}x{}",
                        t.name,
                        model.name(),
                        size.0,
                        size.1
                    );
                    let row = match run_one(&ctx, t, &cell) {
                        Ok(row) => row,
                        // What the device cannot hold is a result, not a failure of the run.
                        Err(e) if too_large(&e) => {
                            if !args.json {
                                eprintln!("skipped {what}: {e:#}");
                            }
                            skipped.push(format!("{what}: {e:#}"));
                            continue;
                        }
                        Err(e) => return Err(e.context(what)),
                    };
                    if !args.json {
                        eprintln!(
                            "{:<13} {} L{level} {}x{}: {:.2} ms median, IoU {:.4}",
                            t.name,
                            model.name(),
                            size.0,
                            size.1,
                            row.frame_ms_median,
                            row.coverage_iou
                        );
                    }
                    rows.push(row);
                }
            }
        }
    }
    let sweeps = if (args.sweep || matches!(args.preset, Preset::Full))
        && !matches!(args.preset, Preset::Study)
    {
        let cfg = sweep_config(args.preset);
        let model = assets_dir().join("models/bunny.obj");
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
    let fastest = fastest(&rows);
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
        fastest,
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

/// Whether `e` says the scene does not fit the device's limits.
fn too_large(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<ssbvb_passes::PassError>(),
            Some(ssbvb_passes::PassError::TooLarge(_))
        )
    })
}

/// The fastest technique per (model, size, level) with more than one technique measured.
fn fastest(rows: &[Row]) -> Vec<Fastest> {
    use std::collections::BTreeMap;
    let mut cells: BTreeMap<(String, u32, u32, u32), Vec<&Row>> = BTreeMap::new();
    for r in rows {
        cells
            .entry((r.model.clone(), r.width * r.height, r.width, r.level))
            .or_default()
            .push(r);
    }
    cells
        .into_values()
        .filter(|c| c.len() > 1)
        .map(|mut c| {
            c.sort_by(|a, b| a.frame_ms_median.total_cmp(&b.frame_ms_median));
            Fastest {
                model: c[0].model.clone(),
                width: c[0].width,
                height: c[0].height,
                level: c[0].level,
                technique: c[0].technique,
                frame_ms_median: c[0].frame_ms_median,
                runner_up: c
                    .get(1)
                    .map(|r| (r.technique, r.frame_ms_median / c[0].frame_ms_median)),
            }
        })
        .collect()
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
}

fn run_one(ctx: &ssbvb_gpu::GpuContext, t: &Technique, c: &Cell) -> Result<Row> {
    let mut pipeline = crate::bench_sweep::bundled_pipeline(t.pipeline)?;
    if let Some(edit) = t.edit {
        pipeline = crate::bench_sweep::with_kind_edit(&pipeline, t.name, edit)?;
    }
    let setup = crate::bench_sweep::Setup {
        ctx,
        asset: c.asset,
        lod: LodPolicy::Fixed(c.level),
        level: c.level,
        size: c.size,
        camera: c.camera,
        reference: c.reference,
        warmup: c.warmup,
        frames: c.frames,
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
    let m = crate::bench_sweep::measure(&setup, pipeline, true)?;
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
        gpu_memory_bytes: m.gpu_memory + cube_bytes,
        coverage_iou: acc.coverage_iou,
        // Voxel ids per pixel come from the slot each pixel's ray filled: not available
        // with unique_voxels (one slot per voxel, not per pixel).
        same_voxel_rate: fill
            .filter(|_| t.name != "ssbvb-unique")
            .map(|_| acc.same_voxel_rate),
        depth_error_voxels_median: acc.depth_error_voxels.median,
        normal_error_deg_median: acc.normal_error_deg.median,
        psnr_db: m.psnr.map(|p| p.0).filter(|p| p.is_finite()),
        ssim: m.ssim,
    })
}

fn markdown(r: &Report) -> String {
    let mut s = format!("adapter: {}\ntiming: {}\n\n", r.adapter, r.timing);
    s.push_str("| technique | model | level | size | frame ms (median [min, max]) | fill / covered | voxels | GPU MiB | IoU | same voxel | depth err (vox) | PSNR dB | SSIM |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for x in &r.rows {
        s.push_str(&format!(
            "| {} | {} | {} | {}x{} | {:.2} [{:.2}, {:.2}] | {} | {} | {:.1} | {:.4} | {} | {:.3} | {} | {} |\n",
            x.technique,
            x.model,
            x.level,
            x.width,
            x.height,
            x.frame_ms_median,
            x.frame_ms_min,
            x.frame_ms_max,
            x.fill_count.map_or("-".into(), |f| format!(
                "{f} / {} = {:.3}",
                x.covered_pixels,
                f as f64 / x.covered_pixels.max(1) as f64
            )),
            x.voxels,
            x.gpu_memory_bytes as f64 / (1 << 20) as f64,
            x.coverage_iou,
            x.same_voxel_rate.map_or("-".into(), |v| format!("{v:.4}")),
            x.depth_error_voxels_median,
            x.psnr_db.map_or("-".into(), |p| format!("{p:.2}")),
            x.ssim.map_or("-".into(), |v| format!("{v:.4}"))
        ));
    }
    for k in &r.skipped {
        s.push_str(&format!("\nskipped: {k}"));
    }
    s.push('\n');
    s.push_str(&fastest_markdown(&r.fastest));
    s.push_str(&crate::bench_sweep::markdown(&r.sweeps));
    if !r.plots.is_empty() {
        s.push_str(&crate::bench_plot::markdown(&r.plots));
    }
    s
}

/// Per model, a table of the fastest technique: rows are target sizes, columns levels
/// (model resolution 2^level), like Table 11 of the seed-002 study.
fn fastest_markdown(f: &[Fastest]) -> String {
    let mut models: Vec<&str> = f.iter().map(|x| x.model.as_str()).collect();
    models.dedup();
    let mut s = String::new();
    for model in models {
        let cells: Vec<&Fastest> = f.iter().filter(|x| x.model == model).collect();
        let mut levels: Vec<u32> = cells.iter().map(|x| x.level).collect();
        levels.sort_unstable();
        levels.dedup();
        let mut sizes: Vec<(u32, u32)> = cells.iter().map(|x| (x.width, x.height)).collect();
        sizes.sort_by_key(|&(w, h)| (w * h, w));
        sizes.dedup();
        s.push_str(&format!(
            "\n## Fastest technique per cell: {model}\n\nms of the median frame; in brackets the runner-up and how much slower it was.\n\n| target |"
        ));
        for l in &levels {
            s.push_str(&format!(" {} (L{l}) |", 1u64 << l));
        }
        s.push_str("\n|---|");
        s.push_str(&"---|".repeat(levels.len()));
        s.push('\n');
        for (w, h) in sizes {
            s.push_str(&format!("| {w}x{h} |"));
            for l in &levels {
                match cells
                    .iter()
                    .find(|x| x.width == w && x.height == h && x.level == *l)
                {
                    Some(x) => s.push_str(&format!(
                        " {} {:.2}{} |",
                        x.technique,
                        x.frame_ms_median,
                        x.runner_up
                            .map_or(String::new(), |(t, r)| format!(" ({t} ×{r:.2})"))
                    )),
                    None => s.push_str(" - |"),
                }
            }
            s.push('\n');
        }
    }
    s
}

/// Sweep sizes of a preset.
fn sweep_config(preset: Preset) -> SweepConfig {
    match preset {
        Preset::Quick | Preset::Study => SweepConfig {
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

/// time_vs_level.png, time_vs_resolution.png (main matrix) and `trade_<knob>.png` (sweeps).
fn write_plots(dir: &Path, rows: &[Row], sweeps: &[SweepRow]) -> Result<Vec<PlotInfo>> {
    use std::collections::BTreeMap;
    let mut plots = Vec::new();
    type Points = Vec<(f64, f64)>;
    let sorted = |mut p: Vec<(f64, f64)>| {
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p
    };
    let mut models: Vec<&str> = rows.iter().map(|r| r.model.as_str()).collect();
    models.sort_unstable();
    models.dedup();
    for model in &models {
        let rows: Vec<&Row> = rows.iter().filter(|r| r.model == *model).collect();
        // Only the extreme sizes and levels, so that a study's plots stay readable.
        let mut sizes: Vec<(u32, u32)> = rows.iter().map(|r| (r.width, r.height)).collect();
        sizes.sort_by_key(|&(w, h)| (w * h, w));
        sizes.dedup();
        let sizes = [sizes[0], sizes[sizes.len() - 1]];
        let levels = (
            rows.iter().map(|r| r.level).min().unwrap_or(0),
            rows.iter().map(|r| r.level).max().unwrap_or(0),
        );
        let mut by_size: BTreeMap<(&str, u32, u32), Points> = BTreeMap::new();
        let mut by_level: BTreeMap<(&str, u32), Points> = BTreeMap::new();
        for r in &rows {
            if sizes.contains(&(r.width, r.height)) {
                by_size
                    .entry((r.technique, r.width, r.height))
                    .or_default()
                    .push((r.level as f64, r.frame_ms_median));
            }
            if r.level == levels.0 || r.level == levels.1 {
                by_level
                    .entry((r.technique, r.level))
                    .or_default()
                    .push(((r.width * r.height) as f64 / 1e6, r.frame_ms_median));
            }
        }
        let suffix = if models.len() > 1 {
            format!(
                "_{}",
                model.replace(|c: char| !c.is_ascii_alphanumeric(), "_")
            )
        } else {
            String::new()
        };
        let series: Vec<Series> = by_size
            .into_iter()
            .map(|((t, w, h), p)| Series {
                name: format!("{t} {w}x{h}"),
                points: sorted(p),
            })
            .collect();
        plots.push(crate::bench_plot::plot(
            dir,
            &format!("time_vs_level{suffix}.png"),
            &format!("{model}: frame time vs level"),
            ("level (2^level cells per axis)", "frame ms (median)"),
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
            &format!("time_vs_resolution{suffix}.png"),
            &format!("{model}: frame time vs resolution"),
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
                "composite RMSE vs reference (8-bit levels, pixels either covers)",
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
        "technique,model,level,width,height,frames,frame_ms_median,frame_ms_min,frame_ms_max,fill_count,covered_pixels,voxels,gpu_memory_bytes,coverage_iou,same_voxel_rate,depth_error_voxels_median,normal_error_deg_median,psnr_db,ssim\n",
    );
    for x in &r.rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{:.4},{:.4},{:.4},{},{},{},{},{:.6},{},{:.6},{:.4},{},{}\n",
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
            x.covered_pixels,
            x.voxels,
            x.gpu_memory_bytes,
            x.coverage_iou,
            x.same_voxel_rate
                .map_or(String::new(), |v| format!("{v:.6}")),
            x.depth_error_voxels_median,
            x.normal_error_deg_median,
            x.psnr_db.map_or(String::new(), |p| format!("{p:.4}")),
            x.ssim.map_or(String::new(), |v| format!("{v:.5}"))
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
