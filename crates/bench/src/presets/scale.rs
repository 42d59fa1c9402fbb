//! `ssbvb bench --preset scale`: does a frame's cost follow the screen rather than the
//! scene? The bunny grid of `assets/scenes/bunnies_4096.ron` (2.2 apart, turned by the
//! file's hash) at 1, 16, 256 and 4096 instances (`--instances`), Auto LOD (pixel error 1,
//! finest level 8), seen over the grid from one corner; then one bunny seen touching its
//! surface, from mid distance, and from the far camera. Per technique and view:
//! frame ms, filter ms per covered pixel, the hardware-independent counters, and the IoU
//! against the CPU reference at the same levels. Ratios are against the one-bunny grid
//! row (and the mid view) of the same run.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result};
use glam::DVec3;
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::FrameCounters;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference;

use crate::args::BenchArgs;
use crate::harness::techniques::{self, Technique};
use crate::harness::{TimedFrames, bundled_bunny, grid, grid_camera, technique_pipeline};
use crate::plot::{PlotInfo, Series, plot};
use crate::table::{Column, Fmt, Table, Value, write_report};

/// The finest level of the bunny asset (the table: level 8).
const LEVEL: u32 = 8;

/// One measured technique and view.
#[derive(Debug)]
struct ScaleRow {
    technique: &'static str,
    /// `grid` (over the instances), `near` (touching one bunny), `mid`, `far`.
    view: &'static str,
    instances: usize,
    visible_instances: usize,
    /// Visible instances per level, `level:count` pairs.
    lod_histogram: String,
    width: u32,
    height: u32,
    frame_ms_median: f64,
    /// Median GPU time of the frames timed by timestamps (`None` on software adapters).
    frame_gpu_ms_median: Option<f64>,
    /// The filter pass's time (wall on a software adapter, GPU timestamps otherwise).
    filter_ms: Option<f64>,
    /// Pixels the reference covers.
    covered_pixels: usize,
    filter_us_per_covered_px: Option<f64>,
    frame_us_per_covered_px: Option<f64>,
    coverage_iou: f64,
    counters: FrameCounters,
}

#[derive(Serialize)]
struct ScaleReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    level: u32,
    rows: Table<'a, ScaleRow>,
    /// Technique and view pairs not measured, and why.
    skipped: Vec<String>,
    plots: Vec<PlotInfo>,
}

/// The views of one bunny: touching its surface, mid distance, and the far camera
/// (0.00016° lens, about 1e6 units away).
fn single_views() -> [(&'static str, Camera); 3] {
    let cam = |p: DVec3, at: DVec3, fov: f64| Camera {
        fov_y_deg: fov,
        far: f64::INFINITY,
        ..Camera::new(p, at)
    };
    [
        (
            "near",
            cam(
                DVec3::new(0.05, 0.2, 0.75),
                DVec3::new(0.0, 0.0, -1.0),
                45.0,
            ),
        ),
        ("mid", cam(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO, 45.0)),
        (
            "far",
            cam(
                DVec3::new(309426.0, 206284.0, 928279.0),
                DVec3::ZERO,
                0.00016,
            ),
        ),
    ]
}

/// Runs the scale preset and writes `scale.csv`, `scale.json`, `scale.md` to `--out`.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    run_with(args, true).map(|_| ())
}

/// What another preset reads of a scale row.
pub(crate) struct ScaleTime {
    pub(crate) technique: &'static str,
    /// `grid`, `near`, `mid` or `far`.
    pub(crate) view: &'static str,
    pub(crate) instances: usize,
    pub(crate) frame_ms_median: f64,
    /// Median GPU time (timestamps; `None` on software adapters).
    pub(crate) frame_gpu_ms_median: Option<f64>,
}

