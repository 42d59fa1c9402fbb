//! The dense-DDA baseline (`assets/pipelines/dense_dda.ron`) against the CPU reference:
//! a plain Amanatides–Woo DDA over a dense 3D texture finds the same first voxel as the
//! reference's exact traversal, so coverage IoU must be ≥ 0.99 (f32 vs f64 ties on voxel
//! edges) and the median depth error ≤ 0.01 voxel, with no NaN in the G-buffer. Levels
//! above 8 are refused with `PassError::TooLarge`.

use std::sync::Arc;

use glam::DVec3;
use ssbvb_gpu::scene::GpuScene;
use ssbvb_passes::kinds::dense_dda::MAX_DENSE_LEVEL;
use ssbvb_passes::{PassError, Profiling, Renderer};
use ssbvb_voxel::accuracy;
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, ProxyMesh, SparseLookup};
use ssbvb_voxel::camera::Camera;

const DENSE_DDA: &str = include_str!("../../../assets/pipelines/dense_dda.ron");
const SIZE: (u32, u32) = (120, 90);

fn cameras() -> Vec<Camera> {
    vec![
        Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.6, -0.8, -1.5), DVec3::new(0.0, 0.1, 0.0)),
        // Straight down the Z axis: rays parallel to grid planes (exact f32 ties).
        Camera::new(DVec3::new(0.0, 0.0, 3.2), DVec3::ZERO),
    ]
}

#[test]
fn dense_dda_matches_the_reference() {
    for (file, level) in [("bunny.obj", 6), ("chr_knight.vox", 5)] {
        let asset = ssbvb_tests::model_asset(file, level);
        let cell = 2.0 / (1u64 << level) as f64;
        for (ci, cam) in cameras().iter().enumerate() {
            let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
            let reference = ssbvb_tests::reference_of(&scene, cam, SIZE);
            let f = ssbvb_tests::render(DENSE_DDA, scene, cam, SIZE);
            let hits = ssbvb_tests::gbuffer_hits(&f, file);
            let r = accuracy::compare(&reference, &hits, &[cell]).unwrap();
            eprintln!(
                "DenseDda {file} L{level} camera {ci}: IoU {:.4}, depth median {:.5} p95 {:.4} voxels, normal median {:.2}°, px {}",
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
}

/// One voxel at the centre of a level-`level` grid.
fn one_voxel_lod(level: u32) -> LodLevel {
    let c = 1u32 << (level - 1);
    LodLevel {
        level,
        point_cloud: PointCloud {
            voxels: vec![PackedVoxel::new(
                [c; 3],
                [0.0, 0.0, 1.0],
                [1.0; 4],
                [0.0; 2],
            )],
        },
        lookup: SparseLookup::from_cells(level, [[c; 3]].into_iter()),
        proxy: ProxyMesh::default(),
    }
}

#[test]
fn dense_dda_refuses_levels_above_8() {
    // The bunny's levels 0..=6, then single-voxel levels 7..=9 (cheap to build).
    let mut asset = (*ssbvb_tests::model_asset("bunny.obj", 6)).clone();
    for level in 7..=MAX_DENSE_LEVEL + 1 {
        asset.lods.push(one_voxel_lod(level));
    }
    let level = MAX_DENSE_LEVEL + 1;
    let scene = ssbvb_tests::single_object_scene(Arc::new(asset), level);
    let c = ssbvb_tests::ctx();
    let resolved = ssbvb_graph::resolve_str(DENSE_DDA, "dense_dda").unwrap();
    let mut gpu_scene = GpuScene::new(c, scene).unwrap();
    let mut renderer = Renderer::new(c, &gpu_scene, resolved, SIZE).unwrap();
    let err = renderer
        .render(c, &mut gpu_scene, &cameras()[0], Profiling::Off)
        .expect_err("a level-9 object must be refused");
    let msg = err.to_string();
    assert!(matches!(err, PassError::TooLarge(_)), "{msg}");
    assert!(msg.contains("level 9") && msg.contains("up to 8"), "{msg}");
    c.wait_idle().unwrap();
    let errs = c.take_uncaptured_errors();
    assert!(errs.is_empty(), "wgpu errors: {errs:#?}");
}
