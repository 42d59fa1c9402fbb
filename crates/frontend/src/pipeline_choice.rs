//! The pipeline of a command: the engine's choice ([`ssbvb_engine::choice`]) under this
//! process's `--limits`, its warnings printed.

use std::path::PathBuf;

use anyhow::Result;
pub use ssbvb_engine::PipelineChoice;
use ssbvb_gpu::AdapterVerdict;

use crate::adapter_cmd::limits;

fn said(c: PipelineChoice) -> PipelineChoice {
    // The message names the file already (`the calibration was ignored (FILE: why)`).
    for w in &c.warnings {
        eprintln!("warning: {}", w.message);
    }
    c
}

/// The pipeline of a command: `flag` (`--pipeline`), else the scene's, else the choice for
/// this process's adapter and limits.
pub fn choose(flag: Option<PathBuf>, scene: Option<PathBuf>) -> Result<PipelineChoice> {
    Ok(said(ssbvb_engine::choice::choose(flag, scene, limits())?))
}

/// The adapter the rule picks and which of `files` it fits.
pub fn adapter_and_fitting_forms(
    files: &[&'static str],
) -> Result<(AdapterVerdict, Vec<&'static str>)> {
    Ok(ssbvb_engine::choice::adapter_and_fitting_forms(
        files,
        limits(),
    )?)
}
