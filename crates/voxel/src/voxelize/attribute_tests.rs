//! Per-voxel attributes of the mesh voxelizer against an independent oracle: a dense
//! lattice of equal-area points on each triangle, binned into cells. A voxel's colour and
//! uv are sampled at the area centroid of its part of the triangle and weighted by the
//! parts' areas (from the mutation run: the cell oracles never looked at either).

use std::collections::BTreeMap;

use glam::{DVec3, Vec2, Vec3};

use super::*;
use crate::model::{Material, Mesh, ObjectSpace};
use crate::progress::NoProgress;
use crate::voxelize::test_support::expected_normal;

/// Object space = model space: grid units are `(p + 1) · 2^level / 2`.
const IDENTITY: ObjectSpace = ObjectSpace {
    center: DVec3::ZERO,
    scale: 1.0,
};

fn grid(p: Vec3, level: u32) -> DVec3 {
    (p.as_dvec3() + DVec3::ONE) * half_cells(level)
}

/// `m²` points of triangle `t`, one per cell of its `m`-fold subdivision (equal areas).
fn lattice(t: [DVec3; 3], m: usize) -> Vec<DVec3> {
    let (e1, e2) = ((t[1] - t[0]) / m as f64, (t[2] - t[0]) / m as f64);
    let mut out = Vec::with_capacity(m * m);
    for i in 0..m {
        for j in 0..m - i {
            let at = |a: f64, b: f64| t[0] + e1 * (i as f64 + a) + e2 * (j as f64 + b);
            out.push(at(1.0 / 3.0, 1.0 / 3.0));
            if i + j + 1 < m {
                out.push(at(2.0 / 3.0, 2.0 / 3.0));
            }
        }
    }
    out
}

/// Lattice points per cell: (count, sum of the points).
fn binned(points: &[DVec3]) -> BTreeMap<[u32; 3], (usize, DVec3)> {
    let mut cells: BTreeMap<[u32; 3], (usize, DVec3)> = BTreeMap::new();
    for p in points {
        let c = p.floor().to_array().map(|x| x as u32);
        let e = cells.entry(c).or_default();
        e.0 += 1;
        e.1 += *p;
    }
    cells
}

fn voxel_of(set: &VoxelSet, cell: [u32; 3]) -> usize {
    (0..set.voxels.len())
        .find(|&i| set.voxels.cell(i) == cell)
        .unwrap_or_else(|| panic!("no voxel at {cell:?}"))
}

#[test]
fn a_voxel_takes_the_uv_at_the_area_centroid_of_its_part() {
    // uv = the model's (x, y): a voxel's uv is then the centroid of the triangle's part
    // in its cell, which the lattice gives independently (measured worst 0.0007 cell at
    // m = 600; bound 0.002). The vertex mean of a clipped part is further away.
    let level = 3;
    let p = [
        Vec3::new(-0.9, -0.8, -0.5),
        Vec3::new(0.85, -0.3, 0.2),
        Vec3::new(-0.2, 0.9, 0.6),
    ];
    let m = Mesh {
        positions: p.to_vec(),
        triangles: vec![[0, 1, 2]],
        uvs: p.iter().map(|q| Vec2::new(q.x, q.y)).collect(),
        ..Default::default()
    };
    let set = voxelize_mesh_in(&m, level, Some(IDENTITY), &NoProgress).unwrap();
    let t = p.map(|q| grid(q, level));
    let samples = 600 * 600;
    let cells = binned(&lattice(t, 600));
    let full = samples as f64 / (0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length());
    let (mut compared, mut worst) = (0, 0.0f64);
    for (cell, (count, sum)) in &cells {
        // Parts of at least a tenth of a cell's cross-section.
        if (*count as f64) < 0.1 * full {
            continue;
        }
        let want = *sum / *count as f64;
        let uv = set.voxels.uvs[voxel_of(&set, *cell)];
        let got = grid(Vec3::new(uv[0], uv[1], 0.0), level);
        let err = (got.x - want.x).abs().max((got.y - want.y).abs());
        worst = worst.max(err);
        compared += 1;
    }
    eprintln!("{compared} cells, worst centroid error {worst:.5} cell");
    assert!(compared >= 20, "{compared}");
    assert!(worst < 0.002, "{worst}");
}

