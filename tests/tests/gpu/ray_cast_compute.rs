//! The compute form of the octree ray casters (`compute: true` on `OctreeRayCast` and
//! `EsvoRayCast`; `shaders/ray_cast_compute.inc.wgsl`) against their fragment form, which
//! the other GPU tests hold to the CPU reference: the same G-buffer bit for bit (every
//! attachment, depth and stencil) and the same counters, on one object, on overlapping
//! mirrored instances and at a size that is no multiple of the 16 × 16 workgroup. A frame
//! that does not count draws the same too. The compute form launches only the tiles some
//! instance's box may cover: boxes around, behind and beside the camera on a screen of
//! more tiles than the listing takes at a time draw what the fragment form draws, and the
//! count of tiles it launched is the count of the boxes' widened pixel rectangles,
//! projected on the CPU.

use glam::{DAffine3, DVec2, DVec3};
use ssbvb_gpu::scene::Scene;
use ssbvb_voxel::camera::Camera;

const ESVO: &str = include_str!("../../../assets/pipelines/esvo.ron");
const OCTREE: &str = include_str!("../../../assets/pipelines/octree.ron");

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

/// The 16 × 16 tiles of a `w` × `h` screen that the boxes' pixel rectangles, widened by
/// `widen` pixels, touch (`box_tiles` in `shaders/ray_cast_compute.inc.wgsl`, in f64): each
/// visible instance's box of voxels (camera-relative world) projected through `camera`.
/// Every box here lies wholly in front of the camera or wholly behind it (no tile).
fn projected_tiles(frame: &ssbvb_tests::Frame, camera: &Camera, widen: (f64, f64)) -> usize {
    let (w, h) = (337.0, 203.0);
    let (right, up, forward) = camera.basis();
    let tan_y = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let tan_x = tan_y * w / h;
    let across = (w / 16.0_f64).ceil() as usize;
    let rows = (h / 16.0_f64).ceil() as usize;
    let mut flagged = vec![false; across * rows];
    let gpu = &frame.scene;
    let instances: Vec<DAffine3> = gpu.scene.objects[0].instances.clone();
    for v in &gpu.visible {
        let lod = (gpu.lod_base[v.object] + v.level) as usize;
        let (lo, hi) = gpu.lod_bounds[lod].expect("every instance has voxels");
        let xf = instances[v.scene_index as usize];
        let (mut lo_ndc, mut hi_ndc) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
        let mut ahead = 0;
        for i in 0..8 {
            let corner =
                DVec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), hi, lo);
            let c = xf.transform_point3(corner) - camera.position;
            let a = c.dot(forward);
            ahead += usize::from(a > 0.0);
            let ndc = DVec2::new(c.dot(right) / tan_x, c.dot(up) / tan_y) / a;
            lo_ndc = lo_ndc.min(ndc);
            hi_ndc = hi_ndc.max(ndc);
        }
        assert!(ahead == 0 || ahead == 8, "a box reaches the camera's plane");
        if ahead == 0 {
            continue;
        }
        // Pixel k's centre has NDC (k + 0.5) / size * 2 - 1 (y flipped).
        let p_lo = (DVec2::new(lo_ndc.x, -hi_ndc.y) + 1.0) * 0.5 * DVec2::new(w, h) - 0.5 - widen.0;
        let p_hi = (DVec2::new(hi_ndc.x, -lo_ndc.y) + 1.0) * 0.5 * DVec2::new(w, h) - 0.5 + widen.1;
        if p_hi.x < 0.0 || p_hi.y < 0.0 || p_lo.x > w || p_lo.y > h {
            continue;
        }
        let tile = |p: f64, size: f64, last: usize| ((p.clamp(0.0, size) as usize) / 16).min(last);
        for ty in tile(p_lo.y, h, rows - 1)..=tile(p_hi.y, h, rows - 1) {
            for tx in tile(p_lo.x, w, across - 1)..=tile(p_hi.x, w, across - 1) {
                flagged[ty * across + tx] = true;
            }
        }
    }
    flagged.iter().filter(|&&f| f).count()
}

