//! How the scene's streams are split over bindings, how a GPU budget is split into the
//! fixed part and the page pools of a streamed scene, and the scene's buffer helpers.

use ssbvb_voxel::asset::GPU_VOXEL_BYTES;
use ssbvb_voxel::lookup::NODE_WORDS;

use crate::{GpuContext, wgpu};

use super::streaming::{BLOCK_BYTES, MAX_PAGE_BYTES, PagedLayoutBuilder, RUN_BYTES, SLOT_BYTES};
use crate::ResourceError;

/// How the scene's streams are split over bindings (`LodInfo.chunk_bits` in
/// `common.inc.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamChunks {
    /// log2 of the words per binding of the colour and normal streams.
    pub word_bits: u32,
    /// log2 of the nodes per binding of the lookup-node stream.
    pub node_bits: u32,
    /// log2 of the nodes per binding of the octree baseline's 8-byte nodes.
    pub octree_bits: u32,
}

impl StreamChunks {
    /// The largest power-of-two chunks a device binding at most `max_binding` bytes holds
    /// (at least 2^4 words or nodes, at most 2^30 words and 2^28 nodes).
    pub fn for_device(max_binding: u64) -> Self {
        let bits = |unit: u64, max: u32| (max_binding / unit).max(16).ilog2().min(max);
        Self {
            word_bits: bits(4, 30),
            node_bits: bits(4 * NODE_WORDS as u64, 28),
            octree_bits: bits(8, 28),
        }
    }
}

impl Default for StreamChunks {
    /// 2^25 words (128 MiB, the smallest storage binding size a device may have), 2^23
    /// lookup nodes (96 MiB) and 2^24 octree nodes (128 MiB).
    fn default() -> Self {
        Self {
            word_bits: 25,
            node_bits: 23,
            octree_bits: 24,
        }
    }
}
/// Most bindings one stream of the scene may take (with 128 MiB bindings: 1 GiB); a
/// device's storage-buffer limit may allow fewer, which the pipeline check names.
pub const MAX_STREAM_CHUNKS: usize = 8;

/// A stream, the concatenation of `parts`, split into as few bindings of at most
/// `chunk_bytes` each as hold it (one small buffer when it is empty); an error when it
/// needs more than [`MAX_STREAM_CHUNKS`]. One chunk at a time is assembled on the CPU.
pub(super) fn chunked(
    ctx: &GpuContext,
    label: &str,
    parts: &[&[u8]],
    chunk_bytes: usize,
) -> Result<Vec<wgpu::Buffer>, ResourceError> {
    let total: usize = parts.iter().map(|p| p.len()).sum();
    let needed = total.div_ceil(chunk_bytes).max(1);
    if needed > MAX_STREAM_CHUNKS {
        return Err(ResourceError::TooLarge(format!(
            "the scene's {label} take {total} bytes; the renderer binds at most \
             {MAX_STREAM_CHUNKS} × {chunk_bytes} bytes of them: use a coarser level, fewer \
             objects or a GPU budget"
        )));
    }
    let mut chunk = Vec::with_capacity(total.min(chunk_bytes));
    let mut buffers = Vec::with_capacity(needed);
    for part in parts {
        let mut rest = *part;
        while !rest.is_empty() {
            let n = rest.len().min(chunk_bytes - chunk.len());
            chunk.extend_from_slice(&rest[..n]);
            rest = &rest[n..];
            if chunk.len() == chunk_bytes {
                buffers.push(storage(ctx, &format!("{label} {}", buffers.len()), &chunk)?);
                chunk.clear();
            }
        }
    }
    if !chunk.is_empty() || buffers.is_empty() {
        buffers.push(storage(ctx, &format!("{label} {}", buffers.len()), &chunk)?);
    }
    Ok(buffers)
}

/// The pools of a streamed scene.
pub(super) struct Pools {
    pub(super) node_pool_start: u32,
    pub(super) voxel_pool_start: u32,
    pub(super) slots: u32,
    pub(super) blocks: u32,
    pub(super) fixed_bytes: u64,
}

