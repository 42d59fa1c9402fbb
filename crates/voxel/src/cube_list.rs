//! The instance data of the instanced cube rasterization baseline: the list of
//! axis-aligned cubes that cover one LOD level's voxels, one instance each.
//!
//! Without merging every voxel is a unit cube. With merging, every *completely full*
//! octree node — all 8 children present and themselves full, recursively — becomes ONE
//! cube of its node size, as the octree variants of instanced cube rasterization send
//! each fully filled node. The merge runs bottom-up over the Morton-sorted cells: at each size,
//! eight consecutive full nodes that share a parent (`code >> 3`) form a full parent;
//! everything else is emitted at its current size. The cubes are disjoint and their union
//! is exactly the voxel set.
//!
//! Note: assets store voxel *shells* (conservative surface voxelization, the interior is
//! never filled), so merging only acts on nodes that are full *in the stored voxels* —
//! thick or flat-and-blocky surfaces merge, thin curved shells barely do. The counts
//! reported here are what the GPU really receives.
//!
//! Packing ([`Cube`], 8 bytes): the cube's minimum cell at the level (16 bits per axis, as
//! [`PackedVoxel`](crate::asset::PackedVoxel)) and log2 of its edge in cells. The original
//! instanced cube rasterization used four 32-bit floats (16 bytes) per cube.

use bytemuck::{Pod, Zeroable};

use crate::asset::{LodLevel, MAX_LEVEL};
use crate::svo::{morton_decode, morton_encode};

/// Bytes of one [`Cube`] on the GPU.
pub const CUBE_BYTES: usize = 8;

/// One cube instance, packed for the GPU (WGSL mirror `Cube` in `shaders/cube_raster.wgsl`).
///
/// - `xy`: minimum cell x in bits 0..16, y in bits 16..32;
/// - `z_size`: minimum cell z in bits 0..16, log2 of the edge length in cells in bits
///   16..21 (0 = one voxel; at most the level, 16).
///
/// The cube covers cells `min .. min + 2^log2_size` on every axis; `min` is a multiple of
/// `2^log2_size` (an octree node).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct Cube {
    /// x (low 16 bits) and y (high 16 bits) of the minimum cell.
    pub xy: u32,
    /// z of the minimum cell (low 16 bits) and log2 of the edge length (bits 16..21).
    pub z_size: u32,
}

impl Cube {
    /// Packs a cube; `min` components must be < 2^16 and `log2_size` ≤ 16.
    pub fn new(min: [u32; 3], log2_size: u32) -> Self {
        debug_assert!(min.iter().all(|&c| c < 1 << 16) && log2_size <= MAX_LEVEL);
        Self {
            xy: (min[0] & 0xffff) | (min[1] << 16),
            z_size: (min[2] & 0xffff) | (log2_size << 16),
        }
    }

    /// The minimum cell.
    pub fn min(&self) -> [u32; 3] {
        [self.xy & 0xffff, self.xy >> 16, self.z_size & 0xffff]
    }

    /// log2 of the edge length in cells.
    pub fn log2_size(&self) -> u32 {
        (self.z_size >> 16) & 0x1f
    }

    /// Edge length in cells.
    pub fn size(&self) -> u32 {
        1 << self.log2_size()
    }

    /// Whether `cell` lies inside the cube.
    pub fn contains(&self, cell: [u32; 3]) -> bool {
        let (min, s) = (self.min(), self.size());
        (0..3).all(|a| cell[a] >= min[a] && cell[a] - min[a] < s)
    }
}

/// Errors of building a cube list.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CubeListError {
    /// The level is finer than cube packing (16 bits per axis) allows.
    #[error("level {level} is above the highest supported level {MAX_LEVEL}")]
    LevelTooHigh {
        /// The level asked for.
        level: u32,
    },
    /// A cell lies outside the level's grid.
    #[error("cell {cell:?} lies outside the 2^{level} grid")]
    CellOutsideGrid {
        /// The cell.
        cell: [u32; 3],
        /// The grid level.
        level: u32,
    },
}

/// The cubes drawn for one LOD level (one instance each).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CubeList {
    /// Grid level the cube coordinates refer to.
    pub level: u32,
    /// Whether full octree nodes were merged.
    pub merged: bool,
    /// The cubes, disjoint, in Morton order of their minimum cell.
    pub cubes: Vec<Cube>,
    /// How many voxels they cover (the level's voxel count).
    pub voxel_count: usize,
}

