//! The command line of `ssbvb bench`: [`BenchArgs`] and the [`Preset`]s. Its own file so
//! that the presets and the harness read the arguments without importing the dispatch.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

/// Benchmark presets.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Preset {
    /// Small: CI-sized (bunny levels 5-6, 160x120, few frames).
    Quick,
    /// The measurement run: bunny levels 7-12 at 640x480 and 1280x720, plus knob sweeps.
    Full,
    /// The ray casting against cube rasterization study: a filled ball, 50 % random voxels
    /// and the bunny mesh, model resolutions 8-512 (levels 3-9), targets 640x480-2560x1440,
    /// and the fastest technique per cell (the thesis's Table 11).
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
    /// RastaVox: surface-model memory of the bunny and the knight at each level
    /// (`--levels`, default 5-9) beside the SSBVB asset, the GPU build time, and a
    /// pixel-error sweep (0, 1, 2, 4) on the bunny at the finest of those levels (and on
    /// `--instances N` bunnies) against the drawn model and the finest level; writes
    /// rastavox.csv, rastavox.json and rastavox.md.
    Rastavox,
    /// Dynamic objects: the bunny (`--levels`, default 7-9) static against twisting and
    /// re-voxelized on the GPU every frame (update stages, the frame after it, and the same
    /// update on the CPU); writes dynamic.csv, dynamic.json and dynamic.md.
    Dynamic,
    /// Voxel cone tracing: the lit default scene against the plain frame, the cone count,
    /// aperture and volume resolution swept, each row's cone-pass time beside the filter's
    /// and its errors (AO, shadow, bounce, lit output) against 256-sample Monte Carlo, and
    /// the defaults on 64 bunnies; writes vct.csv, vct.json and vct.md.
    Vct,
    /// Volumetric billboards: the cloud and the bunny's coverage volume against the
    /// emission–absorption integral with the slice spacing and mip bias swept (time,
    /// slice fragments per pixel, PSNR, SSIM), and the thesis's crossover: the cow and
    /// bunny meshes against their 128³ volumes by screen size; writes volumes.csv,
    /// volumes.json and volumes.md.
    Volumes,
    /// The seed paper's comparison (Table 2 and Figure 9): every bundled model at level 9,
    /// 1280x720, with SSBVB (exact and fast march), ESVO, the octree caster and dense DDA,
    /// then the 4096-bunny grid; writes bench.*, scale.* and paper.{csv,json,md} (each
    /// SSBVB frame over the ray casters' of the same run, beside the paper's 0.28).
    Paper,
    /// Image quality still and in motion: an orbit and a dolly over the 64-bunny grid
    /// drawn by each technique and by the reference at `--flip-samples` per pixel; per
    /// technique FLIP of the still frame and over the path, and `flicker_ratio` (frame-to-
    /// frame FLIP over the reference's); writes quality.{csv,json,md}, crops and FLIP maps.
    Quality,
}

/// Arguments of `ssbvb bench`.
#[derive(Args, Debug, Clone)]
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
    #[arg(long, value_delimiter = ',', value_parser = ssbvb_engine::values::parse_size)]
    pub sizes: Option<Vec<(u32, u32)>>,
    /// Techniques to run (comma-separated names; default: all).
    #[arg(long, value_delimiter = ',')]
    pub techniques: Option<Vec<String>>,
    /// Timed frames per cell instead of the preset's.
    #[arg(long)]
    pub frames: Option<usize>,
    /// Views of `--preset quality` to run (comma-separated: path, hover, bunny; default
    /// all).
    #[arg(long, value_delimiter = ',')]
    pub views: Option<Vec<String>>,
    /// Instance counts of `--preset scale` (comma-separated; default 1,16,256,4096).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(usize))]
    pub instances: Option<Vec<usize>>,
    /// GPU memory budgets in MiB (comma-separated): the budgets of `--preset memory`;
    /// with another preset, every cell is uploaded under the first one (techniques that
    /// read whole levels are skipped).
    #[arg(long, value_delimiter = ',', value_name = "MIB")]
    pub gpu_budget: Option<Vec<u64>>,
    /// Samples per pixel of the supersampled reference that `flip_mean` is measured
    /// against (1 to 1024).
    #[arg(long, default_value_t = 16, value_parser = ssbvb_engine::values::parse_samples)]
    pub flip_samples: u32,
    /// Fault injection for tests: `device-lost@ROW` destroys the device before the main
    /// matrix measures row ROW (from 0; repeatable). That row is reported failed and the
    /// rows after it run on a new device. `oom@ROW` refuses that row's first large
    /// allocation: the row is reported failed with the resource named.
    #[arg(long, hide = true, value_parser = ssbvb_engine::faults::parse_fault)]
    pub inject_fault: Vec<ssbvb_engine::faults::Fault>,
    /// The device's limits: `adapter` (its own) or `webgpu` (WebGPU's defaults and no
    /// optional feature; the techniques' pipelines are checked against them up front, and
    /// what they need beyond them is named).
    #[arg(long, default_value = "adapter", value_parser = ssbvb_engine::values::parse_limits)]
    pub limits: ssbvb_gpu::DeviceLimits,
}

impl BenchArgs {
    /// `--flip-samples` as a sample grid (validated when parsed).
    pub(crate) fn flip_samples_grid(&self) -> ssbvb_voxel::reference::SampleGrid {
        ssbvb_voxel::reference::SampleGrid::from_count(self.flip_samples)
            .unwrap_or(ssbvb_voxel::reference::SampleGrid::CENTRE)
    }

    /// The first `--sizes`, else `default`: the one image size of the presets that
    /// measure at one size.
    pub(crate) fn first_size(&self, default: (u32, u32)) -> (u32, u32) {
        self.sizes
            .as_ref()
            .and_then(|s| s.first().copied())
            .unwrap_or(default)
    }
}
