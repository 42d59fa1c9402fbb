//! Billboards (both modes) against the CPU reference.
//!
//! The SSBVB is filled from the CPU reference itself (one slot per covered pixel, exactly
//! what the ray-march filter produces), so these tests measure the billboard pass alone:
//! coverage IoU, depth error in voxel units and normal angle error. The passes are run
//! through the ordinary `Recorder` on the resources of a resolved pipeline, without the
//! passes before them.

use glam::{DAffine3, DQuat, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_graph::BillboardMode;
use ssbvb_passes::kinds::billboards::{BillboardOptions, DEFAULT_CULL_COS, Footprint};
use ssbvb_tests::{ctx, model_asset, reference_of, single_object_scene};
use ssbvb_voxel::camera::Camera;

use crate::billboard_harness::*;

#[test]
fn ray_box_matches_the_reference() {
    for model in [BUNNY, VOX] {
        let scene = single_object_scene(model_asset(model, LEVEL), LEVEL);
        for (name, cam) in cameras() {
            let (g, r) = draw(
                &scene,
                &cam,
                SIZE,
                Some(options(BillboardMode::RayBox)),
                false,
            );
            let a = measure(&g, &r, &scene, &cam);
            eprintln!("RayBox {model} {name}: {a:?}");
            g.write_pngs(&format!("raybox_{model}_{name}"));
            assert!(a.both > 1000, "{model} {name}: too few pixels ({a:?})");
            assert!(a.iou >= 0.99, "{model} {name}: {a:?}");
            assert!(a.depth_median <= 1e-3, "{model} {name}: {a:?}");
            assert!(a.face_normal_median <= 0.1, "{model} {name}: {a:?}");
            // The shading normal is the stored one (f16 rounding: ~0.05°).
            assert!(a.stored_normal_median <= 0.2, "{model} {name}: {a:?}");
            assert!(a.same_voxel >= 0.99, "{model} {name}: {a:?}");
            // Stencil is exactly "voxel" on covered pixels and 0 elsewhere.
            for i in 0..g.albedo.len() {
                assert_eq!(g.stencil[i], if g.covered(i) { 1 } else { 0 }, "pixel {i}");
            }
        }
    }
}

#[test]
fn flat_billboards_are_within_their_bounds() {
    for model in [BUNNY, VOX] {
        let scene = single_object_scene(model_asset(model, LEVEL), LEVEL);
        for (name, cam) in cameras() {
            let (g, r) = draw(
                &scene,
                &cam,
                SIZE,
                Some(options(BillboardMode::Flat)),
                false,
            );
            let a = measure(&g, &r, &scene, &cam);
            eprintln!("Flat {model} {name}: {a:?}");
            g.write_pngs(&format!("flat_{model}_{name}"));
            assert!(a.iou >= 0.99, "{model} {name}: {a:?}");
            assert_eq!(a.ref_only, 0, "{model} {name}: holes: {a:?}");
            assert_flat_depth(&a, &format!("{model} {name}"));
            // Same conventions as RayBox: the entered face (by the same slab rule) and the
            // stored normal, wherever the winning quad is the reference's voxel.
            assert!(a.face_normal_median <= 0.1, "{model} {name}: {a:?}");
            assert!(a.stored_normal_median <= 0.2, "{model} {name}: {a:?}");
            for i in 0..g.albedo.len() {
                assert_eq!(g.stencil[i], if g.covered(i) { 1 } else { 0 }, "pixel {i}");
            }
        }
    }
}

#[test]
fn culling_by_voxel_normal_only_removes_coverage() {
    let scene = single_object_scene(model_asset(BUNNY, LEVEL), LEVEL);
    for (name, cam) in cameras().into_iter().take(3) {
        let mut last = usize::MAX;
        let mut last_flat = usize::MAX;
        let mut unculled = (0, 0);
        for cull_cos in [DEFAULT_CULL_COS, -0.5, -0.2, 0.0] {
            for mode in [BillboardMode::RayBox, BillboardMode::Flat] {
                let o = BillboardOptions {
                    mode,
                    size_scale: 1.0,
                    footprint: Footprint::Box,
                    cull_cos,
                };
                let (g, r) = draw(&scene, &cam, SIZE, Some(o), false);
                let a = measure(&g, &r, &scene, &cam);
                eprintln!(
                    "cull_cos {cull_cos} {mode:?} {name}: iou {:.4}, ref-only {}",
                    a.iou, a.ref_only
                );
                // What is left after culling still shows the reference's voxel. Measured:
                // RayBox 0.993 at worst (cull_cos 0); Flat 0.667 at worst, since a
                // neighbour's flat quad at its centre depth can win the depth test.
                let min_same = if mode == BillboardMode::RayBox {
                    0.99
                } else {
                    0.6
                };
                assert!(a.same_voxel >= min_same, "{cull_cos} {mode:?}: {a:?}");
                if mode == BillboardMode::RayBox {
                    // Never a pixel outside the reference; fewer pixels as culling tightens.
                    assert_eq!(a.gpu_only, 0, "{a:?}");
                    assert!(a.both <= last, "{cull_cos}: {a:?}");
                    last = a.both;
                } else {
                    // Flat quads overhang their voxel, but coverage still only shrinks.
                    let drawn = a.both + a.gpu_only;
                    assert!(drawn <= last_flat, "{cull_cos}: {a:?}");
                    last_flat = drawn;
                }
                if cull_cos == DEFAULT_CULL_COS {
                    unculled = (last, last_flat);
                }
            }
        }
        // Culling every billboard that faces away (cull_cos 0) removes some of the
        // silhouette's (measured: 62 to 88 reference pixels lost per view against the
        // default's none): a pass that ignores `cull_cos` must not pass.
        assert!(
            last < unculled.0 && last_flat < unculled.1,
            "{name}: {last} {last_flat} vs {unculled:?}"
        );
    }
}

#[test]
fn transformed_instances_match_the_reference() {
    let asset = model_asset(BUNNY, 5);
    let rot = DQuat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 0.2);
    let far = DVec3::new(1e5, -2e5, 3e4);
    let scene = Scene {
        objects: vec![VoxelObject {
            asset,
            instances: vec![
                DAffine3::from_scale_rotation_translation(DVec3::splat(0.6), rot, far),
                DAffine3::from_scale_rotation_translation(
                    DVec3::splat(0.5),
                    DQuat::IDENTITY,
                    far + DVec3::new(1.1, 0.2, -0.4),
                ),
            ],
            lod: LodPolicy::Fixed(5),
        }],
        ..Default::default()
    };
    let cam = Camera::new(
        far + DVec3::new(0.9, 0.7, 2.4),
        far + DVec3::new(0.5, 0.0, 0.0),
    );
    let (g, r) = draw(
        &scene,
        &cam,
        SIZE,
        Some(options(BillboardMode::RayBox)),
        false,
    );
    g.write_pngs("raybox_transformed");
    let a = measure(&g, &r, &scene, &cam);
    eprintln!("RayBox transformed: {a:?}");
    assert!(a.both > 1000, "{a:?}");
    assert!(a.iou >= 0.99, "{a:?}");
    assert!(a.depth_median <= 1e-2, "{a:?}");
    assert!(a.face_normal_median <= 0.1, "{a:?}");
    assert!(a.same_voxel >= 0.99, "{a:?}");
    let (g, r) = draw(
        &scene,
        &cam,
        SIZE,
        Some(options(BillboardMode::Flat)),
        false,
    );
    let a = measure(&g, &r, &scene, &cam);
    eprintln!("Flat transformed: {a:?}");
    assert!(a.iou >= 0.99, "{a:?}");
    assert_eq!(a.ref_only, 0, "holes: {a:?}");
    // Measured 0.834 (see the culling test for why Flat is below RayBox).
    assert!(a.same_voxel >= 0.6, "{a:?}");
    assert_flat_depth(&a, "Flat transformed");
}

