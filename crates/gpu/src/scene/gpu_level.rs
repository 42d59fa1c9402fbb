//! A level of voxels built on the GPU: its codes, colours, normals and lookup nodes in
//! buffers, as the GPU LOD build (`ssbvb-gpu-build`) returns them and
//! [`super::GpuScene::set_object_levels`] copies them into a dynamic object's room.

use ssbvb_voxel::lookup::{NODE_WORDS, SparseLookup, tree_depth};

use crate::kernels::read_words;
use crate::{GpuContext, ResourceError, wgpu};

/// One level on the GPU.
pub struct GpuLevel {
    /// Grid level.
    pub level: u32,
    /// Voxels.
    pub count: u32,
    /// Morton codes, low and high words.
    pub key_lo: wgpu::Buffer,
    /// High words of the codes.
    pub key_hi: wgpu::Buffer,
    /// Linear RGBA (f32 × 4) per voxel, for the next coarser level.
    pub colors: wgpu::Buffer,
    /// Unit normal (f32 × 4) per voxel.
    pub normals: wgpu::Buffer,
    /// RGBA8 colour per voxel (the scene's colour stream).
    pub packed: wgpu::Buffer,
    /// 16-bit octahedral normals, two per word (the scene's normal stream).
    pub packed_normals: wgpu::Buffer,
    /// The lookup's nodes, root first ([`NODE_WORDS`] words each).
    pub nodes: wgpu::Buffer,
    /// Nodes in `nodes`.
    pub node_count: u32,
}

impl GpuLevel {
    /// Reads the level back: its codes, point-cloud words (colour and 16-bit normal per
    /// voxel, interleaved) and lookup (tests; the cross-check against the CPU preparation).
    pub fn read_back(
        &self,
        ctx: &GpuContext,
    ) -> Result<(Vec<u64>, Vec<u32>, SparseLookup), ResourceError> {
        let n = u64::from(self.count);
        let lo = read_words(ctx, &self.key_lo, 0, n)?;
        let hi = read_words(ctx, &self.key_hi, 0, n)?;
        let codes = lo
            .iter()
            .zip(&hi)
            .map(|(&l, &h)| u64::from(l) | u64::from(h) << 32)
            .collect();
        let colors = read_words(ctx, &self.packed, 0, n)?;
        let normals = read_words(ctx, &self.packed_normals, 0, n.div_ceil(2))?;
        let packed = (0..n as usize)
            .flat_map(|i| [colors[i], (normals[i / 2] >> (16 * (i % 2))) & 0xffff])
            .collect();
        let nodes = read_words(
            ctx,
            &self.nodes,
            0,
            NODE_WORDS as u64 * u64::from(self.node_count),
        )?;
        Ok((
            codes,
            packed,
            SparseLookup {
                level: self.level,
                depth: tree_depth(self.level),
                nodes,
            },
        ))
    }
}
