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
use glam::{DAffine3, DQuat, DVec3};
use serde::Serialize;
use ssbvb_passes::{FrameCounters, GpuScene, LodPolicy, Renderer, Scene, VoxelObject};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference;

use super::BenchArgs;
use super::plot::{PlotInfo, Series, plot};
use super::sweep::{bundled_pipeline, with_kind_edit};
use super::techniques::{TECHNIQUES, Technique};

/// The finest level of the bunny asset (the table: level 8).
const LEVEL: u32 = 8;

/// One measured technique and view.
#[derive(Debug, Serialize)]
pub(super) struct ScaleRow {
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
    /// The filter pass's time (wall on a software adapter, GPU timestamps otherwise).
    filter_ms: Option<f64>,
    /// Pixels the reference covers.
    covered_pixels: usize,
    filter_us_per_covered_px: Option<f64>,
    frame_us_per_covered_px: Option<f64>,
    coverage_iou: f64,
    #[serde(flatten)]
    counters: FrameCounters,
}

/// The bunny grid's first `n` instances (row by row on a square grid).
pub(super) fn grid(n: usize) -> Vec<DAffine3> {
    let side = (n as f64).sqrt().ceil().max(1.0) as usize;
    let half = (side as f64 - 1.0) / 2.0;
    (0..n)
        .map(|k| {
            let (i, j) = (k % side, k / side);
            let deg = ((i as u64 * 73856093) ^ (j as u64 * 19349663)) % 360;
            DAffine3::from_rotation_translation(
                DQuat::from_rotation_y((deg as f64).to_radians()),
                DVec3::new((i as f64 - half) * 2.2, 0.0, (j as f64 - half) * 2.2),
            )
        })
        .collect()
}

