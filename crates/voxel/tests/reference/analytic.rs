//! Analytic scenes: single voxels, transformed voxels, filled balls and planes of voxels
//! against their exact projections and depths.

use glam::{DAffine3, DQuat, DVec3};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{Instance, trace_pixel};

use crate::{b, ball_cells, cell_box, check_ball, check_projected_box, lod, render_one};

#[test]
fn single_voxel_covers_exactly_its_projection_from_every_side() {
    let level = 3;
    let cell = [5, 2, 3];
    let l = lod(level, &[cell]);
    let (lo, hi) = cell_box(level, cell);
    let c = (lo + hi) * 0.5;
    let dirs = [
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(-1.0, 0.7, 0.4),
        DVec3::new(0.3, -1.0, -0.8),
    ];
    for d in dirs {
        let cam = Camera {
            fov_y_deg: 12.0,
            up: if d.x == 0.0 && d.z == 0.0 {
                DVec3::Z
            } else {
                DVec3::Y
            },
            ..Camera::new(
                c + d.normalize() * 3.0 + DVec3::new(0.013, 0.007, -0.011),
                c,
            )
        };
        let img = render_one(&l, DAffine3::IDENTITY, &cam, 48, 40);
        let covered = check_projected_box(&img, &cam, lo, hi);
        assert!(covered > 50, "{d:?}: only {covered} pixels");
        assert_eq!(
            img.coverage(),
            covered,
            "{d:?}: hits outside the analytic margin band"
        );
        // Colour: alpha 1 on hits, transparent elsewhere.
        for (hit, col) in img.hits.iter().zip(&img.colors) {
            assert_eq!(col[3], if hit.is_some() { 1.0 } else { 0.0 });
            if hit.is_none() {
                assert_eq!(*col, [0.0; 4]);
            }
        }
    }
}

#[test]
fn rotated_scaled_translated_voxel_matches_the_analytic_box_and_depth() {
    // Only axis-permuting rotations keep the world box axis-aligned for the analytic check.
    let level = 2;
    let cell = [1, 3, 0];
    let l = lod(level, &[cell]);
    let xf = DAffine3::from_scale_rotation_translation(
        DVec3::splat(2.5),
        DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
        DVec3::new(10.0, -4.0, 7.0),
    );
    let (lo, hi) = cell_box(level, cell);
    let (a, bb) = (xf.transform_point3(lo), xf.transform_point3(hi));
    let (wlo, whi) = (a.min(bb), a.max(bb));
    let c = (wlo + whi) * 0.5;
    let cam = Camera {
        fov_y_deg: 20.0,
        ..Camera::new(c + DVec3::new(3.0, 2.0, 4.0), c)
    };
    let img = render_one(&l, xf, &cam, 64, 64);
    assert!(check_projected_box(&img, &cam, wlo, whi) > 100);
    // view_depth is the distance along the forward axis; the hit position projects back
    // onto its pixel's centre with the camera's view-projection, and its reversed-Z depth
    // decodes to view_depth.
    let (_, _, f) = cam.basis();
    let vp = cam.view_projection(1.0);
    for (i, hit) in img.hits.iter().enumerate() {
        let Some(hit) = hit else { continue };
        assert!(((hit.position - cam.position).dot(f) - hit.view_depth).abs() < 1e-9);
        assert!(((hit.position - cam.position).length() - hit.t).abs() < 1e-9);
        let clip = vp * hit.position.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let (px, py) = ((i % 64) as f64 + 0.5, (i / 64) as f64 + 0.5);
        assert!(((ndc.x + 1.0) * 32.0 - px).abs() < 1e-6, "pixel {i}");
        assert!(((1.0 - ndc.y) * 32.0 - py).abs() < 1e-6, "pixel {i}");
        assert!((cam.linear_depth(ndc.z) - hit.view_depth).abs() < 1e-6 * hit.view_depth);
    }
}

