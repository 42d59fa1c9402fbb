//! Measuring one configuration: its frames timed, one profiled frame, and the G-buffer
//! (and optionally the shaded composite) compared with the CPU reference.

use std::sync::Arc;

use anyhow::{Result, bail};
use glam::DAffine3;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{LodPolicy, StreamingOptions};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::accuracy::GpuHit;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{ReferenceImage, SampleGrid};

use super::frames::{gpu_timed_frames, timed_frames};
use super::models::one_object;

/// What one measured configuration gave.
pub(crate) struct Measured {
    /// Wall ms of each timed frame, in order.
    pub times: Vec<f64>,
    /// GPU ms of each frame timed by timestamps (`None` on software adapters).
    pub gpu_times: Option<Vec<f64>>,
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
    /// Mean FLIP of the composite against the supersampled reference, both over black
    /// (a pixel the reference covers in part compared at its coverage); only when asked
    /// for and a supersampled reference is given.
    pub flip_mean: Option<f64>,
    /// Hardware-independent counts of the profiled frame (steps per ray, ...).
    pub counters: ssbvb_passes::FrameCounters,
    /// With a filter: the share of the pixels holding an SSBVB slot (its ray's first voxel)
    /// whose voxel is the reference's at that pixel. With `unique_voxels` a voxel's slot
    /// sits at the pixel that claimed it, so this measures the march where
    /// `acc.same_voxel_rate` (every covered pixel) cannot.
    pub slot_same_voxel_rate: Option<f64>,
}

/// Everything [`measure`] needs besides the pipeline.
pub(crate) struct Setup<'a> {
    pub ctx: &'a GpuContext,
    pub asset: &'a Arc<VoxelAsset>,
    pub lod: LodPolicy,
    /// The level the reference was rendered at (the one the renderer picks).
    pub level: u32,
    pub size: (u32, u32),
    pub camera: &'a Camera,
    pub reference: &'a ReferenceImage,
    /// The reference with several samples per pixel, for FLIP (`None`: no FLIP).
    pub supersampled: Option<&'a ReferenceImage>,
    pub warmup: usize,
    pub frames: usize,
    /// Upload under a GPU budget (pages from memory), converged before the warm-up.
    pub streaming: Option<&'a StreamingOptions>,
}

/// The CPU reference image of `asset` at `level`, seen from `camera` at `size`.
pub(crate) fn reference_at(
    asset: &VoxelAsset,
    level: u32,
    camera: &Camera,
    size: (u32, u32),
) -> ReferenceImage {
    supersampled_reference_at(asset, level, camera, size, SampleGrid::CENTRE)
}

