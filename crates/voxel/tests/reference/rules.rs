//! The exact rules: axis-parallel, grazing, edge and corner rays, and rays starting inside.

use glam::DVec3;
use ssbvb_voxel::asset::LodLevel;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{Traversal, trace_object_ray};

use crate::{b, lod};

#[test]
fn axis_parallel_grazing_edge_and_corner_rays_follow_the_documented_rules() {
    let level = 3;
    let s = cell_size(level);
    let centre = |k: i64| b(level, k) + 0.5 * s;
    let one = lod(level, &[[3, 3, 3]]);
    let trace = |l: &LodLevel, o: DVec3, d: DVec3| {
        let h = trace_object_ray(&l.lookup, o, d, Traversal::Hierarchical);
        assert_eq!(h, trace_object_ray(&l.lookup, o, d, Traversal::CellByCell));
        h
    };

    // Straight through the middle, along +x: enters the -x face.
    let h = trace(&one, DVec3::new(-3.0, centre(3), centre(3)), DVec3::X).unwrap();
    assert_eq!(
        (h.cell, h.face_axis, h.face_normal, h.inside),
        ([3, 3, 3], 0, DVec3::NEG_X, false)
    );
    assert_eq!(h.t, b(level, 3) + 3.0);
    // Along -y from above: enters the +y face.
    let h = trace(&one, DVec3::new(centre(3), 5.0, centre(3)), DVec3::NEG_Y).unwrap();
    assert_eq!((h.face_normal, h.t), (DVec3::Y, 5.0 - b(level, 4)));

    // Grazing: the ray runs inside the voxel's top face plane y = b(4): closed cells hit.
    let h = trace(&one, DVec3::new(-3.0, b(level, 4), centre(3)), DVec3::X).unwrap();
    assert_eq!((h.cell, h.face_normal), ([3, 3, 3], DVec3::NEG_X));
    // Along an edge (y and z both on the voxel's upper planes).
    let h = trace(&one, DVec3::new(-3.0, b(level, 4), b(level, 4)), DVec3::X).unwrap();
    assert_eq!(h.cell, [3, 3, 3]);
    // Just off the face: a miss.
    assert!(
        trace(
            &one,
            DVec3::new(-3.0, b(level, 4) + 1e-12, centre(3)),
            DVec3::X
        )
        .is_none()
    );

    // Two voxels stacked in y; a ray in their shared plane reports the lower one...
    let two = lod(level, &[[3, 4, 3], [3, 3, 3]]);
    let h = trace(&two, DVec3::new(-3.0, b(level, 4), centre(3)), DVec3::X).unwrap();
    assert_eq!(
        (h.cell, h.voxel),
        ([3, 3, 3], crate::id_of(&two, [3, 3, 3]))
    );
    // ...and the upper one when the lower one is absent.
    let upper = lod(level, &[[3, 4, 3]]);
    let h = trace(&upper, DVec3::new(-3.0, b(level, 4), centre(3)), DVec3::X).unwrap();
    assert_eq!(h.cell, [3, 4, 3]);

    // Diagonal through the corner shared by cells (3,3), (4,3), (3,4), (4,4) in xy.
    let o = DVec3::new(b(level, 4) - 1.5 * s, b(level, 4) - 1.5 * s, centre(3));
    let d = DVec3::new(1.0, 1.0, 0.0);
    // Entering (4,4) through its corner: that cell wins, x face on the exact tie.
    let h = trace(&lod(level, &[[4, 3, 3], [3, 4, 3], [4, 4, 3]]), o, d).unwrap();
    assert_eq!((h.cell, h.face_axis, h.t), ([4, 4, 3], 0, 1.5 * s));
    // Without (4,4): both neighbours are touched at the same time; rank sums tie, and the
    // one differing from (4,4) on x wins: (3,4), entered through its -y face.
    let h = trace(&lod(level, &[[4, 3, 3], [3, 4, 3]]), o, d).unwrap();
    assert_eq!(
        (h.cell, h.face_normal, h.t),
        ([3, 4, 3], DVec3::NEG_Y, 1.5 * s)
    );
    // A diagonal gap between voxels that share only an edge does not leak.
    let h = trace(&lod(level, &[[4, 3, 3]]), o, d).unwrap();
    assert_eq!((h.cell, h.face_normal), ([4, 3, 3], DVec3::NEG_X));

    // Camera inside the voxel: t = 0, normal from the dominant axis, against the ray.
    let inside = DVec3::splat(centre(3));
    let h = trace(&one, inside, DVec3::new(0.3, -0.9, 0.1)).unwrap();
    assert_eq!((h.t, h.inside, h.face_normal), (0.0, true, DVec3::Y));
    // Camera exactly on the voxel's face, looking in: t = 0 through that face.
    let h = trace(
        &one,
        DVec3::new(b(level, 3), centre(3), centre(3)),
        DVec3::X,
    )
    .unwrap();
    assert_eq!((h.t, h.inside, h.face_normal), (0.0, false, DVec3::NEG_X));
    // Looking out of the face: still touching the closed cell at t = 0.
    let h = trace(
        &one,
        DVec3::new(b(level, 3), centre(3), centre(3)),
        DVec3::NEG_X,
    )
    .unwrap();
    assert_eq!((h.t, h.inside), (0.0, true));

    // Rays outside the box, parallel to it, on its faces, zero, NaN: no panics, no NaN.
    let corner = lod(level, &[[0, 0, 0], [7, 7, 7]]);
    assert!(trace(&corner, DVec3::new(-3.0, 1.0 + 1e-15, 0.0), DVec3::X).is_none());
    let h = trace(&corner, DVec3::new(-3.0, -1.0, -1.0), DVec3::X).unwrap();
    assert_eq!((h.cell, h.t), ([0, 0, 0], 2.0));
    let h = trace(&corner, DVec3::new(3.0, 1.0, 1.0), DVec3::NEG_X).unwrap();
    assert_eq!((h.cell, h.t), ([7, 7, 7], 2.0));
    assert!(trace(&corner, DVec3::ZERO, DVec3::ZERO).is_none());
    assert!(trace(&corner, DVec3::NAN, DVec3::X).is_none());
    assert!(trace(&corner, DVec3::ZERO, DVec3::new(f64::INFINITY, 0.0, 0.0)).is_none());
    assert!(
        trace(
            &corner,
            DVec3::new(-3.0, -1.0, -1.0),
            DVec3::new(1e-310, 1.0, 0.0)
        )
        .is_none()
    );
    // A subnormal component inside the box acts as a static axis (its crossings overflow
    // to infinity), never as NaN.
    let h = trace(
        &corner,
        DVec3::new(-0.9, -3.0, -0.9),
        DVec3::new(1e-310, 1.0, 0.0),
    )
    .unwrap();
    assert_eq!((h.cell, h.t, h.face_normal), ([0, 0, 0], 2.0, DVec3::NEG_Y));
}

