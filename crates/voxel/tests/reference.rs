//! Tests of the CPU reference ray caster against analytic geometry and against two
//! independent oracles (the cell-by-cell DDA and a brute-force test of every voxel).

use glam::{DAffine3, DQuat, DVec2, DVec3};
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, ProxyMesh, SparseLookup};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{
    Instance, ObjectHit, ReferenceImage, Traversal, render, trace_object_ray, trace_pixel,
};
use ssbvb_voxel::shading::Light;

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

/// A LOD level from cells (voxel id = index), normals pointing away from the origin.
fn lod(level: u32, cells: &[[u32; 3]]) -> LodLevel {
    let s = cell_size(level);
    let voxels = cells
        .iter()
        .map(|&c| {
            let centre = c.map(|v| (-1.0 + (v as f64 + 0.5) * s) as f32);
            PackedVoxel::new(c, centre, [0.8, 0.6, 0.4, 1.0], [0.0; 2])
        })
        .collect();
    LodLevel {
        level,
        point_cloud: PointCloud { voxels },
        lookup: SparseLookup::from_cells(level, cells.iter().copied()),
        proxy: ProxyMesh::default(),
    }
}

/// Lower boundary of cell `k` (exact for the levels used here).
fn b(level: u32, k: i64) -> f64 {
    -1.0 + k as f64 * cell_size(level)
}

/// Cells whose centre lies within `r` of the origin.
fn ball_cells(level: u32, r: f64) -> Vec<[u32; 3]> {
    let n = 1u32 << level;
    let s = cell_size(level);
    let mut cells = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = DVec3::new(x as f64, y as f64, z as f64) * s + DVec3::splat(-1.0 + s * 0.5);
                if c.length() <= r {
                    cells.push([x, y, z]);
                }
            }
        }
    }
    cells
}

/// SplitMix64: a tiny deterministic generator (no dependency).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// Slab test of a world-space ray against an axis-aligned box: `(t_enter, entry axis)`.
fn ray_box(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, usize, f64)> {
    let (mut t0, mut t1, mut axis, mut second) =
        (f64::NEG_INFINITY, f64::INFINITY, 0, f64::NEG_INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        let (near, far) = (ta.min(tb), ta.max(tb));
        if near > t0 {
            second = t0;
            t0 = near;
            axis = a;
        } else if near > second {
            second = near;
        }
        t1 = t1.min(far);
    }
    // Also return the gap to the runner-up entry plane so callers can skip edge ties.
    (t0 <= t1 && t1 >= 0.0).then_some((t0.max(0.0), axis, t0 - second))
}

/// Ray–sphere (`d` unit): the nearest `t >= 0` or `None`. Uses the closest-approach
/// point, which stays accurate when the eye is 1e7 radii away (the textbook discriminant
/// `b² - c` cancels catastrophically there).
fn ray_sphere(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let t_close = -oc.dot(d);
    let perp = oc + d * t_close;
    let h2 = r * r - perp.length_squared();
    if h2 < 0.0 {
        return None;
    }
    let t = t_close - h2.sqrt();
    (t >= 0.0).then_some(t)
}

fn assert_finite(img: &ReferenceImage) {
    assert!(img.all_finite(), "non-finite value in the reference image");
    for h in img.hits.iter().flatten() {
        let n = DVec3::from(h.face_normal.map(f64::from));
        assert!(
            (n.length() - 1.0).abs() < 1e-5,
            "face normal not unit: {n:?}"
        );
    }
}

