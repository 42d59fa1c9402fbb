//! `ssbvb bench --preset volumes`: volumetric billboards, two tables.
//!
//! 1. **Knobs.** The procedural cloud and the bunny's coverage volume (64³ each) alone at
//!    the first `--sizes` (default 320x240): `slice_spacing` from 0.25 to 4 texels and
//!    `mip_bias` 1 and 2, one at a time. Each row: the `VolumeSlices` pass time and the
//!    frame time, the slices drawn and the slice fragments per covered pixel (counted on
//!    the CPU from the slice polygons' projected areas: hardware-independent), and PSNR
//!    and SSIM of the frame against the emission–absorption integral through the finest
//!    level (4 steps per texel), over the pixels either shows.
//! 2. **Crossover** (the thesis's chapter 4: when is a volumetric billboard cheaper than
//!    the mesh it replaces?). The cow (2,903 vertices) and the bunny (35,947) drawn as
//!    triangles against their 128³ coverage volumes at the default knobs, the object
//!    `height` pixels tall on a 768x768 frame for heights 16 to 512: each row times the
//!    `triangles` pass of the mesh frame and the `volumes` pass of the volume frame.
//!
//! Writes volumes.csv, volumes.json and volumes.md.

use std::sync::Arc;

use anyhow::{Context, Result};
use glam::{DAffine3, DMat4, DVec3, DVec4};
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{Scene, TriangleObject, VolumeObject};
use ssbvb_graph::{PassKind, ResolvedPipeline};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::{Mesh, ObjectSpace};
use ssbvb_voxel::rgba_volume::RgbaVolume;
use ssbvb_voxel::rgba_volume::integrate::{self, PlacedVolume};
use ssbvb_voxel::rgba_volume::slicing::{SliceSettings, slice};
use ssbvb_voxel::rgba_volume::sources::{Cloud, from_mesh_coverage};

use crate::args::BenchArgs;
use crate::harness::TimedFrames;
use crate::table::{Column, Fmt, Table, size, write_report};
use ssbvb_engine::assets::assets_dir;

#[derive(Debug, Clone)]
struct KnobRow {
    subject: &'static str,
    sweep: &'static str,
    width: u32,
    height: u32,
    slice_spacing: f32,
    mip_bias: f32,
    level: usize,
    slices: u32,
    fragments_per_covered_pixel: f64,
    covered_pixels: usize,
    frame_ms: f64,
    volume_ms: Option<f64>,
    psnr_db: f64,
    ssim: Option<f64>,
}

#[derive(Debug, Clone)]
struct CrossoverRow {
    model: &'static str,
    vertices: usize,
    triangles: usize,
    volume_edge: u32,
    /// The object's height on screen (pixels).
    screen_height: u32,
    mesh_ms: Option<f64>,
    volume_ms: Option<f64>,
    /// volume_ms / mesh_ms: below 1 the volume is cheaper.
    volume_vs_mesh: Option<f64>,
    volume_fragments_per_covered_pixel: f64,
    /// GPU bytes of the volume's atlas (stored bricks with aprons, every level, tables).
    volume_atlas_bytes: u64,
    /// The same levels dense, 4 bytes a texel (the thesis's uncompressed 3D texture).
    volume_dense_bytes: u64,
    /// The mesh's vertex (position + normal, 24 bytes) and index (12 per triangle) bytes.
    mesh_bytes: u64,
}

#[derive(Serialize)]
struct VolumesReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    knobs: Table<'a, KnobRow>,
    crossover: Table<'a, CrossoverRow>,
}

/// A mesh as a triangle object in the object space its volume uses ([-1, 1]³ around its
/// bounding box), grey, with area-weighted vertex normals.
fn mesh_object(mesh: &Mesh, to_world: DAffine3) -> TriangleObject {
    let (lo, hi) = mesh.positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p.as_dvec3()), hi.max(p.as_dvec3())),
    );
    let space = ObjectSpace::from_bounds(lo, hi);
    let positions: Vec<[f32; 3]> = mesh
        .positions
        .iter()
        .map(|p| space.to_object(p.as_dvec3()).as_vec3().into())
        .collect();
    let mut normals = vec![glam::Vec3::ZERO; positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| glam::Vec3::from(positions[i as usize]));
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    TriangleObject {
        positions,
        normals: normals
            .iter()
            .map(|n| n.normalize_or(glam::Vec3::Y).into())
            .collect(),
        indices: mesh.triangles.iter().flatten().copied().collect(),
        color: [0.7, 0.7, 0.7, 1.0],
        transform: to_world,
    }
}

