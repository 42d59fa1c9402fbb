//! Speed–accuracy knob sweeps of `ssbvb bench --sweep`: each knob of the paper's SSBVB
//! frame (`assets/pipelines/ssbvb_flat.ron`: one billboard per covered pixel, so the
//! resolution and size knobs act on every pixel's billboard) changed alone, the frame
//! timed and compared with the CPU reference (coverage, depth, and the shaded composite
//! as PSNR).

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DAffine3;
use serde::Serialize;
use ssbvb_graph::{CountDesc, PassKind, ResolvedPipeline, ResourceDesc, SizeDesc};
use ssbvb_passes::{GpuScene, LodPolicy, Profiling, Renderer, Scene, VoxelObject};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::ReferenceImage;

use crate::render_cmd::assets_dir;

/// What one measured configuration gave.
pub(crate) struct Measured {
    /// Wall ms of each timed frame, in order.
    pub times: Vec<f64>,
    pub passes: Vec<ssbvb_passes::PassTiming>,
    pub fill: Option<u32>,
    pub acc: ssbvb_voxel::accuracy::AccuracyReport,
    pub gpu_memory: u64,
    /// PSNR (dB) of the composite output against the reference colours over the pixels
    /// either covers, and that pixel count; only when asked for.
    pub psnr: Option<(f64, usize)>,
    /// Mean SSIM (8×8 windows, RGB, `image-compare`) of the composite against the
    /// reference over the whole image, with pixels neither covers set to black in both
    /// (their backgrounds differ by design); only when asked for.
    pub ssim: Option<f64>,
    /// Hardware-independent counts of the profiled frame (steps per ray, ...).
    pub counters: ssbvb_passes::FrameCounters,
}

/// Everything [`measure`] needs besides the pipeline.
pub(crate) struct Setup<'a> {
    pub ctx: &'a ssbvb_gpu::GpuContext,
    pub asset: &'a Arc<VoxelAsset>,
    pub lod: LodPolicy,
    /// The level the reference was rendered at (the one the renderer picks).
    pub level: u32,
    pub size: (u32, u32),
    pub camera: &'a Camera,
    pub reference: &'a ReferenceImage,
    pub warmup: usize,
    pub frames: usize,
    /// Upload under a GPU budget (pages from memory), converged before the warm-up.
    pub streaming: Option<&'a ssbvb_passes::StreamingOptions>,
}

/// The source text of a bundled pipeline file.
pub(crate) fn bundled_pipeline(file: &str) -> Result<ResolvedPipeline> {
    let path = assets_dir().join("pipelines").join(file);
    ssbvb_graph::resolve_file(&path).map_err(|e| anyhow::anyhow!("{e}"))
}

