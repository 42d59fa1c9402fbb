//! The voxelizer's geometry piece by piece, against values worked out by hand (from the
//! mutation run: the whole-mesh oracles compare cells, which the exact separating axis
//! test decides however the clipping, the candidate ranges or the walk axis go wrong).

use glam::DVec3;

use super::*;
use crate::voxelize::test_support::unit_randoms;

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).abs().max_element() < 1e-12
}

/// The triangle (0,0), (2,0), (0,2) in the plane z = `z`.
fn right_triangle(z: f64) -> [DVec3; 3] {
    [
        DVec3::new(0.0, 0.0, z),
        DVec3::new(2.0, 0.0, z),
        DVec3::new(0.0, 2.0, z),
    ]
}

#[test]
fn candidate_ranges_are_the_cells_whose_closed_box_touches_a_coordinate_widened_by_eps() {
    // Cell i covers [i, i + 1]: a boundary belongs to both cells, EPS widens both ways.
    assert_eq!((cell_lo(3.0), cell_hi(3.0)), (2, 3));
    assert_eq!((cell_lo(3.5), cell_hi(3.5)), (3, 3));
    assert_eq!((cell_lo(3.0 + 0.5 * EPS), cell_hi(3.0 - 0.5 * EPS)), (2, 3));
    assert_eq!((cell_lo(3.0 + 2.0 * EPS), cell_hi(3.0 - 2.0 * EPS)), (3, 2));
    assert_eq!((cell_lo(-0.25), cell_hi(-0.25)), (-1, -1));
}

#[test]
fn the_walk_axis_is_the_dominant_normal_axis_or_the_longest_extent() {
    let t = right_triangle(1.0);
    assert_eq!(depth_axis(&t), 2);
    let yz = t.map(|p| DVec3::new(p.z, p.x, p.y));
    assert_eq!(depth_axis(&yz), 0);
    let zx = t.map(|p| DVec3::new(p.y, p.z, p.x));
    assert_eq!(depth_axis(&zx), 1);
    // Tilted: normal (1, 2, 3)-ish components decide; ties go to the lower axis.
    let n = |a: DVec3, b: DVec3, c: DVec3| depth_axis(&[a, b, c]);
    let o = DVec3::ZERO;
    // Normal ∝ (1, 1, 0) and (0, 1, 1) and (1, 1, 1): ties.
    assert_eq!(n(o, DVec3::Z, DVec3::new(1.0, -1.0, 0.0)), 0);
    assert_eq!(n(o, DVec3::X, DVec3::new(0.0, 1.0, -1.0)), 1);
    assert_eq!(n(DVec3::X, DVec3::Y, DVec3::Z), 0);
    // Normal (0, 2, 3): z; (0, 3, 2): y.
    assert_eq!(n(o, DVec3::X, DVec3::new(0.0, -3.0, 2.0)), 2);
    assert_eq!(n(o, DVec3::X, DVec3::new(0.0, -2.0, 3.0)), 1);
    // Degenerate: a segment runs along its longest extent (here y, then z).
    let seg = [
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.5, 4.0, 2.0),
        DVec3::new(2.0, 7.0, 3.0),
    ];
    assert_eq!(depth_axis(&seg), 1);
    let seg = seg.map(|p| DVec3::new(p.x, p.z, p.y));
    assert_eq!(depth_axis(&seg), 2);
    let seg = seg.map(|p| DVec3::new(p.z, p.x, p.y));
    assert_eq!(depth_axis(&seg), 0);
    // Away from the origin the extent is not the sum nor the ratio of the corners:
    // extents (1, 3, 1) with corner sums largest in x, (2, 4, 0.5) with ratios largest
    // in x.
    let mid = |a: DVec3, b: DVec3| [a, b, (a + b) / 2.0];
    let seg = mid(DVec3::new(10.0, 1.0, 1.0), DVec3::new(11.0, 4.0, 2.0));
    assert_eq!(depth_axis(&seg), 1);
    let seg = mid(DVec3::new(1.0, 10.0, 1.0), DVec3::new(3.0, 14.0, 1.5));
    assert_eq!(depth_axis(&seg), 1);
}

