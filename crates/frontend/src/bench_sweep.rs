//! Speed–accuracy knob sweeps of `ssbvb bench --sweep`: each knob of the default SSBVB
//! pipeline (`assets/pipelines/ssbvb.ron`) changed alone, the frame timed and compared
//! with the CPU reference (coverage, depth, and the shaded composite as PSNR).

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DAffine3;
use serde::Serialize;
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
}

/// The source text of a bundled pipeline file.
pub(crate) fn pipeline_source(file: &str) -> Result<(String, String)> {
    let path = assets_dir().join("pipelines").join(file);
    let src =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    Ok((src, path.display().to_string()))
}

/// Renders `warmup` + `frames` frames (median over the timed ones is the caller's), one
/// profiled frame, and compares the G-buffer (and optionally the composite) with the
/// reference.
pub(crate) fn measure(s: &Setup, src: &str, label: &str, with_psnr: bool) -> Result<Measured> {
    let ctx = s.ctx;
    let pipeline = ssbvb_graph::resolve_str(src, label).map_err(|e| anyhow::anyhow!("{e}"))?;
    let scene = Scene {
        objects: vec![VoxelObject {
            asset: s.asset.clone(),
            instances: vec![DAffine3::IDENTITY],
            lod: s.lod,
        }],
        ..Default::default()
    };
    let mut gpu_scene = GpuScene::new(ctx, scene)?;
    let mut renderer = Renderer::new(ctx, &gpu_scene, pipeline, s.size)?;
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
    })
}

/// Replaces the value of parameter `param` of the single pass of kind `kind`
/// (`kind: Kind(.., param: value, ..)`) with `value`, or adds it when the file leaves it
/// at its default.
pub(crate) fn set_kind_param(src: &str, kind: &str, param: &str, value: &str) -> Result<String> {
    let needle = format!("kind: {kind}(");
    let mut found = src.match_indices(&needle);
    let Some((start, _)) = found.next() else {
        bail!("no pass of kind `{kind}(..)` in the pipeline");
    };
    if found.next().is_some() {
        bail!("more than one pass of kind `{kind}` in the pipeline");
    }
    let open = start + needle.len();
    let close = open
        + src[open..]
            .find(')')
            .with_context(|| format!("unclosed `{kind}(`"))?;
    let args = &src[open..close];
    let key = format!("{param}:");
    let Some(k) = args.find(&key) else {
        // Not written in the file (it has its default): add it.
        let sep = if args.trim().is_empty() { "" } else { ", " };
        return Ok(format!(
            "{}{sep}{param}: {value}{}",
            &src[..close],
            &src[close..]
        ));
    };
    let v_start = k + key.len();
    let v_end = args[v_start..]
        .find(',')
        .map_or(args.len(), |e| v_start + e);
    Ok(format!(
        "{} {value}{}",
        &src[..open + v_start],
        &src[open + v_end..]
    ))
}

/// Replaces the value of `field` (`size`, `count`, ...) in the declaration of resource
/// `resource` (`"name": Kind(.., field: value, ..)`, on one line) with `value`.
pub(crate) fn set_resource_field(
    src: &str,
    resource: &str,
    field: &str,
    value: &str,
) -> Result<String> {
    let key = format!("\"{resource}\":");
    let start = src
        .find(&key)
        .with_context(|| format!("no resource `{resource}` in the pipeline"))?;
    let line_end = src[start..].find('\n').map_or(src.len(), |e| start + e);
    let decl = &src[start..line_end];
    let f = decl
        .find(&format!("{field}:"))
        .with_context(|| format!("resource `{resource}` has no `{field}` on its line"))?;
    let v_start = start + f + field.len() + 1;
    // The value ends at the first `,` or unmatched `)` outside parentheses.
    let mut depth = 0i32;
    let mut v_end = line_end;
    for (i, c) in src[v_start..line_end].char_indices() {
        match c {
            '(' => depth += 1,
            ')' if depth == 0 => {
                v_end = v_start + i;
                break;
            }
            ')' => depth -= 1,
            ',' if depth == 0 => {
                v_end = v_start + i;
                break;
            }
            _ => {}
        }
    }
    Ok(format!("{} {value}{}", &src[..v_start], &src[v_end..]))
}