impl CubeList {
    /// The cubes of an asset's LOD level (see [`CubeList::from_cells`]).
    pub fn from_lod(lod: &LodLevel, merge_full_nodes: bool) -> Result<Self, CubeListError> {
        Self::from_cells(
            lod.level,
            lod.point_cloud.voxels.iter().map(|v| v.cell()),
            merge_full_nodes,
        )
    }

    /// The cubes covering `cells` (duplicates count once) of a `2^level` grid: one unit
    /// cube per cell, or, with `merge_full_nodes`, one cube per maximal completely full
    /// octree node.
    pub fn from_cells(
        level: u32,
        cells: impl IntoIterator<Item = [u32; 3]>,
        merge_full_nodes: bool,
    ) -> Result<Self, CubeListError> {
        if level > MAX_LEVEL {
            return Err(CubeListError::LevelTooHigh { level });
        }
        let n = 1u64 << level;
        let mut codes = Vec::new();
        for cell in cells {
            if cell.iter().any(|&c| u64::from(c) >= n) {
                return Err(CubeListError::CellOutsideGrid { cell, level });
            }
            codes.push(morton_encode(cell));
        }
        codes.sort_unstable();
        codes.dedup();
        let voxel_count = codes.len();
        // (Morton code of the node at its size, log2 size) of every emitted cube.
        let mut emitted: Vec<(u64, u32)> = Vec::new();
        let mut full = codes;
        let mut log2 = 0;
        while merge_full_nodes && log2 < level && !full.is_empty() {
            // `full`: sorted codes of the full nodes of edge 2^log2; a run of 8 with one
            // parent is a full parent, anything else is emitted at this size.
            let mut parents = Vec::with_capacity(full.len() / 8);
            let mut i = 0;
            while i < full.len() {
                let parent = full[i] >> 3;
                let mut j = i + 1;
                while j < full.len() && full[j] >> 3 == parent {
                    j += 1;
                }
                if j - i == 8 {
                    parents.push(parent);
                } else {
                    emitted.extend(full[i..j].iter().map(|&c| (c, log2)));
                }
                i = j;
            }
            full = parents;
            log2 += 1;
        }
        emitted.extend(full.iter().map(|&c| (c, log2)));
        // Morton order of the minimum cell: a node code at size 2^k shifted left by 3k.
        emitted.sort_unstable_by_key(|&(c, k)| c << (3 * k));
        let cubes = emitted
            .into_iter()
            .map(|(c, k)| Cube::new(morton_decode(c).map(|v| v << k), k))
            .collect();
        Ok(Self {
            level,
            merged: merge_full_nodes,
            cubes,
            voxel_count,
        })
    }

    /// Number of cubes (instances drawn).
    pub fn len(&self) -> usize {
        self.cubes.len()
    }

    /// Whether there is no cube.
    pub fn is_empty(&self) -> bool {
        self.cubes.is_empty()
    }

    /// Bytes of the instance data sent to the GPU.
    pub fn bytes(&self) -> usize {
        self.cubes.len() * CUBE_BYTES
    }

    /// `counts[k]`: how many cubes have an edge of `2^k` cells (`k` in `0..=level`).
    pub fn size_histogram(&self) -> Vec<usize> {
        let mut counts = vec![0; self.level as usize + 1];
        for c in &self.cubes {
            counts[c.log2_size() as usize] += 1;
        }
        counts
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use proptest::prelude::*;

    use super::*;

    fn block(min: [u32; 3], size: u32) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        for z in 0..size {
            for y in 0..size {
                for x in 0..size {
                    out.push([min[0] + x, min[1] + y, min[2] + z]);
                }
            }
        }
        out
    }

    /// Every cell of every cube, failing on an overlap.
    fn covered(list: &CubeList) -> HashSet<[u32; 3]> {
        let mut set = HashSet::new();
        for c in &list.cubes {
            for cell in block(c.min(), c.size()) {
                assert!(set.insert(cell), "cell {cell:?} covered twice");
            }
        }
        set
    }

    #[test]
    fn cube_packing_round_trips() {
        let c = Cube::new([65535, 1234, 40000], 16);
        assert_eq!(c.min(), [65535, 1234, 40000]);
        assert_eq!(c.log2_size(), 16);
        assert_eq!(std::mem::size_of::<Cube>(), CUBE_BYTES);
    }

    #[test]
    fn a_full_block_is_one_cube() {
        for k in 0..=4 {
            let min = [3 << k, 1 << k, 0];
            let list = CubeList::from_cells(6, block(min, 1 << k), true).unwrap();
            assert_eq!(list.cubes, vec![Cube::new(min, k)], "k = {k}");
            assert_eq!(list.voxel_count, 1 << (3 * k));
            assert_eq!(list.bytes(), 8);
        }
        // The whole grid: the root.
        let list = CubeList::from_cells(3, block([0; 3], 8), true).unwrap();
        assert_eq!(list.cubes, vec![Cube::new([0; 3], 3)]);
    }

