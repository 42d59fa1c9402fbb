//! Unit tests of the voxelizer: brute-force oracles for meshes and voxel models.

use std::collections::BTreeSet;

use glam::{DVec3, Vec3};

use super::*;
use crate::model::{Material, Mesh, Texture, VoxelModel, cell_size};
use crate::progress::NoProgress;
use crate::voxelize::resample::FACE_OFFSETS;

fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    Mesh {
        positions,
        triangles,
        ..Default::default()
    }
}

/// Axis-aligned box mesh, outward-facing triangles.
fn box_mesh(min: Vec3, max: Vec3) -> Mesh {
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(
            if x { max.x } else { min.x },
            if y { max.y } else { min.y },
            if z { max.z } else { min.z },
        )
    };
    let positions = (0..8)
        .map(|i| p(i & 1 != 0, i & 2 != 0, i & 4 != 0))
        .collect();
    let quads = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[2], q[1]], [q[0], q[3], q[2]]])
        .collect();
    mesh(positions, triangles)
}

/// UV sphere of radius `r` around `c`.
pub(crate) fn sphere_mesh(c: Vec3, r: f32, rings: u32, segments: u32) -> Mesh {
    let mut positions = vec![c + Vec3::new(0.0, 0.0, r), c - Vec3::new(0.0, 0.0, r)];
    for i in 1..rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let ph = std::f32::consts::TAU * j as f32 / segments as f32;
            positions.push(c + r * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    let v = |i: u32, j: u32| 2 + (i - 1) * segments + (j % segments);
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, v(1, j), v(1, j + 1)]);
        triangles.push([1, v(rings - 1, j + 1), v(rings - 1, j)]);
        for i in 1..rings - 1 {
            triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    mesh(positions, triangles)
}

fn cells(set: &VoxelSet) -> BTreeSet<[u32; 3]> {
    (0..set.voxels.len()).map(|i| set.voxels.cell(i)).collect()
}

/// Brute force oracle: every cell in each valid triangle's bounding box, tested with
/// the separating axis test (no row/column walk, no bricks).
fn oracle(mesh: &Mesh, level: u32) -> BTreeSet<[u32; 3]> {
    let os = mesh_object_space(mesh).unwrap();
    let hc = half_cells(level);
    let n = 1i64 << level;
    let mut out = BTreeSet::new();
    for t in &mesh.triangles {
        if t.iter().any(|&i| i as usize >= mesh.positions.len()) {
            continue;
        }
        let v = t.map(|i| (os.to_object(mesh.positions[i as usize].as_dvec3()) + DVec3::ONE) * hc);
        if !v.iter().all(|p| p.is_finite()) {
            continue;
        }
        let lo = v[0].min(v[1]).min(v[2]);
        let hi = v[0].max(v[1]).max(v[2]);
        let r =
            |a: f64, b: f64| ((a.floor() as i64 - 1).max(0))..=((b.floor() as i64 + 1).min(n - 1));
        for z in r(lo.z, hi.z) {
            for y in r(lo.y, hi.y) {
                for x in r(lo.x, hi.x) {
                    let c = DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5);
                    if triangle_box_overlap(&v, c, 0.5) {
                        out.insert([x as u32, y as u32, z as u32]);
                    }
                }
            }
        }
    }
    out
}

fn assert_sane(set: &VoxelSet) {
    set.voxels.check().unwrap();
    for n in &set.voxels.normals {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-4, "normal {n:?}");
    }
}

