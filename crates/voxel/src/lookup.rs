//! The sparse lookup of one LOD level: a 64-ary occupancy tree whose leaves rank voxels.
//!
//! SSBVB's sparse 3D lookup texture maps a cell to its voxel. Stored as a virtual texture
//! of 16³ pages of `u32`s it cost 16 KiB per page whatever the page held
//! (docs/architecture.md compares the bytes per voxel). Here every node covers 4³ children
//! and holds only a 64-bit occupancy mask and one base index (12 bytes):
//!
//! - the root covers `4^depth ≥ 2^level` cells per axis, a node at depth `k` covers
//!   `4^(depth - k)`, a node at depth `depth - 1` (a *leaf*) covers 4³ cells;
//! - the child (or cell) at local coordinates `l ∈ [0, 4)³` is bit
//!   `(l.x & 1) | (l.y & 1) << 1 | (l.z & 1) << 2 | (l.x >> 1) << 3 | (l.y >> 1) << 4 | (l.z >> 1) << 5`
//!   of the mask: the Morton order of the 2-bit local coordinates;
//! - an inner node's children are stored contiguously in bit order, only the present ones;
//!   its base is the index of its first child (relative to the root), so child `b` is at
//!   `base + popcount(mask & (2^b - 1))`;
//! - a leaf's base is the id of its first voxel, so the voxel in cell bit `b` has id
//!   `base + popcount(mask & (2^b - 1))`.
//!
//! Because every level's digit is a Morton digit, walking the tree in bit order visits the
//! cells in Morton order, so **voxel id = Morton rank of the cell**: exactly the index in
//! a prepared point cloud, and no id is stored anywhere. A surface voxel costs about one
//! byte of lookup (docs/benchmarks.md, "Compact voxels"), and every node is also an
//! empty-space skip: a ray in an absent child of size `4^m` jumps over it in one step (see
//! `reference/dda.rs` and `shaders/sparse_march.inc.wgsl`).
//!
//! Nodes are stored breadth first (root, all depth-1 nodes, ..., all leaves), each depth
//! in Morton order of its nodes.

use crate::svo::{morton_decode, morton_encode};

/// Highest supported grid level (cells are packed in 16 bits per axis on the GPU).
pub const MAX_LEVEL: u32 = 16;

/// Words per node in [`SparseLookup::nodes`]: mask low, mask high, base.
pub const NODE_WORDS: usize = 3;

/// Cells per axis of the 16³ region the proxy mesh and the culling test are built from.
pub const PAGE_SIZE: u32 = 16;

/// The 64-ary occupancy tree of one LOD level (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SparseLookup {
    /// Grid level (2^level cells per axis).
    pub level: u32,
    /// Tree depth: `max(1, ceil(level / 2))`; the root covers `4^depth` cells per axis.
    pub depth: u32,
    /// Nodes, [`NODE_WORDS`] words each (mask low, mask high, base), breadth first.
    pub nodes: Vec<u32>,
}

impl Default for SparseLookup {
    fn default() -> Self {
        Self::from_codes(0, &[])
    }
}

/// Tree depth of a level: the smallest `d ≥ 1` with `4^d ≥ 2^level`.
pub fn tree_depth(level: u32) -> u32 {
    level.div_ceil(2).max(1)
}

/// Bit of a child in its parent's mask: the Morton order of 2-bit local coordinates.
pub fn child_bit(l: [u32; 3]) -> u32 {
    (l[0] & 1)
        | (l[1] & 1) << 1
        | (l[2] & 1) << 2
        | (l[0] >> 1) << 3
        | (l[1] >> 1) << 4
        | (l[2] >> 1) << 5
}

/// Ones of `mask` below `bit`.
fn rank(mask: u64, bit: u32) -> u32 {
    (mask & ((1u64 << bit) - 1)).count_ones()
}

impl SparseLookup {
    /// Builds the lookup of a level from strictly increasing Morton codes of its cells
    /// (voxel id = index). The tree is built leaves first, one linear pass per depth.
    ///
    /// # Panics
    ///
    /// When `level > MAX_LEVEL`, or (in debug builds) when the codes are not strictly
    /// increasing or lie outside the grid; [`crate::cache::read_cache`] checks both before
    /// calling.
    pub fn from_codes(level: u32, codes: &[u64]) -> Self {
        let mut b = LookupBuilder::new(level);
        b.extend(codes);
        b.finish()
    }

