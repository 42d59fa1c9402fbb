//! The sparse-voxel-octree baseline (`assets/pipelines/octree.ron`) against the
//! CPU reference: a stack-based front-to-back descent of the octree finds the same first
//! voxel as the reference's exact traversal, so coverage IoU must be ≥ 0.99 (f32 vs f64
//! ties on voxel edges) and the median depth error ≤ 0.01 voxel, with no NaN in the
//! G-buffer — at the asset's finest level and at a coarser LOD (inner octree nodes).
//! Several objects: `ray_casters.rs`.

use glam::DVec3;
use ssbvb_voxel::accuracy;
use ssbvb_voxel::camera::Camera;

const OCTREE: &str = include_str!("../../../assets/pipelines/octree.ron");
const SIZE: (u32, u32) = (120, 90);

fn cameras() -> Vec<Camera> {
    vec![
        Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.6, -0.8, -1.5), DVec3::new(0.0, 0.1, 0.0)),
        // Straight down the Z axis: rays parallel to grid planes (exact f32 ties).
        Camera::new(DVec3::new(0.0, 0.0, 3.2), DVec3::ZERO),
    ]
}

/// Renders `file` (prepared at `asset_level`) at LOD `level` from every camera and checks
/// it against the CPU reference of that LOD.
fn check(file: &str, asset_level: u32, level: u32) {
    let asset = ssbvb_tests::model_asset(file, asset_level);
    let cell = 2.0 / (1u64 << level) as f64;
    for (ci, cam) in cameras().iter().enumerate() {
        let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
        let reference = ssbvb_tests::reference_of(&scene, cam, SIZE);
        let f = ssbvb_tests::render(OCTREE, scene, cam, SIZE);
        let hits = ssbvb_tests::gbuffer_hits(&f, file);
        let r = accuracy::compare(&reference, &hits, &[cell]).unwrap();
        eprintln!(
            "OctreeRayCast {file} asset L{asset_level} LOD {level} camera {ci}: IoU {:.4}, depth median {:.5} p95 {:.4} voxels, normal median {:.2}°, px {}",
            r.coverage_iou,
            r.depth_error_voxels.median,
            r.depth_error_voxels.p95,
            r.normal_error_deg.median,
            r.covered_reference,
        );
        assert!(
            r.covered_reference > 200,
            "{file} camera {ci}: only {} px",
            r.covered_reference
        );
        assert!(r.coverage_iou >= 0.99, "{file} camera {ci}: {r:?}");
        assert!(
            r.depth_error_voxels.median <= 0.01,
            "{file} camera {ci}: {r:?}"
        );
        // Measured on lavapipe: depth p95 and normal median are 0 (exact face hits); the
        // bounds leave a margin for other adapters' rounding.
        assert!(
            r.depth_error_voxels.p95 <= 0.05,
            "{file} camera {ci}: {r:?}"
        );
        assert!(
            r.normal_error_deg.median <= 0.5,
            "{file} camera {ci}: {r:?}"
        );
    }
}

#[test]
fn octree_ray_cast_matches_the_reference() {
    for (file, level) in [("bunny.obj", 6), ("chr_knight.vox", 5)] {
        check(file, level, level);
    }
}

#[test]
fn octree_ray_cast_matches_the_reference_at_a_coarser_lod() {
    // The level-6 bunny rendered at LOD 4: the hits are inner nodes of the octree.
    check("bunny.obj", 6, 4);
}
