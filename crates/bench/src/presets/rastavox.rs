//! `ssbvb bench --preset rastavox`: RastaVox on the bundled models, in three
//! tables (`rastavox.{csv,json,md}`):
//!
//! 1. **Memory** beside the paper's Table 1: per model (bunny, knight) and level, the
//!    surface voxels and the bytes of the surface model (4 per voxel, 8 of attributes, the
//!    OR-merged LODs, the chunk tables) against the SSBVB asset of the same level (every
//!    coarser level resident, as the renderer keeps it). Computed on the CPU
//!    (`ssbvb_voxel::surface`), equal to what the GPU build allocates.
//! 2. **GPU build** beside the paper's Table 2: extraction + sort (base) and the LOD chain,
//!    host wall clock with each step waited for, and per million surface voxels.
//! 3. **Pixel-error sweep** on the bunny at the sweep level (`--levels`' last, default 9)
//!    and on `--instances N` bunnies if given: frame time and its ratio to pixel error 0,
//!    surface voxels drawn, chunks per LOD, and accuracy against the reference of the
//!    drawn model (each chunk's OR-merged LOD hit through its masked faces: coverage IoU,
//!    same voxel, depth, PSNR of the lit frame) and against the finest level (IoU: what the
//!    pixel error costs).

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DAffine3;
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::ObjectMemory;
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_gpu_build::surface_build::SurfaceBuilder;
use ssbvb_graph::PassKind;
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::accuracy::{self, AccuracyReport};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{self, Instance, ReferenceImage};
use ssbvb_voxel::shading::Light;
use ssbvb_voxel::surface::{FaceLod, SurfaceModel, select_chunks};

use crate::args::BenchArgs;
use crate::harness::{
    bench_camera, bundled_asset, bundled_pipeline, covered_rgba, grid, grid_camera, median,
    timed_frames, with_kind_edit,
};
use crate::table::{Column, Fmt, Table, Value, size, write_report};

/// Pixel errors of the sweep (0 is the baseline of the ratios; 1 the paper's setting).
const PIXEL_ERRORS: [f32; 4] = [0.0, 1.0, 2.0, 4.0];
/// Default levels of the memory and build tables.
const DEFAULT_LEVELS: [u32; 5] = [5, 6, 7, 8, 9];
const MODELS: [(&str, &str); 2] = [
    ("bunny", "models/bunny.obj"),
    ("knight", "models/chr_knight.vox"),
];

/// One model at one level: memory and build.
#[derive(Debug)]
struct ModelRow {
    model: &'static str,
    level: u32,
    /// Voxels of the asset at that level.
    voxels: u64,
    surface_voxels: u64,
    chunks: usize,
    /// Surface voxels and attributes of the finest level (MiB).
    base_mib: f64,
    /// The coarser OR-merged levels (MiB).
    lod_mib: f64,
    /// Everything, with the chunk tables (MiB).
    total_mib: f64,
    /// The SSBVB asset at that level (point clouds, lookups, proxies of every level; MiB).
    ssbvb_mib: f64,
    /// GPU build: extraction, sort and chunk ranges of the finest level (ms).
    build_base_ms: f64,
    /// GPU build: every coarser level (ms).
    build_lod_ms: f64,
    /// (base + LOD) per million surface voxels (ms).
    build_ms_per_million: f64,
}

/// One pixel error on one scene.
#[derive(Debug)]
struct SweepRow {
    scene: String,
    level: u32,
    width: u32,
    height: u32,
    pixel_error: f32,
    frames: usize,
    frame_ms_median: f64,
    /// Against pixel error 0 on the same scene in this run.
    frame_ms_ratio: f64,
    /// Surface voxels in the chunk draws (hardware-independent cost).
    voxels_drawn: u64,
    /// Chunks drawn at each LOD (0 = finest).
    chunks_per_lod: Vec<usize>,
    /// Against the reference of the drawn model.
    coverage_iou: f64,
    same_voxel_rate: f64,
    depth_error_voxels_median: f64,
    psnr_db: Option<f64>,
    /// Coverage IoU against the finest level (what the pixel error costs).
    coverage_iou_vs_finest: f64,
}