/// [`reference_at`] with `grid` samples per pixel, box-filtered.
pub(crate) fn supersampled_reference_at(
    asset: &VoxelAsset,
    level: u32,
    camera: &Camera,
    size: (u32, u32),
    grid: SampleGrid,
) -> ReferenceImage {
    let inst = [ssbvb_voxel::reference::Instance {
        lod: &asset.lods[level as usize],
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    let light = Default::default();
    ssbvb_voxel::reference::render_supersampled(&inst, camera, size.0, size.1, &light, grid)
}

/// Renders `warmup` + `frames` frames (median over the timed ones is the caller's), one
/// profiled frame, and compares the G-buffer (and with `with_psnr` the composite) with the
/// reference.
pub(crate) fn measure(s: &Setup, pipeline: ResolvedPipeline, with_psnr: bool) -> Result<Measured> {
    let ctx = s.ctx;
    let scene = one_object(s.asset, s.lod);
    let mut gpu_scene = match &s.streaming {
        Some(o) => ssbvb_engine::upload::upload_scene(
            ctx,
            scene,
            ssbvb_engine::upload::Residency::Streamed(o),
        )?,
        None => {
            ssbvb_engine::upload::upload_scene(ctx, scene, ssbvb_engine::upload::Residency::Whole)?
        }
    };
    let mut renderer = ssbvb_engine::upload::renderer(ctx, &gpu_scene, pipeline, s.size)?;
    ssbvb_engine::budget::converge(ctx, &mut renderer, &mut gpu_scene, s.camera, 64)?;
    // A temporal pipeline's still frame is measured converged: a whole jitter sequence.
    let warmup = if has_temporal_pass(&renderer.pipeline) {
        s.warmup
            .max(ssbvb_passes::kinds::temporal::JITTER_PERIOD as usize)
    } else {
        s.warmup
    };
    for _ in 0..warmup {
        renderer.render(ctx, &mut gpu_scene, s.camera, Profiling::Off)?;
    }
    ctx.wait_idle()?;
    let times = timed_frames(ctx, &mut renderer, &mut gpu_scene, s.camera, s.frames)?;
    let gpu_times = gpu_timed_frames(ctx, &mut renderer, &mut gpu_scene, s.camera, s.frames)?;
    // Pass times from a frame doing the timed frames' work; the work counted in a frame
    // of its own.
    let stats = ssbvb_engine::timing::profiled_frame(ctx, &mut renderer, &mut gpu_scene, s.camera)?;
    let counted =
        ssbvb_engine::timing::counted_frame(ctx, &mut renderer, &mut gpu_scene, s.camera)?;
    let (fill, counters) = (counted.fill_count, counted.counters);
    let hits = ssbvb_passes::measure::gbuffer_hits(ctx, &renderer)?;
    let acc = ssbvb_voxel::accuracy::compare(s.reference, &hits, &[2.0 / (1u64 << s.level) as f64])
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let (psnr, ssim, flip_mean) = if with_psnr {
        composite_error(s, &renderer, &hits)?
    } else {
        (None, None, None)
    };
    let slot_same_voxel_rate = fill.and_then(|_| slot_same_voxel(s.reference, &hits));
    Ok(Measured {
        times,
        gpu_times,
        passes: stats.passes,
        fill,
        acc,
        slot_same_voxel_rate,
        gpu_memory: gpu_scene.total_memory(),
        psnr,
        ssim,
        flip_mean,
        counters,
    })
}

/// Whether `pipeline` anti-aliases over frames (`Temporal`): its frames are jittered.
pub(crate) fn has_temporal_pass(pipeline: &ResolvedPipeline) -> bool {
    pipeline
        .passes
        .iter()
        .any(|p| matches!(p.kind, ssbvb_graph::PassKind::Temporal(_)))
}

/// The share of the pixels holding a slot (a voxel cell, not `u32::MAX`) and covered by the
/// reference whose cell is the reference's (`None` when there are none).
pub(crate) fn slot_same_voxel(reference: &ReferenceImage, hits: &[Option<GpuHit>]) -> Option<f64> {
    let (mut slotted, mut same) = (0usize, 0usize);
    for (r, g) in reference.hits.iter().zip(hits) {
        if let (Some(r), Some(g)) = (r, g)
            && g.cell != [u32::MAX; 3]
        {
            slotted += 1;
            same += (r.cell == g.cell) as usize;
        }
    }
    (slotted > 0).then(|| same as f64 / slotted as f64)
}

/// The RGBA8 bytes of `gpu` and `reference` at the pixels either image covers (`hits`,
/// `reference_hits`): a hole or an extra pixel is an error (object colour against
/// background); pixels neither covers are skipped, as the backgrounds differ by design.
pub(crate) fn covered_rgba<H, R>(
    hits: &[Option<H>],
    reference_hits: &[Option<R>],
    gpu: &[u8],
    reference: &[u8],
) -> (Vec<u8>, Vec<u8>) {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for (i, (h, r)) in hits.iter().zip(reference_hits).enumerate() {
        if h.is_some() || r.is_some() {
            a.extend_from_slice(&gpu[i * 4..i * 4 + 4]);
            b.extend_from_slice(&reference[i * 4..i * 4 + 4]);
        }
    }
    (a, b)
}

/// PSNR (dB) and its pixel count, SSIM, and FLIP of the composite against the reference
/// (see [`Measured`]).
type CompositeError = (Option<(f64, usize)>, Option<f64>, Option<f64>);

/// The [`CompositeError`] of the frame `renderer` drew (G-buffer `hits`).
fn composite_error(
    s: &Setup,
    renderer: &Renderer,
    hits: &[Option<GpuHit>],
) -> Result<CompositeError> {
    let out = s.ctx.read_texture(
        &renderer.output().texture,
        ssbvb_gpu::wgpu::TextureAspect::All,
    )?;
    let gpu = crate::harness::engine::to_rgba8(&out)?;
    let reference = s.reference.to_rgba8();
    if gpu.len() != reference.len() || hits.len() * 4 != gpu.len() {
        bail!(
            "output {} bytes, reference {} bytes, {} pixels",
            gpu.len(),
            reference.len(),
            hits.len()
        );
    }
    let (a, b) = covered_rgba(hits, &s.reference.hits, &gpu, &reference);
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
        (Some(x), Some(y)) => {
            image_compare::rgb_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &x, &y)
                .ok()
                .map(|sim| sim.score)
        }
        _ => None,
    };
    let flip_mean = match s.supersampled {
        Some(sup) => Some(flip_over_black(s.size, &gpu, sup)?),
        None => None,
    };
    Ok((
        ssbvb_voxel::accuracy::psnr_rgba8(&a, &b).map(|p| (p, n)),
        ssim,
        flip_mean,
    ))
}

/// Mean FLIP of the GPU composite against the supersampled reference, both composited over
/// black by their alpha: a temporal pipeline's silhouette pixels are covered in part, as
/// the reference's are (masking by the last frame's G-buffer hits, as before, made them
/// either opaque or black and hid its anti-aliasing).
fn flip_over_black(size: (u32, u32), gpu: &[u8], supersampled: &ReferenceImage) -> Result<f64> {
    let test = crate::flip::over_black(gpu);
    let reference = crate::flip::over_black(&supersampled.to_rgba8());
    crate::flip::flip_rgb8(&reference, &test, size)
}