/// Convex hull (counter-clockwise) of 2D points, Andrew's monotone chain.
fn convex_hull(mut p: Vec<DVec2>) -> Vec<DVec2> {
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Signed distance-like margin of `q` inside a CCW convex polygon (positive inside).
fn polygon_margin(poly: &[DVec2], q: DVec2) -> f64 {
    let mut m = f64::INFINITY;
    for i in 0..poly.len() {
        let (a, c) = (poly[i], poly[(i + 1) % poly.len()]);
        let e = c - a;
        m = m.min(e.perp_dot(q - a) / e.length());
    }
    m
}

/// Checks a rendered world box pixel by pixel against its analytic projection (convex hull
/// of the 8 projected corners) and its analytic entry depth and face. Returns the number
/// of pixels covered.
fn check_projected_box(img: &ReferenceImage, cam: &Camera, lo: DVec3, hi: DVec3) -> usize {
    let (w, h) = (img.width, img.height);
    let vp = cam.view_projection(w as f64 / h as f64);
    let corners: Vec<DVec2> = (0..8)
        .map(|i| {
            let p = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let c = vp * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            DVec2::new(
                (ndc.x + 1.0) * 0.5 * w as f64,
                (1.0 - ndc.y) * 0.5 * h as f64,
            )
        })
        .collect();
    let hull = convex_hull(corners);
    let mut covered = 0;
    for py in 0..h {
        for px in 0..w {
            let m = polygon_margin(&hull, DVec2::new(px as f64 + 0.5, py as f64 + 0.5));
            let hit = img.hit(px, py);
            if m > 1e-6 {
                let hit =
                    hit.unwrap_or_else(|| panic!("pixel ({px},{py}) inside by {m} but missed"));
                covered += 1;
                let (o, d) = cam.ray(px, py, w, h);
                let (t, axis, gap) = ray_box(o, d, lo, hi).expect("analytic ray misses");
                assert!(
                    (hit.t - t).abs() <= 1e-9 * t.max(1e-300),
                    "({px},{py}) t {} vs {t}",
                    hit.t
                );
                if gap > 1e-9 * t {
                    let mut n = DVec3::ZERO;
                    n[axis] = -d[axis].signum();
                    let got = DVec3::from(hit.face_normal.map(f64::from));
                    assert!(
                        got.dot(n) > 1.0 - 1e-6,
                        "pixel ({px},{py}): normal {got} vs {n}"
                    );
                }
            } else if m < -1e-6 {
                assert!(
                    hit.is_none(),
                    "pixel ({px},{py}) outside by {m} but hit {hit:?}"
                );
            }
        }
    }
    covered
}

/// World box of `cell` of a LOD placed with `xf`, for axis-aligned transforms only.
fn cell_box(level: u32, cell: [u32; 3]) -> (DVec3, DVec3) {
    let s = cell_size(level);
    let lo = DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64) * s - DVec3::ONE;
    (lo, lo + DVec3::splat(s))
}

// ---------------------------------------------------------------------------------------
// Brute-force oracle: every voxel's closed box, written independently of the DDA (no
// mirroring; the same per-plane crossing-time formula the module documents).
// ---------------------------------------------------------------------------------------

