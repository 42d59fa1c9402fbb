//! Executing pipelines: resources follow the graph, unimplemented kinds are reported.

use ssbvb_passes::{GpuScene, PassError, Renderer, Scene};

#[test]
fn frame_resources_follow_the_resolved_graph() {
    let c = ssbvb_tests::ctx();
    let src = include_str!("../../../assets/pipelines/ssbvb.ron");
    let p = ssbvb_graph::resolve_str(src, "ssbvb.ron").unwrap();
    let res = ssbvb_passes::frame::FrameResources::new(c, &p, (32, 16)).unwrap();
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
    let src = include_str!("../../../assets/pipelines/ssbvb.ron");
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
