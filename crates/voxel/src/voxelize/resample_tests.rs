//! Colours and normals of resampled voxel models, and the refusal estimate, against f64
//! oracles (the occupancy oracle in `tests.rs` never looked at either; the mutation runs
//! showed that the source index of a voxel past the first 1024, the centre fallback and
//! the direction of an exposed face went unchecked).

use std::collections::BTreeMap;

use glam::DVec3;

use super::*;
use crate::model::{VoxelModel, cell_size};
use crate::progress::NoProgress;
use crate::voxelize::test_support::expected_normal;

/// A 12³ block with a hole pattern (over 1024 voxels, so the resampler's chunks matter),
/// one isolated voxel, and two positions listed twice (the later entry wins). Every entry
/// has its own colour.
fn model() -> VoxelModel {
    let mut voxels = Vec::new();
    for z in 0..12 {
        for y in 0..12 {
            for x in 0..12 {
                if (x + 2 * y + 3 * z) % 11 != 0 {
                    voxels.push([x, y, z]);
                }
            }
        }
    }
    voxels.push([20, 5, 9]);
    voxels.push([3, 4, 5]);
    voxels.push([11, 11, 11]);
    let colors = (0..voxels.len())
        .map(|i| {
            let v: [i32; 3] = voxels[i];
            [
                v[0] as f32 / 20.0,
                v[1] as f32 / 12.0,
                ((i * 37) % 101) as f32 / 100.0,
                ((i * 53) % 97) as f32 / 96.0,
            ]
        })
        .collect();
    VoxelModel { voxels, colors }
}

/// Per occupied cell: the sum of the colours of the distinct source positions it overlaps
/// (f64 object space, the last entry of a position) and their count.
fn oracle(model: &VoxelModel, level: u32) -> BTreeMap<[i64; 3], ([f64; 4], f64)> {
    let os = voxel_model_object_space(model).unwrap();
    let s = cell_size(level);
    let mut last = BTreeMap::new();
    for (v, c) in model.voxels.iter().zip(&model.colors) {
        last.insert(*v, *c);
    }
    let mut cells: BTreeMap<[i64; 3], ([f64; 4], f64)> = BTreeMap::new();
    for (v, col) in last {
        let lo = os.to_object(DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64));
        let hi = os.to_object(DVec3::new(
            v[0] as f64 + 1.0,
            v[1] as f64 + 1.0,
            v[2] as f64 + 1.0,
        ));
        // Cells overlapping [lo, hi) by more than a rounding tolerance.
        let range = |k: usize| {
            let a = ((lo[k] + 1.0) / s + 1e-9).floor() as i64;
            let b = ((hi[k] + 1.0) / s - 1e-9).ceil() as i64 - 1;
            a..=b
        };
        for z in range(2) {
            for y in range(1) {
                for x in range(0) {
                    let e = cells.entry([x, y, z]).or_default();
                    for (s, c) in e.0.iter_mut().zip(col) {
                        *s += f64::from(c);
                    }
                    e.1 += 1.0;
                }
            }
        }
    }
    cells
}

#[test]
fn resampled_voxels_take_the_mean_colour_of_their_sources_and_the_occupancy_gradient() {
    let m = model();
    assert!(m.voxels.len() > 1024);
    // Extent 21: levels 3 and 4 group source voxels into coarser cells, level 5 splits
    // them.
    for level in 3..=5u32 {
        let n = 1i64 << level;
        let want = oracle(&m, level);
        for fill in [VoxelFill::Shell, VoxelFill::Solid] {
            let set = voxelize_voxels_with(&m, level, fill, &NoProgress).unwrap();
            let mut fallbacks = 0;
            for i in 0..set.voxels.len() {
                let c = set.voxels.cell(i).map(i64::from);
                let (sum, count) = want[&c];
                let got = set.voxels.colors[i];
                for k in 0..4 {
                    assert!(
                        (f64::from(got[k]) - sum[k] / count).abs() < 1e-5,
                        "level {level} {fill:?} {c:?}: colour {got:?} against {sum:?} / {count}"
                    );
                }
                let (want_n, fallback) = expected_normal(|c| want.contains_key(c), c, n);
                if fallback {
                    fallbacks += 1;
                }
                let got_n = DVec3::from(set.voxels.normals[i].map(f64::from));
                assert!(
                    (got_n - want_n).length() < 1e-6,
                    "level {level} {fill:?} {c:?}: normal {got_n} against {want_n}"
                );
            }
            // Cells without a gradient take the direction from the centre: the inner cells
            // of the solid block, and the isolated voxel's one cell at level 3 (it spans
            // two cells along z at level 4).
            assert!(
                (fill == VoxelFill::Shell && level > 3) || fallbacks >= 1,
                "level {level} {fill:?}"
            );
        }
    }
}

