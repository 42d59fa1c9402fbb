//! The seed paper's Figure 8 scene for `ssbvb bench --preset paper`: 21 objects, 402 M
//! voxels at 2048³ in the paper, 22 FPS at 720p on a GTX 980. Ours: every model of the
//! paper preset three times (7 × 3 = 21 objects), each turned, in a 7 × 3 grid, at level 11
//! (or the largest of `--levels`), under a GPU budget (512 MiB, or the first
//! `--gpu-budget`), seen from above the front row. Each technique renders until no page is
//! missing, then the timed frames; the last is compared with the CPU reference at the same
//! level (`figure8_<technique>.png` in the output folder is that frame). Pipelines that cannot stream (the ray casters refuse a budget) are reported as
//! skipped, with their reason.

use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use glam::{DAffine3, DQuat, DVec3};
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_passes::Renderer;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference;

use crate::args::BenchArgs;
use crate::harness::techniques::{Technique, refused};
use crate::harness::{bundled_asset, median, technique_pipeline, timed_frames};
use ssbvb_engine::budget::PageSourceRef;

/// The paper's level (2048³).
const LEVEL: u32 = 11;
/// GPU budget of the voxel scene unless `--gpu-budget` names one (MiB).
const BUDGET_MIB: u64 = 512;
/// Copies of each model.
const COPIES: usize = 3;
/// Grid spacing (world units; every object spans [-1, 1]³).
const SPACING: f64 = 2.4;
/// Most frames rendered to converge.
const MAX_FRAMES: usize = 64;

/// One technique on the scene.
#[derive(Debug)]
pub(crate) struct Figure8Time {
    pub(crate) technique: &'static str,
    pub(crate) frame_ms_median: f64,
    pub(crate) frames_to_converge: usize,
    pub(crate) converged: bool,
    pub(crate) coverage_iou: f64,
}

/// What the scene gave.
#[derive(Debug)]
pub(crate) struct Figure8 {
    pub(crate) objects: usize,
    pub(crate) level: u32,
    /// Voxels of the drawn level over every object.
    pub(crate) voxels: u64,
    pub(crate) budget_mib: u64,
    pub(crate) times: Vec<Figure8Time>,
    /// Techniques that could not draw it, and why.
    pub(crate) skipped: Vec<String>,
}

/// Where object `k` (`model`, `copy`) of the grid stands: the models along x, the copies
/// along z, each copy turned by a further 120° about y.
fn placement(model: usize, models: usize, copy: usize) -> DAffine3 {
    let x = (model as f64 - (models as f64 - 1.0) / 2.0) * SPACING;
    let z = (copy as f64 - (COPIES as f64 - 1.0) / 2.0) * SPACING;
    DAffine3::from_rotation_translation(
        DQuat::from_rotation_y((35.0 + 120.0 * copy as f64).to_radians()),
        DVec3::new(x, 0.0, z),
    )
}

/// The camera: above and in front of the grid's middle, the whole grid in view.
fn camera(models: usize) -> Camera {
    let half_width = (models as f64 - 1.0) / 2.0 * SPACING + 1.0;
    Camera {
        fov_y_deg: 40.0,
        ..Camera::new(
            DVec3::new(0.0, 0.5 * half_width, 1.8 * half_width),
            DVec3::new(0.0, -0.6, 0.0),
        )
    }
}

