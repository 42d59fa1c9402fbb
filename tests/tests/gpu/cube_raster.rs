//! The instanced cube rasterization baseline (`assets/pipelines/cube_raster.ron`) against
//! the CPU reference. Rasterizing the cubes' front faces covers the pixels whose centre
//! ray hits a voxel (up to the rasterizer's sub-pixel snapping at cube edges), and the
//! fragment's ray–face intersection gives the reference's depth, so coverage IoU must be
//! ≥ 0.995, the same-voxel rate ≥ 0.99 and the depth error tiny (see `ssbvb_tests::assert_face_raster_accurate`):
//! on the bunny at several LODs, on every test model, with two objects at different
//! levels (one rotated and scaled), and far from the world origin. Merged and unmerged
//! cube lists must give the same G-buffer, and merged lists must cover every model's
//! voxels exactly. Every render fails on a wgpu validation error (`ssbvb_tests::render`).
//!
//! The G-buffer holds no cell id: the shown voxel is recovered from the written position
//! and face normal (half a cell inside the face), which is also how the shader picks the
//! voxel whose colour it writes.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_voxel::accuracy::{self, AccuracyReport, GpuHit};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::cube_list::CubeList;

const CUBES: &str = include_str!("../../../assets/pipelines/cube_raster.ron");
const SIZE: (u32, u32) = (160, 120);

fn unmerged_pipeline() -> String {
    let text = CUBES.replace(
        "CubeRaster(merge_full_nodes: true)",
        "CubeRaster(merge_full_nodes: false)",
    );
    assert_ne!(
        text, CUBES,
        "the pipeline file must name merge_full_nodes: true"
    );
    text
}

fn cameras() -> Vec<Camera> {
    vec![
        Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.6, -0.8, -1.5), DVec3::new(0.0, 0.1, 0.0)),
        // Straight down the Z axis: rays parallel to grid planes (exact f32 ties).
        Camera::new(DVec3::new(0.0, 0.0, 3.2), DVec3::ZERO),
    ]
}

/// Per-instance (transform, LOD level, asset) of `scene`, in the reference's numbering.
fn instances(scene: &Scene) -> Vec<(DAffine3, u32, Arc<VoxelAsset>)> {
    let mut out = Vec::new();
    for o in &scene.objects {
        let LodPolicy::Fixed(level) = o.lod else {
            panic!("fixed LODs only")
        };
        for xf in &o.instances {
            out.push((*xf, level, o.asset.clone()));
        }
    }
    out
}

/// The G-buffer of a render as reference-comparable hits: the voxel is the cell half a
/// cell behind the written position along the written normal, in the instance whose LOD
/// holds a voxel there.
fn hits(f: &ssbvb_tests::Frame, scene: &Scene, cam: &Camera, what: &str) -> Vec<Option<GpuHit>> {
    let insts = instances(scene);
    let pos = f.read_f32("gbuffer_position");
    ssbvb_tests::gbuffer_hits(f, what)
        .into_iter()
        .enumerate()
        .map(|(i, h)| {
            h.map(|mut hit| {
                let p = &pos[i * 4..i * 4 + 3];
                let world = cam.position + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                let n = hit.normal;
                let n_world = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
                for (ii, (xf, level, asset)) in insts.iter().enumerate() {
                    let s = 2.0 / (1u64 << level) as f64;
                    let p_obj = xf.inverse().transform_point3(world);
                    // Normals go world → object with the transpose of the linear part.
                    let n_obj = xf.matrix3.transpose().mul_vec3(n_world).normalize_or_zero();
                    let q = (p_obj - n_obj * (0.5 * s) + 1.0) / s;
                    let lookup = &asset.lods[*level as usize].lookup;
                    let n_cells = (1u64 << level) as f64;
                    if q.min_element() < 0.0 || q.max_element() >= n_cells {
                        continue;
                    }
                    let cell = [q.x as u32, q.y as u32, q.z as u32];
                    if lookup.get(cell).is_some() {
                        hit.instance = ii as u32;
                        hit.cell = cell;
                        break;
                    }
                }
                hit
            })
        })
        .collect()
}