#[test]
fn sat_basics() {
    let t = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 2.0, 0.0),
    ];
    assert!(triangle_box_overlap(&t, DVec3::new(0.5, 0.5, 0.5), 0.5)); // touches z = 0 face
    assert!(triangle_box_overlap(&t, DVec3::new(0.5, 0.5, -0.5), 0.5));
    assert!(!triangle_box_overlap(&t, DVec3::new(0.5, 0.5, 1.5), 0.5));
    // Beyond the hypotenuse x + y = 2: the box [1.5, 2.5]² misses it.
    assert!(!triangle_box_overlap(&t, DVec3::new(2.0, 2.0, 0.0), 0.5));
    // Corner of box (1, 1) lies on the hypotenuse: touching.
    assert!(triangle_box_overlap(&t, DVec3::new(1.5, 1.5, 0.0), 0.5));
    // A point triangle and a segment triangle.
    let p = [DVec3::splat(1.0); 3];
    assert!(triangle_box_overlap(&p, DVec3::splat(0.5), 0.5));
    assert!(!triangle_box_overlap(&p, DVec3::splat(-0.5), 0.5));
    let s = [DVec3::ZERO, DVec3::splat(3.0), DVec3::splat(3.0)];
    assert!(triangle_box_overlap(&s, DVec3::splat(1.5), 0.5));
    assert!(!triangle_box_overlap(&s, DVec3::new(2.5, 0.5, 0.5), 0.5));
}

#[test]
fn single_triangle_matches_brute_force() {
    let m = mesh(
        vec![
            Vec3::new(-0.9, -0.7, 0.13),
            Vec3::new(0.8, -0.2, -0.6),
            Vec3::new(0.1, 0.9, 0.7),
        ],
        vec![[0, 1, 2]],
    );
    for level in 0..=6 {
        let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
        assert_sane(&set);
        assert_eq!(cells(&set), oracle(&m, level), "level {level}");
        // The face normal, everywhere.
        let n = (m.positions[1] - m.positions[0])
            .cross(m.positions[2] - m.positions[0])
            .normalize();
        for v in &set.voxels.normals {
            assert!(Vec3::from(*v).dot(n) > 0.9999, "{v:?} vs {n:?}");
        }
        assert!(
            set.voxels
                .colors
                .iter()
                .all(|c| *c == Material::default().base_color)
        );
    }
}

#[test]
fn quad_on_cell_boundaries_sets_both_sides() {
    // Bounds [-1, 1]² × {0}: object space is the identity, the quad lies on z = 0,
    // which is a cell boundary at every level ≥ 1.
    let m = mesh(
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    for level in 1..=5u32 {
        let n = 1u32 << level;
        let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
        assert_sane(&set);
        let mut expected = BTreeSet::new();
        for y in 0..n {
            for x in 0..n {
                expected.insert([x, y, n / 2 - 1]);
                expected.insert([x, y, n / 2]);
            }
        }
        assert_eq!(cells(&set), expected, "level {level}");
        for v in &set.voxels.normals {
            assert!(v[2] > 0.9999, "{v:?}");
        }
    }
}

#[test]
fn box_surface_cells_exactly() {
    // Object space is the identity (centre 0, extent 2); the y and z faces fall inside
    // cells, the x faces on the grid border.
    let (lo, hi) = (Vec3::new(-1.0, -0.65, -0.55), Vec3::new(1.0, 0.65, 0.55));
    let m = box_mesh(lo, hi);
    for level in 1..=6u32 {
        let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
        assert_sane(&set);
        // Analytic oracle: the closed cell meets the box surface iff it meets the closed
        // box and is not inside its open interior.
        let s = cell_size(level);
        let n = 1u32 << level;
        let mut expected = BTreeSet::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let c = [x, y, z];
                    let (bl, bh): (Vec<f64>, Vec<f64>) = (0..3)
                        .map(|k| (-1.0 + c[k] as f64 * s, -1.0 + (c[k] + 1) as f64 * s))
                        .unzip();
                    let meets =
                        (0..3).all(|k| bl[k] <= f64::from(hi[k]) && bh[k] >= f64::from(lo[k]));
                    let inside =
                        (0..3).all(|k| bl[k] > f64::from(lo[k]) && bh[k] < f64::from(hi[k]));
                    if meets && !inside {
                        expected.insert(c);
                    }
                }
            }
        }
        assert_eq!(cells(&set), expected, "level {level}");
    }
    // Normals on face centres point out of the box.
    let set = voxelize_mesh(&m, 5, &NoProgress).unwrap();
    let at = |c: [u32; 3]| set.voxels.normals[set.voxels.find(c).unwrap()];
    let top_y = ((0.65f64 + 1.0) / cell_size(5)) as u32;
    assert!(at([16, top_y, 16])[1] > 0.9999);
    assert!(at([16, 16, ((1.0 - 0.55f64) / cell_size(5)) as u32])[2] < -0.9999);
    assert!(at([0, 16, 16])[0] < -0.9999);
}

