//! `ssbvb render`: one frame of a scene (or of a single model) to a PNG, with the SSBVB
//! pipeline on the GPU or with the CPU reference ray caster.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::DVec3;

use crate::cli_values::{parse_samples, parse_vec3};
use serde::Serialize;
use ssbvb_engine::{Content, clipping_warnings};
use ssbvb_gpu::scene::Scene;
use ssbvb_voxel::camera::Camera;

use crate::pipeline_cmd::parse_size;
use crate::progress::BarProgress;
use ssbvb_engine::session::{GpuSession, SessionSource};

/// Arguments of `ssbvb render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// A scene file (.ron) or a model file (.obj, .ply, .gltf, .glb, .vox, .raw); default:
    /// the bundled default scene (the bunny on a ground plane).
    pub input: Option<PathBuf>,
    /// Voxelization level for a model file (2^level cells per axis).
    #[arg(long)]
    pub level: Option<u32>,
    /// Image size.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Camera position `x,y,z`.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub camera_pos: Option<DVec3>,
    /// Point the camera looks at, `x,y,z`.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub look_at: Option<DVec3>,
    /// Up direction `x,y,z` (default +Y).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<DVec3>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub fov_y: Option<f64>,
    /// Near plane distance (default: the scene's, else 0.01).
    #[arg(long, allow_hyphen_values = true)]
    pub near: Option<f64>,
    /// Far plane distance (default: the scene's, else none: an infinite reversed-Z
    /// projection; 0 also means none).
    #[arg(long, allow_hyphen_values = true)]
    pub far: Option<f64>,
    /// Pipeline file (default: the scene's, else the SSBVB form fastest on this adapter:
    /// `pipeline_choice` in `--json` says which and why).
    #[arg(long)]
    pub pipeline: Option<PathBuf>,
    /// Render with the exact CPU reference ray caster instead of the GPU.
    #[arg(long)]
    pub reference: bool,
    /// Samples per pixel of `--reference`, 1 to 1024: one jittered ray in each stratum of
    /// the most nearly square grid (16: 4 × 4; 8: 4 × 2), box-filtered (the ground truth of
    /// an anti-aliased frame); 1 is the pixel centre.
    #[arg(long, default_value_t = 1, value_parser = parse_samples)]
    pub samples: u32,
    /// Output PNG.
    #[arg(short = 'o', long, default_value = "render.png")]
    pub output: PathBuf,
    /// Also write the frame's voxel coverage as a PNG: white where the stencil says a voxel
    /// was drawn, black elsewhere (GPU pipelines with a `depth_stencil` resource; the web
    /// page's `readVoxelMask` reads the same).
    #[arg(long, value_name = "PNG")]
    pub voxel_mask: Option<PathBuf>,
    /// Print the report as one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// GPU memory budget in MiB for the voxel scene (default: the scene's
    /// `gpu_budget_mib`, else none): levels above the coarsest are paged in as rays need
    /// them, and frames are rendered until no page is missing (`--max-frames`).
    #[arg(long, value_name = "MIB")]
    pub gpu_budget: Option<u64>,
    /// Most frames rendered to converge under a GPU budget.
    #[arg(long, default_value_t = 64)]
    pub max_frames: usize,
    /// A soak: render this many frames with the camera moving along `--camera-path`,
    /// sampling process RSS and device memory, before the written frame (`soak` in
    /// `--json`). 1: just the frame.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    pub frames: u64,
    /// Time in seconds at which the scene's animated objects (`animate:`) are drawn: each is
    /// deformed, voxelized and prepared on the GPU for that time (`animation` in `--json`
    /// gives the cost per stage).
    #[arg(long, default_value_t = 0.0)]
    pub time: f64,
    /// The camera's path during `--frames`.
    #[arg(long, value_enum, default_value = "orbit")]
    pub camera_path: crate::soak::CameraPath,
    /// Fault injection for tests: `device-lost@FRAME` destroys the device before soak
    /// frame FRAME (repeatable); the soak recovers (`device_recoveries` in `--json`).
    /// `oom@FRAME` refuses the next large allocation and rebuilds the session there
    /// (`oom@0` without a soak: the first upload); under a budget the budget is halved
    /// until the scene fits, without one the run ends naming the resource.
    #[arg(long, hide = true, value_parser = ssbvb_engine::faults::parse_fault)]
    pub inject_fault: Vec<ssbvb_engine::faults::Fault>,
    /// Time each GPU submission alone (the scene upload, the warm-up, the soak and the
    /// written frame) and list the longest per kind in `--json` `submissions` (a driver
    /// resets the GPU when one runs too long). Serializes the CPU and the GPU. After a
    /// device loss or rebuild the list is the last device's.
    #[arg(long)]
    pub time_submissions: bool,
    /// The device's limits: `adapter` (its own) or `webgpu` (WebGPU's defaults and no
    /// optional feature; `limits` in `--json`).
    #[arg(long, value_enum, default_value = "adapter")]
    pub limits: crate::adapter_cmd::LimitsArg,
    /// How a ray finds the instances it may meet: `lists` (its screen tile's instances,
    /// nearest first) or `hierarchy` (the walk over every visible instance's box), for
    /// comparison; the image is the same.
    #[arg(long, value_enum, default_value = "lists")]
    pub instance_walk: crate::cli_values::InstanceWalk,
}

