//! The whole preparation of one model: voxelize → LOD chain → per-level point cloud,
//! sparse lookup and proxy mesh, with statistics.
//!
//! Memory is the constraint at high levels (level 12 of the bunny is ~57 M voxels), so the
//! stages hand their data on and free it: the LOD chain is built from the voxelization,
//! then each level, finest first, is turned into its point cloud and lookup and its
//! floating-point attributes are dropped before the next level is converted.

mod regions;

pub use regions::{PrepareToFileError, REGION_LOG, prepare_mesh_in_regions, prepare_mesh_to_cache};

use web_time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::asset::{
    GPU_COLOR_BYTES, GPU_NORMAL_BYTES, GPU_VOXEL_BYTES, LodLevel, MAX_LEVEL, PackedVoxel,
    PointCloud, SparseLookup, VoxelAsset,
};
use crate::model::Model;
use crate::progress::Progress;
use crate::proxy::build_proxy;
use crate::svo::{LevelVoxels, build_lod_chain, morton_decode, octree_bytes};
use crate::voxelize::{VoxelFill, VoxelSet, VoxelizeError, VoxelizeReport, voxelize_voxels_with};

/// Highest level [`prepare_asset`] accepts unless [`PrepareOptions::max_level`] raises it.
/// Meshes are prepared region by region, so memory is the asset's own (16 bytes per voxel
/// on the CPU; level 13 of a scanned model: docs/benchmarks.md, "Preparation in bounded
/// memory").
pub const DEFAULT_MAX_LEVEL: u32 = 13;

/// Knobs of [`prepare_asset_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct PrepareOptions {
    /// Highest level accepted; values above [`MAX_LEVEL`] are treated as [`MAX_LEVEL`].
    pub max_level: u32,
    /// Which occupied cells a voxel model keeps (meshes are always surface-voxelized).
    pub voxel_fill: VoxelFill,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        Self {
            max_level: DEFAULT_MAX_LEVEL,
            voxel_fill: VoxelFill::Shell,
        }
    }
}

/// Wall-clock seconds of each preparation stage.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Voxelization (or voxel-model resampling) of the finest level.
    pub voxelize_s: f64,
    /// Building the coarser levels (octree / LOD chain).
    pub octree_s: f64,
    /// Packing the point clouds of all levels.
    pub point_clouds_s: f64,
    /// Building the sparse lookups of all levels.
    pub lookups_s: f64,
    /// Building the proxy meshes of all levels.
    pub proxies_s: f64,
    /// The whole preparation.
    pub total_s: f64,
}

/// Size statistics of one LOD level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LevelStats {
    /// Grid level.
    pub level: u32,
    /// Voxels (point-cloud entries).
    pub voxels: u64,
    /// Occupied 16³ regions (the bricks of the proxy mesh).
    pub resident_pages: u64,
    /// Nodes of the sparse lookup's occupancy tree (12 bytes each).
    pub lookup_nodes: u64,
    /// GPU bytes of the voxel attributes: colour plus normal, [`GPU_VOXEL_BYTES`] per
    /// voxel (the cell is implied by the lookup).
    pub point_cloud_bytes: u64,
    /// Of `point_cloud_bytes`: the colours.
    pub color_bytes: u64,
    /// Of `point_cloud_bytes`: the normals.
    pub normal_bytes: u64,
    /// Bytes of the CPU-side packed point cloud (16 per voxel, with cell and uv).
    pub cpu_point_cloud_bytes: u64,
    /// GPU bytes of the sparse lookup (the occupancy tree's nodes).
    pub lookup_bytes: u64,
    /// `(lookup_bytes + point_cloud_bytes) / voxels`: what a voxel costs the renderer.
    pub bytes_per_voxel: f64,
    /// `lookup_bytes / voxels`.
    pub lookup_bytes_per_voxel: f64,
    /// Bytes a dense `u32` lookup texture of the level would take.
    pub dense_lookup_bytes: u64,
    /// `lookup_bytes` as a percentage of `dense_lookup_bytes`.
    pub lookup_percent_of_dense: f64,
    /// Octree nodes down to this level (levels 0..=level).
    pub octree_nodes: u64,
    /// Bytes of the octree down to this level: 8-byte nodes plus 16-byte packed
    /// attributes per node (see [`octree_bytes`]).
    pub octree_bytes: u64,
    /// Triangles of the level's proxy mesh.
    pub proxy_triangles: u64,
    /// Seconds spent on this level's point cloud, lookup and proxy (absent when the
    /// level came from the cache).
    pub seconds: Option<f64>,
}

