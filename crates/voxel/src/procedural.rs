//! Procedural voxel sets for the seed-002 study (`ssbvb bench --preset study`): a filled
//! ball and a grid of independent random voxels, both solid (every occupied cell kept, as
//! in the study: full octree nodes exist for the cube rasterizer to merge). Each fills the
//! level's whole grid, so object space is the grid itself and no resampling happens.

use glam::DVec3;
use rayon::prelude::*;

use crate::model::ObjectSpace;
use crate::svo::{LevelVoxels, morton_encode};
use crate::voxelize::{MAX_VOXELS, VoxelSet, VoxelizeError, VoxelizeReport, gradient_26};

/// Which procedural model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProceduralModel {
    /// Every cell whose centre lies inside the ball inscribed in the grid.
    FilledBall,
    /// Each cell occupied independently with probability `fraction` (a hash of the cell
    /// and `seed`, so the set is the same on every machine).
    Random {
        /// Probability of a cell being occupied, in [0, 1].
        fraction: f64,
        /// Seed of the hash.
        seed: u64,
    },
}

/// SplitMix64 finaliser: a well-mixed 64-bit hash of `x`.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

impl ProceduralModel {
    /// Whether cell `c` of a level-`level` grid is occupied.
    pub fn occupied(&self, level: u32, c: [i64; 3]) -> bool {
        let n = 1i64 << level;
        if c.iter().any(|&v| !(0..n).contains(&v)) {
            return false;
        }
        match *self {
            ProceduralModel::FilledBall => {
                let h = n as f64 * 0.5;
                let d = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) + 0.5 - h;
                d.length_squared() <= h * h
            }
            ProceduralModel::Random { fraction, seed } => {
                let code = morton_encode(c.map(|v| v as u32));
                // Top 53 bits as a uniform number in [0, 1).
                let u = (mix(code ^ mix(seed)) >> 11) as f64 / (1u64 << 53) as f64;
                u < fraction
            }
        }
    }

    /// The voxel set at `level` (Morton-sorted), with unit normals (the ball's radial
    /// direction; for random voxels the occupancy gradient of the 26-neighbourhood, +Y
    /// where it vanishes) and colours. Refused with [`VoxelizeError::TooLarge`] when the
    /// grid could hold more than [`MAX_VOXELS`] occupied cells.
    pub fn voxels(&self, level: u32) -> Result<VoxelSet, VoxelizeError> {
        let n = 1u64 << level;
        let bound = match self {
            ProceduralModel::FilledBall => {
                (std::f64::consts::PI / 6.0 * (n * n * n) as f64).ceil() as u64
            }
            ProceduralModel::Random { fraction, .. } => {
                ((n * n * n) as f64 * fraction.clamp(0.0, 1.0)).ceil() as u64
            }
        };
        if level > 16 || bound > MAX_VOXELS {
            return Err(VoxelizeError::TooLarge {
                level,
                estimate: bound,
                limit: MAX_VOXELS,
            });
        }
        let n = n as i64;
        // One z-slab per task; each slab's cells, then one Morton sort.
        let mut cells: Vec<(u64, [i64; 3])> = (0..n)
            .into_par_iter()
            .flat_map_iter(|z| {
                let mut out = Vec::new();
                for y in 0..n {
                    for x in 0..n {
                        let c = [x, y, z];
                        if self.occupied(level, c) {
                            out.push((morton_encode(c.map(|v| v as u32)), c));
                        }
                    }
                }
                out
            })
            .collect();
        cells.par_sort_unstable_by_key(|e| e.0);
        let h = n as f64 * 0.5;
        let normals: Vec<[f32; 3]> = cells
            .par_iter()
            .map(|&(_, c)| {
                let g = match self {
                    ProceduralModel::FilledBall => {
                        DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) + 0.5 - h
                    }
                    ProceduralModel::Random { .. } => DVec3::from(gradient_26(|d| {
                        self.occupied(level, [c[0] + d[0], c[1] + d[1], c[2] + d[2]])
                    })),
                };
                let g = g.normalize_or(DVec3::Y);
                g.as_vec3().to_array()
            })
            .collect();
        let colors: Vec<[f32; 4]> = cells
            .par_iter()
            .map(|&(code, _)| match self {
                ProceduralModel::FilledBall => [0.85, 0.45, 0.2, 1.0],
                ProceduralModel::Random { .. } => {
                    let k = mix(code);
                    let ch = |s: u32| 0.25 + 0.6 * ((k >> s) & 0xff) as f32 / 255.0;
                    [ch(0), ch(8), ch(16), 1.0]
                }
            })
            .collect();
        let len = cells.len();
        Ok(VoxelSet {
            object_space: ObjectSpace {
                center: DVec3::ZERO,
                scale: 1.0,
            },
            voxels: LevelVoxels {
                level,
                codes: cells.into_iter().map(|e| e.0).collect(),
                normals,
                colors,
                uvs: vec![[0.0; 2]; len],
            },
            report: VoxelizeReport::default(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ball_fills_about_pi_over_six_of_the_grid() {
        for level in [3, 5] {
            let set = ProceduralModel::FilledBall.voxels(level).unwrap();
            let n = (1u64 << level).pow(3) as f64;
            let ratio = set.voxels.len() as f64 / n;
            assert!((ratio - std::f64::consts::PI / 6.0).abs() < 0.05, "{ratio}");
            assert!(set.voxels.codes.windows(2).all(|w| w[0] < w[1]));
            // Touches every face of the grid (extent = the grid).
            let cells: Vec<[u32; 3]> = (0..set.voxels.len()).map(|i| set.voxels.cell(i)).collect();
            for a in 0..3 {
                assert!(cells.iter().any(|c| c[a] == 0));
                assert!(cells.iter().any(|c| c[a] == (1 << level) - 1));
            }
            // Radial normals: the +X pole's normal points along +X.
            let top = cells.iter().position(|c| c[0] == (1 << level) - 1).unwrap();
            assert!(
                set.voxels.normals[top][0] > 0.7,
                "{:?}",
                set.voxels.normals[top]
            );
        }
    }

    #[test]
    fn random_voxels_fill_the_fraction_and_are_reproducible() {
        let m = ProceduralModel::Random {
            fraction: 0.5,
            seed: 7,
        };
        let a = m.voxels(5).unwrap();
        let b = m.voxels(5).unwrap();
        assert_eq!(a.voxels.codes, b.voxels.codes);
        let ratio = a.voxels.len() as f64 / 32768.0;
        assert!((ratio - 0.5).abs() < 0.02, "{ratio}");
        let other = ProceduralModel::Random {
            fraction: 0.5,
            seed: 8,
        }
        .voxels(5)
        .unwrap();
        assert_ne!(a.voxels.codes, other.voxels.codes);
        assert!(a.voxels.normals.iter().all(|n| {
            let l = n.iter().map(|v| v * v).sum::<f32>();
            (l - 1.0).abs() < 1e-4
        }));
    }

    #[test]
    fn absurd_levels_are_refused() {
        assert!(matches!(
            ProceduralModel::FilledBall.voxels(12),
            Err(VoxelizeError::TooLarge { .. })
        ));
    }
}
