//! The `ssbvb` command-line tool.

mod adapter_cmd;
mod calibrate_cmd;
mod cli_values;
mod decl_docs;
mod export_cmd;
mod pipeline_choice;
mod pipeline_cmd;
mod pipeline_kinds;
mod progress;
mod render_cmd;
mod scene_reference;
mod soak;
mod view;
mod voxelize_cmd;
mod voxelize_gpu;
mod voxelize_report;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Screen Space Billboard Voxel Buffer renderer: render, voxelize and check pipelines.
#[derive(Parser)]
#[command(name = "ssbvb", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render pipeline files (RON).
    #[command(subcommand)]
    Pipeline(pipeline_cmd::PipelineCommand),
    /// Render one frame of a scene or model to a PNG (GPU SSBVB pipeline, or the CPU
    /// reference with --reference).
    Render(render_cmd::RenderArgs),
    /// Benchmark techniques × levels × resolutions against the CPU reference (CSV, JSON,
    /// Markdown).
    Bench(ssbvb_bench::BenchArgs),
    /// Voxelize a model: every LOD, sparse lookup pages, proxy meshes; cached on disk.
    Voxelize(voxelize_cmd::VoxelizeArgs),
    /// Measure each SSBVB form on this adapter (the bundled default scene) and keep the
    /// fastest as the default pipeline for this adapter, driver and limits
    /// (`calibration.json` beside the asset cache).
    Calibrate(calibrate_cmd::CalibrateArgs),
    /// Open a window on a scene or model: orbit/fly camera, overlay with per-pass timings,
    /// knobs, LOD and technique switch, hot reload of the pipeline file (needs a display).
    View(view::ViewArgs),
    /// List every GPU adapter with what it lacks for a pipeline, and the one ssbvb would
    /// use (set SSBVB_ADAPTER / WGPU_BACKEND to choose).
    Adapter(adapter_cmd::AdapterArgs),
    /// Scene files (RON).
    #[command(subcommand)]
    Scene(SceneCommand),
    /// Write a model's voxels at a level where other tools open them: MagicaVoxel VOX, the
    /// dense raw grid, NumPy .npy (dense or --sparse), or an OBJ of the exposed faces.
    Export(export_cmd::ExportArgs),
}

/// Scene-file subcommands.
#[derive(Subcommand)]
enum SceneCommand {
    /// Print the scene-file reference (every field: type, default, meaning; Markdown, the
    /// text of `docs/scenes.md`), from the format's own declarations.
    Fields,
}

fn main() -> ExitCode {
    // SAFETY: first thing in `main`, before any other thread exists.
    unsafe { ssbvb_gpu::context::prefer_gles_on_mesa() };
    let cli = Cli::parse();
    if !matches!(cli.command, Command::View(_)) {
        // SAFETY: first thing in `main` after the arguments, before any other thread exists.
        unsafe { ssbvb_engine::platform::quiet_window_system_probe() };
    }
    match &cli.command {
        Command::Adapter(a) => adapter_cmd::set_limits(a.limits),
        Command::Bench(a) => ssbvb_engine::choice::set_process_limits(a.limits),
        Command::Render(a) => adapter_cmd::set_limits(a.limits),
        Command::View(a) => adapter_cmd::set_limits(a.limits),
        Command::Calibrate(a) => adapter_cmd::set_limits(a.limits),
        Command::Pipeline(_) | Command::Voxelize(_) | Command::Scene(_) | Command::Export(_) => {}
    }
    let result = match cli.command {
        Command::Pipeline(c) => pipeline_cmd::run(&c),
        Command::Adapter(a) => pipeline_choice::choose(a.pipeline.clone(), None)
            .and_then(|c| adapter_cmd::run(&c.path(), &c.line())),
        Command::Bench(a) => ssbvb_bench::run(&a).map(|_| ExitCode::SUCCESS),
        Command::Render(a) => render_cmd::run(&a).map(|_| ExitCode::SUCCESS),
        Command::View(a) => view::run(&a).map(|_| ExitCode::SUCCESS),
        Command::Voxelize(a) => voxelize_cmd::run(&a).map(|_| ExitCode::SUCCESS),
        Command::Calibrate(a) => calibrate_cmd::run(&a).map(|_| ExitCode::SUCCESS),
        Command::Export(a) => export_cmd::run(&a).map(|_| ExitCode::SUCCESS),
        Command::Scene(SceneCommand::Fields) => {
            print!("{}", scene_reference::markdown());
            Ok(ExitCode::SUCCESS)
        }
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
