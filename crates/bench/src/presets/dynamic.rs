//! `ssbvb bench --preset dynamic`: the cost of a dynamic object beside a static one (the
//! paper's Table 1 columns "static" and "streamed"). Per bunny level (`--levels`, default
//! 7-9), at the first `--sizes` (default 1280x720): the static frame (the CPU-prepared asset
//! uploaded once), then the bunny twisting and re-voxelized every frame by GPU
//! voxelization: the update's stages on the GPU (deform, voxelize, LOD chain and lookups,
//! copy into the scene) and the frame after it; and the CPU path for the same update
//! (voxelize and prepare on the CPU), to compare the GPU build with; and an edit (a sphere
//! of radius 8 voxels carved into the bunny, its levels rebuilt on the GPU) against the
//! full rebuild, and the same edit region-local (its blocks recomputed on the CPU, every
//! level spliced on the GPU: `ssbvb_voxel::local_edit`, `ssbvb_gpu_build::level_splice`).
//! Writes dynamic.csv, dynamic.json and dynamic.md.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Result, bail};
use serde::Serialize;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{DynamicRoom, GpuScene, LodPolicy, Scene};
use ssbvb_gpu_build::animated::{AnimatedMesh, Animator, UpdateTimes};
use ssbvb_gpu_build::level_splice::{LevelSplicer, SpliceStats};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::animate::MeshAnimation;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::edit::Edit;
use ssbvb_voxel::local_edit::LocalEditor;
use ssbvb_voxel::model::{Mesh, Model};
use ssbvb_voxel::svo::LevelVoxels;

use crate::args::BenchArgs;
use crate::harness::{bench_camera, bundled_pipeline, median, one_object};
use crate::table::{Column, Fmt, Table, Value, size, write_report};
use ssbvb_engine::assets::assets_dir;

const DEFAULT_LEVELS: [u32; 3] = [7, 8, 9];
/// Time step between animated frames (s) and the twist rate (degrees per second).
const STEP: f64 = 1.0 / 30.0;
const RATE: f64 = 90.0;

#[derive(Debug)]
struct DynamicRow {
    level: u32,
    width: u32,
    height: u32,
    voxels: u64,
    /// The static bunny's frame (median, ms).
    static_frame_ms: f64,
    /// Median of each update stage over the animated frames (ms).
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
    local_edit_splice: SpliceStats,
    /// local_edit_ms / the full GPU rebuild (update_ms).
    local_edit_vs_rebuild: f64,
    /// local_edit_ms / rebuilding the levels alone on the GPU (lod_ms + copy_ms).
    local_edit_vs_lod_rebuild: f64,
}

#[derive(Serialize)]
struct DynamicReport<'a> {
    adapter: String,
    adapter_is_software: bool,
    rows: Table<'a, DynamicRow>,
}

/// The median of `v` (see `harness::median`).
fn median_of(mut v: Vec<f64>) -> f64 {
    median(&mut v)
}

/// What every level is measured with.
struct Bench<'a> {
    ctx: &'a GpuContext,
    animator: &'a Animator,
    pipeline: &'a ResolvedPipeline,
    mesh: &'a Mesh,
    size: (u32, u32),
    frames: usize,
    camera: Camera,
}

impl Bench<'_> {
    /// Renders one frame of `gpu_scene`, waited for, and returns its wall time (ms).
    fn frame(&self, gpu_scene: &mut GpuScene, renderer: &mut Renderer) -> Result<f64> {
        let t0 = Instant::now();
        renderer.render(self.ctx, gpu_scene, &self.camera, Profiling::Off)?;
        self.ctx.wait_idle()?;
        Ok(t0.elapsed().as_secs_f64() * 1e3)
    }

    /// A renderer of `gpu_scene` at the bench's size, its first frame rendered (untimed).
    fn renderer(&self, gpu_scene: &mut GpuScene) -> Result<Renderer> {
        let mut renderer =
            ssbvb_engine::upload::renderer(self.ctx, gpu_scene, self.pipeline.clone(), self.size)?;
        self.frame(gpu_scene, &mut renderer)?;
        Ok(renderer)
    }
}

