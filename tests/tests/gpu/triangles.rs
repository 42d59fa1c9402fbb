//! Triangles in the G-buffer: a ground plane checked against its analytic intersection
//! (coverage, stencil, colour, normal, position, linear and reversed-Z depth), and
//! billboards depth-tested against triangles (stencil 1 exactly on voxel pixels).

use glam::DVec3;
use ssbvb_gpu::scene::{Scene, TriangleObject};
use ssbvb_graph::BillboardMode;
use ssbvb_passes::kinds::billboards::{BillboardOptions, DEFAULT_CULL_COS, Footprint};
use ssbvb_tests::{model_asset, reference_of, render, single_object_scene};
use ssbvb_voxel::camera::Camera;

use crate::billboard_harness::{BUNNY, GBuffer, LEVEL, SIZE, draw, pipeline_src};

const TRIANGLES_ONLY: &str = r#"Pipeline(
  resources: {
    "gbuffer_albedo":   Texture(format: R32Uint, size: Screen),
    "gbuffer_normal":   Texture(format: Rgba16Float, size: Screen),
    "gbuffer_position": Texture(format: Rgba32Float, size: Screen),
    // Geometric normal (the face or triangle hit), octahedral-encoded.
    "gbuffer_geometric_normal": Texture(format: Rg16Float, size: Screen),
    "depth_stencil":    Texture(format: Depth32FloatStencil8, size: Screen),
  },
  passes: [
    (name: "triangles", kind: Triangles,
     writes: ["gbuffer_albedo", "gbuffer_normal", "gbuffer_position", "gbuffer_geometric_normal", "depth_stencil"]),
  ],
  output: "gbuffer_albedo",
)"#;

/// Colour whose channels are exact in 8-bit unorm (51, 153, 102).
const PLANE_COLOR: [f32; 4] = [0.2, 0.6, 0.4, 1.0];
const PLANE_RGBA8: [u8; 4] = [51, 153, 102, 255];

/// The ray of pixel `i` against the square `|x - c.x|, |z - c.z| <= half` at `y = c.y`:
/// `Some((t, inside margin))`, where the flag says the hit is at least `margin` inside.
fn plane_hit(cam: &Camera, i: usize, c: DVec3, half: f64, margin: f64) -> Option<(f64, bool)> {
    let (w, h) = SIZE;
    let (o, d) = cam.ray(i as u32 % w, i as u32 / w, w, h);
    if d.y == 0.0 {
        return None;
    }
    let t = (c.y - o.y) / d.y;
    if t <= 0.0 {
        return None;
    }
    let p = o + d * t - c;
    let m = p.x.abs().max(p.z.abs());
    if m > half + margin {
        None
    } else {
        Some((t, m < half - margin))
    }
}

#[test]
fn ground_plane_matches_its_analytic_intersection() {
    let c = DVec3::new(0.1, -0.5, -0.2);
    let half = 2.0;
    let scene = Scene {
        triangles: vec![TriangleObject::ground_plane(c, half as f32, PLANE_COLOR)],
        ..Default::default()
    };
    for (name, cam, normal_y) in [
        (
            "above",
            Camera::new(DVec3::new(0.5, 1.2, 3.0), DVec3::new(0.0, -0.4, 0.0)),
            1.0,
        ),
        (
            "below",
            Camera::new(DVec3::new(-0.4, -1.6, 2.5), DVec3::new(0.0, -0.3, 0.0)),
            -1.0,
        ),
    ] {
        let frame = render(TRIANGLES_ONLY, scene.clone(), &cam, SIZE);
        let g = GBuffer::read(&frame.renderer.pipeline, &frame.renderer.resources);
        g.assert_finite();
        g.write_pngs(&format!("triangles_plane_{name}"));
        let (_, _, forward) = cam.basis();
        let (mut inside, mut outside) = (0, 0);
        let (mut depth_err, mut pos_err) = (0.0f64, 0.0f64);
        for i in 0..g.albedo.len() {
            match plane_hit(&cam, i, c, half, 0.02) {
                None => {
                    outside += 1;
                    assert!(!g.covered(i), "{name} pixel {i} is off the plane");
                    assert_eq!(g.stencil[i], 0);
                    assert_eq!(g.depth[i], 0.0);
                    assert_eq!(g.normal[i], [0.0; 4]);
                }
                Some((t, true)) => {
                    inside += 1;
                    assert_eq!(g.stencil[i], 2, "{name} pixel {i}");
                    assert_eq!(g.albedo[i], PLANE_RGBA8, "{name} pixel {i}");
                    let n = g.normal[i];
                    assert!(
                        n[0].abs() < 1e-3 && (n[1] - normal_y).abs() < 1e-3 && n[2].abs() < 1e-3,
                        "{name} pixel {i}: normal {n:?}"
                    );
                    // The plane's own normal, towards the camera (derivatives of the
                    // position: a few f32 ulps off axis; f16 storage).
                    let geo = g.geometric[i];
                    assert!(
                        geo[0].abs() < 2e-3
                            && (geo[1] - normal_y).abs() < 1e-3
                            && geo[2].abs() < 2e-3,
                        "{name} pixel {i}: geometric normal {geo:?}"
                    );
                    let (_, d) = cam.ray(i as u32 % SIZE.0, i as u32 / SIZE.0, SIZE.0, SIZE.1);
                    let view_depth = t * d.dot(forward);
                    let p = g.position[i];
                    depth_err = depth_err.max((p[3] as f64 - view_depth).abs() / view_depth);
                    let want = d * t;
                    let got = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                    pos_err = pos_err.max((got - want).length() / t);
                    // Reversed Z: B / z - A with the camera's finite projection.
                    let (n_, f_) = (cam.near, cam.far);
                    let ndc = n_ * f_ / (f_ - n_) / view_depth - n_ / (f_ - n_);
                    assert!(
                        (g.depth[i] as f64 - ndc).abs() <= 1e-5 * ndc,
                        "{name} pixel {i}: depth {} want {ndc}",
                        g.depth[i]
                    );
                }
                Some((_, false)) => {} // within 0.02 of the edge: either
            }
        }
        eprintln!(
            "plane {name}: {inside} inside, {outside} outside, max rel. linear depth error \
             {depth_err:.2e}, position {pos_err:.2e}"
        );
        assert!(inside > 2000 && outside > 500, "{inside} {outside}");
        assert!(depth_err < 1e-5 && pos_err < 1e-5);
    }
}

