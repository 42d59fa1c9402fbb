//! Objects whose voxels change on the GPU (dynamic objects: animated meshes re-voxelized
//! every frame, edits, voxels streamed by the application). At upload such an object gets
//! room in the scene's streams beyond its asset ([`DynamicRoom`]: colours and normals per
//! voxel, lookup nodes, per level); [`super::GpuScene::set_object_levels`] then copies
//! GPU-built levels ([`super::GpuLevel`], from `ssbvb-gpu-build`'s voxelizer and LOD build)
//! into that room on the GPU (the copy is `GpuScene`'s, in `mod.rs`; this file holds the
//! rooms and the copy kernels' helpers), so the SSBVB frame draws them without any CPU
//! preparation or upload of voxels. Voxel ids are Morton ranks and lookup bases are
//! relative to the level's root, so the copied words are the whole description: the LOD
//! table never changes.
//!
//! Their proxy is the object's whole box [-1, 1]³ and their culling box too (whatever the
//! voxels become, both stay conservative). The CPU asset of a dynamic object is not
//! updated: passes that build their own structures from it (the baselines, RastaVox)
//! refuse scenes with dynamic objects, as they refuse paged ones.

use crate::wgpu;

/// Room to reserve for one object's changing voxels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicRoom {
    /// The object (index in the scene's objects).
    pub object: usize,
    /// Voxels and lookup nodes reserved per level, as a multiple of the asset's (≥ 1).
    pub growth: f64,
}

impl DynamicRoom {
    /// Slots for a level with `n` entries now: `growth × n`, and at least 1024 more;
    /// even, so a level's normal words (two per word) never reach past its room.
    pub(super) fn capacity(&self, n: usize) -> usize {
        let grown = (n as f64 * self.growth.max(1.0)).ceil() as usize;
        grown.max(n + 1024).next_multiple_of(2)
    }
}

/// Where one level of a dynamic object lives in the streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DynamicLevel {
    /// First voxel (even: normals are two per word).
    pub voxel_offset: u32,
    /// Voxels reserved.
    pub voxel_capacity: u32,
    /// First lookup node.
    pub node_offset: u32,
    /// Nodes reserved.
    pub node_capacity: u32,
    /// Voxels now.
    pub voxels: u32,
    /// Lookup nodes now.
    pub nodes: u32,
}

/// A dynamic object's room, per level.
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicObject {
    /// The object.
    pub object: usize,
    /// `levels[l]`: level `l`.
    pub levels: Vec<DynamicLevel>,
}

/// The proxy of a dynamic object's levels: the object box [-1, 1]³, triangles
/// counter-clockwise seen from outside.
pub(super) fn object_box() -> ssbvb_voxel::asset::ProxyMesh {
    let positions = (0..8)
        .map(|i| [0, 1, 2].map(|a| if (i >> a) & 1 == 1 { 1.0 } else { -1.0 }))
        .collect();
    // Per face: the four corners with that axis at its side, as two triangles.
    let mut triangles = Vec::new();
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for side in [0u32, 1] {
            let corner = |u: u32, v: u32| (side << a) | (u << b) | (v << c);
            let (p00, p10, p11, p01) = (corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1));
            // Outward along +a: (b, c) counter-clockwise; along −a: reversed.
            if side == 1 {
                triangles.extend([[p00, p10, p11], [p00, p11, p01]]);
            } else {
                triangles.extend([[p00, p11, p10], [p00, p01, p11]]);
            }
        }
    }
    ssbvb_voxel::asset::ProxyMesh {
        positions,
        triangles,
    }
}

/// Copies `words` words of a stream split in bindings of `chunk_words` words, from stream
/// word `src_word`, into `dst` (from word 0).
pub fn copy_words_from_chunks(
    enc: &mut wgpu::CommandEncoder,
    chunks: &[wgpu::Buffer],
    chunk_words: u64,
    src_word: u64,
    dst: &wgpu::Buffer,
    words: u64,
) {
    let (mut s, mut d, mut left) = (src_word, 0, words);
    while left > 0 {
        let (chunk, within) = ((s / chunk_words) as usize, s % chunk_words);
        let n = left.min(chunk_words - within);
        enc.copy_buffer_to_buffer(&chunks[chunk], 4 * within, dst, 4 * d, 4 * n);
        (s, d, left) = (s + n, d + n, left - n);
    }
}

/// Copies `words` words from `src` (at word `src_word`) into a stream split in bindings of
/// `chunk_words` words, starting at stream word `dst_word`.
pub fn copy_words(
    enc: &mut wgpu::CommandEncoder,
    src: &wgpu::Buffer,
    src_word: u64,
    chunks: &[wgpu::Buffer],
    chunk_words: u64,
    dst_word: u64,
    words: u64,
) {
    let (mut s, mut d, mut left) = (src_word, dst_word, words);
    while left > 0 {
        let (chunk, within) = ((d / chunk_words) as usize, d % chunk_words);
        let n = left.min(chunk_words - within);
        enc.copy_buffer_to_buffer(src, 4 * s, &chunks[chunk], 4 * within, 4 * n);
        (s, d, left) = (s + n, d + n, left - n);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_object_box_is_closed_and_outward() {
        let b = super::object_box();
        assert_eq!((b.positions.len(), b.triangles.len()), (8, 12));
        ssbvb_voxel::proxy::check_closed(&b).unwrap();
        // Counter-clockwise from outside: a positive volume of 2³.
        assert!((ssbvb_voxel::proxy::signed_volume(&b) - 8.0).abs() < 1e-9);
    }
}
