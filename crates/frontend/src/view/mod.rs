//! `ssbvb view`: an interactive window on a scene or model.
//!
//! The renderer draws into its own output texture exactly as `ssbvb render` does; the
//! viewer copies that onto the window surface ([`blit`]) and draws the egui overlay
//! ([`overlay`]) on top. Modules, one job each:
//!
//! - [`display`]: is there a display at all (and the message when not);
//! - [`surface`]: instance, adapter and device that can present to the window;
//! - [`app`]: the winit event loop and the frame;
//! - [`camera_control`]: orbit and fly camera math (pure, unit-tested); [`input`]: which
//!   mouse and keyboard events drive it;
//! - [`overlay`]: the egui panel; [`knobs`]: generic editing of pass parameters;
//!   [`techniques`]: the pipeline files to switch between; [`stats`]: timings;
//! - [`blit`]: output texture → surface; [`capture`]: screenshots;
//! - [`brush`]: editing voxel objects with the mouse (`--brush`).
//!
//! Hot reload is `ssbvb_graph::PipelineWatcher`: an edit that does not resolve keeps the
//! last good pipeline rendering and shows the errors in the overlay.

mod app;
mod blit;
mod brush;
mod brush_history;
mod brush_journal;
mod camera_control;
mod capture;
mod display;
mod input;
mod knobs;
mod overlay;
mod script;
mod stats;
mod surface;
mod techniques;

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;
use winit::event_loop::EventLoop;

use crate::pipeline_cmd::parse_size;
use crate::progress::BarProgress;
use crate::render_cmd::{assets_dir, load_input};

/// Arguments of `ssbvb view`.
#[derive(Args, Debug)]
pub struct ViewArgs {
    /// A scene file (.ron) or a model file (.obj, .ply, .gltf, .glb, .vox, .raw); default:
    /// the bundled default scene.
    pub input: Option<PathBuf>,
    /// Voxelization level for a model file (2^level cells per axis).
    #[arg(long)]
    pub level: Option<u32>,
    /// Pipeline file (default: the scene's, else the SSBVB form fastest on this adapter,
    /// printed with why). Watched: edits are reloaded while the viewer runs.
    #[arg(long)]
    pub pipeline: Option<PathBuf>,
    /// Window size in pixels.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Exit after this many frames (automation).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Write a PNG of the last frame as the window shows it, overlay included (with
    /// --frames: the last of them; otherwise the frame on screen when the window closes).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// GPU memory budget in MiB for the voxel scene (default: the scene's
    /// `gpu_budget_mib`, else none): pages stream in as rays need them; the overlay shows
    /// residency and changes the budget live.
    #[arg(long, value_name = "MIB")]
    pub gpu_budget: Option<u64>,
    /// With --frames: write process RSS and device memory after the warm-up and at the
    /// end, and the pipeline reloads seen, as JSON (a soak of the viewer and hot reload).
    #[arg(long, value_name = "FILE", requires = "frames")]
    pub memory_report: Option<PathBuf>,
    /// Make the scene's voxel objects editable: Ctrl + left click carves or adds a sphere
    /// or box at the voxel under the cursor (the overlay's Brush section sets which), each
    /// edit region-local on the GPU.
    #[arg(long)]
    pub brush: bool,
    /// The brush's radius at start, in voxels of the edited object's finest level.
    #[arg(long, value_name = "VOXELS", default_value_t = 6.0)]
    pub brush_radius: f64,
    /// Automation: after the first frame, in order: apply the brush (carving a sphere of
    /// --brush-radius) at window pixel X,Y, or `undo`, `redo`, or `save` (to the save
    /// path); repeatable; implies --brush.
    #[arg(long, value_name = "X,Y|undo|redo|save", value_parser = script::parse_script_step, requires = "frames")]
    pub paint: Vec<script::ScriptStep>,
    /// Automation: turn the orbit camera by DEG degrees about its target every frame after
    /// the first (a moving camera, e.g. to see temporal anti-aliasing in motion). The last
    /// camera is printed as `ssbvb render` flags when the viewer closes, with or without it.
    #[arg(long, value_name = "DEG", value_parser = script::parse_orbit, requires = "frames", allow_hyphen_values = true)]
    pub orbit: Option<f64>,
    /// Save the edited objects here when the viewer closes (a prepared asset file that
    /// `ssbvb render FILE` and `ssbvb view FILE` open, every level as edited; with several
    /// editable objects, FILE with each object's index before the extension). Also where
    /// Ctrl+S saves. Implies --brush.
    #[arg(long, value_name = "FILE")]
    pub save_on_exit: Option<PathBuf>,
    /// Replay the journal an earlier session left beside the model (its unsaved brush
    /// work) without asking. Implies --brush.
    #[arg(long, conflicts_with = "discard_journal")]
    pub restore: bool,
    /// Set an earlier session's journal aside (renamed `….discarded`) without asking, also
    /// one that cannot be used. Implies --brush.
    #[arg(long)]
    pub discard_journal: bool,
    /// The brush journal's file (default: beside the model, `MODEL.L<level>.ssbvb-journal`,
    /// or `SCENE.ron.ssbvb-journal`).
    #[arg(long, value_name = "FILE")]
    pub journal: Option<PathBuf>,
    /// Crash injection for tests: `after@N` aborts right after journal record N,
    /// `torn@N` in the middle of writing it.
    #[arg(long, hide = true, value_parser = brush_journal::parse_crash)]
    pub inject_crash: Option<brush_journal::Crash>,
    /// Fault injection for tests: `device-lost@FRAME` destroys the device before frame
    /// FRAME, `oom@FRAME` rebuilds the GPU side there with its first large allocation
    /// refused (repeatable); the viewer recovers, keeping the brush edits.
    #[arg(long, hide = true, value_parser = ssbvb_engine::faults::parse_fault)]
    pub inject_fault: Vec<ssbvb_engine::faults::Fault>,
    /// The device's limits: `adapter` (its own) or `webgpu` (WebGPU's defaults and no
    /// optional feature).
    #[arg(long, value_enum, default_value = "adapter")]
    pub limits: crate::adapter_cmd::LimitsArg,
}