/// The refusal estimate in f64: per source voxel, the cells its cube overlaps per axis;
/// solid counts the block, the shell the smaller of the block and the faces without a
/// source neighbour.
fn estimate_oracle(model: &VoxelModel, level: u32, fill: VoxelFill) -> u64 {
    let os = voxel_model_object_space(model).unwrap();
    let hc = (1u64 << level) as f64 / 2.0;
    let grid =
        |x: [i32; 3]| (os.to_object(DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64)) + 1.0) * hc;
    let mut total = 0u64;
    for v in &model.voxels {
        let (lo, hi) = (grid(*v), grid(v.map(|x| x + 1)));
        let d: Vec<u64> = (0..3)
            .map(|k| ((hi[k] - 1e-6).ceil() - (lo[k] + 1e-6).floor()) as u64)
            .collect();
        let volume = d[0] * d[1] * d[2];
        let mut faces = 0;
        for k in 0..3 {
            for dir in [-1, 1] {
                let mut q = *v;
                q[k] += dir;
                if !model.voxels.contains(&q) {
                    faces += d[(k + 1) % 3] * d[(k + 2) % 3];
                }
            }
        }
        total += match fill {
            VoxelFill::Solid => volume,
            VoxelFill::Shell => volume.min(faces),
        };
    }
    total
}

#[test]
fn the_refusal_estimate_counts_each_axis_and_each_exposed_face() {
    // Five voxels in a row along x at level 15: 6553.6 cells per voxel, so blocks span
    // 6554 or 6555 cells along x and 6554 across; the shell has 22 exposed faces.
    let row = VoxelModel {
        voxels: (0..5).map(|x| [x - 2, 7, -1]).collect(),
        colors: vec![],
    };
    let shell = estimate_oracle(&row, 15, VoxelFill::Shell);
    assert_eq!(shell, 4 * 6554 * (3 * 6554 + 2 * 6555) + 2 * 6554 * 6554);
    for (fill, want) in [
        (VoxelFill::Shell, shell),
        (
            VoxelFill::Solid,
            estimate_oracle(&row, 15, VoxelFill::Solid),
        ),
    ] {
        let got = voxelize_voxels_with(&row, 15, fill, &NoProgress);
        assert!(
            matches!(got, Err(VoxelizeError::TooLarge { estimate, .. }) if estimate == want),
            "{fill:?}: {got:?}, want {want}"
        );
    }
}

#[test]
fn the_refusal_estimate_bounds_the_output_and_takes_faces_by_direction_where_blocks_are_small() {
    // A pair of voxels along each axis and a lone voxel, 13 voxels wide. The exposed faces
    // of a row are symmetric (one start, one end), so a face looked up in the wrong
    // direction changes the sum only where `min(volume, faces)` clips one voxel of a
    // pair: blocks of 5 cells (4 < volume / face area < 6), here at level 6 (64/13 =
    // 4.9 cells per voxel).
    let m = VoxelModel {
        voxels: vec![
            [0, 0, 0],
            [1, 0, 0],
            [4, 0, 0],
            [4, 1, 0],
            [8, 0, 0],
            [8, 0, 1],
            [12, 0, 0],
        ],
        colors: vec![],
    };
    let (min, max) = voxel_bounds(&m).unwrap();
    let index = SourceIndex::new(&m, min, max);
    for level in 2..=10 {
        let rs = Resample::new(min, max, level);
        for fill in [VoxelFill::Shell, VoxelFill::Solid] {
            let estimate = refusal_estimate(&m, &rs, &index, fill);
            let want = estimate_oracle(&m, level, fill);
            assert_eq!(estimate, u128::from(want), "level {level}, {fill:?}");
            if level <= 8 {
                let kept = voxelize_voxels_with(&m, level, fill, &NoProgress)
                    .unwrap()
                    .voxels
                    .len();
                assert!(kept as u128 <= estimate, "level {level}, {fill:?}: {kept}");
            }
        }
    }
}