/// [`run`], printing the report only when `print_report`; returns the rows' times.
pub(crate) fn run_with(args: &BenchArgs, print_report: bool) -> Result<Vec<ScaleTime>> {
    let techniques = scale_techniques(args)?;
    let pipelines = techniques
        .iter()
        .map(|t| technique_pipeline(t))
        .collect::<Result<Vec<_>>>()?;
    let ctx = ssbvb_engine::choice::headless_context(&pipelines.iter().collect::<Vec<_>>())?;
    let (asset, _) = bundled_bunny(LEVEL)?;
    let (rows, skipped) = measure_views(args, &ctx, &asset, &techniques, &pipelines)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let plots = plots(&args.out, &rows)?;
    let report = ScaleReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        level: LEVEL,
        rows: table(&rows),
        skipped,
        plots,
    };
    write_report(
        &args.out,
        "scale",
        report.rows.csv(),
        &report,
        markdown(&report),
    )?;
    if print_report && args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if print_report {
        println!("{}", markdown(&report));
        println!("wrote {}/scale.{{csv,json,md}}", args.out.display());
    }
    Ok(rows
        .iter()
        .map(|r| ScaleTime {
            technique: r.technique,
            view: r.view,
            instances: r.instances,
            frame_ms_median: r.frame_ms_median,
            frame_gpu_ms_median: r.frame_gpu_ms_median,
        })
        .collect())
}

/// The techniques of `--techniques`, else the SSBVB variants and the baselines that draw
/// many instances.
fn scale_techniques(args: &BenchArgs) -> Result<Vec<&'static Technique>> {
    techniques::select_or(
        args,
        &[
            "ssbvb-unique",
            "ssbvb-splat",
            "ssbvb-flat",
            "octree",
            "esvo",
            "dense-dda",
            "cube-raster",
        ],
    )
}