#[test]
fn clipping_keeps_the_closed_part_with_exact_corners() {
    let t = Poly::triangle(&right_triangle(0.5));
    assert!(close(t.mean(), DVec3::new(2.0 / 3.0, 2.0 / 3.0, 0.5)));
    assert!((t.area() - 2.0).abs() < 1e-12);
    // x <= 1: the quad (0,0), (1,0), (1,1), (0,2).
    let q = t.clip_half(0, 1.0, 1.0);
    let want = [
        DVec3::new(0.0, 0.0, 0.5),
        DVec3::new(1.0, 0.0, 0.5),
        DVec3::new(1.0, 1.0, 0.5),
        DVec3::new(0.0, 2.0, 0.5),
    ];
    assert_eq!(q.n, 4);
    for (got, want) in q.p[..4].iter().zip(want) {
        assert!(close(*got, want), "{got} {want}");
    }
    assert!((q.area() - 1.5).abs() < 1e-12);
    // Area centroid by decomposition (4/9, 7/9), not the vertex mean (1/2, 3/4).
    let (area, c) = q.area_centroid();
    assert!((area - 1.5).abs() < 1e-12);
    assert!(close(c, DVec3::new(4.0 / 9.0, 7.0 / 9.0, 0.5)), "{c}");
    assert!(close(q.mean(), DVec3::new(0.5, 0.75, 0.5)));
    // 0.5 <= x <= 1: the quad (0.5, 0), (1, 0), (1, 1), (0.5, 1.5), area 0.625.
    let s = t.clip_slab(0, 0.5, 1.0);
    assert_eq!((s.n, s.range(0), s.range(1)), (4, (0.5, 1.0), (0.0, 1.5)));
    assert!((s.area() - 0.625).abs() < 1e-12);
    // The same along z (the triangle stood up in the x–z plane): every axis is clipped.
    let up = Poly::triangle(&right_triangle(0.5).map(|p| DVec3::new(p.x, p.z, p.y)));
    let s = up.clip_slab(2, 0.5, 1.0);
    assert_eq!((s.n, s.range(2), s.range(0)), (4, (0.5, 1.0), (0.0, 1.5)));
    assert!((s.area() - 0.625).abs() < 1e-12);
    // y >= 3 keeps nothing; x <= 2 keeps all; touching x = 0 keeps one closed edge.
    assert_eq!(t.clip_half(1, -3.0, -1.0).n, 0);
    assert_eq!(t.clip_half(0, 2.0, 1.0).n, 3);
    let edge = t.clip_half(0, 0.0, 1.0);
    assert_eq!(
        (edge.n, edge.range(0), edge.range(1)),
        (2, (0.0, 0.0), (0.0, 2.0))
    );
    // A single point is kept when inside and dropped when outside.
    let point = t.clip_half(0, 0.0, 1.0).clip_half(1, 0.0, 1.0);
    assert_eq!(point.n, 1);
    assert!(close(point.p[0], DVec3::new(0.0, 0.0, 0.5)));
    assert_eq!(point.clip_half(2, 0.5, 1.0).n, 1);
    assert_eq!(point.clip_half(2, 0.4, 1.0).n, 0);
}

#[test]
fn zero_area_parts_take_the_vertex_mean() {
    let seg = Poly::triangle(&[
        DVec3::ZERO,
        DVec3::new(1.0, 2.0, 3.0),
        DVec3::new(2.0, 4.0, 6.0),
    ]);
    let (area, c) = seg.area_centroid();
    assert_eq!(area, 0.0);
    assert!(close(c, DVec3::new(1.0, 2.0, 3.0)));
    let none = seg.clip_half(0, -1.0, 1.0);
    assert_eq!(none.n, 0);
    assert_eq!(none.area_centroid(), (0.0, DVec3::ZERO));
    // The quad of `clipping_keeps_the_closed_part_with_exact_corners` shrunk: at area
    // 1.5e-12 its area centroid is used, at 1.5e-16 (below the 1e-14 threshold) the mean.
    let quad = |k: f64| Poly::triangle(&right_triangle(0.0).map(|p| p * k)).clip_half(0, k, 1.0);
    let (area, c) = quad(1e-6).area_centroid();
    assert!((area / 1.5e-12 - 1.0).abs() < 1e-9);
    assert!(
        close(c / 1e-6, DVec3::new(4.0 / 9.0, 7.0 / 9.0, 0.0)),
        "{c}"
    );
    let (area, c) = quad(1e-8).area_centroid();
    assert_eq!(area, 0.0);
    assert!(close(c / 1e-8, DVec3::new(0.5, 0.75, 0.0)), "{c}");
}

/// Random triangles in grid units, from tiny to a few hundred cells, some degenerate.
fn random_triangles(count: usize) -> Vec<[DVec3; 3]> {
    let mut next = unit_randoms();
    (0..count)
        .map(|i| {
            let size = [0.3, 3.0, 40.0][i % 3];
            let o = DVec3::new(next(), next(), next()) * 64.0 + DVec3::splat(50.0);
            let mut t = [0; 3].map(|_| o + DVec3::new(next(), next(), next()) * size);
            if i % 7 == 0 {
                // A segment: the third vertex between the first two.
                t[2] = t[0].lerp(t[1], 0.3);
            }
            t
        })
        .collect()
}