fn compare(scene: &Scene, cam: &Camera, pipeline: &str, what: &str) -> AccuracyReport {
    let reference = ssbvb_tests::reference_of(scene, cam, SIZE);
    let f = ssbvb_tests::render(pipeline, scene.clone(), cam, SIZE);
    let gpu = hits(&f, scene, cam, what);
    let cells: Vec<f64> = instances(scene)
        .iter()
        .map(|(xf, level, _)| {
            let scale = xf.matrix3.x_axis.length();
            2.0 * scale / (1u64 << level) as f64
        })
        .collect();
    let r = accuracy::compare(&reference, &gpu, &cells).unwrap();
    eprintln!(
        "CubeRaster {what}: IoU {:.4}, same voxel {:.4}, depth median {:.2e} p95 {:.2e} max {:.2e} voxels, normal median {:.2}° p95 {:.2}°, px {}",
        r.coverage_iou,
        r.same_voxel_rate,
        r.depth_error_voxels.median,
        r.depth_error_voxels.p95,
        r.depth_error_voxels.max,
        r.normal_error_deg.median,
        r.normal_error_deg.p95,
        r.covered_reference,
    );
    r
}

#[test]
fn cube_raster_matches_the_reference_on_the_bunny_at_several_lods() {
    let asset = ssbvb_tests::model_asset("bunny.obj", 7);
    for level in [5, 6, 7] {
        for (ci, cam) in cameras().iter().enumerate() {
            let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
            let what = format!("bunny LOD {level} camera {ci}");
            let r = compare(&scene, cam, CUBES, &what);
            ssbvb_tests::assert_face_raster_accurate(&r, &what);
        }
    }
}

#[test]
fn cube_raster_draws_two_objects_at_different_levels() {
    let bunny = ssbvb_tests::model_asset("bunny.obj", 6);
    let knight = ssbvb_tests::model_asset("chr_knight.vox", 5);
    let scene = Scene {
        objects: vec![
            VoxelObject {
                asset: bunny,
                instances: vec![DAffine3::from_translation(DVec3::new(-1.1, 0.0, 0.0))],
                lod: LodPolicy::Fixed(6),
            },
            VoxelObject {
                asset: knight,
                // Rotated and scaled: the face culling and the normals go through the
                // instance transform.
                instances: vec![
                    DAffine3::from_scale_rotation_translation(
                        DVec3::splat(0.8),
                        glam::DQuat::from_rotation_y(0.6),
                        DVec3::new(1.1, 0.0, 0.0),
                    ),
                    DAffine3::from_translation(DVec3::new(0.0, 0.0, -2.5)),
                    // Mirrored (negative determinant): faces are chosen from the camera's
                    // object-space position, not from the winding.
                    DAffine3::from_scale_rotation_translation(
                        DVec3::new(-0.7, 0.7, 0.7),
                        glam::DQuat::from_rotation_y(-0.4),
                        DVec3::new(0.0, 1.4, -1.0),
                    ),
                ],
                lod: LodPolicy::Fixed(4),
            },
        ],
        ..Default::default()
    };
    let cam = Camera::new(DVec3::new(0.4, 1.2, 4.5), DVec3::new(0.0, 0.0, -0.5));
    let r = compare(&scene, &cam, CUBES, "bunny L6 + 3 knights L4");
    ssbvb_tests::assert_face_raster_accurate(&r, "two objects");
    // Every instance shows up.
    let f = ssbvb_tests::render(CUBES, scene.clone(), &cam, SIZE);
    let gpu = hits(&f, &scene, &cam, "two objects");
    for i in 0..4 {
        let px = gpu.iter().flatten().filter(|h| h.instance == i).count();
        assert!(px > 100, "instance {i}: {px} px");
    }
}

#[test]
fn merged_and_unmerged_cubes_give_the_same_gbuffer() {
    // Level 7 of the bunny has full 2³ nodes where the shell is thick; the merged list is
    // smaller, the image must not change.
    let asset = ssbvb_tests::model_asset("bunny.obj", 7);
    let level = 7;
    let merged = CubeList::from_lod(&asset.lods[level as usize], true).unwrap();
    let unmerged = CubeList::from_lod(&asset.lods[level as usize], false).unwrap();
    eprintln!(
        "bunny L{level}: {} voxels, {} cubes merged ({} B), {} unmerged ({} B), sizes {:?}",
        merged.voxel_count,
        merged.len(),
        merged.bytes(),
        unmerged.len(),
        unmerged.bytes(),
        merged.size_histogram()
    );
    assert!(merged.len() < unmerged.len(), "nothing merged");
    let unmerged_text = unmerged_pipeline();
    for (ci, cam) in cameras().iter().enumerate() {
        let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
        let a = ssbvb_tests::render(CUBES, scene.clone(), cam, SIZE);
        let b = ssbvb_tests::render(&unmerged_text, scene, cam, SIZE);
        let (albedo_a, albedo_b) = (a.read("gbuffer_albedo"), b.read("gbuffer_albedo"));
        let (pos_a, pos_b) = (
            a.read_f32("gbuffer_position"),
            b.read_f32("gbuffer_position"),
        );
        let (n_a, n_b) = (
            ssbvb_tests::read_half4(&a, "gbuffer_normal"),
            ssbvb_tests::read_half4(&b, "gbuffer_normal"),
        );
        let (g_a, g_b) = (
            ssbvb_tests::read_geometric_normals(&a),
            ssbvb_tests::read_geometric_normals(&b),
        );
        let pixels = (SIZE.0 * SIZE.1) as usize;
        let mut differ = 0;
        let mut max_pos = 0f32;
        for i in 0..pixels {
            let same_albedo = albedo_a[i * 4..i * 4 + 4] == albedo_b[i * 4..i * 4 + 4];
            if !same_albedo || n_a[i] != n_b[i] || g_a[i] != g_b[i] {
                differ += 1;
                continue;
            }
            for c in 0..4 {
                max_pos = max_pos.max((pos_a[i * 4 + c] - pos_b[i * 4 + c]).abs());
            }
        }
        eprintln!(
            "merged vs unmerged camera {ci}: {differ} of {pixels} px differ, max position difference {max_pos:e}"
        );
        // Measured: identical (coverage of coplanar quads and the ray–face position do not
        // depend on how a face is split); allow a few edge-tie pixels.
        assert!(differ <= pixels / 1000, "camera {ci}: {differ} px differ");
        assert!(
            max_pos <= 1e-5,
            "camera {ci}: position differs by {max_pos}"
        );
    }
}

