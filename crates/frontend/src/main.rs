//! The `ssbvb` command-line tool.

mod pipeline_cmd;

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
    /// Print the GPU adapter ssbvb would use (set SSBVB_ADAPTER / WGPU_BACKEND to choose).
    Adapter,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Pipeline(c) => pipeline_cmd::run(&c),
        Command::Adapter => adapter(),
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