    /// Builds the tree from its leaves (key, mask, first voxel), in key order.
    fn from_leaves(level: u32, leaves: Vec<(u64, u64, u32)>) -> Self {
        let depth = tree_depth(level);
        // Per depth, from the leaves up: (key, mask, first child or voxel).
        let mut per_depth: Vec<Vec<(u64, u64, u32)>> = Vec::with_capacity(depth as usize);
        let mut children: Vec<u64> = Vec::new();
        let mut level_nodes = leaves;
        for _ in 0..depth {
            children.clear();
            children.extend(level_nodes.iter().map(|n| n.0));
            per_depth.push(std::mem::take(&mut level_nodes));
            for (i, &k) in children.iter().enumerate() {
                group(&mut level_nodes, k, i as u32);
            }
        }
        // `level_nodes` now groups the root's key (0) — one past the root: discard it.
        per_depth.reverse(); // root first
        if per_depth[0].is_empty() {
            per_depth[0].push((0, 0, 0));
        }
        let total: usize = per_depth.iter().map(Vec::len).sum();
        let mut nodes = Vec::with_capacity(total * NODE_WORDS);
        let mut next_depth_start = 0u32;
        for (k, d) in per_depth.iter().enumerate() {
            next_depth_start += d.len() as u32;
            let leaf = k + 1 == per_depth.len();
            for &(_, mask, first) in d {
                let base = if leaf || mask == 0 {
                    first
                } else {
                    next_depth_start + first
                };
                nodes.extend_from_slice(&[mask as u32, (mask >> 32) as u32, base]);
            }
        }
        Self {
            level,
            depth,
            nodes,
        }
    }

    /// Builds the lookup of a level from its voxels' cells, which must lie inside the grid
    /// (a repeated cell counts once). Voxel ids are Morton ranks (see the module docs): the
    /// index of the cell in `cells` only when `cells` is in Morton order without repeats,
    /// as every prepared point cloud is.
    pub fn from_cells(level: u32, cells: impl Iterator<Item = [u32; 3]>) -> Self {
        let mut codes: Vec<u64> = cells.map(morton_encode).collect();
        codes.sort_unstable();
        codes.dedup();
        Self::from_codes(level, &codes)
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len() / NODE_WORDS
    }

    fn node(&self, i: usize) -> (u64, u32) {
        let w = &self.nodes[i * NODE_WORDS..][..NODE_WORDS];
        (w[0] as u64 | (w[1] as u64) << 32, w[2])
    }

    /// Number of voxels (cells set in the leaves).
    pub fn voxel_count(&self) -> u64 {
        let first_leaf = self.node_count() - self.leaf_count();
        (first_leaf..self.node_count())
            .map(|i| self.node(i).0.count_ones() as u64)
            .sum()
    }

    fn leaf_count(&self) -> usize {
        // Leaves are the last depth: count the children of depth `depth - 2` (or 1: root).
        let mut start = 0usize;
        let mut count = 1usize;
        for _ in 1..self.depth {
            let children: usize = (start..start + count)
                .map(|i| self.node(i).0.count_ones() as usize)
                .sum();
            start += count;
            count = children;
        }
        count
    }

    /// Whether the aligned region of `4^m` cells per axis at region coordinates `region`
    /// holds a voxel (`m = 0`: the cell itself; `m ≥ depth`: the whole grid, region 0).
    pub fn region_occupied(&self, m: u32, region: [u32; 3]) -> bool {
        let m = m.min(self.depth);
        let digits = self.depth - m;
        if region.iter().any(|&r| (r as u64) >> (2 * digits) != 0) {
            return false;
        }
        if digits == 0 {
            return self.node(0).0 != 0;
        }
        self.descend(morton_encode(region), digits).is_some()
    }

    /// Walks `digits` Morton digits (6 bits each, most significant first) of `code` from
    /// the root; the rank-addressed index reached (a node, or a voxel id after `depth`
    /// digits), or `None` at the first absent child.
    fn descend(&self, code: u64, digits: u32) -> Option<u32> {
        let mut node = 0usize;
        for k in 0..digits {
            let bit = ((code >> (6 * (digits - 1 - k))) & 63) as u32;
            let (mask, base) = self.node(node);
            if mask >> bit & 1 == 0 {
                return None;
            }
            let next = base + rank(mask, bit);
            if k + 1 == self.depth {
                return Some(next);
            }
            node = next as usize;
        }
        Some(node as u32)
    }

