//! Preparation of a mesh in bounded memory: voxelized region by region, every level
//! streamed into its packed point cloud and its lookup as the regions arrive.
//!
//! The whole-grid path holds the finest level's float attributes (44 bytes per voxel) and
//! every coarser level's at once (for the bunny at level 12: docs/benchmarks.md,
//! "Preparation in bounded memory"). Here a region of `2^REGION_LOG` cells per axis is
//! voxelized, packed (16 bytes per voxel) and coarsened `REGION_LOG` times inside itself —
//! a region is a whole octree subtree, so its parents are complete — and only its root (one
//! voxel of level `level - REGION_LOG`) is kept in floats; the levels above those roots are
//! built at the end from them. Codes go to [`LookupBuilder`]s, which keep only the 4³
//! leaves. What stays is what the asset holds anyway (the point clouds) plus one region's
//! floats. The result equals the whole-grid path's exactly (same per-brick voxels, same
//! per-sibling-run averages; a test checks).

use web_time::Instant;

use std::path::Path;

use super::{
    LevelStats, PrepareStats, StageTimes, asset_level_stats, build_proxy_timed, point_cloud_of,
    stats_with_seconds,
};
use crate::asset::{LodLevel, PackedVoxel, VoxelAsset};
use crate::cache::{CacheError, CacheStream};
use crate::lookup::LookupBuilder;
use crate::model::Mesh;
use crate::progress::Progress;
use crate::svo::{LevelVoxels, build_lod_chain};
use crate::voxelize::{VoxelizeError, voxelize_mesh_regions};

/// Log2 of the region edge in finest cells: 256³ regions hold a few hundred thousand
/// surface voxels (~10 MB of float attributes) at most.
pub const REGION_LOG: u32 = 8;

/// What the region-by-region pass produced besides the levels it emitted.
struct Streamed {
    object_space: crate::model::ObjectSpace,
    report: crate::voxelize::VoxelizeReport,
    stages: StageTimes,
    /// Seconds of voxelization, coarsening and emission, per level.
    seconds: Vec<f64>,
}

/// Why streaming stopped: the voxelizer, or the level sink.
enum StreamError<E> {
    Voxelize(VoxelizeError),
    Sink(E),
}

/// Voxelizes `mesh` region by region and hands every level's voxels to `emit`, each level
/// in Morton order (levels interleave). `emit`'s time counts as point-cloud time.
fn stream_levels<E>(
    mesh: &Mesh,
    level: u32,
    region_log: u32,
    progress: &dyn Progress,
    emit: &mut dyn FnMut(&LevelVoxels) -> Result<(), E>,
) -> Result<Streamed, StreamError<E>> {
    let start = Instant::now();
    let region_log = region_log.min(level);
    // The coarsest level complete inside one region: the regions' roots.
    let root_level = level - region_log;
    let mut stages = StageTimes::default();
    let mut seconds = vec![0.0; level as usize + 1];
    let mut roots = LevelVoxels {
        level: root_level,
        ..Default::default()
    };
    let mut sink_s = 0.0;
    let mut failed: Option<E> = None;
    let (object_space, report) = voxelize_mesh_regions(mesh, level, region_log, progress, |v| {
        if failed.is_some() {
            return;
        }
        let t_sink = Instant::now();
        let mut v = v;
        for l in (root_level + 1..=level).rev() {
            let t = Instant::now();
            if let Err(e) = emit(&v) {
                failed = Some(e);
                return;
            }
            let t_emit = t.elapsed().as_secs_f64();
            let t = Instant::now();
            v = v.coarsen();
            stages.octree_s += t.elapsed().as_secs_f64();
            stages.point_clouds_s += t_emit;
            seconds[l as usize] += t_emit;
        }
        roots.codes.extend_from_slice(&v.codes);
        roots.normals.extend_from_slice(&v.normals);
        roots.colors.extend_from_slice(&v.colors);
        roots.uvs.extend_from_slice(&v.uvs);
        sink_s += t_sink.elapsed().as_secs_f64();
    })
    .map_err(StreamError::Voxelize)?;
    if let Some(e) = failed {
        return Err(StreamError::Sink(e));
    }
    stages.voxelize_s = start.elapsed().as_secs_f64() - sink_s;

    // The levels from the regions' roots up to the root of the grid.
    let t = Instant::now();
    let chain = build_lod_chain(roots, progress);
    stages.octree_s += t.elapsed().as_secs_f64();
    for v in &chain {
        let t = Instant::now();
        emit(v).map_err(StreamError::Sink)?;
        let t_emit = t.elapsed().as_secs_f64();
        stages.point_clouds_s += t_emit;
        seconds[v.level as usize] += t_emit;
    }
    Ok(Streamed {
        object_space,
        report,
        stages,
        seconds,
    })
}

