//! RastaVox surface voxels: the boundary of a voxel model in 4 bytes per
//! voxel, cut into chunks, with a level-of-detail chain built by OR-merging face masks.
//!
//! A **surface voxel** is a solid voxel with at least one empty 6-neighbour (outside the
//! grid counts as empty). It stores its position inside its chunk (8 bits per axis, chunks
//! of at most 256³ cells) and a 6-bit mask of its boundary faces, bit `f` for face `f` in
//! the `VoxelSlot.face` order: 0..2 = −X/−Y/−Z, 3..5 = +X/+Y/+Z ([`SurfaceVoxel`], one
//! `u32`). Colour (linear RGBA8) and normal (the asset's 8-bit octahedral code) live in
//! side buffers, one `u32` each per voxel. Interior voxels (solid VOX/raw grids) drop out;
//! the shells the voxelizer writes keep almost every voxel.
//!
//! **Level of detail**: level `k + 1` of a chunk merges the runs of level-`k`
//! voxels that share a parent cell (`position >> 1`). The face masks are OR-ed, so thin
//! features grow instead of vanishing (a MIN on density); colours are averaged per channel
//! with integer rounding and normals by summing their octahedral (L1-unit) vectors and
//! encoding the sum. The chain runs down to one voxel per chunk. Voxels are kept in
//! chunk-major, then Morton order: RastaVox's radix sort on positions with the low bit
//! dropped is then a no-op on every level after the first, because a run of children is
//! contiguous in Morton order and the merged output comes out in order (the GPU build in
//! `ssbvb-gpu-build` sorts only the extraction's output, whose order atomics scramble).
//!
//! The merged model is *not* the asset's coarser LOD: an OR-merged voxel draws every face
//! any child had, also faces that now lie between two coarse voxels. [`SurfaceModel::face_lod`]
//! gives any (chunk, level) as a [`FaceLod`] for the CPU reference, which hits a voxel only
//! through a face in its mask ([`crate::reference`]), exactly as rasterizing the masked,
//! camera-facing faces does.
//!
//! This CPU path is the oracle of the GPU build (same voxels, masks and colours bit for
//! bit; normals within one octahedral step) and what tests and memory reports use.

use bytemuck::{Pod, Zeroable};
use glam::{DAffine3, DVec3, DVec4};

use crate::asset::{
    LodLevel, MAX_LEVEL, PackedVoxel, PointCloud, decode_octahedral, encode_octahedral,
};
use crate::camera::Camera;
use crate::lookup::SparseLookup;
use crate::model::cell_size;
use crate::svo::morton_encode;

/// Bytes of one [`SurfaceVoxel`].
pub const SURFACE_VOXEL_BYTES: u64 = 4;
/// Attribute bytes per surface voxel: colour (RGBA8) and normal (16-bit octahedral,
/// stored in a `u32`: WGSL has no 16-bit storage type).
pub const ATTRIBUTE_BYTES: u64 = 8;
/// Bytes per chunk and level of the chunk table (first voxel and count).
pub const RANGE_BYTES: u64 = 8;
/// log2 of the largest chunk edge: 8-bit positions address 256 cells per axis.
pub const MAX_CHUNK_LOG2: u32 = 8;

/// One surface voxel: x, y, z inside the chunk in bits 0..8, 8..16, 16..24, the face mask
/// in bits 24..30 (bit `f` = face `f`, −X/−Y/−Z/+X/+Y/+Z), bits 30..32 zero.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct SurfaceVoxel(pub u32);

impl SurfaceVoxel {
    /// Packs a position (each component < 256) and a face mask (< 64).
    pub fn new(pos: [u32; 3], mask: u32) -> Self {
        debug_assert!(pos.iter().all(|&c| c < 256) && mask < 64);
        Self((pos[0] & 0xff) | (pos[1] & 0xff) << 8 | (pos[2] & 0xff) << 16 | (mask & 0x3f) << 24)
    }

