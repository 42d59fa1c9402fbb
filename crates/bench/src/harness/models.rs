//! The bundled models the presets load, and the cameras and scenes they see them in.

use std::sync::Arc;

use anyhow::{Context, Result};
use glam::{DAffine3, DQuat, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::cache::PrepareOutcome;
use ssbvb_voxel::camera::Camera;

use ssbvb_engine::assets::assets_dir;

/// The bundled model `file` (relative to `assets`) at `level`, every coarser level
/// included, from the asset cache (prepared on a miss), and how the cache answered.
pub(crate) fn bundled_asset(file: &str, level: u32) -> Result<(Arc<VoxelAsset>, PrepareOutcome)> {
    let path = assets_dir().join(file);
    let (asset, outcome) =
        ssbvb_voxel::cache::load_or_prepare(&path, level, None, &ssbvb_voxel::progress::NoProgress)
            .with_context(|| format!("preparing {} at level {level}", path.display()))?;
    Ok((Arc::new(asset), outcome))
}

/// The bundled bunny at `level` (see [`bundled_asset`]).
pub(crate) fn bundled_bunny(level: u32) -> Result<(Arc<VoxelAsset>, PrepareOutcome)> {
    bundled_asset("models/bunny.obj", level)
}

/// The camera of the bunny presets: in front of the model, slightly above it.
pub(crate) fn bench_camera() -> Camera {
    Camera::new(DVec3::new(0.0, 0.3, 2.6), DVec3::ZERO)
}

/// A scene of `asset` once, untransformed, drawn with `lod`.
pub(crate) fn one_object(asset: &Arc<VoxelAsset>, lod: LodPolicy) -> Scene {
    Scene {
        objects: vec![VoxelObject {
            asset: asset.clone(),
            instances: vec![DAffine3::IDENTITY],
            lod,
        }],
        ..Default::default()
    }
}

/// The first `n` instances of the bunny grid of `assets/scenes/bunnies_4096.ron` (2.2
/// apart, row by row on a square grid, each turned by the file's hash).
pub(crate) fn grid(n: usize) -> Vec<DAffine3> {
    let side = (n as f64).sqrt().ceil().max(1.0) as usize;
    let half = (side as f64 - 1.0) / 2.0;
    (0..n)
        .map(|k| {
            let (i, j) = (k % side, k / side);
            let deg = ((i as u64 * 73856093) ^ (j as u64 * 19349663)) % 360;
            DAffine3::from_rotation_translation(
                DQuat::from_rotation_y((deg as f64).to_radians()),
                DVec3::new((i as f64 - half) * 2.2, 0.0, (j as f64 - half) * 2.2),
            )
        })
        .collect()
}

/// Over the grid of `n` instances from one corner, as `bunnies_4096.ron` looks at its
/// 64 × 64 bunnies.
pub(crate) fn grid_camera(n: usize) -> Camera {
    let side = (n as f64).sqrt().ceil().max(1.0);
    let h = (side - 1.0) / 2.0 * 2.2;
    Camera {
        fov_y_deg: 50.0,
        near: 0.05,
        far: f64::INFINITY,
        ..Camera::new(
            DVec3::new(-(h + 4.0), 1.2 + 0.11 * h, -(h + 4.0)),
            DVec3::new(0.0, -1.0, 0.0),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_matches_the_scene_file_layout() {
        // bunnies_64.ron: 8 x 8, first bunny at (-7.7, 0, -7.7), the second turned by
        // (1 * 73856093) mod 360 = 293 degrees.
        let g = grid(64);
        assert_eq!(g.len(), 64);
        assert!((g[0].translation - DVec3::new(-7.7, 0.0, -7.7)).length() < 1e-12);
        assert!((g[1].translation - DVec3::new(-5.5, 0.0, -7.7)).length() < 1e-12);
        let want = glam::DMat3::from_rotation_y(293f64.to_radians());
        assert!(g[1].matrix3.abs_diff_eq(want, 1e-12), "{:?}", g[1].matrix3);
        let text = include_str!("../../../../assets/scenes/bunnies_64.ron");
        assert!(text.contains("(translation: (-5.5, 0.0, -7.7), rotation_y_deg: 293.0)"));
        assert_eq!(grid(1)[0].translation, DVec3::ZERO);
        assert_eq!(grid(3).len(), 3);
    }
}
