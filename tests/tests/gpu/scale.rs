//! Scale: many instances with per-instance LOD against the reference, and the filter's
//! counters, which show that a pixel's cost follows the instances its ray meets.

use glam::{DAffine3, DQuat, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_passes::FrameCounters;
use ssbvb_tests::{ctx, model_asset};
use ssbvb_voxel::camera::Camera;

use crate::ray_march_filter::{check_against_reference, run_filter};

/// The layout of `assets/scenes/bunnies_64.ron` (and of the 4096 scene, at `n` = 64): an
/// `n` × `n` grid 2.2 apart, turned by the file's hash.
pub(crate) fn bunny_grid(n: usize, level: u32, lod: LodPolicy) -> Scene {
    model_grid("bunny.obj", n, level, lod)
}

/// `n` × `n` instances of model `file` at `level`, 2.2 apart, each turned its own way.
fn model_grid(file: &str, n: usize, level: u32, lod: LodPolicy) -> Scene {
    let half = (n as f64 - 1.0) / 2.0;
    let mut instances = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let deg = ((i as u64 * 73856093) ^ (j as u64 * 19349663)) % 360;
            instances.push(DAffine3::from_rotation_translation(
                DQuat::from_rotation_y((deg as f64).to_radians()),
                DVec3::new((i as f64 - half) * 2.2, 0.0, (j as f64 - half) * 2.2),
            ));
        }
    }
    Scene {
        objects: vec![VoxelObject {
            asset: model_asset(file, level),
            instances,
            lod,
        }],
        ..Default::default()
    }
}

fn counters(run: &crate::ray_march_filter::FilterRun) -> FrameCounters {
    let c = run.frame.renderer.counters(ctx()).unwrap();
    eprintln!("counters: {c:?}");
    c
}

/// Pixels the prepass covered (`entry` w = instance + 1 >= 1): the filter casts one ray
/// from each of them and from no other pixel.
fn prepass_pixels(run: &crate::ray_march_filter::FilterRun) -> u64 {
    let entry = run.frame.read_f32("entry");
    entry.chunks(4).filter(|e| e[3] >= 1.0).count() as u64
}

/// 64 bunnies with per-instance Auto LOD, seen over the grid as in `bunnies_64.ron`: the
/// filter equals the reference at the same levels, and a ray tests a few hierarchy boxes
/// instead of every visible instance.
#[test]
fn a_grid_of_64_bunnies_with_auto_lod_matches_the_reference() {
    let scene = bunny_grid(8, 6, LodPolicy::AUTO);
    let camera = Camera::new(DVec3::new(-11.0, 3.5, -11.0), DVec3::new(0.0, -1.0, 0.0));
    let size = (160, 120);
    let report = check_against_reference("bunnies64", &scene, &camera, size);
    assert!(report.coverage_iou >= 0.999, "{report:?}");
    assert!(report.covered_reference > 3000, "{report:?}");
    let run = run_filter(&scene, &camera, size, 1024);
    let visible = run.frame.scene.visible.len();
    let levels = run.frame.scene.lod_histogram();
    eprintln!("visible {visible}, levels {levels:?}");
    assert!(visible >= 40, "{visible} visible");
    assert!(
        levels.len() >= 2,
        "one level for near and far bunnies: {levels:?}"
    );
    assert_eq!(levels.values().sum::<usize>(), visible);
    let c = counters(&run);
    let rays = c.filter_rays.unwrap();
    assert_eq!(rays, prepass_pixels(&run), "{c:?}");
    assert!(rays >= run.fill as u64, "{c:?}");
    let boxes = c.instance_boxes_per_ray.unwrap();
    let marched = c.instances_marched_per_ray.unwrap();
    // Measured on lavapipe: 6.0 boxes of the screen tiles' lists (20.1 hierarchy boxes
    // before the lists; the old per-pixel loop box-tested all 62 visible) and 1.88
    // instances marched per ray; 2.02 when the walk does not start at the prepass entry
    // (`prepass_floor`, filter_march.inc.wgsl): the bound on marches lies between the two.
    assert!(boxes > 3.0 && boxes < 30.0, "{c:?}");
    assert!((1.0..1.95).contains(&marched), "{c:?}");
    let mean = c.march_steps_mean.unwrap();
    assert!(
        mean >= 1.0 && (c.march_steps_p99.unwrap() as f64) >= mean,
        "{c:?}"
    );
    // Lookup nodes (3 words) read per step: most steps stay in the leaf or its parent the
    // march keeps in registers. Bounded by a descent from the root (depth 4 at level 8)
    // per step.
    let words = c.node_words_per_step.unwrap();
    assert!(words > 0.0 && words < 12.0, "{c:?}");
}