#[test]
fn near_field_camera_is_finite_and_exact_with_ray_box() {
    // The camera sits among the voxels: many billboards' spheres cross the near plane.
    let scene = single_object_scene(model_asset(BUNNY, 5), 5);
    for (name, cam) in [
        (
            "inside",
            Camera::new(DVec3::new(0.0, 0.0, 0.05), DVec3::new(0.3, 0.1, -1.0)),
        ),
        (
            "close",
            Camera::new(DVec3::new(-0.2, 0.1, 0.75), DVec3::new(-0.2, 0.1, 0.0)),
        ),
    ] {
        let (g, r) = draw(
            &scene,
            &cam,
            SIZE,
            Some(options(BillboardMode::RayBox)),
            false,
        );
        g.write_pngs(&format!("raybox_near_{name}"));
        let a = measure(&g, &r, &scene, &cam);
        eprintln!("RayBox near field {name}: {a:?}");
        assert!(a.iou >= 0.99, "{name}: {a:?}");
        let (g, r) = draw(
            &scene,
            &cam,
            SIZE,
            Some(options(BillboardMode::Flat)),
            false,
        );
        g.write_pngs(&format!("flat_near_{name}"));
        let a = measure(&g, &r, &scene, &cam);
        eprintln!("Flat near field {name}: {a:?}");
        assert!(a.iou >= 0.99, "{name}: {a:?}");
    }
}