    #[test]
    fn a_block_not_aligned_to_a_node_does_not_merge_across_nodes() {
        // 2³ voxels straddling the node boundary at 1..3: no full node.
        let list = CubeList::from_cells(3, block([1, 1, 1], 2), true).unwrap();
        assert_eq!(list.len(), 8);
    }

    #[test]
    fn removing_one_voxel_splits_the_path_to_the_root() {
        // A full 8³ block without one voxel: along its path, at each of the 3 sizes (1, 2,
        // 4), the 7 siblings stay: 7 unit cubes + 7 cubes of 2 + 7 cubes of 4.
        let mut cells = block([0; 3], 8);
        cells.retain(|&c| c != [5, 2, 7]);
        let list = CubeList::from_cells(4, cells, true).unwrap();
        assert_eq!(list.len(), 21);
        assert_eq!(list.size_histogram(), vec![7, 7, 7, 0, 0]);
        assert_eq!(list.voxel_count, 511);
        assert!(!covered(&list).contains(&[5, 2, 7]));
    }

    #[test]
    fn without_merging_every_voxel_is_one_cube() {
        let cells = block([2, 0, 4], 4);
        let list = CubeList::from_cells(4, cells.iter().copied(), false).unwrap();
        assert_eq!(list.len(), 64);
        assert!(list.cubes.iter().all(|c| c.log2_size() == 0));
        assert_eq!(covered(&list), cells.into_iter().collect());
    }

    #[test]
    fn empty_and_invalid_inputs() {
        let list = CubeList::from_cells(5, [], true).unwrap();
        assert!(list.is_empty());
        assert_eq!(
            CubeList::from_cells(17, [], true),
            Err(CubeListError::LevelTooHigh { level: 17 })
        );
        assert_eq!(
            CubeList::from_cells(2, [[4, 0, 0]], true),
            Err(CubeListError::CellOutsideGrid {
                cell: [4, 0, 0],
                level: 2
            })
        );
        // Level 0: the single cell is the root.
        let list = CubeList::from_cells(0, [[0, 0, 0]], true).unwrap();
        assert_eq!(list.cubes, vec![Cube::new([0; 3], 0)]);
    }

    #[test]
    fn cubes_are_in_morton_order_of_their_minimum_cell() {
        let mut cells = block([0; 3], 4);
        cells.extend(block([4, 4, 4], 2));
        cells.push([7, 0, 0]);
        let list = CubeList::from_cells(3, cells, true).unwrap();
        let keys: Vec<_> = list.cubes.iter().map(|c| morton_encode(c.min())).collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:?}");
    }

    proptest! {
        #[test]
        fn cubes_are_disjoint_and_cover_exactly_the_voxels(
            // Dense-ish random sets at level 3 (so full nodes occur) plus full blocks.
            cells in proptest::collection::vec((0u32..8, 0u32..8, 0u32..8), 0..400),
            blocks in proptest::collection::vec((0u32..4, 0u32..4, 0u32..4, 0u32..2), 0..4),
            merge in any::<bool>(),
        ) {
            let mut input: Vec<[u32; 3]> = cells.iter().map(|&(x, y, z)| [x, y, z]).collect();
            for &(x, y, z, k) in &blocks {
                let s = 2 << k;
                input.extend(block([x * 2 % (8 - s + 1), y * 2 % (8 - s + 1), z * 2 % (8 - s + 1)], s));
            }
            let expected: HashSet<[u32; 3]> = input.iter().copied().collect();
            let list = CubeList::from_cells(3, input, merge).unwrap();
            prop_assert_eq!(list.voxel_count, expected.len());
            prop_assert_eq!(covered(&list), expected.clone());
            if !merge {
                prop_assert_eq!(list.len(), expected.len());
            }
            // Every cube is an aligned octree node, and merged cubes are maximal: no 8
            // sibling cubes of one size remain.
            let mut per_parent = std::collections::HashMap::new();
            for c in &list.cubes {
                let (min, k) = (c.min(), c.log2_size());
                prop_assert!(min.iter().all(|&v| v % (1 << k) == 0));
                if merge && k < 3 {
                    *per_parent.entry((min.map(|v| v >> (k + 1)), k)).or_insert(0) += 1;
                }
            }
            prop_assert!(per_parent.values().all(|&n| n < 8));
        }
    }
}
