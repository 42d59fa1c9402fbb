//! The prepared voxel asset: what the renderer uploads and the reference caster reads.
//!
//! These types are the contract between the CPU preparation (voxelization, SVO, LOD) and
//! every consumer (GPU uploads, the CPU reference ray caster, the asset cache). Layouts
//! marked `#[repr(C)]` are uploaded to the GPU as they are; WGSL mirrors them.

use bytemuck::{Pod, Zeroable};

use crate::model::ObjectSpace;

/// Edge length of a sparse-lookup page in cells (pages are `PAGE_SIZE³` cells).
pub const PAGE_SIZE: u32 = 16;
/// Cells per page (`16³ = 4096`).
pub const PAGE_CELLS: usize = (PAGE_SIZE * PAGE_SIZE * PAGE_SIZE) as usize;
/// Page-table entry of a page that holds no voxel.
pub const EMPTY_PAGE: u32 = u32::MAX;
/// Highest supported grid level (positions are packed in 16 bits per axis).
pub const MAX_LEVEL: u32 = 16;

/// One voxel of a point cloud, packed into 16 bytes for the GPU.
///
/// - `xy`: cell x in bits 0..16, cell y in bits 16..32;
/// - `z_normal`: cell z in bits 0..16, octahedral-encoded unit normal in bits 16..32
///   (u in bits 16..24, v in bits 24..32, each `round((e * 0.5 + 0.5) * 255)`);
/// - `color`: linear RGBA8, r in bits 0..8 … a in bits 24..32;
/// - `uv`: texture coordinate as two 16-bit unorms (u low, v high), 0 if the model has none.
///
/// Cell coordinates are at the level the point cloud belongs to; the cell's box in object
/// space is `[-1 + c·s, -1 + (c+1)·s]` with `s = 2 / 2^level`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct PackedVoxel {
    /// x (low 16 bits) and y (high 16 bits) cell coordinates.
    pub xy: u32,
    /// z cell coordinate (low 16 bits) and octahedral normal (high 16 bits).
    pub z_normal: u32,
    /// Linear RGBA8 colour.
    pub color: u32,
    /// Texture coordinate, two 16-bit unorms.
    pub uv: u32,
}

/// The voxel point cloud of one LOD level: voxels sorted in Morton order of their cell.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    /// The packed voxels; a voxel's id is its index here.
    pub voxels: Vec<PackedVoxel>,
}

/// The paper's sparse 3D lookup texture of one LOD level, as a virtual texture.
///
/// The grid of `2^level` cells per axis is cut into pages of `PAGE_SIZE³` cells. The page
/// table has one entry per page (`pages_per_axis³`, x fastest, then y, then z): the index
/// of the page in `pool`, or [`EMPTY_PAGE`]. Only pages holding at least one voxel are
/// resident. A resident page is `PAGE_CELLS` consecutive `u32`s in `pool` (cell x fastest,
/// then y, then z, coordinates local to the page), each `voxel id + 1`, or 0 when empty.
/// For levels below 4 the grid is smaller than a page: one page, cells outside the grid 0.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SparseLookup {
    /// Grid level (2^level cells per axis).
    pub level: u32,
    /// Pages per axis: `max(1, 2^level / PAGE_SIZE)`.
    pub pages_per_axis: u32,
    /// One entry per page: pool page index or [`EMPTY_PAGE`].
    pub page_table: Vec<u32>,
    /// Resident pages, `PAGE_CELLS` entries each: voxel id + 1, or 0.
    pub pool: Vec<u32>,
    /// Coarse occupancy for skipping large empty regions: one bit per block of
    /// `COARSE_PAGES³` pages (x fastest), set when any page of the block is resident.
    pub coarse: Vec<u32>,
    /// Blocks per axis of `coarse`: `ceil(pages_per_axis / COARSE_PAGES)`.
    pub coarse_per_axis: u32,
}

/// Pages per axis in one block of [`SparseLookup::coarse`].
pub const COARSE_PAGES: u32 = 4;

/// A closed triangle mesh in object space that encloses every voxel of the asset.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProxyMesh {
    /// Vertex positions in object space.
    pub positions: Vec<[f32; 3]>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

/// One LOD level of an asset.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LodLevel {
    /// Grid level of this LOD (2^level cells per axis).
    pub level: u32,
    /// The voxel point cloud.
    pub point_cloud: PointCloud,
    /// The sparse lookup: voxel id + 1 per cell.
    pub lookup: SparseLookup,
    /// Conservative proxy mesh enclosing every voxel box of this level.
    pub proxy: ProxyMesh,
}

/// A prepared voxel asset: every LOD from level 0 up to the finest.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelAsset {
    /// Where the model's own coordinates map into object space.
    pub object_space: ObjectSpace,
    /// `lods[l]` is level `l`; the last is the finest (the voxelization level).
    pub lods: Vec<LodLevel>,
}

