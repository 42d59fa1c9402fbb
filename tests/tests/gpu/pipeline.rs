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