/// Voxels and a plane that cuts through them: each pixel shows whichever is nearer.
/// With `end_to_end` the SSBVB comes from the GPU prepass and filter through the renderer,
/// else from the CPU reference.
fn check_depth_order(mode: BillboardMode, max_wrong: f64, end_to_end: bool) {
    let scene_base = single_object_scene(model_asset(BUNNY, LEVEL), LEVEL);
    let c = DVec3::new(0.0, -0.05, 0.0);
    let half = 1.4;
    let scene = Scene {
        triangles: vec![TriangleObject::ground_plane(c, half as f32, PLANE_COLOR)],
        ..scene_base
    };
    let o = BillboardOptions {
        mode,
        size_scale: 1.0,
        footprint: Footprint::Box,
        cull_cos: DEFAULT_CULL_COS,
    };
    for (name, cam) in [
        ("above", Camera::new(DVec3::new(0.6, 1.4, 2.6), DVec3::ZERO)),
        (
            "below",
            Camera::new(DVec3::new(-1.2, -1.3, 2.2), DVec3::ZERO),
        ),
    ] {
        let (g, r) = if end_to_end {
            let frame = render(
                &pipeline_src(mode, 1.0, "Rgba16Float"),
                scene.clone(),
                &cam,
                SIZE,
            );
            let g = GBuffer::read(&frame.renderer.pipeline, &frame.renderer.resources);
            g.assert_finite();
            (g, reference_of(&scene, &cam, SIZE))
        } else {
            draw(&scene, &cam, SIZE, Some(o), true)
        };
        g.write_pngs(&format!("depth_order_{mode:?}_{name}_{end_to_end}"));
        let lod = &scene.objects[0].asset.lods[LEVEL as usize];
        let (mut wrong, mut voxel_px, mut plane_px) = (0, 0, 0);
        for i in 0..g.albedo.len() {
            let voxel = r.hits[i].as_ref();
            let plane = plane_hit(&cam, i, c, half, 0.0).map(|(t, _)| t);
            let want = match (voxel, plane) {
                (Some(v), Some(t)) if v.t < t => 1,
                (Some(_), None) => 1,
                (_, Some(_)) => 2,
                (None, None) => 0,
            };
            match want {
                1 => voxel_px += 1,
                2 => plane_px += 1,
                _ => {}
            }
            let ok = g.stencil[i] == want
                && match want {
                    // Stencil 1 exactly on voxel pixels, with the voxel's colour in RayBox.
                    1 if mode == BillboardMode::RayBox => {
                        let v = lod.point_cloud.voxels[voxel.unwrap().voxel as usize];
                        g.albedo[i][..3] == v.color.to_le_bytes()[..3]
                    }
                    2 => g.albedo[i] == PLANE_RGBA8,
                    _ => true,
                };
            if !ok {
                wrong += 1;
            }
        }
        let frac = wrong as f64 / g.albedo.len() as f64;
        eprintln!(
            "{mode:?} {name} (end to end: {end_to_end}): {voxel_px} voxel px, {plane_px} plane px, {wrong} differ ({:.3}%)",
            frac * 100.0
        );
        assert!(voxel_px > 1000 && plane_px > 1000);
        assert!(frac <= max_wrong, "{mode:?} {name}: {wrong} pixels differ");
    }
}

#[test]
fn ray_box_billboards_are_depth_tested_against_triangles() {
    // Only ties along the intersection line (and f32 rounding) may differ.
    check_depth_order(BillboardMode::RayBox, 0.002, false);
    check_depth_order(BillboardMode::RayBox, 0.002, true);
}