    /// Position inside the chunk, in cells of the voxel's level.
    pub fn pos(self) -> [u32; 3] {
        [self.0 & 0xff, (self.0 >> 8) & 0xff, (self.0 >> 16) & 0xff]
    }

    /// Face mask: bit `f` set when face `f` (−X, −Y, −Z, +X, +Y, +Z) is a boundary face.
    pub fn mask(self) -> u32 {
        (self.0 >> 24) & 0x3f
    }
}

/// Errors of building a surface model.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SurfaceError {
    /// The level is finer than cell packing allows.
    #[error("level {level} is above the highest supported level {MAX_LEVEL}")]
    LevelTooHigh {
        /// The level asked for.
        level: u32,
    },
    /// More surface voxels than 32-bit indices address.
    #[error("{count} voxels do not fit 32-bit surface indices")]
    TooManyVoxels {
        /// Voxels in the input.
        count: usize,
    },
}

/// One level of detail of every chunk: voxels chunk-major, Morton order inside a chunk.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SurfaceLevel {
    /// The surface voxels.
    pub voxels: Vec<SurfaceVoxel>,
    /// Linear RGBA8 colour per voxel (r in bits 0..8).
    pub colors: Vec<u32>,
    /// Octahedral normal per voxel: u in bits 0..8, v in bits 8..16 (as [`PackedVoxel`]).
    pub normals: Vec<u32>,
    /// Per chunk (in [`SurfaceModel::chunks`] order): first voxel and count.
    pub ranges: Vec<[u32; 2]>,
}

impl SurfaceLevel {
    /// The voxels of chunk `c`.
    pub fn chunk(&self, c: usize) -> std::ops::Range<usize> {
        let [first, count] = self.ranges[c];
        first as usize..(first + count) as usize
    }
}

/// A surface model with its level-of-detail chain.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SurfaceModel {
    /// Grid level of the finest surface (the input level: 2^level cells per axis).
    pub level: u32,
    /// log2 of the chunk edge in finest cells (`min(level, 8)`).
    pub chunk_log2: u32,
    /// Chunk coordinates (cell >> chunk_log2) of the non-empty chunks, in Morton order.
    pub chunks: Vec<[u32; 3]>,
    /// Tight bounds of each chunk's surface voxels in finest cells: min and max + 1.
    pub bounds: Vec<[[u32; 3]; 2]>,
    /// `levels[k]`: cells of grid level `level - k`; the last holds one voxel per chunk.
    pub levels: Vec<SurfaceLevel>,
}

/// Memory of a surface model, split as RastaVox reports it (base model, LOD).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SurfaceBytes {
    /// Surface voxels of the finest level (4 bytes each).
    pub base_voxels: u64,
    /// Their attributes (colour, normal).
    pub base_attributes: u64,
    /// Surface voxels and attributes of the coarser levels.
    pub lod: u64,
    /// The chunk tables (ranges per level, coordinates, bounds).
    pub chunk_tables: u64,
}

impl SurfaceBytes {
    /// Everything.
    pub fn total(&self) -> u64 {
        self.base_voxels + self.base_attributes + self.lod + self.chunk_tables
    }
}

/// Face bit of face `f` seen from the neighbour: the face of cell `c` on axis `a` toward
/// `+` (`positive`) or `−`.
pub const fn face_bit(axis: usize, positive: bool) -> u32 {
    1 << (axis + if positive { 3 } else { 0 })
}

/// Sum of the octahedral (L1-unit) vectors of a set of normal codes is encoded with this.
fn octahedral_l1(code: u32) -> [f32; 3] {
    let n = decode_octahedral(code & 0xff, (code >> 8) & 0xff);
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    [n[0] / l1, n[1] / l1, n[2] / l1]
}

impl SurfaceModel {
    /// The surface of `lod`'s voxels and its OR-merged chain.
    pub fn extract(lod: &LodLevel) -> Result<Self, SurfaceError> {
        let mut model = Self::extract_finest(lod)?;
        for _ in 0..model.chunk_log2 {
            let next = merge(model.levels.last().expect("the finest level"));
            model.levels.push(next);
        }
        Ok(model)
    }

