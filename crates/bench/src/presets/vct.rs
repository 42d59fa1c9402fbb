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

use anyhow::Result;
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::Scene;
use ssbvb_graph::{PassKind, ResolvedPipeline, ResourceDesc, SizeDesc};
use ssbvb_passes::measure::lighting::{LitFrame, compare, monte_carlo_reference};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::lighting::LightingSample;
use ssbvb_voxel::lighting::volume::RadianceVolume;
use ssbvb_voxel::progress::NoProgress;

use crate::args::BenchArgs;
use crate::harness::{TimedFrames, bundled_pipeline};
use crate::plot::{Series, plot};
use crate::table::{Column, Fmt, Table, Value, size, write_report};
use ssbvb_engine::assets::assets_dir;

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

#[derive(Debug, Clone)]
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

#[derive(Serialize)]
struct VctReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    samples: u32,
    stride: u32,
    rows: Table<'a, VctRow>,
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

/// `ssbvb_vct.ron` (`base`) with its `ConeTrace` knobs set and its cone targets at `scale`
/// times the screen: a typed edit of the resolved description.
fn pipeline_with(base: &ResolvedPipeline, k: &Knobs) -> Result<ResolvedPipeline> {
    let mut traced = 0;
    let p = base
        .edited(|d| {
            traced = d.edit_kinds(|kind| match kind {
                PassKind::ConeTrace(c) => {
                    c.cones = k.cones;
                    c.aperture = k.aperture;
                    c.step_scale = k.step_scale;
                    c.resolution = k.resolution;
                    true
                }
                _ => false,
            });
            for target in ["occlusion", "indirect"] {
                if let Some(ResourceDesc::Texture { size, .. }) = d.resource_mut(target) {
                    *size = SizeDesc::ScreenScaled(k.scale);
                }
            }
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    anyhow::ensure!(traced == 1, "{} has {traced} ConeTrace passes", base.file);
    Ok(p)
}

impl Knobs {
    /// The file's knobs (`ssbvb_vct.ron`'s `ConeTrace` and cone targets).
    const DEFAULTS: Knobs = Knobs {
        sweep: "default",
        cones: DEFAULT_CONES,
        aperture: DEFAULT_APERTURE,
        step_scale: DEFAULT_STEP_SCALE,
        resolution: DEFAULT_RESOLUTION,
        scale: DEFAULT_SCALE,
    };
}

/// The knobs of the default scene's rows: the defaults, traced at full resolution, and
/// one knob at a time swept.
fn default_scene_knobs(d: Knobs) -> Vec<Knobs> {
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
    settings
}

/// The knobs of the wider scene's rows: the default resolution and finer ones (one
/// volume over the scene spreads its cells as the scene grows).
fn wide_scene_knobs(d: Knobs) -> Vec<Knobs> {
    [DEFAULT_RESOLUTION, 256, 512]
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
        .collect()
}

/// Runs `ssbvb bench --preset vct`.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let plain = bundled_pipeline("ssbvb_unique.ron")?;
    let vct = bundled_pipeline("ssbvb_vct.ron")?;
    let ctx = ssbvb_engine::choice::headless_context(&[&plain, &vct])?;
    let size = args.first_size((640, 480));
    let frames = args.frames.unwrap_or(3).max(1);
    let d = Knobs::DEFAULTS;
    let mut rows = Vec::new();
    for (file, sweeps) in [
        ("default.ron", default_scene_knobs(d)),
        ("bunnies_64.ron", wide_scene_knobs(d)),
    ] {
        let loaded =
            ssbvb_engine::scene_file::load(&assets_dir().join("scenes").join(file), &NoProgress)?;
        let s = SceneRun {
            ctx: &ctx,
            scene: &loaded.scene,
            camera: &loaded.camera,
            file,
            size,
            frames,
        };
        rows.push(measure_plain(&s, &plain)?);
        let mut reference = None;
        for k in &sweeps {
            let row = measure_cones(&s, &vct, k, &mut reference)?;
            if !args.json {
                eprintln!(
                    "vct {file} {}: {} cones, {}°, step {}, res {}, scale {}: frame {:.1} ms, cones {:.1} ms (filter {:.1}); AO error {:.4}, lit {:.2} dB",
                    k.sweep,
                    k.cones,
                    k.aperture,
                    k.step_scale,
                    k.resolution,
                    k.scale,
                    row.frame_ms,
                    row.cone_ms.unwrap_or(f64::NAN),
                    row.filter_ms.unwrap_or(f64::NAN),
                    row.ao_mae.unwrap_or(f64::NAN),
                    row.lit_psnr_db.unwrap_or(f64::NAN)
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
        rows: table(&rows),
    };
    write_report(
        &args.out,
        "vct",
        report.rows.csv(),
        &report,
        markdown(&report),
    )?;
    trade_plot(&args.out, &rows)?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("wrote {}/vct.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// One scene file's rows: what each is measured on.
struct SceneRun<'a> {
    ctx: &'a GpuContext,
    scene: &'a Scene,
    camera: &'a Camera,
    /// The scene file (the rows' `scene`).
    file: &'a str,
    size: (u32, u32),
    frames: usize,
}

/// The cone-lit frame with knobs `k` (`base`: `ssbvb_vct.ron`): the volume
/// built on the CPU, the frame timed, and its lighting compared with the Monte Carlo
/// `reference` (computed on the first call, then reused: it does not depend on the knobs).
fn measure_cones(
    s: &SceneRun,
    base: &ResolvedPipeline,
    k: &Knobs,
    reference: &mut Option<Vec<(usize, LightingSample)>>,
) -> Result<VctRow> {
    let (ctx, scene) = (s.ctx, s.scene);
    let pipeline = pipeline_with(base, k)?;
    let t0 = Instant::now();
    let volume = RadianceVolume::build(
        &ssbvb_passes::kinds::cone_trace::volume_instances(scene),
        &scene.light,
        k.resolution,
    );
    let build_ms = t0.elapsed().as_secs_f64() * 1e3;
    let mut gpu_scene = ssbvb_engine::upload::upload_scene(
        ctx,
        scene.clone(),
        ssbvb_engine::upload::Residency::Whole,
    )?;
    let mut renderer = ssbvb_engine::upload::renderer(ctx, &gpu_scene, pipeline, s.size)?;
    let timed = TimedFrames::run(ctx, &mut renderer, &mut gpu_scene, s.camera, s.frames)?;
    let lit = LitFrame::read(ctx, &renderer)?;
    // The finest level drawn sets the reference's ray offset: a voxel diagonal.
    let level = gpu_scene.lod_histogram().keys().max().copied().unwrap_or(0);
    let near = 3f64.sqrt()
        * ssbvb_voxel::model::cell_size(level)
        * scene.objects.first().map_or(1.0, |o| {
            o.instances
                .first()
                .map_or(1.0, |m| m.matrix3.x_axis.length())
        });
    let reference = reference
        .get_or_insert_with(|| monte_carlo_reference(&lit, scene, s.camera, near, SAMPLES, STRIDE));
    let r = compare(&lit, reference, &scene.light);
    Ok(VctRow {
        scene: s.file.into(),
        sweep: k.sweep,
        width: s.size.0,
        height: s.size.1,
        cones: k.cones,
        aperture_deg: k.aperture,
        step_scale: k.step_scale,
        resolution: k.resolution,
        target_scale: k.scale,
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
    })
}

/// The plain SSBVB frame of the scene: the baseline row.
fn measure_plain(s: &SceneRun, plain: &ResolvedPipeline) -> Result<VctRow> {
    let (ctx, size) = (s.ctx, s.size);
    let mut gpu_scene = ssbvb_engine::upload::upload_scene(
        ctx,
        s.scene.clone(),
        ssbvb_engine::upload::Residency::Whole,
    )?;
    let mut renderer = ssbvb_engine::upload::renderer(ctx, &gpu_scene, plain.clone(), size)?;
    let timed = TimedFrames::run(ctx, &mut renderer, &mut gpu_scene, s.camera, s.frames)?;
    Ok(VctRow {
        scene: s.file.into(),
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

/// The rows of `vct.csv`, `vct.md` and `vct.json`.
fn table(rows: &[VctRow]) -> Table<'_, VctRow> {
    // Optional numbers: 5 digits in the CSV (empty when missing), `–` in the Markdown.
    let opt = |name: &'static str, value: fn(&VctRow) -> Option<f64>, header: &str, md: usize| {
        Column::new(name, move |w: &VctRow| value(w))
            .csv(Fmt::fixed(5))
            .md(header, Fmt::fixed(md).or("–"))
            .right()
    };
    Table::new(
        rows,
        vec![
            Column::new("scene", |w: &VctRow| w.scene.clone())
                .csv(Fmt::PLAIN)
                .md("scene", Fmt::PLAIN),
            Column::new("sweep", |w: &VctRow| w.sweep)
                .csv(Fmt::PLAIN)
                .md("sweep", Fmt::PLAIN),
            Column::new("width", |w: &VctRow| w.width).csv(Fmt::PLAIN),
            Column::new("height", |w: &VctRow| w.height).csv(Fmt::PLAIN),
            Column::md_only("size", |w: &VctRow| size(w.width, w.height)),
            Column::new("cones", |w: &VctRow| w.cones)
                .csv(Fmt::PLAIN)
                .md("cones", Fmt::PLAIN)
                .right(),
            Column::new("aperture_deg", |w: &VctRow| w.aperture_deg)
                .csv(Fmt::PLAIN)
                .md("aperture °", Fmt::PLAIN)
                .right(),
            Column::new("step_scale", |w: &VctRow| w.step_scale)
                .csv(Fmt::PLAIN)
                .md("step scale", Fmt::PLAIN)
                .right(),
            Column::new("resolution", |w: &VctRow| w.resolution).csv(Fmt::PLAIN),
            Column::new("target_scale", |w: &VctRow| w.target_scale)
                .csv(Fmt::PLAIN)
                .md("target scale", Fmt::PLAIN)
                .right(),
            Column::new("volume_dims", |w: &VctRow| Value::json(&w.volume_dims)),
            Column::text("volume_x", |w: &VctRow| w.volume_dims[0]).csv(Fmt::PLAIN),
            Column::text("volume_y", |w: &VctRow| w.volume_dims[1]).csv(Fmt::PLAIN),
            Column::text("volume_z", |w: &VctRow| w.volume_dims[2]).csv(Fmt::PLAIN),
            Column::md_only("volume", |w: &VctRow| {
                let [x, y, z] = w.volume_dims;
                format!("{x}×{y}×{z}")
            }),
            Column::new("volume_mib", |w: &VctRow| w.volume_mib)
                .csv(Fmt::fixed(3))
                .md("MiB", Fmt::fixed(1))
                .right(),
            Column::new("volume_build_ms", |w: &VctRow| w.volume_build_ms)
                .csv(Fmt::fixed(2))
                .md("build ms", Fmt::fixed(0))
                .right(),
            Column::new("frame_ms", |w: &VctRow| w.frame_ms)
                .csv(Fmt::fixed(3))
                .md("frame ms", Fmt::fixed(1))
                .right(),
            opt("cone_ms", |w| w.cone_ms, "cone ms", 1),
            opt("filter_ms", |w| w.filter_ms, "filter ms", 1),
            opt("cone_vs_filter", |w| w.cone_vs_filter, "cone / filter", 2),
            Column::new("compared_pixels", |w: &VctRow| w.compared_pixels)
                .csv(Fmt::PLAIN)
                .md("pixels", Fmt::PLAIN)
                .right(),
            opt("ao_mae", |w| w.ao_mae, "AO error", 4),
            opt("ao_bias", |w| w.ao_bias, "AO bias", 4),
            opt("shadow_mae", |w| w.shadow_mae, "shadow error", 4),
            opt("bounce_mae", |w| w.bounce_mae, "bounce error", 4),
            opt("lit_mae", |w| w.lit_mae, "lit error", 4),
            opt("lit_psnr_db", |w| w.lit_psnr_db, "lit PSNR dB", 2),
        ],
    )
}

/// `vct.md`: title, adapter, the reference's settings and the table.
fn markdown(r: &VctReport) -> String {
    format!(
        "# Voxel cone tracing\n\nAdapter: {}; Monte Carlo: {} rays per term at every {}th row and column.\n\n{}",
        r.adapter,
        r.samples,
        r.stride,
        r.rows.markdown()
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
        series.push(Series {
            name: format!("{knob} = {} (by time)", values.join(", ")),
            points: pts.iter().map(|p| (p.0, p.1)).collect(),
        });
    }
    plot(
        dir,
        "vct_trade.png",
        "Cone tracing: AO error vs cone pass time (bunny on its plane)",
        ("cone pass ms", "AO mean absolute error vs Monte Carlo"),
        &series,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The knobs reach the cone pass and the cone targets, and the defaults are the file's.
    #[test]
    fn knobs_are_typed_edits_of_the_bundled_pipeline() {
        let base = bundled_pipeline("ssbvb_vct.ron").unwrap();
        let d = Knobs::DEFAULTS;
        assert_eq!(pipeline_with(&base, &d).unwrap().desc, base.desc);
        let k = Knobs {
            cones: 16,
            aperture: 30.0,
            step_scale: 2.0,
            resolution: 64,
            scale: 1.0,
            ..d
        };
        let p = pipeline_with(&base, &k).unwrap();
        let cone = p.desc.passes.iter().find_map(|s| match &s.kind {
            PassKind::ConeTrace(c) => Some(*c),
            _ => None,
        });
        let c = cone.unwrap();
        assert_eq!(
            (c.cones, c.aperture, c.step_scale, c.resolution),
            (16, 30.0, 2.0, 64)
        );
        for target in ["occlusion", "indirect"] {
            let r = p
                .desc
                .resources
                .0
                .iter()
                .find(|(n, _)| n == target)
                .unwrap();
            assert!(
                matches!(r.1, ResourceDesc::Texture { size: SizeDesc::ScreenScaled(s), .. } if s == 1.0),
                "{target}: {:?}",
                r.1
            );
        }
    }
}