#[test]
fn flat_billboards_are_depth_tested_against_triangles() {
    // Flat quads sit at the voxel centre's depth (up to ~0.87 cell behind the surface) and
    // overhang silhouettes slightly: near the plane's intersection line and at the outline
    // a few pixels differ (measured 0.21-0.23 % on lavapipe).
    check_depth_order(BillboardMode::Flat, 0.01, false);
    check_depth_order(BillboardMode::Flat, 0.01, true);
}

#[test]
fn degenerate_triangles_and_normals_stay_finite() {
    // Zero-length and NaN normals fall back to the geometric normal; a zero-area triangle
    // draws nothing; a mirrored transform keeps normals facing the camera.
    let mut zero = TriangleObject::ground_plane(DVec3::new(0.0, -0.5, 0.0), 1.0, PLANE_COLOR);
    zero.normals = vec![[0.0; 3], [f32::NAN; 3], [0.0; 3], [1e-30, 0.0, 0.0]];
    let degenerate = TriangleObject {
        positions: vec![
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.5],
            [1.0, 1.0, 1.0],
            [0.2, 0.0, 0.0],
        ],
        normals: vec![[0.0, 1.0, 0.0]; 4],
        indices: vec![0, 1, 2, 3, 3, 3],
        color: [1.0, 0.0, 0.0, 1.0],
        transform: glam::DAffine3::IDENTITY,
    };
    let mut mirrored = TriangleObject::ground_plane(DVec3::new(0.0, 0.5, 0.0), 0.3, PLANE_COLOR);
    mirrored.transform = glam::DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0))
        * glam::DAffine3::from_translation(DVec3::new(0.0, 0.5, 0.0));
    let scene = Scene {
        triangles: vec![zero, degenerate, mirrored],
        ..Default::default()
    };
    let cam = Camera::new(DVec3::new(0.3, 1.5, 2.0), DVec3::ZERO);
    let frame = render(TRIANGLES_ONLY, scene, &cam, SIZE);
    let g = GBuffer::read(&frame.renderer.pipeline, &frame.renderer.resources);
    g.assert_finite();
    g.write_pngs("triangles_degenerate");
    let mut drawn = 0;
    for i in 0..g.albedo.len() {
        if !g.covered(i) {
            continue;
        }
        drawn += 1;
        assert_eq!(g.stencil[i], 2);
        assert_eq!(
            g.albedo[i], PLANE_RGBA8,
            "pixel {i}: the degenerate triangles drew"
        );
        let n = g.normal[i];
        // Both planes face +Y; the camera is above them.
        assert!((n[1] - 1.0).abs() < 1e-3, "pixel {i}: normal {n:?}");
    }
    assert!(drawn > 1000, "{drawn}");
}

/// Tilted planes, each seen from the side its normal points to: every covered pixel's
/// geometric normal (octahedral-encoded in the G-buffer, decoded by the CPU twin) is the
/// plane's, in both halves of the encoding (normals with z > 0 and z < 0) and with every
/// component non-zero, which axis-aligned voxel faces never reach.
#[test]
fn tilted_planes_write_their_geometric_normal() {
    let targets = [
        DVec3::new(0.3, 0.5, 0.81),
        DVec3::new(0.3, 0.5, -0.81),
        DVec3::new(-0.6, 0.2, -0.77),
        DVec3::new(-0.45, -0.7, 0.55),
    ];
    for target in targets {
        let n = target.normalize();
        let mut plane = TriangleObject::ground_plane(DVec3::ZERO, 1.0, PLANE_COLOR);
        plane.transform = glam::DAffine3::from_quat(glam::DQuat::from_rotation_arc(DVec3::Y, n));
        let scene = Scene {
            triangles: vec![plane],
            ..Default::default()
        };
        // Off the normal a little, so the view is not exactly head-on.
        let side = n.cross(DVec3::X).normalize();
        let cam = Camera::new(n * 3.0 + side * 0.4, DVec3::ZERO);
        let frame = render(TRIANGLES_ONLY, scene, &cam, SIZE);
        let g = GBuffer::read(&frame.renderer.pipeline, &frame.renderer.resources);
        g.assert_finite();
        let mut covered = 0;
        let mut worst = 0.0f64;
        for i in 0..g.albedo.len() {
            if !g.covered(i) {
                continue;
            }
            covered += 1;
            let geo = g.geometric[i];
            let got = DVec3::new(geo[0] as f64, geo[1] as f64, geo[2] as f64);
            worst = worst.max((got - n).length());
        }
        eprintln!("plane facing {n:?}: {covered} pixels, worst geometric normal error {worst:.2e}");
        assert!(
            covered > SIZE.0 as usize * SIZE.1 as usize / 8,
            "{covered} pixels"
        );
        // Measured: position derivatives and f16 storage, 4e-4 to 1.3e-3 (the ground plane's
        // bound is 2e-3 per component).
        assert!(
            worst < 4e-3,
            "plane facing {n:?}: geometric normal off by {worst}"
        );
    }
}
