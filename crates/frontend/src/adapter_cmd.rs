//! Choosing the adapter for the pipelines a command runs, and `ssbvb adapter`, which lists
//! every adapter with its verdict on a pipeline.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;
use ssbvb_gpu::{ContextOptions, GpuContext, Requirements};
use ssbvb_graph::ResolvedPipeline;

use crate::bundled::assets_dir;

/// Arguments of `ssbvb adapter`.
#[derive(Args, Debug)]
pub struct AdapterArgs {
    /// The pipeline to check adapters against (default: the bundled SSBVB pipeline).
    #[arg(long)]
    pub pipeline: Option<PathBuf>,
}

/// What `pipelines` together need from an adapter.
pub fn requirements_of(pipelines: &[&ResolvedPipeline]) -> Requirements {
    let mut req = Requirements::default();
    for p in pipelines {
        req.merge(&ssbvb_passes::pipeline_requirements(p));
    }
    req
}

/// A headless context on the best adapter that can run every one of `pipelines`.
pub fn headless_context(pipelines: &[&ResolvedPipeline]) -> Result<GpuContext> {
    Ok(GpuContext::new_headless(&ContextOptions {
        requirements: Some(requirements_of(pipelines)),
        ..Default::default()
    })?)
}

/// Resolves a pipeline file with the graph's error report as the message.
pub fn resolve(path: &Path) -> Result<ResolvedPipeline> {
    ssbvb_graph::resolve_file(path).map_err(|e| anyhow::anyhow!("{e}"))
}

/// Runs `ssbvb adapter`: every adapter, best first, with what it lacks for the pipeline;
/// then the one `render` would use. Fails when none fits.
pub fn run(args: &AdapterArgs) -> Result<ExitCode> {
    let path = args
        .pipeline
        .clone()
        .unwrap_or_else(|| assets_dir().join("pipelines/ssbvb.ron"));
    let pipeline = resolve(&path)?;
    let req = requirements_of(&[&pipeline]);
    let list = GpuContext::list_adapters(&req);
    println!("adapters, best first, checked against {}:", path.display());
    if list.is_empty() {
        println!("  (none)");
    }
    for a in &list {
        let verdict = if !a.allowed {
            "not allowed by SSBVB_ADAPTER".to_string()
        } else if a.verdict.fits() {
            let fb = a.verdict.fallback_notes();
            if fb.is_empty() {
                "fits".to_string()
            } else {
                format!("fits with fallbacks: {}", fb.join(", "))
            }
        } else {
            format!("lacks: {}", a.verdict.missing.join("; "))
        };
        println!("  {} [{}, {}]: {verdict}", a.name, a.backend, a.device_type);
    }
    let ctx = GpuContext::new_headless(&ContextOptions {
        requirements: Some(req),
        ..Default::default()
    })?;
    println!("chosen: {}", ctx.report());
    Ok(ExitCode::SUCCESS)
}
