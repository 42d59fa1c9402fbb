//! Voxels given cell by cell on a level's grid (arrays handed in by a program: a dense
//! grid, or sparse integer coordinates), kept exactly where they are: no resampling, so
//! cell `(i, j, k)` of the input is cell `(i, j, k)` of the level. Normals are the
//! occupancy gradient of the 26-neighbourhood, as for resampled voxel models, falling
//! back to the direction from the grid centre.

use rayon::prelude::*;

use super::attributes::gradient_26;
use super::{MAX_VOXELS, VoxelizeError, check_level};
use crate::svo::{LevelVoxels, morton_decode, morton_encode, normalize_or};

/// The finest level whose grid is looked up in a bit per cell (128 MiB at level 10).
const DENSE_BITS_MAX_LEVEL: u32 = 10;

/// The level-`level` voxels of `cells` with their linear RGBA `colors` (same length).
/// A cell given twice keeps its first colour. Cells outside the grid are an error naming
/// the first, as is a count above [`MAX_VOXELS`].
pub fn voxels_from_cells(
    level: u32,
    cells: &[[u32; 3]],
    colors: &[[f32; 4]],
) -> Result<LevelVoxels, VoxelizeError> {
    check_level(level)?;
    if cells.len() != colors.len() {
        return Err(VoxelizeError::BadCells(format!(
            "{} cells but {} colours",
            cells.len(),
            colors.len()
        )));
    }
    if cells.len() as u64 > MAX_VOXELS {
        return Err(VoxelizeError::TooLarge {
            level,
            estimate: cells.len() as u64,
            limit: MAX_VOXELS,
        });
    }
    let n = 1u64 << level;
    if let Some(c) = cells.iter().find(|c| c.iter().any(|&x| u64::from(x) >= n)) {
        return Err(VoxelizeError::BadCells(format!(
            "cell {c:?} is outside the level-{level} grid of {n} cells per axis"
        )));
    }
    let mut order: Vec<(u64, u32)> = cells
        .par_iter()
        .enumerate()
        .map(|(i, &c)| (morton_encode(c), i as u32))
        .collect();
    order.par_sort_unstable();
    order.dedup_by_key(|e| e.0);
    let codes: Vec<u64> = order.iter().map(|e| e.0).collect();
    // Neighbours are looked up 26 times per voxel: in a bit per cell of the grid where
    // that fits (16 MiB at level 9, 128 MiB at level 10), else by binary search.
    let bits = (level <= DENSE_BITS_MAX_LEVEL).then(|| {
        let mut bits = vec![0u64; (n * n * n).div_ceil(64) as usize];
        for &code in &codes {
            let c = morton_decode(code).map(u64::from);
            let i = (c[2] * n + c[1]) * n + c[0];
            bits[(i / 64) as usize] |= 1 << (i % 64);
        }
        bits
    });
    let occupied = |p: [i64; 3]| {
        if !p.iter().all(|&x| (0..n as i64).contains(&x)) {
            return false;
        }
        match &bits {
            Some(bits) => {
                let i = ((p[2] as u64 * n) + p[1] as u64) * n + p[0] as u64;
                bits[(i / 64) as usize] >> (i % 64) & 1 == 1
            }
            None => codes
                .binary_search(&morton_encode(p.map(|x| x as u32)))
                .is_ok(),
        }
    };
    let normals = codes
        .par_iter()
        .map(|&code| {
            let c = morton_decode(code).map(i64::from);
            let g = gradient_26(|d| occupied([c[0] + d[0], c[1] + d[1], c[2] + d[2]]));
            let from_center = c.map(|x| x as f64 + 0.5 - n as f64 * 0.5);
            normalize_or(g, || from_center)
        })
        .collect();
    Ok(LevelVoxels {
        level,
        normals,
        colors: order.iter().map(|e| colors[e.1 as usize]).collect(),
        uvs: vec![[0.0; 2]; codes.len()],
        codes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::VoxelModel;
    use crate::progress::NoProgress;

    /// A voxel model whose bounding box is the whole grid is resampled one source voxel to
    /// one cell: the resampler is an independent oracle of the cells, colours and normals.
    #[test]
    fn cells_equal_a_resampled_model_that_fills_the_grid() {
        let level = 3;
        let mut cells = Vec::new();
        let mut colors = Vec::new();
        for z in 0..8u32 {
            for y in 0..8u32 {
                for x in 0..8u32 {
                    // A ball with the two opposite corners of the grid set (bounds = grid).
                    let d = [x, y, z].map(|v| v as f64 - 3.5);
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if r < 3.0 || [x, y, z] == [0, 0, 0] || [x, y, z] == [7, 7, 7] {
                        cells.push([x, y, z]);
                        colors.push([x as f32 / 7.0, y as f32 / 7.0, z as f32 / 7.0, 1.0]);
                    }
                }
            }
        }
        let model = VoxelModel {
            voxels: cells.iter().map(|c| c.map(|x| x as i32)).collect(),
            colors: colors.clone(),
        };
        let resampled = super::super::voxelize_voxels_with(
            &model,
            level,
            super::super::VoxelFill::Solid,
            &NoProgress,
        )
        .unwrap()
        .voxels;
        // Given in reverse, with a duplicate: order and repeats do not matter.
        let mut rev: Vec<[u32; 3]> = cells.iter().rev().copied().collect();
        let mut rev_colors: Vec<[f32; 4]> = colors.iter().rev().copied().collect();
        rev.push(cells[0]);
        rev_colors.push([0.0, 0.0, 0.0, 1.0]);
        let ours = voxels_from_cells(level, &rev, &rev_colors).unwrap();
        assert_eq!(ours.codes, resampled.codes);
        assert_eq!(ours.colors, resampled.colors);
        for (a, b) in ours.normals.iter().zip(&resampled.normals) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-6, "{a:?} {b:?}");
            }
        }
    }

    /// The same cells shifted into a level-11 grid (looked up by binary search) get the
    /// normals they get in a level-3 grid (looked up in the bit grid).
    #[test]
    fn both_neighbour_lookups_give_the_same_normals() {
        let mut cells = Vec::new();
        for z in 0..6u32 {
            for y in 0..6u32 {
                for x in 0..6u32 {
                    if x + y + z <= 7 {
                        cells.push([x, y, z]);
                    }
                }
            }
        }
        let colors = vec![[1.0; 4]; cells.len()];
        let small = voxels_from_cells(3, &cells, &colors).unwrap();
        let shifted: Vec<[u32; 3]> = cells.iter().map(|c| c.map(|x| x + 1000)).collect();
        let large = voxels_from_cells(11, &shifted, &colors).unwrap();
        // The cells on the slanted face (their gradient is not zero, so no fallback to the
        // grid's centre, which differs between the grids) point the same way.
        for (i, c) in cells.iter().enumerate() {
            if c.iter().sum::<u32>() != 7 || c.contains(&0) {
                continue;
            }
            let a = small.normals[small.codes.binary_search(&morton_encode(*c)).unwrap()];
            let b = large.normals[large
                .codes
                .binary_search(&morton_encode(shifted[i]))
                .unwrap()];
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-6, "{c:?}: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn cells_outside_the_grid_and_mismatched_colours_are_refused() {
        let e = voxels_from_cells(2, &[[4, 0, 0]], &[[1.0; 4]]).unwrap_err();
        assert!(e.to_string().contains("[4, 0, 0]"), "{e}");
        let e = voxels_from_cells(2, &[[0, 0, 0]], &[]).unwrap_err();
        assert!(e.to_string().contains("1 cells but 0 colours"), "{e}");
        let one = voxels_from_cells(2, &[[1, 2, 3]], &[[1.0; 4]]).unwrap();
        assert_eq!(one.len(), 1);
        // A lone voxel's normal points away from the grid centre.
        let n = one.normals[0];
        assert!(n[2] > 0.5, "{n:?}");
    }
}
