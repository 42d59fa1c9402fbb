//! What `ssbvb voxelize` takes and reports: its arguments and the JSON report, shared by
//! the CPU path (`voxelize_cmd`) and the GPU path (`voxelize_gpu`).

use std::path::PathBuf;

use serde::Serialize;
use ssbvb_gpu_build::voxelize::{GpuVoxelizeMethod, GpuVoxelizeStats};
use ssbvb_voxel::prepare::{LevelStats, StageTimes};
use ssbvb_voxel::voxelize::VoxelizeReport;

/// Arguments of `ssbvb voxelize`.
#[derive(Debug, Clone, clap::Args)]
pub struct VoxelizeArgs {
    /// Model file (.obj, .ply, .gltf, .glb, .vox, .raw).
    pub model: PathBuf,
    /// Octree level of the finest grid (2^level cells per axis), 0..=13.
    #[arg(long)]
    pub level: u32,
    /// Also write the prepared asset (cache format) to this file.
    #[arg(short = 'o', long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Neither read nor write the asset cache; always prepare from the model.
    #[arg(long)]
    pub no_cache: bool,
    /// Voxelize a mesh on the GPU (conservative rasterization along each
    /// triangle's dominant axis) and report how its voxels differ from the exact CPU
    /// voxelization per level (`differs_from_cpu`); never uses the cache.
    #[arg(long)]
    pub gpu: bool,
    /// With `--gpu`: `exact` (the CPU's triangle–box test in f64, its very voxel set; the
    /// default where the adapter has f64 shaders) or `raster` (conservative
    /// rasterization, a near superset).
    #[arg(long, value_enum, requires = "gpu")]
    pub gpu_method: Option<GpuMethodArg>,
    /// With `--gpu`: time each GPU submission alone and list the longest per kind in
    /// `gpu.submissions` (a driver resets the GPU when one runs too long). Serializes the
    /// CPU and the GPU, so `gpu_seconds` grows.
    #[arg(long, requires = "gpu")]
    pub time_submissions: bool,
}

/// `--gpu-method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum GpuMethodArg {
    /// The CPU's test in f64 per cell (needs f64 shaders).
    Exact,
    /// Conservative rasterization.
    Raster,
}

/// What the JSON output holds (and the table shows).
#[derive(Serialize)]
pub(crate) struct Report {
    pub(crate) model: PathBuf,
    pub(crate) level: u32,
    /// "hit", "rebuilt", "asset_file" (the model is a prepared asset) or "disabled".
    pub(crate) cache: CacheReport,
    /// Where `-o` wrote the asset.
    pub(crate) output: Option<PathBuf>,
    pub(crate) object_space_center: [f64; 3],
    pub(crate) object_space_scale: f64,
    /// Stage times when the asset was prepared (absent on a cache hit).
    pub(crate) stages: Option<StageTimes>,
    /// Voxelizer report when the asset was prepared.
    pub(crate) voxelize: Option<VoxelizeReport>,
    /// Seconds for the whole command (load or prepare, and writing `-o`).
    pub(crate) total_s: f64,
    pub(crate) levels: Vec<LevelStats>,
    /// With `--gpu`: per level, the GPU's voxels against the exact CPU voxelization's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) differs_from_cpu: Option<Vec<LevelDiff>>,
    /// With `--gpu`: the adapter, the GPU's counts and times against the CPU's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) gpu: Option<GpuReport>,
}

#[derive(Serialize)]
pub(crate) struct CacheReport {
    pub(crate) status: &'static str,
    pub(crate) reason: Option<String>,
    pub(crate) path: Option<PathBuf>,
    pub(crate) write_error: Option<String>,
}

/// One level of `differs_from_cpu`.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct LevelDiff {
    pub(crate) level: u32,
    pub(crate) gpu_voxels: u64,
    pub(crate) cpu_voxels: u64,
    /// Cells the GPU sets and the CPU does not.
    pub(crate) extra: u64,
    /// Cells the CPU sets and the GPU does not.
    pub(crate) missing: u64,
}

/// `gpu` in the report.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct GpuReport {
    pub(crate) adapter: String,
    pub(crate) adapter_is_software: bool,
    /// `Exact` or `Raster`.
    pub(crate) method: GpuVoxelizeMethod,
    #[serde(flatten)]
    pub(crate) stats: GpuVoxelizeStats,
    /// GPU voxelization, host wall clock (raster, sort, merge, readback).
    pub(crate) gpu_seconds: f64,
    /// The CPU voxelizer on the same mesh and level, on this machine.
    pub(crate) cpu_seconds: f64,
    /// `cpu_seconds / gpu_seconds`.
    pub(crate) speedup: f64,
    /// With `--time-submissions`: per kind of submission, the longest first.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(crate) submissions: Vec<ssbvb_gpu::submissions::SubmissionTimes>,
}