/// 64 knights (`chr_knight.vox`: flat faces, so its proxy lies on the voxels' faces) at
/// level 6, seen from so far that each covers a pixel or two: most of their pixels have no
/// neighbour of the same instance, so the filter starts their marches from the margin for
/// such pixels (outside the object's box; started after the entry instead, the march
/// begins inside the first voxels and returns a deeper one), and must still find the
/// reference's voxel at every pixel.
#[test]
fn models_of_a_pixel_or_two_match_the_reference() {
    let scene = model_grid("chr_knight.vox", 8, 6, LodPolicy::Fixed(6));
    let camera = Camera::new(DVec3::new(-70.0, 25.0, -70.0), DVec3::new(0.0, 0.0, 0.0));
    let size = (64, 48);
    let report = check_against_reference("knights64_tiny", &scene, &camera, size);
    let run = run_filter(&scene, &camera, size, 1024);
    let entry = run.frame.read_f32("entry");
    let instance = |x: i64, y: i64| -> f32 {
        if x < 0 || y < 0 || x >= size.0 as i64 || y >= size.1 as i64 {
            return 0.0;
        }
        entry[(y as usize * size.0 as usize + x as usize) * 4 + 3]
    };
    let mut lone = 0;
    for y in 0..size.1 as i64 {
        for x in 0..size.0 as i64 {
            let w = instance(x, y);
            let alone = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .all(|(dx, dy)| instance(x + dx, y + dy) != w);
            if w >= 1.0 && alone {
                lone += 1;
            }
        }
    }
    eprintln!("{lone} pixels without a neighbour of their instance; {report:?}");
    // Measured on lavapipe: all 25 pixels of the proxies are alone, 23 of them hit a voxel.
    assert!(lone >= 20, "{lone} lone pixels");
    assert!(report.covered_reference >= 20, "{report:?}");
    assert!(report.same_voxel_rate == 1.0, "{report:?}");
}

/// One instance: no hierarchy walk, one march per ray; a step limit bounds the steps per
/// ray and their p99 (the histogram and its bins), and more steps are counted when the
/// limit is lifted.
#[test]
fn counters_of_one_instance_and_of_a_step_limit() {
    let scene = ssbvb_tests::single_object_scene(model_asset("bunny.obj", 6), 6);
    let camera = Camera::new(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO);
    let size = (80, 60);
    let run = run_filter(&scene, &camera, size, 1024);
    let c = counters(&run);
    assert_eq!(c.instance_boxes_per_ray, Some(0.0), "{c:?}");
    assert_eq!(c.instances_marched_per_ray, Some(1.0), "{c:?}");
    assert_eq!(c.billboards_drawn, Some(run.fill as u64));
    let rays = c.filter_rays.unwrap();
    assert!(rays >= run.fill as u64 && run.fill > 800, "{c:?}");
    assert_eq!(rays, prepass_pixels(&run), "{c:?}");
    let free = c.march_steps_mean.unwrap();
    for limit in [3u32, 40] {
        let run = run_filter(&scene, &camera, size, limit);
        let c = counters(&run);
        let mean = c.march_steps_mean.unwrap();
        let p99 = c.march_steps_p99.unwrap();
        assert!(mean > 1.0 && mean <= limit as f64, "limit {limit}: {c:?}");
        // p99 is its bin's largest count: the bin of `limit` ends within 1/8 above it.
        assert!(
            p99 as f64 >= mean && p99 <= limit as u64 + limit as u64 / 8,
            "{c:?}"
        );
    }
    assert!(free > 3.0, "{free}");
}