/// The compute form launches the tiles its boxes' pixel rectangles (widened by two pixels)
/// touch, no fewer (a hole) and no more (work wasted, which no image shows): the launched
/// count against the same rectangles projected in f64, widened by two pixels give or take
/// the rounding of the shader's f32 mapping. Twelve small boxes ahead, apart on the
/// screen; two cut by the screen's edges; one whose bounding sphere the frustum keeps but
/// whose box lies off the screen, and one whose sphere holds the camera but whose box lies
/// wholly behind it (no tile for either); two behind the camera (culled). The view is
/// one where a pixel more or less of widening on either side changes the count.
#[test]
fn compute_casters_launch_the_tiles_their_boxes_project_to() {
    let level = 4;
    let asset = ssbvb_tests::model_asset("bunny.obj", level);
    let mut scene = ssbvb_tests::single_object_scene(asset, level);
    let mut at: Vec<(f64, f64, f64)> = (0..12)
        .map(|i| {
            let (col, row) = ((i % 4) as f64, (i / 4) as f64);
            (
                -4.4 + 3.05 * col + 0.3 * row,
                -2.36 + 2.45 * row,
                -7.0 - 1.3 * row - 0.4 * col,
            )
        })
        .collect();
    at.extend([
        (-4.4, 0.5, -6.0),
        (4.7, -1.0, -6.5),
        (4.95, 1.5, -6.0),
        (0.3, 0.1, 0.5),
        (0.0, 0.0, 6.0),
        (2.0, 1.0, 9.0),
    ]);
    scene.objects[0].instances = at
        .iter()
        .map(|&(x, y, z)| {
            DAffine3::from_translation(DVec3::new(x, y, z))
                * DAffine3::from_scale(DVec3::splat(0.4))
        })
        .collect();
    let camera = Camera::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0));
    for (pipeline, kind) in [(ESVO, "EsvoRayCast"), (OCTREE, "OctreeRayCast")] {
        let frame = ssbvb_tests::render(
            &compute_form(pipeline, kind),
            scene.clone(),
            &camera,
            (337, 203),
        );
        let launched = frame
            .renderer
            .counters(ssbvb_tests::ctx())
            .unwrap()
            .ray_cast_tiles
            .expect("the compute form counts its tiles");
        let seen: Vec<u32> = frame.scene.visible.iter().map(|v| v.scene_index).collect();
        assert_eq!(seen, (0..16).collect::<Vec<_>>(), "{kind}");
        let tiles = |lo: f64, hi: f64| projected_tiles(&frame, &camera, (lo, hi));
        let (fewest, most) = (tiles(1.98, 1.98), tiles(2.03, 2.03));
        assert!(
            (fewest..=most).contains(&(launched as usize)),
            "{kind}: {launched} tiles launched, the boxes project to {fewest}..={most}"
        );
        // A pixel more or less on either side would fail.
        assert!(tiles(3.0, 2.03) > most && tiles(2.03, 3.0) > most);
        assert!(tiles(1.0, 1.98) < fewest && tiles(1.98, 1.0) < fewest);
        assert!(most < 200, "{kind}: {most} of 286 tiles: too little sky");
    }
    // A box beside the camera reaching behind its plane (its corners project to no
    // rectangle): every tile.
    scene.objects[0].instances = vec![
        DAffine3::from_translation(DVec3::new(0.8, 0.0, -0.1))
            * DAffine3::from_scale(DVec3::splat(0.4)),
    ];
    let frame = ssbvb_tests::render(
        &compute_form(ESVO, "EsvoRayCast"),
        scene,
        &camera,
        (337, 203),
    );
    let v = &frame.scene.visible;
    assert!(v.len() == 1 && !v[0].camera_inside);
    let counters = frame.renderer.counters(ssbvb_tests::ctx()).unwrap();
    assert_eq!(counters.ray_cast_tiles, Some(286));
}
