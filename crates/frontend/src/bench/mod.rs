//! `ssbvb bench`: technique × model × level × resolution on one adapter, with warm-up
//! frames, timed frames (median and spread), per-pass times, the SSBVB fill count, GPU
//! memory, and accuracy against the CPU reference. Writes CSV, JSON and a Markdown table,
//! PNG plots, and with `--sweep` (or `--preset full`) speed–accuracy knob sweeps.
//!
//! This file holds the command line and [`run()`], the order of the steps; the steps live
//! in their own files: `techniques` (what is compared), `matrix` (what each preset
//! covers), `run` (measuring the cells), `sweep` (the knob sweeps), `plot` (PNG plots),
//! `report` (JSON, CSV, Markdown), `scale` (`--preset scale`, its own table), `memory`
//! (`--preset memory`), `rastavox` (`--preset rastavox`), `dynamic` (`--preset dynamic`)
//! `vct` (`--preset vct`) and `volumes` (`--preset volumes`).

mod dynamic;
mod matrix;
mod memory;
mod plot;
mod rastavox;
mod report;
mod run;
mod scale;
mod sweep;
mod techniques;
mod vct;
mod volumes;

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use ssbvb_voxel::camera::Camera;

use crate::render_cmd::assets_dir;
use report::Report;
use sweep::SweepRow;
use techniques::Technique;

/// Benchmark presets.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Preset {
    /// Small: CI-sized (bunny levels 5-6, 160x120, few frames).
    Quick,
    /// The measurement run: bunny levels 7-12 at 640x480 and 1280x720, plus knob sweeps.
    Full,
    /// The seed-002 study: a filled ball, 50 % random voxels and the bunny mesh, model
    /// resolutions 8-512 (levels 3-9), targets 640x480-2560x1440, and the fastest technique
    /// per cell (its Table 11).
    Study,
    /// Cost against scene size: the bunny grid at 1, 16, 256 and 4096 instances
    /// (`--instances`) with Auto LOD, plus a near, a mid and a far camera on one bunny;
    /// writes scale.csv, scale.json and scale.md.
    Scale,
    /// Pages by demand under a GPU budget: the bunny at levels 7-13 × budgets
    /// (`--gpu-budget`, default 32,128,512 MiB) against the unbudgeted upload, and a
    /// fly-through that measures streaming stalls; writes memory.csv, memory.json and
    /// memory.md.
    Memory,
    /// RastaVox (seed 001): surface-model memory of the bunny and the knight at each level
    /// (`--levels`, default 5-9) beside the SSBVB asset, the GPU build time, and a
    /// pixel-error sweep (0, 1, 2, 4) on the bunny at the finest of those levels (and on
    /// `--instances N` bunnies) against the drawn model and the finest level; writes
    /// rastavox.csv, rastavox.json and rastavox.md.
    Rastavox,
    /// Dynamic objects: the bunny (`--levels`, default 7-9) static against twisting and
    /// re-voxelized on the GPU every frame (update stages, the frame after it, and the same
    /// update on the CPU); writes dynamic.csv, dynamic.json and dynamic.md.
    Dynamic,
    /// Voxel cone tracing (seed 003): the lit default scene against the plain frame, the
    /// cone count, aperture and volume resolution swept, each row's cone-pass time beside
    /// the filter's and its errors (AO, shadow, bounce, lit output) against 256-sample
    /// Monte Carlo, and the defaults on 64 bunnies; writes vct.csv, vct.json and vct.md.
    Vct,
    /// Volumetric billboards (seed 004): the cloud and the bunny's coverage volume against
    /// the emission–absorption integral with the slice spacing and mip bias swept (time,
    /// slice fragments per pixel, PSNR, SSIM), and the thesis's crossover: the cow and
    /// bunny meshes against their 128³ volumes by screen size; writes volumes.csv,
    /// volumes.json and volumes.md.
    Volumes,
}

