//! Executing pipelines: resources follow the graph, unimplemented kinds are reported.

use ssbvb_gpu::scene::{GpuScene, Scene};
use ssbvb_passes::{PassError, Renderer};

#[test]
fn frame_resources_follow_the_resolved_graph() {
    let c = ssbvb_tests::ctx();
    let src = include_str!("../../../assets/pipelines/ssbvb_unique.ron");
    let p = ssbvb_graph::resolve_str(src, "ssbvb_unique.ron").unwrap();
    let res = ssbvb_passes::runtime::resources::FrameResources::new(c, &p, (32, 16)).unwrap();
    // Aliased resources share one texture object.
    let entry = p.resource("entry").unwrap();
    let pos = p.resource("gbuffer_position").unwrap();
    let (a, b) = (res.texture(entry), res.texture(pos));
    assert_eq!(a.texture, b.texture);
    assert_eq!((a.texture.width(), a.texture.height()), (32, 16));
    assert_eq!(
        res.buffer(p.resource("ssbvb").unwrap()).size(),
        32 * 16 * 32
    );
    let scene = GpuScene::new(c, Scene::default()).unwrap();
    if ssbvb_passes::registered_kinds().len() < ssbvb_graph::KIND_NAMES.len() {
        match Renderer::new(c, &scene, p, (32, 16)) {
            Err(PassError::NotImplemented { pass, .. }) => assert!(!pass.is_empty()),
            Err(e) => panic!("unexpected error {e}"),
            Ok(_) => panic!("a pipeline with unimplemented kinds must not build"),
        }
    }
}

/// `measure::gbuffer_hits` (what the bench and the viewer measure with) against two
/// independent readings: the harness's own G-buffer decoder for coverage, depth and normal
/// (bit for bit), and the CPU reference for the voxel cell of each pixel's SSBVB slot.
#[test]
fn measured_gbuffer_hits_match_the_harness_and_the_reference() {
    let size = (96, 72);
    let level = 5;
    let scene =
        ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", level), level);
    let cam = ssbvb_voxel::camera::Camera::new(glam::DVec3::new(1.8, 1.1, 2.4), glam::DVec3::ZERO);
    let src = include_str!("../../../assets/pipelines/ssbvb_flat.ron");
    let reference = ssbvb_tests::reference_of(&scene, &cam, size);
    let f = ssbvb_tests::render(src, scene, &cam, size);
    let measured = ssbvb_passes::measure::gbuffer_hits(ssbvb_tests::ctx(), &f.renderer).unwrap();
    let harness = ssbvb_tests::gbuffer_hits(&f, "bunny L5");
    assert_eq!(measured.len(), harness.len());
    let (mut covered, mut without_slot) = (0, 0);
    for (m, h) in measured.iter().zip(&harness) {
        match (m, h) {
            (Some(m), Some(h)) => {
                covered += 1;
                assert_eq!(m.t.to_bits(), h.t.to_bits());
                assert_eq!(m.normal.map(f32::to_bits), h.normal.map(f32::to_bits));
                // A pixel whose own ray found nothing can still be covered by a neighbour's
                // billboard (at silhouettes): it has no slot, so no cell.
                without_slot += (m.cell == [u32::MAX; 3]) as usize;
            }
            (None, None) => {}
            _ => panic!("coverage differs: measured {m:?}, harness {h:?}"),
        }
    }
    assert!(covered > 1000, "{covered}");
    eprintln!("{covered} covered pixels, {without_slot} without a slot of their own");
    assert!(
        without_slot * 50 <= covered,
        "{without_slot} of {covered} without a slot"
    );
    eprintln!("{covered} covered pixels, {without_slot} without a slot of their own");
    assert!(
        without_slot * 50 <= covered,
        "{without_slot} of {covered} without a slot"
    );
    let r = ssbvb_voxel::accuracy::compare(&reference, &measured, &[2.0 / 32.0]).unwrap();
    // Flat billboards at screen resolution: measured same-voxel rate 1.0 on the bunny.
    assert!(r.same_voxel_rate >= 0.99, "{r:?}");
    assert!(r.coverage_iou >= 0.99, "{r:?}");
}

/// `LodPolicy::Auto` on the GPU: three bunnies at different distances get different levels,
/// each the coarsest level whose cell projects to at most a pixel (checked from the camera
/// geometry, not with `choose_level`), and the frame matches the reference rendered at
/// those levels.
#[test]
fn auto_lod_picks_a_level_per_instance_and_matches_the_reference() {
    use glam::{DAffine3, DVec3};
    use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
    let size = (160u32, 120u32);
    let asset = ssbvb_tests::model_asset("bunny.obj", 7);
    let at = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(-3.0, 0.0, -12.0),
        DVec3::new(5.0, 0.5, -40.0),
    ];
    let scene_with = |lods: &[LodPolicy]| Scene {
        objects: at
            .iter()
            .zip(lods)
            .map(|(p, lod)| VoxelObject {
                asset: asset.clone(),
                instances: vec![DAffine3::from_translation(*p)],
                lod: *lod,
            })
            .collect(),
        ..Default::default()
    };
    let cam =
        ssbvb_voxel::camera::Camera::new(DVec3::new(0.5, 0.4, 4.0), DVec3::new(0.0, 0.0, -10.0));
    let src = include_str!("../../../assets/pipelines/cube_raster.ron");
    let f = ssbvb_tests::render(src, scene_with(&[LodPolicy::AUTO; 3]), &cam, size);
    let mut levels = vec![u32::MAX; 3];
    for v in &f.scene.visible {
        levels[v.object] = v.level;
    }
    eprintln!("auto levels {levels:?}");
    let tan = (cam.fov_y_deg.to_radians() / 2.0).tan();
    for (p, &l) in at.iter().zip(&levels) {
        assert!(l <= 7, "an instance was not drawn: {levels:?}");
        // Pixels per cell of level l at the bounding sphere's nearest point.
        let dist = (*p - cam.position).length() - 3f64.sqrt();
        let px = (2.0 / (1u64 << l) as f64) * size.1 as f64 / (2.0 * dist * tan);
        // At most a pixel, and one level coarser would exceed it (unless clamped).
        assert!(
            (0.5..=1.0).contains(&px) || (l == 7 && px <= 1.0) || (l == 0 && px > 0.5),
            "level {l} at distance {dist:.1}: a cell spans {px:.2} px"
        );
    }
    assert!(levels[0] > levels[2], "{levels:?}");
    let fixed: Vec<LodPolicy> = levels.iter().map(|&l| LodPolicy::Fixed(l)).collect();
    let reference = ssbvb_tests::reference_of(&scene_with(&fixed), &cam, size);
    let hits = ssbvb_tests::gbuffer_hits(&f, "auto LOD");
    let cells: Vec<f64> = levels.iter().map(|&l| 2.0 / (1u64 << l) as f64).collect();
    let r = ssbvb_voxel::accuracy::compare(&reference, &hits, &cells).unwrap();
    eprintln!("auto LOD vs reference at {levels:?}: {r:?}");
    assert!(r.covered_reference > 1000, "{r:?}");
    assert!(r.coverage_iou >= 0.99, "{r:?}");
    assert!(r.depth_error_voxels.median <= 1e-3, "{r:?}");
}