#[test]
fn sphere_matches_brute_force_and_stays_near_the_surface() {
    let m = sphere_mesh(Vec3::new(0.3, -2.0, 5.0), 1.7, 12, 20);
    let set = voxelize_mesh(&m, 5, &NoProgress).unwrap();
    assert_sane(&set);
    let got = cells(&set);
    assert_eq!(got, oracle(&m, 5));
    // Far from the surface: nothing. The tessellation's sagitta is below 4% of r.
    let r_grid = 16.0;
    for c in &got {
        let p = DVec3::new(c[0] as f64 + 0.5, c[1] as f64 + 0.5, c[2] as f64 + 0.5)
            - DVec3::splat(16.0);
        let d = (p.length() - r_grid).abs();
        assert!(
            d <= 3f64.sqrt() / 2.0 + 0.04 * r_grid,
            "{c:?} at distance {d}"
        );
        // Normals point outwards.
        let n = DVec3::from_array(set.voxels.normals[set.voxels.find(*c).unwrap()].map(f64::from));
        assert!(n.dot(p.normalize()) > 0.5, "{c:?} {n:?}");
    }
    // Watertight surface: the centre and the corners are never set.
    assert!(!got.contains(&[16, 16, 16]) && !got.contains(&[0, 0, 0]));
}

#[test]
fn scaling_the_mesh_does_not_change_the_voxels() {
    let base = sphere_mesh(Vec3::new(0.25, 0.5, -0.125), 1.0, 9, 14);
    let reference = voxelize_mesh(&base, 6, &NoProgress).unwrap();
    for s in [1e-6f32, 1e7] {
        let mut m = base.clone();
        for p in &mut m.positions {
            *p *= s;
        }
        let set = voxelize_mesh(&m, 6, &NoProgress).unwrap();
        assert_eq!(set.voxels.codes, reference.voxels.codes, "scale {s}");
        for (a, b) in set.voxels.normals.iter().zip(&reference.voxels.normals) {
            assert!(Vec3::from(*a).dot(Vec3::from(*b)) > 0.9999);
        }
    }
}

#[test]
fn degenerate_and_invalid_triangles() {
    // A segment, a point, a proper triangle, a NaN triangle, a bad index.
    let m = mesh(
        vec![
            Vec3::new(-1.0, -0.3, 0.2),
            Vec3::new(1.0, 0.9, -0.7),
            Vec3::new(0.31, 0.27, 0.11),
            Vec3::new(-0.6, 0.5, 0.5),
            Vec3::new(-0.2, 0.6, 0.55),
            Vec3::new(-0.5, 0.9, 0.3),
            Vec3::new(f32::NAN, 0.0, 0.0),
        ],
        vec![[0, 1, 1], [2, 2, 2], [3, 4, 5], [3, 4, 6], [0, 1, 99]],
    );
    for level in [0, 1, 3, 6] {
        let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
        assert_sane(&set);
        assert_eq!(set.report.skipped_non_finite, 1);
        assert_eq!(set.report.skipped_bad_index, 1);
        assert_eq!(set.report.degenerate, 2);
        assert_eq!(cells(&set), oracle(&m, level), "level {level}");
    }
    // Only degenerate triangles: still voxelized, normals finite (fallbacks counted).
    let seg = mesh(vec![Vec3::ZERO, Vec3::new(1.0, 0.5, 0.25)], vec![[0, 1, 1]]);
    let set = voxelize_mesh(&seg, 5, &NoProgress).unwrap();
    assert_sane(&set);
    assert_eq!(cells(&set), oracle(&seg, 5));
    assert_eq!(set.report.normal_fallbacks as usize, set.voxels.len());
    let point = mesh(vec![Vec3::splat(3.0)], vec![[0, 0, 0]]);
    let set = voxelize_mesh(&point, 4, &NoProgress).unwrap();
    assert_sane(&set);
    // A zero-extent model maps to the origin: the eight cells around it.
    assert_eq!(set.voxels.len(), 8);
    // Nothing valid at all: an error, not a panic.
    let bad = mesh(vec![Vec3::NAN], vec![[0, 0, 0], [5, 6, 7]]);
    assert!(matches!(
        voxelize_mesh(&bad, 4, &NoProgress),
        Err(VoxelizeError::Empty(_))
    ));
    assert!(matches!(
        voxelize_mesh(&Mesh::default(), 4, &NoProgress),
        Err(VoxelizeError::Empty(_))
    ));
    assert!(matches!(
        voxelize_mesh(&seg, 17, &NoProgress),
        Err(VoxelizeError::LevelTooHigh { .. })
    ));
}