/// Measures every technique on every view: the grid at each `--instances` count, then the
/// single-bunny views. Returns the rows and the pairs skipped, and why.
fn measure_views(
    args: &BenchArgs,
    ctx: &GpuContext,
    asset: &std::sync::Arc<VoxelAsset>,
    techniques: &[&Technique],
    pipelines: &[ResolvedPipeline],
) -> Result<(Vec<ScaleRow>, Vec<String>)> {
    let counts = args
        .instances
        .clone()
        .unwrap_or_else(|| vec![1, 16, 256, 4096]);
    let size = args.first_size((640, 480));
    let frames = args.frames.unwrap_or(3);
    let mut views: Vec<(&'static str, usize, Camera)> = counts
        .iter()
        .map(|&n| ("grid", n, grid_camera(n)))
        .collect();
    views.extend(single_views().into_iter().map(|(v, c)| (v, 1, c)));
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for (view, n, camera) in &views {
        let scene = Scene {
            objects: vec![VoxelObject {
                asset: asset.clone(),
                instances: grid(*n),
                lod: LodPolicy::AUTO,
            }],
            ..Default::default()
        };
        let (reference, cells) = reference_for(&scene, asset, camera, size);
        let v = View {
            scene: &scene,
            camera,
            size,
            frames,
            reference: &reference,
            cells: &cells,
        };
        for (t, p) in techniques.iter().zip(pipelines) {
            let what = format!("{} {view} x{n} {}x{}", t.name, size.0, size.1);
            let row = match measure(ctx, t, p.clone(), &v) {
                Ok(row) => row,
                // What a technique cannot draw (a baseline's one-object limit, a device
                // limit) is a result, not a failure of the run.
                Err(e) if techniques::refused(&e) => {
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
                    "{what}: {:.1} ms, filter {}, IoU {:.4}",
                    row.frame_ms_median,
                    row.filter_us_per_covered_px
                        .map_or("-".into(), |v| format!("{v:.2} us/px")),
                    row.coverage_iou
                );
            }
            rows.push(row);
        }
    }
    Ok((rows, skipped))
}

/// `scale_frame.png` (every technique) and `scale_filter.png` (the SSBVB variants):
/// µs per covered pixel against log2 of the instance count, grid rows.
fn plots(dir: &Path, rows: &[ScaleRow]) -> Result<Vec<PlotInfo>> {
    let series = |value: fn(&ScaleRow) -> Option<f64>| -> Vec<Series> {
        // Techniques in first-seen order, once each (rows interleave them).
        let mut names: Vec<&str> = Vec::new();
        for r in rows {
            if !names.contains(&r.technique) {
                names.push(r.technique);
            }
        }
        names
            .into_iter()
            .map(|t| Series {
                name: t.to_string(),
                points: rows
                    .iter()
                    .filter(|r| r.technique == t && r.view == "grid")
                    .filter_map(|r| Some(((r.instances as f64).log2(), value(r)?)))
                    .collect(),
            })
            .filter(|s| !s.points.is_empty())
            .collect()
    };
    let mut out = Vec::new();
    for (file, title, y, value) in [
        (
            "scale_frame.png",
            "Frame cost per covered pixel vs instances",
            "frame µs per covered pixel",
            (|r: &ScaleRow| r.frame_us_per_covered_px) as fn(&ScaleRow) -> Option<f64>,
        ),
        (
            "scale_filter.png",
            "Ray-march filter cost per covered pixel vs instances",
            "filter µs per covered pixel",
            |r: &ScaleRow| r.filter_us_per_covered_px,
        ),
    ] {
        let s = series(value);
        if !s.is_empty() {
            out.push(plot(dir, file, title, ("log2(instances)", y), &s)?);
        }
    }
    Ok(out)
}

/// The reference at the levels the renderer picks, and each instance's world cell size.
fn reference_for(
    scene: &Scene,
    asset: &VoxelAsset,
    camera: &Camera,
    size: (u32, u32),
) -> (reference::ReferenceImage, Vec<f64>) {
    let max = asset.lods.len() as u32 - 1;
    let obj = &scene.objects[0];
    let mut instances = Vec::new();
    let mut cells = Vec::new();
    for xf in &obj.instances {
        let level = ssbvb_gpu::scene::choose_level(obj.lod, xf, camera, size, max);
        instances.push(reference::Instance {
            lod: &asset.lods[level as usize],
            object_to_world: *xf,
            faces: None,
        });
        cells.push(2.0 * xf.matrix3.determinant().abs().cbrt() / (1u64 << level) as f64);
    }
    let img = reference::render(&instances, camera, size.0, size.1, &scene.light);
    (img, cells)
}

/// One view of the scene: what every technique is measured on.
struct View<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    size: (u32, u32),
    frames: usize,
    reference: &'a reference::ReferenceImage,
    /// Each instance's world cell size at the level the renderer picks.
    cells: &'a [f64],
}

/// Measures technique `t` (its `pipeline`) on view `v`.
fn measure(
    ctx: &GpuContext,
    t: &Technique,
    pipeline: ResolvedPipeline,
    v: &View,
) -> Result<ScaleRow> {
    let mut gpu_scene = ssbvb_engine::upload::upload_scene(
        ctx,
        v.scene.clone(),
        ssbvb_engine::upload::Residency::Whole,
    )?;
    let mut renderer = ssbvb_engine::upload::renderer(ctx, &gpu_scene, pipeline, v.size)?;
    let timed = TimedFrames::run(ctx, &mut renderer, &mut gpu_scene, v.camera, v.frames)?;
    let counters = renderer.counters(ctx)?;
    let hits = ssbvb_passes::measure::gbuffer_hits(ctx, &renderer)?;
    let acc = ssbvb_voxel::accuracy::compare(v.reference, &hits, v.cells)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let filter_ms = timed.pass_ms("filter");
    let covered = acc.covered_reference;
    let per_px = |ms: f64| (covered > 0).then(|| ms * 1e3 / covered as f64);
    let frame_ms = timed.frame_ms;
    let histogram: BTreeMap<u32, usize> = gpu_scene.lod_histogram();
    Ok(ScaleRow {
        technique: t.name,
        view: view_of(v.camera, v.scene),
        instances: v.scene.objects[0].instances.len(),
        visible_instances: gpu_scene.visible.len(),
        lod_histogram: histogram
            .iter()
            .map(|(l, c)| format!("{l}:{c}"))
            .collect::<Vec<_>>()
            .join(" "),
        width: v.size.0,
        height: v.size.1,
        frame_ms_median: frame_ms,
        frame_gpu_ms_median: timed.frame_gpu_ms,
        filter_ms,
        covered_pixels: covered,
        filter_us_per_covered_px: filter_ms.and_then(per_px),
        frame_us_per_covered_px: per_px(frame_ms),
        coverage_iou: acc.coverage_iou,
        counters,
    })
}