impl PackedVoxel {
    /// Packs a voxel. `cell` components must be < 2^16; `normal` need not be unit length
    /// (a zero or non-finite normal packs as +Z so no NaN reaches the GPU); `color` is
    /// linear RGBA in [0, 1] (clamped); `uv` in [0, 1] (wrapped into it).
    pub fn new(cell: [u32; 3], normal: [f32; 3], color: [f32; 4], uv: [f32; 2]) -> Self {
        debug_assert!(cell.iter().all(|&c| c < 1 << 16));
        let [u, v] = encode_octahedral(normal);
        let c = |x: f32| (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
        let q = |x: f32| {
            let f = x - x.floor();
            let f = if f.is_finite() { f } else { 0.0 };
            (f * 65535.0 + 0.5) as u32
        };
        Self {
            xy: (cell[0] & 0xffff) | (cell[1] << 16),
            z_normal: (cell[2] & 0xffff) | (u << 16) | (v << 24),
            color: c(color[0]) | (c(color[1]) << 8) | (c(color[2]) << 16) | (c(color[3]) << 24),
            uv: q(uv[0]) | (q(uv[1]) << 16),
        }
    }

    /// Cell coordinates at the point cloud's level.
    pub fn cell(&self) -> [u32; 3] {
        [self.xy & 0xffff, self.xy >> 16, self.z_normal & 0xffff]
    }

    /// Decoded unit normal (up to the 8-bit octahedral quantization, ~0.8° worst case).
    pub fn normal(&self) -> [f32; 3] {
        decode_octahedral((self.z_normal >> 16) & 0xff, self.z_normal >> 24)
    }

    /// Linear RGBA colour in [0, 1].
    pub fn color(&self) -> [f32; 4] {
        let b = |s: u32| ((self.color >> s) & 0xff) as f32 / 255.0;
        [b(0), b(8), b(16), b(24)]
    }

    /// Texture coordinate in [0, 1].
    pub fn uv(&self) -> [f32; 2] {
        [
            (self.uv & 0xffff) as f32 / 65535.0,
            (self.uv >> 16) as f32 / 65535.0,
        ]
    }
}

/// Octahedral encoding of a direction into two 8-bit unorms (Cigolle et al. 2014).
fn encode_octahedral(n: [f32; 3]) -> [u32; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    let (mut x, mut y, z) = if l1 > 0.0 && l1.is_finite() {
        (n[0] / l1, n[1] / l1, n[2] / l1)
    } else {
        (0.0, 0.0, 1.0)
    };
    if z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * ox.signum();
        y = (1.0 - ox.abs()) * oy.signum();
    }
    let q = |e: f32| ((e.clamp(-1.0, 1.0) * 0.5 + 0.5) * 255.0).round() as u32;
    [q(x), q(y)]
}

/// Inverse of [`encode_octahedral`]; always returns a unit vector.
fn decode_octahedral(u: u32, v: u32) -> [f32; 3] {
    let mut x = u as f32 / 255.0 * 2.0 - 1.0;
    let mut y = v as f32 / 255.0 * 2.0 - 1.0;
    let z = 1.0 - x.abs() - y.abs();
    if z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * ox.signum();
        y = (1.0 - ox.abs()) * oy.signum();
    }
    let len = (x * x + y * y + z * z).sqrt();
    [x / len, y / len, z / len]
}

impl SparseLookup {
    /// Builds the lookup of a level from its voxels' cells; voxel id = index in `cells`.
    /// Cells must be distinct and inside the grid (`< 2^level`).
    pub fn from_cells(level: u32, cells: impl ExactSizeIterator<Item = [u32; 3]>) -> Self {
        assert!(level <= MAX_LEVEL, "level {level} above MAX_LEVEL");
        let pages_per_axis = ((1u32 << level) / PAGE_SIZE).max(1);
        let ppa = pages_per_axis as usize;
        let mut page_table = vec![EMPTY_PAGE; ppa * ppa * ppa];
        let mut pool: Vec<u32> = Vec::new();
        for (id, c) in cells.enumerate() {
            let p = [c[0] / PAGE_SIZE, c[1] / PAGE_SIZE, c[2] / PAGE_SIZE];
            let pi = p[0] as usize + ppa * (p[1] as usize + ppa * p[2] as usize);
            if page_table[pi] == EMPTY_PAGE {
                page_table[pi] = (pool.len() / PAGE_CELLS) as u32;
                pool.resize(pool.len() + PAGE_CELLS, 0);
            }
            let base = page_table[pi] as usize * PAGE_CELLS;
            pool[base + local_index(c)] = id as u32 + 1;
        }
        let coarse_per_axis = pages_per_axis.div_ceil(COARSE_PAGES);
        let cpa = coarse_per_axis as usize;
        let mut coarse = vec![0u32; (cpa * cpa * cpa).div_ceil(32)];
        for z in 0..ppa {
            for y in 0..ppa {
                for x in 0..ppa {
                    if page_table[x + ppa * (y + ppa * z)] != EMPTY_PAGE {
                        let b = x / COARSE_PAGES as usize
                            + cpa * (y / COARSE_PAGES as usize + cpa * (z / COARSE_PAGES as usize));
                        coarse[b / 32] |= 1 << (b % 32);
                    }
                }
            }
        }
        Self {
            level,
            pages_per_axis,
            page_table,
            pool,
            coarse,
            coarse_per_axis,
        }
    }

