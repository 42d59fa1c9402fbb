//! Preparation of a mesh in bounded memory: voxelized region by region, every level
//! streamed into its packed point cloud and its lookup as the regions arrive.
//!
//! The whole-grid path holds the finest level's float attributes (44 bytes per voxel)
//! and every coarser level's at once: 5 GiB for the bunny at level 12. Here a region of
//! `2^REGION_LOG` cells per axis is voxelized, packed (16 bytes per voxel) and coarsened
//! `REGION_LOG` times inside itself — a region is a whole octree subtree, so its parents
//! are complete — and only its root (one voxel of level `level - REGION_LOG`) is kept in
//! floats; the levels above those roots are built at the end from them. Codes go to
//! [`LookupBuilder`]s, which keep only the 4³ leaves. What stays is what the asset holds
//! anyway (the point clouds) plus one region's floats. The result equals the whole-grid
//! path's exactly (same per-brick voxels, same per-sibling-run averages; a test checks).

use std::time::Instant;

use super::{
    PrepareStats, StageTimes, asset_level_stats, build_proxy_timed, point_cloud_of,
    stats_with_seconds,
};
use crate::asset::{LodLevel, PackedVoxel, VoxelAsset};
use crate::lookup::LookupBuilder;
use crate::model::Mesh;
use crate::progress::Progress;
use crate::svo::{LevelVoxels, build_lod_chain};
use crate::voxelize::{VoxelizeError, voxelize_mesh_regions};

/// Log2 of the region edge in finest cells: 256³ regions hold a few hundred thousand
/// surface voxels (~10 MB of float attributes) at most.
pub const REGION_LOG: u32 = 8;

/// Prepares a mesh at `level` region by region (regions of `2^region_log` cells per axis;
/// see the module docs).
pub fn prepare_mesh_in_regions(
    mesh: &Mesh,
    level: u32,
    region_log: u32,
    progress: &dyn Progress,
) -> Result<(VoxelAsset, PrepareStats), VoxelizeError> {
    let start = Instant::now();
    let region_log = region_log.min(level);
    // The coarsest level complete inside one region: the regions' roots.
    let root_level = level - region_log;
    let mut stages = StageTimes::default();
    let mut clouds: Vec<Vec<PackedVoxel>> = vec![Vec::new(); level as usize + 1];
    let mut lookups: Vec<LookupBuilder> = (0..=level).map(LookupBuilder::new).collect();
    let mut seconds = vec![0.0; level as usize + 1];
    let mut roots = LevelVoxels {
        level: root_level,
        ..Default::default()
    };
    let mut sink_s = 0.0;
    let (object_space, report) = voxelize_mesh_regions(mesh, level, region_log, progress, |v| {
        let t_sink = Instant::now();
        let mut v = v;
        for l in (root_level + 1..=level).rev() {
            let t = Instant::now();
            clouds[l as usize].extend(point_cloud_of(&v).voxels);
            let t_pc = t.elapsed().as_secs_f64();
            let t = Instant::now();
            lookups[l as usize].extend(&v.codes);
            let t_lookup = t.elapsed().as_secs_f64();
            let t = Instant::now();
            v = v.coarsen();
            stages.octree_s += t.elapsed().as_secs_f64();
            stages.point_clouds_s += t_pc;
            stages.lookups_s += t_lookup;
            seconds[l as usize] += t_pc + t_lookup;
        }
        roots.codes.extend_from_slice(&v.codes);
        roots.normals.extend_from_slice(&v.normals);
        roots.colors.extend_from_slice(&v.colors);
        roots.uvs.extend_from_slice(&v.uvs);
        sink_s += t_sink.elapsed().as_secs_f64();
    })?;
    stages.voxelize_s = start.elapsed().as_secs_f64() - sink_s;

    // The levels from the regions' roots up to the root of the grid.
    let t = Instant::now();
    let chain = build_lod_chain(roots, progress);
    stages.octree_s += t.elapsed().as_secs_f64();
    for v in chain {
        let l = v.level as usize;
        let t = Instant::now();
        clouds[l] = point_cloud_of(&v).voxels;
        let t_pc = t.elapsed().as_secs_f64();
        let t = Instant::now();
        lookups[l].extend(&v.codes);
        let t_lookup = t.elapsed().as_secs_f64();
        stages.point_clouds_s += t_pc;
        stages.lookups_s += t_lookup;
        seconds[l] += t_pc + t_lookup;
    }

    progress.begin("lookups and proxies", level as u64 + 1);
    let mut lods = Vec::with_capacity(level as usize + 1);
    for (l, (voxels, builder)) in clouds.into_iter().zip(lookups).enumerate() {
        let t = Instant::now();
        let lookup = builder.finish();
        let t_lookup = t.elapsed().as_secs_f64();
        stages.lookups_s += t_lookup;
        let (proxy, t_proxy) = build_proxy_timed(&lookup);
        stages.proxies_s += t_proxy;
        seconds[l] += t_lookup + t_proxy;
        lods.push(LodLevel {
            level: l as u32,
            point_cloud: crate::asset::PointCloud { voxels },
            lookup,
            proxy,
        });
        progress.advance(1);
    }
    progress.end();
    let asset = VoxelAsset { object_space, lods };
    stages.total_s = start.elapsed().as_secs_f64();
    let levels = stats_with_seconds(asset_level_stats(&asset), seconds);
    let stats = PrepareStats {
        level,
        object_space_center: object_space.center.to_array(),
        object_space_scale: object_space.scale,
        voxelize: report,
        stages,
        levels,
    };
    Ok((asset, stats))
}