#[test]
fn oversized_requests_are_refused_before_allocating() {
    // One triangle across the whole grid at level 16 is ~2^31 cells.
    let m = mesh(
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.3),
            Vec3::new(0.0, 1.0, 1.0),
        ],
        vec![[0, 1, 2]],
    );
    assert!(matches!(
        voxelize_mesh(&m, 16, &NoProgress),
        Err(VoxelizeError::TooLarge { level: 16, .. })
    ));
    // A segment at level 16 is small and fine.
    let seg = mesh(vec![Vec3::ZERO, Vec3::new(1.0, 0.3, 0.2)], vec![[0, 1, 1]]);
    let set = voxelize_mesh(&seg, 16, &NoProgress).unwrap();
    assert_sane(&set);
    assert!(set.voxels.len() >= 65536);
}

#[test]
fn opposite_faces_in_one_cell_keep_a_finite_normal() {
    // A slab thinner than a cell: its two big faces cancel in every cell.
    let m = box_mesh(Vec3::new(-1.0, -1.0, -0.001), Vec3::new(1.0, 1.0, 0.001));
    let set = voxelize_mesh(&m, 4, &NoProgress).unwrap();
    assert_sane(&set);
    let interior = set.voxels.find([8, 8, 7]).unwrap();
    assert!(set.voxels.normals[interior][2].abs() > 0.9999);
}

