//! The prepared voxel asset: what the renderer uploads and the reference caster reads.
//!
//! These types are the contract between the CPU preparation (voxelization, SVO, LOD) and
//! every consumer (GPU uploads, the CPU reference ray caster, the asset cache). Layouts
//! marked `#[repr(C)]` are uploaded to the GPU as they are; WGSL mirrors them.

use bytemuck::{Pod, Zeroable};

use crate::model::ObjectSpace;

pub use crate::lookup::{MAX_LEVEL, PAGE_SIZE, SparseLookup};

/// GPU bytes of a voxel's colour (linear RGBA8).
pub const GPU_COLOR_BYTES: u64 = 4;
/// GPU bytes of a voxel's normal (16-bit octahedral).
pub const GPU_NORMAL_BYTES: u64 = 2;
/// GPU bytes per voxel of the attribute streams the renderer uploads: colour and normal.
/// The cell is implied by the sparse lookup (voxel id = Morton rank) and texture
/// coordinates are not uploaded (no pass reads them).
pub const GPU_VOXEL_BYTES: u64 = GPU_COLOR_BYTES + GPU_NORMAL_BYTES;

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
    /// The sparse lookup: cell → voxel id (the cell's Morton rank).
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
pub(crate) fn encode_octahedral(n: [f32; 3]) -> [u32; 2] {
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
pub(crate) fn decode_octahedral(u: u32, v: u32) -> [f32; 3] {
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
}
