//! Choosing the adapter for the pipelines a command runs, and `ssbvb adapter`, which lists
//! every adapter with its verdict on a pipeline.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;
use ssbvb_gpu::{ContextOptions, DeviceLimits, GpuContext, Requirements};
use ssbvb_graph::ResolvedPipeline;

/// Arguments of `ssbvb adapter`.
#[derive(Args, Debug)]
pub struct AdapterArgs {
    /// The pipeline to check adapters against (default: the SSBVB form `render` would
    /// choose on the best adapter).
    #[arg(long)]
    pub pipeline: Option<PathBuf>,
    /// Check against these limits (`webgpu`: WebGPU's defaults and no optional feature).
    #[arg(long, value_enum, default_value = "adapter")]
    pub limits: LimitsArg,
}

/// `--limits` of `render`, `view`, `bench` and `adapter`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum LimitsArg {
    /// The adapter's own limits and the optional features ssbvb uses where present.
    #[default]
    Adapter,
    /// WebGPU's default limits and no optional feature (what a browser guarantees): no
    /// per-pass GPU times, no exact GPU voxelization, the compute splat in two steps;
    /// pipelines that need more are refused up front, naming what they need.
    Webgpu,
}

impl LimitsArg {
    /// The device limits it asks for.
    pub fn device(self) -> DeviceLimits {
        match self {
            LimitsArg::Adapter => DeviceLimits::Adapter,
            LimitsArg::Webgpu => DeviceLimits::WebGpuDefaults,
        }
    }
}

/// Sets the limits of this process's devices from `--limits` (the first call wins).
pub fn set_limits(limits: LimitsArg) {
    ssbvb_engine::choice::set_process_limits(limits.device());
}

/// The limits of this process's devices.
pub fn limits() -> DeviceLimits {
    ssbvb_engine::choice::process_limits()
}

/// What `pipelines` together need from an adapter.
pub fn requirements_of(pipelines: &[&ResolvedPipeline]) -> Requirements {
    ssbvb_engine::choice::requirements_of(pipelines)
}

/// A headless context on the best adapter that can run every one of `pipelines`.
pub fn headless_context(pipelines: &[&ResolvedPipeline]) -> Result<GpuContext> {
    Ok(ssbvb_engine::choice::headless_context(pipelines)?)
}

/// Resolves a pipeline file with the graph's error report as the message.
pub fn resolve(path: &Path) -> Result<ResolvedPipeline> {
    ssbvb_graph::resolve_file(path).map_err(|e| anyhow::anyhow!("{e}"))
}

/// Runs `ssbvb adapter`: every adapter, best first, with what it lacks for the pipeline
/// `path` (`--pipeline`, else the default form, chosen as `chosen_because` says); then the
/// one `render` would use. Fails when none fits.
pub fn run(path: &Path, chosen_because: &str) -> Result<ExitCode> {
    let pipeline = resolve(path)?;
    let req = requirements_of(&[&pipeline]);
    let list = GpuContext::list_adapters(&req, limits());
    let under = match limits() {
        DeviceLimits::Adapter => "",
        DeviceLimits::WebGpuDefaults => " under WebGPU's default limits",
    };
    println!(
        "adapters, best first, checked against {}{under}:",
        path.display()
    );
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
        limits: limits(),
        ..Default::default()
    })?;
    println!("chosen: {}", ctx.report());
    println!("{chosen_because}");
    Ok(ExitCode::SUCCESS)
}

/// The format substitutions the device took, what a device without read-only depth-stencil
/// attachments or depth-to-buffer copies does instead (GL), the compute splat's two-step
/// form where `pipeline` has one and the device no 64-bit atomics, and the exact GPU
/// voxelization of animated objects given up where the device has no f64 shaders (WebGPU's
/// limits, most mobile and browser adapters): they are voxelized by conservative
/// rasterization instead.
pub fn gpu_fallbacks(
    ctx: &ssbvb_gpu::GpuContext,
    pipeline: &ssbvb_graph::ResolvedPipeline,
    animation: Option<&ssbvb_engine::animation::AnimationReport>,
) -> Vec<String> {
    let mut fallbacks = ctx.report().fallbacks.clone();
    let flags = ctx.adapter.get_downlevel_capabilities().flags;
    if !flags.contains(ssbvb_gpu::wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL) {
        fallbacks.push(
            "the smoothing copies the depth before it (no read-only depth-stencil \
             attachments)"
                .into(),
        );
    }
    if !flags.contains(ssbvb_gpu::wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES) {
        fallbacks.push(
            "voxel pixels counted by a stencil-tested draw (no depth texture to buffer copies)"
                .into(),
        );
    }
    let splats = pipeline
        .passes
        .iter()
        .any(|p| matches!(p.kind, ssbvb_graph::PassKind::SplatBillboards(_)));
    if splats && !ssbvb_passes::kinds::splat_billboards::has_wide_atomics(ctx) {
        fallbacks
            .push("the compute splat takes two 32-bit steps, not one (no 64-bit atomics)".into());
    }
    let raster = animation
        .is_some_and(|a| a.method == Some(ssbvb_gpu_build::voxelize::GpuVoxelizeMethod::Raster));
    if raster
        && !ctx
            .device
            .features()
            .contains(ssbvb_gpu::wgpu::Features::SHADER_F64)
    {
        fallbacks.push(
            "animated objects voxelized by conservative rasterization, not exactly (the \
             device has no SHADER_F64)"
                .into(),
        );
    }
    fallbacks
}