#[test]
fn vertex_colours_and_textures_colour_the_voxels() {
    let mut m = mesh(
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        vec![[0, 1, 2]],
    );
    m.colors = vec![
        [1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
    ];
    m.materials = vec![Material {
        base_color: [1.0; 4],
        base_color_texture: None,
    }];
    let set = voxelize_mesh(&m, 4, &NoProgress).unwrap();
    let red = set.voxels.colors[set.voxels.find([0, 0, 7]).unwrap()];
    assert!(red[0] > 0.85 && red[1] < 0.15 && red[2] < 0.15, "{red:?}");
    let green = set.voxels.colors[set.voxels.find([15, 0, 8]).unwrap()];
    assert!(green[1] > 0.85, "{green:?}");

    // A 2×1 texture: left texel black, right texel white; u runs along x.
    m.colors.clear();
    m.uvs = vec![
        glam::Vec2::new(0.0, 0.0),
        glam::Vec2::new(1.0, 0.0),
        glam::Vec2::new(0.0, 1.0),
    ];
    m.materials[0].base_color_texture = Some(Texture {
        width: 2,
        height: 1,
        texels: vec![[0, 0, 0, 255], [255, 255, 255, 255]],
    });
    let set = voxelize_mesh(&m, 4, &NoProgress).unwrap();
    let left = set.voxels.colors[set.voxels.find([4, 1, 8]).unwrap()];
    let right = set.voxels.colors[set.voxels.find([12, 1, 8]).unwrap()];
    assert!(left[0] < 0.3 && right[0] > 0.7, "{left:?} {right:?}");
    let uv = set.voxels.uvs[set.voxels.find([12, 1, 8]).unwrap()];
    assert!(uv[0] > 0.7 && uv[1] < 0.2, "{uv:?}");
    // A malformed texture samples as white instead of panicking.
    m.materials[0].base_color_texture = Some(Texture {
        width: 4,
        height: 4,
        texels: vec![],
    });
    assert_sane(&voxelize_mesh(&m, 3, &NoProgress).unwrap());
}

#[test]
fn all_levels_up_to_12_on_a_needle() {
    // A long thin triangle across the grid keeps level 12 small (~ 4096·√3 · 3 cells).
    let m = mesh(
        vec![
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(0.999, 1.0, 0.9995),
        ],
        vec![[0, 1, 2]],
    );
    let mut prev: Option<VoxelSet> = None;
    for level in 1..=12u32 {
        let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
        assert_sane(&set);
        if level <= 7 {
            assert_eq!(cells(&set), oracle(&m, level), "level {level}");
        } else {
            // Sample points along the triangle: their cells must be set.
            let os = set.object_space;
            let hc = half_cells(level);
            let v = [0, 1, 2]
                .map(|i| m.positions[i])
                .map(|p| (os.to_object(p.as_dvec3()) + DVec3::ONE) * hc);
            for i in 0..=1000 {
                let a = i as f64 / 1000.0;
                let p = v[0] + (v[1] - v[0]) * a + (v[2] - v[1]) * (a * 0.5);
                let c = p
                    .to_array()
                    .map(|x| (x.floor() as i64).clamp(0, (1 << level) - 1) as u32);
                assert!(set.voxels.find(c).is_some(), "level {level}: {c:?} missing");
            }
        }
        // The parents of this level's cells contain the previous level's cells.
        if let Some(p) = &prev {
            let parents: BTreeSet<u64> = set.voxels.codes.iter().map(|c| c >> 3).collect();
            assert!(
                p.voxels.codes.iter().all(|c| parents.contains(c)),
                "level {level}"
            );
        }
        prev = Some(set);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]
    /// Random triangles, optionally snapped to a lattice of cell boundaries (with the
    /// object space pinned to the identity by two point triangles at the corners),
    /// so exact touching cases are common: the walk must find what brute force finds.
    #[test]
    fn random_triangles_match_brute_force(
        c in proptest::array::uniform9(-1.0f32..1.0),
        level in 0u32..6,
        snap in proptest::bool::ANY,
    ) {
        let c = if snap { c.map(|x| (x * 4.0).round() / 4.0) } else { c };
        let m = mesh(
            vec![
                Vec3::new(c[0], c[1], c[2]),
                Vec3::new(c[3], c[4], c[5]),
                Vec3::new(c[6], c[7], c[8]),
                Vec3::splat(-1.0),
                Vec3::splat(1.0),
            ],
            vec![[0, 1, 2], [3, 3, 3], [4, 4, 4]],
        );
        let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
        assert_sane(&set);
        proptest::prop_assert_eq!(cells(&set), oracle(&m, level));
    }
}

// ----- voxel models -----

/// Independent occupancy oracle in f64 object space with a tolerance for boundaries
/// that coincide (true overlaps are far larger than it).
fn voxel_oracle(model: &VoxelModel, level: u32, fill: VoxelFill) -> BTreeSet<[u32; 3]> {
    let os = voxel_model_object_space(model).unwrap();
    let s = cell_size(level);
    let n = 1i64 << level;
    let occ = |c: [i64; 3]| -> bool {
        if c.iter().any(|&x| !(0..n).contains(&x)) {
            return false;
        }
        model.voxels.iter().any(|v| {
            let lo = os.to_object(DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64));
            let hi = os.to_object(DVec3::new(
                v[0] as f64 + 1.0,
                v[1] as f64 + 1.0,
                v[2] as f64 + 1.0,
            ));
            (0..3).all(|k| {
                let (cl, ch) = (-1.0 + c[k] as f64 * s, -1.0 + (c[k] + 1) as f64 * s);
                ch.min(hi[k]) - cl.max(lo[k]) > 1e-9
            })
        })
    };
    let mut out = BTreeSet::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                if !occ([x, y, z]) {
                    continue;
                }
                let boundary = FACE_OFFSETS
                    .iter()
                    .any(|d| !occ([x + d[0], y + d[1], z + d[2]]));
                if fill == VoxelFill::Solid || boundary {
                    out.insert([x as u32, y as u32, z as u32]);
                }
            }
        }
    }
    out
}