pub use ssbvb_engine::assets::assets_dir;

#[derive(Serialize)]
struct Report {
    output: String,
    mode: &'static str,
    adapter: Option<String>,
    adapter_is_software: Option<bool>,
    /// The limits the device was created with: `adapter` or `webgpu` (`null` for the
    /// reference).
    limits: Option<&'static str>,
    /// Format substitutions taken because the adapter lacks a pipeline format
    /// (`wanted -> used (resource)`).
    fallbacks: Vec<String>,
    size: [u32; 2],
    /// Samples per pixel (the GPU frame: 1; `--reference --samples N`: N).
    samples: u32,
    camera: Camera,
    pipeline: Option<String>,
    /// How the pipeline was chosen: `--pipeline`, the scene, or the rule for this adapter
    /// (`null` for the reference).
    pipeline_choice: Option<crate::pipeline_choice::PipelineChoice>,
    passes: Vec<ssbvb_passes::PassTiming>,
    frame_wall_ms: f64,
    ssbvb_fill_count: Option<u32>,
    covered_pixels: Option<usize>,
    /// Pixels showing a voxel (GPU: stencil = voxel), what the fill count compares with.
    voxel_pixels: Option<usize>,
    visible_instances: usize,
    /// Hardware-independent counts (march steps, boxes tested, billboards drawn, …); empty
    /// for the reference.
    counters: ssbvb_passes::FrameCounters,
    /// Visible instances per chosen level (JSON keys are the levels).
    lod_histogram: std::collections::BTreeMap<u32, usize>,
    /// Why the image may be empty (nothing in view, everything beyond the far plane), or
    /// coarser than asked (a budget too small for the view).
    warnings: Vec<String>,
    /// Under a GPU budget: how streaming converged and what is resident (`null` without).
    streaming: Option<ssbvb_engine::budget::StreamingReport>,
    /// With `--frames N > 1`: memory at the start and end of the soak (`null` without).
    soak: Option<crate::soak::SoakReport>,
    /// Times the soak lost the GPU device and recreated it (0 without a soak).
    device_recoveries: usize,
    /// With `--time-submissions`: per kind of GPU submission, the longest first.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    submissions: Vec<ssbvb_gpu::submissions::SubmissionTimes>,
    /// With animated objects: the time drawn and each update's cost by stage.
    #[serde(skip_serializing_if = "Option::is_none")]
    animation: Option<ssbvb_engine::animation::AnimationReport>,
    gpu_memory_bytes: Vec<ObjectReport>,
    asset_notes: Vec<String>,
}

#[derive(Serialize)]
struct ObjectReport {
    object: usize,
    #[serde(flatten)]
    memory: ssbvb_gpu::scene::ObjectMemory,
    total: u64,
    /// Lookup plus voxel attributes per voxel, over all levels.
    bytes_per_voxel: f64,
}

/// Opens a scene file (`.ron`), a model file or a prepared asset at `level`, as `ssbvb
/// render` and `ssbvb view` accept them ([`Content::open`]).
pub fn load_input(
    input: &Path,
    level: Option<u32>,
    progress: &dyn ssbvb_voxel::progress::Progress,
) -> Result<Content> {
    Ok(Content::open(input, level, progress)?)
}

