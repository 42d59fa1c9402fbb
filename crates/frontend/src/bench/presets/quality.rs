//! `ssbvb bench --preset quality`: image quality still and in motion, against ground
//! truth. A camera path over the 64-bunny grid (the layout of `bunnies_4096.ron`, Auto
//! LOD, finest level 8) — an orbit of two degrees, then a dolly toward the grid's centre
//! to 0.85 of the distance, so instances cross LOD switches — is rendered by every
//! technique and by the CPU reference at `--flip-samples` samples per pixel (the
//! supersampled ground truth), all composited over black. Per technique:
//!
//! - `flip_still`: FLIP of the still frame (the path's first camera, held for a temporal
//!   pass's whole jitter sequence) against the reference's;
//! - `flip_mean`: FLIP of each frame against the reference's, averaged over the path;
//! - `flicker_ratio`: the mean FLIP between consecutive frames divided by the same for
//!   the reference's path (1.0: as stable as ground truth; above: shimmering, popping).
//!
//! The one-sample reference is a row too (`reference-1spp`): what exact aliasing costs.
//! The first frame of each technique is written as a side-by-side crop (technique |
//! reference) and as its FLIP error map in NVIDIA's magma colours.

use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{GpuScene, LodPolicy, Scene, VoxelObject};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{self, SampleGrid};

use crate::bench::args::BenchArgs;
use crate::bench::harness::techniques::{self, TECHNIQUES, Technique};
use crate::bench::harness::{bundled_bunny, grid, grid_camera, technique_pipeline};
use crate::bench::table::{Column, Fmt, Table, write_report};
use crate::flip::{flip_map_rgb8, flip_rgb8, over_black};

/// The finest level of the bunny asset.
const LEVEL: u32 = 8;
/// Bunnies in the grid.
const INSTANCES: usize = 64;

/// One technique's quality over the path.
#[derive(Debug)]
struct QualityRow {
    technique: String,
    width: u32,
    height: u32,
    frames: usize,
    flip_still: f64,
    flip_mean: f64,
    /// Mean FLIP between consecutive frames.
    flicker: f64,
    flicker_ratio: f64,
}

#[derive(Serialize)]
struct QualityReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    instances: usize,
    level: u32,
    /// Samples per pixel of the ground truth.
    reference_samples: u32,
    /// Mean FLIP between consecutive frames of the ground truth's path.
    reference_flicker: f64,
    rows: Table<'a, QualityRow>,
    /// Techniques not measured, and why.
    skipped: Vec<String>,
    /// The PNGs written (crops and error maps), relative to `--out`.
    images: Vec<String>,
}

/// The path's orbit, in degrees about the vertical through the grid's centre, and the
/// distance the dolly ends at (of the start's). Small steps: between frames the image moves
/// by about a pixel at 320 × 240, so what differs from frame to frame beyond the ground
/// truth's change is shimmering and popping, not motion.
const ORBIT_DEG: f64 = 2.0;
const DOLLY_TO: f64 = 0.85;

/// Frame `i` of `n` on the path: the first half the orbit, the second half the dolly
/// toward the grid's centre.
fn path_camera(base: &Camera, i: usize, n: usize) -> Camera {
    let half = n.div_ceil(2).max(1);
    let orbit_steps = i.min(half - 1);
    let angle = ORBIT_DEG.to_radians() * orbit_steps as f64 / (half - 1).max(1) as f64;
    let offset = glam::DQuat::from_rotation_y(angle) * (base.position - base.look_at);
    let dolly = if i < half {
        1.0
    } else {
        1.0 - (1.0 - DOLLY_TO) * (i + 1 - half) as f64 / (n - half).max(1) as f64
    };
    Camera {
        position: base.look_at + offset * dolly,
        ..*base
    }
}

/// The reference of `scene` from `camera` with `grid` samples per pixel, over black (RGB8),
/// at the levels the renderer picks.
fn reference_rgb(
    scene: &Scene,
    asset: &VoxelAsset,
    camera: &Camera,
    size: (u32, u32),
    grid: SampleGrid,
) -> Vec<u8> {
    let max = asset.lods.len() as u32 - 1;
    let obj = &scene.objects[0];
    let instances: Vec<reference::Instance> = obj
        .instances
        .iter()
        .map(|xf| reference::Instance {
            lod: &asset.lods
                [ssbvb_gpu::scene::choose_level(obj.lod, xf, camera, size, max) as usize],
            object_to_world: *xf,
            faces: None,
        })
        .collect();
    let img =
        reference::render_supersampled(&instances, camera, size.0, size.1, &scene.light, grid);
    over_black(&img.to_rgba8())
}

/// Frames the camera holds still at the path's start before the still frame is taken (a
/// temporal pass's whole jitter sequence).
const STILL_FRAMES: usize = ssbvb_passes::kinds::temporal::JITTER_PERIOD as usize;