    /// The voxel id at `cell`, or `None` when the cell is empty or outside the grid.
    pub fn get(&self, cell: [u32; 3]) -> Option<u32> {
        let n = 1u32 << self.level;
        if cell.iter().any(|&c| c >= n) {
            return None;
        }
        self.descend(morton_encode(cell), self.depth)
    }

    /// Whether the 16³ region `page` (in units of [`PAGE_SIZE`] cells; the whole grid for
    /// levels below 4) holds a voxel.
    pub fn page_occupied(&self, page: [u32; 3]) -> bool {
        self.region_occupied(2, page)
    }

    /// Number of occupied 16³ regions ([`Self::page_occupied`]).
    pub fn occupied_pages(&self) -> u64 {
        if self.depth < 2 {
            return u64::from(self.node(0).0 != 0);
        }
        // Nodes at depth `depth - 2` cover 16³ cells each: count them.
        let mut start = 0usize;
        let mut count = 1usize;
        for _ in 0..self.depth - 2 {
            let children: usize = (start..start + count)
                .map(|i| self.node(i).0.count_ones() as usize)
                .sum();
            start += count;
            count = children;
        }
        if self.node(0).0 == 0 { 0 } else { count as u64 }
    }

    /// Every occupied cell, in Morton order (so the `i`-th has voxel id `i`).
    pub fn cells(&self) -> Vec<[u32; 3]> {
        self.occupied_regions(0)
    }

    /// Every occupied aligned region of `4^m` cells per axis (region coordinates, Morton
    /// order); `m ≥ depth`: the whole grid as region 0 when it holds a voxel.
    pub fn occupied_regions(&self, m: u32) -> Vec<[u32; 3]> {
        let digits = self.depth - m.min(self.depth);
        let mut out = Vec::new();
        if digits == 0 {
            if self.node(0).0 != 0 {
                out.push([0; 3]);
            }
        } else {
            self.walk(0, 0, 0, digits, &mut out);
        }
        out
    }

    fn walk(&self, node: usize, k: u32, prefix: u64, digits: u32, out: &mut Vec<[u32; 3]>) {
        let (mut mask, base) = self.node(node);
        let mut i = 0u32;
        while mask != 0 {
            let bit = mask.trailing_zeros();
            mask &= mask - 1;
            let code = prefix << 6 | bit as u64;
            if k + 1 == digits {
                out.push(morton_decode(code));
            } else {
                self.walk((base + i) as usize, k + 1, code, digits, out);
            }
            i += 1;
        }
    }

    /// Bytes of the node array (what the GPU uploads).
    pub fn bytes(&self) -> usize {
        4 * self.nodes.len()
    }

    /// Bytes a dense `u32` texture of the whole grid would take.
    pub fn dense_bytes(&self) -> u64 {
        4 * (1u64 << (3 * self.level))
    }
}

/// Builds a [`SparseLookup`] from a level's Morton codes fed in increasing order, a chunk
/// at a time (the streaming preparation never holds a level's codes at once): only the
/// leaves (24 bytes per 4³ brick) are kept until [`LookupBuilder::finish`].
#[derive(Debug, Clone)]
pub struct LookupBuilder {
    level: u32,
    leaves: Vec<(u64, u64, u32)>,
    count: u32,
    last: Option<u64>,
}

impl LookupBuilder {
    /// An empty builder of a level-`level` lookup.
    ///
    /// # Panics
    ///
    /// When `level > MAX_LEVEL`.
    pub fn new(level: u32) -> Self {
        assert!(level <= MAX_LEVEL, "level {level} above MAX_LEVEL");
        Self {
            level,
            leaves: Vec::new(),
            count: 0,
            last: None,
        }
    }

    /// Adds the next codes (strictly increasing, continuing the previous ones, inside the
    /// grid; checked in debug builds).
    pub fn extend(&mut self, codes: &[u64]) {
        for &c in codes {
            debug_assert!(self.last.is_none_or(|l| l < c), "codes not increasing");
            debug_assert!(c < 1u64 << (3 * self.level), "code outside the grid");
            self.last = Some(c);
            group(&mut self.leaves, c, self.count);
            self.count += 1;
        }
    }