/// What [`prepare_asset`] did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrepareStats {
    /// Finest level.
    pub level: u32,
    /// Object-space centre (model units).
    pub object_space_center: [f64; 3],
    /// Object-space scale (model units → object units).
    pub object_space_scale: f64,
    /// Skipped inputs and fallbacks of the voxelizer.
    pub voxelize: VoxelizeReport,
    /// Time per stage.
    pub stages: StageTimes,
    /// Per level, from 0 to the finest.
    pub levels: Vec<LevelStats>,
}

impl LevelStats {
    /// Statistics of a level written by a streaming preparation (only its counts exist);
    /// `octree_nodes` counts the nodes of levels `0..=level`.
    pub fn from_counts(
        level: u32,
        w: &crate::cache::StreamedLevel,
        octree_nodes: u64,
        seconds: Option<f64>,
    ) -> LevelStats {
        Self::from_parts(
            level,
            w.voxels,
            w.pages,
            w.lookup_nodes,
            w.proxy_triangles,
            octree_nodes,
            seconds,
        )
    }

    /// Statistics of a prepared level; `octree_nodes` counts the nodes of levels
    /// `0..=lod.level`.
    pub fn of(lod: &LodLevel, octree_nodes: u64, seconds: Option<f64>) -> LevelStats {
        Self::from_parts(
            lod.level,
            lod.point_cloud.voxels.len() as u64,
            lod.lookup.occupied_pages(),
            lod.lookup.node_count() as u64,
            lod.proxy.triangles.len() as u64,
            octree_nodes,
            seconds,
        )
    }

    /// Every statistic from the counts of a level.
    fn from_parts(
        level: u32,
        voxels: u64,
        pages: u64,
        lookup_nodes: u64,
        proxy_triangles: u64,
        octree_nodes: u64,
        seconds: Option<f64>,
    ) -> LevelStats {
        let lookup_bytes = lookup_nodes * 4 * crate::lookup::NODE_WORDS as u64;
        let dense = 4 * (1u64 << (3 * level));
        let per_voxel = |b: u64| {
            if voxels == 0 {
                0.0
            } else {
                b as f64 / voxels as f64
            }
        };
        LevelStats {
            level,
            voxels,
            resident_pages: pages,
            lookup_nodes,
            point_cloud_bytes: voxels * GPU_VOXEL_BYTES,
            color_bytes: voxels * GPU_COLOR_BYTES,
            normal_bytes: voxels * GPU_NORMAL_BYTES,
            cpu_point_cloud_bytes: voxels * std::mem::size_of::<PackedVoxel>() as u64,
            lookup_bytes,
            bytes_per_voxel: per_voxel(lookup_bytes + voxels * GPU_VOXEL_BYTES),
            lookup_bytes_per_voxel: per_voxel(lookup_bytes),
            dense_lookup_bytes: dense,
            lookup_percent_of_dense: 100.0 * lookup_bytes as f64 / dense as f64,
            octree_nodes,
            octree_bytes: octree_bytes(octree_nodes),
            proxy_triangles,
            seconds,
        }
    }
}

impl PrepareStats {
    /// The statistics of a preparation of `level` into `object_space`.
    fn new(
        level: u32,
        object_space: &crate::model::ObjectSpace,
        voxelize: VoxelizeReport,
        stages: StageTimes,
        levels: Vec<LevelStats>,
    ) -> Self {
        Self {
            level,
            object_space_center: object_space.center.to_array(),
            object_space_scale: object_space.scale,
            voxelize,
            stages,
            levels,
        }
    }
}

/// Per-level statistics of an asset (without times), e.g. of one read from the cache.
pub fn asset_level_stats(asset: &VoxelAsset) -> Vec<LevelStats> {
    let mut nodes = 0u64;
    asset
        .lods
        .iter()
        .map(|lod| {
            nodes += lod.point_cloud.voxels.len() as u64;
            LevelStats::of(lod, nodes, None)
        })
        .collect()
}