#[derive(Serialize)]
struct RastaVoxReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    models: Table<'a, ModelRow>,
    sweep: Table<'a, SweepRow>,
}

fn mib(b: u64) -> f64 {
    b as f64 / (1 << 20) as f64
}

/// The memory and build rows of one model at `levels`.
fn model_rows(
    ctx: &GpuContext,
    builder: &SurfaceBuilder,
    name: &'static str,
    file: &str,
    levels: &[u32],
    log: bool,
) -> Result<Vec<ModelRow>> {
    let Some(&max) = levels.iter().max() else {
        return Ok(Vec::new());
    };
    let (asset, _) = bundled_asset(file, max)?;
    let mut rows = Vec::new();
    for &level in levels {
        let lod = &asset.lods[level as usize];
        let cpu = SurfaceModel::extract(lod).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        let t0 = Instant::now();
        let gpu = builder.build(ctx, lod)?;
        let wall = t0.elapsed().as_secs_f64();
        if gpu.surface_voxels() != cpu.surface_voxels() as u64 {
            bail!(
                "{name} level {level}: the GPU build found {} surface voxels, the CPU {}",
                gpu.surface_voxels(),
                cpu.surface_voxels()
            );
        }
        let mut ssbvb = ObjectMemory::default();
        for l in &asset.lods[..=level as usize] {
            ssbvb.add(&ObjectMemory::of_lod(l));
        }
        let b = cpu.bytes();
        let surface = cpu.surface_voxels() as u64;
        let row = ModelRow {
            model: name,
            level,
            voxels: lod.point_cloud.voxels.len() as u64,
            surface_voxels: surface,
            chunks: cpu.chunks.len(),
            base_mib: mib(b.base_voxels + b.base_attributes),
            lod_mib: mib(b.lod),
            total_mib: mib(b.total()),
            ssbvb_mib: mib(ssbvb.total()),
            build_base_ms: gpu.times.base_seconds * 1e3,
            build_lod_ms: gpu.times.lod_seconds * 1e3,
            build_ms_per_million: if surface == 0 {
                0.0
            } else {
                wall * 1e3 / (surface as f64 / 1e6)
            },
        };
        if log {
            eprintln!(
                "rastavox {name} L{level}: {} surface voxels, {:.2} MiB (SSBVB {:.2} MiB), build {:.1} + {:.1} ms",
                row.surface_voxels,
                row.total_mib,
                row.ssbvb_mib,
                row.build_base_ms,
                row.build_lod_ms
            );
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The drawn model of `instances` of `model`: per instance, each chunk the camera sees at
/// its LOD, and the surface voxels drawn.
fn drawn(
    model: &SurfaceModel,
    instances: &[DAffine3],
    camera: &Camera,
    size: (u32, u32),
    pixel_error: f32,
) -> (Vec<(DAffine3, FaceLod)>, Vec<usize>, u64) {
    let mut placed = Vec::new();
    let mut per_lod = vec![0; model.levels.len()];
    let mut voxels = 0;
    for xf in instances {
        let draws = select_chunks(
            model.level,
            model.chunk_log2,
            &model.bounds,
            xf,
            camera,
            size,
            pixel_error,
        );
        for c in draws {
            per_lod[c.k] += 1;
            voxels += u64::from(model.levels[c.k].ranges[c.chunk][1]);
            placed.push((*xf, model.face_lod(c.chunk, c.k)));
        }
    }
    (placed, per_lod, voxels)
}

/// Everything one sweep scene needs.
struct SweepScene<'a> {
    name: String,
    asset: &'a Arc<VoxelAsset>,
    model: &'a SurfaceModel,
    level: u32,
    instances: Vec<DAffine3>,
    camera: Camera,
    size: (u32, u32),
    frames: usize,
}

/// Renders `s` at every pixel error and compares.
fn sweep_scene(ctx: &GpuContext, s: &SweepScene, log: bool) -> Result<Vec<SweepRow>> {
    let base = bundled_pipeline("rastavox.ron")?;
    let scene = Scene {
        objects: vec![VoxelObject {
            asset: s.asset.clone(),
            instances: s.instances.clone(),
            lod: LodPolicy::Fixed(s.level),
        }],
        ..Default::default()
    };
    let finest_instances: Vec<Instance> = s
        .instances
        .iter()
        .map(|xf| Instance {
            lod: &s.asset.lods[s.level as usize],
            object_to_world: *xf,
            faces: None,
        })
        .collect();
    let light = scene.light;
    let finest = reference::render(&finest_instances, &s.camera, s.size.0, s.size.1, &light);
    let mut gpu_scene =
        ssbvb_engine::upload::upload_scene(ctx, scene, ssbvb_engine::upload::Residency::Whole)?;
    let mut rows: Vec<SweepRow> = Vec::new();
    for pe in PIXEL_ERRORS {
        let pipeline = with_kind_edit(&base, "pixel_error", |k| match k {
            PassKind::RastaVox(r) => {
                r.pixel_error = pe;
                true
            }
            _ => false,
        })?;
        let mut renderer = ssbvb_engine::upload::renderer(ctx, &gpu_scene, pipeline, s.size)?;
        // The first frame builds the surface model: not timed.
        renderer.render(ctx, &mut gpu_scene, &s.camera, Profiling::Off)?;
        ctx.wait_idle()?;
        let mut times = timed_frames(ctx, &mut renderer, &mut gpu_scene, &s.camera, s.frames)?;
        let frame_ms = median(&mut times);
        let d = compare_drawn(ctx, s, &renderer, pe, &finest, &light)?;
        let baseline = rows.first().map_or(frame_ms, |r| r.frame_ms_median);
        let row = SweepRow {
            scene: s.name.clone(),
            level: s.level,
            width: s.size.0,
            height: s.size.1,
            pixel_error: pe,
            frames: times.len(),
            frame_ms_median: frame_ms,
            frame_ms_ratio: frame_ms / baseline,
            voxels_drawn: d.voxels,
            chunks_per_lod: d.per_lod,
            coverage_iou: d.acc.coverage_iou,
            same_voxel_rate: d.acc.same_voxel_rate,
            depth_error_voxels_median: d.acc.depth_error_voxels.median,
            psnr_db: d.psnr_db,
            coverage_iou_vs_finest: d.iou_vs_finest,
        };
        if log {
            eprintln!(
                "rastavox {} L{} pixel error {pe}: {:.2} ms (x{:.3}), {} voxels drawn, IoU {:.4} same voxel {:.4} (vs finest IoU {:.4})",
                s.name,
                s.level,
                row.frame_ms_median,
                row.frame_ms_ratio,
                row.voxels_drawn,
                row.coverage_iou,
                row.same_voxel_rate,
                row.coverage_iou_vs_finest
            );
        }
        rows.push(row);
    }
    Ok(rows)
}

/// What a frame at one pixel error drew, and how it compares.
struct DrawnAccuracy {
    /// Surface voxels in the chunk draws.
    voxels: u64,
    /// Chunks drawn at each LOD.
    per_lod: Vec<usize>,
    /// Against the reference of the drawn model.
    acc: AccuracyReport,
    psnr_db: Option<f64>,
    /// Coverage IoU against the finest level.
    iou_vs_finest: f64,
}

/// Compares the frame `renderer` drew at pixel error `pe` with the reference of the drawn
/// model (each chunk's OR-merged LOD hit through its masked faces) and with `finest`.
fn compare_drawn(
    ctx: &GpuContext,
    s: &SweepScene,
    renderer: &Renderer,
    pe: f32,
    finest: &ReferenceImage,
    light: &Light,
) -> Result<DrawnAccuracy> {
    let mut hits = ssbvb_passes::measure::gbuffer_hits(ctx, renderer)?;
    let (placed, per_lod, voxels) = drawn(s.model, &s.instances, &s.camera, s.size, pe);
    let refs: Vec<Instance> = placed
        .iter()
        .map(|(xf, f)| Instance {
            lod: &f.lod,
            object_to_world: *xf,
            faces: Some(&f.faces),
        })
        .collect();
    let reference = reference::render(&refs, &s.camera, s.size.0, s.size.1, light);
    let lookups: Vec<_> = placed.iter().map(|(xf, f)| (*xf, &f.lod.lookup)).collect();
    let cells: Vec<f64> = placed
        .iter()
        .map(|(xf, f)| xf.matrix3.x_axis.length() * ssbvb_voxel::model::cell_size(f.lod.level))
        .collect();
    let vs_finest = accuracy::compare(finest, &hits, &vec![f64::MAX; s.instances.len()])
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    accuracy::recover_face_voxels(&mut hits, &s.camera, s.size, &lookups);
    let acc = accuracy::compare(&reference, &hits, &cells).map_err(|e| anyhow::anyhow!("{e}"))?;
    let out = ctx.read_texture(
        &renderer.output().texture,
        ssbvb_gpu::wgpu::TextureAspect::All,
    )?;
    let gpu_rgba = crate::harness::engine::to_rgba8(&out)?;
    let ref_rgba = reference.to_rgba8();
    let (a, b) = covered_rgba(&hits, &reference.hits, &gpu_rgba, &ref_rgba);
    Ok(DrawnAccuracy {
        voxels,
        per_lod,
        acc,
        psnr_db: accuracy::psnr_rgba8(&a, &b).filter(|p| p.is_finite()),
        iou_vs_finest: vs_finest.coverage_iou,
    })
}

/// Runs `ssbvb bench --preset rastavox`.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let log = !args.json;
    let base = bundled_pipeline("rastavox.ron")?;
    let ctx = ssbvb_engine::choice::headless_context(&[&base])?;
    let builder = SurfaceBuilder::new(&ctx)?;
    let levels = args.levels.clone().unwrap_or(DEFAULT_LEVELS.to_vec());
    let mut models = Vec::new();
    for (name, file) in MODELS {
        models.extend(model_rows(&ctx, &builder, name, file, &levels, log)?);
    }
    let level = *levels.iter().max().context("--levels is empty")?;
    let size = args.first_size((1280, 720));
    let frames = args.frames.unwrap_or(5);
    let (asset, _) = bundled_asset(MODELS[0].1, level)?;
    let model = SurfaceModel::extract(&asset.lods[level as usize])
        .map_err(|e| anyhow::anyhow!("bunny: {e}"))?;
    let mut sweep = sweep_scene(
        &ctx,
        &SweepScene {
            name: "bunny".into(),
            asset: &asset,
            model: &model,
            level,
            instances: vec![DAffine3::IDENTITY],
            camera: bench_camera(),
            size,
            frames,
        },
        log,
    )?;
    for &n in args.instances.iter().flatten() {
        sweep.extend(sweep_scene(
            &ctx,
            &SweepScene {
                name: format!("{n} bunnies"),
                asset: &asset,
                model: &model,
                level,
                instances: grid(n),
                camera: grid_camera(n),
                size,
                frames,
            },
            log,
        )?);
    }
    let report = RastaVoxReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        models: models_table(&models),
        sweep: sweep_table(&sweep),
    };
    write_report(
        &args.out,
        "rastavox",
        report.sweep.csv(),
        &report,
        markdown(&report),
    )?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("wrote {}/rastavox.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// The memory and build rows: the first table of `rastavox.md`, `models` in the JSON.
fn models_table(rows: &[ModelRow]) -> Table<'_, ModelRow> {
    Table::new(
        rows,
        vec![
            Column::new("model", |m: &ModelRow| m.model).md("model", Fmt::PLAIN),
            Column::new("level", |m: &ModelRow| m.level)
                .md("level", Fmt::PLAIN)
                .right(),
            Column::new("voxels", |m: &ModelRow| m.voxels)
                .md("voxels", Fmt::PLAIN)
                .right(),
            Column::new("surface_voxels", |m: &ModelRow| m.surface_voxels)
                .md("surface voxels", Fmt::PLAIN)
                .right(),
            Column::new("chunks", |m: &ModelRow| m.chunks)
                .md("chunks", Fmt::PLAIN)
                .right(),
            Column::new("base_mib", |m: &ModelRow| m.base_mib)
                .md("base MiB", Fmt::fixed(2))
                .right(),
            Column::new("lod_mib", |m: &ModelRow| m.lod_mib)
                .md("LOD MiB", Fmt::fixed(2))
                .right(),
            Column::new("total_mib", |m: &ModelRow| m.total_mib)
                .md("total MiB", Fmt::fixed(2))
                .right(),
            Column::new("ssbvb_mib", |m: &ModelRow| m.ssbvb_mib)
                .md("SSBVB MiB", Fmt::fixed(2))
                .right(),
            Column::new("build_base_ms", |m: &ModelRow| m.build_base_ms)
                .md("build base ms", Fmt::fixed(1))
                .right(),
            Column::new("build_lod_ms", |m: &ModelRow| m.build_lod_ms)
                .md("build LOD ms", Fmt::fixed(1))
                .right(),
            Column::new("build_ms_per_million", |m: &ModelRow| {
                m.build_ms_per_million
            })
            .md("ms per M surface voxels", Fmt::fixed(1))
            .right(),
        ],
    )
}

/// The pixel-error sweep: `rastavox.csv`, the second table of `rastavox.md`, `sweep` in
/// the JSON.
fn sweep_table(rows: &[SweepRow]) -> Table<'_, SweepRow> {
    Table::new(
        rows,
        vec![
            Column::new("scene", |w: &SweepRow| w.scene.clone())
                .csv(Fmt::PLAIN)
                .md("scene", Fmt::PLAIN),
            Column::new("level", |w: &SweepRow| w.level)
                .csv(Fmt::PLAIN)
                .md("level", Fmt::PLAIN)
                .right(),
            Column::new("width", |w: &SweepRow| w.width).csv(Fmt::PLAIN),
            Column::new("height", |w: &SweepRow| w.height).csv(Fmt::PLAIN),
            Column::md_only("size", |w: &SweepRow| size(w.width, w.height)),
            Column::new("pixel_error", |w: &SweepRow| w.pixel_error)
                .csv(Fmt::PLAIN)
                .md("pixel error", Fmt::PLAIN)
                .right(),
            Column::new("frames", |w: &SweepRow| w.frames).csv(Fmt::PLAIN),
            Column::new("frame_ms_median", |w: &SweepRow| w.frame_ms_median)
                .csv(Fmt::fixed(4))
                .md("frame ms", Fmt::fixed(2))
                .right(),
            Column::new("frame_ms_ratio", |w: &SweepRow| w.frame_ms_ratio)
                .csv(Fmt::fixed(4))
                .md("× pixel error 0", Fmt::fixed(3))
                .right(),
            Column::new("voxels_drawn", |w: &SweepRow| w.voxels_drawn)
                .csv(Fmt::PLAIN)
                .md("voxels drawn", Fmt::PLAIN)
                .right(),
            Column::new("chunks_per_lod", |w: &SweepRow| {
                Value::json(&w.chunks_per_lod)
            }),
            Column::md_only("chunks per LOD", |w: &SweepRow| {
                format!("{:?}", w.chunks_per_lod)
            }),
            Column::new("coverage_iou", |w: &SweepRow| w.coverage_iou)
                .csv(Fmt::fixed(6))
                .md("IoU", Fmt::fixed(4))
                .right(),
            Column::new("same_voxel_rate", |w: &SweepRow| w.same_voxel_rate)
                .csv(Fmt::fixed(6))
                .md("same voxel", Fmt::fixed(4))
                .right(),
            Column::new("depth_error_voxels_median", |w: &SweepRow| {
                w.depth_error_voxels_median
            })
            .csv(Fmt::exp(3))
            .md("depth err (voxels)", Fmt::exp(2))
            .right(),
            Column::new("psnr_db", |w: &SweepRow| w.psnr_db)
                .csv(Fmt::fixed(3))
                .md("PSNR dB", Fmt::fixed(2).or("-"))
                .right(),
            Column::new("coverage_iou_vs_finest", |w: &SweepRow| {
                w.coverage_iou_vs_finest
            })
            .csv(Fmt::fixed(6))
            .md("IoU vs finest", Fmt::fixed(4))
            .right(),
        ],
    )
}

/// `rastavox.md`: the memory and build table, then the sweep.
fn markdown(r: &RastaVoxReport) -> String {
    format!(
        "# RastaVox\n\nAdapter: {}\n\n{}\n{}",
        r.adapter,
        r.models.markdown(),
        r.sweep.markdown()
    )
}
