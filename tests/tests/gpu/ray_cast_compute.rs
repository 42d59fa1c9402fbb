//! The compute form of the octree ray casters (`compute: true` on `OctreeRayCast` and
//! `EsvoRayCast`; `shaders/ray_cast_compute.inc.wgsl`) against their fragment form, which
//! the other GPU tests hold to the CPU reference: the same G-buffer bit for bit (every
//! attachment, depth and stencil) and the same counters, on one object, on overlapping
//! mirrored instances and at a size that is no multiple of the 16 × 16 workgroup. A frame
//! that does not count draws the same too. The compute form launches only the tiles some
//! instance's box may cover: boxes around, behind and beside the camera on a screen of
//! more tiles than the listing takes at a time draw what the fragment form draws.

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::Scene;
use ssbvb_voxel::camera::Camera;

const ESVO: &str = include_str!("../../../assets/pipelines/esvo.ron");
const OCTREE: &str = include_str!("../../../assets/pipelines/octree_ray_cast.ron");

/// The attachments the casters write.
const GBUFFER: [&str; 5] = [
    "gbuffer_albedo",
    "gbuffer_normal",
    "gbuffer_position",
    "gbuffer_geometric_normal",
    "depth_stencil",
];

/// `pipeline` with its ray-casting pass (`kind`, written `kind(max_steps: 4096)` in the
/// bundled files) switched to the compute form.
fn compute_form(pipeline: &str, kind: &str) -> String {
    let from = format!("kind: {kind}(max_steps: 4096)");
    assert!(pipeline.contains(&from), "{kind}: the bundled file changed");
    pipeline.replace(
        &from,
        &format!("kind: {kind}(max_steps: 4096, compute: true)"),
    )
}

/// Renders `scene` with both forms of `pipeline` and asserts they agree; returns the
/// covered pixels.
fn same_gbuffer(
    what: &str,
    pipeline: &str,
    kind: &str,
    scene: &Scene,
    cam: &Camera,
    size: (u32, u32),
) -> usize {
    let fragment = ssbvb_tests::render(pipeline, scene.clone(), cam, size);
    let mut compute = ssbvb_tests::render(&compute_form(pipeline, kind), scene.clone(), cam, size);
    let covered = ssbvb_tests::gbuffer_hits(&fragment, what)
        .iter()
        .flatten()
        .count();
    for name in GBUFFER {
        let (a, b) = (fragment.read(name), compute.read(name));
        let differing = a.iter().zip(&b).filter(|(x, y)| x != y).count();
        assert!(
            a.len() == b.len() && differing == 0,
            "{what}: {name}: {differing} bytes differ"
        );
    }
    assert_eq!(
        fragment.read_stencil("depth_stencil"),
        compute.read_stencil("depth_stencil"),
        "{what}: stencil"
    );
    let c = ssbvb_tests::ctx();
    let (fc, cc) = (
        fragment.renderer.counters(c).unwrap(),
        compute.renderer.counters(c).unwrap(),
    );
    eprintln!("{what}: {covered} px covered; fragment {fc:?}; compute {cc:?}");
    assert_eq!(fc.ray_cast_rays, cc.ray_cast_rays, "{what}");
    assert_eq!(fc.octree_nodes_per_ray, cc.octree_nodes_per_ray, "{what}");
    assert_eq!(fc.node_words_per_step, cc.node_words_per_step, "{what}");
    // A frame without the counters: the same G-buffer, nothing counted.
    let counted: Vec<Vec<u8>> = GBUFFER.iter().map(|n| compute.read(n)).collect();
    compute.renderer.set_counting(false);
    compute
        .renderer
        .render(c, &mut compute.scene, cam, ssbvb_passes::Profiling::Off)
        .unwrap();
    for (name, bytes) in GBUFFER.iter().zip(&counted) {
        assert!(
            compute.read(name) == *bytes,
            "{what}: {name} differs without counting"
        );
    }
    assert!(
        compute
            .renderer
            .counters(c)
            .unwrap()
            .ray_cast_rays
            .is_none(),
        "{what}"
    );
    covered
}

#[test]
fn compute_casters_draw_what_the_fragment_casters_draw() {
    let level = 6;
    let asset = ssbvb_tests::model_asset("bunny.obj", level);
    let one = ssbvb_tests::single_object_scene(asset.clone(), level);
    let mut three = one.clone();
    three.objects[0].instances = ssbvb_tests::three_overlapping_instances();
    let views = [
        (
            "one object",
            &one,
            Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO),
            (120, 90),
        ),
        // Straight down an axis: rays in grid planes (exact ties).
        (
            "down Z",
            &one,
            Camera::new(DVec3::new(0.0, 0.0, 3.2), DVec3::ZERO),
            (64, 64),
        ),
        (
            "three instances, 101×77",
            &three,
            Camera::new(DVec3::new(0.5, 1.4, 4.2), DVec3::new(0.1, 0.0, 0.0)),
            (101, 77),
        ),
        // The bunny fills the screen: threads past the right edge of a partial workgroup
        // would cast rays that hit, and must not write the next row's first pixel.
        (
            "filling the screen, 101×77",
            &one,
            Camera::new(DVec3::new(0.25, 0.15, 0.75), DVec3::new(0.0, 0.1, 0.0)),
            (101, 77),
        ),
    ];
    for (pipeline, kind) in [(ESVO, "EsvoRayCast"), (OCTREE, "OctreeRayCast")] {
        for (what, scene, cam, size) in &views {
            let what = format!("{kind} {what}");
            let covered = same_gbuffer(&what, pipeline, kind, scene, cam, *size);
            assert!(covered > 800, "{what}: {covered} px");
        }
    }
}

/// Instances around the camera on a 337 × 203 screen (286 tiles: the listing takes two
/// groups; the last column and row of tiles are cut): a box holding the camera (every
/// tile), boxes behind it (none), boxes cut by the screen's edges and far ones.
#[test]
fn compute_casters_launch_every_tile_a_box_may_cover() {
    let level = 5;
    let asset = ssbvb_tests::model_asset("bunny.obj", level);
    let mut scene = ssbvb_tests::single_object_scene(asset, level);
    scene.objects[0].instances = [
        // Holds the camera.
        (0.2, 0.1, 0.4),
        // Behind it.
        (0.0, 0.0, 5.0),
        (3.0, 1.0, 4.0),
        // Ahead, beside and cut by the screen's edges.
        (-2.6, -0.4, -4.0),
        (3.1, 0.6, -3.5),
        (0.5, -1.9, -3.0),
        (-0.4, 1.8, -5.0),
        // Far.
        (6.0, 2.0, -30.0),
    ]
    .iter()
    .map(|&(x, y, z)| DAffine3::from_translation(DVec3::new(x, y, z)))
    .collect();
    let camera = Camera::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0));
    for (pipeline, kind) in [(ESVO, "EsvoRayCast"), (OCTREE, "OctreeRayCast")] {
        let what = format!("{kind} around the camera, 337×203");
        let covered = same_gbuffer(&what, pipeline, kind, &scene, &camera, (337, 203));
        assert!(covered > 10_000, "{what}: {covered} px");
    }
}
