//! Region-by-region voxelization of a mesh, for preparation in bounded memory.
//!
//! The grid is cut into cubic regions of `2^region_log` cells per axis. Bricks are already
//! in Morton order, so a region's bricks are a contiguous run of them and the regions come
//! out in Morton order too: concatenated, the regions' voxels are exactly
//! [`voxelize_mesh`](super::voxelize_mesh)'s (same bricks, same per-brick computation).
//! Only the gradient-normal fallback looks beyond a voxel's own cell: a neighbour in
//! another region is found by voxelizing that neighbour's brick again, which gives the same
//! cells the whole-grid pass would (a test compares both on meshes with such voxels on
//! region borders).

use std::collections::HashMap;
use std::sync::Mutex;

use rayon::prelude::*;

use super::mesh::{Chunk, MeshBricks, gradient_normals};
use super::{MAX_REGION_VOXELS, VoxelizeError, VoxelizeReport};
use crate::model::{Mesh, ObjectSpace};
use crate::progress::Progress;
use crate::svo::{LevelVoxels, morton_encode};

/// Voxelizes `mesh` at `level` one region of `2^region_log` cells per axis at a time (the
/// log is clamped to the brick size and the grid), handing each non-empty region's voxels,
/// Morton-sorted, to `sink` in Morton order of the regions. Returns the object space and
/// the report of the whole voxelization.
pub fn voxelize_mesh_regions(
    mesh: &Mesh,
    level: u32,
    region_log: u32,
    progress: &dyn Progress,
    mut sink: impl FnMut(LevelVoxels),
) -> Result<(ObjectSpace, VoxelizeReport), VoxelizeError> {
    let bricks = MeshBricks::new(mesh, level, MAX_REGION_VOXELS, None, progress)?;
    let brick_log = bricks.brick_log();
    let region_log = region_log.clamp(brick_log, level);
    // A brick's region: its code without the brick digits below the region.
    let shift = 3 * (region_log - brick_log);
    let mut report = bricks.report.clone();
    let all = &bricks.bricks;
    progress.begin("voxelizing", all.len() as u64);
    let mut start = 0;
    while start < all.len() {
        let region = all[start].0 >> shift;
        let end = all[start..]
            .iter()
            .position(|b| b.0 >> shift != region)
            .map_or(all.len(), |n| start + n);
        let chunks: Vec<Chunk> = all[start..end]
            .par_chunks(16)
            .map(|run| {
                let c = bricks.voxelize_run(run);
                progress.advance(run.len() as u64);
                c
            })
            .collect();
        let mut voxels = LevelVoxels {
            level,
            ..Default::default()
        };
        let mut missing = Vec::new();
        for c in chunks {
            c.append_to(&mut voxels, &mut missing);
        }
        if !missing.is_empty() {
            report.normal_fallbacks += missing.len() as u64;
            let others: Mutex<HashMap<u64, Vec<u64>>> = Mutex::default();
            let fixed = gradient_normals(&voxels, &missing, |q| {
                let code = morton_encode(q);
                if code >> (3 * region_log) == region {
                    return voxels.codes.binary_search(&code).is_ok();
                }
                let brick = code >> (3 * brick_log);
                let mut others = others.lock().unwrap_or_else(|e| e.into_inner());
                others
                    .entry(brick)
                    .or_insert_with(|| bricks.brick_codes(brick))
                    .binary_search(&code)
                    .is_ok()
            });
            for (i, normal) in fixed {
                voxels.normals[i] = normal;
            }
        }
        sink(voxels);
        start = end;
    }
    progress.end();
    Ok((bricks.object_space, report))
}
