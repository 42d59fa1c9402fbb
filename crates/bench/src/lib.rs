//! `ssbvb bench` (this crate, `ssbvb-bench`, built on the engine): technique × model ×
//! level × resolution on one adapter, with warm-up
//! frames, timed frames (median and spread), per-pass times, the SSBVB fill count, GPU
//! memory, and accuracy against the CPU reference. Writes CSV, JSON and a Markdown table,
//! PNG plots, and with `--sweep` (or `--preset full`) speed–accuracy knob sweeps.
//!
//! This file holds the module list and [`run()`], which checks the arguments and hands
//! the run to its preset. The command line is `args`; what every preset shares (models,
//! pipelines, timing frames, accuracy against the reference, the techniques) is `harness`;
//! `table` writes a preset's rows as CSV, JSON and Markdown; `plot` draws PNG plots;
//! `report` is the report of the main matrix; `presets` holds one file per preset:
//! `matrix` (`quick`, `full`, `study`), `sweep` (their knob sweeps), `scale`, `memory`,
//! `rastavox`, `dynamic`, `vct`, `volumes` and `paper` (which runs the matrix and the
//! scale grid and compares them with the seed paper). Presets import `args`, `harness`, `table`,
//! `plot` and `report`; nothing imports a preset but [`run()`].

mod args;
mod flip;
mod harness;
mod plot;
mod presets;
mod report;
mod table;

use anyhow::Result;

pub use args::{BenchArgs, Preset};

/// Runs `ssbvb bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    check(args)?;
    match args.preset {
        Preset::Quick | Preset::Full | Preset::Study => {
            let m = presets::matrix::run(args)?;
            let sweeps = presets::sweep::run(args, &m.ctx, &m.camera)?;
            report::write(args, &m.ctx, m.camera, &m.results, &sweeps, true)
        }
        Preset::Paper => presets::paper::run(args),
        Preset::Scale => presets::scale::run(args),
        Preset::Memory => presets::memory::run(args),
        Preset::Rastavox => presets::rastavox::run(args),
        Preset::Dynamic => presets::dynamic::run(args),
        Preset::Vct => presets::vct::run(args),
        Preset::Volumes => presets::volumes::run(args),
        Preset::Quality => presets::quality::run(args),
    }
}

/// Checks the counts the presets read: `--instances` for the presets that take it
/// (scale, rastavox), `--gpu-budget` for the others.
fn check(args: &BenchArgs) -> Result<()> {
    if matches!(
        args.preset,
        Preset::Scale | Preset::Rastavox | Preset::Paper
    ) {
        if let Some(n) = args
            .instances
            .iter()
            .flatten()
            .find(|&&n| n == 0 || n > 1 << 16)
        {
            anyhow::bail!("--instances: {n} is not a count from 1 to 65536");
        }
        return Ok(());
    }
    if let Some(b) = args
        .gpu_budget
        .iter()
        .flatten()
        .find(|&&b| b == 0 || b > ssbvb_engine::budget::MAX_BUDGET_MIB)
    {
        anyhow::bail!(
            "--gpu-budget: {b} is not a budget from 1 to {} MiB",
            ssbvb_engine::budget::MAX_BUDGET_MIB
        );
    }
    Ok(())
}
