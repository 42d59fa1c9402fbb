//! Sparse voxel octree and the LOD chain.
//!
//! Every level of the octree is a LOD. A level is stored as a Morton-sorted sparse set
//! ([`LevelVoxels`]: 64-bit Morton codes plus attribute arrays); the next coarser level is
//! obtained by `parent = code >> 3`, dedup, and averaging the children's attributes
//! ([`LevelVoxels::coarsen`]). Because Morton order is hierarchical, the children of a
//! parent are a contiguous run of the sorted finer codes, so coarsening is one linear pass
//! (parallel per parent) and never needs a dense grid.
//!
//! [`Svo`] is the explicit pointer structure built from those per-level sets, laid out
//! level by level like an ESVO without contours: node `i` of level `l` is entry
//! `i` of LOD `l`'s point cloud (same Morton order), so a GPU octree ray caster reads a
//! node's averaged attributes from the point cloud of its level.

use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use crate::asset::{MAX_LEVEL, VoxelAsset};
use crate::progress::Progress;

/// Spreads the low 21 bits of `v` so that bit `b` lands on bit `3b`.
fn spread3(v: u32) -> u64 {
    let mut x = u64::from(v) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Inverse of [`spread3`]: gathers bits `0, 3, 6, …` into the low 21 bits.
fn compact3(v: u64) -> u32 {
    let mut x = v & 0x1249_2492_4924_9249;
    x = (x | (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x | (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x | (x >> 32)) & 0x1f_ffff;
    x as u32
}

/// Morton code of a cell: x in bits 0, 3, 6, …, y in bits 1, 4, …, z in bits 2, 5, ….
/// Components must be < 2^21. The parent cell (one level coarser) is `code >> 3`.
pub fn morton_encode(cell: [u32; 3]) -> u64 {
    spread3(cell[0]) | (spread3(cell[1]) << 1) | (spread3(cell[2]) << 2)
}

/// Cell of a Morton code (inverse of [`morton_encode`]).
pub fn morton_decode(code: u64) -> [u32; 3] {
    [compact3(code), compact3(code >> 1), compact3(code >> 2)]
}

/// The voxels of one level as a sparse set: Morton-sorted, distinct codes with per-voxel
/// attributes in parallel arrays (structure of arrays, so no dense 2^L³ grid ever exists).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LevelVoxels {
    /// Grid level (2^level cells per axis).
    pub level: u32,
    /// Strictly increasing Morton codes of the occupied cells.
    pub codes: Vec<u64>,
    /// Unit normal per voxel (always finite).
    pub normals: Vec<[f32; 3]>,
    /// Linear RGBA colour per voxel in [0, 1].
    pub colors: Vec<[f32; 4]>,
    /// Texture coordinate per voxel (0 when the model has none).
    pub uvs: Vec<[f32; 2]>,
}

impl LevelVoxels {
    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.codes.len()
    }

    /// Whether the level holds no voxel.
    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    /// Cell of voxel `i`.
    pub fn cell(&self, i: usize) -> [u32; 3] {
        morton_decode(self.codes[i])
    }

    /// Index of the voxel at `cell`, if occupied (binary search; cells outside the grid:
    /// `None`).
    pub fn find(&self, cell: [u32; 3]) -> Option<usize> {
        if cell.iter().any(|&c| u64::from(c) >= 1u64 << self.level) {
            return None;
        }
        self.codes.binary_search(&morton_encode(cell)).ok()
    }

    /// Checks the invariants: equal array lengths, strictly increasing codes inside the
    /// grid, finite attributes. Returns a description of the first violation.
    pub fn check(&self) -> Result<(), String> {
        let n = self.codes.len();
        if self.normals.len() != n || self.colors.len() != n || self.uvs.len() != n {
            return Err("attribute arrays differ in length from the codes".into());
        }
        if let Some(w) = self.codes.windows(2).position(|w| w[0] >= w[1]) {
            return Err(format!("codes not strictly increasing at index {w}"));
        }
        let last = self.codes.last().copied().unwrap_or(0);
        if self.level < 21 && last >> (3 * self.level) != 0 {
            return Err(format!(
                "code {last:#x} outside the level-{} grid",
                self.level
            ));
        }
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        if !self.normals.iter().all(|v| finite(v)) || !self.colors.iter().all(|v| finite(v)) {
            return Err("non-finite normal or colour".into());
        }
        Ok(())
    }

    /// The next coarser level: `parent = code >> 3` (dedup), attributes averaged over the
    /// children. Normals: normalized mean of the child normals; where they cancel, the
    /// direction away from the children's centroid inside the parent (the occupancy
    /// gradient), and if that is zero too, the first child's normal. Level 0 coarsens to
    /// itself.
    pub fn coarsen(&self) -> LevelVoxels {
        if self.level == 0 {
            return self.clone();
        }
        // Start index of every run of siblings. Sequential: one compare per voxel, far
        // cheaper than the averaging below, and it fixes the parents' order.
        let mut starts: Vec<usize> = Vec::with_capacity(self.codes.len() / 2 + 1);
        let mut prev = u64::MAX;
        for (i, &c) in self.codes.iter().enumerate() {
            if c >> 3 != prev {
                starts.push(i);
                prev = c >> 3;
            }
        }
        starts.push(self.codes.len());
        let runs = starts.len() - 1;
        let run = |g: usize| starts[g]..starts[g + 1];

        let codes: Vec<u64> = (0..runs)
            .into_par_iter()
            .map(|g| self.codes[starts[g]] >> 3)
            .collect();
        let normals: Vec<[f32; 3]> = (0..runs)
            .into_par_iter()
            .map(|g| {
                let r = run(g);
                let mut sum = [0.0f64; 3];
                let mut offset = [0.0f64; 3];
                for i in r.clone() {
                    let c = self.codes[i] & 7;
                    for k in 0..3 {
                        sum[k] += f64::from(self.normals[i][k]);
                        offset[k] += if (c >> k) & 1 == 1 { 0.5 } else { -0.5 };
                    }
                }
                normalize_or(sum, || {
                    if offset.iter().any(|&o| o != 0.0) {
                        offset.map(|o| -o)
                    } else {
                        self.normals[r.start].map(f64::from)
                    }
                })
            })
            .collect();
        let colors: Vec<[f32; 4]> = (0..runs)
            .into_par_iter()
            .map(|g| {
                let r = run(g);
                let n = r.len() as f32;
                let mut sum = [0.0f32; 4];
                for c in &self.colors[r] {
                    for k in 0..4 {
                        sum[k] += c[k];
                    }
                }
                sum.map(|s| s / n)
            })
            .collect();
        let uvs: Vec<[f32; 2]> = (0..runs)
            .into_par_iter()
            .map(|g| {
                let r = run(g);
                let n = r.len() as f32;
                let mut sum = [0.0f32; 2];
                for uv in &self.uvs[r] {
                    sum[0] += uv[0];
                    sum[1] += uv[1];
                }
                sum.map(|s| s / n)
            })
            .collect();
        LevelVoxels {
            level: self.level - 1,
            codes,
            normals,
            colors,
            uvs,
        }
    }
}

/// Unit vector of `v` as f32, or `fallback()` (normalized again; +Z if that fails too)
/// when `v` is too short or not finite. Never returns NaN.
pub(crate) fn normalize_or(v: [f64; 3], fallback: impl FnOnce() -> [f64; 3]) -> [f32; 3] {
    fn unit(v: [f64; 3]) -> Option<[f32; 3]> {
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        (len > 1e-12 && len.is_finite()).then(|| v.map(|c| (c / len) as f32))
    }
    unit(v)
        .or_else(|| unit(fallback()))
        .unwrap_or([0.0, 0.0, 1.0])
}

/// The full LOD chain from the finest level down to level 0; `result[l]` is level `l`.
pub fn build_lod_chain(finest: LevelVoxels, progress: &dyn Progress) -> Vec<LevelVoxels> {
    let top = finest.level as usize;
    progress.begin("octree levels", top as u64);
    let mut chain: Vec<LevelVoxels> = Vec::with_capacity(top + 1);
    chain.push(finest);
    while chain.last().is_some_and(|l| l.level > 0) {
        let coarser = chain.last().map(LevelVoxels::coarsen).unwrap_or_default();
        chain.push(coarser);
        progress.advance(1);
    }
    progress.end();
    chain.reverse();
    chain
}

/// One octree node: which children exist and where they are.
///
/// `child_mask` bit `c` (0..8) is set when child `c` exists, with `c = x | y << 1 | z << 2`
/// (the low three bits of the child's Morton code). The existing children are stored
/// consecutively from `first_child` (an index into [`Svo::nodes`]) in increasing `c`.
/// Leaves (nodes of the finest level) have `child_mask == 0` and `first_child == 0`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Pod, Zeroable)]
pub struct SvoNode {
    /// Bit `c` set when child `c` exists (bits 8..32 are zero).
    pub child_mask: u32,
    /// Index of the first existing child in [`Svo::nodes`].
    pub first_child: u32,
}

/// Why an octree could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SvoError {
    /// Level `level` is not exactly the set of parents of level `level + 1`.
    #[error("octree level {level} is not the set of parents of level {}", level + 1)]
    Inconsistent {
        /// The coarser of the two levels that disagree.
        level: u32,
    },
    /// More nodes than a `u32` index can address.
    #[error("octree of {nodes} nodes exceeds the u32 node index range")]
    TooManyNodes {
        /// Total node count.
        nodes: u64,
    },
    /// The levels do not run 0, 1, 2, … or exceed [`MAX_LEVEL`].
    #[error("octree levels must be 0..=n with n <= {MAX_LEVEL}, got {0} levels")]
    BadLevels(usize),
}