fn blob() -> VoxelModel {
    // A lumpy ball of radius ~3.4 with a hole, at odd coordinates.
    let mut voxels = Vec::new();
    for z in -4..4 {
        for y in -4..4 {
            for x in -3..5 {
                let d = ((x * x + y * y + z * z) as f32).sqrt();
                if d < 3.4 && !(x == 0 && y == 0) && (x + y + z) % 7 != 3 {
                    voxels.push([x + 10, y - 20, z + 3]);
                }
            }
        }
    }
    let colors = voxels
        .iter()
        .map(|v| [((v[0] & 1) as f32), 0.5, 0.25, 1.0])
        .collect();
    VoxelModel { voxels, colors }
}

#[test]
fn voxel_models_match_the_occupancy_oracle() {
    let m = blob();
    for level in 0..=5u32 {
        for fill in [VoxelFill::Shell, VoxelFill::Solid] {
            let set = voxelize_voxels_with(&m, level, fill, &NoProgress).unwrap();
            assert_sane(&set);
            assert_eq!(
                cells(&set),
                voxel_oracle(&m, level, fill),
                "level {level} {fill:?}"
            );
        }
    }
    // A 3³ cube of voxels: all cells of a level-2 grid occupied; the shell drops the 2³
    // interior.
    let cube = VoxelModel {
        voxels: (0..27).map(|i| [i % 3, (i / 3) % 3, i / 9]).collect(),
        colors: vec![[0.2, 0.4, 0.6, 1.0]; 27],
    };
    assert_eq!(
        voxelize_voxels_with(&cube, 2, VoxelFill::Solid, &NoProgress)
            .unwrap()
            .voxels
            .len(),
        64
    );
    let shell = voxelize_voxels(&cube, 2, &NoProgress).unwrap();
    assert_eq!(shell.voxels.len(), 56);
    assert!(
        shell
            .voxels
            .colors
            .iter()
            .all(|c| (c[2] - 0.6).abs() < 1e-6)
    );
    // Upsampled: face-centre cells get the face normal.
    let up = voxelize_voxels(&cube, 6, &NoProgress).unwrap();
    assert_sane(&up);
    assert!(up.voxels.normals[up.voxels.find([32, 32, 63]).unwrap()][2] > 0.9999);
    assert!(up.voxels.normals[up.voxels.find([0, 32, 32]).unwrap()][0] < -0.9999);
    assert_eq!(up.voxels.len(), 64usize.pow(3) - 62usize.pow(3));
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 64, ..Default::default() })]
    /// Random voxel sets (any extents and offsets) at low levels, both fills.
    #[test]
    fn random_voxel_models_match_the_oracle(
        voxels in proptest::collection::vec(proptest::array::uniform3(-6i32..6), 1..40),
        offset in proptest::array::uniform3(-1000i32..1000),
        level in 0u32..5,
        solid in proptest::bool::ANY,
    ) {
        let voxels: Vec<[i32; 3]> =
            voxels.iter().map(|v| [v[0] + offset[0], v[1] + offset[1], v[2] + offset[2]]).collect();
        let model = VoxelModel { colors: vec![[0.5; 4]; voxels.len()], voxels };
        let fill = if solid { VoxelFill::Solid } else { VoxelFill::Shell };
        let set = voxelize_voxels_with(&model, level, fill, &NoProgress).unwrap();
        assert_sane(&set);
        proptest::prop_assert_eq!(cells(&set), voxel_oracle(&model, level, fill));
    }
}

