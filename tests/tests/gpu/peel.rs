//! `RayMarchFilter(peel: true)`: the filter's second proxy layer lets a ray whose prepass
//! instance is hit before any other instance's proxy skip the walk over the instances'
//! boxes. It must find every hit the walk finds (the filter without the layer, itself held
//! to the CPU reference elsewhere, and the reference here): in a crowd seen from above
//! (64 bunnies, Auto LOD), nine overlapping rotated and scaled instances, two bunnies
//! 10⁶ units away through a narrow lens (f32 distances), and with the camera inside one
//! instance's proxy (the layer is then cleared and no ray skips). Where it may skip, it
//! must: fewer boxes are tested per ray by the walk over the hierarchy (skipped walks, and
//! subtrees the ray leaves before the layer passed over). With the screen tiles' instance
//! lists (the default walk) it finds the same hits too.

use glam::{DAffine3, DQuat, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_tests::{ctx, model_asset, reference_of, render_walking};
use ssbvb_voxel::accuracy;
use ssbvb_voxel::camera::Camera;

use crate::ray_march_filter::{FilterRun, cell_sizes, filter_run_of};

const PIXEL: &str = include_str!("../../../assets/pipelines/ssbvb_pixel.ron");

/// The bundled frame without billboards, its filter with or without the layer.
fn pipeline(peel: bool) -> String {
    let filter = "RayMarchFilter(max_steps: 1024, unique_voxels: false, march: Fast";
    assert!(
        PIXEL.contains(filter),
        "the bundled filter's parameters changed"
    );
    let with = format!("{filter}, peel: {peel}");
    let src = PIXEL
        .replace(&format!("{filter}, peel: true"), filter)
        .replace(filter, &with);
    assert_eq!(src.matches(&with).count(), 1);
    src
}

/// Nine overlapping instances (scaled, rotated about two axes).
pub(crate) fn nine() -> Scene {
    let xfs = (0..9)
        .map(|k| {
            let (i, j) = ((k % 3) as f64, (k / 3) as f64);
            let k = k as f64;
            DAffine3::from_scale_rotation_translation(
                DVec3::splat(0.8 + 0.05 * k),
                DQuat::from_rotation_y(0.4 * k) * DQuat::from_rotation_x(0.1 * k),
                DVec3::new(i * 1.3 - 1.3, j * 1.2 - 1.2, -0.4 * k),
            )
        })
        .collect();
    Scene {
        objects: vec![VoxelObject {
            asset: model_asset("bunny.obj", 5),
            instances: xfs,
            lod: LodPolicy::Fixed(5),
        }],
        ..Default::default()
    }
}

#[test]
fn the_second_proxy_layer_keeps_every_hit_and_spares_walks_in_a_crowd() {
    let size = (96, 72);
    let crowd = crate::scale::bunny_grid(8, 6, LodPolicy::AUTO);
    let (far, far_camera) = crate::scale::far_two_bunnies(5);
    let views = [
        (
            "crowd",
            crowd.clone(),
            Camera::new(DVec3::new(-11.0, 3.5, -11.0), DVec3::new(0.0, -1.0, 0.0)),
        ),
        (
            "nine",
            nine(),
            Camera::new(DVec3::new(1.0, 1.5, 5.5), DVec3::new(0.0, 0.0, -1.5)),
        ),
        ("far two", far, far_camera),
        // Inside the first row's third bunny, looking along the row.
        (
            "inside",
            crowd,
            Camera::new(DVec3::new(-3.3, -0.2, -7.7), DVec3::new(8.0, -0.5, -7.7)),
        ),
    ];
    for (name, scene, camera) in views {
        let run = |peel: bool, lists: bool| -> FilterRun {
            let frame = render_walking(&pipeline(peel), scene.clone(), &camera, size, lists);
            filter_run_of(frame, &scene, &camera, size, size)
        };
        let (with, without) = (run(true, false), run(false, false));
        assert!(
            run(true, true).hits == without.hits,
            "{name}: the layer with lists"
        );
        assert!(with.frame.scene.visible.len() > 1, "{name}");
        let inside = with.frame.scene.visible.iter().any(|v| v.camera_inside);
        assert_eq!(inside, name == "inside", "{name}");
        let covered = without.hits.iter().flatten().count();
        let same = with.hits == without.hits;
        let reference = reference_of(&scene, &camera, size);
        let r =
            accuracy::compare(&reference, &with.hits, &cell_sizes(&scene, &camera, size)).unwrap();
        let c = |run: &FilterRun| run.frame.renderer.counters(ctx()).unwrap();
        let (cw, co) = (c(&with), c(&without));
        let boxes = (
            cw.instance_boxes_per_ray.unwrap(),
            co.instance_boxes_per_ray.unwrap(),
        );
        eprintln!("{name}: {covered} hits, same {same}, boxes per ray {boxes:?}; {r:?}");
        assert!(covered > 300, "{name}: {covered}");
        assert!(same, "{name}: the layer changed some hit");
        assert!(
            r.coverage_iou >= 0.99 && r.same_voxel_rate >= 0.99,
            "{name}: {r:?}"
        );
        match name {
            // The camera inside a proxy: the layer is cleared, every ray walks.
            "inside" => assert_eq!(boxes.0, boxes.1, "{name}"),
            // Measured on lavapipe: 13.5 against 19.7 boxes a ray in the crowd, 5.1 against
            // 10.7 for the nine instances, 1.8 against 3.0 far away.
            "crowd" => assert!(boxes.0 < 0.8 * boxes.1, "{name}: {boxes:?}"),
            "nine" => assert!(boxes.0 < 0.6 * boxes.1, "{name}: {boxes:?}"),
            _ => assert!(boxes.0 < boxes.1, "{name}: {boxes:?}"),
        }
    }
}
