//! The ESVO baseline (`assets/pipelines/esvo.ron`, Laine & Karras' traversal on the octree
//! caster's data) against the CPU reference, on the octree caster's views: one object from
//! three cameras (one straight down an axis) at the finest level and at a coarser LOD,
//! several instances, a camera inside the grid, one inside a closed shell, a far narrow
//! view and a close-up 1e7 units from the origin.
//!
//! ESVO is exact up to its f32 arithmetic: its plane times are `x · coef − bias` (the
//! reference's `(b − o) / d`, rounded differently) and it steps diagonally through exact
//! edge ties, so a ray that grazes a voxel edge may hit the neighbour the reference does
//! not. Each view's bounds are the values measured on lavapipe minus a stated margin; a
//! broken traversal (a wrong child slot, a lost stack entry, a wrong t mapping) drops the
//! same-voxel rate or the IoU far below them.

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::Scene;
use ssbvb_voxel::accuracy::{self, AccuracyReport};
use ssbvb_voxel::camera::Camera;

const ESVO: &str = include_str!("../../../assets/pipelines/esvo.ron");
const SIZE: (u32, u32) = (120, 90);

/// Lower bounds on agreement and upper bounds on error for one view.
struct Bounds {
    iou: f64,
    same_voxel: f64,
    /// Median and p95 depth error, in cells.
    depth: (f64, f64),
    /// Median and p95 normal error, in degrees.
    normal: (f64, f64),
}

/// Measured on lavapipe over the views below (one object, instances, inside views, grazing
/// rays, close up at 1e7): IoU 1.0, same voxel ≥ 0.9952 (three instances; ≥ 0.9989 elsewhere), depth
/// median ≤ 9.7e-6 and p95 ≤ 3.9e-5 cells, normal median 0° and p95 ≤ 0.01°. Bounds: 4×
/// the measured voxel misses, ≥ 10× the depth error, and IoU 0.995 as for the octree
/// caster (other adapters' f32 rounding).
const EXACT: Bounds = Bounds {
    iou: 0.995,
    same_voxel: 0.98,
    depth: (1e-4, 5e-4),
    normal: (0.5, 0.5),
};

/// The far narrow view: at 1e6 units the G-buffer's camera-relative f32 positions are
/// ~0.06 units (one cell of level 5) apart, so depth, and the voxel recovered from it,
/// are coarse for every technique. Measured on lavapipe, identical for ESVO and the
/// octree caster: IoU 1.0, same voxel 0.274, depth median 1.02 and p95 1.63 cells.
const FAR: Bounds = Bounds {
    iou: 0.995,
    same_voxel: 0.2,
    depth: (1.5, 2.5),
    normal: (0.5, 0.5),
};

/// The accuracy of `pipeline` (`technique`) on `scene` (one object at LOD `level`) from
/// `cam` at `size`.
fn measure(
    technique: &str,
    pipeline: &str,
    what: &str,
    scene: &Scene,
    level: u32,
    cam: &Camera,
    size: (u32, u32),
) -> AccuracyReport {
    let reference = ssbvb_tests::reference_of(scene, cam, size);
    let f = ssbvb_tests::render(pipeline, scene.clone(), cam, size);
    let mut hits = ssbvb_tests::gbuffer_hits(&f, what);
    // The G-buffer holds no voxel id: the voxel is the cell behind the entered face.
    let object = &scene.objects[0];
    let lookup = &object.asset.lods[level as usize].lookup;
    let placed: Vec<_> = object.instances.iter().map(|xf| (*xf, lookup)).collect();
    accuracy::recover_face_voxels(&mut hits, cam, size, &placed);
    let r = accuracy::compare(&reference, &hits, &cells(scene, level)).unwrap();
    eprintln!(
        "{technique} {what}: IoU {:.4}, same voxel {:.4}, depth median {:.2e} p95 {:.2e} voxels, normal median {:.2}° p95 {:.2}°, px {}",
        r.coverage_iou,
        r.same_voxel_rate,
        r.depth_error_voxels.median,
        r.depth_error_voxels.p95,
        r.normal_error_deg.median,
        r.normal_error_deg.p95,
        r.covered_reference
    );
    r
}