/// Pages the viewer streams in before one frame at most.
const VIEW_PAGES_PER_FRAME: usize = 512;

/// Runs `ssbvb view`.
pub fn run(args: &ViewArgs) -> Result<()> {
    display::check_display_env().map_err(anyhow::Error::msg)?;
    if args.frames == Some(0) {
        return Err(anyhow!("--frames must be at least 1"));
    }
    if let Some(f) = args
        .inject_fault
        .iter()
        .find(|f| args.frames.is_none_or(|n| f.frame() as u64 >= n))
    {
        return Err(anyhow!(
            "--inject-fault {} needs --frames {} or more: faults are injected before a \
             numbered frame of an automated run",
            f.spelled(),
            f.frame() + 1
        ));
    }
    // Before any voxelization: fail fast when the display cannot be opened.
    let event_loop = create_event_loop()?;

    let progress = BarProgress::new(std::io::stderr().is_terminal());
    let input = args
        .input
        .clone()
        .unwrap_or_else(|| assets_dir().join("scenes/default.ron"));
    let content = load_input(&input, args.level, &progress)?;
    let warnings = content.warning_lines();
    let ssbvb_engine::Content {
        scene,
        camera,
        pipeline,
        mut notes,
        gpu_budget_mib,
        page_sources,
        animated,
        ..
    } = content;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    if !animated.is_empty() && args.gpu_budget.or(gpu_budget_mib).is_some() {
        anyhow::bail!("animated objects cannot be paged under a GPU budget; drop --gpu-budget");
    }
    let editable = args.brush
        || !args.paint.is_empty()
        || args.save_on_exit.is_some()
        || args.restore
        || args.discard_journal;
    if !(args.brush_radius.is_finite()
        && args.brush_radius > 0.0
        && args.brush_radius <= brush::MAX_RADIUS_VOXELS)
    {
        anyhow::bail!(
            "--brush-radius must be a number of voxels in (0, {}], got {}",
            brush::MAX_RADIUS_VOXELS,
            args.brush_radius
        );
    }
    if editable && args.gpu_budget.or(gpu_budget_mib).is_some() {
        anyhow::bail!("edited objects cannot be paged under a GPU budget; drop --gpu-budget");
    }
    let brush = editable.then(|| {
        let skip: Vec<usize> = animated.iter().map(|a| a.object).collect();
        let (journal, save_path) = journal_and_save_paths(args, &input, &scene);
        let decision = match (args.restore, args.discard_journal) {
            (true, _) => brush_journal::JournalDecision::Restore,
            (_, true) => brush_journal::JournalDecision::Discard,
            _ => brush_journal::JournalDecision::Ask,
        };
        let journal = brush_journal::JournalOptions {
            path: Some(journal),
            decision,
            crash: args.inject_crash,
        };
        let mut b = brush::Brush::new(&scene, &skip, &journal, save_path);
        b.settings.radius_voxels = args.brush_radius;
        for n in b.journal_notes() {
            eprintln!("journal: {n}");
        }
        b
    });
    progress.finish();
    // Pages streamed per frame at most: a camera cut fills the view over a few frames
    // rather than stalling one.
    let streaming = match args.gpu_budget.or(gpu_budget_mib) {
        Some(mib) => Some(ssbvb_engine::budget::options(
            mib,
            &page_sources,
            VIEW_PAGES_PER_FRAME,
            &mut notes,
        )?),
        None => None,
    };
    for n in &notes {
        eprintln!("asset: {n}");
    }
    let choice = crate::pipeline_choice::choose(args.pipeline.clone(), pipeline)?;
    eprintln!("{}", choice.line());
    let pipeline_path = choice.path();
    // Canonical, so the overlay shows a plain path and the technique list can mark it.
    let pipeline_path = pipeline_path.canonicalize().unwrap_or(pipeline_path);
    let watcher = ssbvb_graph::PipelineWatcher::new(&pipeline_path)
        .map_err(|e| anyhow!("{}", e.to_string().trim_end()))?;

    let options = app::Options {
        title: format!("ssbvb view — {}", input.display()),
        size: args.size,
        frames: args.frames,
        screenshot: args.screenshot.clone(),
        techniques: techniques::list(&assets_dir().join("pipelines")),
        memory_report: args.memory_report.clone(),
        paint: args.paint.clone(),
        save_on_exit: args.save_on_exit.clone(),
        faults: args.inject_fault.clone(),
        orbit_deg: args.orbit,
        warnings,
    };
    let mut app = app::App::new(
        options,
        app::Loaded {
            scene,
            camera,
            watcher,
            streaming,
            animated,
            brush,
        },
    );
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    app.into_result()
}