    /// The voxel id at `cell`, or `None` when the cell is empty or outside the grid.
    pub fn get(&self, cell: [u32; 3]) -> Option<u32> {
        let n = 1u32 << self.level;
        if cell.iter().any(|&c| c >= n) {
            return None;
        }
        let ppa = self.pages_per_axis as usize;
        let p = cell.map(|c| (c / PAGE_SIZE) as usize);
        let page = self.page_table[p[0] + ppa * (p[1] + ppa * p[2])];
        if page == EMPTY_PAGE {
            return None;
        }
        let v = self.pool[page as usize * PAGE_CELLS + local_index(cell)];
        v.checked_sub(1)
    }

    /// Whether the page containing `cell` is resident (cells outside the grid: `false`).
    pub fn page_resident(&self, page: [u32; 3]) -> bool {
        if page.iter().any(|&p| p >= self.pages_per_axis) {
            return false;
        }
        let ppa = self.pages_per_axis as usize;
        self.page_table[page[0] as usize + ppa * (page[1] as usize + ppa * page[2] as usize)]
            != EMPTY_PAGE
    }

    /// Whether the coarse block `block` (in units of `COARSE_PAGES` pages) holds any page.
    pub fn coarse_occupied(&self, block: [u32; 3]) -> bool {
        if block.iter().any(|&b| b >= self.coarse_per_axis) {
            return false;
        }
        let cpa = self.coarse_per_axis as usize;
        let b = block[0] as usize + cpa * (block[1] as usize + cpa * block[2] as usize);
        self.coarse[b / 32] & (1 << (b % 32)) != 0
    }

    /// Number of resident pages.
    pub fn resident_pages(&self) -> usize {
        self.pool.len() / PAGE_CELLS
    }

    /// Bytes of page table + pool + coarse occupancy.
    pub fn bytes(&self) -> usize {
        4 * (self.page_table.len() + self.pool.len() + self.coarse.len())
    }

    /// Bytes a dense `u32` texture of the whole grid would take.
    pub fn dense_bytes(&self) -> u64 {
        4 * (1u64 << (3 * self.level))
    }
}

/// Index of a cell inside its page (x fastest).
fn local_index(c: [u32; 3]) -> usize {
    let l = c.map(|v| (v % PAGE_SIZE) as usize);
    l[0] + PAGE_SIZE as usize * (l[1] + PAGE_SIZE as usize * l[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_voxel_round_trips() {
        let v = PackedVoxel::new(
            [65535, 7, 1234],
            [0.0, 0.0, -1.0],
            [1.0, 0.5, 0.0, 1.0],
            [0.25, 0.75],
        );
        assert_eq!(v.cell(), [65535, 7, 1234]);
        let n = v.normal();
        assert!((n[2] + 1.0).abs() < 1e-3, "{n:?}");
        assert_eq!(v.color()[0], 1.0);
        assert!((v.color()[1] - 0.5).abs() < 0.003);
        assert!((v.uv()[0] - 0.25).abs() < 1e-4 && (v.uv()[1] - 0.75).abs() < 1e-4);
        // Zero and NaN normals never decode to NaN.
        for bad in [[0.0; 3], [f32::NAN, 0.0, 0.0]] {
            let n = PackedVoxel::new([0; 3], bad, [0.0; 4], [0.0; 2]).normal();
            assert!(n.iter().all(|c| c.is_finite()));
        }
        // Octahedral quantization error stays under 1 degree over many directions.
        for i in 0..1000 {
            let t = i as f32 * 0.731;
            let p = i as f32 * 0.377;
            let d = [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
            let n = PackedVoxel::new([0; 3], d, [0.0; 4], [0.0; 2]).normal();
            let dot: f32 = (0..3).map(|k| n[k] * d[k]).sum();
            assert!(dot > 1.0f32.to_radians().cos(), "{d:?} -> {n:?}");
        }
    }

    #[test]
    fn sparse_lookup_finds_every_cell_and_nothing_else() {
        let cells = vec![[0, 0, 0], [17, 3, 40], [63, 63, 63], [16, 16, 16]];
        let l = SparseLookup::from_cells(6, cells.clone().into_iter());
        assert_eq!(l.pages_per_axis, 4);
        assert_eq!(l.resident_pages(), 4);
        for (i, c) in cells.iter().enumerate() {
            assert_eq!(l.get(*c), Some(i as u32));
        }
        assert_eq!(l.get([1, 0, 0]), None);
        assert_eq!(l.get([64, 0, 0]), None);
        assert!(l.page_resident([1, 0, 2]));
        assert!(!l.page_resident([2, 2, 2]));
        assert!(l.coarse_occupied([0, 0, 0]));
        // Levels below a page still work: one page.
        let small = SparseLookup::from_cells(1, [[1, 1, 0]].into_iter());
        assert_eq!(small.pages_per_axis, 1);
        assert_eq!(small.get([1, 1, 0]), Some(0));
        assert_eq!(small.get([2, 0, 0]), None);
    }
}