/// A camera close to the bunny's surface (voxels tens of pixels wide): the default
/// pipeline draws each visible voxel once — no more billboards than visible voxels (counted
/// from the reference's hits, an independent oracle) or covered pixels — and a few
/// fragments per covered pixel, while the paper's per-pixel Flat frame draws a quad per
/// pixel, tens of fragments each. Both show the same G-buffer.
#[test]
fn near_camera_overdraw_is_bounded_in_the_default_pipeline() {
    let level = 5;
    let scene = ssbvb_tests::single_object_scene(model_asset("bunny.obj", level), level);
    let size = (96, 72);
    let views = [
        (
            "touching",
            Camera::new(DVec3::new(0.05, 0.2, 0.75), DVec3::new(0.0, 0.0, -1.0)),
        ),
        ("mid", Camera::new(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO)),
    ];
    let default = include_str!("../../../assets/pipelines/ssbvb_unique.ron");
    let flat = include_str!("../../../assets/pipelines/ssbvb_flat.ron");
    for (name, camera) in views {
        let reference = ssbvb_tests::reference_of(&scene, &camera, size);
        let mut visible: Vec<(u32, u32)> = reference
            .hits
            .iter()
            .flatten()
            .map(|h| (h.instance, h.voxel))
            .collect();
        visible.sort_unstable();
        visible.dedup();
        let covered = reference.coverage();
        let d = ssbvb_tests::render(default, scene.clone(), &camera, size);
        let f = ssbvb_tests::render(flat, scene.clone(), &camera, size);
        let (cd, cf) = (
            d.renderer.counters(ctx()).unwrap(),
            f.renderer.counters(ctx()).unwrap(),
        );
        eprintln!(
            "{name}: {covered} covered px, {} visible voxels; default {cd:?}; flat {cf:?}",
            visible.len()
        );
        let drawn = cd.billboards_drawn.unwrap();
        // Silhouette rays may differ from the reference's by a handful.
        assert!(
            drawn as usize <= visible.len() + 4,
            "{name}: {drawn} billboards"
        );
        assert!(drawn as usize <= covered + 4, "{name}: {drawn} billboards");
        // llvmpipe counts fragment-shader invocations per touched 4x4 block (every count is
        // a multiple of 16), so small quads count up to 16 each: the mid view's numbers are
        // inflated, the touching view's (quads of hundreds of pixels) nearly exact.
        // Measured: touching 2.6 (flat 799), mid 16.4 (flat 55.1).
        let frags = cd
            .fragments_per_covered_pixel
            .expect("lavapipe counts fragments");
        let flat_frags = cf.fragments_per_covered_pixel.unwrap();
        assert!(
            frags < flat_frags * 0.5,
            "{name}: {frags} vs flat {flat_frags}"
        );
        if name == "touching" {
            assert!(frags < 4.0, "{name}: {frags} fragments per covered pixel");
            assert!(
                flat_frags > 100.0 * frags,
                "{name}: flat {flat_frags} vs {frags}"
            );
        }
        // Same G-buffer (up to a few ties between voxels at one depth).
        let (a, b) = (d.read("gbuffer_normal"), f.read("gbuffer_normal"));
        let differing = a.chunks(8).zip(b.chunks(8)).filter(|(p, q)| p != q).count();
        assert!(differing <= 3, "{name}: {differing} pixels differ");
    }
}

/// The far view: the bunny from (309426, 206284, 928279) through a 0.00016° lens,
/// with the default (infinite) far plane. The prepass and billboards go object → view in
/// an f64-composed matrix and the filter marches from the entry point, so the frame
/// matches the f64 reference (measured IoU 0.997 at level 8, 320x240; before, 0.118 —
/// f32 camera-relative coordinates lost the voxels).
#[test]
fn the_far_narrow_view_matches_the_reference() {
    let level = 6;
    let scene = ssbvb_tests::single_object_scene(model_asset("bunny.obj", level), level);
    let camera = Camera {
        fov_y_deg: 0.00016,
        far: f64::INFINITY,
        ..Camera::new(DVec3::new(309426.0, 206284.0, 928279.0), DVec3::ZERO)
    };
    let size = (96, 72);
    let reference = ssbvb_tests::reference_of(&scene, &camera, size);
    assert!(reference.coverage() > 1500, "{}", reference.coverage());
    let f = ssbvb_tests::render(
        include_str!("../../../assets/pipelines/ssbvb_unique.ron"),
        scene,
        &camera,
        size,
    );
    let hits = ssbvb_tests::gbuffer_hits(&f, "far narrow");
    let cell = 2.0 / (1u64 << level) as f64;
    let r = ssbvb_voxel::accuracy::compare(&reference, &hits, &[cell]).unwrap();
    eprintln!("far narrow view: {r:?}");
    assert!(r.coverage_iou >= 0.97, "{r:?}");
    // Depth: the G-buffer stores camera-relative f32 positions, and an f32 ulp at 1.1e6
    // units is 0.125, four cells of level 6: measured median 1.5 cells, p95 4.3.
    assert!(r.depth_error_voxels.median <= 3.0, "{r:?}");
    assert!(r.depth_error_voxels.p95 <= 8.0, "{r:?}");
}

/// Two bunnies at `level` seen from 10⁶ units away through a 0.00025° lens, the second
/// behind and beside the first, partly hidden.
pub(crate) fn far_two_bunnies(level: u32) -> (Scene, Camera) {
    let mut scene = ssbvb_tests::single_object_scene(model_asset("bunny.obj", level), level);
    let eye = DVec3::new(309426.0, 206284.0, 928279.0);
    let back = -eye.normalize() * 3.0;
    let side = eye.cross(DVec3::Y).normalize() * 0.9;
    scene.objects[0].instances = vec![DAffine3::IDENTITY, DAffine3::from_translation(back + side)];
    let camera = Camera {
        fov_y_deg: 0.00025,
        far: f64::INFINITY,
        ..Camera::new(eye, DVec3::ZERO)
    };
    (scene, camera)
}