/// A sparse voxel octree laid out level by level (breadth first).
///
/// Nodes of level `l` occupy `nodes[level_offsets[l]..level_offsets[l + 1]]` in Morton
/// order; node `level_offsets[l] + i` is voxel `i` of LOD `l` (its averaged attributes are
/// that LOD's point-cloud entry). The root is node 0 (level 0, the whole [-1, 1]³ cube).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Svo {
    /// All nodes, level 0 first.
    pub nodes: Vec<SvoNode>,
    /// Start of each level in `nodes`, plus the total node count at the end
    /// (`levels + 1` entries).
    pub level_offsets: Vec<u32>,
}

impl Svo {
    /// Builds the octree from the Morton codes of every level (`levels[l]` = level `l`,
    /// sorted and distinct). Level `l` must be exactly the parents of level `l + 1`.
    pub fn from_level_codes<C: AsRef<[u64]> + Sync>(levels: &[C]) -> Result<Svo, SvoError> {
        if levels.is_empty() || levels.len() > MAX_LEVEL as usize + 1 {
            return Err(SvoError::BadLevels(levels.len()));
        }
        let total: u64 = levels.iter().map(|l| l.as_ref().len() as u64).sum();
        if total > u64::from(u32::MAX) {
            return Err(SvoError::TooManyNodes { nodes: total });
        }
        let mut level_offsets = Vec::with_capacity(levels.len() + 1);
        let mut acc = 0u32;
        for l in levels {
            level_offsets.push(acc);
            acc += l.as_ref().len() as u32;
        }
        level_offsets.push(acc);

        let mut nodes = vec![SvoNode::default(); total as usize];
        for l in 0..levels.len() - 1 {
            let parents = levels[l].as_ref();
            let children = levels[l + 1].as_ref();
            let base = level_offsets[l] as usize;
            let child_base = level_offsets[l + 1];
            let mut next = 0usize;
            for (i, &p) in parents.iter().enumerate() {
                let first = next;
                let mut mask = 0u32;
                while next < children.len() && children[next] >> 3 == p {
                    mask |= 1 << (children[next] & 7);
                    next += 1;
                }
                if mask == 0 {
                    return Err(SvoError::Inconsistent { level: l as u32 });
                }
                nodes[base + i] = SvoNode {
                    child_mask: mask,
                    first_child: child_base + first as u32,
                };
            }
            if next != children.len() {
                return Err(SvoError::Inconsistent { level: l as u32 });
            }
        }
        Ok(Svo {
            nodes,
            level_offsets,
        })
    }

