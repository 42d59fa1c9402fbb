//! What the bench takes from the engine, in the bench's error type: pipelines resolved,
//! the adapter's default form, frames read as RGBA8.

use std::path::Path;

use anyhow::Result;
use ssbvb_graph::ResolvedPipeline;

/// Resolves a pipeline file with the graph's error report as the message.
pub(crate) fn resolve(path: &Path) -> Result<ResolvedPipeline> {
    Ok(ssbvb_engine::choice::resolve_pipeline(path)?)
}

/// The SSBVB form `ssbvb render` chooses on this process's adapter and limits (its
/// warnings printed).
pub(crate) fn default_form() -> Result<ssbvb_engine::PipelineChoice> {
    let c = ssbvb_engine::choice::default_for_adapter(ssbvb_engine::choice::process_limits())?;
    for w in &c.warnings {
        eprintln!("warning: {}", w.message);
    }
    Ok(c)
}

/// RGBA8 bytes of an output texture (sRGB or not, RGBA or BGRA).
pub(crate) fn to_rgba8(t: &ssbvb_gpu::readback::TextureData) -> Result<Vec<u8>> {
    Ok(t.to_rgba8()?)
}