/// Over the grid from one corner, as `bunnies_4096.ron` looks at its 64 × 64 bunnies.
pub(super) fn grid_camera(n: usize) -> Camera {
    let side = (n as f64).sqrt().ceil().max(1.0);
    let h = (side - 1.0) / 2.0 * 2.2;
    Camera {
        fov_y_deg: 50.0,
        near: 0.05,
        far: f64::INFINITY,
        ..Camera::new(
            DVec3::new(-(h + 4.0), 1.2 + 0.11 * h, -(h + 4.0)),
            DVec3::new(0.0, -1.0, 0.0),
        )
    }
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
pub(super) fn run(args: &BenchArgs) -> Result<()> {
    let counts = args
        .instances
        .clone()
        .unwrap_or_else(|| vec![1, 16, 256, 4096]);
    let size = args
        .sizes
        .as_ref()
        .and_then(|s| s.first().copied())
        .unwrap_or((640, 480));
    let frames = args.frames.unwrap_or(3);
    let techniques: Vec<&Technique> = match &args.techniques {
        Some(_) => super::techniques::select(args)?,
        None => TECHNIQUES
            .iter()
            .filter(|t| {
                matches!(
                    t.name,
                    "ssbvb-unique"
                        | "ssbvb-splat"
                        | "ssbvb-flat"
                        | "octree"
                        | "dense-dda"
                        | "cube-raster"
                )
            })
            .collect(),
    };
    let pipelines = techniques
        .iter()
        .map(|t| {
            let p = bundled_pipeline(t.pipeline)?;
            match t.edit {
                Some(e) => with_kind_edit(&p, t.name, e),
                None => Ok(p),
            }
        })
        .collect::<Result<Vec<_>>>()?;
    let ctx = crate::adapter_cmd::headless_context(&pipelines.iter().collect::<Vec<_>>())?;
    let (asset, _) = super::bundled_bunny(LEVEL)?;
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
        let (reference, cells) = reference_for(&scene, &asset, camera, size);
        for (t, p) in techniques.iter().zip(&pipelines) {
            let what = format!("{} {view} x{n} {}x{}", t.name, size.0, size.1);
            let row = match measure(
                &ctx,
                t,
                p.clone(),
                &scene,
                camera,
                size,
                frames,
                &reference,
                &cells,
            ) {
                Ok(row) => row,
                // What a technique cannot draw (a baseline's one-object limit, a device
                // limit) is a result, not a failure of the run.
                Err(e) if refused(&e) => {
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
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let plots = plots(&args.out, &rows)?;
    let report = ScaleReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        level: LEVEL,
        rows,
        skipped,
        plots,
    };
    write(&args.out, &report)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("{}", markdown(&report));
        println!("wrote {}/scale.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

#[derive(Serialize)]
struct ScaleReport {
    adapter: String,
    adapter_is_software: bool,
    level: u32,
    rows: Vec<ScaleRow>,
    /// Technique and view pairs not measured, and why.
    skipped: Vec<String>,
    plots: Vec<PlotInfo>,
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

/// Whether `e` is a technique's refusal of the scene (too large, or a baseline's limits).
fn refused(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<ssbvb_passes::PassError>(),
            Some(ssbvb_passes::PassError::TooLarge(_) | ssbvb_passes::PassError::BadScene(_))
        )
    })
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
        let level = ssbvb_passes::gpu_scene::choose_level(obj.lod, xf, camera, size, max);
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

#[allow(clippy::too_many_arguments)]
fn measure(
    ctx: &ssbvb_gpu::GpuContext,
    t: &Technique,
    pipeline: ssbvb_graph::ResolvedPipeline,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    frames: usize,
    reference: &reference::ReferenceImage,
    cells: &[f64],
) -> Result<ScaleRow> {
    let mut gpu_scene = GpuScene::new(ctx, scene.clone())?;
    let mut renderer = Renderer::new(ctx, &gpu_scene, pipeline, size)?;
    let timed = super::run::TimedFrames::run(ctx, &mut renderer, &mut gpu_scene, camera, frames)?;
    let counters = renderer.counters(ctx)?;
    let hits = ssbvb_passes::measure::gbuffer_hits(ctx, &renderer)?;
    let acc = ssbvb_voxel::accuracy::compare(reference, &hits, cells)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let filter_ms = timed.pass_ms("filter");
    let covered = acc.covered_reference;
    let per_px = |ms: f64| (covered > 0).then(|| ms * 1e3 / covered as f64);
    let frame_ms = timed.frame_ms;
    let histogram: BTreeMap<u32, usize> = gpu_scene.lod_histogram();
    Ok(ScaleRow {
        technique: t.name,
        view: "",
        instances: scene.objects[0].instances.len(),
        visible_instances: gpu_scene.visible.len(),
        lod_histogram: histogram
            .iter()
            .map(|(l, c)| format!("{l}:{c}"))
            .collect::<Vec<_>>()
            .join(" "),
        width: size.0,
        height: size.1,
        frame_ms_median: frame_ms,
        filter_ms,
        covered_pixels: covered,
        filter_us_per_covered_px: filter_ms.and_then(per_px),
        frame_us_per_covered_px: per_px(frame_ms),
        coverage_iou: acc.coverage_iou,
        counters,
    })
    .map(|mut r| {
        r.view = view_of(camera, scene);
        r
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

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or(String::new(), |v| format!("{v:.digits$}"))
}

/// The report as a Markdown table, with each technique's ratio to its one-bunny grid row.
fn markdown(r: &ScaleReport) -> String {
    let mut s = format!(
        "## Scale: bunny grid (finest level {}, Auto LOD), {}\n\n| technique | view | instances (visible) | levels | frame ms | filter µs/covered px | ×1 bunny | frame µs/covered px | covered px | steps/ray mean (p99)¹ | boxes/ray | billboards | fragments/covered px | IoU |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        r.level, r.adapter
    );
    for x in &r.rows {
        let base = r
            .rows
            .iter()
            .find(|b| b.technique == x.technique && b.view == "grid" && b.instances == 1);
        let ratio = match (
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
        };
        let c = &x.counters;
        s.push_str(&format!(
            "| {} | {} | {} ({}) | {} | {:.1} | {} | {} | {} | {} | {} ({}) | {} | {} | {} | {:.4} |\n",
            x.technique,
            x.view,
            x.instances,
            x.visible_instances,
            x.lod_histogram,
            x.frame_ms_median,
            opt(x.filter_us_per_covered_px, 2),
            ratio,
            opt(x.frame_us_per_covered_px, 2),
            x.covered_pixels,
            opt(
                c.march_steps_mean
                    .or(c.dda_steps_per_ray)
                    .or(c.octree_nodes_per_ray),
                1
            ),
            c.march_steps_p99.map_or(String::new(), |v| v.to_string()),
            opt(c.instance_boxes_per_ray, 1),
            c.billboards_drawn.map_or(String::new(), |v| v.to_string()),
            opt(c.fragments_per_covered_pixel, 2),
            x.coverage_iou
        ));
    }
    s.push_str(
        "\n¹ Filter: march steps per filter ray (p99); dense DDA: cells per traced ray; octree: \
         nodes visited per traced ray.\n",
    );
    for k in &r.skipped {
        s.push_str(&format!("\nSkipped: {k}\n"));
    }
    if !r.plots.is_empty() {
        s.push_str(&super::plot::markdown(&r.plots));
    }
    s
}

fn csv(r: &ScaleReport) -> String {
    let mut s = String::from(
        "technique,view,instances,visible_instances,lod_histogram,width,height,frame_ms_median,filter_ms,covered_pixels,filter_us_per_covered_px,frame_us_per_covered_px,coverage_iou,filter_rays,march_steps_mean,march_steps_p99,instance_boxes_per_ray,instances_marched_per_ray,billboards_drawn,billboard_fragments,fragments_per_covered_pixel,ray_cast_rays,dda_steps_per_ray,octree_nodes_per_ray\n",
    );
    for x in &r.rows {
        let c = &x.counters;
        let u = |v: Option<u64>| v.map_or(String::new(), |v| v.to_string());
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{:.4},{},{},{},{},{:.6},{},{},{},{},{},{},{},{},{},{},{}\n",
            x.technique,
            x.view,
            x.instances,
            x.visible_instances,
            x.lod_histogram,
            x.width,
            x.height,
            x.frame_ms_median,
            opt(x.filter_ms, 4),
            x.covered_pixels,
            opt(x.filter_us_per_covered_px, 4),
            opt(x.frame_us_per_covered_px, 4),
            x.coverage_iou,
            u(c.filter_rays),
            opt(c.march_steps_mean, 3),
            u(c.march_steps_p99),
            opt(c.instance_boxes_per_ray, 3),
            opt(c.instances_marched_per_ray, 3),
            u(c.billboards_drawn),
            u(c.billboard_fragments),
            opt(c.fragments_per_covered_pixel, 3),
            u(c.ray_cast_rays),
            opt(c.dda_steps_per_ray, 3),
            opt(c.octree_nodes_per_ray, 3),
        ));
    }
    s
}

fn write(dir: &Path, r: &ScaleReport) -> Result<()> {
    super::report::write_files(
        dir,
        vec![
            ("scale.csv", csv(r)),
            ("scale.json", serde_json::to_string_pretty(r)?),
            ("scale.md", markdown(r)),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_matches_the_scene_file_layout() {
        // bunnies_64.ron: 8 x 8, first bunny at (-7.7, 0, -7.7), the second turned by
        // (1 * 73856093) mod 360 = 293 degrees.
        let g = grid(64);
        assert_eq!(g.len(), 64);
        assert!((g[0].translation - DVec3::new(-7.7, 0.0, -7.7)).length() < 1e-12);
        assert!((g[1].translation - DVec3::new(-5.5, 0.0, -7.7)).length() < 1e-12);
        let want = glam::DMat3::from_rotation_y(293f64.to_radians());
        assert!(g[1].matrix3.abs_diff_eq(want, 1e-12), "{:?}", g[1].matrix3);
        let text = include_str!("../../../../assets/scenes/bunnies_64.ron");
        assert!(text.contains("(translation: (-5.5, 0.0, -7.7), rotation_y_deg: 293.0)"));
        assert_eq!(grid(1)[0].translation, DVec3::ZERO);
        assert_eq!(grid(3).len(), 3);
    }
}