/// Renders `warmup` + `frames` frames (median over the timed ones is the caller's), one
/// profiled frame, and compares the G-buffer (and optionally the composite) with the
/// reference.
pub(crate) fn measure(s: &Setup, pipeline: ResolvedPipeline, with_psnr: bool) -> Result<Measured> {
    let ctx = s.ctx;
    let scene = Scene {
        objects: vec![VoxelObject {
            asset: s.asset.clone(),
            instances: vec![DAffine3::IDENTITY],
            lod: s.lod,
        }],
        ..Default::default()
    };
    let mut gpu_scene = match &s.streaming {
        Some(o) => GpuScene::streamed(ctx, scene, o)?,
        None => GpuScene::new(ctx, scene)?,
    };
    let mut renderer = Renderer::new(ctx, &gpu_scene, pipeline, s.size)?;
    crate::budget::converge(ctx, &mut renderer, &mut gpu_scene, s.camera, 64)?;
    for _ in 0..s.warmup {
        renderer.render(ctx, &mut gpu_scene, s.camera, Profiling::Off)?;
    }
    ctx.wait_idle()?;
    let mut times = Vec::new();
    for _ in 0..s.frames.max(1) {
        let t0 = Instant::now();
        renderer.render(ctx, &mut gpu_scene, s.camera, Profiling::Off)?;
        ctx.wait_idle()?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let profiling = if ctx.report().is_software {
        Profiling::TimestampsAndWall
    } else {
        Profiling::Timestamps
    };
    let stats = renderer.render(ctx, &mut gpu_scene, s.camera, profiling)?;
    let fill = renderer.fill_count(ctx)?;
    let counters = renderer.counters(ctx)?;
    let hits = ssbvb_passes::measure::gbuffer_hits(ctx, &renderer)?;
    let acc = ssbvb_voxel::accuracy::compare(s.reference, &hits, &[2.0 / (1u64 << s.level) as f64])
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let (psnr, ssim) = if with_psnr {
        let out = ctx.read_texture(
            &renderer.output().texture,
            ssbvb_gpu::wgpu::TextureAspect::All,
        )?;
        let gpu = crate::render_cmd::to_rgba8(&out)?;
        let reference = s.reference.to_rgba8();
        if gpu.len() != reference.len() || hits.len() * 4 != gpu.len() {
            bail!(
                "output {} bytes, reference {} bytes, {} pixels",
                gpu.len(),
                reference.len(),
                hits.len()
            );
        }
        // Pixels either covers: a hole or an extra pixel is an error (object colour
        // against background); pixels neither covers are skipped, as the backgrounds
        // differ by design.
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for (i, (h, r)) in hits.iter().zip(&s.reference.hits).enumerate() {
            if h.is_some() || r.is_some() {
                a.extend_from_slice(&gpu[i * 4..i * 4 + 4]);
                b.extend_from_slice(&reference[i * 4..i * 4 + 4]);
            }
        }
        let n = a.len() / 4;
        let rgb = |img: &[u8], covered_only: bool| {
            let mut px = Vec::with_capacity(hits.len() * 3);
            for (i, (h, r)) in hits.iter().zip(&s.reference.hits).enumerate() {
                if covered_only && h.is_none() && r.is_none() {
                    px.extend_from_slice(&[0, 0, 0]);
                } else {
                    px.extend_from_slice(&img[i * 4..i * 4 + 3]);
                }
            }
            image::RgbImage::from_raw(s.size.0, s.size.1, px)
        };
        let ssim = match (rgb(&gpu, true), rgb(&reference, true)) {
            (Some(x), Some(y)) => image_compare::rgb_similarity_structure(
                &image_compare::Algorithm::MSSIMSimple,
                &x,
                &y,
            )
            .ok()
            .map(|sim| sim.score),
            _ => None,
        };
        (
            ssbvb_voxel::accuracy::psnr_rgba8(&a, &b).map(|p| (p, n)),
            ssim,
        )
    } else {
        (None, None)
    };
    Ok(Measured {
        times,
        passes: stats.passes,
        fill,
        acc,
        gpu_memory: gpu_scene.total_memory(),
        psnr,
        ssim,
        counters,
    })
}

/// `base` with `edit` applied to its pass kinds; an error when `edit` changes none (the
/// pipeline lacks the kind it edits) or the edited pipeline does not resolve.
pub(crate) fn with_kind_edit(
    base: &ResolvedPipeline,
    what: &str,
    edit: impl FnMut(&mut PassKind) -> bool,
) -> Result<ResolvedPipeline> {
    let mut changed = 0;
    let p = base
        .edited(|d| changed = d.edit_kinds(edit))
        .map_err(|e| anyhow::anyhow!("{what}: {e}"))?;
    if changed == 0 {
        bail!("{what}: {} has no pass of the kind this edits", base.file);
    }
    Ok(p)
}

/// The default SSBVB pipeline with the empty-space prepass and the ray-march filter at
/// `scale` of the screen per axis (their textures and the SSBVB shrink with it); the
/// billboards, smoothing and composite stay at full resolution.
pub(crate) fn with_filter_scale(base: &ResolvedPipeline, scale: f64) -> Result<ResolvedPipeline> {
    if scale == 1.0 {
        return Ok(base.clone());
    }
    let scale = scale as f32;
    base.edited(|d| {
        for r in ["entry", "prepass_depth"] {
            if let Some(ResourceDesc::Texture { size, .. }) = d.resource_mut(r) {
                *size = SizeDesc::ScreenScaled(scale);
            }
        }
        if let Some(ResourceDesc::Buffer { count, .. }) = d.resource_mut("ssbvb") {
            *count = CountDesc::ScreenPixelsScaled(scale);
        }
    })
    .map_err(|e| anyhow::anyhow!("resolution scale {scale}: {e}"))
}

/// Sweep sizes.
pub(crate) struct SweepConfig {
    pub size: (u32, u32),
    /// Level of the fixed-level knobs, and the finest level the LOD-bias sweep may pick.
    pub level: u32,
    pub warmup: usize,
    pub frames: usize,
    pub max_steps: &'static [u32],
    pub size_scale: &'static [f64],
    pub max_i: &'static [f64],
    pub min_dist: &'static [f64],
    /// Fractions of the screen the empty-space prepass and the ray-march filter run at.
    pub resolution_scale: &'static [f64],
    pub lod_bias: &'static [i32],
}

/// One sweep point.
#[derive(Debug, Serialize)]
pub(crate) struct SweepRow {
    /// `max_steps`, `size_scale`, `max_i`, `min_dist`, `resolution_scale` or `lod_bias`.
    pub knob: &'static str,
    pub value: f64,
    /// Whether this is the value of the default pipeline.
    pub is_default: bool,
    pub level: u32,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub frame_ms_median: f64,
    pub fill_count: Option<u32>,
    pub coverage_iou: f64,
    pub depth_error_voxels_median: f64,
    /// PSNR (dB) of the composite against the reference over the pixels either covers;
    /// `None` (null) when identical (infinite) or when neither covers any pixel.
    pub psnr_db: Option<f64>,
    pub psnr_pixels: usize,
    /// Mean SSIM of the composite against the reference (see `Measured::ssim`).
    pub ssim: Option<f64>,
}

/// The CPU reference image of `asset` at `level`, seen from `camera` at `size`.
pub(crate) fn reference_at(
    asset: &VoxelAsset,
    level: u32,
    camera: &Camera,
    size: (u32, u32),
) -> ReferenceImage {
    let inst = [ssbvb_voxel::reference::Instance {
        lod: &asset.lods[level as usize],
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    ssbvb_voxel::reference::render(&inst, camera, size.0, size.1, &Default::default())
}

/// Runs every knob sweep; `log` prints a line per point.
pub(crate) fn run_sweeps(
    ctx: &ssbvb_gpu::GpuContext,
    asset: &Arc<VoxelAsset>,
    camera: &Camera,
    cfg: &SweepConfig,
    log: bool,
) -> Result<Vec<SweepRow>> {
    let base = bundled_pipeline("ssbvb_flat.ron")?;
    let size = cfg.size;
    let fixed_ref = reference_at(asset, cfg.level, camera, size);
    let mut points: Vec<(&'static str, f64, bool, ResolvedPipeline)> = Vec::new();
    for &v in cfg.max_steps {
        let p = with_kind_edit(&base, "max_steps", |k| match k {
            PassKind::RayMarchFilter(f) => {
                f.max_steps = v;
                true
            }
            _ => false,
        })?;
        points.push(("max_steps", v as f64, v == 1024, p));
    }
    for &v in cfg.size_scale {
        let p = with_kind_edit(&base, "size_scale", |k| match k {
            PassKind::Billboards(b) => {
                b.size_scale = v as f32;
                true
            }
            _ => false,
        })?;
        points.push(("size_scale", v, v == 1.0, p));
    }
    for &v in cfg.max_i {
        let p = with_kind_edit(&base, "max_i", |k| match k {
            PassKind::Smooth(s) => {
                s.max_i = v as f32;
                true
            }
            _ => false,
        })?;
        points.push(("max_i", v, v == 1.0, p));
    }
    for &v in cfg.min_dist {
        let p = with_kind_edit(&base, "min_dist", |k| match k {
            PassKind::Smooth(s) => {
                s.min_dist = v as f32;
                true
            }
            _ => false,
        })?;
        points.push(("min_dist", v, v == 0.5, p));
    }
    for &v in cfg.resolution_scale {
        points.push((
            "resolution_scale",
            v,
            v == 1.0,
            with_filter_scale(&base, v)?,
        ));
    }
    let mut rows = Vec::new();
    let to_row = |knob: &'static str,
                  value: f64,
                  is_default: bool,
                  level: u32,
                  m: Measured|
     -> SweepRow {
        let mut t = m.times.clone();
        let row = SweepRow {
            knob,
            value,
            is_default,
            level,
            width: size.0,
            height: size.1,
            frames: m.times.len(),
            frame_ms_median: super::run::median(&mut t),
            fill_count: m.fill,
            coverage_iou: m.acc.coverage_iou,
            depth_error_voxels_median: m.acc.depth_error_voxels.median,
            psnr_db: m.psnr.map(|p| p.0).filter(|p| p.is_finite()),
            psnr_pixels: m.psnr.map_or(0, |p| p.1),
            ssim: m.ssim,
        };
        if log {
            eprintln!(
                "sweep {knob:<10} = {value:<6} L{level}: {:.2} ms, IoU {:.4}, depth err {:.3}, PSNR {}",
                row.frame_ms_median,
                row.coverage_iou,
                row.depth_error_voxels_median,
                row.psnr_db.map_or("-".into(), |p| format!("{p:.2} dB"))
            );
        }
        row
    };
    let fixed = Setup {
        ctx,
        asset,
        lod: LodPolicy::Fixed(cfg.level),
        level: cfg.level,
        size,
        camera,
        reference: &fixed_ref,
        warmup: cfg.warmup,
        frames: cfg.frames,
        streaming: None,
    };
    for (knob, value, is_default, pipeline) in points {
        let m =
            measure(&fixed, pipeline, true).with_context(|| format!("sweep {knob} = {value}"))?;
        rows.push(to_row(knob, value, is_default, cfg.level, m));
    }
    let max_level = asset.lods.len() as u32 - 1;
    for &bias in cfg.lod_bias {
        let lod = LodPolicy::Auto {
            bias,
            pixel_error: 1.0,
        };
        let level = ssbvb_passes::gpu_scene::choose_level(
            lod,
            &DAffine3::IDENTITY,
            camera,
            size,
            max_level,
        );
        let reference = reference_at(asset, level, camera, size);
        let setup = Setup {
            lod,
            level,
            reference: &reference,
            ..fixed
        };
        let m = measure(&setup, base.clone(), true)
            .with_context(|| format!("sweep lod_bias = {bias}"))?;
        rows.push(to_row("lod_bias", bias as f64, bias == 0, level, m));
    }
    Ok(rows)
}

/// `sweeps.csv`.
pub(crate) fn csv(rows: &[SweepRow]) -> String {
    let mut s = String::from(
        "knob,value,is_default,level,width,height,frames,frame_ms_median,fill_count,coverage_iou,depth_error_voxels_median,psnr_db,psnr_pixels,ssim\n",
    );
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{:.4},{},{:.6},{:.6},{},{},{}\n",
            r.knob,
            r.value,
            r.is_default,
            r.level,
            r.width,
            r.height,
            r.frames,
            r.frame_ms_median,
            r.fill_count.map_or(String::new(), |f| f.to_string()),
            r.coverage_iou,
            r.depth_error_voxels_median,
            r.psnr_db.map_or(String::new(), |p| format!("{p:.4}")),
            r.psnr_pixels,
            r.ssim.map_or(String::new(), |v| format!("{v:.5}"))
        ));
    }
    s
}

/// The Markdown section of the sweeps.
pub(crate) fn markdown(rows: &[SweepRow]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "\n## Knob sweeps (default SSBVB pipeline, one knob changed at a time)\n\n\
         PSNR: composite output (sRGB RGBA8) vs the CPU reference colours over the pixels either covers (a hole or an extra pixel counts as object against background).\n\n\
         | knob | value | level | size | frame ms (median) | fill | IoU | depth err (vox) | PSNR dB | SSIM |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {}{} | {} | {}x{} | {:.2} | {} | {:.4} | {:.3} | {} | {} |\n",
            r.knob,
            r.value,
            if r.is_default { " (default)" } else { "" },
            r.level,
            r.width,
            r.height,
            r.frame_ms_median,
            r.fill_count.map_or("-".into(), |f| f.to_string()),
            r.coverage_iou,
            r.depth_error_voxels_median,
            r.psnr_db.map_or("-".into(), |p| format!("{p:.2}")),
            r.ssim.map_or("-".into(), |v| format!("{v:.4}"))
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_edits_need_a_pass_of_the_kind() {
        let base = bundled_pipeline("dense_dda.ron").unwrap();
        let err = with_kind_edit(&base, "max_steps", |k| match k {
            PassKind::RayMarchFilter(f) => {
                f.max_steps = 3;
                true
            }
            _ => false,
        })
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("max_steps") && err.contains("dense_dda.ron"),
            "{err}"
        );
    }

    #[test]
    fn filter_scale_pipeline_resolves_with_scaled_resources() {
        let base = bundled_pipeline("ssbvb_flat.ron").unwrap();
        let p = with_filter_scale(&base, 0.5).unwrap();
        let entry = p.resource("entry").unwrap();
        match &p.resources[entry].desc {
            ssbvb_graph::ResourceDesc::Texture { size, .. } => {
                assert_eq!(size.resolve((640, 480)), (320, 240))
            }
            _ => panic!("entry is a texture"),
        }
    }
}
