//! The `ssbvb` command-line tool.

mod bench_cmd;
mod bench_plot;
mod bench_sweep;
mod pipeline_cmd;
mod progress;
mod render_cmd;
mod scene_file;
mod view;
mod voxelize_cmd;

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
    Bench(bench_cmd::BenchArgs),
    /// Voxelize a model: every LOD, sparse lookup pages, proxy meshes; cached on disk.
    Voxelize(voxelize_cmd::VoxelizeArgs),
    /// Open a window on a scene or model: orbit/fly camera, overlay with per-pass timings,
    /// knobs, LOD and technique switch, hot reload of the pipeline file (needs a display).
    View(view::ViewArgs),
    /// Print the GPU adapter ssbvb would use (set SSBVB_ADAPTER / WGPU_BACKEND to choose).
    Adapter,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Pipeline(c) => pipeline_cmd::run(&c),
        Command::Adapter => adapter(),
        Command::Bench(a) => bench_cmd::run(&a).map(|_| ExitCode::SUCCESS),
        Command::Render(a) => render_cmd::run(&a).map(|_| ExitCode::SUCCESS),
        Command::View(a) => view::run(&a).map(|_| ExitCode::SUCCESS),
        Command::Voxelize(a) => voxelize_cmd::run(&a).map(|_| ExitCode::SUCCESS),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn adapter() -> anyhow::Result<ExitCode> {
    let ctx = ssbvb_gpu::GpuContext::new_headless(&Default::default())?;
    println!("{}", ctx.report());
    Ok(ExitCode::SUCCESS)
}