/// Runs `ssbvb bench --preset dynamic`.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let pipeline = bundled_pipeline("ssbvb_unique.ron")?;
    let ctx = ssbvb_engine::choice::headless_context(&[&pipeline])?;
    let animator = Animator::new(&ctx)?;
    let model = assets_dir().join("models/bunny.obj");
    let Model::Mesh(mesh) = ssbvb_voxel::load::load_model(&model)? else {
        bail!("{} is not a mesh", model.display());
    };
    let bench = Bench {
        ctx: &ctx,
        animator: &animator,
        pipeline: &pipeline,
        mesh: &mesh,
        size: args.first_size((1280, 720)),
        frames: args.frames.unwrap_or(5).max(1),
        camera: bench_camera(),
    };
    let mut rows = Vec::new();
    for &level in args.levels.as_deref().unwrap_or(&DEFAULT_LEVELS) {
        let row = measure_level(&bench, level)?;
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
        rows: table(&rows),
    };
    let md = markdown(&report) + &edits_markdown(&rows);
    write_report(&args.out, "dynamic", report.rows.csv(), &report, md)?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("wrote {}/dynamic.{{csv,json,md}}", args.out.display());
    }
    Ok(())
}

/// The bunny at `level`: static, animated, carved whole-set and region-local.
fn measure_level(b: &Bench, level: u32) -> Result<DynamicRow> {
    let anim = AnimatedMesh::new(
        0,
        b.mesh.clone(),
        MeshAnimation::Twist {
            degrees_per_second: RATE,
        },
        level,
    )?;
    let rest = Arc::new(anim.cpu_asset(0.0)?);
    let scene = one_object(&rest, LodPolicy::Fixed(level));
    let static_ms = static_frame_ms(b, scene.clone())?;
    // Dynamic: an update, then the frame, every frame.
    let room = DynamicRoom {
        object: 0,
        growth: 1.5,
    };
    let mut gpu_scene = ssbvb_engine::upload::upload_scene(
        b.ctx,
        scene,
        ssbvb_engine::upload::Residency::Dynamic(&[room]),
    )?;
    let mut renderer = b.renderer(&mut gpu_scene)?;
    let animated = animate(b, &anim, &mut gpu_scene, &mut renderer)?;
    let finest = ssbvb_voxel::edit::level_voxels(&rest.lods[level as usize]);
    let edit = carving(&finest, level);
    let (edit_ms, removed) = whole_set_edit(b, &mut gpu_scene, &finest, edit)?;
    let local = local_edit(b, &mut gpu_scene, &finest, edit)?;
    // The object still draws after the splices.
    b.frame(&mut gpu_scene, &mut renderer)?;
    let update = animated.stages();
    let update_ms = median_of(animated.updates.iter().map(UpdateTimes::total_ms).collect());
    let animated_ms = median_of(animated.frames);
    let cpu_ms = median_of(animated.cpu);
    Ok(DynamicRow {
        level,
        width: b.size.0,
        height: b.size.1,
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
        local_edit_ms: local.total_ms,
        local_edit_cpu_ms: median_of(local.cpu),
        local_edit_gpu_ms: median_of(local.gpu),
        local_edit_blocks: local.blocks,
        local_edit_block_side: local.block_side,
        local_edit_splice: local.stats,
        local_edit_vs_rebuild: local.total_ms / update_ms,
        local_edit_vs_lod_rebuild: local.total_ms / (update.lod_ms + update.copy_ms),
    })
}

/// The static bunny's median frame (the CPU-prepared asset uploaded once).
fn static_frame_ms(b: &Bench, scene: Scene) -> Result<f64> {
    let mut gpu_scene =
        ssbvb_engine::upload::upload_scene(b.ctx, scene, ssbvb_engine::upload::Residency::Whole)?;
    let mut renderer = b.renderer(&mut gpu_scene)?;
    Ok(median_of(
        (0..b.frames)
            .map(|_| b.frame(&mut gpu_scene, &mut renderer))
            .collect::<Result<_>>()?,
    ))
}