#[test]
fn two_triangles_in_a_cell_mix_colour_and_normal_by_the_areas_of_their_parts() {
    // A red triangle and a blue one crossing it at an angle; no uvs or vertex colours, so
    // each part contributes its material colour and its unit normal, weighted by its area.
    let level = 3;
    let p = vec![
        Vec3::new(-0.95, -0.9, -0.1),
        Vec3::new(0.9, -0.85, 0.05),
        Vec3::new(-0.1, 0.95, 0.0),
        Vec3::new(-0.9, -0.2, -0.7),
        Vec3::new(0.8, 0.1, 0.6),
        Vec3::new(-0.6, 0.9, 0.5),
    ];
    let red = [1.0, 0.0, 0.0, 1.0];
    let blue = [0.0, 0.0, 1.0, 1.0];
    let material = |c| Material {
        base_color: c,
        base_color_texture: None,
    };
    let m = Mesh {
        positions: p.clone(),
        triangles: vec![[0, 1, 2], [3, 4, 5]],
        triangle_materials: vec![0, 1],
        materials: vec![material(red), material(blue)],
        ..Default::default()
    };
    let set = voxelize_mesh_in(&m, level, Some(IDENTITY), &NoProgress).unwrap();
    let tris = [[0, 1, 2], [3, 4, 5]].map(|t| t.map(|i| grid(p[i], level)));
    let per_tri = tris.map(|t| {
        let cross = (t[1] - t[0]).cross(t[2] - t[0]);
        let m = 500;
        // Area of each cell's part: the triangle's area times its share of the points.
        let per_cell: BTreeMap<[u32; 3], f64> = binned(&lattice(t, m))
            .into_iter()
            .map(|(c, (n, _))| (c, 0.5 * cross.length() * n as f64 / (m * m) as f64))
            .collect();
        (cross.normalize(), per_cell)
    });
    let (mut compared, mut worst_color, mut worst_normal) = (0, 0.0f64, 0.0f64);
    for (cell, &a0) in &per_tri[0].1 {
        let Some(&a1) = per_tri[1].1.get(cell) else {
            continue;
        };
        // Both parts at least a fifth of a cell's cross-section.
        if a0.min(a1) < 0.2 {
            continue;
        }
        let i = voxel_of(&set, *cell);
        let want_red = a0 / (a0 + a1);
        let c = set.voxels.colors[i];
        worst_color = worst_color
            .max((f64::from(c[0]) - want_red).abs())
            .max((f64::from(c[2]) - (1.0 - want_red)).abs());
        let n = (per_tri[0].0 * a0 + per_tri[1].0 * a1).normalize();
        let got = DVec3::from(set.voxels.normals[i].map(f64::from));
        worst_normal = worst_normal.max(got.angle_between(n).to_degrees());
        compared += 1;
    }
    eprintln!("{compared} cells, worst colour error {worst_color:.4}, normal {worst_normal:.3}°");
    assert!(compared >= 3, "{compared}");
    // Measured: 0.0001 and 0.003° (the lattice's own error); bounds ten times that.
    assert!(
        worst_color < 0.001 && worst_normal < 0.03,
        "{worst_color} {worst_normal}"
    );
}

#[test]
fn a_plane_within_eps_of_a_boundary_sets_only_the_cells_it_touches() {
    // z = ∓1e-8 lies 1e-8 to 4e-8 cells (levels 1–3) from the boundary z = 0, inside the
    // 1e-7 band by which candidates are widened: the exact test must still leave out the
    // cells on the far side, however close the part's points come to them.
    for (z, side) in [(-1e-8f32, 0u32), (1e-8, 1)] {
        let m = Mesh {
            positions: vec![
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(1.0, -1.0, z),
                Vec3::new(1.0, 1.0, z),
                Vec3::new(-1.0, 1.0, z),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..Default::default()
        };
        for level in 1..=3u32 {
            let n = 1u32 << level;
            let set = voxelize_mesh_in(&m, level, Some(IDENTITY), &NoProgress).unwrap();
            let got: Vec<[u32; 3]> = (0..set.voxels.len()).map(|i| set.voxels.cell(i)).collect();
            assert_eq!(got.len() as u32, n * n, "z {z}, level {level}");
            assert!(
                got.iter().all(|c| c[2] == n / 2 - 1 + side),
                "z {z}, level {level}"
            );
        }
    }
}

#[test]
fn cancelling_faces_take_the_normal_of_their_largest_part() {
    // A sheet drawn twice with opposite windings: the area-weighted normals cancel in every
    // cell, so each voxel takes the normal of its largest part, ±z (which one is decided
    // by rounding: the parts are equal). The occupancy-gradient fallback would point away
    // from the grid centre instead.
    let level = 3;
    let m = Mesh {
        positions: vec![
            Vec3::new(-0.9, -0.9, 0.3),
            Vec3::new(0.9, -0.9, 0.3),
            Vec3::new(-0.9, 0.9, 0.3),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 1]],
        ..Default::default()
    };
    let set = voxelize_mesh_in(&m, level, Some(IDENTITY), &NoProgress).unwrap();
    assert!(set.voxels.len() > 10);
    assert_eq!(set.report.normal_fallbacks, 0);
    for n in &set.voxels.normals {
        assert!(n[..2] == [0.0, 0.0] && n[2].abs() == 1.0, "{n:?}");
    }
}