/// Runs `ssbvb render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    let progress = BarProgress::new(!args.json && std::io::stderr().is_terminal());
    let default_scene = assets_dir().join("scenes/default.ron");
    let input = args.input.clone().unwrap_or(default_scene);
    let content = load_input(&input, args.level, &progress)?;
    let loader_warnings = content.warning_lines();
    let Content {
        scene,
        mut camera,
        pipeline: scene_pipeline,
        notes,
        gpu_budget_mib,
        page_sources,
        animated,
        ..
    } = content;
    let budget = args.gpu_budget.or(gpu_budget_mib);
    if !args.time.is_finite() {
        bail!(
            "--time must be a finite number of seconds, got {}",
            args.time
        );
    }
    if !animated.is_empty() && budget.is_some() {
        bail!("animated objects cannot be paged under a GPU budget; drop --gpu-budget");
    }
    progress.finish();
    apply_camera_args(args, &mut camera)?;
    let mut warnings = loader_warnings;
    warnings.extend(clipping_warnings(&scene, &camera));
    if !args.reference && args.samples != 1 {
        bail!(
            "--samples {} applies to --reference only (the GPU frame takes one sample per pixel; anti-aliasing is a pipeline pass)",
            args.samples
        );
    }
    if args.reference && args.frames > 1 {
        bail!("--frames (a soak of the GPU renderer) does not apply to --reference");
    }
    if args.reference && !args.inject_fault.is_empty() {
        bail!("--inject-fault injects GPU faults; --reference renders on the CPU");
    }
    ssbvb_engine::faults::check_faults(&args.inject_fault, args.frames)?;
    let report = if args.reference {
        render_reference(args, &scene, &animated, camera, warnings, notes)?
    } else {
        let input = GpuInput {
            scene,
            pipeline: scene_pipeline,
            budget,
            page_sources,
            animated,
        };
        render_gpu(args, input, camera, warnings, notes)?
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report);
    }
    Ok(())
}

/// The camera flags over the scene's camera, each checked.
fn apply_camera_args(args: &RenderArgs, camera: &mut Camera) -> Result<()> {
    if let Some(p) = args.camera_pos {
        camera.position = p;
    }
    if let Some(p) = args.look_at {
        camera.look_at = p;
    }
    if let Some(u) = args.up {
        camera.up = u;
    }
    if let Some(f) = args.fov_y {
        if !(f > 0.0 && f < 180.0) {
            bail!("--fov-y must be in (0, 180) degrees, got {f}");
        }
        camera.fov_y_deg = f;
    }
    if let Some(n) = args.near {
        if !(n > 0.0 && n.is_finite()) {
            bail!("--near must be a positive number, got {n}");
        }
        camera.near = n;
    }
    if let Some(f) = args.far {
        if f.is_nan() || f < 0.0 {
            bail!("--far must be a distance (0 for none), got {f}");
        }
        camera.far = if f == 0.0 { f64::INFINITY } else { f };
    }
    if camera.far.is_finite() && camera.far <= camera.near {
        bail!(
            "the far plane ({}) must be beyond the near plane ({})",
            camera.far,
            camera.near
        );
    }
    if camera.position == camera.look_at {
        bail!("the camera position and --look-at are the same point");
    }
    Ok(())
}