/// The animated frames: each update's stages, the frame after it, and the same update on
/// the CPU (ms).
struct Animated {
    updates: Vec<UpdateTimes>,
    frames: Vec<f64>,
    cpu: Vec<f64>,
}

impl Animated {
    /// The median of each update stage, and the voxels of the last update.
    fn stages(&self) -> UpdateTimes {
        let stage = |f: fn(&UpdateTimes) -> f64| median_of(self.updates.iter().map(f).collect());
        UpdateTimes {
            deform_ms: stage(|u| u.deform_ms),
            voxelize_ms: stage(|u| u.voxelize_ms),
            lod_ms: stage(|u| u.lod_ms),
            copy_ms: stage(|u| u.copy_ms),
            voxels: self.updates.last().map_or(0, |u| u.voxels),
        }
    }
}

/// Twists and re-voxelizes `anim` on the GPU every frame, a time step apart, and times
/// each update, the frame after it, and the same update on the CPU.
fn animate(
    b: &Bench,
    anim: &AnimatedMesh,
    gpu_scene: &mut GpuScene,
    renderer: &mut Renderer,
) -> Result<Animated> {
    let mut out = Animated {
        updates: Vec::new(),
        frames: Vec::new(),
        cpu: Vec::new(),
    };
    for i in 0..b.frames {
        let t = (i + 1) as f64 * STEP;
        out.updates
            .push(b.animator.update(b.ctx, gpu_scene, anim, t)?);
        out.frames.push(b.frame(gpu_scene, renderer)?);
        let t0 = Instant::now();
        anim.cpu_asset(t)?;
        out.cpu.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    Ok(out)
}

/// An edit of radius 8 voxels centred on a surface voxel of the rest pose `finest` (the
/// middle one in Morton order) at `level`.
fn carving(finest: &LevelVoxels, level: u32) -> Edit {
    let s = ssbvb_voxel::model::cell_size(level);
    let c = ssbvb_voxel::edit::cell_of(finest.codes[finest.codes.len() / 2])
        .map(|v| (f64::from(v) + 0.5) * s - 1.0);
    Edit::RemoveSphere {
        center: (c[0], c[1], c[2]),
        radius: 8.0 * s,
    }
}

/// Applies `edit` to the whole voxel set `finest` (CPU) and rebuilds the object's levels
/// on the GPU, every frame: the median time (ms) and the voxels it removed.
fn whole_set_edit(
    b: &Bench,
    gpu_scene: &mut GpuScene,
    finest: &LevelVoxels,
    edit: Edit,
) -> Result<(f64, u64)> {
    let (mut edits, mut removed) = (Vec::new(), 0);
    for _ in 0..b.frames {
        let t0 = Instant::now();
        let (voxels, r) = ssbvb_voxel::edit::apply_edits(finest, &[edit])?;
        b.animator.stream(b.ctx, gpu_scene, 0, &voxels)?;
        edits.push(t0.elapsed().as_secs_f64() * 1e3);
        removed = r.removed;
    }
    Ok((median_of(edits), removed))
}

/// The region-local edit: its median time and parts, and what the last carving touched.
struct LocalEdit {
    /// Median of CPU + GPU (ms).
    total_ms: f64,
    /// The CPU part of each carving (ms).
    cpu: Vec<f64>,
    /// The GPU part of each carving (ms).
    gpu: Vec<f64>,
    blocks: usize,
    block_side: u32,
    stats: SpliceStats,
}

/// The same edit region-local. The room first holds the levels of `finest` (built on the
/// GPU: codes and lookups equal the CPU's, which is what the patches need); then the ball
/// is carved and filled back in turn, and the carving is timed.
fn local_edit(
    b: &Bench,
    gpu_scene: &mut GpuScene,
    finest: &LevelVoxels,
    edit: Edit,
) -> Result<LocalEdit> {
    b.animator.stream(b.ctx, gpu_scene, 0, finest)?;
    let splicer = LevelSplicer::new(b.ctx)?;
    let mut editor = LocalEditor::new(finest.clone());
    let Edit::RemoveSphere { center, radius } = edit else {
        unreachable!("the bench's edit is a carving")
    };
    let refill = Edit::AddSphere {
        center,
        radius,
        color: (0.8, 0.8, 0.8, 1.0),
    };
    let (mut cpu, mut gpu) = (Vec::new(), Vec::new());
    let mut last = (0, 0, SpliceStats::default());
    for i in 0..2 * b.frames {
        let carve = i % 2 == 0;
        let t0 = Instant::now();
        let local = editor.apply(&[if carve { edit } else { refill }])?;
        let t1 = Instant::now();
        let stats = splicer.apply(b.ctx, gpu_scene, 0, &local.patches)?;
        b.ctx.wait_idle()?;
        if carve {
            cpu.push((t1 - t0).as_secs_f64() * 1e3);
            gpu.push(t1.elapsed().as_secs_f64() * 1e3);
            last = (local.blocks, local.block_side, stats);
        }
    }
    let total: Vec<f64> = cpu.iter().zip(&gpu).map(|(a, b)| a + b).collect();
    Ok(LocalEdit {
        total_ms: median_of(total),
        cpu,
        gpu,
        blocks: last.0,
        block_side: last.1,
        stats: last.2,
    })
}

/// The rows of `dynamic.csv`, `dynamic.json` and the first table of `dynamic.md` (the
/// update's stages flattened into each JSON row, the splice counts likewise).
fn table(rows: &[DynamicRow]) -> Table<'_, DynamicRow> {
    let ms = |name: &'static str, value: fn(&DynamicRow) -> f64, csv: usize| {
        Column::new(name, move |w: &DynamicRow| value(w)).csv(Fmt::fixed(csv))
    };
    Table::new(
        rows,
        vec![
            Column::new("level", |w: &DynamicRow| w.level)
                .csv(Fmt::PLAIN)
                .md("level", Fmt::PLAIN)
                .right(),
            Column::new("width", |w: &DynamicRow| w.width).csv(Fmt::PLAIN),
            Column::new("height", |w: &DynamicRow| w.height).csv(Fmt::PLAIN),
            Column::md_only("size", |w: &DynamicRow| size(w.width, w.height)),
            Column::new("voxels", |w: &DynamicRow| w.voxels)
                .csv(Fmt::PLAIN)
                .md("voxels", Fmt::PLAIN)
                .right(),
            ms("static_frame_ms", |w| w.static_frame_ms, 3)
                .md("static frame ms", Fmt::fixed(1))
                .right(),
            Column::new("update", |w: &DynamicRow| Value::flatten(&w.update)),
            ms("update_ms", |w| w.update_ms, 3)
                .md("update ms", Fmt::fixed(1))
                .right(),
            Column::text("deform_ms", |w: &DynamicRow| w.update.deform_ms)
                .csv(Fmt::fixed(3))
                .md("deform", Fmt::fixed(1))
                .right(),
            Column::text("voxelize_ms", |w: &DynamicRow| w.update.voxelize_ms)
                .csv(Fmt::fixed(3))
                .md("voxelize", Fmt::fixed(1))
                .right(),
            Column::text("lod_ms", |w: &DynamicRow| w.update.lod_ms)
                .csv(Fmt::fixed(3))
                .md("LOD", Fmt::fixed(1))
                .right(),
            Column::text("copy_ms", |w: &DynamicRow| w.update.copy_ms)
                .csv(Fmt::fixed(3))
                .md("copy", Fmt::fixed(2))
                .right(),
            ms("animated_frame_ms", |w| w.animated_frame_ms, 3)
                .md("frame after update ms", Fmt::fixed(1))
                .right(),
            ms("ratio_to_static", |w| w.ratio_to_static, 4)
                .md("(update + frame) / static", Fmt::fixed(2))
                .right(),
            ms("cpu_update_ms", |w| w.cpu_update_ms, 3)
                .md("CPU update ms", Fmt::fixed(1))
                .right(),
            ms("gpu_speedup", |w| w.gpu_speedup, 4)
                .md("CPU / GPU update", Fmt::fixed(2))
                .right(),
            ms("edit_ms", |w| w.edit_ms, 3)
                .md("edit ms (r = 8 voxels)", Fmt::fixed(1))
                .right(),
            Column::new("edit_removed", |w: &DynamicRow| w.edit_removed)
                .csv(Fmt::PLAIN)
                .md("voxels removed", Fmt::PLAIN)
                .right(),
            ms("edit_vs_rebuild", |w| w.edit_vs_rebuild, 4)
                .md("edit / rebuild", Fmt::fixed(3))
                .right(),
            ms("local_edit_ms", |w| w.local_edit_ms, 3),
            ms("local_edit_cpu_ms", |w| w.local_edit_cpu_ms, 3),
            ms("local_edit_gpu_ms", |w| w.local_edit_gpu_ms, 3),
            Column::new("local_edit_blocks", |w: &DynamicRow| w.local_edit_blocks).csv(Fmt::PLAIN),
            Column::new("local_edit_block_side", |w: &DynamicRow| {
                w.local_edit_block_side
            })
            .csv(Fmt::PLAIN),
            Column::new("local_edit_splice", |w: &DynamicRow| {
                Value::flatten(&w.local_edit_splice)
            }),
            Column::text("local_edit_words_uploaded", |w: &DynamicRow| {
                w.local_edit_splice.words_uploaded
            })
            .csv(Fmt::PLAIN),
            Column::text("local_edit_voxels_rewritten", |w: &DynamicRow| {
                w.local_edit_splice.voxels_rewritten
            })
            .csv(Fmt::PLAIN),
            ms("local_edit_vs_rebuild", |w| w.local_edit_vs_rebuild, 5),
            ms(
                "local_edit_vs_lod_rebuild",
                |w| w.local_edit_vs_lod_rebuild,
                4,
            ),
        ],
    )
}

