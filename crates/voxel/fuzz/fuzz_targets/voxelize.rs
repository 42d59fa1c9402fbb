//! Fuzzes voxelization and asset preparation on arbitrary small meshes: byte 0 picks the
//! level (0-6), the rest are `f32` vertex coordinates (any bits: degenerate, huge, tiny,
//! non-finite), three vertices per triangle. Preparation returns an asset or a
//! `VoxelizeError`; an asset's voxels lie inside its grid.
#![no_main]

use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use ssbvb_voxel::model::{Mesh, Model};
use ssbvb_voxel::prepare::prepare_asset;
use ssbvb_voxel::progress::NoProgress;

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let level = u32::from(first % 7);
    let positions: Vec<Vec3> = rest
        .chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes(c[i..i + 4].try_into().unwrap_or_default());
            Vec3::new(f(0), f(4), f(8))
        })
        .collect();
    let triangles = (0..positions.len() as u32 / 3)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    let mesh = Mesh {
        positions,
        triangles,
        ..Mesh::default()
    };
    if let Ok((asset, _)) = prepare_asset(&Model::Mesh(mesh), level, &NoProgress) {
        let finest = &asset.lods[level as usize];
        let n = 1u32 << level;
        assert!(finest.point_cloud.voxels.iter().all(|v| v.cell().iter().all(|&c| c < n)));
    }
});