/// Prepares a model at `level` with the default options (levels up to
/// [`DEFAULT_MAX_LEVEL`], voxel models as shells).
pub fn prepare_asset(
    model: &Model,
    level: u32,
    progress: &dyn Progress,
) -> Result<(VoxelAsset, PrepareStats), VoxelizeError> {
    prepare_asset_with(model, level, &PrepareOptions::default(), progress)
}

/// Prepares a model: voxelizes it at `level`, builds every coarser level down to 0, and per
/// level the point cloud, the sparse lookup and the proxy mesh.
pub fn prepare_asset_with(
    model: &Model,
    level: u32,
    options: &PrepareOptions,
    progress: &dyn Progress,
) -> Result<(VoxelAsset, PrepareStats), VoxelizeError> {
    let max = options.max_level.min(MAX_LEVEL);
    if level > max {
        return Err(VoxelizeError::LevelTooHigh { level, max });
    }
    let start = Instant::now();
    let mut stages = StageTimes::default();

    let set = match model {
        // Meshes go region by region: the same asset in bounded memory.
        Model::Mesh(mesh) => return prepare_mesh_in_regions(mesh, level, REGION_LOG, progress),
        Model::Voxels(voxels) => voxelize_voxels_with(voxels, level, options.voxel_fill, progress)?,
    };
    stages.voxelize_s = start.elapsed().as_secs_f64();
    Ok(prepare_from_set(set, start, stages, progress))
}

/// Prepares an already voxelized set (e.g. a procedural one, see
/// [`crate::procedural`]): every coarser level down to 0 and, per level, the point cloud,
/// the sparse lookup and the proxy mesh.
pub fn prepare_voxel_set(set: VoxelSet, progress: &dyn Progress) -> (VoxelAsset, PrepareStats) {
    prepare_from_set(set, Instant::now(), StageTimes::default(), progress)
}

fn prepare_from_set(
    set: VoxelSet,
    start: Instant,
    mut stages: StageTimes,
    progress: &dyn Progress,
) -> (VoxelAsset, PrepareStats) {
    let level = set.voxels.level;
    let object_space = set.object_space;
    let report = set.report;

    let t = Instant::now();
    let mut chain: Vec<Option<LevelVoxels>> = build_lod_chain(set.voxels, progress)
        .into_iter()
        .map(Some)
        .collect();
    stages.octree_s = t.elapsed().as_secs_f64();

    progress.begin("point clouds and lookups", chain.len() as u64);
    let mut lods: Vec<LodLevel> = Vec::with_capacity(chain.len());
    let mut seconds = vec![0.0; chain.len()];
    // Finest first: it is the largest, and freeing its attributes early lowers the peak.
    for l in (0..chain.len()).rev() {
        let Some(voxels) = chain[l].take() else {
            continue;
        };
        let t = Instant::now();
        let point_cloud = point_cloud_of(&voxels);
        let t_pc = t.elapsed().as_secs_f64();
        stages.point_clouds_s += t_pc;
        // Free the float attributes now (a partially moved struct would keep them alive
        // to the end of the iteration, next to the lookup being built).
        let LevelVoxels {
            codes,
            normals,
            colors,
            uvs,
            ..
        } = voxels;
        drop((normals, colors, uvs));
        let t = Instant::now();
        let lookup = lookup_from_codes(l as u32, &codes);
        drop(codes);
        let t_lookup = t.elapsed().as_secs_f64();
        stages.lookups_s += t_lookup;
        let (proxy, t_proxy) = build_proxy_timed(&lookup);
        stages.proxies_s += t_proxy;
        seconds[l] = t_pc + t_lookup + t_proxy;
        lods.push(LodLevel {
            level: l as u32,
            point_cloud,
            lookup,
            proxy,
        });
        progress.advance(1);
    }
    progress.end();
    lods.reverse();

    let asset = VoxelAsset { object_space, lods };
    stages.total_s = start.elapsed().as_secs_f64();
    let levels = stats_with_seconds(asset_level_stats(&asset), seconds);
    let stats = PrepareStats::new(level, &object_space, report, stages, levels);
    (asset, stats)
}

/// The proxy of a lookup and the seconds it took.
fn build_proxy_timed(lookup: &SparseLookup) -> (crate::asset::ProxyMesh, f64) {
    let t = Instant::now();
    let proxy = build_proxy(lookup);
    (proxy, t.elapsed().as_secs_f64())
}