fn brute_force(level: u32, cells: &[[u32; 3]], o: DVec3, d: DVec3) -> Option<ObjectHit> {
    let n = 1i64 << level;
    let tp = |a: usize, k: i64| (b(level, k) - o[a]) / d[a];
    // Touch interval of a cell on an axis (None if a static axis misses it).
    let interval = |a: usize, c: i64| -> Option<(f64, f64)> {
        if d[a] == 0.0 {
            (b(level, c) <= o[a] && o[a] <= b(level, c + 1))
                .then_some((f64::NEG_INFINITY, f64::INFINITY))
        } else if d[a] > 0.0 {
            Some((tp(a, c), tp(a, c + 1)))
        } else {
            Some((tp(a, c + 1), tp(a, c)))
        }
    };
    let mut touched: Vec<(f64, usize)> = Vec::new();
    for (id, cell) in cells.iter().enumerate() {
        let mut t_in = 0.0f64;
        let mut t_out = f64::INFINITY;
        let mut ok = true;
        for (a, &c) in cell.iter().enumerate() {
            match interval(a, c as i64) {
                Some((i, e)) => {
                    t_in = t_in.max(i);
                    t_out = t_out.min(e);
                }
                None => ok = false,
            }
        }
        if ok && t_in <= t_out {
            touched.push((t_in, id));
        }
    }
    let t_min = touched
        .iter()
        .map(|&(t, _)| t)
        .fold(f64::INFINITY, f64::min);
    let mut best: Option<((i64, i64, i64, i64), usize)> = None;
    for &(t, id) in touched.iter().filter(|(t, _)| *t == t_min) {
        let c = cells[id].map(|v| v as i64);
        let mut rank = [0i64; 3];
        for a in 0..3 {
            rank[a] = if d[a] == 0.0 {
                i64::from(c[a] > 0 && b(level, c[a]) == o[a])
            } else {
                // Cells further along this axis that are also touched at `t`.
                let step = if d[a] > 0.0 { 1 } else { -1 };
                let mut j = c[a] + step;
                let mut r = 0;
                while (0..n).contains(&j) && interval(a, j).unwrap().0 <= t {
                    r += 1;
                    j += step;
                }
                r
            };
        }
        let key = (rank.iter().sum(), rank[2], rank[1], rank[0]);
        if best.is_none_or(|(k, _)| key < k) {
            best = Some((key, id));
        }
    }
    let (_, id) = best?;
    let c = cells[id];
    let mut face: Option<usize> = None;
    for a in 0..3 {
        if d[a] != 0.0
            && interval(a, c[a] as i64).unwrap().0 == t_min
            && face.is_none_or(|f| d[a].abs() > d[f].abs())
        {
            face = Some(a);
        }
    }
    let dominant = |d: DVec3| {
        let a = d.abs();
        if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        }
    };
    let face_axis = face.unwrap_or_else(|| dominant(d));
    let mut face_normal = DVec3::ZERO;
    face_normal[face_axis] = -d[face_axis].signum();
    Some(ObjectHit {
        voxel: id as u32,
        cell: c,
        t: t_min,
        face_axis,
        face_normal,
        inside: face.is_none(),
    })
}

/// Random cells clustered into a few pages so that page and block skipping matter.
fn random_sparse_cells(rng: &mut Rng, level: u32, count: usize) -> Vec<[u32; 3]> {
    let n = 1u64 << level;
    let cluster = (n / 4).max(1);
    let centres: Vec<[u64; 3]> = (0..3)
        .map(|_| [rng.below(n), rng.below(n), rng.below(n)])
        .collect();
    let mut set = std::collections::BTreeSet::new();
    while set.len() < count.min((n * n * n) as usize) {
        let c = centres[rng.below(3) as usize];
        let cell = c.map(|v| {
            let off = rng.below(2 * cluster + 1) as i64 - cluster as i64;
            (v as i64 + off).clamp(0, n as i64 - 1) as u32
        });
        // Also scatter some isolated voxels anywhere.
        if rng.below(10) == 0 {
            set.insert([
                rng.below(n) as u32,
                rng.below(n) as u32,
                rng.below(n) as u32,
            ]);
        } else {
            set.insert(cell);
        }
    }
    set.into_iter().collect()
}