/// ESVO's accuracy on `scene` (one object at LOD `level`) from `cam` at `size`. Asserts `b`
/// and at least `min_px` covered reference pixels.
fn check(
    what: &str,
    scene: &Scene,
    level: u32,
    cam: &Camera,
    size: (u32, u32),
    min_px: usize,
    b: &Bounds,
) -> AccuracyReport {
    let r = measure("EsvoRayCast", ESVO, what, scene, level, cam, size);
    assert!(r.covered_reference >= min_px, "{what}: {r:?}");
    assert!(r.coverage_iou >= b.iou, "{what}: {r:?}");
    assert!(r.same_voxel_rate >= b.same_voxel, "{what}: {r:?}");
    assert!(r.depth_error_voxels.median <= b.depth.0, "{what}: {r:?}");
    assert!(r.depth_error_voxels.p95 <= b.depth.1, "{what}: {r:?}");
    assert!(r.normal_error_deg.median <= b.normal.0, "{what}: {r:?}");
    assert!(r.normal_error_deg.p95 <= b.normal.1, "{what}: {r:?}");
    r
}

/// Cell sizes of the scene's instances (one object) at `level`.
fn cells(scene: &Scene, level: u32) -> Vec<f64> {
    scene.objects[0]
        .instances
        .iter()
        .map(|xf| 2.0 * xf.matrix3.determinant().abs().cbrt() / (1u64 << level) as f64)
        .collect()
}

#[test]
fn esvo_matches_the_reference_on_one_object() {
    let cameras = [
        Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.6, -0.8, -1.5), DVec3::new(0.0, 0.1, 0.0)),
        // Straight down the Z axis: rays parallel to grid planes (exact f32 ties).
        Camera::new(DVec3::new(0.0, 0.0, 3.2), DVec3::ZERO),
    ];
    // The finest level of two models, and the bunny at LOD 4 (inner octree nodes).
    for (file, asset_level, level) in [
        ("bunny.obj", 6, 6),
        ("chr_knight.vox", 5, 5),
        ("bunny.obj", 6, 4),
    ] {
        let asset = ssbvb_tests::model_asset(file, asset_level);
        let scene = ssbvb_tests::single_object_scene(asset, level);
        for (ci, cam) in cameras.iter().enumerate() {
            let what = format!("{file} L{asset_level} LOD {level} camera {ci}");
            check(&what, &scene, level, cam, SIZE, 200, &EXACT);
        }
    }
}

#[test]
fn esvo_matches_the_reference_with_instances_and_inside_views() {
    let level = 5;
    let asset = ssbvb_tests::model_asset("bunny.obj", level);
    let mut scene = ssbvb_tests::single_object_scene(asset.clone(), level);
    // Inside the grid's box in an empty corner, looking at the bunny.
    let inside = Camera {
        near: 1e-3,
        ..Camera::new(DVec3::new(0.85, 0.7, 0.85), DVec3::ZERO)
    };
    check(
        "camera inside the grid",
        &scene,
        level,
        &inside,
        SIZE,
        3000,
        &EXACT,
    );
    // Rotated, scaled and mirrored instances overlapping on screen.
    scene.objects[0].instances = ssbvb_tests::three_overlapping_instances();
    let cam = Camera::new(DVec3::new(0.5, 1.4, 4.2), DVec3::new(0.1, 0.0, 0.0));
    check("three instances", &scene, level, &cam, SIZE, 2000, &EXACT);

    // Rays almost in the plane of a voxel layer's top faces: edge ties everywhere, where
    // ESVO's diagonal steps and accumulated times could part from the reference most
    // (measured on lavapipe: all the same voxels).
    let grazing = ssbvb_tests::grazing_camera(&asset, level);
    let scene = ssbvb_tests::single_object_scene(asset, level);
    check("grazing", &scene, level, &grazing, SIZE, 100, &EXACT);

    // A closed shell around the camera: every pixel hits a wall, entered from inside the
    // octree's box.
    let shell = crate::empty_space::synthetic_asset(level, &crate::empty_space::hollow_box(3, 28));
    let scene = ssbvb_tests::single_object_scene(shell, level);
    let cell = 2.0 / (1u64 << level) as f64;
    let eye = DVec3::new(-1.0 + 9.5 * cell, -1.0 + 17.5 * cell, -1.0 + 20.5 * cell);
    for look in [DVec3::new(1.0, 0.1, 0.2), DVec3::new(-1.0, 1.0, -1.0)] {
        let cam = Camera {
            near: 1e-3,
            ..Camera::new(eye, eye + look)
        };
        let r = check("inside a shell", &scene, level, &cam, SIZE, 0, &EXACT);
        assert_eq!(
            r.covered_gpu,
            (SIZE.0 * SIZE.1) as usize,
            "a gap in the shell"
        );
    }
}