/// The view name of a camera of [`run`] (grid views have more than one instance or the
/// grid camera).
fn view_of(camera: &Camera, scene: &Scene) -> &'static str {
    single_views()
        .into_iter()
        .find(|(_, c)| c.position == camera.position && scene.objects[0].instances.len() == 1)
        .map_or("grid", |(v, _)| v)
}

/// Each technique's ratio to its one-bunny grid row: filter µs per covered pixel, else
/// (marked) frame µs per covered pixel.
fn ratio(rows: &[ScaleRow], x: &ScaleRow) -> String {
    let base = rows
        .iter()
        .find(|b| b.technique == x.technique && b.view == "grid" && b.instances == 1);
    match (
        x.filter_us_per_covered_px,
        base.and_then(|b| b.filter_us_per_covered_px),
    ) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
        _ => match (
            x.frame_us_per_covered_px,
            base.and_then(|b| b.frame_us_per_covered_px),
        ) {
            (Some(a), Some(b)) if b > 0.0 => format!("{:.2} (frame)", a / b),
            _ => String::new(),
        },
    }
}

/// The rows of `scale.csv`, `scale.md` and `scale.json` (the counters flattened into each
/// JSON row; in the CSV each its own column, in the Markdown the ones it shows).
fn table(rows: &[ScaleRow]) -> Table<'_, ScaleRow> {
    Table::new(
        rows,
        vec![
            Column::new("technique", |r: &ScaleRow| r.technique)
                .csv(Fmt::PLAIN)
                .md("technique", Fmt::PLAIN),
            Column::new("view", |r: &ScaleRow| r.view)
                .csv(Fmt::PLAIN)
                .md("view", Fmt::PLAIN),
            Column::new("instances", |r: &ScaleRow| r.instances).csv(Fmt::PLAIN),
            Column::new("visible_instances", |r: &ScaleRow| r.visible_instances).csv(Fmt::PLAIN),
            Column::md_only("instances (visible)", |r: &ScaleRow| {
                format!("{} ({})", r.instances, r.visible_instances)
            }),
            Column::new("lod_histogram", |r: &ScaleRow| r.lod_histogram.clone())
                .csv(Fmt::PLAIN)
                .md("levels", Fmt::PLAIN),
            Column::new("width", |r: &ScaleRow| r.width).csv(Fmt::PLAIN),
            Column::new("height", |r: &ScaleRow| r.height).csv(Fmt::PLAIN),
            Column::new("frame_ms_median", |r: &ScaleRow| r.frame_ms_median)
                .csv(Fmt::fixed(4))
                .md("frame ms", Fmt::fixed(1)),
            Column::new("frame_gpu_ms_median", |r: &ScaleRow| r.frame_gpu_ms_median)
                .csv(Fmt::fixed(4))
                .md("GPU ms", Fmt::fixed(2).or("-")),
            Column::new("filter_ms", |r: &ScaleRow| r.filter_ms).csv(Fmt::fixed(4)),
            Column::new("covered_pixels", |r: &ScaleRow| r.covered_pixels).csv(Fmt::PLAIN),
            Column::new("filter_us_per_covered_px", |r: &ScaleRow| {
                r.filter_us_per_covered_px
            })
            .csv(Fmt::fixed(4))
            .md("filter µs/covered px", Fmt::fixed(2)),
            Column::md_only("×1 bunny", move |x: &ScaleRow| ratio(rows, x)),
            Column::new("frame_us_per_covered_px", |r: &ScaleRow| {
                r.frame_us_per_covered_px
            })
            .csv(Fmt::fixed(4))
            .md("frame µs/covered px", Fmt::fixed(2)),
            Column::md_only("covered px", |r: &ScaleRow| r.covered_pixels),
            Column::md_only("steps/ray mean (p99)¹", |r: &ScaleRow| {
                let c = &r.counters;
                format!(
                    "{} ({})",
                    Fmt::fixed(1).text(
                        &c.march_steps_mean
                            .or(c.dda_steps_per_ray)
                            .or(c.octree_nodes_per_ray)
                            .into()
                    ),
                    Fmt::PLAIN.text(&c.march_steps_p99.into())
                )
            }),
            Column::text("", |r: &ScaleRow| r.counters.instance_boxes_per_ray)
                .md("boxes/ray", Fmt::fixed(1)),
            Column::text("", |r: &ScaleRow| r.counters.billboards_drawn)
                .md("billboards", Fmt::PLAIN),
            Column::text("", |r: &ScaleRow| r.counters.fragments_per_covered_pixel)
                .md("fragments/covered px", Fmt::fixed(2)),
            Column::new("coverage_iou", |r: &ScaleRow| r.coverage_iou)
                .csv(Fmt::fixed(6))
                .md("IoU", Fmt::fixed(4)),
            Column::new("counters", |r: &ScaleRow| Value::flatten(&r.counters)),
            Column::text("filter_rays", |r: &ScaleRow| r.counters.filter_rays).csv(Fmt::PLAIN),
            Column::text("march_steps_mean", |r: &ScaleRow| {
                r.counters.march_steps_mean
            })
            .csv(Fmt::fixed(3)),
            Column::text("march_steps_p99", |r: &ScaleRow| r.counters.march_steps_p99)
                .csv(Fmt::PLAIN),
            Column::text("instance_boxes_per_ray", |r: &ScaleRow| {
                r.counters.instance_boxes_per_ray
            })
            .csv(Fmt::fixed(3)),
            Column::text("instances_marched_per_ray", |r: &ScaleRow| {
                r.counters.instances_marched_per_ray
            })
            .csv(Fmt::fixed(3)),
            Column::text("billboards_drawn", |r: &ScaleRow| {
                r.counters.billboards_drawn
            })
            .csv(Fmt::PLAIN),
            Column::text("billboard_fragments", |r: &ScaleRow| {
                r.counters.billboard_fragments
            })
            .csv(Fmt::PLAIN),
            Column::text("fragments_per_covered_pixel", |r: &ScaleRow| {
                r.counters.fragments_per_covered_pixel
            })
            .csv(Fmt::fixed(3)),
            Column::text("ray_cast_rays", |r: &ScaleRow| r.counters.ray_cast_rays).csv(Fmt::PLAIN),
            Column::text("dda_steps_per_ray", |r: &ScaleRow| {
                r.counters.dda_steps_per_ray
            })
            .csv(Fmt::fixed(3)),
            Column::text("octree_nodes_per_ray", |r: &ScaleRow| {
                r.counters.octree_nodes_per_ray
            })
            .csv(Fmt::fixed(3)),
        ],
    )
}

/// The report as Markdown: the table, with each technique's ratio to its one-bunny grid
/// row, its footnote, the pairs skipped and the plots.
fn markdown(r: &ScaleReport) -> String {
    let mut s = format!(
        "## Scale: bunny grid (finest level {}, Auto LOD), {}\n\n",
        r.level, r.adapter
    );
    s.push_str(&r.rows.markdown());
    s.push_str(
        "\n¹ Filter: march steps per filter ray (p99); dense DDA: cells per traced ray; octree: \
         nodes visited per traced ray; ESVO: loop iterations per traced ray.\n",
    );
    for k in &r.skipped {
        s.push_str(&format!("\nSkipped: {k}\n"));
    }
    if !r.plots.is_empty() {
        s.push_str(&crate::plot::markdown(&r.plots));
    }
    s
}