/// From an origin inside the grid, the first event is the origin itself: only the cell
/// holding it is touched, not the next ones (a voxel one or two cells ahead is hit where
/// the ray reaches it, never at t = 0). Found by mutation testing (`docs/reliability.md`).
#[test]
fn an_origin_inside_the_grid_touches_only_its_own_cell_at_first() {
    let s = cell_size(3);
    for ahead in [1i64, 2] {
        let l = lod(3, &[[(3 + ahead) as u32, 4, 4]]);
        // Centre of cell (3, 4, 4), moving +x.
        let o = DVec3::new(b(3, 3) + 0.5 * s, b(3, 4) + 0.5 * s, b(3, 4) + 0.5 * s);
        for traversal in [Traversal::Hierarchical, Traversal::CellByCell] {
            let h = trace_object_ray(&l.lookup, o, DVec3::X, traversal).expect("a hit ahead");
            assert_eq!(h.cell, [(3 + ahead) as u32, 4, 4]);
            let t = b(3, 3 + ahead) - o.x;
            assert!((h.t - t).abs() < 1e-12 && !h.inside, "ahead {ahead}: {h:?}");
            // Mirrored: from cell (3 + 2·ahead, 4, 4) moving −x.
            let o2 = DVec3::new(b(3, 3 + 2 * ahead) + 0.5 * s, o.y, o.z);
            let h2 = trace_object_ray(&l.lookup, o2, DVec3::NEG_X, traversal).unwrap();
            assert!((h2.t - (o2.x - b(3, 4 + ahead))).abs() < 1e-12, "{h2:?}");
        }
    }
}