    /// The finest level only (what the GPU extraction produces before its sort).
    pub fn extract_finest(lod: &LodLevel) -> Result<Self, SurfaceError> {
        let level = lod.level;
        if level > MAX_LEVEL {
            return Err(SurfaceError::LevelTooHigh { level });
        }
        let voxels = &lod.point_cloud.voxels;
        if u32::try_from(voxels.len()).is_err() {
            return Err(SurfaceError::TooManyVoxels {
                count: voxels.len(),
            });
        }
        let chunk_log2 = level.min(MAX_CHUNK_LOG2);
        let n = 1u32 << level;
        let local_mask = (1u32 << chunk_log2) - 1;
        let mut model = Self {
            level,
            chunk_log2,
            ..Self::default()
        };
        let mut out = SurfaceLevel::default();
        for v in voxels {
            let c = v.cell();
            let mask = boundary_mask(&lod.lookup, c, n);
            if mask == 0 {
                continue;
            }
            let chunk = c.map(|x| x >> chunk_log2);
            if model.chunks.last() != Some(&chunk) {
                model.chunks.push(chunk);
                model.bounds.push([c, c.map(|x| x + 1)]);
                out.ranges.push([out.voxels.len() as u32, 0]);
            }
            let b = model.bounds.last_mut().expect("pushed above");
            for a in 0..3 {
                b[0][a] = b[0][a].min(c[a]);
                b[1][a] = b[1][a].max(c[a] + 1);
            }
            out.ranges.last_mut().expect("pushed above")[1] += 1;
            out.voxels
                .push(SurfaceVoxel::new(c.map(|x| x & local_mask), mask));
            out.colors.push(v.color);
            out.normals.push(v.z_normal >> 16);
        }
        model.levels.push(out);
        Ok(model)
    }

    /// Grid level of LOD `k` (`level - k`).
    pub fn grid_level(&self, k: usize) -> u32 {
        self.level - k as u32
    }

    /// Surface voxels of the finest level.
    pub fn surface_voxels(&self) -> usize {
        self.levels.first().map_or(0, |l| l.voxels.len())
    }

    /// Whether there is nothing to draw.
    pub fn is_empty(&self) -> bool {
        self.chunks.is_empty()
    }

    /// Bytes, split as RastaVox reports them.
    pub fn bytes(&self) -> SurfaceBytes {
        let per_voxel = SURFACE_VOXEL_BYTES + ATTRIBUTE_BYTES;
        let base = self.surface_voxels() as u64;
        let lod: u64 = self
            .levels
            .iter()
            .skip(1)
            .map(|l| l.voxels.len() as u64)
            .sum();
        let chunks = self.chunks.len() as u64;
        SurfaceBytes {
            base_voxels: base * SURFACE_VOXEL_BYTES,
            base_attributes: base * ATTRIBUTE_BYTES,
            lod: lod * per_voxel,
            // Ranges per level, then 4 bytes of coordinates and 2 × 4 of packed bounds.
            chunk_tables: chunks * (RANGE_BYTES * self.levels.len() as u64 + 12),
        }
    }

    /// Chunk `c` at LOD `k` as a face-masked LOD level in the object's grid at level
    /// `level - k` (for the CPU reference).
    pub fn face_lod(&self, c: usize, k: usize) -> FaceLod {
        self.face_lod_of(k, std::iter::once(c))
    }

    /// Every chunk at LOD `k`.
    pub fn face_lod_all(&self, k: usize) -> FaceLod {
        self.face_lod_of(k, 0..self.chunks.len())
    }

