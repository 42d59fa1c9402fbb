//! The brute-force oracle (every voxel's closed box, written independently of the DDA)
//! and its comparisons with the hierarchical and cell-by-cell traversals on random rays.

use glam::DVec3;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{ObjectHit, Traversal, trace_object_ray};

use crate::{Rng, b, lod};

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
    // Morton order: voxel ids are Morton ranks, so the brute force's index is the id.
    let mut cells: Vec<[u32; 3]> = set.into_iter().collect();
    cells.sort_by_key(|&c| ssbvb_voxel::svo::morton_encode(c));
    cells
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