/// Sum of the slice triangles' projected areas (pixels): the fragments the slices would
/// shade with no depth test and no discards.
fn slice_fragments(
    volumes: &[(&RgbaVolume, DAffine3)],
    camera: &Camera,
    size: (u32, u32),
    settings: SliceSettings,
) -> (f64, u32, usize) {
    let g = slice(volumes, camera, size, settings);
    let vp: DMat4 = camera.view_projection(f64::from(size.0) / f64::from(size.1));
    let px = |p: [f32; 3]| {
        let w = camera.position + DVec3::new(p[0].into(), p[1].into(), p[2].into());
        let c: DVec4 = vp * w.extend(1.0);
        DVec3::new(
            (c.x / c.w * 0.5 + 0.5) * f64::from(size.0),
            (c.y / c.w * 0.5 + 0.5) * f64::from(size.1),
            0.0,
        )
    };
    let area: f64 = g
        .vertices
        .chunks(3)
        .map(|t| {
            let [a, b, c] = [px(t[0].0), px(t[1].0), px(t[2].0)];
            (b - a).cross(c - a).length() * 0.5
        })
        .sum();
    let slices = g.volumes.iter().map(|v| v.slices).sum();
    (area, slices, g.volumes.first().map_or(0, |v| v.level))
}

fn render_frame(
    ctx: &ssbvb_gpu::GpuContext,
    pipeline: &ssbvb_graph::ResolvedPipeline,
    scene: Scene,
    camera: &Camera,
    size: (u32, u32),
    frames: usize,
) -> Result<(TimedFrames, Vec<u8>)> {
    let mut gpu_scene =
        ssbvb_engine::upload::upload_scene(ctx, scene, ssbvb_engine::upload::Residency::Whole)?;
    let mut renderer = ssbvb_engine::upload::renderer(ctx, &gpu_scene, pipeline.clone(), size)?;
    let timed = TimedFrames::run(ctx, &mut renderer, &mut gpu_scene, camera, frames)?;
    let i = renderer
        .resource("color")
        .context("the volumetric pipeline has no `color`")?;
    let t = ctx.read_texture(
        &renderer.resources.texture(i).texture,
        ssbvb_gpu::wgpu::TextureAspect::All,
    )?;
    Ok((timed, t.bytes))
}

fn psnr_ssim(gpu: &[u8], reference: &[u8], size: (u32, u32)) -> (f64, Option<f64>, usize) {
    let (mut sq, mut n) = (0.0f64, 0usize);
    let mut a = Vec::with_capacity(gpu.len() / 4 * 3);
    let mut b = Vec::with_capacity(gpu.len() / 4 * 3);
    for (p, q) in gpu.chunks(4).zip(reference.chunks(4)) {
        let drawn = p[3] > 0 || q[3] > 0;
        if drawn {
            sq += (0..3)
                .map(|c| (f64::from(p[c]) - f64::from(q[c])).powi(2))
                .sum::<f64>();
            n += 1;
        }
        a.extend_from_slice(if drawn { &p[..3] } else { &[0, 0, 0] });
        b.extend_from_slice(if drawn { &q[..3] } else { &[0, 0, 0] });
    }
    let psnr = 10.0 * (255.0f64 * 255.0 / (sq / (3 * n.max(1)) as f64).max(1e-12)).log10();
    let ssim = match (
        image::RgbImage::from_raw(size.0, size.1, a),
        image::RgbImage::from_raw(size.0, size.1, b),
    ) {
        (Some(x), Some(y)) => {
            image_compare::rgb_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &x, &y)
                .ok()
                .map(|s| s.score)
        }
        _ => None,
    };
    (psnr, ssim, n)
}

fn camera_at(distance: f64) -> Camera {
    let dir = DVec3::new(0.45, 0.3, 1.0).normalize();
    let mut c = Camera::new(dir * distance, DVec3::ZERO);
    c.near = 0.01;
    c.far = f64::INFINITY;
    c
}