/// `levels` with each level's preparation seconds filled in.
fn stats_with_seconds(mut levels: Vec<LevelStats>, seconds: Vec<f64>) -> Vec<LevelStats> {
    for (s, secs) in levels.iter_mut().zip(seconds) {
        s.seconds = Some(secs);
    }
    levels
}

/// Packs a level's voxels (Morton order is kept: voxel id = index).
pub fn point_cloud_of(voxels: &LevelVoxels) -> PointCloud {
    let voxels: Vec<PackedVoxel> = (0..voxels.len())
        .into_par_iter()
        .map(|i| {
            PackedVoxel::new(
                morton_decode(voxels.codes[i]),
                voxels.normals[i],
                voxels.colors[i],
                voxels.uvs[i],
            )
        })
        .collect();
    PointCloud { voxels }
}

/// Builds the sparse lookup of a level from its strictly increasing Morton codes (voxel id
/// = index): [`SparseLookup::from_codes`].
pub fn lookup_from_codes(level: u32, codes: &[u64]) -> SparseLookup {
    SparseLookup::from_codes(level, codes)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::{Mesh, VoxelModel};
    use crate::progress::NoProgress;
    use crate::svo::{Svo, morton_encode};
    use glam::Vec3;

    /// A small tetrahedron, off-centre and not axis-aligned: the model the preparation and
    /// cache tests share.
    pub(crate) fn tetra() -> Model {
        Model::Mesh(Mesh {
            positions: vec![
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.3, 0.1),
                Vec3::new(0.2, 0.1, 0.9),
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            ..Default::default()
        })
    }

    #[test]
    fn prepared_levels_are_parents_of_finer_levels() {
        let (asset, stats) = prepare_asset(&tetra(), 6, &NoProgress).unwrap();
        assert_eq!(asset.lods.len(), 7);
        assert_eq!(stats.levels.len(), 7);
        for (l, lod) in asset.lods.iter().enumerate() {
            assert_eq!(lod.level, l as u32);
            assert_eq!(lod.lookup.level, l as u32);
            let cells: Vec<[u32; 3]> = lod.point_cloud.voxels.iter().map(|v| v.cell()).collect();
            // Morton order, and the lookup maps every cell to its id.
            assert!(
                cells
                    .windows(2)
                    .all(|w| morton_encode(w[0]) < morton_encode(w[1]))
            );
            for (id, c) in cells.iter().enumerate() {
                assert_eq!(lod.lookup.get(*c), Some(id as u32));
            }
            if l + 1 < asset.lods.len() {
                let mut parents: Vec<[u32; 3]> = asset.lods[l + 1]
                    .point_cloud
                    .voxels
                    .iter()
                    .map(|v| v.cell().map(|c| c / 2))
                    .collect();
                parents.sort_by_key(|&c| morton_encode(c));
                parents.dedup();
                assert_eq!(parents, cells, "level {l}");
            }
            assert_eq!(stats.levels[l].voxels as usize, cells.len());
        }
        assert_eq!(asset.lods[0].point_cloud.voxels.len(), 1);
        let svo = Svo::from_asset(&asset).unwrap();
        assert_eq!(svo.nodes.len() as u64, stats.levels[6].octree_nodes);
        // Same cells as a direct voxelization at the coarser level.
        let (coarse, _) = prepare_asset(&tetra(), 4, &NoProgress).unwrap();
        assert_eq!(
            coarse.lods[4].point_cloud.voxels.len(),
            asset.lods[4].point_cloud.voxels.len()
        );
        for (a, b) in coarse.lods[4]
            .point_cloud
            .voxels
            .iter()
            .zip(&asset.lods[4].point_cloud.voxels)
        {
            assert_eq!(a.cell(), b.cell());
        }
    }

    /// The tetrahedron plus degenerate triangles (segments) through the grid's centre,
    /// where every region border meets: cells only they touch get gradient normals from
    /// neighbours in other regions.
    fn tetra_with_segments() -> Mesh {
        let Model::Mesh(mut mesh) = tetra() else {
            unreachable!()
        };
        let n = mesh.positions.len() as u32;
        mesh.positions.extend([
            Vec3::new(0.15, 0.9, 0.2),
            Vec3::new(0.8, 0.3, 0.7),
            Vec3::new(0.5, 0.2, 0.1),
            Vec3::new(0.52, 0.75, 0.6),
        ]);
        mesh.triangles
            .extend([[n, n + 1, n], [n + 2, n + 3, n + 3], [n, n + 3, n + 1]]);
        mesh
    }

    #[test]
    fn regions_with_gradient_normals_on_their_borders_equal_the_whole_grid() {
        let mesh = tetra_with_segments();
        for (level, region_log) in [(5, 5), (6, 5), (7, 5), (7, 6), (2, 8)] {
            let set = crate::voxelize::voxelize_mesh(&mesh, level, &NoProgress).unwrap();
            let fallbacks = set.report.normal_fallbacks;
            let (whole, _) = prepare_voxel_set(set, &NoProgress);
            let (regions, stats) =
                prepare_mesh_in_regions(&mesh, level, region_log, &NoProgress).unwrap();
            assert_eq!(stats.voxelize.normal_fallbacks, fallbacks, "level {level}");
            assert!(
                level < 5 || fallbacks > 0,
                "level {level}: no gradient normal"
            );
            assert_eq!(regions.object_space, whole.object_space);
            assert_eq!(regions.lods.len(), whole.lods.len());
            for (a, b) in regions.lods.iter().zip(&whole.lods) {
                // Not assert_eq: the Debug of a level is thousands of lines.
                assert!(
                    a == b,
                    "level {level}, regions of 2^{region_log}: LOD {} differs",
                    a.level
                );
            }
        }
    }

    #[test]
    fn streaming_into_a_file_writes_the_bytes_of_the_prepared_asset() {
        let mesh = tetra_with_segments();
        let dir = tempfile::tempdir().unwrap();
        for (level, region_log) in [(7, 5), (6, 6), (3, 8)] {
            let (asset, stats) =
                prepare_mesh_in_regions(&mesh, level, region_log, &NoProgress).unwrap();
            let a = dir.path().join(format!("a{level}.ssbvbast"));
            let b = dir.path().join(format!("b{level}.ssbvbast"));
            crate::cache::write_cache(&a, &asset, 77, level).unwrap();
            let streamed =
                prepare_mesh_to_cache(&mesh, level, region_log, &b, 77, &NoProgress).unwrap();
            assert!(
                std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
                "level {level}: the streamed file differs"
            );
            // Only the two cache files are left (spill files and temporaries are gone).
            let left: Vec<_> = std::fs::read_dir(dir.path())
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            assert_eq!(
                left.len(),
                2 * [7, 6, 3]
                    .iter()
                    .position(|&l| l == level)
                    .map_or(0, |i| i + 1),
                "{left:?}"
            );
            let key = |l: &LevelStats| {
                (
                    l.voxels,
                    l.resident_pages,
                    l.lookup_nodes,
                    l.lookup_bytes,
                    l.proxy_triangles,
                    l.octree_nodes,
                    l.point_cloud_bytes,
                )
            };
            let want: Vec<_> = stats.levels.iter().map(key).collect();
            let got: Vec<_> = streamed.levels.iter().map(key).collect();
            assert_eq!(got, want, "level {level}");
            assert_eq!(streamed.voxelize, stats.voxelize);
            assert_eq!(
                crate::cache::read_cache(&b, 77, level).unwrap(),
                asset,
                "level {level}"
            );
        }
    }

    #[test]
    fn levels_are_validated() {
        assert!(matches!(
            prepare_asset(&tetra(), 14, &NoProgress),
            Err(VoxelizeError::LevelTooHigh { level: 14, max: 13 })
        ));
        let opts = PrepareOptions {
            max_level: 99,
            ..Default::default()
        };
        assert!(matches!(
            prepare_asset_with(&tetra(), 17, &opts, &NoProgress),
            Err(VoxelizeError::LevelTooHigh { level: 17, max: 16 })
        ));
        let (asset, _) = prepare_asset(&tetra(), 0, &NoProgress).unwrap();
        assert_eq!(asset.lods.len(), 1);
        let vox = Model::Voxels(VoxelModel {
            voxels: vec![[0, 0, 0], [1, 0, 0]],
            colors: vec![],
        });
        let (asset, stats) = prepare_asset(&vox, 3, &NoProgress).unwrap();
        assert_eq!(asset.lods.len(), 4);
        assert!(stats.levels[3].voxels > 0);
    }
}