/// Renders the scene of `models` (files under `assets/`) with each technique.
pub(crate) fn run(
    args: &BenchArgs,
    ctx: &GpuContext,
    models: &[&str],
    techniques: &[&'static Technique],
) -> Result<Figure8> {
    let level = args
        .levels
        .as_ref()
        .and_then(|l| l.iter().copied().max())
        .unwrap_or(LEVEL);
    let budget_mib = args
        .gpu_budget
        .as_ref()
        .and_then(|b| b.first().copied())
        .unwrap_or(BUDGET_MIB);
    let size = args.first_size((1280, 720));
    let mut objects = Vec::new();
    let mut sources = Vec::new();
    for (i, m) in models.iter().enumerate() {
        let (asset, outcome) = bundled_asset(&format!("models/{m}"), level)?;
        objects.push(VoxelObject {
            asset,
            instances: (0..COPIES).map(|c| placement(i, models.len(), c)).collect(),
            lod: LodPolicy::Fixed(level),
        });
        sources.push(PageSourceRef::of(&outcome, level));
    }
    let scene = Scene {
        objects,
        ..Default::default()
    };
    let camera = camera(models.len());
    let voxels = scene
        .objects
        .iter()
        .map(|o| o.asset.lods[level as usize].lookup.voxel_count() * o.instances.len() as u64)
        .sum();
    let reference = reference_of(&scene, level, &camera, size);
    let cells = vec![2.0 / (1u64 << level) as f64; scene.objects.len() * COPIES];
    let mut out = Figure8 {
        objects: scene.objects.len() * COPIES,
        level,
        voxels,
        budget_mib,
        times: Vec::new(),
        skipped: Vec::new(),
    };
    for t in techniques {
        let mut notes = Vec::new();
        let options = ssbvb_engine::budget::options(budget_mib, &sources, usize::MAX, &mut notes)?;
        let what = format!(
            "{} Figure 8 ({} objects, level {level})",
            t.name, out.objects
        );
        let measured = (|| -> Result<Figure8Time> {
            let mut s = ssbvb_engine::upload::upload_scene(
                ctx,
                scene.clone(),
                ssbvb_engine::upload::Residency::Streamed(&options),
            )?;
            let mut r = ssbvb_engine::upload::renderer(ctx, &s, technique_pipeline(t)?, size)?;
            let (n, converged) =
                ssbvb_engine::budget::converge(ctx, &mut r, &mut s, &camera, MAX_FRAMES)?;
            let mut times = timed_frames(ctx, &mut r, &mut s, &camera, args.frames.unwrap_or(3))?;
            let hits = ssbvb_passes::measure::gbuffer_hits(ctx, &r)?;
            let acc = ssbvb_voxel::accuracy::compare(&reference, &hits, &cells)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            write_frame(
                ctx,
                &r,
                &args.out.join(format!("figure8_{}.png", t.name)),
                size,
            )?;
            Ok(Figure8Time {
                technique: t.name,
                frame_ms_median: median(&mut times),
                frames_to_converge: n,
                converged,
                coverage_iou: acc.coverage_iou,
            })
        })();
        match measured {
            Ok(m) => {
                if !args.json {
                    eprintln!(
                        "{what}: {:.1} ms median after {} frames to converge{}, IoU {:.4}",
                        m.frame_ms_median,
                        m.frames_to_converge,
                        if m.converged { "" } else { " (not converged)" },
                        m.coverage_iou
                    );
                }
                out.times.push(m);
            }
            // A technique that cannot draw the scene (a budget it refuses, a device
            // limit) is a result of the preset, not its failure.
            Err(e) if cannot_draw(&e) => {
                out.skipped.push(format!("{what}: {e:#}"));
            }
            Err(e) => return Err(e.context(what)),
        }
    }
    Ok(out)
}

/// The renderer's last frame as a PNG (to look at).
fn write_frame(ctx: &GpuContext, r: &Renderer, path: &Path, size: (u32, u32)) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let out = ctx.read_texture(&r.output().texture, ssbvb_gpu::wgpu::TextureAspect::All)?;
    let rgba = crate::harness::engine::to_rgba8(&out)?;
    ssbvb_gpu::readback::write_png_rgba8(path, size.0, size.1, &rgba)?;
    Ok(())
}

/// Whether `e` says the technique cannot draw the scene: a baseline's limits, a pass that
/// needs whole levels (no budget), or a budget below what never leaves.
fn cannot_draw(e: &anyhow::Error) -> bool {
    refused(e)
        || e.chain().any(|c| {
            matches!(
                c.downcast_ref::<ssbvb_passes::PassError>(),
                Some(ssbvb_passes::PassError::NeedsWholeLevels { .. })
            ) || matches!(
                c.downcast_ref::<ssbvb_gpu::ResourceError>(),
                Some(ssbvb_gpu::ResourceError::BudgetTooSmall { .. })
            )
        })
}

/// The CPU reference of `scene` at `level` (the drawn level once converged).
fn reference_of(
    scene: &Scene,
    level: u32,
    camera: &Camera,
    size: (u32, u32),
) -> reference::ReferenceImage {
    let assets: Vec<(&Arc<_>, &Vec<DAffine3>)> = scene
        .objects
        .iter()
        .map(|o| (&o.asset, &o.instances))
        .collect();
    let instances: Vec<reference::Instance> = assets
        .iter()
        .flat_map(|(a, xfs)| {
            xfs.iter().map(|xf| reference::Instance {
                lod: &a.lods[level as usize],
                object_to_world: *xf,
                faces: None,
            })
        })
        .collect();
    reference::render(&instances, camera, size.0, size.1, &scene.light)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_keeps_objects_apart_and_in_view() {
        let models = 7;
        let cam = camera(models);
        let mut centres: Vec<DVec3> = Vec::new();
        for m in 0..models {
            for c in 0..COPIES {
                let p = placement(m, models, c).translation;
                // Boxes of half-diagonal sqrt(3) never overlap at this spacing.
                for q in &centres {
                    assert!((p - *q).length() >= SPACING - 1e-9);
                }
                centres.push(p);
                // In front of the camera, within its vertical field of view.
                let to = p - cam.position;
                let fwd = (cam.look_at - cam.position).normalize();
                assert!(to.dot(fwd) > 0.0);
                let up_angle = (to.normalize().dot(DVec3::Y)).asin().to_degrees()
                    - fwd.dot(DVec3::Y).asin().to_degrees();
                assert!(up_angle.abs() < cam.fov_y_deg / 2.0, "{m} {c}: {up_angle}");
            }
        }
        assert_eq!(centres.len(), 21);
    }
}