#[test]
fn the_cell_estimate_bounds_the_cells_a_triangle_overlaps_and_is_not_loose() {
    // The estimate refuses oversized requests before anything is allocated: it must never
    // be below the count. A looser one would refuse requests that fit: per size class
    // (0.3, 3 and 40 cells; segments apart) its worst ratio to the count is bounded by
    // the measured one plus 10 %.
    const MEASURED: [f64; 4] = [12.39, 10.09, 5.08, 13.69];
    let mut worst = [0.0f64; 4];
    for (i, t) in random_triangles(300).into_iter().enumerate() {
        let mut cells = 0u64;
        for_each_cell(&t, [0; 3], [1 << 20; 3], |_, _| cells += 1);
        let estimate = cell_estimate(&t);
        assert!(estimate >= cells as f64, "{t:?}: {estimate} < {cells}");
        let class = if i % 7 == 0 { 3 } else { i % 3 };
        worst[class] = worst[class].max(estimate / cells as f64);
    }
    eprintln!("worst estimate / cells per class: {worst:.2?}");
    for (w, m) in worst.iter().zip(MEASURED) {
        assert!(*w <= 1.1 * m, "{worst:?}");
    }
}

#[test]
fn the_cell_estimate_holds_where_closed_cells_touch_the_most() {
    // Vertices on lattice points touch the most closed cells: every corner 8, every edge
    // 4. These were below the count before the per-column rise: a segment along a cell
    // edge (84 cells, estimate 34) and a 45°/45° plane through lattice lines (3568 and
    // 3273).
    let count = |t: &[DVec3; 3]| {
        let mut cells = 0u64;
        for_each_cell(t, [-(1 << 20); 3], [1 << 20; 3], |_, _| cells += 1);
        cells
    };
    let d = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let n = 40.0;
    let cases = [
        (
            [d(0.5, 2.0, 2.0), d(20.5, 2.0, 2.0), d(10.5, 2.0, 2.0)],
            84,
            88.0,
        ),
        ([DVec3::ZERO, d(n, n, 0.0), d(n, 0.0, n)], 3568, 4308.5),
        ([DVec3::splat(3.0); 3], 8, 8.0),
        (
            [DVec3::ZERO, DVec3::splat(n), DVec3::splat(n / 2.0)],
            288,
            690.8,
        ),
    ];
    for (t, cells, estimate) in cases {
        assert_eq!(count(&t), cells, "{t:?}");
        assert!(
            (cell_estimate(&t) - estimate).abs() < 0.1,
            "{t:?}: {}",
            cell_estimate(&t)
        );
    }
    // Random lattice triangles, a third of them segments.
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move |m: u64| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x % m) as f64
    };
    for i in 0..300 {
        let size = [2, 6, 30][i % 3];
        let mut t = [0; 3].map(|_| DVec3::new(next(size), next(size), next(size)));
        if i % 3 == 1 {
            t[2] = t[[0, 1][i % 2]];
        }
        assert!(cell_estimate(&t) >= count(&t) as f64, "{t:?}");
    }
}

#[test]
fn a_normal_counts_as_zero_below_1e_9_of_the_longest_edge_squared() {
    // A sliver 1000 cells from the origin: a segment d = (40, 10, 5) with its midpoint
    // lifted by δ across it, so |n| = |d|·δ. Relative to the longest edge (|d|², 1787
    // cells²) the normal is 2.4e-9 of it at δ = 1e-7 (slopes: rise 0.147) and 4.8e-10
    // at δ = 2e-8 (a segment: √2·depth / longest projected edge = 0.171). The two rises
    // give estimates 362.69 and 366.82 (worked out with the formula in f64 Python).
    // Every rotation of the vertices makes each edge the longest once; measured against
    // the vertex positions instead of the edges, or against 1e-9 alone, the threshold
    // would flip one of the two.
    let o = DVec3::splat(1000.5);
    let d = DVec3::new(40.0, 10.0, 5.0);
    let u = DVec3::new(1.0, -4.0, 0.0).normalize();
    for (delta, estimate) in [(1e-7, 362.69), (2e-8, 366.82)] {
        let (a, b, m) = (o, o + d, o + d * 0.5 + u * delta);
        for t in [[a, b, m], [m, a, b], [b, m, a]] {
            let got = cell_estimate(&t);
            assert!((got - estimate).abs() < 0.01, "δ {delta}, {t:?}: {got}");
            let mut cells = 0u64;
            for_each_cell(&t, [0; 3], [1 << 20; 3], |_, _| cells += 1);
            assert!(got >= cells as f64, "{cells} cells");
        }
    }
}

#[test]
fn a_speck_within_eps_of_a_corner_sets_only_its_own_cell() {
    // The speck is inside the widened slabs of the cell across the corner, and so is the
    // mean of its clipped part: only the separating axis test may reject that cell (the
    // shortcut takes means well inside a cell only).
    for (corner, own) in [(2.0 - 5e-8, [1, 1, 1]), (3.0 + 5e-8, [3, 3, 3])] {
        let o = DVec3::splat(corner);
        let t = [o, o + DVec3::X * 1e-8, o + DVec3::Y * 1e-8];
        let mut cells = Vec::new();
        for_each_cell(&t, [0; 3], [8; 3], |c, _| cells.push(c));
        assert_eq!(cells, vec![own], "speck at {corner}");
    }
}