#[test]
fn esvo_matches_the_reference_far_away() {
    let level = 5;
    let asset = ssbvb_tests::model_asset("bunny.obj", level);
    let mut scene = ssbvb_tests::single_object_scene(asset, level);
    // A narrow view from 1e6 units with a second bunny behind the first, partly hidden
    // (ray casters measured IoU 1.0 there).
    let eye = DVec3::new(309426.0, 206284.0, 928279.0);
    let back = -eye.normalize() * 3.0;
    let side = eye.cross(DVec3::Y).normalize() * 0.9;
    scene.objects[0].instances = vec![DAffine3::IDENTITY, DAffine3::from_translation(back + side)];
    let far = Camera {
        fov_y_deg: 0.00025,
        far: f64::INFINITY,
        ..Camera::new(eye, DVec3::ZERO)
    };
    let esvo = check(
        "far narrow, two bunnies",
        &scene,
        level,
        &far,
        (96, 72),
        1000,
        &FAR,
    );
    // The same pixels as the octree caster's (the error is the G-buffer's, not ESVO's).
    let octree = measure(
        "OctreeRayCast",
        include_str!("../../../assets/pipelines/octree.ron"),
        "far narrow, two bunnies",
        &scene,
        level,
        &far,
        (96, 72),
    );
    assert!(
        esvo.same_voxel_rate >= octree.same_voxel_rate - 0.02,
        "{esvo:?} {octree:?}"
    );
    assert!(
        esvo.depth_error_voxels.median <= octree.depth_error_voxels.median + 0.05,
        "{esvo:?} {octree:?}"
    );
    // The object 1e7 units from the origin, seen close up with a near plane of 1e-4.
    let offset = DVec3::new(1e7, -2e7, 1.5e7);
    scene.objects[0].instances = vec![DAffine3::from_translation(offset)];
    let close = Camera {
        near: 1e-4,
        ..Camera::new(
            offset + DVec3::new(0.35, 0.1, 0.95),
            offset + DVec3::new(0.0, 0.1, 0.0),
        )
    };
    check("close up at 1e7", &scene, level, &close, SIZE, 3000, &EXACT);
}

/// Counters: every covered pixel cast a ray, and a ray descends at least to the level; a
/// frame that does not count draws the same G-buffer bit for bit and reports nothing.
#[test]
fn esvo_counts_its_steps_and_draws_the_same_without_counting() {
    let level = 6;
    let scene =
        ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", level), level);
    let cam = Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO);
    let mut f = ssbvb_tests::render(ESVO, scene, &cam, SIZE);
    let covered = ssbvb_tests::gbuffer_hits(&f, "counters")
        .iter()
        .flatten()
        .count();
    let c = f.renderer.counters(ssbvb_tests::ctx()).unwrap();
    eprintln!("EsvoRayCast counters: {c:?}, {covered} px covered");
    assert!(covered > 1000, "{covered} px");
    assert!(c.ray_cast_rays.unwrap() >= covered as u64, "{c:?}");
    let steps = c.octree_nodes_per_ray.unwrap();
    assert!(steps >= f64::from(level), "{c:?}");
    assert!(c.dda_steps_per_ray.is_none(), "{c:?}");
    let gbuffer = ["gbuffer_position", "gbuffer_normal", "gbuffer_albedo"];
    let counted: Vec<Vec<u8>> = gbuffer.iter().map(|n| f.read(n)).collect();
    f.renderer.set_counting(false);
    f.renderer
        .render(
            ssbvb_tests::ctx(),
            &mut f.scene,
            &cam,
            ssbvb_passes::Profiling::Off,
        )
        .unwrap();
    for (n, bytes) in gbuffer.iter().zip(&counted) {
        assert!(f.read(n) == *bytes, "{n} differs without counting");
    }
    let c = f.renderer.counters(ssbvb_tests::ctx()).unwrap();
    assert!(c.ray_cast_rays.is_none(), "{c:?}");
}