/// The bundled `volumetric.ron`: its text (whose knobs the rows replace) and the pipeline
/// as it is.
struct Volumetric {
    default: ResolvedPipeline,
}

impl Volumetric {
    fn load() -> Result<Self> {
        let path = assets_dir().join("pipelines/volumetric.ron");
        let default = ssbvb_graph::resolve_file(&path).map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(Volumetric { default })
    }

    /// The pipeline with `slice_spacing` and `mip_bias` in place of the file's (a typed
    /// edit of its `VolumeSlices` pass).
    fn with_knobs(&self, spacing: f32, bias: f32) -> Result<ResolvedPipeline> {
        let mut sliced = 0;
        let p = self
            .default
            .edited(|d| {
                sliced = d.edit_kinds(|k| match k {
                    PassKind::VolumeSlices(v) => {
                        v.slice_spacing = spacing;
                        v.mip_bias = bias;
                        true
                    }
                    _ => false,
                });
            })
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        anyhow::ensure!(
            sliced == 1,
            "{} has {sliced} VolumeSlices passes",
            self.default.file
        );
        Ok(p)
    }
}

/// Runs `ssbvb bench --preset volumes`.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let pipelines = Volumetric::load()?;
    let ctx = ssbvb_engine::choice::headless_context(&[&pipelines.default])?;
    let frames = args.frames.unwrap_or(3).max(1);
    let models = assets_dir().join("models");
    let load_mesh =
        |file: &str| -> Result<Mesh> { Ok(ssbvb_voxel::load::load_mesh(&models.join(file))?) };
    let knobs = knob_rows(
        &ctx,
        &pipelines,
        &load_mesh("bunny.obj")?,
        args.first_size((320, 240)),
        frames,
        !args.json,
    )?;
    let mut crossover = Vec::new();
    for (model, file) in [("cow", "cow.obj"), ("bunny", "bunny.obj")] {
        let mesh = load_mesh(file)?;
        crossover.extend(crossover_rows(
            &ctx,
            &pipelines.default,
            model,
            &mesh,
            frames,
            !args.json,
        )?);
    }
    let report = VolumesReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        knobs: knobs_table(&knobs),
        crossover: crossover_table(&crossover),
    };
    let csv = report.knobs.csv() + &report.crossover.csv_rows();
    write_report(&args.out, "volumes", csv, &report, markdown(&report))?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("wrote {}/volumes.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// The knob rows: the cloud and the bunny's coverage volume (`bunny`) alone at `size`,
/// at the default knobs and with the slice spacing and the mip bias swept, each against
/// the emission–absorption integral.
fn knob_rows(
    ctx: &GpuContext,
    pipelines: &Volumetric,
    bunny: &Mesh,
    size: (u32, u32),
    frames: usize,
    log: bool,
) -> Result<Vec<KnobRow>> {
    let subjects: [(&'static str, Arc<RgbaVolume>); 2] = [
        ("cloud", Arc::new(Cloud::default().volume(64)?)),
        ("bunny volume", Arc::new(from_mesh_coverage(bunny, 6)?)),
    ];
    let mut knobs = Vec::new();
    let camera = {
        let mut c = Camera::new(DVec3::new(1.4, 0.9, 2.9), DVec3::ZERO);
        c.near = 0.01;
        c
    };
    for (subject, volume) in &subjects {
        let xf = DAffine3::IDENTITY;
        let placed = [PlacedVolume {
            volume,
            object_to_world: xf,
            level: 0,
        }];
        let reference = integrate::to_srgb8(&integrate::render(&placed, &camera, size, None, 4));
        let mut settings = vec![("default", 0.5f32, 0.0f32)];
        for s in [0.25, 1.0, 2.0, 4.0] {
            settings.push(("slice_spacing", s, 0.0));
        }
        for b in [1.0, 2.0] {
            settings.push(("mip_bias", 0.5, b));
        }
        for (sweep, spacing, bias) in settings {
            let scene = Scene {
                volumes: vec![VolumeObject {
                    name: (*subject).into(),
                    volume: volume.clone(),
                    instances: vec![xf],
                }],
                ..Default::default()
            };
            let pipeline = pipelines.with_knobs(spacing, bias)?;
            let (timed, gpu) = render_frame(ctx, &pipeline, scene, &camera, size, frames)?;
            let s = SliceSettings {
                spacing: f64::from(spacing),
                mip_bias: f64::from(bias),
            };
            let (area, slices, level) = slice_fragments(&[(volume, xf)], &camera, size, s);
            let (psnr, ssim, covered) = psnr_ssim(&gpu, &reference, size);
            let row = KnobRow {
                subject,
                sweep,
                width: size.0,
                height: size.1,
                slice_spacing: spacing,
                mip_bias: bias,
                level,
                slices,
                fragments_per_covered_pixel: area / covered.max(1) as f64,
                covered_pixels: covered,
                frame_ms: timed.frame_ms,
                volume_ms: timed.pass_ms("volumes"),
                psnr_db: psnr,
                ssim,
            };
            if log {
                println!(
                    "{subject} {sweep} spacing {spacing} bias {bias}: level {level}, {slices} \
                     slices, {:.1} fragments / px, volume pass {} ms, PSNR {psnr:.2} dB",
                    row.fragments_per_covered_pixel,
                    row.volume_ms.map_or("-".into(), |v| format!("{v:.2}"))
                );
            }
            knobs.push(row);
        }
    }
    Ok(knobs)
}

/// The crossover rows of `model` (`mesh`): the mesh against its 128³ coverage volume at
/// the default knobs, the object at each height on a square frame.
fn crossover_rows(
    ctx: &GpuContext,
    default: &ResolvedPipeline,
    model: &'static str,
    mesh: &Mesh,
    frames: usize,
    log: bool,
) -> Result<Vec<CrossoverRow>> {
    let square = (768, 768);
    let fov = camera_at(1.0).fov_y_deg.to_radians();
    let volume = Arc::new(from_mesh_coverage(mesh, 7)?);
    let atlas = ssbvb_voxel::rgba_volume::atlas::VolumeAtlas::build(&[&volume], u32::MAX)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut rows = Vec::new();
    for height in [16u32, 24, 32, 48, 64, 128, 256, 512] {
        // The object space's 2 units span `height` of the frame's rows.
        let distance = 2.0 * f64::from(square.1) / (f64::from(height) * 2.0 * (fov * 0.5).tan());
        let cam = camera_at(distance);
        let mesh_scene = Scene {
            triangles: vec![mesh_object(mesh, DAffine3::IDENTITY)],
            ..Default::default()
        };
        let volume_scene = Scene {
            volumes: vec![VolumeObject {
                name: model.into(),
                volume: volume.clone(),
                instances: vec![DAffine3::IDENTITY],
            }],
            ..Default::default()
        };
        let (m, _) = render_frame(ctx, default, mesh_scene, &cam, square, frames)?;
        let (v, img) = render_frame(ctx, default, volume_scene, &cam, square, frames)?;
        let covered = img.chunks(4).filter(|p| p[3] > 0).count();
        let (area, ..) = slice_fragments(
            &[(&volume, DAffine3::IDENTITY)],
            &cam,
            square,
            SliceSettings::default(),
        );
        let (mesh_ms, volume_ms) = (m.pass_ms("triangles"), v.pass_ms("volumes"));
        let row = CrossoverRow {
            model,
            vertices: mesh.positions.len(),
            triangles: mesh.triangles.len(),
            volume_edge: 128,
            screen_height: height,
            mesh_ms,
            volume_ms,
            volume_vs_mesh: mesh_ms.zip(volume_ms).map(|(m, v)| v / m),
            volume_fragments_per_covered_pixel: area / covered.max(1) as f64,
            volume_atlas_bytes: atlas.bytes(),
            volume_dense_bytes: volume.dense_bytes(),
            mesh_bytes: mesh.positions.len() as u64 * 24 + mesh.triangles.len() as u64 * 12,
        };
        if log {
            println!(
                "crossover {model} at {height} px: mesh {} ms, volume {} ms",
                mesh_ms.map_or("-".into(), |v| format!("{v:.2}")),
                volume_ms.map_or("-".into(), |v| format!("{v:.2}"))
            );
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The knob rows: the first table of `volumes.md`, `knobs` in the JSON, and the `knobs`
/// rows of `volumes.csv` (whose columns the crossover rows share: see
/// [`crossover_table`]).
fn knobs_table(rows: &[KnobRow]) -> Table<'_, KnobRow> {
    let none = |name| Column::text(name, |_: &KnobRow| None::<u32>).csv(Fmt::PLAIN);
    Table::new(
        rows,
        vec![
            Column::text("table", |_: &KnobRow| "knobs").csv(Fmt::PLAIN),
            Column::new("subject", |w: &KnobRow| w.subject)
                .csv(Fmt::PLAIN)
                .md("subject", Fmt::PLAIN),
            Column::new("sweep", |w: &KnobRow| w.sweep)
                .csv(Fmt::PLAIN)
                .md("sweep", Fmt::PLAIN),
            Column::new("width", |w: &KnobRow| w.width).csv(Fmt::PLAIN),
            Column::new("height", |w: &KnobRow| w.height).csv(Fmt::PLAIN),
            Column::md_only("size", |w: &KnobRow| size(w.width, w.height)),
            Column::new("slice_spacing", |w: &KnobRow| w.slice_spacing)
                .csv(Fmt::PLAIN)
                .md("spacing (texels)", Fmt::PLAIN)
                .right(),
            Column::new("mip_bias", |w: &KnobRow| w.mip_bias)
                .csv(Fmt::PLAIN)
                .md("mip bias", Fmt::PLAIN)
                .right(),
            Column::new("level", |w: &KnobRow| w.level)
                .csv(Fmt::PLAIN)
                .md("level", Fmt::PLAIN)
                .right(),
            Column::new("slices", |w: &KnobRow| w.slices)
                .csv(Fmt::PLAIN)
                .md("slices", Fmt::PLAIN)
                .right(),
            Column::new("fragments_per_covered_pixel", |w: &KnobRow| {
                w.fragments_per_covered_pixel
            })
            .csv(Fmt::fixed(3))
            .md("fragments / covered px", Fmt::fixed(1))
            .right(),
            Column::new("covered_pixels", |w: &KnobRow| w.covered_pixels).csv(Fmt::PLAIN),
            Column::new("frame_ms", |w: &KnobRow| w.frame_ms)
                .csv(Fmt::fixed(3))
                .md("frame ms", Fmt::fixed(1))
                .right(),
            Column::new("volume_ms", |w: &KnobRow| w.volume_ms)
                .csv(Fmt::fixed(4))
                .md("volume pass ms", Fmt::fixed(2).or("–"))
                .right(),
            Column::new("psnr_db", |w: &KnobRow| w.psnr_db)
                .csv(Fmt::fixed(3))
                .md("PSNR dB", Fmt::fixed(2))
                .right(),
            Column::new("ssim", |w: &KnobRow| w.ssim)
                .csv(Fmt::fixed(4))
                .md("SSIM", Fmt::fixed(4).or("–"))
                .right(),
            none("vertices"),
            none("triangles"),
            none("screen_height"),
            none("mesh_ms"),
            none("volume_vs_mesh"),
        ],
    )
}

/// The crossover rows: the second table of `volumes.md`, `crossover` in the JSON, and the
/// `crossover` rows of `volumes.csv` in the knob rows' columns (the model as the subject,
/// the frame's size and the default knobs, the rest of the knob columns empty).
fn crossover_table(rows: &[CrossoverRow]) -> Table<'_, CrossoverRow> {
    let csv =
        |name, text: &'static str| Column::text(name, move |_: &CrossoverRow| text).csv(Fmt::PLAIN);
    let mib = |header: &str, bytes: fn(&CrossoverRow) -> u64| {
        Column::text("", move |w: &CrossoverRow| bytes(w) as f64 / 1048576.0)
            .md(header, Fmt::fixed(2))
            .right()
    };
    Table::new(
        rows,
        vec![
            csv("table", "crossover"),
            Column::text("subject", |w: &CrossoverRow| w.model).csv(Fmt::PLAIN),
            csv("sweep", ""),
            csv("width", "768"),
            csv("height", "768"),
            csv("slice_spacing", "0.5"),
            csv("mip_bias", "0"),
            csv("level", ""),
            csv("slices", ""),
            Column::text("fragments_per_covered_pixel", |w: &CrossoverRow| {
                w.volume_fragments_per_covered_pixel
            })
            .csv(Fmt::fixed(3)),
            csv("covered_pixels", ""),
            csv("frame_ms", ""),
            Column::text("volume_ms", |w: &CrossoverRow| w.volume_ms).csv(Fmt::fixed(4)),
            csv("psnr_db", ""),
            csv("ssim", ""),
            Column::new("model", |w: &CrossoverRow| w.model).md("model", Fmt::PLAIN),
            Column::new("vertices", |w: &CrossoverRow| w.vertices)
                .csv(Fmt::PLAIN)
                .md("vertices", Fmt::PLAIN)
                .right(),
            Column::new("triangles", |w: &CrossoverRow| w.triangles)
                .csv(Fmt::PLAIN)
                .md("triangles", Fmt::PLAIN)
                .right(),
            mib("mesh MiB", |w| w.mesh_bytes),
            Column::new("volume_edge", |w: &CrossoverRow| w.volume_edge),
            Column::md_only("volume", |w: &CrossoverRow| format!("{}³", w.volume_edge)),
            mib("atlas MiB", |w| w.volume_atlas_bytes),
            mib("dense MiB", |w| w.volume_dense_bytes),
            Column::new("screen_height", |w: &CrossoverRow| w.screen_height)
                .csv(Fmt::PLAIN)
                .md("object height px", Fmt::PLAIN)
                .right(),
            Column::new("mesh_ms", |w: &CrossoverRow| w.mesh_ms)
                .csv(Fmt::fixed(4))
                .md("mesh pass ms", Fmt::fixed(2).or("–"))
                .right(),
            Column::new("volume_ms", |w: &CrossoverRow| w.volume_ms)
                .md("volume pass ms", Fmt::fixed(2).or("–"))
                .right(),
            Column::new("volume_vs_mesh", |w: &CrossoverRow| w.volume_vs_mesh)
                .csv(Fmt::fixed(4))
                .md("volume / mesh", Fmt::fixed(2).or("–"))
                .right(),
            Column::new("volume_fragments_per_covered_pixel", |w: &CrossoverRow| {
                w.volume_fragments_per_covered_pixel
            })
            .md("volume fragments / covered px", Fmt::fixed(1))
            .right(),
            Column::new("volume_atlas_bytes", |w: &CrossoverRow| {
                w.volume_atlas_bytes
            }),
            Column::new("volume_dense_bytes", |w: &CrossoverRow| {
                w.volume_dense_bytes
            }),
            Column::new("mesh_bytes", |w: &CrossoverRow| w.mesh_bytes),
        ],
    )
}

/// `volumes.md`: the knob table, then the crossover.
fn markdown(r: &VolumesReport) -> String {
    format!(
        "# Volumetric billboards\n\nAdapter: {}.\n\n## Knobs\n\n{}\n## Crossover: volume against mesh by screen size (768x768)\n\n{}",
        r.adapter,
        r.knobs.markdown(),
        r.crossover.markdown()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knob_and_crossover_rows_share_the_csv_columns() {
        let header = knobs_table(&[]).csv_header();
        assert_eq!(header, crossover_table(&[]).csv_header());
        assert!(header.starts_with("table,subject,sweep,width,height,"));
    }

    /// The knobs reach the slices pass; the file's own values are the defaults.
    #[test]
    fn knobs_are_typed_edits_of_the_bundled_pipeline() {
        let v = Volumetric::load().unwrap();
        let knobs = |p: &ResolvedPipeline| {
            p.desc.passes.iter().find_map(|s| match &s.kind {
                PassKind::VolumeSlices(v) => Some((v.slice_spacing, v.mip_bias)),
                _ => None,
            })
        };
        assert_eq!(knobs(&v.default), Some((0.5, 0.0)));
        assert_eq!(knobs(&v.with_knobs(2.0, 1.5).unwrap()), Some((2.0, 1.5)));
        assert!(
            v.with_knobs(-1.0, 0.0).is_err(),
            "an invalid spacing is refused"
        );
    }
}
