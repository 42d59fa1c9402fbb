//! `ssbvb bench --preset dynamic`: the cost of a dynamic object beside a static one (the
//! paper's Table 1 columns "static" and "streamed"). Per bunny level (`--levels`, default
//! 7-9), at the first `--sizes` (default 1280x720): the static frame (the CPU-prepared asset
//! uploaded once), then the bunny twisting and re-voxelized every frame: the update's
//! stages on the GPU (deform, voxelize, LOD chain and lookups, copy into the scene) and the
//! frame after it; and the CPU path for the same update (voxelize and prepare on the CPU),
//! to compare the GPU build with; and an edit (a sphere of radius 8 voxels carved into the
//! bunny, its levels rebuilt on the GPU) against the full rebuild, and the same edit
//! region-local (its blocks recomputed on the CPU, every level spliced on the GPU:
//! `ssbvb_voxel::local_edit`, `ssbvb_passes::level_splice`). Writes dynamic.csv,
//! dynamic.json and dynamic.md.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Result, bail};
use serde::Serialize;
use ssbvb_passes::animated::{AnimatedMesh, Animator, UpdateTimes};
use ssbvb_passes::level_splice::{LevelSplicer, SpliceStats};
use ssbvb_passes::{DynamicRoom, GpuScene, LodPolicy, Profiling, Renderer, Scene, VoxelObject};
use ssbvb_voxel::animate::MeshAnimation;
use ssbvb_voxel::edit::Edit;
use ssbvb_voxel::local_edit::LocalEditor;
use ssbvb_voxel::model::Model;

use super::BenchArgs;
use super::sweep::bundled_pipeline;

const DEFAULT_LEVELS: [u32; 3] = [7, 8, 9];
/// Time step between animated frames (s) and the twist rate (degrees per second).
const STEP: f64 = 1.0 / 30.0;
const RATE: f64 = 90.0;

#[derive(Debug, Serialize)]
struct DynamicRow {
    level: u32,
    width: u32,
    height: u32,
    voxels: u64,
    /// The static bunny's frame (median, ms).
    static_frame_ms: f64,
    /// Median of each update stage over the animated frames (ms).
    #[serde(flatten)]
    update: UpdateTimes,
    update_ms: f64,
    /// The frame after an update (median, ms).
    animated_frame_ms: f64,
    /// (update + frame) / static frame.
    ratio_to_static: f64,
    /// The same update on the CPU: voxelize and prepare (median, ms).
    cpu_update_ms: f64,
    /// cpu_update_ms / update_ms.
    gpu_speedup: f64,
    /// An edit (a sphere of radius 8 voxels around a surface voxel removed): applying it to
    /// the voxel set (CPU) and rebuilding the object's levels on the GPU (median, ms).
    edit_ms: f64,
    /// Voxels the edit removed.
    edit_removed: u64,
    /// edit_ms / the full GPU rebuild (update_ms).
    edit_vs_rebuild: f64,
    /// The same edit region-local: CPU blocks and GPU splice, waited for (median, ms).
    local_edit_ms: f64,
    /// Its CPU part: the edit on the touched blocks, every level's patch (median, ms).
    local_edit_cpu_ms: f64,
    /// Its GPU part: uploading the patches and splicing every level (median, ms).
    local_edit_gpu_ms: f64,
    /// Blocks the edit touched at the finest level, and their side (cells).
    local_edit_blocks: usize,
    local_edit_block_side: u32,
    /// What the splice moved and uploaded (hardware-independent counts).
    #[serde(flatten)]
    local_edit_splice: SpliceStats,
    /// local_edit_ms / the full GPU rebuild (update_ms).
    local_edit_vs_rebuild: f64,
    /// local_edit_ms / rebuilding the levels alone on the GPU (lod_ms + copy_ms).
    local_edit_vs_lod_rebuild: f64,
}

#[derive(Debug, Serialize)]
struct DynamicReport {
    adapter: String,
    adapter_is_software: bool,
    rows: Vec<DynamicRow>,
}