/// Prepares a mesh at `level` region by region (regions of `2^region_log` cells per axis;
/// see the module docs).
pub fn prepare_mesh_in_regions(
    mesh: &Mesh,
    level: u32,
    region_log: u32,
    progress: &dyn Progress,
) -> Result<(VoxelAsset, PrepareStats), VoxelizeError> {
    let start = Instant::now();
    let mut clouds: Vec<Vec<PackedVoxel>> = vec![Vec::new(); level as usize + 1];
    let mut lookups: Vec<LookupBuilder> = (0..=level).map(LookupBuilder::new).collect();
    let mut lookup_s = vec![0.0; level as usize + 1];
    let mut emit = |v: &LevelVoxels| -> Result<(), std::convert::Infallible> {
        let l = v.level as usize;
        clouds[l].extend(point_cloud_of(v).voxels);
        let t = Instant::now();
        lookups[l].extend(&v.codes);
        lookup_s[l] += t.elapsed().as_secs_f64();
        Ok(())
    };
    let streamed = match stream_levels(mesh, level, region_log, progress, &mut emit) {
        Ok(s) => s,
        Err(StreamError::Voxelize(e)) => return Err(e),
        Err(StreamError::Sink(never)) => match never {},
    };
    let mut stages = streamed.stages;
    let mut seconds = streamed.seconds;
    let building: f64 = lookup_s.iter().sum();
    stages.lookups_s += building;
    stages.point_clouds_s -= building;

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
    let object_space = streamed.object_space;
    let asset = VoxelAsset { object_space, lods };
    stages.total_s = start.elapsed().as_secs_f64();
    let levels = stats_with_seconds(asset_level_stats(&asset), seconds);
    let stats = PrepareStats::new(level, &object_space, streamed.report, stages, levels);
    Ok((asset, stats))
}

/// Why a preparation into a cache file failed.
#[derive(Debug, thiserror::Error)]
pub enum PrepareToFileError {
    /// The voxelization failed.
    #[error(transparent)]
    Voxelize(#[from] VoxelizeError),
    /// The cache file (or a spill file beside it) could not be written.
    #[error(transparent)]
    Cache(#[from] CacheError),
}

/// Prepares a mesh at `level` straight into a cache file at `path` (for a source with hash
/// `source_hash`), region by region, never holding a level: the voxels go to spill files
/// beside `path` as they come (see [`CacheStream`]). Peak memory is one region plus the
/// page indexes, whatever the level. The file equals [`crate::cache::write_cache`]'s for
/// the asset [`prepare_mesh_in_regions`] returns.
pub fn prepare_mesh_to_cache(
    mesh: &Mesh,
    level: u32,
    region_log: u32,
    path: &Path,
    source_hash: u128,
    progress: &dyn Progress,
) -> Result<PrepareStats, PrepareToFileError> {
    let start = Instant::now();
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let mut stream = CacheStream::new(&dir, level)?;
    let mut emit = |v: &LevelVoxels| stream.push(v.level, &point_cloud_of(v).voxels);
    let streamed = match stream_levels(mesh, level, region_log, progress, &mut emit) {
        Ok(s) => s,
        Err(StreamError::Voxelize(e)) => return Err(e.into()),
        Err(StreamError::Sink(e)) => return Err(e.into()),
    };
    let mut stages = streamed.stages;
    let t = Instant::now();
    let written = stream.finish(path, source_hash, &streamed.object_space)?;
    stages.proxies_s += t.elapsed().as_secs_f64();
    stages.total_s = start.elapsed().as_secs_f64();
    let mut nodes = 0u64;
    let levels = written
        .iter()
        .enumerate()
        .map(|(l, w)| {
            nodes += w.voxels;
            LevelStats::from_counts(l as u32, w, nodes, Some(streamed.seconds[l]))
        })
        .collect();
    Ok(PrepareStats::new(
        level,
        &streamed.object_space,
        streamed.report,
        stages,
        levels,
    ))
}
