//! `ssbvb bench --preset vct`: voxel cone tracing's speed against its error. On the bundled
//! default scene (the bunny at level 8 on its plane) at the first `--sizes` (default
//! 640x480): the plain SSBVB frame as the baseline, then the cone-lit frame at the
//! defaults, traced at full resolution, and with one knob at a time swept: cone count,
//! aperture, step scale and the scene volume's resolution. Each row gives the frame time, the
//! cone pass's time beside the ray-march filter's in the same profiled frame, and the
//! errors of AO, shadow, bounce and the lit output against 256-sample Monte Carlo at every
//! 7th row and column (computed once: the reference does not depend on the cone knobs).
//! Then `bunnies_64.ron` (64 instances) at volume resolutions 128, 256 and 512: how the
//! one scene volume spreads over a wider scene. Writes vct.csv, vct.json and vct.md.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use serde::Serialize;
use ssbvb_passes::measure_lighting::{LitFrame, compare, monte_carlo_reference};
use ssbvb_passes::{GpuScene, Renderer, Scene};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::lighting::volume::RadianceVolume;
use ssbvb_voxel::progress::NoProgress;

use super::BenchArgs;
use super::run::TimedFrames;
use crate::render_cmd::assets_dir;

/// Monte Carlo rays per term and receiver.
const SAMPLES: u32 = 256;
/// Every `STRIDE`-th row and column is compared: odd, so at half resolution a quarter of
/// the compared pixels (even row and column) were traced and the rest upsampled.
const STRIDE: u32 = 7;
const DEFAULT_CONES: u32 = 9;
const DEFAULT_APERTURE: f32 = 60.0;
const DEFAULT_RESOLUTION: u32 = 128;
const DEFAULT_STEP_SCALE: f32 = 1.0;
/// The cone targets' size relative to the screen in `ssbvb_vct.ron` (the "target scale"
/// row traces every pixel).
const DEFAULT_SCALE: f32 = 0.5;

#[derive(Debug, Serialize, Clone)]
struct VctRow {
    scene: String,
    /// Which knob this row varies ("baseline": the plain SSBVB frame; "default").
    sweep: &'static str,
    width: u32,
    height: u32,
    cones: u32,
    aperture_deg: f32,
    step_scale: f32,
    resolution: u32,
    /// The cone targets' size relative to the screen.
    target_scale: f32,
    volume_dims: [u32; 3],
    volume_mib: f64,
    /// Building the volume on the CPU (ms).
    volume_build_ms: f64,
    frame_ms: f64,
    cone_ms: Option<f64>,
    filter_ms: Option<f64>,
    /// cone_ms / filter_ms (the target: at most 1).
    cone_vs_filter: Option<f64>,
    compared_pixels: usize,
    ao_mae: Option<f64>,
    ao_bias: Option<f64>,
    shadow_mae: Option<f64>,
    bounce_mae: Option<f64>,
    lit_mae: Option<f64>,
    lit_psnr_db: Option<f64>,
}

#[derive(Debug, Serialize)]
struct VctReport {
    adapter: String,
    adapter_is_software: bool,
    samples: u32,
    stride: u32,
    rows: Vec<VctRow>,
}

/// One row's knobs.
#[derive(Clone, Copy)]
struct Knobs {
    sweep: &'static str,
    cones: u32,
    aperture: f32,
    step_scale: f32,
    resolution: u32,
    scale: f32,
}