/// What `pipeline` draws, over black (RGB8): the still frame (the path's first camera after
/// [`STILL_FRAMES`] frames), then each frame of the path, which starts there.
fn technique_frames(
    ctx: &GpuContext,
    scene: &Scene,
    pipeline: ResolvedPipeline,
    cameras: &[Camera],
    size: (u32, u32),
) -> Result<(Vec<u8>, Vec<Vec<u8>>)> {
    let mut gpu_scene = GpuScene::new(ctx, scene.clone())?;
    let mut renderer = Renderer::new(ctx, &gpu_scene, pipeline, size)?;
    let mut draw = |camera: &Camera| -> Result<Vec<u8>> {
        renderer.render(ctx, &mut gpu_scene, camera, Profiling::Off)?;
        let out = ctx.read_texture(
            &renderer.output().texture,
            ssbvb_gpu::wgpu::TextureAspect::All,
        )?;
        Ok(over_black(&crate::render_cmd::to_rgba8(&out)?))
    };
    let mut still = Vec::new();
    for _ in 0..STILL_FRAMES {
        still = draw(&cameras[0])?;
    }
    let frames = cameras.iter().map(&mut draw).collect::<Result<Vec<_>>>()?;
    Ok((still, frames))
}

/// Mean FLIP between consecutive frames.
fn flicker(frames: &[Vec<u8>], size: (u32, u32)) -> Result<f64> {
    let pairs = frames.len().saturating_sub(1);
    if pairs == 0 {
        return Ok(0.0);
    }
    let mut sum = 0.0;
    for w in frames.windows(2) {
        sum += flip_rgb8(&w[0], &w[1], size)?;
    }
    Ok(sum / pairs as f64)
}

/// The techniques of `--techniques`, else the SSBVB variants and the ray casters that draw
/// many instances.
fn quality_techniques(args: &BenchArgs) -> Result<Vec<&'static Technique>> {
    Ok(match &args.techniques {
        Some(_) => techniques::select(args)?,
        None => TECHNIQUES
            .iter()
            .filter(|t| {
                matches!(
                    t.name,
                    "ssbvb-unique"
                        | "ssbvb-aa"
                        | "ssbvb-edge-aa"
                        | "ssbvb-flat"
                        | "ssbvb-raybox"
                        | "octree"
                        | "esvo"
                )
            })
            .collect(),
    })
}

