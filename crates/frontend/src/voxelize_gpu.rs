//! `ssbvb voxelize MODEL --level N --gpu [--gpu-method exact|raster]`: the mesh voxelized
//! on the GPU ([`GpuVoxelizer`]: by default the exact f64 test where the adapter has f64
//! shaders, else conservative rasterization), the rest of the preparation
//! as usual, and the same report as the CPU path plus `differs_from_cpu` (per level, the
//! GPU's voxels against the exact CPU voxelization's, both carried down the LOD chain by
//! OR-ing children) and `gpu` (adapter, fragments, raster passes, time against the CPU's).

use std::time::Instant;

use anyhow::{Context, bail};
use ssbvb_gpu_build::voxelize::{GpuVoxelizeMethod, GpuVoxelizer};
use ssbvb_voxel::cache::{hash_source, write_cache};
use ssbvb_voxel::load::load_model;
use ssbvb_voxel::model::Model;
use ssbvb_voxel::prepare::prepare_voxel_set;
use ssbvb_voxel::progress::NoProgress;
use ssbvb_voxel::voxelize::voxelize_mesh;

use crate::voxelize_report::{
    CacheReport, GpuMethodArg, GpuReport, LevelDiff, Report, VoxelizeArgs,
};

/// Per level from the finest down: extra and missing cells between two Morton-sorted sets.
fn differences(level: u32, mut gpu: Vec<u64>, mut cpu: Vec<u64>) -> Vec<LevelDiff> {
    let mut out = Vec::new();
    for l in (0..=level).rev() {
        let (mut extra, mut missing) = (0u64, 0u64);
        let (mut i, mut j) = (0, 0);
        while i < gpu.len() || j < cpu.len() {
            match (gpu.get(i), cpu.get(j)) {
                (Some(a), Some(b)) if a == b => (i, j) = (i + 1, j + 1),
                (Some(a), Some(b)) if a < b => (extra, i) = (extra + 1, i + 1),
                (Some(_), None) => (extra, i) = (extra + 1, i + 1),
                _ => (missing, j) = (missing + 1, j + 1),
            }
        }
        out.push(LevelDiff {
            level: l,
            gpu_voxels: gpu.len() as u64,
            cpu_voxels: cpu.len() as u64,
            extra,
            missing,
        });
        for v in [&mut gpu, &mut cpu] {
            for c in v.iter_mut() {
                *c >>= 3;
            }
            v.dedup();
        }
    }
    out
}

/// Runs the GPU path of `ssbvb voxelize`.
pub(crate) fn run(args: &VoxelizeArgs) -> anyhow::Result<Report> {
    let start = Instant::now();
    let mesh = match load_model(&args.model)? {
        Model::Mesh(m) => m,
        _ => bail!(
            "{}: --gpu voxelizes meshes; this is a voxel model (voxelize it without --gpu)",
            args.model.display()
        ),
    };
    let ctx = crate::adapter_cmd::headless_context(&[])?;
    let voxelizer = GpuVoxelizer::new(&ctx)?;
    ctx.time_submissions(args.time_submissions);
    let method = match args.gpu_method {
        Some(GpuMethodArg::Exact) => GpuVoxelizeMethod::Exact,
        Some(GpuMethodArg::Raster) => GpuVoxelizeMethod::Raster,
        None if voxelizer.has_exact() => GpuVoxelizeMethod::Exact,
        None => GpuVoxelizeMethod::Raster,
    };
    let t0 = Instant::now();
    let (set, stats) = voxelizer
        .voxelize_by(&ctx, &mesh, args.level, None, method)
        .with_context(|| format!("{}: GPU voxelization failed", args.model.display()))?;
    let gpu_seconds = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let cpu = voxelize_mesh(&mesh, args.level, &NoProgress)
        .with_context(|| format!("{}: CPU voxelization failed", args.model.display()))?;
    let cpu_seconds = t1.elapsed().as_secs_f64();
    let differs = differences(args.level, set.voxels.codes.clone(), cpu.voxels.codes);
    let voxelize = set.report.clone();
    let (asset, mut prep) = prepare_voxel_set(set, &NoProgress);
    prep.stages.voxelize_s = gpu_seconds;
    if let Some(out) = &args.out {
        write_cache(out, &asset, hash_source(&args.model)?, args.level)?;
    }
    Ok(Report {
        model: args.model.clone(),
        level: args.level,
        cache: CacheReport {
            status: "disabled",
            reason: None,
            path: None,
            write_error: None,
        },
        output: args.out.clone(),
        object_space_center: asset.object_space.center.to_array(),
        object_space_scale: asset.object_space.scale,
        stages: Some(prep.stages),
        voxelize: Some(voxelize),
        total_s: start.elapsed().as_secs_f64(),
        levels: prep.levels,
        differs_from_cpu: Some(differs),
        gpu: Some(GpuReport {
            adapter: ctx.report().to_string(),
            adapter_is_software: ctx.report().is_software,
            method,
            stats,
            gpu_seconds,
            cpu_seconds,
            speedup: cpu_seconds / gpu_seconds,
            submissions: ctx.submission_times(),
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::differences;
    use ssbvb_voxel::svo::morton_encode;

    #[test]
    fn differences_count_per_level_after_or_merging() {
        let code = |c: [u32; 3]| morton_encode(c);
        // Level 2: the GPU has one extra cell in another parent and misses one whose
        // sibling it has (so the parent level agrees there).
        let mut gpu = vec![code([0, 0, 0]), code([1, 0, 0]), code([3, 3, 3])];
        let mut cpu = vec![code([0, 0, 0]), code([0, 1, 0]), code([1, 0, 0])];
        gpu.sort();
        cpu.sort();
        let d = differences(2, gpu, cpu);
        let rows: Vec<_> = d
            .iter()
            .map(|r| (r.level, r.gpu_voxels, r.cpu_voxels, r.extra, r.missing))
            .collect();
        assert_eq!(
            rows,
            vec![(2, 3, 3, 1, 1), (1, 2, 1, 1, 0), (0, 1, 1, 0, 0)]
        );
    }
}