fn median(mut v: Vec<f64>) -> f64 {
    super::run::median(&mut v)
}

/// Runs `ssbvb bench --preset dynamic`.
pub(super) fn run(args: &BenchArgs) -> Result<()> {
    let pipeline = bundled_pipeline("ssbvb.ron")?;
    let ctx = crate::adapter_cmd::headless_context(&[&pipeline])?;
    let animator = Animator::new(&ctx)?;
    let model = crate::render_cmd::assets_dir().join("models/bunny.obj");
    let Model::Mesh(mesh) = ssbvb_voxel::load::load_model(&model)? else {
        bail!("{} is not a mesh", model.display());
    };
    let size = args
        .sizes
        .as_ref()
        .and_then(|s| s.first().copied())
        .unwrap_or((1280, 720));
    let frames = args.frames.unwrap_or(5).max(1);
    let camera = super::matrix::matrix(args).camera;
    let mut rows = Vec::new();
    for &level in args.levels.as_deref().unwrap_or(&DEFAULT_LEVELS) {
        let anim = AnimatedMesh::new(
            0,
            mesh.clone(),
            MeshAnimation::Twist {
                degrees_per_second: RATE,
            },
            level,
        )?;
        let rest = Arc::new(anim.cpu_asset(0.0)?);
        let scene = Scene {
            objects: vec![VoxelObject {
                asset: rest.clone(),
                instances: vec![glam::DAffine3::IDENTITY],
                lod: LodPolicy::Fixed(level),
            }],
            ..Default::default()
        };
        let frame = |gpu_scene: &mut GpuScene, renderer: &mut Renderer| -> Result<f64> {
            let t0 = Instant::now();
            renderer.render(&ctx, gpu_scene, &camera, Profiling::Off)?;
            ctx.wait_idle()?;
            Ok(t0.elapsed().as_secs_f64() * 1e3)
        };
        // Static.
        let mut gpu_scene = GpuScene::new(&ctx, scene.clone())?;
        let mut renderer = Renderer::new(&ctx, &gpu_scene, pipeline.clone(), size)?;
        frame(&mut gpu_scene, &mut renderer)?;
        let static_ms = median(
            (0..frames)
                .map(|_| frame(&mut gpu_scene, &mut renderer))
                .collect::<Result<_>>()?,
        );
        // Dynamic: an update, then the frame, every frame.
        let room = DynamicRoom {
            object: 0,
            growth: 1.5,
        };
        let mut gpu_scene = GpuScene::with_dynamic(&ctx, scene, &[room])?;
        let mut renderer = Renderer::new(&ctx, &gpu_scene, pipeline.clone(), size)?;
        frame(&mut gpu_scene, &mut renderer)?;
        let (mut updates, mut animated, mut cpu) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..frames {
            let t = (i + 1) as f64 * STEP;
            updates.push(animator.update(&ctx, &mut gpu_scene, &anim, t)?);
            animated.push(frame(&mut gpu_scene, &mut renderer)?);
            let t0 = Instant::now();
            anim.cpu_asset(t)?;
            cpu.push(t0.elapsed().as_secs_f64() * 1e3);
        }
        let stage = |f: fn(&UpdateTimes) -> f64| median(updates.iter().map(f).collect());
        let update = UpdateTimes {
            deform_ms: stage(|u| u.deform_ms),
            voxelize_ms: stage(|u| u.voxelize_ms),
            lod_ms: stage(|u| u.lod_ms),
            copy_ms: stage(|u| u.copy_ms),
            voxels: updates.last().map_or(0, |u| u.voxels),
        };
        let update_ms = median(updates.iter().map(UpdateTimes::total_ms).collect());
        // An edit of radius 8 voxels centred on a surface voxel of the rest pose (the
        // middle one in Morton order).
        let finest = ssbvb_voxel::edit::level_voxels(&rest.lods[level as usize]);
        let s = ssbvb_voxel::model::cell_size(level);
        let c = ssbvb_voxel::edit::cell_of(finest.codes[finest.codes.len() / 2])
            .map(|v| (f64::from(v) + 0.5) * s - 1.0);
        let edit = ssbvb_voxel::edit::Edit::RemoveSphere {
            center: (c[0], c[1], c[2]),
            radius: 8.0 * s,
        };
        let (mut edits, mut removed) = (Vec::new(), 0);
        for _ in 0..frames {
            let t0 = Instant::now();
            let (voxels, r) = ssbvb_voxel::edit::apply_edits(&finest, &[edit])?;
            animator.stream(&ctx, &mut gpu_scene, 0, &voxels)?;
            edits.push(t0.elapsed().as_secs_f64() * 1e3);
            removed = r.removed;
        }
        let edit_ms = median(edits);
        // The same edit region-local. The room first holds the levels of `finest` (built
        // on the GPU: codes and lookups equal the CPU's, which is what the patches need);
        // then the ball is carved and filled back in turn, and the carving is timed.
        animator.stream(&ctx, &mut gpu_scene, 0, &finest)?;
        let splicer = LevelSplicer::new(&ctx)?;
        let mut editor = LocalEditor::new(finest.clone());
        let Edit::RemoveSphere { center, radius } = edit else {
            unreachable!("the bench's edit is a carving")
        };
        let refill = Edit::AddSphere {
            center,
            radius,
            color: (0.8, 0.8, 0.8, 1.0),
        };
        let (mut local_cpu, mut local_gpu) = (Vec::new(), Vec::new());
        let mut local_last = (0, 0, SpliceStats::default());
        for i in 0..2 * frames {
            let carve = i % 2 == 0;
            let t0 = Instant::now();
            let local = editor.apply(&[if carve { edit } else { refill }])?;
            let t1 = Instant::now();
            let stats = splicer.apply(&ctx, &mut gpu_scene, 0, &local.patches)?;
            ctx.wait_idle()?;
            if carve {
                local_cpu.push((t1 - t0).as_secs_f64() * 1e3);
                local_gpu.push(t1.elapsed().as_secs_f64() * 1e3);
                local_last = (local.blocks, local.block_side, stats);
            }
        }
        let local_total: Vec<f64> = local_cpu
            .iter()
            .zip(&local_gpu)
            .map(|(a, b)| a + b)
            .collect();
        let local_edit_ms = median(local_total);
        // The object still draws after the splices.
        frame(&mut gpu_scene, &mut renderer)?;
        let animated_ms = median(animated);
        let cpu_ms = median(cpu);
        let row = DynamicRow {
            level,
            width: size.0,
            height: size.1,
            voxels: update.voxels,
            static_frame_ms: static_ms,
            update,
            update_ms,
            animated_frame_ms: animated_ms,
            ratio_to_static: (update_ms + animated_ms) / static_ms,
            cpu_update_ms: cpu_ms,
            gpu_speedup: cpu_ms / update_ms,
            edit_ms,
            edit_removed: removed,
            edit_vs_rebuild: edit_ms / update_ms,
            local_edit_ms,
            local_edit_cpu_ms: median(local_cpu),
            local_edit_gpu_ms: median(local_gpu),
            local_edit_blocks: local_last.0,
            local_edit_block_side: local_last.1,
            local_edit_splice: local_last.2,
            local_edit_vs_rebuild: local_edit_ms / update_ms,
            local_edit_vs_lod_rebuild: local_edit_ms / (update.lod_ms + update.copy_ms),
        };
        if !args.json {
            eprintln!(
                "dynamic L{level}: static {:.1} ms; update {:.1} ms (voxelize {:.1}, LOD {:.1}, copy {:.2}) + frame {:.1} ms; CPU update {:.1} ms; edit {:.1} ms, local {:.1} ms",
                row.static_frame_ms,
                row.update_ms,
                row.update.voxelize_ms,
                row.update.lod_ms,
                row.update.copy_ms,
                row.animated_frame_ms,
                row.cpu_update_ms,
                row.edit_ms,
                row.local_edit_ms
            );
        }
        rows.push(row);
    }
    let report = DynamicReport {
        adapter: ctx.report().to_string(),
        adapter_is_software: ctx.report().is_software,
        rows,
    };
    write(&args.out, &report)?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("wrote {}/dynamic.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

fn write(dir: &Path, r: &DynamicReport) -> Result<()> {
    let mut md = format!(
        "# Dynamic objects\n\nAdapter: {}\n\n| level | size | voxels | static frame ms | update ms | deform | voxelize | LOD | copy | frame after update ms | (update + frame) / static | CPU update ms | CPU / GPU update | edit ms (r = 8 voxels) | voxels removed | edit / rebuild |\n|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        r.adapter
    );
    let mut csv = String::from(
        "level,width,height,voxels,static_frame_ms,update_ms,deform_ms,voxelize_ms,lod_ms,copy_ms,animated_frame_ms,ratio_to_static,cpu_update_ms,gpu_speedup,edit_ms,edit_removed,edit_vs_rebuild,local_edit_ms,local_edit_cpu_ms,local_edit_gpu_ms,local_edit_blocks,local_edit_block_side,local_edit_words_uploaded,local_edit_voxels_rewritten,local_edit_vs_rebuild,local_edit_vs_lod_rebuild\n",
    );
    let mut edits = String::from(
        "\n## The edit, region-local\n\n| level | voxels | whole-set edit ms | local edit ms | CPU ms | GPU ms | blocks | block side | levels spliced | voxels rewritten | nodes rewritten | words uploaded | local / full rebuild | local / levels rebuild | local / whole-set edit |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for w in &r.rows {
        let sp = &w.local_edit_splice;
        edits.push_str(&format!(
            "| {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {} | {} | {} | {} | {} | {:.4} | {:.3} | {:.3} |\n",
            w.level, w.voxels, w.edit_ms, w.local_edit_ms, w.local_edit_cpu_ms,
            w.local_edit_gpu_ms, w.local_edit_blocks, w.local_edit_block_side, sp.levels,
            sp.voxels_rewritten, sp.nodes_rewritten, sp.words_uploaded,
            w.local_edit_vs_rebuild, w.local_edit_vs_lod_rebuild,
            w.local_edit_ms / w.edit_ms
        ));
    }
    for w in &r.rows {
        md.push_str(&format!(
            "| {} | {}x{} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.1} | {:.2} | {:.1} | {:.2} | {:.1} | {} | {:.3} |\n",
            w.level, w.width, w.height, w.voxels, w.static_frame_ms, w.update_ms, w.update.deform_ms,
            w.update.voxelize_ms, w.update.lod_ms, w.update.copy_ms, w.animated_frame_ms,
            w.ratio_to_static, w.cpu_update_ms, w.gpu_speedup, w.edit_ms, w.edit_removed,
            w.edit_vs_rebuild
        ));
        csv.push_str(&format!(
            "{},{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.4},{:.3},{:.4},{:.3},{},{:.4},{:.3},{:.3},{:.3},{},{},{},{},{:.5},{:.4}\n",
            w.level,
            w.width,
            w.height,
            w.voxels,
            w.static_frame_ms,
            w.update_ms,
            w.update.deform_ms,
            w.update.voxelize_ms,
            w.update.lod_ms,
            w.update.copy_ms,
            w.animated_frame_ms,
            w.ratio_to_static,
            w.cpu_update_ms,
            w.gpu_speedup,
            w.edit_ms,
            w.edit_removed,
            w.edit_vs_rebuild,
            w.local_edit_ms,
            w.local_edit_cpu_ms,
            w.local_edit_gpu_ms,
            w.local_edit_blocks,
            w.local_edit_block_side,
            w.local_edit_splice.words_uploaded,
            w.local_edit_splice.voxels_rewritten,
            w.local_edit_vs_rebuild,
            w.local_edit_vs_lod_rebuild
        ));
    }
    super::report::write_files(
        dir,
        vec![
            ("dynamic.csv", csv),
            ("dynamic.json", serde_json::to_string_pretty(r)?),
            ("dynamic.md", md + &edits),
        ],
    )
}