/// The first part of `dynamic.md`: title, adapter and the table.
fn markdown(r: &DynamicReport) -> String {
    format!(
        "# Dynamic objects\n\nAdapter: {}\n\n{}",
        r.adapter,
        r.rows.markdown()
    )
}

/// The second part of `dynamic.md`: the edit, region-local, beside the whole-set edit.
fn edits_markdown(rows: &[DynamicRow]) -> String {
    let col = |header: &str, value: fn(&DynamicRow) -> Value, fmt: Fmt| {
        Column::text("", value).md(header, fmt).right()
    };
    let t = Table::new(
        rows,
        vec![
            col("level", |w| w.level.into(), Fmt::PLAIN),
            col("voxels", |w| w.voxels.into(), Fmt::PLAIN),
            col("whole-set edit ms", |w| w.edit_ms.into(), Fmt::fixed(1)),
            col("local edit ms", |w| w.local_edit_ms.into(), Fmt::fixed(1)),
            col("CPU ms", |w| w.local_edit_cpu_ms.into(), Fmt::fixed(1)),
            col("GPU ms", |w| w.local_edit_gpu_ms.into(), Fmt::fixed(1)),
            col("blocks", |w| w.local_edit_blocks.into(), Fmt::PLAIN),
            col("block side", |w| w.local_edit_block_side.into(), Fmt::PLAIN),
            col(
                "levels spliced",
                |w| w.local_edit_splice.levels.into(),
                Fmt::PLAIN,
            ),
            col(
                "voxels rewritten",
                |w| w.local_edit_splice.voxels_rewritten.into(),
                Fmt::PLAIN,
            ),
            col(
                "nodes rewritten",
                |w| w.local_edit_splice.nodes_rewritten.into(),
                Fmt::PLAIN,
            ),
            col(
                "words uploaded",
                |w| w.local_edit_splice.words_uploaded.into(),
                Fmt::PLAIN,
            ),
            col(
                "local / full rebuild",
                |w| w.local_edit_vs_rebuild.into(),
                Fmt::fixed(4),
            ),
            col(
                "local / levels rebuild",
                |w| w.local_edit_vs_lod_rebuild.into(),
                Fmt::fixed(3),
            ),
            col(
                "local / whole-set edit",
                |w| (w.local_edit_ms / w.edit_ms).into(),
                Fmt::fixed(3),
            ),
        ],
    );
    format!("\n## The edit, region-local\n\n{}", t.markdown())
}