/// The default SSBVB pipeline with the empty-space prepass and the ray-march filter at
/// `scale` of the screen per axis (their textures and the SSBVB shrink with it); the
/// billboards, smoothing and composite stay at full resolution.
pub(crate) fn with_filter_scale(src: &str, scale: f64) -> Result<String> {
    if scale == 1.0 {
        return Ok(src.to_owned());
    }
    let mut s = src.to_owned();
    for r in ["entry", "prepass_depth"] {
        s = set_resource_field(&s, r, "size", &format!("ScreenScaled({scale:?})"))?;
    }
    set_resource_field(
        &s,
        "ssbvb",
        "count",
        &format!("ScreenPixelsScaled({scale:?})"),
    )
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

fn reference_at(
    asset: &VoxelAsset,
    level: u32,
    camera: &Camera,
    size: (u32, u32),
) -> ReferenceImage {
    let inst = [ssbvb_voxel::reference::Instance {
        lod: &asset.lods[level as usize],
        object_to_world: DAffine3::IDENTITY,
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
    let (base, label) = pipeline_source("ssbvb.ron")?;
    let size = cfg.size;
    let fixed_ref = reference_at(asset, cfg.level, camera, size);
    let mut points: Vec<(&'static str, f64, bool, String)> = Vec::new();
    for &v in cfg.max_steps {
        let src = set_kind_param(&base, "RayMarchFilter", "max_steps", &v.to_string())?;
        points.push(("max_steps", v as f64, v == 1024, src));
    }
    for &v in cfg.size_scale {
        let src = set_kind_param(&base, "Billboards", "size_scale", &format!("{v:?}"))?;
        points.push(("size_scale", v, v == 1.0, src));
    }
    for &v in cfg.max_i {
        let src = set_kind_param(&base, "Smooth", "max_i", &format!("{v:?}"))?;
        points.push(("max_i", v, v == 1.0, src));
    }
    for &v in cfg.min_dist {
        let src = set_kind_param(&base, "Smooth", "min_dist", &format!("{v:?}"))?;
        points.push(("min_dist", v, v == 0.5, src));
    }
    for &v in cfg.resolution_scale {
        let src = with_filter_scale(&base, v)?;
        points.push(("resolution_scale", v, v == 1.0, src));
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
            frame_ms_median: crate::bench_cmd::median(&mut t),
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
    };
    for (knob, value, is_default, src) in points {
        let m = measure(&fixed, &src, &label, true)
            .with_context(|| format!("sweep {knob} = {value}"))?;
        rows.push(to_row(knob, value, is_default, cfg.level, m));
    }
    let max_level = asset.lods.len() as u32 - 1;
    for &bias in cfg.lod_bias {
        let lod = LodPolicy::Auto { bias };
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
        let m = measure(&setup, &base, &label, true)
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
    fn set_kind_param_rewrites_one_parameter() {
        let src = "(kind: Billboards(mode: Flat, size_scale: 1.0),)\n(kind: Smooth(max_i: 1.0, min_dist: 0.5))";
        assert_eq!(
            set_kind_param(src, "Billboards", "size_scale", "1.3").unwrap(),
            "(kind: Billboards(mode: Flat, size_scale: 1.3),)\n(kind: Smooth(max_i: 1.0, min_dist: 0.5))"
        );
        assert_eq!(
            set_kind_param(src, "Smooth", "max_i", "3.0").unwrap(),
            "(kind: Billboards(mode: Flat, size_scale: 1.0),)\n(kind: Smooth(max_i: 3.0, min_dist: 0.5))"
        );
        assert_eq!(
            set_kind_param(src, "Smooth", "extra", "true").unwrap(),
            "(kind: Billboards(mode: Flat, size_scale: 1.0),)\n(kind: Smooth(max_i: 1.0, min_dist: 0.5, extra: true))"
        );
        assert_eq!(
            set_kind_param(
                "kind: CubeRaster()",
                "CubeRaster",
                "merge_full_nodes",
                "false"
            )
            .unwrap(),
            "kind: CubeRaster(merge_full_nodes: false)"
        );
        assert!(set_kind_param(src, "RayMarchFilter", "max_steps", "1").is_err());
    }

    #[test]
    fn set_resource_field_rewrites_one_declaration() {
        let src = "  \"entry\": Texture(format: Rgba32Float, size: Screen),\n  \"ssbvb\": Buffer(layout: VoxelSlot, count: ScreenPixels),\n  \"x\": Texture(format: R8Unorm, size: Fixed(2, 3)),\n";
        let out = set_resource_field(src, "entry", "size", "ScreenScaled(0.5)").unwrap();
        assert!(out.contains("\"entry\": Texture(format: Rgba32Float, size: ScreenScaled(0.5)),"));
        let out = set_resource_field(&out, "x", "size", "Screen").unwrap();
        assert!(
            out.contains("\"x\": Texture(format: R8Unorm, size: Screen),"),
            "{out}"
        );
        let out = set_resource_field(&out, "ssbvb", "count", "Fixed(7)").unwrap();
        assert!(out.contains("count: Fixed(7)),"), "{out}");
        assert!(set_resource_field(src, "nope", "size", "Screen").is_err());
        assert!(set_resource_field(src, "ssbvb", "size", "Screen").is_err());
    }

    #[test]
    fn filter_scale_pipeline_resolves_with_scaled_resources() {
        let (base, label) = pipeline_source("ssbvb.ron").unwrap();
        let src = with_filter_scale(&base, 0.5).unwrap();
        let p = ssbvb_graph::resolve_str(&src, &label).unwrap();
        let entry = p.resource("entry").unwrap();
        match &p.resources[entry].desc {
            ssbvb_graph::ResourceDesc::Texture { size, .. } => {
                assert_eq!(size.resolve((640, 480)), (320, 240))
            }
            _ => panic!("entry is a texture"),
        }
    }
}