#[test]
fn voxels_without_a_surface_take_the_occupancy_gradient_then_the_direction_from_the_centre() {
    // Segments and a point have no area: every voxel falls back to minus the sum of its
    // occupied 26-neighbours' unit offsets, recomputed here from the output cells; the
    // isolated point's voxel has no neighbour and points away from the grid centre.
    let level = 4;
    let n = 1i64 << level;
    let m = Mesh {
        positions: vec![
            Vec3::new(-0.7, -0.6, -0.5),
            Vec3::new(0.6, 0.2, 0.3),
            Vec3::new(0.1, 0.8, -0.4),
            Vec3::new(-0.8, 0.7, 0.7),
        ],
        triangles: vec![[0, 1, 1], [1, 2, 2], [3, 3, 3]],
        ..Default::default()
    };
    let set = voxelize_mesh_in(&m, level, Some(IDENTITY), &NoProgress).unwrap();
    let cells: std::collections::BTreeSet<[i64; 3]> = (0..set.voxels.len())
        .map(|i| set.voxels.cell(i).map(i64::from))
        .collect();
    assert_eq!(set.report.normal_fallbacks, set.voxels.len() as u64);
    assert!(cells.contains(&[1, 13, 13]) && cells.len() > 30);
    for i in 0..set.voxels.len() {
        let c = &set.voxels.cell(i).map(i64::from);
        let (want, _) = expected_normal(|c| cells.contains(c), *c, n);
        let got = DVec3::from(set.voxels.normals[i].map(f64::from));
        assert!((got - want).length() < 1e-6, "{c:?}: {got} against {want}");
    }
    // Level 0: one cell, centred on the grid: the last resort +z.
    let set = voxelize_mesh_in(&m, 0, Some(IDENTITY), &NoProgress).unwrap();
    assert_eq!(set.voxels.normals, vec![[0.0, 0.0, 1.0]]);
}

/// A mesh from triangles given in grid units of a level-2 grid (object space = model
/// space), voxelized.
fn voxelize_grid_triangles(tris: &[[DVec3; 3]]) -> VoxelSet {
    let m = Mesh {
        positions: tris
            .iter()
            .flatten()
            .map(|g| (*g / half_cells(2) - DVec3::ONE).as_vec3())
            .collect(),
        triangles: (0..tris.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect(),
        ..Default::default()
    };
    voxelize_mesh_in(&m, 2, Some(IDENTITY), &NoProgress).unwrap()
}

/// A triangle in the plane `axis` = 0.5 (y or z) from a base at x = 0.2 to a tip at
/// x = 2 + `poke` (0.5 cell on the other axes): its part in cell (2, 0, 0) is the tip.
fn tip(axis: usize, poke: f64) -> [DVec3; 3] {
    let base = |s: f64| {
        let mut p = DVec3::new(0.2, 0.5, 0.5);
        p[3 - axis] = s;
        p
    };
    [base(0.2), base(0.8), DVec3::new(2.0 + poke, 0.5, 0.5)]
}

#[test]
fn parts_under_1e_14_of_a_cell_only_touch_and_small_parts_still_mix_their_normals() {
    // A tip 1e-8 deep (part area ~2e-15 with the EPS slab) counts as touching: the voxel
    // takes the occupancy gradient (+x, away from its neighbour); 1e-6 deep (~2e-13) is
    // a surface with the triangle's normal (-z).
    let at_tip =
        |set: &VoxelSet| DVec3::from(set.voxels.normals[voxel_of(set, [2, 0, 0])].map(f64::from));
    let touch = voxelize_grid_triangles(&[tip(2, 1e-8)]);
    assert_eq!(touch.report.normal_fallbacks, 1);
    assert!(
        (at_tip(&touch) - DVec3::X).length() < 1e-6,
        "{}",
        at_tip(&touch)
    );
    let surface = voxelize_grid_triangles(&[tip(2, 1e-6)]);
    assert_eq!(surface.report.normal_fallbacks, 0);
    assert!(
        (at_tip(&surface) + DVec3::Z).length() < 1e-6,
        "{}",
        at_tip(&surface)
    );
    // Two tips of ~1.7e-7 and ~6.7e-7 cell² (normals -z and +y): the voxel's normal is
    // their area-weighted mean however small the total area. Part areas 0.3·d²/(1.8 + d)
    // with d the depth in the cell (EPS included; its effect is below the tolerance).
    let (d1, d2) = (1e-3, 2e-3);
    let mixed = voxelize_grid_triangles(&[tip(2, d1), tip(1, d2)]);
    let a = |d: f64| 0.3 * d * d / (1.8 + d);
    let want = (DVec3::NEG_Z * a(d1) + DVec3::Y * a(d2)).normalize();
    assert!(
        (at_tip(&mixed) - want).length() < 1e-3,
        "{} against {want}",
        at_tip(&mixed)
    );
}