/// `render --reference`: the CPU reference ray caster at the levels the GPU would pick.
fn render_reference(
    args: &RenderArgs,
    scene: &Scene,
    animated: &[ssbvb_gpu_build::animated::AnimatedMesh],
    camera: Camera,
    warnings: Vec<String>,
    notes: Vec<String>,
) -> Result<Report> {
    let start = Instant::now();
    let (w, h) = args.size;
    if args.voxel_mask.is_some() {
        bail!("--voxel-mask reads a GPU frame's stencil; the CPU reference (--reference) has none");
    }
    let scene = ssbvb_engine::animation::posed(scene, animated, args.time)?;
    let mut instances = Vec::new();
    let mut lod_histogram = std::collections::BTreeMap::new();
    for o in &scene.objects {
        let max = o.asset.lods.len() as u32 - 1;
        for xf in &o.instances {
            let level = ssbvb_gpu::scene::choose_level(o.lod, xf, &camera, args.size, max);
            *lod_histogram.entry(level).or_insert(0) += 1;
            instances.push(ssbvb_voxel::reference::Instance {
                lod: &o.asset.lods[level as usize],
                object_to_world: *xf,
                faces: None,
            });
        }
    }
    if !scene.triangles.is_empty() && !args.json {
        eprintln!(
            "note: the CPU reference renders voxel objects only; triangle objects are left out"
        );
    }
    let grid = ssbvb_voxel::reference::SampleGrid::from_count(args.samples)
        .map_err(|e| anyhow::anyhow!("--samples: {e}"))?;
    let img =
        ssbvb_voxel::reference::render_supersampled(&instances, &camera, w, h, &scene.light, grid);
    img.to_png(&args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    Ok(Report {
        output: args.output.display().to_string(),
        mode: "reference",
        samples: args.samples,
        adapter: None,
        adapter_is_software: None,
        limits: None,
        fallbacks: Vec::new(),
        size: [w, h],
        camera,
        pipeline: None,
        pipeline_choice: None,
        passes: Vec::new(),
        frame_wall_ms: start.elapsed().as_secs_f64() * 1e3,
        ssbvb_fill_count: None,
        covered_pixels: Some(img.coverage()),
        voxel_pixels: Some(img.coverage()),
        visible_instances: instances.len(),
        counters: Default::default(),
        lod_histogram,
        warnings,
        streaming: None,
        soak: None,
        device_recoveries: 0,
        submissions: Vec::new(),
        animation: (!animated.is_empty()).then(|| ssbvb_engine::animation::AnimationReport {
            time_s: args.time,
            method: None,
            objects: Vec::new(),
        }),
        gpu_memory_bytes: Vec::new(),
        asset_notes: notes,
    })
}

/// What the GPU path renders: the scene and where its pipeline, pages and animation come
/// from.
struct GpuInput {
    scene: Scene,
    pipeline: Option<PathBuf>,
    budget: Option<u64>,
    page_sources: Vec<Option<ssbvb_engine::budget::PageSourceRef>>,
    animated: Vec<ssbvb_gpu_build::animated::AnimatedMesh>,
}

/// `render` on the GPU: warm-up frames (under a budget, until no page is missing), the
/// optional soak, then the measured frame.
fn render_gpu(
    args: &RenderArgs,
    input: GpuInput,
    camera: Camera,
    mut warnings: Vec<String>,
    mut notes: Vec<String>,
) -> Result<Report> {
    let GpuInput {
        scene,
        pipeline: scene_pipeline,
        budget,
        page_sources,
        animated,
    } = input;
    let (w, h) = args.size;
    let choice = crate::pipeline_choice::choose(args.pipeline.clone(), scene_pipeline)?;
    let pipeline_path = choice.path();
    let mut source = SessionSource {
        scene,
        pipeline: crate::adapter_cmd::resolve(&pipeline_path)?,
        budget,
        page_sources,
        animated,
        time: args.time,
        size: args.size,
        time_submissions: args.time_submissions,
        instance_lists: args.instance_walk == crate::cli_values::InstanceWalk::Lists,
        counting: false,
        limits: crate::adapter_cmd::limits(),
        host: None,
    };
    let opened = source.open_refusing(
        &mut notes,
        ssbvb_engine::faults::runs_out_of_memory_at(&args.inject_fault, 0) && args.frames == 1,
    )?;
    warnings.extend(opened.warnings);
    let mut session = opened.session;
    // Warm-up frames (pipeline caches, lazy allocations; under a budget, until no page
    // is missing), then the measured one.
    let (frames, converged) = ssbvb_engine::budget::converge(
        &session.ctx,
        &mut session.renderer,
        &mut session.scene,
        &camera,
        args.max_frames,
    )?;
    let mut streaming =
        ssbvb_engine::budget::StreamingReport::of(&session.scene, frames, converged);
    ssbvb_engine::budget::streaming_warnings(streaming.as_ref(), frames, &mut warnings);
    let soak = if args.frames > 1 {
        let (s, r) = crate::soak::run(
            session,
            &mut source,
            &camera,
            args.camera_path,
            args.frames as usize,
            &args.inject_fault,
            args.max_frames,
        )?;
        session = s;
        warnings.extend(r.warnings.iter().cloned());
        // The written frame is the scene's camera converged again: under a budget the
        // soak's path (and a recovery's fresh pool) left other pages resident.
        let (frames, converged) = ssbvb_engine::budget::converge(
            &session.ctx,
            &mut session.renderer,
            &mut session.scene,
            &camera,
            args.max_frames,
        )?;
        if source.budget != budget {
            // A rebuild lowered the budget: report the scene the frame is drawn from.
            streaming =
                ssbvb_engine::budget::StreamingReport::of(&session.scene, frames, converged);
        }
        Some(r)
    } else {
        None
    };
    let GpuSession {
        ctx,
        scene: mut gpu_scene,
        mut renderer,
        animation,
    } = session;
    // Timed without counters; the work is counted in a frame of its own below.
    let stats = ssbvb_engine::timing::profiled_frame(&ctx, &mut renderer, &mut gpu_scene, &camera)?;
    let out = ctx.read_texture(
        &renderer.output().texture,
        ssbvb_gpu::wgpu::TextureAspect::All,
    )?;
    let rgba = to_rgba8(&out)?;
    ssbvb_gpu::readback::write_png_rgba8(&args.output, w, h, &rgba)?;
    if let Some(path) = &args.voxel_mask {
        write_voxel_mask(&ctx, &renderer, path, (w, h))?;
    }
    let counted =
        ssbvb_engine::timing::counted_frame(&ctx, &mut renderer, &mut gpu_scene, &camera)?;
    let (fill, counters) = (counted.fill_count, counted.counters);
    Ok(Report {
        output: args.output.display().to_string(),
        mode: "gpu",
        samples: 1,
        adapter: Some(ctx.report().to_string()),
        adapter_is_software: Some(ctx.report().is_software),
        limits: Some(ctx.report().limits),
        fallbacks: crate::adapter_cmd::gpu_fallbacks(&ctx, &renderer.pipeline, animation.as_ref()),
        size: [w, h],
        camera,
        pipeline: Some(pipeline_path.display().to_string()),
        pipeline_choice: Some(choice),
        passes: stats.passes,
        frame_wall_ms: stats.frame_wall_ms,
        ssbvb_fill_count: fill,
        covered_pixels: Some(rgba.chunks(4).filter(|p| p[3] > 0).count()),
        voxel_pixels: ssbvb_passes::measure::voxel_pixels(&ctx, &renderer)?,
        visible_instances: stats.visible_instances,
        counters,
        lod_histogram: gpu_scene.lod_histogram(),
        warnings,
        streaming,
        device_recoveries: soak.as_ref().map_or(0, |s| s.device_recoveries),
        submissions: ctx.submission_times(),
        soak,
        animation,
        gpu_memory_bytes: gpu_scene
            .memory
            .iter()
            .enumerate()
            .map(|(i, m)| ObjectReport {
                object: i,
                memory: *m,
                total: m.total(),
                bytes_per_voxel: m.bytes_per_voxel(),
            })
            .collect(),
        asset_notes: notes,
    })
}

/// RGBA8 bytes of an output texture (sRGB or not, RGBA or BGRA).
/// `--voxel-mask`: the stencil's voxel pixels as an opaque black-and-white PNG.
fn write_voxel_mask(
    ctx: &ssbvb_gpu::GpuContext,
    renderer: &ssbvb_passes::Renderer,
    path: &std::path::Path,
    (w, h): (u32, u32),
) -> Result<()> {
    let Some(mask) = ssbvb_passes::measure::voxel_mask(ctx, renderer)? else {
        bail!("--voxel-mask: this pipeline has no depth_stencil resource to read coverage from");
    };
    let rgba: Vec<u8> = mask
        .iter()
        .flat_map(|&m| {
            let v = if m == 0 { 0 } else { 255 };
            [v, v, v, 255]
        })
        .collect();
    ssbvb_gpu::readback::write_png_rgba8(path, w, h, &rgba)?;
    Ok(())
}

pub(crate) fn to_rgba8(t: &ssbvb_gpu::readback::TextureData) -> Result<Vec<u8>> {
    t.to_rgba8()
        .context("cannot write the output as PNG; use an 8-bit RGBA/BGRA output")
}

fn print_report(r: &Report) {
    println!(
        "wrote {} ({}x{}, {})",
        r.output, r.size[0], r.size[1], r.mode
    );
    if let Some(a) = &r.adapter {
        println!("adapter: {a}");
        for f in &r.fallbacks {
            println!("format fallback: {f}");
        }
    }
    match (&r.pipeline, &r.pipeline_choice) {
        (Some(p), Some(c)) => println!("pipeline: {p} ({})", c.reason),
        (Some(p), None) => println!("pipeline: {p}"),
        _ => {}
    }
    for n in &r.asset_notes {
        println!("asset: {n}");
    }
    if !r.passes.is_empty() {
        println!("{:<16} {:>12} {:>12}", "pass", "gpu ms", "wall ms");
        for p in &r.passes {
            let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
            println!("{:<16} {:>12} {:>12}", p.name, f(p.gpu_ms), f(p.wall_ms));
        }
        if r.adapter_is_software == Some(true) {
            println!(
                "(software adapter: GPU timestamps are unreliable here; wall ms is each pass submitted and waited alone)"
            );
        }
    }
    println!("frame wall time: {:.2} ms", r.frame_wall_ms);
    if let Some(f) = r.ssbvb_fill_count {
        println!("SSBVB fill count: {f} entries");
    }
    if let Some(c) = r.covered_pixels {
        println!("covered pixels: {c}");
    }
    if let Some(c) = r.voxel_pixels {
        println!("pixels showing a voxel: {c}");
    }
    println!("visible instances: {}", r.visible_instances);
    if !r.lod_histogram.is_empty() {
        let levels: Vec<String> = r
            .lod_histogram
            .iter()
            .map(|(l, n)| format!("{n} at {l}"))
            .collect();
        println!("levels: {}", levels.join(", "));
    }
    let c = &r.counters;
    if let (Some(rays), Some(mean), Some(p99)) =
        (c.filter_rays, c.march_steps_mean, c.march_steps_p99)
    {
        println!(
            "filter: {rays} rays, march steps per ray mean {mean:.1}, p99 <= {p99}; per ray \
             {:.2} instance boxes tested, {:.2} instances marched",
            c.instance_boxes_per_ray.unwrap_or(0.0),
            c.instances_marched_per_ray.unwrap_or(0.0)
        );
    }
    if let Some(t) = c.filter_tiles {
        println!("filter: {t} tiles of 16x16 launched");
    }
    if let Some(rays) = c.ray_cast_rays {
        let (what, v) = match (c.dda_steps_per_ray, c.octree_nodes_per_ray) {
            (Some(v), _) => ("DDA cells", v),
            (_, Some(v)) => ("octree nodes", v),
            _ => ("steps", 0.0),
        };
        println!("ray casting: {rays} rays, {v:.1} {what} per ray");
    }
    if let Some(t) = c.ray_cast_tiles {
        println!("ray casting: {t} tiles of 16x16 launched");
    }
    if let Some(f) = c.fragments_per_covered_pixel {
        println!("billboard fragment invocations per covered pixel: {f:.2}");
    }
    for w in &r.warnings {
        println!("warning: {w}");
    }
    if let Some(soak) = &r.soak {
        let s = &soak.memory;
        let mib = |b: u64| b as f64 / (1 << 20) as f64;
        let rss = |x: Option<u64>| x.map_or("?".to_string(), |b| format!("{:.1} MiB", mib(b)));
        println!(
            "soak: {} frames ({:?}), RSS {} -> {} ({:+.2} %), GPU {:.1} -> {:.1} MiB ({:+.2} %), \
             buffers {} -> {}, bind groups {} -> {}, frame median {:.1} ms, worst {:.1} ms",
            soak.frames,
            soak.camera_path,
            rss(s.start.rss_bytes),
            rss(s.end.rss_bytes),
            s.rss_growth_percent.unwrap_or(0.0),
            mib(s.start.gpu_bytes),
            mib(s.end.gpu_bytes),
            s.gpu_growth_percent,
            s.start.buffers,
            s.end.buffers,
            s.start.bind_groups,
            s.end.bind_groups,
            soak.frame_ms_median,
            soak.frame_ms_max
        );
    }
    for o in &r.gpu_memory_bytes {
        println!(
            "GPU memory, object {}: {} bytes (voxel attributes {}, lookup {}, proxies {}; \
             {:.2} bytes per voxel)",
            o.object,
            o.total,
            o.memory.point_cloud_bytes,
            o.memory.lookup_bytes,
            o.memory.proxy_bytes,
            o.bytes_per_voxel
        );
    }
}