/// Runs the quality preset and writes `quality.{csv,json,md}` and the PNGs to `--out`.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let chosen = quality_techniques(args)?;
    let pipelines = chosen
        .iter()
        .map(|t| technique_pipeline(t))
        .collect::<Result<Vec<_>>>()?;
    let ctx = crate::adapter_cmd::headless_context(&pipelines.iter().collect::<Vec<_>>())?;
    let (asset, _) = bundled_bunny(LEVEL)?;
    let scene = Scene {
        objects: vec![VoxelObject {
            asset: asset.clone(),
            instances: grid(INSTANCES),
            lod: LodPolicy::AUTO,
        }],
        ..Default::default()
    };
    let size = args.first_size((320, 240));
    let n = args.frames.unwrap_or(12).max(2);
    let base = grid_camera(INSTANCES);
    let cameras: Vec<Camera> = (0..n).map(|i| path_camera(&base, i, n)).collect();
    let grid_samples = args.flip_samples_grid();
    let truth: Vec<Vec<u8>> = cameras
        .iter()
        .map(|c| reference_rgb(&scene, &asset, c, size, grid_samples))
        .collect();
    let truth_flicker = flicker(&truth, size)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut images = Vec::new();
    let one_sample: Vec<Vec<u8>> = cameras
        .iter()
        .map(|c| reference_rgb(&scene, &asset, c, size, SampleGrid::CENTRE))
        .collect();
    let mut measured = vec![(
        "reference-1spp".to_string(),
        one_sample[0].clone(),
        one_sample,
    )];
    for (t, p) in chosen.iter().zip(pipelines) {
        match technique_frames(&ctx, &scene, p, &cameras, size) {
            Ok((still, frames)) => measured.push((t.name.to_string(), still, frames)),
            Err(e) if techniques::refused(&e) => skipped.push(format!("{}: {e:#}", t.name)),
            Err(e) => return Err(e.context(t.name)),
        }
    }
    for (name, still, frames) in &measured {
        let mut row = quality_row(name, frames, &truth, truth_flicker, size)?;
        row.flip_still = flip_rgb8(&truth[0], still, size)?;
        images.extend(write_images(&args.out, name, still, &truth[0], size)?);
        if !args.json {
            eprintln!(
                "{name}: FLIP still {:.4}, path {:.4}, flicker ratio {:.2}",
                row.flip_still, row.flip_mean, row.flicker_ratio
            );
        }
        rows.push(row);
    }
    let report = QualityReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        instances: INSTANCES,
        level: LEVEL,
        reference_samples: grid_samples.count(),
        reference_flicker: truth_flicker,
        rows: table(&rows),
        skipped,
        images,
    };
    let md = markdown(&report);
    write_report(&args.out, "quality", report.rows.csv(), &report, md.clone())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("{md}");
        println!("wrote {}/quality.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// The row of one technique's `frames` against the ground truth's.
fn quality_row(
    name: &str,
    frames: &[Vec<u8>],
    truth: &[Vec<u8>],
    truth_flicker: f64,
    size: (u32, u32),
) -> Result<QualityRow> {
    let mut flips = Vec::with_capacity(frames.len());
    for (f, r) in frames.iter().zip(truth) {
        flips.push(flip_rgb8(r, f, size)?);
    }
    let own = flicker(frames, size)?;
    Ok(QualityRow {
        technique: name.to_string(),
        width: size.0,
        height: size.1,
        frames: frames.len(),
        flip_still: flips[0],
        flip_mean: flips.iter().sum::<f64>() / flips.len() as f64,
        flicker: own,
        flicker_ratio: if truth_flicker > 0.0 {
            own / truth_flicker
        } else {
            f64::NAN
        },
    })
}

/// `quality_<name>_crop.png` (the centre half of the first frame beside the reference's)
/// and `quality_<name>_flip.png` (its FLIP error map); returns their names.
fn write_images(
    dir: &Path,
    name: &str,
    frame: &[u8],
    truth: &[u8],
    size: (u32, u32),
) -> Result<Vec<String>> {
    let (w, h) = (size.0 as usize, size.1 as usize);
    let (cw, ch) = ((w / 2).max(1), (h / 2).max(1));
    let (x0, y0) = ((w - cw) / 2, (h - ch) / 2);
    let mut crop = Vec::with_capacity(cw * 2 * ch * 4);
    for y in y0..y0 + ch {
        for img in [frame, truth] {
            for x in x0..x0 + cw {
                let i = (y * w + x) * 3;
                crop.extend_from_slice(&[img[i], img[i + 1], img[i + 2], 255]);
            }
        }
    }
    let (_, magma) = flip_map_rgb8(truth, frame, size)?;
    let magma: Vec<u8> = magma
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let crop_name = format!("quality_{name}_crop.png");
    let map_name = format!("quality_{name}_flip.png");
    reference::write_png_atomic(&dir.join(&crop_name), (cw * 2) as u32, ch as u32, &crop)
        .with_context(|| format!("writing {}", dir.join(&crop_name).display()))?;
    reference::write_png_atomic(&dir.join(&map_name), size.0, size.1, &magma)
        .with_context(|| format!("writing {}", dir.join(&map_name).display()))?;
    Ok(vec![crop_name, map_name])
}

fn table(rows: &[QualityRow]) -> Table<'_, QualityRow> {
    Table::new(
        rows,
        vec![
            Column::new("technique", |r: &QualityRow| r.technique.clone())
                .csv(Fmt::PLAIN)
                .md("technique", Fmt::PLAIN),
            Column::new("width", |r: &QualityRow| r.width).csv(Fmt::PLAIN),
            Column::new("height", |r: &QualityRow| r.height).csv(Fmt::PLAIN),
            Column::new("frames", |r: &QualityRow| r.frames)
                .csv(Fmt::PLAIN)
                .md("frames", Fmt::PLAIN),
            Column::new("flip_still", |r: &QualityRow| r.flip_still)
                .csv(Fmt::fixed(5))
                .md("FLIP still", Fmt::fixed(4)),
            Column::new("flip_mean", |r: &QualityRow| r.flip_mean)
                .csv(Fmt::fixed(5))
                .md("FLIP path", Fmt::fixed(4)),
            Column::new("flicker", |r: &QualityRow| r.flicker)
                .csv(Fmt::fixed(5))
                .md("frame-to-frame FLIP", Fmt::fixed(4)),
            Column::new("flicker_ratio", |r: &QualityRow| r.flicker_ratio)
                .csv(Fmt::fixed(4))
                .md("flicker ratio", Fmt::fixed(2)),
        ],
    )
}

fn markdown(r: &QualityReport) -> String {
    format!(
        "# Image quality in motion ({} bunnies, Auto LOD to level {}; adapter {})\n\n\
         Ground truth: the CPU reference at {} samples per pixel; its frame-to-frame FLIP \
         {:.4}.\n\n{}",
        r.instances,
        r.level,
        r.adapter,
        r.reference_samples,
        r.reference_flicker,
        r.rows.markdown()
    )
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    #[test]
    fn the_path_orbits_then_dollies_in() {
        let base = Camera::new(DVec3::new(0.0, 3.0, 10.0), DVec3::ZERO);
        let n = 8;
        let d0 = (base.position - base.look_at).length();
        let cams: Vec<Camera> = (0..n).map(|i| path_camera(&base, i, n)).collect();
        assert_eq!(cams[0].position, base.position);
        for c in &cams[..4] {
            assert!(((c.position - c.look_at).length() - d0).abs() < 1e-9);
        }
        // The orbit's whole angle over the first four frames, then the dolly.
        let turned = cams[3].position.x.atan2(cams[3].position.z).to_degrees();
        assert!((turned - ORBIT_DEG).abs() < 1e-9, "{turned}");
        let last = (cams[n - 1].position - base.look_at).length();
        assert!((last - DOLLY_TO * d0).abs() < 1e-9, "{last} vs {d0}");
        for w in cams[4..].windows(2) {
            let d = |c: &Camera| (c.position - c.look_at).length();
            assert!(d(&w[1]) < d(&w[0]));
        }
    }
}