/// The brush journal's path and where saves go: `--journal` or beside the input (the
/// level in the name for a model file, whose journal depends on it), and
/// `--save-on-exit` or `INPUT_STEM.edited.ssbvb` beside the input.
fn journal_and_save_paths(
    args: &ViewArgs,
    input: &std::path::Path,
    scene: &ssbvb_gpu::scene::Scene,
) -> (PathBuf, PathBuf) {
    let is_scene = input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"));
    let level = (!is_scene)
        .then(|| scene.objects.first().map(|o| o.asset.lods.len() as u32 - 1))
        .flatten();
    let journal = args
        .journal
        .clone()
        .unwrap_or_else(|| brush_journal::default_path(input, level));
    let stem = input
        .file_stem()
        .map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    let save = args.save_on_exit.clone().unwrap_or_else(|| {
        input.with_file_name(format!(
            "{stem}.edited.{}",
            ssbvb_voxel::cache::ASSET_FILE_EXTENSION
        ))
    });
    (journal, save)
}

/// The event loop, or the no-display error (winit panics on some broken X servers:
/// that becomes the same error instead of a crash).
fn create_event_loop() -> Result<EventLoop<()>> {
    let created = std::panic::catch_unwind(EventLoop::new);
    match created {
        Ok(Ok(l)) => Ok(l),
        Ok(Err(e)) => Err(anyhow!(display::no_display_message(&format!(
            "cannot connect to the window system: {e}"
        )))),
        Err(_) => Err(anyhow!(display::no_display_message(
            "the window system could not be initialized"
        ))),
    }
}
