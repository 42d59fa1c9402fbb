//! The screen tiles' instance lists (`ssbvb-gpu` `scene/tile_lists.rs`, walked by
//! `instance_walk` in `shaders/instance_bvh.inc.wgsl`): with them a ray tests the boxes of
//! its tile, nearest first, instead of walking the hierarchy over every visible instance.
//! They must change which boxes are tested, never what is drawn: the filter's hits and a
//! compute caster's G-buffer equal those of the hierarchy walk bit for bit, in a crowd
//! (64 bunnies, Auto LOD), among nine overlapping turned and scaled instances, among
//! fifteen overlapping cubes, for two bunnies 10⁶ units away through a narrow lens, and
//! with the camera inside an instance (whose box then covers every tile); the crowd is
//! also held to the CPU reference. And where they can spare box tests they must: the
//! crowd's rays test well under the walk's boxes.

use glam::DVec3;
use ssbvb_gpu::scene::{LodPolicy, Scene};
use ssbvb_tests::{ctx, reference_of, render_walking};
use ssbvb_voxel::accuracy;
use ssbvb_voxel::camera::Camera;

use crate::ray_march_filter::{cell_sizes, filter_run_of};

const PIXEL: &str = include_str!("../../../assets/pipelines/ssbvb_pixel.ron");
const ESVO: &str = include_str!("../../../assets/pipelines/esvo.ron");

/// The views: a name, a scene and a camera.
fn views() -> Vec<(&'static str, Scene, Camera)> {
    let crowd = crate::scale::bunny_grid(8, 6, LodPolicy::AUTO);
    let (far, far_camera) = crate::scale::far_two_bunnies(5);
    let (cubes, cubes_camera) = crate::scale::overlapping_cubes();
    vec![
        (
            "crowd",
            crowd.clone(),
            Camera::new(DVec3::new(-11.0, 3.5, -11.0), DVec3::new(0.0, -1.0, 0.0)),
        ),
        (
            "nine",
            crate::peel::nine(),
            Camera::new(DVec3::new(1.0, 1.5, 5.5), DVec3::new(0.0, 0.0, -1.5)),
        ),
        ("cubes", cubes, cubes_camera),
        ("far two", far, far_camera),
        // Inside the first row's third bunny, looking along the row.
        (
            "inside",
            crowd,
            Camera::new(DVec3::new(-3.3, -0.2, -7.7), DVec3::new(8.0, -0.5, -7.7)),
        ),
    ]
}

#[test]
fn the_filter_hits_the_same_voxels_by_tile_lists_as_by_the_hierarchy() {
    // Not a multiple of the 16-pixel tile, so the last row and column are partial.
    let size = (168, 120);
    for (name, scene, camera) in views() {
        let run = |lists: bool| {
            let frame = render_walking(PIXEL, scene.clone(), &camera, size, lists);
            filter_run_of(frame, &scene, &camera, size, size)
        };
        let (with, without) = (run(true), run(false));
        let words = with.frame.scene.instance_list_words;
        assert!(words > 0, "{name}: no lists were built");
        assert_eq!(without.frame.scene.instance_list_words, 0, "{name}");
        let covered = with.hits.iter().flatten().count();
        let c = |r: &crate::ray_march_filter::FilterRun| r.frame.renderer.counters(ctx()).unwrap();
        let (cw, co) = (c(&with), c(&without));
        let boxes = (
            cw.instance_boxes_per_ray.unwrap(),
            co.instance_boxes_per_ray.unwrap(),
        );
        eprintln!("{name}: {covered} hits, {words} list words, boxes per ray {boxes:?}");
        assert!(covered > 300, "{name}: {covered}");
        assert!(
            with.hits == without.hits,
            "{name}: the lists changed some hit"
        );
        assert_eq!(cw.filter_rays, co.filter_rays, "{name}");
        if name == "crowd" {
            let reference = reference_of(&scene, &camera, size);
            let sizes = cell_sizes(&scene, &camera, size);
            let r = accuracy::compare(&reference, &with.hits, &sizes).unwrap();
            assert!(
                r.coverage_iou >= 0.999 && r.same_voxel_rate >= 0.999,
                "{name}: {r:?}"
            );
            // Measured on lavapipe: 5.96 against 17.3 boxes a ray (nine: 3.70 / 10.7; cubes: 1.41 / 11.8).
            assert!(boxes.0 < 0.5 * boxes.1, "{name}: {boxes:?}");
        }
    }
}

#[test]
fn a_compute_caster_draws_the_same_by_tile_lists_as_by_the_hierarchy() {
    let from = "kind: EsvoRayCast(max_steps: 4096)";
    assert!(ESVO.contains(from), "the bundled file changed");
    let pipeline = ESVO.replace(from, "kind: EsvoRayCast(max_steps: 4096, compute: true)");
    let size = (168, 120);
    for (name, scene, camera) in views() {
        let with = render_walking(&pipeline, scene.clone(), &camera, size, true);
        let without = render_walking(&pipeline, scene, &camera, size, false);
        assert!(
            with.scene.instance_list_words > 0,
            "{name}: no lists were built"
        );
        let covered = ssbvb_tests::gbuffer_hits(&with, name)
            .iter()
            .flatten()
            .count();
        assert!(covered > 300, "{name}: {covered}");
        for attachment in ["gbuffer_albedo", "gbuffer_position", "depth_stencil"] {
            let (a, b) = (with.read(attachment), without.read(attachment));
            let differing = a.iter().zip(&b).filter(|(x, y)| x != y).count();
            assert!(
                a.len() == b.len() && differing == 0,
                "{name}: {attachment}: {differing} bytes differ"
            );
        }
    }
}