    fn face_lod_of(&self, k: usize, chunks: impl Iterator<Item = usize>) -> FaceLod {
        let lvl = &self.levels[k];
        let shift = self.chunk_log2 - k as u32;
        let mut cells = Vec::new();
        for c in chunks {
            let origin = self.chunks[c].map(|x| x << shift);
            for i in lvl.chunk(c) {
                let p = lvl.voxels[i].pos();
                let cell = [0, 1, 2].map(|a| origin[a] + p[a]);
                cells.push((morton_encode(cell), cell, i));
            }
        }
        cells.sort_unstable_by_key(|e| e.0);
        let level = self.grid_level(k);
        let voxels = cells
            .iter()
            .map(|&(_, cell, i)| PackedVoxel {
                xy: cell[0] | cell[1] << 16,
                z_normal: cell[2] | (lvl.normals[i] & 0xffff) << 16,
                color: lvl.colors[i],
                uv: 0,
            })
            .collect();
        let faces = cells
            .iter()
            .map(|&(_, _, i)| lvl.voxels[i].mask() as u8)
            .collect();
        let codes: Vec<u64> = cells.iter().map(|e| e.0).collect();
        FaceLod {
            lod: LodLevel {
                level,
                point_cloud: PointCloud { voxels },
                lookup: SparseLookup::from_codes(level, &codes),
                proxy: Default::default(),
            },
            faces,
        }
    }
}

/// A LOD level whose voxels are hit only through the faces in their masks (the drawn
/// faces of a RastaVox level): `faces[id]` is voxel `id`'s mask ([`SurfaceVoxel::mask`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaceLod {
    /// Cells (global at the level), colours and normals; no proxy.
    pub lod: LodLevel,
    /// Face mask per voxel id.
    pub faces: Vec<u8>,
}

/// Boundary faces of solid cell `c` in a grid of `n` cells per axis.
fn boundary_mask(lookup: &SparseLookup, c: [u32; 3], n: u32) -> u32 {
    let mut mask = 0;
    for a in 0..3 {
        for positive in [false, true] {
            let empty = if positive {
                c[a] + 1 >= n || {
                    let mut m = c;
                    m[a] += 1;
                    lookup.get(m).is_none()
                }
            } else {
                c[a] == 0 || {
                    let mut m = c;
                    m[a] -= 1;
                    lookup.get(m).is_none()
                }
            };
            if empty {
                mask |= face_bit(a, positive);
            }
        }
    }
    mask
}

/// Local Morton code of a chunk position.
fn local_code(p: [u32; 3]) -> u64 {
    morton_encode(p)
}

/// One OR-merge step: runs of voxels with the same parent become one voxel.
fn merge(prev: &SurfaceLevel) -> SurfaceLevel {
    let mut out = SurfaceLevel::default();
    for (c, _) in prev.ranges.iter().enumerate() {
        let range = prev.chunk(c);
        out.ranges.push([out.voxels.len() as u32, 0]);
        let mut i = range.start;
        while i < range.end {
            let parent = local_code(prev.voxels[i].pos()) >> 3;
            let mut j = i;
            let (mut mask, mut rgba, mut normal) = (0u32, [0u32; 4], [0f32; 3]);
            while j < range.end && local_code(prev.voxels[j].pos()) >> 3 == parent {
                mask |= prev.voxels[j].mask();
                for (ch, sum) in rgba.iter_mut().enumerate() {
                    *sum += (prev.colors[j] >> (8 * ch)) & 0xff;
                }
                let n = octahedral_l1(prev.normals[j]);
                for a in 0..3 {
                    normal[a] += n[a];
                }
                j += 1;
            }
            let count = (j - i) as u32;
            let avg = |sum: u32| (sum + count / 2) / count;
            let [u, v] = encode_octahedral(normal);
            out.voxels.push(SurfaceVoxel::new(
                prev.voxels[i].pos().map(|x| x >> 1),
                mask,
            ));
            out.colors
                .push(avg(rgba[0]) | avg(rgba[1]) << 8 | avg(rgba[2]) << 16 | avg(rgba[3]) << 24);
            out.normals.push(u | v << 8);
            out.ranges.last_mut().expect("pushed above")[1] += 1;
            i = j;
        }
    }
    out
}