/// Arguments of `ssbvb bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Which matrix to run.
    #[arg(long, value_enum, default_value = "quick")]
    pub preset: Preset,
    /// Output folder for bench.csv, bench.json and bench.md.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
    /// Print the results as one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// Also sweep the knobs of the default SSBVB pipeline one at a time (ray-march
    /// max_steps, billboard size_scale, smoothing max_i, LOD bias) and write sweeps.csv
    /// and `trade_<knob>.png`; always on with `--preset full`.
    #[arg(long)]
    pub sweep: bool,
    /// Levels to run instead of the preset's (comma-separated, e.g. `3,4,5`).
    #[arg(long, value_delimiter = ',')]
    pub levels: Option<Vec<u32>>,
    /// Image sizes to run instead of the preset's (comma-separated, e.g.
    /// `640x480,1280x720`).
    #[arg(long, value_delimiter = ',', value_parser = crate::pipeline_cmd::parse_size)]
    pub sizes: Option<Vec<(u32, u32)>>,
    /// Techniques to run (comma-separated names; default: all).
    #[arg(long, value_delimiter = ',')]
    pub techniques: Option<Vec<String>>,
    /// Timed frames per cell instead of the preset's.
    #[arg(long)]
    pub frames: Option<usize>,
    /// Instance counts of `--preset scale` (comma-separated; default 1,16,256,4096).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(usize))]
    pub instances: Option<Vec<usize>>,
    /// GPU memory budgets in MiB (comma-separated): the budgets of `--preset memory`;
    /// with another preset, every cell is uploaded under the first one (techniques that
    /// read whole levels are skipped).
    #[arg(long, value_delimiter = ',', value_name = "MIB")]
    pub gpu_budget: Option<Vec<u64>>,
}

/// Runs `ssbvb bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    if matches!(args.preset, Preset::Scale | Preset::Rastavox) {
        if let Some(n) = args
            .instances
            .iter()
            .flatten()
            .find(|&&n| n == 0 || n > 1 << 16)
        {
            anyhow::bail!("--instances: {n} is not a count from 1 to 65536");
        }
        if matches!(args.preset, Preset::Rastavox) {
            return rastavox::run(args);
        }
        return scale::run(args);
    }
    if let Some(b) = args
        .gpu_budget
        .iter()
        .flatten()
        .find(|&&b| b == 0 || b > crate::budget::MAX_BUDGET_MIB)
    {
        anyhow::bail!(
            "--gpu-budget: {b} is not a budget from 1 to {} MiB",
            crate::budget::MAX_BUDGET_MIB
        );
    }
    if matches!(args.preset, Preset::Memory) {
        return memory::run(args);
    }
    if matches!(args.preset, Preset::Dynamic) {
        return dynamic::run(args);
    }
    if matches!(args.preset, Preset::Vct) {
        return vct::run(args);
    }
    if matches!(args.preset, Preset::Volumes) {
        return volumes::run(args);
    }
    let m = matrix::matrix(args);
    let techniques = techniques::select(args)?;
    let ctx = open_context(&techniques)?;
    let software = ctx.report().is_software;
    let budget = args.gpu_budget.as_ref().and_then(|b| b.first().copied());
    let results = run::run_matrix(&ctx, &m, &techniques, budget, !args.json)?;
    let sweeps = sweeps(args, &ctx, &m.camera)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let plots = plot::write_plots(&args.out, &results.rows, &sweeps)?;
    let fastest = report::fastest(&results.rows);
    let report = Report {
        adapter: ctx.report().to_string(),
        adapter_is_software: software,
        timing: report::timing(software),
        preset: format!("{:?}", args.preset),
        camera: m.camera,
        rows: results.rows,
        skipped: results.skipped,
        sweeps,
        fastest,
        plots,
    };
    report::write_outputs(&args.out, &report)?;
    report::print(&report, &args.out, args.json)
}

/// A headless GPU context that can run every technique's pipeline.
fn open_context(techniques: &[&Technique]) -> Result<ssbvb_gpu::GpuContext> {
    let pipelines = techniques
        .iter()
        .map(|t| sweep::bundled_pipeline(t.pipeline))
        .collect::<Result<Vec<_>>>()?;
    crate::adapter_cmd::headless_context(&pipelines.iter().collect::<Vec<_>>())
}

/// The knob sweeps on the bunny, with `--sweep` or the full preset (never for the study);
/// empty otherwise.
fn sweeps(args: &BenchArgs, ctx: &ssbvb_gpu::GpuContext, camera: &Camera) -> Result<Vec<SweepRow>> {
    if !((args.sweep || matches!(args.preset, Preset::Full))
        && !matches!(args.preset, Preset::Study))
    {
        return Ok(Vec::new());
    }
    let cfg = matrix::sweep_config(args.preset);
    let (asset, _) = bundled_bunny(cfg.level)?;
    sweep::run_sweeps(ctx, &asset, camera, &cfg, !args.json)
}

/// The bundled bunny at `level`, from the asset cache (prepared on a miss), and how the
/// cache answered.
fn bundled_bunny(
    level: u32,
) -> Result<(
    Arc<ssbvb_voxel::asset::VoxelAsset>,
    ssbvb_voxel::cache::PrepareOutcome,
)> {
    let model = assets_dir().join("models/bunny.obj");
    let (asset, outcome) = ssbvb_voxel::cache::load_or_prepare(
        &model,
        level,
        None,
        &ssbvb_voxel::progress::NoProgress,
    )
    .with_context(|| format!("preparing {} at level {level}", model.display()))?;
    Ok((Arc::new(asset), outcome))
}