#[test]
fn voxel_model_edge_cases() {
    let one = VoxelModel {
        voxels: vec![[-7, 100, 3]],
        colors: vec![],
    };
    let set = voxelize_voxels(&one, 3, &NoProgress).unwrap();
    assert_sane(&set);
    assert_eq!(set.voxels.len(), 8 * 8 * 8 - 6 * 6 * 6);
    assert_eq!(set.voxels.colors[0], Material::default().base_color);
    assert!(matches!(
        voxelize_voxels(&VoxelModel::default(), 3, &NoProgress),
        Err(VoxelizeError::Empty(_))
    ));
    // Solid upsampling to a huge grid is refused up front.
    assert!(matches!(
        voxelize_voxels_with(&one, 12, VoxelFill::Solid, &NoProgress),
        Err(VoxelizeError::TooLarge { estimate, .. }) if estimate == 1 << 36
    ));
    // The estimate is exact for one voxel: all 4096³ cells solid, or the six 8192² faces
    // of its block as a shell (over the limit at level 13, not at 12).
    assert!(matches!(
        voxelize_voxels_with(&one, 13, VoxelFill::Shell, &NoProgress),
        Err(VoxelizeError::TooLarge { estimate, .. }) if estimate == 6 << 26
    ));
    // Two voxels side by side (blocks off the grid origin, each 4096³ at level 13 and
    // 8192³ at level 14): the shell counts the ten faces that have no source neighbour.
    let two = VoxelModel {
        voxels: vec![[5, -3, 8], [6, -3, 8]],
        colors: vec![],
    };
    assert!(matches!(
        voxelize_voxels_with(&two, 13, VoxelFill::Solid, &NoProgress),
        Err(VoxelizeError::TooLarge { estimate, .. }) if estimate == 1 << 37
    ));
    assert!(matches!(
        voxelize_voxels_with(&two, 14, VoxelFill::Shell, &NoProgress),
        Err(VoxelizeError::TooLarge { estimate, .. }) if estimate == 10 << 26
    ));
    // Downsampling a large solid block: grouped, not scanned per cell.
    let block = VoxelModel {
        voxels: (0..64 * 64 * 64)
            .map(|i| [i % 64, (i / 64) % 64, i / 4096])
            .collect(),
        colors: vec![[0.25, 0.5, 0.75, 1.0]; 64 * 64 * 64],
    };
    let solid = voxelize_voxels_with(&block, 3, VoxelFill::Solid, &NoProgress).unwrap();
    assert_eq!(solid.voxels.len(), 512);
    assert_eq!(solid.report.source_voxels, 64 * 64 * 64);
    assert!(
        solid
            .voxels
            .colors
            .iter()
            .all(|c| (c[1] - 0.5).abs() < 1e-6)
    );
    assert_eq!(
        voxelize_voxels(&block, 3, &NoProgress)
            .unwrap()
            .voxels
            .len(),
        512 - 216
    );
    // Far-apart voxels use the hash index.
    let sparse = VoxelModel {
        voxels: vec![[0, 0, 0], [1000, 1000, 1000]],
        colors: vec![[1.0; 4]; 2],
    };
    let set = voxelize_voxels(&sparse, 4, &NoProgress).unwrap();
    assert_eq!(cells(&set), voxel_oracle(&sparse, 4, VoxelFill::Shell));
}

#[test]
fn regions_arrive_one_at_a_time_in_morton_order_and_make_up_the_grid() {
    let m = sphere_mesh(Vec3::ZERO, 1.0, 12, 16);
    let whole = voxelize_mesh(&m, 7, &NoProgress).unwrap();
    for region_log in [5u32, 6] {
        let mut batches: Vec<LevelVoxels> = Vec::new();
        let (space, report) =
            voxelize_mesh_regions(&m, 7, region_log, &NoProgress, |v| batches.push(v)).unwrap();
        assert_eq!(space, whole.object_space);
        assert_eq!(report.triangles, whole.report.triangles);
        let region = |code: u64| code >> (3 * region_log);
        let mut codes = Vec::new();
        for (i, b) in batches.iter().enumerate() {
            assert!(!b.codes.is_empty(), "2^{region_log}: batch {i} is empty");
            let r = region(b.codes[0]);
            assert!(
                b.codes.iter().all(|&c| region(c) == r),
                "2^{region_log}: batch {i} spans regions"
            );
            assert!(i == 0 || region(batches[i - 1].codes[0]) < r);
            codes.extend_from_slice(&b.codes);
        }
        // The sphere crosses every region of 2^6 (8 of them), and more of 2^5.
        assert!(
            batches.len() >= 8,
            "2^{region_log}: {} batches",
            batches.len()
        );
        assert_eq!(codes, whole.voxels.codes, "2^{region_log}");
    }
}