/// Entering a voxel exactly through its edge with equal speeds on the two axes: the face
/// reported is the lower axis's (the documented tie rule of the face normal).
#[test]
fn an_edge_entry_at_equal_speeds_reports_the_lower_axis_face() {
    let l = lod(3, &[[4, 4, 4]]);
    let s = cell_size(3);
    // Through the edge x = b(4), y = b(4) at z inside the cell, from (−,−) at equal speeds.
    let z = b(3, 4) + 0.5 * s;
    let o = DVec3::new(b(3, 4) - 0.75 * s, b(3, 4) - 0.75 * s, z);
    let h = trace_object_ray(
        &l.lookup,
        o,
        DVec3::new(1.0, 1.0, 0.0),
        Traversal::Hierarchical,
    )
    .unwrap();
    assert_eq!((h.cell, h.face_axis), ([4, 4, 4], 0), "{h:?}");
    assert_eq!(h.face_normal, DVec3::NEG_X);
    // Mirrored on both axes: still the x face (+X, against the ray).
    let o = DVec3::new(b(3, 5) + 0.75 * s, b(3, 5) + 0.75 * s, z);
    let h = trace_object_ray(
        &l.lookup,
        o,
        DVec3::new(-1.0, -1.0, 0.0),
        Traversal::CellByCell,
    )
    .unwrap();
    assert_eq!(
        (h.cell, h.face_axis, h.face_normal),
        ([4, 4, 4], 0, DVec3::X),
        "{h:?}"
    );
}

/// Several occupied cells touched first at one corner: the one differing from the entered
/// cell on the fewest axes wins before the z, y, x order (the rank sum comes first).
#[test]
fn a_corner_tie_prefers_the_fewest_differing_axes_before_z() {
    // The ray passes exactly through the grid point (4, 4, 4) along (1, 1, 1); the entered
    // cell (4, 4, 4) is empty. A = (4, 4, 3) differs on z only (rank sum 1, z rank 1);
    // B = (3, 3, 4) differs on x and y (rank sum 2, z rank 0).
    let l = lod(3, &[[4, 4, 3], [3, 3, 4]]);
    let s = cell_size(3);
    let o = DVec3::splat(b(3, 4) - 0.375 * s);
    for traversal in [Traversal::Hierarchical, Traversal::CellByCell] {
        let h = trace_object_ray(&l.lookup, o, DVec3::ONE, traversal).unwrap();
        assert_eq!(h.cell, [4, 4, 3], "{h:?}");
    }
}

/// A ray parallel to an axis whose origin lies a rounding step below, on, or above a cell
/// boundary of that axis touches the right cells: the cell estimate `(o + 1) / s` can round
/// up across the boundary, and the exact comparisons that follow settle it (found by
/// mutation testing: with boundaries hit exactly the settling never ran).
#[test]
fn a_static_axis_origin_next_to_a_boundary_touches_the_right_cells() {
    let level = 3;
    for k in 1..8i64 {
        // A voxel in the row below the boundary y = b(k), ahead along +x.
        let l = lod(level, &[[5, (k - 1) as u32, 4]]);
        let z = b(level, 4) + 0.5 * cell_size(level);
        let on = b(level, k);
        let (below, above) = (on.next_down(), on.next_up());
        assert!(below < on && on < above, "k {k}");
        for traversal in [Traversal::Hierarchical, Traversal::CellByCell] {
            let hit =
                |y: f64| trace_object_ray(&l.lookup, DVec3::new(-1.5, y, z), DVec3::X, traversal);
            assert_eq!(
                hit(below).map(|h| h.cell),
                Some([5, (k - 1) as u32, 4]),
                "k {k} below"
            );
            assert_eq!(
                hit(on).map(|h| h.cell),
                Some([5, (k - 1) as u32, 4]),
                "k {k} on"
            );
            assert_eq!(hit(above), None, "k {k} above");
        }
        // And the voxel above the boundary: seen from on and above, not from below.
        let l = lod(level, &[[5, k as u32, 4]]);
        let hit = |y: f64| {
            trace_object_ray(
                &l.lookup,
                DVec3::new(-1.5, y, z),
                DVec3::X,
                Traversal::Hierarchical,
            )
        };
        assert_eq!(hit(below), None, "k {k} below, voxel above");
        assert!(
            hit(on).is_some() && hit(above).is_some(),
            "k {k} voxel above"
        );
    }
}