/// LOD by pixel error (RastaVox's LOD selection, after Dick et al. 2009): the coarsest LOD `k ≤ max_k` whose
/// voxel, `cell_world · 2^k` world units across, has a worst-case projected area of at most
/// `pixel_error²` pixels at `distance` from the eye (`focal_px` pixels per unit of
/// `size / distance`). A cube's largest silhouette, seen along its diagonal, is a hexagon of
/// area √3 · edge², so the test is `3^¼ · edge · focal_px / distance ≤ pixel_error`. Pixel
/// error 0, a zero or non-finite distance pick the finest (0).
pub fn pixel_error_lod(
    cell_world: f64,
    distance: f64,
    focal_px: f64,
    pixel_error: f64,
    max_k: usize,
) -> usize {
    if !(pixel_error > 0.0 && distance > 0.0 && distance.is_finite() && cell_world > 0.0) {
        return 0;
    }
    let mut k = 0;
    while k < max_k {
        let projected =
            3f64.powf(0.25) * cell_world * (1u64 << (k + 1)) as f64 * focal_px / distance;
        if projected > pixel_error {
            break;
        }
        k += 1;
    }
    k
}

/// One chunk to draw and the LOD it is drawn at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkDraw {
    /// Chunk index ([`SurfaceModel::chunks`] order).
    pub chunk: usize,
    /// LOD (0 = finest).
    pub k: usize,
}

/// The chunks of one placed surface model that a camera sees, each with its pixel-error
/// LOD: chunks whose world box lies wholly outside one side plane of the view, or
/// wholly behind the eye, are culled; the LOD is [`pixel_error_lod`] at the chunk box's
/// nearest view depth with the largest world size a cell takes under `object_to_world`.
/// Chunk boxes are the tight `bounds` in finest cells of a `2^level` grid in [-1, 1]³.
pub fn select_chunks(
    level: u32,
    chunk_log2: u32,
    bounds: &[[[u32; 3]; 2]],
    object_to_world: &DAffine3,
    camera: &Camera,
    screen: (u32, u32),
    pixel_error: f32,
) -> Vec<ChunkDraw> {
    let (w, h) = (screen.0.max(1) as f64, screen.1.max(1) as f64);
    let view_proj = camera.view_projection(w / h);
    let forward = camera.pixel_rays(1, 1).forward();
    let focal_px = 0.5 * h / (camera.fov_y_deg.to_radians() * 0.5).tan();
    let m = object_to_world.matrix3;
    let scale = m
        .x_axis
        .length()
        .max(m.y_axis.length())
        .max(m.z_axis.length());
    let cell_world = scale * cell_size(level);
    let s = cell_size(level);
    let mut out = Vec::new();
    for (chunk, b) in bounds.iter().enumerate() {
        let mut clip = [DVec4::ZERO; 8];
        let mut depth = f64::INFINITY;
        for (i, c) in clip.iter_mut().enumerate() {
            let corner = DVec3::new(
                -1.0 + b[i & 1][0] as f64 * s,
                -1.0 + b[(i >> 1) & 1][1] as f64 * s,
                -1.0 + b[(i >> 2) & 1][2] as f64 * s,
            );
            let world = object_to_world.transform_point3(corner);
            depth = depth.min((world - camera.position).dot(forward));
            *c = view_proj * world.extend(1.0);
        }
        let outside = |f: &dyn Fn(&DVec4) -> bool| clip.iter().all(f);
        if outside(&|c| c.w <= 0.0)
            || outside(&|c| c.x > c.w)
            || outside(&|c| c.x < -c.w)
            || outside(&|c| c.y > c.w)
            || outside(&|c| c.y < -c.w)
        {
            continue;
        }
        // The nearest corner's depth bounds the box's from below only for boxes ahead of
        // the eye; a box around the eye's plane gets depth ≤ 0 and the finest LOD.
        let k = pixel_error_lod(
            cell_world,
            depth,
            focal_px,
            f64::from(pixel_error),
            chunk_log2 as usize,
        );
        out.push(ChunkDraw { chunk, k });
    }
    out
}

#[cfg(test)]
mod tests;
