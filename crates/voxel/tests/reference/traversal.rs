//! The traversal's own mechanics, found by mutation testing: several planes of one axis
//! crossed at one time, and how much work the hierarchical skip saves.

use glam::DVec3;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{Traversal, trace_object_ray, trace_object_ray_counted};

use crate::{b, lod};

/// An origin 2^53 + 2 away along −x: `b − o` rounds the level-3 boundaries to three values
/// (plane 0; planes 1–7; plane 8), so planes 1–7 are crossed at one time and cells 1–7 are
/// touched together. The tie rule then picks the occupied cell furthest along the ray.
#[test]
fn a_far_origin_crosses_several_planes_of_one_axis_at_once() {
    let level = 3;
    let far = 2f64.powi(53) + 2.0;
    let t = |k: i64| b(level, k) + far;
    assert!(
        t(0) < t(1) && t(1) == t(7) && t(7) < t(8),
        "the rounding assumed"
    );
    let c = b(level, 4) + 0.5 * cell_size(level);
    let l = lod(level, &[[3, 4, 4], [6, 4, 4]]);
    let mirrored = lod(level, &[[1, 4, 4], [4, 4, 4]]);
    for traversal in [Traversal::Hierarchical, Traversal::CellByCell] {
        let h = trace_object_ray(&l.lookup, DVec3::new(-far, c, c), DVec3::X, traversal)
            .expect("a hit");
        assert_eq!(
            (h.cell, h.t, h.face_normal, h.inside),
            ([6, 4, 4], t(1), DVec3::NEG_X, false),
            "{traversal:?}"
        );
        // The same from +x moving −x: cells 6..1 are touched together; cell 1 is furthest.
        let h = trace_object_ray(
            &mirrored.lookup,
            DVec3::new(far, c, c),
            DVec3::NEG_X,
            traversal,
        )
        .expect("a hit");
        assert_eq!(
            (h.cell, h.t, h.face_normal),
            ([1, 4, 4], t(1), DVec3::X),
            "{traversal:?}"
        );
    }
}

/// Level 8 (256 cells a side), one voxel near the far end of a row: the plain DDA visits
/// every cell on the way; the hierarchical traversal jumps over the empty 64-, 16- and
/// 4-cell regions. Both report the same hit. The counts are exact for this ray (measured;
/// a change of the skipping that costs events fails here, one that saves them is a
/// reason to update the numbers).
#[test]
fn the_hierarchical_traversal_skips_empty_regions_and_the_plain_one_visits_every_cell() {
    let level = 8;
    let l = lod(level, &[[250, 128, 128]]);
    let c = b(level, 128) + 0.5 * cell_size(level);
    let o = DVec3::new(-2.0, c, c);
    let (plain, plain_count) =
        trace_object_ray_counted(&l.lookup, None, o, DVec3::X, Traversal::CellByCell);
    let (fast, fast_count) =
        trace_object_ray_counted(&l.lookup, None, o, DVec3::X, Traversal::Hierarchical);
    assert_eq!(plain, fast);
    assert_eq!(fast.map(|h| h.cell), Some([250, 128, 128]));
    eprintln!("plain {plain_count:?}, hierarchical {fast_count:?}");
    assert_eq!(plain_count.skips, 0);
    assert_eq!(
        plain_count.events, 250,
        "one event per plane crossed before the voxel"
    );
    assert_eq!(fast_count.skips, 8);
    assert!(fast_count.events <= 10, "{fast_count:?}");
    // A ray that misses everything: the plain traversal crosses every plane, the
    // hierarchical one a region at a time.
    let miss = DVec3::new(-2.0, c + cell_size(level), c);
    let (h, plain_count) =
        trace_object_ray_counted(&l.lookup, None, miss, DVec3::X, Traversal::CellByCell);
    assert_eq!(h, None);
    let (h, fast_count) =
        trace_object_ray_counted(&l.lookup, None, miss, DVec3::X, Traversal::Hierarchical);
    assert_eq!(h, None);
    eprintln!("miss: plain {plain_count:?}, hierarchical {fast_count:?}");
    assert_eq!(plain_count.events, 256);
    // The row shares its regions with the voxel's: 3 + 3 + 2 skips up to the voxel's 4³
    // brick, its 4 cells one by one, then the last brick.
    assert_eq!(fast_count.skips, 9);
    assert!(fast_count.events <= 13, "{fast_count:?}");
}

/// Cells looked up per ray: the cells a crossing event newly touches, never again the ones
/// the previous event covered, and none outside the grid, also with the ray running in a
/// face or along an edge of the grid (static axes at ±1). Exact counts (events, skips,
/// lookups), measured: cell by cell, then hierarchical.
#[test]
fn each_event_looks_up_only_the_cells_it_newly_touches() {
    let level = 3;
    let s = cell_size(level);
    let l = lod(level, &[[7, 7, 7]]);
    let c = b(level, 4) + 0.5 * s;
    for (name, o, d, want) in [
        (
            "row",
            DVec3::new(-2.0, c, c),
            DVec3::X,
            [(8, 0, 8), (5, 1, 5)],
        ),
        (
            "+y face",
            DVec3::new(-2.0, 1.0, c),
            DVec3::X,
            [(8, 0, 8), (5, 1, 5)],
        ),
        (
            "-y face",
            DVec3::new(-2.0, -1.0, c),
            DVec3::X,
            [(8, 0, 8), (2, 2, 2)],
        ),
        (
            "+y+z edge",
            DVec3::new(-2.0, 1.0, 1.0),
            DVec3::X,
            [(7, 0, 8), (4, 1, 5)],
        ),
        (
            "leaving through the +x face",
            DVec3::new(1.0, c, c),
            DVec3::X,
            [(0, 0, 1), (0, 0, 1)],
        ),
        (
            "diagonal",
            DVec3::new(-2.0, -1.9, -1.8),
            DVec3::ONE,
            [(21, 0, 22), (12, 3, 13)],
        ),
    ] {
        for (traversal, want) in [Traversal::CellByCell, Traversal::Hierarchical]
            .into_iter()
            .zip(want)
        {
            let (_, n) = trace_object_ray_counted(&l.lookup, None, o, d, traversal);
            assert_eq!(
                (n.events, n.skips, n.lookups),
                want,
                "{name}, {traversal:?}"
            );
        }
    }
}