    /// Builds the octree of a prepared asset from its LODs' point clouds.
    pub fn from_asset(asset: &VoxelAsset) -> Result<Svo, SvoError> {
        let codes: Vec<Vec<u64>> = asset
            .lods
            .iter()
            .map(|lod| {
                lod.point_cloud
                    .voxels
                    .par_iter()
                    .map(|v| morton_encode(v.cell()))
                    .collect()
            })
            .collect();
        Svo::from_level_codes(&codes)
    }

    /// Number of levels (finest level + 1).
    pub fn levels(&self) -> u32 {
        self.level_offsets.len().saturating_sub(1) as u32
    }

    /// Bytes of the node array.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<SvoNode>()
    }

    /// Walks from the root to `cell` at `level`; returns the voxel id within that level
    /// (the index into its LOD's point cloud) when every node on the way exists.
    pub fn find(&self, level: u32, cell: [u32; 3]) -> Option<u32> {
        if level >= self.levels() || cell.iter().any(|&c| u64::from(c) >= 1u64 << level) {
            return None;
        }
        if self.level_offsets[0] == self.level_offsets[1] {
            return None;
        }
        let code = morton_encode(cell);
        let mut node = 0usize;
        for l in 0..level {
            let n = self.nodes[node];
            let child = ((code >> (3 * (level - l - 1))) & 7) as u32;
            if n.child_mask & (1 << child) == 0 {
                return None;
            }
            let rank = (n.child_mask & ((1 << child) - 1)).count_ones();
            node = (n.first_child + rank) as usize;
        }
        Some(node as u32 - self.level_offsets[level as usize])
    }
}