#[test]
fn filled_ball_depth_is_within_a_voxel_of_the_sphere() {
    let level = 5;
    let r = 0.7;
    let l = lod(level, &ball_cells(level, r));
    let hd = cell_size(level) * 3f64.sqrt() * 0.5;
    let cam = Camera {
        fov_y_deg: 40.0,
        ..Camera::new(DVec3::new(0.3, 0.5, 3.0), DVec3::ZERO)
    };
    let img = render_one(&l, DAffine3::IDENTITY, &cam, 96, 96);
    assert!(check_ball(&img, &cam, DVec3::ZERO, r, hd) > 2000);

    // The same ball rotated, scaled and moved far away from the origin: same checks in
    // world units.
    let xf = DAffine3::from_scale_rotation_translation(
        DVec3::splat(3.0),
        DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 0.7),
        DVec3::new(1e7, -1e7, 1e7),
    );
    let centre = xf.translation;
    let cam = Camera {
        fov_y_deg: 40.0,
        ..Camera::new(centre + DVec3::new(2.0, 3.0, 8.0), centre)
    };
    let img = render_one(&l, xf, &cam, 96, 96);
    assert!(check_ball(&img, &cam, centre, 3.0 * r, 3.0 * hd) > 2000);
}

#[test]
fn object_far_from_the_world_origin_renders_like_at_the_origin() {
    let level = 6;
    let l = lod(level, &ball_cells(level, 0.8));
    let offset = DVec3::new(1e7, 1e7, -1e7);
    let eye = DVec3::new(0.4, 0.9, 2.5);
    let cam0 = Camera::new(eye, DVec3::ZERO);
    let cam1 = Camera::new(eye + offset, offset);
    let a = render_one(&l, DAffine3::IDENTITY, &cam0, 80, 80);
    let bimg = render_one(&l, DAffine3::from_translation(offset), &cam1, 80, 80);
    let mut same = 0;
    for (ha, hb) in a.hits.iter().zip(&bimg.hits) {
        match (ha, hb) {
            (Some(ha), Some(hb)) => {
                assert!((ha.t - hb.t).abs() < 1e-6, "{} vs {}", ha.t, hb.t);
                same += usize::from(ha.voxel == hb.voxel);
            }
            (None, None) => same += 1,
            _ => {}
        }
    }
    // World coordinates of 1e7 carry ~2e-9 of rounding: only pixels whose ray passes
    // within that of a voxel edge may differ.
    assert!(
        same >= a.hits.len() - 3,
        "{same} of {} pixels agree",
        a.hits.len()
    );
}

#[test]
fn plane_of_voxels_head_on_and_at_grazing_angles() {
    let level = 6;
    let n = 1u32 << level;
    let k = 40;
    let cells: Vec<[u32; 3]> = (0..n * n).map(|i| [i % n, i / n, k]).collect();
    let l = lod(level, &cells);
    let (lo, hi) = (
        DVec3::new(-1.0, -1.0, b(level, k as i64)),
        DVec3::new(1.0, 1.0, b(level, k as i64 + 1)),
    );
    // Head on from above and below: every pixel inside the slab's projection hits, at the
    // analytic depth, with the face's normal.
    for (eye, up) in [
        (DVec3::new(0.0, 0.0, 3.0), DVec3::Y),
        (DVec3::new(0.2, -0.1, -3.0), DVec3::X),
    ] {
        let cam = Camera {
            fov_y_deg: 50.0,
            up,
            ..Camera::new(eye, DVec3::ZERO)
        };
        let img = render_one(&l, DAffine3::IDENTITY, &cam, 64, 64);
        assert!(check_projected_box(&img, &cam, lo, hi) > 1000);
    }
    // Grazing: the eye just above the top face, looking along it. The union of the layer
    // is exactly the slab box, so the slab test is the analytic answer.
    for (dz, fov) in [(0.02, 30.0), (1e-4, 5.0), (0.0, 5.0), (-1e-5, 5.0)] {
        let eye = DVec3::new(-3.0, 0.05, hi.z + dz);
        let cam = Camera {
            fov_y_deg: fov,
            ..Camera::new(eye, DVec3::new(0.0, 0.0, hi.z))
        };
        let img = render_one(&l, DAffine3::IDENTITY, &cam, 64, 64);
        let covered = check_projected_box(&img, &cam, lo, hi);
        assert!(covered > 100, "dz {dz}: {covered}");
    }
    // Rays exactly in the top face plane (grazing along it): closed cells are hit, through
    // the slab's -x side, at the analytic distance.
    let eye = DVec3::new(-3.0, 0.123, hi.z);
    let cam = Camera {
        fov_y_deg: 10.0,
        ..Camera::new(eye, DVec3::new(0.0, 0.123, hi.z))
    };
    let hit = trace_pixel(
        &[Instance {
            lod: &l,
            object_to_world: DAffine3::IDENTITY,
            faces: None,
        }],
        &cam,
        0,
        0,
        1,
        1,
    )
    .unwrap();
    assert_eq!((hit.t, hit.face_normal), (2.0, [-1.0, 0.0, 0.0]));
}