#[test]
fn flat_footprint_and_size_scale_trade_coverage() {
    let scene = single_object_scene(model_asset(BUNNY, LEVEL), LEVEL);
    for (name, cam) in cameras().into_iter().take(3) {
        let mut iou = std::collections::HashMap::new();
        for footprint in [Footprint::Box, Footprint::Sphere] {
            for size_scale in [0.7f32, 0.85, 1.0, 1.2] {
                let o = BillboardOptions {
                    mode: BillboardMode::Flat,
                    size_scale,
                    footprint,
                    cull_cos: DEFAULT_CULL_COS,
                };
                let (g, r) = draw(&scene, &cam, SIZE, Some(o), false);
                let a = measure(&g, &r, &scene, &cam);
                eprintln!(
                    "Flat {footprint:?} size_scale {size_scale} {name}: iou {:.4}, \
                     gpu-only {}, ref-only {}",
                    a.iou, a.gpu_only, a.ref_only
                );
                iou.insert((footprint, (size_scale * 100.0) as u32), a);
            }
        }
        // Larger quads cover a superset: holes never grow and overhang never shrinks with
        // the scale, for both bounds; the smallest scale leaves holes.
        for footprint in [Footprint::Box, Footprint::Sphere] {
            let at = |k: u32| iou[&(footprint, k)];
            for (lo, hi) in [(70, 85), (85, 100), (100, 120)] {
                assert!(
                    at(hi).ref_only <= at(lo).ref_only,
                    "{name} {footprint:?} {lo}->{hi}"
                );
                assert!(
                    at(hi).gpu_only >= at(lo).gpu_only,
                    "{name} {footprint:?} {lo}->{hi}"
                );
            }
        }
        assert!(
            iou[&(Footprint::Box, 70)].ref_only > 0,
            "{name}: scale 0.7 leaves no hole"
        );
        // At scale 1 both bounds cover every voxel; the box bound overhangs less.
        let (b, s) = (iou[&(Footprint::Box, 100)], iou[&(Footprint::Sphere, 100)]);
        assert_eq!((b.ref_only, s.ref_only), (0, 0), "{name}");
        assert!(b.gpu_only <= s.gpu_only, "{name}: {b:?} {s:?}");
    }
}

#[test]
fn end_to_end_after_the_filter_matches_the_reference() {
    // The whole G-buffer pipeline (prepass, ray-march filter, triangles, billboards) through
    // the renderer: the SSBVB now comes from the GPU filter.
    for model in [BUNNY, VOX] {
        let scene = single_object_scene(model_asset(model, LEVEL), LEVEL);
        for (name, cam) in cameras() {
            let r = reference_of(&scene, &cam, SIZE);
            for mode in [BillboardMode::RayBox, BillboardMode::Flat] {
                let src = pipeline_src(mode, 1.0, "Rgba16Float");
                let frame = ssbvb_tests::render(&src, scene.clone(), &cam, SIZE);
                let fill = frame.renderer.fill_count(ctx()).unwrap().unwrap();
                let g = GBuffer::read(&frame.renderer.pipeline, &frame.renderer.resources);
                g.assert_finite();
                g.write_pngs(&format!("e2e_{mode:?}_{model}_{name}"));
                let a = measure(&g, &r, &scene, &cam);
                eprintln!("end to end {mode:?} {model} {name}: fill {fill}, {a:?}");
                let covered = r.hits.iter().filter(|h| h.is_some()).count();
                assert!(fill as usize <= covered + 5 && fill as usize + 5 >= covered);
                for i in 0..g.albedo.len() {
                    assert_eq!(g.stencil[i], if g.covered(i) { 1 } else { 0 }, "pixel {i}");
                }
                match mode {
                    BillboardMode::RayBox => {
                        assert!(a.iou >= 0.99, "{model} {name}: {a:?}");
                        assert!(a.same_voxel >= 0.99, "{model} {name}: {a:?}");
                        assert!(a.depth_median <= 1e-3, "{model} {name}: {a:?}");
                        assert!(a.face_normal_median <= 0.1, "{model} {name}: {a:?}");
                    }
                    BillboardMode::Flat => {
                        assert!(a.iou >= 0.99, "{model} {name}: {a:?}");
                        assert_flat_depth(&a, &format!("{model} {name}"));
                    }
                    BillboardMode::Pixel => unreachable!("not a rasterized mode"),
                }
            }
        }
    }
}

#[test]
fn sub_pixel_voxels_keep_their_pixels() {
    // Bunny level 9 at 160x120: a voxel is ~0.2 pixel. The rasterizer snaps quad corners to
    // its sub-pixel grid, which can move an edge past the pixel centre the voxel was found
    // for; the widened-and-trimmed quads must still cover every such pixel (with a plain
    // 1/1024-pixel guard, 0.5-1 % of the pixels were holes at this scale).
    let level = 9;
    let scene = single_object_scene(model_asset(BUNNY, level), level);
    for (name, cam) in cameras().into_iter().take(2) {
        let (g, r) = draw(
            &scene,
            &cam,
            SIZE,
            Some(options(BillboardMode::Flat)),
            false,
        );
        let a = measure(&g, &r, &scene, &cam);
        eprintln!("Flat sub-pixel {name}: {a:?}");
        assert!(a.both + a.ref_only > 3000, "{name}: {a:?}");
        assert_eq!(a.ref_only, 0, "{name}: holes: {a:?}");
        // Overhang of the flat quads past the silhouette: measured 0 to a few pixels.
        assert!(a.iou >= 0.995, "{name}: {a:?}");
    }
}
