//! Helpers of the engine's unit tests.

use std::sync::Arc;

use glam::DVec3;
use ssbvb_voxel::asset::VoxelAsset;

/// An asset holding one voxel, cell (0, 0, 0) of a `2^level` grid over `[-1, 1]³`.
pub fn one_voxel(level: u32) -> Arc<VoxelAsset> {
    let voxels =
        ssbvb_voxel::voxelize::voxels_from_cells(level, &[[0, 0, 0]], &[[1.0, 0.5, 0.25, 1.0]])
            .unwrap();
    let set = ssbvb_voxel::voxelize::VoxelSet {
        object_space: ssbvb_voxel::model::ObjectSpace {
            center: DVec3::ZERO,
            scale: 1.0,
        },
        voxels,
        report: Default::default(),
    };
    let (asset, _) =
        ssbvb_voxel::prepare::prepare_voxel_set(set, &ssbvb_voxel::progress::NoProgress);
    Arc::new(asset)
}