/// Bytes of an octree (node structure plus one 16-byte packed attribute record per node)
/// with `nodes` nodes: what [`Svo`] plus the point clouds of its levels occupy.
pub fn octree_bytes(nodes: u64) -> u64 {
    nodes
        * (std::mem::size_of::<SvoNode>() + std::mem::size_of::<crate::asset::PackedVoxel>()) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_round_trips_and_orders_parents() {
        for cell in [
            [0, 0, 0],
            [1, 0, 0],
            [0, 1, 0],
            [0, 0, 1],
            [65535, 1234, 7],
            [(1 << 21) - 1; 3],
        ] {
            assert_eq!(morton_decode(morton_encode(cell)), cell);
        }
        assert_eq!(morton_encode([1, 0, 0]), 1);
        assert_eq!(morton_encode([0, 1, 0]), 2);
        assert_eq!(morton_encode([0, 0, 1]), 4);
        let c = [37, 1001, 4095];
        assert_eq!(morton_decode(morton_encode(c) >> 3), c.map(|v| v / 2));
    }

    fn level(level: u32, cells: &[[u32; 3]], normals: &[[f32; 3]]) -> LevelVoxels {
        let mut v: Vec<(u64, [f32; 3])> = cells
            .iter()
            .zip(normals)
            .map(|(&c, &n)| (morton_encode(c), n))
            .collect();
        v.sort_by_key(|x| x.0);
        LevelVoxels {
            level,
            codes: v.iter().map(|x| x.0).collect(),
            normals: v.iter().map(|x| x.1).collect(),
            colors: vec![[0.5, 0.25, 1.0, 1.0]; v.len()],
            uvs: vec![[0.0; 2]; v.len()],
        }
    }

    #[test]
    fn coarsen_averages_and_never_yields_nan() {
        // Two children with opposite normals cancel: the fallback points away from them.
        let l = level(
            2,
            &[[0, 0, 0], [0, 0, 1], [3, 3, 3]],
            &[[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]],
        );
        let c = l.coarsen();
        assert_eq!(c.level, 1);
        assert_eq!(
            c.codes,
            vec![morton_encode([0, 0, 0]), morton_encode([1, 1, 1])]
        );
        // Children at z = 0 and 1 of the parent sit at x = y = 0 (low side): gradient +x+y.
        let n = c.normals[0];
        assert!(n.iter().all(|v| v.is_finite()));
        assert!(n[0] > 0.5 && n[1] > 0.5 && n[2].abs() < 1e-6, "{n:?}");
        assert_eq!(c.normals[1], [1.0, 0.0, 0.0]);
        assert_eq!(c.colors[0], [0.5, 0.25, 1.0, 1.0]);
        c.check().unwrap();
        let chain = build_lod_chain(l, &crate::progress::NoProgress);
        assert_eq!(chain.len(), 3);
        assert_eq!(chain[0].codes, vec![0]);
        for (i, lv) in chain.iter().enumerate() {
            assert_eq!(lv.level, i as u32);
        }
    }

    #[test]
    fn svo_finds_every_voxel_of_every_level() {
        let cells: Vec<[u32; 3]> = (0..200u32)
            .map(|i| [(i * 7) % 32, (i * 13) % 32, (i * 29) % 32])
            .collect();
        let mut fine = level(5, &cells, &vec![[0.0, 1.0, 0.0]; cells.len()]);
        fine.codes.dedup();
        fine.normals.truncate(fine.codes.len());
        fine.colors.truncate(fine.codes.len());
        fine.uvs.truncate(fine.codes.len());
        let chain = build_lod_chain(fine, &crate::progress::NoProgress);
        let codes: Vec<&[u64]> = chain.iter().map(|l| l.codes.as_slice()).collect();
        let svo = Svo::from_level_codes(&codes).unwrap();
        assert_eq!(svo.levels(), 6);
        assert_eq!(
            svo.nodes.len(),
            chain.iter().map(|l| l.len()).sum::<usize>()
        );
        for lv in &chain {
            for i in 0..lv.len() {
                assert_eq!(svo.find(lv.level, lv.cell(i)), Some(i as u32));
            }
        }
        assert_eq!(
            svo.find(5, [31, 31, 30]).is_some(),
            chain[5].find([31, 31, 30]).is_some()
        );
        // Inconsistent levels are refused, not mis-built.
        let bad: Vec<Vec<u64>> = vec![vec![0], vec![1], vec![100]];
        assert!(Svo::from_level_codes(&bad).is_err());
    }
}