/// The far narrow view with a second bunny behind the first, partly hidden: where the
/// nearest proxy's instance misses, the ray goes on to the other instance through the
/// hierarchy, and that march must be as precise as the first (`object_ray`). The default
/// pipeline and the ray casters match the reference.
#[test]
fn the_far_narrow_view_of_two_bunnies_matches_the_reference() {
    let level = 5;
    let (scene, camera) = far_two_bunnies(level);
    let size = (96, 72);
    let reference = ssbvb_tests::reference_of(&scene, &camera, size);
    let behind = reference
        .hits
        .iter()
        .flatten()
        .filter(|h| h.instance == 1)
        .count();
    assert!(behind > 300, "the second bunny shows in {behind} px");
    let cell = 2.0 / (1u64 << level) as f64;
    for (name, src) in [
        (
            "ssbvb",
            include_str!("../../../assets/pipelines/ssbvb_unique.ron"),
        ),
        (
            "octree",
            include_str!("../../../assets/pipelines/octree.ron"),
        ),
        (
            "dense",
            include_str!("../../../assets/pipelines/dense_dda.ron"),
        ),
    ] {
        let f = ssbvb_tests::render(src, scene.clone(), &camera, size);
        let hits = ssbvb_tests::gbuffer_hits(&f, "far two");
        let r = ssbvb_voxel::accuracy::compare(&reference, &hits, &[cell, cell]).unwrap();
        eprintln!("{name} far two bunnies: {r:?}");
        // Measured: 0.9927 (SSBVB: the flat quads' overhang at the silhouettes, exactly
        // their rectangles since fragments are trimmed to them; 0.9964 while vertex
        // snapping trimmed some of it, and cost sub-pixel voxels their pixels), 1.0 (ray
        // casters); with the second bunny marched from the camera: 0.988, 0.974, 0.973.
        let bound = if name == "ssbvb" { 0.99 } else { 0.995 };
        assert!(r.coverage_iou >= bound, "{name}: {r:?}");
    }
}

/// Fifteen solid cubes (centre, half size) whose boxes overlap in depth, seen from the
/// origin along −z. Found by a CPU search over random scenes for one where the instance
/// walk, with a child's stack time left stale (the last time stored in that stack slot),
/// prunes the subtree holding the nearest cube: 449 of this view's 4096 pixel rays then
/// keep a farther cube. Regular grids never produce it (no test caught that mutant).
const OVERLAPPING_CUBES: [([f64; 3], f64); 15] = [
    ([-0.03, -2.12, -10.86], 1.52),
    ([-1.01, -2.61, -4.85], 1.23),
    ([1.84, 0.03, -10.27], 0.50),
    ([0.64, 3.34, -13.68], 1.26),
    ([1.01, 1.51, -9.65], 1.69),
    ([-1.42, -1.68, -4.50], 1.11),
    ([2.49, 2.13, -4.35], 0.92),
    ([-0.56, -0.70, -9.97], 1.47),
    ([-2.04, 2.93, -7.20], 1.24),
    ([1.82, -3.07, -10.50], 0.90),
    ([-1.25, 1.28, -5.62], 1.72),
    ([-3.24, 2.95, -3.46], 1.77),
    ([-0.80, 0.83, -3.36], 1.23),
    ([1.72, 1.40, -10.35], 1.78),
    ([-0.63, 0.43, -5.75], 1.50),
];

/// [`OVERLAPPING_CUBES`] as instances of a solid block at level 2, and the camera at the
/// origin looking along −z.
pub(crate) fn overlapping_cubes() -> (Scene, Camera) {
    let level = 2;
    let n = 1u32 << level;
    let cells: Vec<[u32; 3]> = (0..n * n * n)
        .map(|i| [i % n, i / n % n, i / (n * n)])
        .collect();
    let asset = crate::empty_space::synthetic_asset(level, &cells);
    let instances = OVERLAPPING_CUBES
        .iter()
        .map(|&(c, h)| {
            DAffine3::from_scale_rotation_translation(DVec3::splat(h), DQuat::IDENTITY, c.into())
        })
        .collect();
    let scene = Scene {
        objects: vec![VoxelObject {
            asset,
            instances,
            lod: LodPolicy::Fixed(level),
        }],
        ..Default::default()
    };
    (scene, Camera::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0)))
}

/// Overlapping instance boxes: every pixel shows the nearest cube's face, as the reference.
/// (The filter starts its walk from the prepass's nearest proxy, which is the nearest cube
/// here, so it does not depend on the walk's pruning; `ray_casters::overlapping_…` does.)
#[test]
fn overlapping_instance_boxes_keep_the_nearest_hit() {
    let (scene, camera) = overlapping_cubes();
    let r = check_against_reference("overlapping_cubes", &scene, &camera, (64, 64));
    assert!(r.covered_reference > 2000, "{r:?}");
    assert!(r.same_voxel_rate >= 0.999, "{r:?}");
    assert!(r.depth_error_voxels.max <= 1e-3, "{r:?}");
}