/// Sizes the page pools for a budget and appends them to the streams: the fixed part
/// (`nodes`, the pinned levels' voxels, `other_bytes`) first, the rest split between node
/// slots and voxel blocks in the proportion the paged levels' pages need on average.
pub(super) fn plan_pools(
    budget: u64,
    paged: &PagedLayoutBuilder,
    nodes: &mut Vec<u32>,
    colors: &mut Vec<u32>,
    normals: &mut Vec<u16>,
    other_bytes: u64,
) -> Result<Pools, ResourceError> {
    let slot_words = super::page_cache::SLOT_NODES as usize * NODE_WORDS;
    nodes.resize(nodes.len().next_multiple_of(slot_words), 0);
    let block = super::page_cache::BLOCK_VOXELS as usize;
    colors.resize(colors.len().next_multiple_of(block), 0);
    normals.resize(colors.len(), 0);
    let fixed_bytes = nodes.len() as u64 * 4 + colors.len() as u64 * GPU_VOXEL_BYTES + other_bytes;
    let pages = paged.pages() as u64;
    let need = fixed_bytes + if pages > 0 { MAX_PAGE_BYTES } else { 0 };
    if budget < need {
        return Err(ResourceError::BudgetTooSmall {
            budget,
            minimum: need,
        });
    }
    let pool = budget - fixed_bytes;
    // Split the pool in the proportion all pages need (node runs against voxel blocks):
    // a view's pages need about the same.
    let (runs, blocks) = paged.need();
    let node_bytes = runs as f64 * RUN_BYTES as f64;
    let total = node_bytes + blocks as f64 * BLOCK_BYTES as f64;
    let node_share = if total > 0.0 { node_bytes / total } else { 0.5 };
    let slots =
        ((pool as f64 * node_share / SLOT_BYTES as f64).ceil() as u64).clamp(1, pages.max(1));
    let blocks = ((pool.saturating_sub(slots * SLOT_BYTES)) / BLOCK_BYTES).clamp(64, blocks + 64);
    let node_pool_start = checked_u32(nodes.len() / NODE_WORDS, "lookup nodes")?;
    let voxel_pool_start = checked_u32(colors.len(), "voxel count")?;
    nodes.resize(nodes.len() + slots as usize * slot_words, 0);
    colors.resize(colors.len() + blocks as usize * block, 0);
    normals.resize(colors.len(), 0);
    checked_u32(nodes.len() / NODE_WORDS, "lookup nodes")?;
    checked_u32(colors.len(), "voxel count")?;
    Ok(Pools {
        node_pool_start,
        voxel_pool_start,
        slots: slots as u32,
        blocks: blocks as u32,
        fixed_bytes,
    })
}

pub(super) fn storage(
    ctx: &GpuContext,
    label: &str,
    bytes: &[u8],
) -> Result<wgpu::Buffer, ResourceError> {
    // One binding each: refuse clearly what the device cannot bind (lavapipe binds at most
    // 128 MiB, so e.g. the bunny's page pool at level 10 does not fit there).
    let max = ctx.device.limits().max_storage_buffer_binding_size;
    if bytes.len() as u64 > max {
        return Err(ResourceError::TooLarge(format!(
            "the scene's {label} take {} bytes; this device binds at most {max} bytes per \
             storage buffer: use a coarser level or fewer objects",
            bytes.len()
        )));
    }
    // Empty bindings are invalid: keep at least 16 bytes.
    let mut data = bytes.to_vec();
    if data.len() < 16 {
        data.resize(16, 0);
    }
    Ok(ctx.checked_init_buffer(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &data,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
    })?)
}

pub(super) fn checked_u32(v: usize, what: &str) -> Result<u32, ResourceError> {
    u32::try_from(v).map_err(|_| {
        ResourceError::TooLarge(format!("{what}: {v} does not fit the GPU's 32-bit indices"))
    })
}
