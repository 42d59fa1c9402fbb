//! Extreme cases: camera distances from 1e-3 to 1e7 object sizes, levels 0, 1 and 12.

use glam::{DAffine3, DVec3};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;

use crate::{ball_cells, cell_box, check_ball, check_projected_box, lod, render_one};

#[test]
fn extreme_camera_distances() {
    let level = 7;
    let r = 0.75;
    let l = lod(level, &ball_cells(level, r));
    let hd = cell_size(level) * 3f64.sqrt() * 0.5;
    // 1e7 object sizes away, with a field of view that frames the ball.
    let dist = 2e7;
    let fov = (2.0 * (1.0f64 / dist).atan()).to_degrees();
    let cam = Camera {
        fov_y_deg: fov,
        ..Camera::new(DVec3::new(0.0, 0.6, 0.8) * dist, DVec3::ZERO)
    };
    let img = render_one(&l, DAffine3::IDENTITY, &cam, 64, 64);
    assert!(check_ball(&img, &cam, DVec3::ZERO, r, hd) > 1000);
    // 1e-3 object sizes from the surface, inside the object box.
    let eye = DVec3::new(0.0, 0.0, r + hd + 2e-3);
    let cam = Camera {
        fov_y_deg: 90.0,
        ..Camera::new(eye, DVec3::ZERO)
    };
    let img = render_one(&l, DAffine3::IDENTITY, &cam, 48, 48);
    let covered = check_ball(&img, &cam, DVec3::ZERO, r, hd);
    assert!(covered > 1500, "{covered}");
    // At the centre of the filled ball: inside a voxel for every pixel.
    let cam = Camera::new(DVec3::splat(0.3 * cell_size(level)), DVec3::X);
    let img = render_one(&l, DAffine3::IDENTITY, &cam, 32, 32);
    assert!(
        img.hits
            .iter()
            .all(|h| h.is_some_and(|h| h.t == 0.0 && h.inside))
    );
}

#[test]
fn levels_zero_one_and_twelve() {
    // Level 0: the single cell is the whole object box.
    let l0 = lod(0, &[[0, 0, 0]]);
    let cam = Camera {
        fov_y_deg: 40.0,
        ..Camera::new(DVec3::new(2.5, 1.9, 3.1), DVec3::ZERO)
    };
    let img = render_one(&l0, DAffine3::IDENTITY, &cam, 64, 48);
    assert!(check_projected_box(&img, &cam, DVec3::NEG_ONE, DVec3::ONE) > 500);

    // Level 1: two opposite octants.
    let l1 = lod(1, &[[0, 0, 0], [1, 1, 1]]);
    for (cell, eye) in [
        ([1, 1, 1], DVec3::new(3.0, 2.0, 2.5)),
        ([0, 0, 0], DVec3::new(-3.0, -2.0, -2.5)),
    ] {
        let (lo, hi) = cell_box(1, cell);
        let cam = Camera {
            fov_y_deg: 40.0,
            ..Camera::new(eye, DVec3::ZERO)
        };
        let img = render_one(&l1, DAffine3::IDENTITY, &cam, 64, 64);
        // The other octant hides behind this one: every hit is on this box.
        assert!(check_projected_box(&img, &cam, lo, hi) > 500);
    }

    // Level 12: a handful of voxels, one framed closely, in a 4096³ grid.
    let cells = [
        [2048, 2048, 2048],
        [0, 0, 0],
        [4095, 4095, 4095],
        [1000, 3000, 17],
        [2049, 2048, 2048],
    ];
    let l12 = lod(12, &cells);
    let alone = lod(12, &cells[..1]);
    let (lo, hi) = cell_box(12, cells[0]);
    let c = (lo + hi) * 0.5;
    for eye in [
        DVec3::new(0.4, 0.3, 1.0),
        DVec3::new(-0.001, 0.0015, -0.002),
        DVec3::new(0.0, 0.0, 1.0),
    ] {
        let cam = Camera {
            fov_y_deg: 2.0 * (1.5 * cell_size(12) / eye.length()).atan().to_degrees(),
            ..Camera::new(c + eye, c)
        };
        let img = render_one(&l12, DAffine3::IDENTITY, &cam, 40, 40);
        // Its neighbour (2049, ...) may show up beside it: check only this voxel's pixels
        // plus the neighbour's analytic footprint.
        let id = crate::id_of(&l12, cells[0]);
        let covered = img.hits.iter().flatten().filter(|h| h.voxel == id).count();
        assert!(covered > 50, "{eye:?}: {covered}");
        let img = render_one(&alone, DAffine3::IDENTITY, &cam, 40, 40);
        assert!(check_projected_box(&img, &cam, lo, hi) > 50);
    }
}