    /// The lookup of every code added.
    pub fn finish(self) -> SparseLookup {
        SparseLookup::from_leaves(self.level, self.leaves)
    }
}

/// Counts the nodes of the lookup of codes fed in increasing order without building it
/// (what the streaming preparation reports for a level it never holds).
#[derive(Debug, Clone)]
pub struct NodeCounter {
    depth: u32,
    last: Option<u64>,
    nodes: u64,
}

impl NodeCounter {
    /// A counter for a level-`level` lookup.
    pub fn new(level: u32) -> Self {
        Self {
            depth: tree_depth(level),
            last: None,
            nodes: 0,
        }
    }

    /// Adds the next codes (strictly increasing, continuing the previous ones).
    pub fn extend(&mut self, codes: &[u64]) {
        for &c in codes {
            // A new node at every depth whose key (the code without its lower digits)
            // changes; the root (key 0) counts once.
            for j in 1..=self.depth {
                if self.last.is_none_or(|l| l >> (6 * j) != c >> (6 * j)) {
                    self.nodes += 1;
                }
            }
            self.last = Some(c);
        }
    }

    /// The node count of [`SparseLookup::from_codes`] on the codes added.
    pub fn nodes(&self) -> u64 {
        self.nodes.max(1)
    }
}

/// Appends `code` to the nodes being grouped by `code >> 6`: a new node when its key
/// differs from the last one (codes arrive in increasing order).
fn group(nodes: &mut Vec<(u64, u64, u32)>, code: u64, index: u32) {
    let key = code >> 6;
    let bit = 1u64 << (code & 63);
    match nodes.last_mut() {
        Some(last) if last.0 == key => last.1 |= bit,
        _ => nodes.push((key, bit, index)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn brute_region(cells: &HashSet<[u32; 3]>, m: u32, r: [u32; 3]) -> bool {
        let s = 1u32 << (2 * m);
        cells.iter().any(|c| (0..3).all(|a| c[a] / s == r[a]))
    }

    #[test]
    fn every_cell_has_its_morton_rank_and_empty_cells_none() {
        for level in [0u32, 1, 2, 3, 4, 5, 7] {
            let n = 1u32 << level;
            let cells: HashSet<[u32; 3]> = (0..300u32)
                .map(|i| [(i * 7) % n, (i * 13 + 1) % n, (i * 31 + 2) % n])
                .collect();
            let mut sorted: Vec<[u32; 3]> = cells.iter().copied().collect();
            sorted.sort_by_key(|&c| morton_encode(c));
            let l = SparseLookup::from_cells(level, cells.iter().copied());
            assert_eq!(l.depth, tree_depth(level));
            assert_eq!(l.cells(), sorted, "level {level}");
            assert_eq!(l.voxel_count(), sorted.len() as u64);
            for (id, c) in sorted.iter().enumerate() {
                assert_eq!(l.get(*c), Some(id as u32), "level {level} cell {c:?}");
            }
            for x in 0..n.min(9) {
                for y in 0..n.min(9) {
                    for z in 0..n.min(9) {
                        let c = [x, y, z];
                        assert_eq!(l.get(c).is_some(), cells.contains(&c));
                    }
                }
            }
            assert_eq!(l.get([n, 0, 0]), None);
            assert_eq!(l.get([0, 0, u32::MAX]), None);
            for m in 0..=l.depth + 1 {
                let mut regions: Vec<[u32; 3]> = {
                    let s = 1u32 << (2 * m.min(l.depth));
                    let set: HashSet<[u32; 3]> = cells.iter().map(|c| c.map(|v| v / s)).collect();
                    set.into_iter().collect()
                };
                regions.sort_by_key(|&c| morton_encode(c));
                assert_eq!(l.occupied_regions(m), regions, "level {level} m {m}");
                let s = 1u32 << (2 * m.min(l.depth));
                for r in [[0, 0, 0], [1, 0, 0], [0, 1, 1], [2, 3, 1], [5, 0, 0]] {
                    let expect = brute_region(&cells, m.min(l.depth), r)
                        && r.iter()
                            .all(|&v| (v as u64) * (s as u64) < 1u64 << (2 * l.depth));
                    assert_eq!(l.region_occupied(m, r), expect, "level {level} m {m} {r:?}");
                }
            }
        }
    }

    #[test]
    fn pages_are_the_occupied_16_cubed_regions() {
        for level in [2u32, 4, 5, 7] {
            let n = 1u32 << level;
            let cells: HashSet<[u32; 3]> = (0..200u32)
                .map(|i| [(i * 5) % n, (i * 11 + 3) % n, (i * i) % n])
                .collect();
            let l = SparseLookup::from_cells(level, cells.iter().copied());
            let pages: HashSet<[u32; 3]> = cells.iter().map(|c| c.map(|v| v / 16)).collect();
            assert_eq!(l.occupied_pages(), pages.len() as u64, "level {level}");
            let per_axis = (n / 16).max(1);
            for z in 0..per_axis + 1 {
                for y in 0..per_axis {
                    for x in 0..per_axis {
                        let p = [x, y, z];
                        assert_eq!(
                            l.page_occupied(p),
                            pages.contains(&p),
                            "level {level} {p:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_node_counter_counts_what_the_builder_builds() {
        for level in [0u32, 1, 2, 3, 5, 8] {
            let n = 1u32 << level;
            let mut codes: Vec<u64> = (0..700u32)
                .map(|i| morton_encode([(i * 7) % n, (i * i * 13 + 1) % n, (i * 31 + 2) % n]))
                .collect();
            codes.sort_unstable();
            codes.dedup();
            let mut counter = NodeCounter::new(level);
            for chunk in codes.chunks(17) {
                counter.extend(chunk);
            }
            let built = SparseLookup::from_codes(level, &codes);
            assert_eq!(counter.nodes(), built.node_count() as u64, "level {level}");
        }
        assert_eq!(NodeCounter::new(6).nodes(), 1);
    }

    #[test]
    fn nodes_cost_twelve_bytes_and_an_empty_lookup_is_one_empty_root() {
        let empty = SparseLookup::from_codes(6, &[]);
        assert_eq!(empty.nodes, vec![0, 0, 0]);
        // A dense `u32` texture of the grid, what the lookup is compared with.
        assert_eq!(empty.dense_bytes(), 4 * 64 * 64 * 64);
        assert_eq!(SparseLookup::from_codes(0, &[0]).dense_bytes(), 4);
        assert_eq!(empty.get([0, 0, 0]), None);
        assert!(!empty.region_occupied(3, [0, 0, 0]));
        assert!(empty.cells().is_empty());
        assert_eq!(empty.voxel_count(), 0);
        // One voxel at level 6 (depth 3): a root, one inner node and one leaf.
        let one = SparseLookup::from_cells(6, [[63, 0, 5]].into_iter());
        assert_eq!(one.node_count(), 3);
        assert_eq!(one.bytes(), 36);
        assert_eq!(one.get([63, 0, 5]), Some(0));
        // Bits are Morton digits: (63, 0, 5) has top digit (bits 4..6) x=3, y=0, z=0, and
        // leaf digit (bits 0..2) x=3, y=0, z=1.
        assert_eq!(
            one.nodes[0] as u64 | (one.nodes[1] as u64) << 32,
            1 << child_bit([3, 0, 0])
        );
        assert_eq!(
            one.nodes[6] as u64 | (one.nodes[7] as u64) << 32,
            1 << child_bit([3, 0, 1])
        );
        assert_eq!(child_bit([1, 0, 0]), 1);
        assert_eq!(child_bit([0, 1, 0]), 2);
        assert_eq!(child_bit([0, 0, 2]), 32);
        assert_eq!(child_bit([3, 3, 3]), 63);
    }

    #[test]
    fn a_full_grid_and_bits_beyond_32_rank_correctly() {
        // Level 3: 512 cells, every one set; ids are Morton codes.
        let cells: Vec<[u32; 3]> = (0..512u64).map(morton_decode).collect();
        let l = SparseLookup::from_cells(3, cells.iter().copied());
        for (i, c) in cells.iter().enumerate() {
            assert_eq!(l.get(*c), Some(i as u32));
        }
        // Only cells with high bits: ranks must not count the low word twice.
        let high: Vec<[u32; 3]> = [[0, 0, 2], [3, 3, 3], [1, 1, 3]].to_vec();
        let l = SparseLookup::from_cells(2, high.iter().copied());
        let mut sorted = high.clone();
        sorted.sort_by_key(|&c| morton_encode(c));
        for (i, c) in sorted.iter().enumerate() {
            assert_eq!(l.get(*c), Some(i as u32));
        }
    }
}