/// A random ray: generic, lattice-aligned (exact ties: origins on planes and edges,
/// small integer directions, zero components), or aimed at a voxel's corner or edge.
fn random_ray(rng: &mut Rng, level: u32, cells: &[[u32; 3]]) -> (DVec3, DVec3) {
    let n = 1i64 << level;
    let s = cell_size(level);
    match rng.below(3) {
        0 => {
            let o = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            );
            let d = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            (o, d)
        }
        1 => {
            let coord = |rng: &mut Rng| {
                let k = rng.below(n as u64 + 5) as i64 - 2;
                b(level, k) + [0.0, 0.0, 0.5, 0.25][rng.below(4) as usize] * s
            };
            let o = DVec3::new(coord(rng), coord(rng), coord(rng));
            let mut d = DVec3::ZERO;
            while d == DVec3::ZERO {
                d = DVec3::new(
                    rng.below(5) as f64 - 2.0,
                    rng.below(5) as f64 - 2.0,
                    rng.below(5) as f64 - 2.0,
                );
            }
            (o, d)
        }
        _ => {
            let c = cells[rng.below(cells.len() as u64) as usize];
            // A corner, edge midpoint or face centre of the voxel.
            let target = DVec3::new(
                b(level, c[0] as i64) + rng.below(3) as f64 * 0.5 * s,
                b(level, c[1] as i64) + rng.below(3) as f64 * 0.5 * s,
                b(level, c[2] as i64) + rng.below(3) as f64 * 0.5 * s,
            );
            let o = DVec3::new(
                rng.range(-2.5, 2.5),
                rng.range(-2.5, 2.5),
                rng.range(-2.5, 2.5),
            );
            // Sometimes axis-parallel through the target.
            if rng.below(3) == 0 {
                let a = rng.below(3) as usize;
                let mut o2 = target;
                o2[a] = o[a];
                let mut d = DVec3::ZERO;
                d[a] = if o[a] < target[a] { 1.0 } else { -1.0 };
                (o2, d)
            } else {
                (o, target - o)
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Oracle comparisons
// ---------------------------------------------------------------------------------------

#[test]
fn hierarchical_equals_cell_by_cell_and_brute_force_on_random_rays() {
    let mut rng = Rng(0x5eed);
    let mut hits = 0;
    let mut total = 0;
    for level in [0, 1, 2, 3, 4, 5, 6, 7, 8, 9] {
        for round in 0..3 {
            let count = [1, 40, 400][round];
            let cells = random_sparse_cells(&mut rng, level, count);
            let l = lod(level, &cells);
            for _ in 0..400 {
                let (o, d) = random_ray(&mut rng, level, &cells);
                let h = trace_object_ray(&l.lookup, o, d, Traversal::Hierarchical);
                let p = trace_object_ray(&l.lookup, o, d, Traversal::CellByCell);
                assert_eq!(
                    h, p,
                    "level {level}: hierarchical vs plain, ray {o:?} {d:?}"
                );
                let bf = brute_force(level, &cells, o, d);
                assert_eq!(h, bf, "level {level}: DDA vs brute force, ray {o:?} {d:?}");
                if let Some(h) = h {
                    assert!(h.t.is_finite() && h.t >= 0.0);
                    hits += 1;
                }
                total += 1;
            }
        }
    }
    // The generator aims a third of the rays at voxels: plenty of hits and misses.
    assert!(hits > total / 5 && hits < total, "{hits} hits of {total}");
}

#[test]
fn hierarchical_equals_cell_by_cell_at_level_12() {
    let level = 12;
    let mut rng = Rng(12);
    let cells = random_sparse_cells(&mut rng, level, 300);
    let l = lod(level, &cells);
    for _ in 0..300 {
        let (o, d) = random_ray(&mut rng, level, &cells);
        let h = trace_object_ray(&l.lookup, o, d, Traversal::Hierarchical);
        assert_eq!(
            h,
            trace_object_ray(&l.lookup, o, d, Traversal::CellByCell),
            "{o:?} {d:?}"
        );
        assert_eq!(h, brute_force(level, &cells, o, d), "{o:?} {d:?}");
    }
}

// ---------------------------------------------------------------------------------------
// Exact rules: grazing, edges, corners, inside
// ---------------------------------------------------------------------------------------

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
    assert_eq!((h.cell, h.voxel), ([3, 3, 3], 1));
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

// ---------------------------------------------------------------------------------------
// Analytic scenes
// ---------------------------------------------------------------------------------------

fn render_one(l: &LodLevel, xf: DAffine3, cam: &Camera, w: u32, h: u32) -> ReferenceImage {
    let img = render(
        &[Instance {
            lod: l,
            object_to_world: xf,
        }],
        cam,
        w,
        h,
        &Light::default(),
    );
    assert_finite(&img);
    img
}

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

/// Checks a ball (cells with centre within `r` of `centre`, all in world units, voxel
/// half-diagonal `hd`) against the analytic sphere. Returns the pixel coverage.
fn check_ball(img: &ReferenceImage, cam: &Camera, centre: DVec3, r: f64, hd: f64) -> usize {
    let (w, h) = (img.width, img.height);
    let mut covered = 0;
    for py in 0..h {
        for px in 0..w {
            let (o, d) = cam.ray(px, py, w, h);
            let hit = img.hit(px, py);
            let outer = ray_sphere(o, d, centre, r + hd);
            let inner = ray_sphere(o, d, centre, r - hd);
            match (hit, outer, inner) {
                (Some(hit), Some(t_out), _) => {
                    covered += 1;
                    let tol = 1e-9 * t_out;
                    assert!(
                        hit.t >= t_out - tol,
                        "({px},{py}) {} before outer {t_out}",
                        hit.t
                    );
                    if let Some(t_in) = inner {
                        assert!(
                            hit.t <= t_in + tol,
                            "({px},{py}) {} after inner {t_in}",
                            hit.t
                        );
                    }
                    let n = DVec3::from(hit.face_normal.map(f64::from));
                    assert!(n.dot(d) < 0.0, "normal faces the ray");
                }
                (Some(hit), None, _) => panic!("({px},{py}) hit {hit:?} outside the outer sphere"),
                (None, _, Some(_)) => panic!("({px},{py}) missed inside the inner sphere"),
                (None, _, None) => {}
            }
        }
    }
    covered
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
        let covered = img.hits.iter().flatten().filter(|h| h.voxel == 0).count();
        assert!(covered > 50, "{eye:?}: {covered}");
        let img = render_one(&alone, DAffine3::IDENTITY, &cam, 40, 40);
        assert!(check_projected_box(&img, &cam, lo, hi) > 50);
    }
}

#[test]
fn nearest_instance_wins() {
    let l = lod(4, &ball_cells(4, 0.9));
    let instances = [
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_translation(DVec3::new(0.8, 0.0, -1.0)),
        },
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_translation(DVec3::new(-0.8, 0.2, 0.5)),
        },
        // A singular transform hides its instance instead of producing NaN.
        Instance {
            lod: &l,
            object_to_world: DAffine3::from_scale(DVec3::ZERO),
        },
    ];
    let cam = Camera::new(DVec3::new(0.0, 0.5, 6.0), DVec3::ZERO);
    let all = render(&instances, &cam, 64, 48, &Light::default());
    assert_finite(&all);
    let singles: Vec<ReferenceImage> = (0..2)
        .map(|i| render(&instances[i..=i], &cam, 64, 48, &Light::default()))
        .collect();
    let mut from_each = [0; 2];
    for (i, h) in all.hits.iter().enumerate() {
        let a = singles[0].hits[i];
        let b = singles[1].hits[i];
        let want = match (a, b) {
            (Some(a), Some(b)) => Some(if b.t < a.t { (1, b) } else { (0, a) }),
            (Some(a), None) => Some((0, a)),
            (None, Some(b)) => Some((1, b)),
            (None, None) => None,
        };
        match (h, want) {
            (Some(h), Some((inst, w))) => {
                assert_eq!((h.instance, h.voxel, h.t), (inst, w.voxel, w.t));
                from_each[inst as usize] += 1;
            }
            (None, None) => {}
            _ => panic!("pixel {i}: {h:?} vs {want:?}"),
        }
    }
    assert!(from_each[0] > 50 && from_each[1] > 50, "{from_each:?}");
}

#[test]
fn png_outputs_are_written_atomically_and_decode() {
    let l = lod(5, &ball_cells(5, 0.6));
    let cam = Camera::default();
    let img = render_one(&l, DAffine3::IDENTITY, &cam, 32, 24);
    let dir = std::env::temp_dir().join(format!("ssbvb-reference-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for name in ["shaded.png", "normals.png", "depth.png"] {
        let path = dir.join(name);
        match name {
            "shaded.png" => img.to_png(&path),
            "normals.png" => img.normals_to_png(&path),
            _ => img.depth_to_png(&path),
        }
        .unwrap();
        let back = image::open(&path).unwrap().to_rgba8();
        assert_eq!(back.dimensions(), (32, 24));
        // Centre pixel hits the ball, the corner does not.
        assert_eq!(back.get_pixel(16, 12)[3], 255);
        assert_eq!(back.get_pixel(0, 0)[3], 0);
    }
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