/// `ssbvb_vct.ron` with its `ConeTrace(...)` knobs replaced and its cone targets at
/// `scale` times the screen.
fn pipeline_text(base: &str, k: &Knobs) -> String {
    let Knobs {
        cones,
        aperture,
        step_scale,
        resolution,
        scale,
        ..
    } = *k;
    base.lines()
        .map(|l| {
            let t = l.trim_start();
            let target = t.starts_with("\"occlusion\":") || t.starts_with("\"indirect\":");
            if target && t.contains("Texture(") {
                let name = t.split(':').next().unwrap_or_default();
                format!("    {name}: Texture(format: Rgba16Float, size: ScreenScaled({scale:.2})),")
            } else if t.starts_with("kind: ConeTrace(") {
                format!(
                    "      kind: ConeTrace(cones: {cones}, aperture: {aperture:.1}, max_distance: 0.5, step_scale: {step_scale}, shadow_aperture: 6.0, resolution: {resolution}),"
                )
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Runs `ssbvb bench --preset vct`.
pub(super) fn run(args: &BenchArgs) -> Result<()> {
    let plain = super::sweep::bundled_pipeline("ssbvb.ron")?;
    let vct_path = assets_dir().join("pipelines/ssbvb_vct.ron");
    let base = std::fs::read_to_string(&vct_path)
        .with_context(|| format!("reading {}", vct_path.display()))?;
    let vct = super::sweep::bundled_pipeline("ssbvb_vct.ron")?;
    let ctx = crate::adapter_cmd::headless_context(&[&plain, &vct])?;
    let size = args
        .sizes
        .as_ref()
        .and_then(|s| s.first().copied())
        .unwrap_or((640, 480));
    let frames = args.frames.unwrap_or(3).max(1);
    let d = Knobs {
        sweep: "default",
        cones: DEFAULT_CONES,
        aperture: DEFAULT_APERTURE,
        step_scale: DEFAULT_STEP_SCALE,
        resolution: DEFAULT_RESOLUTION,
        scale: DEFAULT_SCALE,
    };
    let mut settings = vec![
        d,
        Knobs {
            sweep: "target scale",
            scale: 1.0,
            ..d
        },
    ];
    for cones in [1, 4, 6, 16, 32] {
        settings.push(Knobs {
            sweep: "cones",
            cones,
            ..d
        });
    }
    for aperture in [30.0, 45.0, 90.0, 120.0] {
        settings.push(Knobs {
            sweep: "aperture",
            aperture,
            ..d
        });
    }
    for step_scale in [0.35, 0.5, 0.75, 1.5] {
        settings.push(Knobs {
            sweep: "step_scale",
            step_scale,
            ..d
        });
    }
    for resolution in [64, 256] {
        settings.push(Knobs {
            sweep: "resolution",
            resolution,
            ..d
        });
    }
    // The wider scene at the default resolution and finer ones: one volume over the scene
    // spreads its cells as the scene grows.
    let wide: Vec<Knobs> = [DEFAULT_RESOLUTION, 256, 512]
        .into_iter()
        .map(|resolution| Knobs {
            sweep: if resolution == DEFAULT_RESOLUTION {
                "default"
            } else {
                "resolution"
            },
            resolution,
            ..d
        })
        .collect();
    let mut rows = Vec::new();
    for (file, sweeps) in [
        ("default.ron", settings.as_slice()),
        ("bunnies_64.ron", wide.as_slice()),
    ] {
        let loaded = crate::scene_file::load(&assets_dir().join("scenes").join(file), &NoProgress)?;
        let (scene, camera) = (loaded.scene, loaded.camera);
        rows.push(measure_plain(
            &ctx, &plain, &scene, &camera, file, size, frames,
        )?);
        let mut reference = None;
        for k in sweeps {
            let Knobs {
                sweep,
                cones,
                aperture,
                step_scale,
                resolution,
                scale,
            } = *k;
            let text = pipeline_text(&base, k);
            let pipeline = ssbvb_graph::resolve_str(&text, "ssbvb_vct.ron (bench)")
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            let t0 = Instant::now();
            let volume = RadianceVolume::build(
                &ssbvb_passes::cone_trace::volume_instances(&scene),
                &scene.light,
                resolution,
            );
            let build_ms = t0.elapsed().as_secs_f64() * 1e3;
            let mut gpu_scene = GpuScene::new(&ctx, scene.clone())?;
            let mut renderer = Renderer::new(&ctx, &gpu_scene, pipeline, size)?;
            let timed = TimedFrames::run(&ctx, &mut renderer, &mut gpu_scene, &camera, frames)?;
            let lit = LitFrame::read(&ctx, &renderer)?;
            // The finest level drawn sets the reference's ray offset: a voxel diagonal.
            let level = gpu_scene.lod_histogram().keys().max().copied().unwrap_or(0);
            let near = 3f64.sqrt()
                * ssbvb_voxel::model::cell_size(level)
                * scene.objects.first().map_or(1.0, |o| {
                    o.instances
                        .first()
                        .map_or(1.0, |m| m.matrix3.x_axis.length())
                });
            let reference = reference.get_or_insert_with(|| {
                monte_carlo_reference(&lit, &scene, &camera, near, SAMPLES, STRIDE)
            });
            let r = compare(&lit, reference, &scene.light);
            let row = VctRow {
                scene: file.into(),
                sweep,
                width: size.0,
                height: size.1,
                cones,
                aperture_deg: aperture,
                step_scale,
                resolution,
                target_scale: scale,
                volume_dims: volume.dims,
                volume_mib: volume.bytes() as f64 / (1 << 20) as f64,
                volume_build_ms: build_ms,
                frame_ms: timed.frame_ms,
                cone_ms: timed.pass_ms("cone_trace"),
                filter_ms: timed.pass_ms("filter"),
                cone_vs_filter: timed
                    .pass_ms("cone_trace")
                    .zip(timed.pass_ms("filter"))
                    .map(|(c, f)| c / f),
                compared_pixels: r.pixels.len(),
                ao_mae: Some(r.ao_mae),
                ao_bias: Some(r.ao_bias),
                shadow_mae: Some(r.shadow_mae),
                bounce_mae: Some(r.indirect_mae),
                lit_mae: Some(r.lit_mae),
                lit_psnr_db: Some(r.lit_psnr),
            };
            if !args.json {
                eprintln!(
                    "vct {file} {sweep}: {cones} cones, {aperture}°, step {step_scale}, res {resolution}, scale {scale}: frame {:.1} ms, cones {:.1} ms (filter {:.1}); AO error {:.4}, lit {:.2} dB",
                    row.frame_ms,
                    row.cone_ms.unwrap_or(f64::NAN),
                    row.filter_ms.unwrap_or(f64::NAN),
                    r.ao_mae,
                    r.lit_psnr
                );
            }
            rows.push(row);
        }
    }
    let report = VctReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        samples: SAMPLES,
        stride: STRIDE,
        rows,
    };
    write(&args.out, &report)?;
    trade_plot(&args.out, &report.rows)?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("wrote {}/vct.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

fn measure_plain(
    ctx: &ssbvb_gpu::GpuContext,
    plain: &ssbvb_graph::ResolvedPipeline,
    scene: &Scene,
    camera: &Camera,
    file: &str,
    size: (u32, u32),
    frames: usize,
) -> Result<VctRow> {
    let mut gpu_scene = GpuScene::new(ctx, scene.clone())?;
    let mut renderer = Renderer::new(ctx, &gpu_scene, plain.clone(), size)?;
    let timed = TimedFrames::run(ctx, &mut renderer, &mut gpu_scene, camera, frames)?;
    Ok(VctRow {
        scene: file.into(),
        sweep: "baseline",
        width: size.0,
        height: size.1,
        cones: 0,
        aperture_deg: 0.0,
        step_scale: 0.0,
        resolution: 0,
        target_scale: 0.0,
        volume_dims: [0; 3],
        volume_mib: 0.0,
        volume_build_ms: 0.0,
        frame_ms: timed.frame_ms,
        cone_ms: None,
        filter_ms: timed.pass_ms("filter"),
        cone_vs_filter: None,
        compared_pixels: 0,
        ao_mae: None,
        ao_bias: None,
        shadow_mae: None,
        bounce_mae: None,
        lit_mae: None,
        lit_psnr_db: None,
    })
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

fn write(dir: &Path, r: &VctReport) -> Result<()> {
    let mut md = format!(
        "# Voxel cone tracing\n\nAdapter: {}; Monte Carlo: {} rays per term at every {}th row and column.\n\n| scene | sweep | size | cones | aperture ° | step scale | target scale | volume | MiB | build ms | frame ms | cone ms | filter ms | cone / filter | pixels | AO error | AO bias | shadow error | bounce error | lit error | lit PSNR dB |\n|---|---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        r.adapter, r.samples, r.stride
    );
    let mut csv = String::from(
        "scene,sweep,width,height,cones,aperture_deg,step_scale,resolution,target_scale,volume_x,volume_y,volume_z,volume_mib,volume_build_ms,frame_ms,cone_ms,filter_ms,cone_vs_filter,compared_pixels,ao_mae,ao_bias,shadow_mae,bounce_mae,lit_mae,lit_psnr_db\n",
    );
    let c = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.5}"));
    for w in &r.rows {
        md.push_str(&format!(
            "| {} | {} | {}x{} | {} | {} | {} | {} | {}×{}×{} | {:.1} | {:.0} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            w.scene, w.sweep, w.width, w.height, w.cones, w.aperture_deg, w.step_scale, w.target_scale, w.volume_dims[0],
            w.volume_dims[1], w.volume_dims[2], w.volume_mib, w.volume_build_ms, w.frame_ms,
            opt(w.cone_ms, 1), opt(w.filter_ms, 1), opt(w.cone_vs_filter, 2), w.compared_pixels,
            opt(w.ao_mae, 4), opt(w.ao_bias, 4), opt(w.shadow_mae, 4), opt(w.bounce_mae, 4),
            opt(w.lit_mae, 4), opt(w.lit_psnr_db, 2)
        ));
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.2},{:.3},{},{},{},{},{},{},{},{},{},{}\n",
            w.scene,
            w.sweep,
            w.width,
            w.height,
            w.cones,
            w.aperture_deg,
            w.step_scale,
            w.resolution,
            w.target_scale,
            w.volume_dims[0],
            w.volume_dims[1],
            w.volume_dims[2],
            w.volume_mib,
            w.volume_build_ms,
            w.frame_ms,
            c(w.cone_ms),
            c(w.filter_ms),
            c(w.cone_vs_filter),
            w.compared_pixels,
            c(w.ao_mae),
            c(w.ao_bias),
            c(w.shadow_mae),
            c(w.bounce_mae),
            c(w.lit_mae),
            c(w.lit_psnr_db)
        ));
    }
    super::report::write_files(
        dir,
        vec![
            ("vct.csv", csv),
            ("vct.json", serde_json::to_string_pretty(r)?),
            ("vct.md", md),
        ],
    )
}

/// `vct_trade.png`: AO error against the cone pass's time on the default scene, one line
/// per swept knob (the default row joins each line).
fn trade_plot(dir: &Path, rows: &[VctRow]) -> Result<()> {
    let mut series = Vec::new();
    for knob in ["cones", "aperture", "step_scale"] {
        let mut pts: Vec<(f64, f64, String)> = rows
            .iter()
            .filter(|r| r.scene == "default.ron" && (r.sweep == knob || r.sweep == "default"))
            .filter_map(|r| {
                let value = match knob {
                    "cones" => r.cones.to_string(),
                    "aperture" => r.aperture_deg.to_string(),
                    _ => r.step_scale.to_string(),
                };
                Some((r.cone_ms?, r.ao_mae?, value))
            })
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let values: Vec<String> = pts.iter().map(|p| p.2.clone()).collect();
        series.push(super::plot::Series {
            name: format!("{knob} = {} (by time)", values.join(", ")),
            points: pts.iter().map(|p| (p.0, p.1)).collect(),
        });
    }
    super::plot::plot(
        dir,
        "vct_trade.png",
        "Cone tracing: AO error vs cone pass time (bunny on its plane)",
        ("cone pass ms", "AO mean absolute error vs Monte Carlo"),
        &series,
    )?;
    Ok(())
}