/// The test models (as in `all_models.rs`) at their levels.
const MODELS: &[(&str, u32)] = &[
    ("bunny.obj", 6),
    ("teapot.obj", 6),
    ("cow.obj", 6),
    ("igea.ply", 6),
    ("chr_knight.vox", 5),
    ("T-Rex.vox", 6),
    ("monu1.vox", 6),
];

#[test]
fn cube_lists_cover_every_shared_model_exactly() {
    // CPU only: at every LOD of every model, merged cubes lie inside the voxel set and
    // their volumes add up to the voxel count, so (being disjoint by construction, see
    // the unit tests) they cover it exactly.
    for &(file, level) in MODELS {
        let asset = ssbvb_tests::model_asset(file, level);
        for lod in &asset.lods {
            let merged = CubeList::from_lod(lod, true).unwrap();
            let unmerged = CubeList::from_lod(lod, false).unwrap();
            assert_eq!(unmerged.len(), lod.point_cloud.voxels.len());
            let mut volume = 0u64;
            for c in &merged.cubes {
                let (min, s) = (c.min(), c.size());
                volume += u64::from(s).pow(3);
                for z in 0..s {
                    for y in 0..s {
                        for x in 0..s {
                            let cell = [min[0] + x, min[1] + y, min[2] + z];
                            assert!(lod.lookup.get(cell).is_some(), "{file} L{}", lod.level);
                        }
                    }
                }
            }
            assert_eq!(volume, merged.voxel_count as u64, "{file} L{}", lod.level);
            assert_eq!(merged.voxel_count, lod.point_cloud.voxels.len());
            if lod.level >= 4 {
                eprintln!(
                    "{file} L{}: {} voxels; cubes merged {} ({} B), unmerged {} ({} B); sizes {:?}",
                    lod.level,
                    merged.voxel_count,
                    merged.len(),
                    merged.bytes(),
                    unmerged.len(),
                    unmerged.bytes(),
                    merged.size_histogram()
                );
            }
        }
    }
}

#[test]
fn cube_raster_matches_the_reference_on_every_shared_model() {
    for &(file, level) in MODELS {
        let asset = ssbvb_tests::model_asset(file, level);
        for (ci, cam) in cameras().iter().enumerate() {
            let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
            let what = format!("{file} L{level} camera {ci}");
            let r = compare(&scene, cam, CUBES, &what);
            ssbvb_tests::assert_face_raster_accurate(&r, &what);
        }
    }
}

#[test]
fn cube_raster_is_accurate_far_from_the_world_origin() {
    // Camera-relative transforms keep f32 precision for an object at 1e7 world units.
    let asset = ssbvb_tests::model_asset("bunny.obj", 6);
    let at = DVec3::new(1e7, -3e6, 2e6);
    let scene = Scene {
        objects: vec![VoxelObject {
            asset,
            instances: vec![DAffine3::from_translation(at)],
            lod: LodPolicy::Fixed(6),
        }],
        ..Default::default()
    };
    let cam = Camera::new(at + DVec3::new(1.8, 1.1, 2.4), at);
    let r = compare(&scene, &cam, CUBES, "bunny L6 at 1e7");
    ssbvb_tests::assert_face_raster_accurate(&r, "bunny L6 at 1e7");
}
