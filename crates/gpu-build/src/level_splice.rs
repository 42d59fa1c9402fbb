//! Region-local updates of a dynamic object's levels on the GPU
//! (`shaders/level_splice.wgsl`): a run-time edit ([`ssbvb_voxel::local_edit`]) recomputes
//! only the blocks it touches, on the CPU, and each level's [`LevelPatch`] is applied here
//! to the object's room in the scene's streams. Per level, the changed tail of the colour
//! and normal streams and the lookup nodes are copied out of the room, rebuilt from the
//! patch and the old words by the patch's segments (moved nodes get their base delta), and
//! copied back: no LOD rebuild, and only the blocks' words cross the bus. Voxel ids are
//! Morton ranks, so an edit moves every later voxel by the change in count: the tail is
//! moved on the GPU, which is a copy, not a rebuild.

use ssbvb_gpu::InitBuffer;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_voxel::level_splice::{LevelPatch, Segment, Source};
use ssbvb_voxel::lookup::NODE_WORDS;

use ssbvb_gpu::ResourceError;
use ssbvb_gpu::kernels::{Bind, Kernels, WORKGROUP, storage, uniform};
use ssbvb_gpu::scene::{DynamicLevel, GpuScene, copy_words, copy_words_from_chunks};

/// The compiled splice kernels.
pub struct LevelSplicer {
    kernels: Kernels,
}

/// What applying an edit's patches moved.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SpliceStats {
    /// Levels whose streams changed.
    pub levels: u32,
    /// Voxel stream entries rewritten (the changed tails).
    pub voxels_rewritten: u64,
    /// Lookup nodes rewritten.
    pub nodes_rewritten: u64,
    /// Words uploaded (patches and segment lists).
    pub words_uploaded: u64,
}

/// A patch that keeps its level as it is: every segment an old run in place, unmoved.
fn is_identity(p: &LevelPatch) -> bool {
    let kept = |s: &[Segment]| {
        s.iter()
            .all(|s| matches!(s.source, Source::Old { from, base_delta: 0 } if from == s.start))
    };
    p.old_voxels == p.voxels
        && p.old_nodes == p.nodes
        && kept(&p.voxel_segments)
        && kept(&p.node_segments)
}

impl LevelSplicer {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext) -> Result<Self, ResourceError> {
        use Bind::{Read, ReadWrite, Uniform};
        Ok(Self {
            kernels: Kernels::new(
                ctx,
                "level_splice.wgsl",
                &[Uniform, Read, Read, Read, ReadWrite],
                &["splice_colors", "splice_normals", "splice_nodes"],
            )?,
        })
    }

    /// Applies `patches` (`patches[l]` for level `l`, as
    /// [`ssbvb_voxel::local_edit::LocalEditor::apply`] returns them) to dynamic object
    /// `object` of `scene`, on the GPU. An error when the object is not dynamic, the patches
    /// were made for other levels or counts than the room holds, or a level outgrows its
    /// room (naming the room needed); nothing is changed then.
    pub fn apply(
        &self,
        ctx: &GpuContext,
        scene: &mut GpuScene,
        object: usize,
        patches: &[LevelPatch],
    ) -> Result<SpliceStats, ResourceError> {
        let chunks = scene.chunks;
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let Some(di) = scene.dynamic.iter().position(|d| d.object == object) else {
            return Err(ResourceError::BadScene(format!(
                "object {object} was not uploaded with room for dynamic voxels"
            )));
        };
        let dynamic = &scene.dynamic[di];
        check_patches(object, patches, &dynamic.levels, limit)?;
        let d = &ctx.device;
        let color_words = 1u64 << chunks.word_bits;
        let node_chunk_words = (NODE_WORDS as u64) << chunks.node_bits;
        let mut stats = SpliceStats::default();
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("level splice"),
        });
        let init = |label: &str, words: &[u32]| {
            let words: &[u32] = if words.is_empty() { &[0] } else { words };
            d.init_buffer(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(words),
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let segments = |s: &[Segment]| -> Vec<u32> { s.iter().flat_map(Segment::words).collect() };
        // Buffers live until the submit below.
        let mut keep = Vec::new();
        for (p, room) in patches.iter().zip(&dynamic.levels) {
            if is_identity(p) {
                continue;
            }
            stats.levels += 1;
            // Voxel streams from the first changed voxel (even: normals go two per word).
            let first = p.first_changed_voxel() & !1;
            let (old_n, new_n) = (
                u64::from(p.old_voxels - first.min(p.old_voxels)),
                u64::from(p.voxels - first.min(p.voxels)),
            );
            let at = u64::from(room.voxel_offset) + u64::from(first);
            let voxel_segs = init("splice voxel segments", &segments(&p.voxel_segments));
            let node_segs = init("splice node segments", &segments(&p.node_segments));
            let halves: Vec<u32> = p
                .normals
                .chunks(2)
                .map(|h| u32::from(h[0]) | u32::from(*h.get(1).unwrap_or(&0)) << 16)
                .collect();
            let (patch_colors, patch_normals, patch_nodes) = (
                init("splice colours", &p.colors),
                init("splice normals", &halves),
                init("splice nodes", &p.node_words),
            );
            stats.words_uploaded += (4 * (p.voxel_segments.len() + p.node_segments.len())
                + p.colors.len()
                + halves.len()
                + p.node_words.len()) as u64;
            // Colours, one word per voxel.
            keep.extend(self.splice_stream(
                d,
                &mut enc,
                Stream {
                    entry: "splice_colors",
                    words_per_thread: 1,
                    chunks: &scene.word_buffers,
                    chunk_words: color_words,
                    at: scene.color_word_base + at,
                    old_words: old_n,
                    new_words: new_n,
                    first,
                    segments: (&voxel_segs, p.voxel_segments.len()),
                    patch: &patch_colors,
                    total: p.voxels,
                },
            ));
            // Normals, two per word; a level's room starts on a word.
            keep.extend(self.splice_stream(
                d,
                &mut enc,
                Stream {
                    entry: "splice_normals",
                    words_per_thread: 1,
                    chunks: &scene.word_buffers,
                    chunk_words: color_words,
                    at: scene.normal_word_base + at / 2,
                    old_words: old_n.div_ceil(2),
                    new_words: new_n.div_ceil(2),
                    first,
                    segments: (&voxel_segs, p.voxel_segments.len()),
                    patch: &patch_normals,
                    total: p.voxels,
                },
            ));
            // Every node of the level (bases before the blocks move too).
            let w = NODE_WORDS as u64;
            keep.extend(self.splice_stream(
                d,
                &mut enc,
                Stream {
                    entry: "splice_nodes",
                    words_per_thread: w,
                    chunks: &scene.lookup_buffers,
                    chunk_words: node_chunk_words,
                    at: w * u64::from(room.node_offset),
                    old_words: w * u64::from(p.old_nodes),
                    new_words: w * u64::from(p.nodes),
                    first: 0,
                    segments: (&node_segs, p.node_segments.len()),
                    patch: &patch_nodes,
                    total: p.nodes,
                },
            ));
            stats.voxels_rewritten += new_n;
            stats.nodes_rewritten += u64::from(p.nodes);
        }
        ctx.submit("brush splice", [enc.finish()]);
        drop(keep);
        for (p, room) in patches.iter().zip(scene.dynamic[di].levels.iter_mut()) {
            room.voxels = p.voxels;
            room.nodes = p.nodes;
        }
        Ok(stats)
    }
}

/// Refuses patches made for other levels or counts than the room holds, or that outgrow
/// the room or the device's storage binding.
fn check_patches(
    object: usize,
    patches: &[LevelPatch],
    rooms: &[DynamicLevel],
    limit: u64,
) -> Result<(), ResourceError> {
    if patches.len() != rooms.len() {
        return Err(ResourceError::BadScene(format!(
            "object {object}: {} patches for {} levels",
            patches.len(),
            rooms.len()
        )));
    }
    for (l, (p, room)) in patches.iter().zip(rooms).enumerate() {
        if p.level != l as u32 || p.old_voxels != room.voxels || p.old_nodes != room.nodes {
            return Err(ResourceError::BadScene(format!(
                "object {object} level {l}: a patch for level {} with {} voxels and {} \
                 nodes, the room holds {} and {} (the editor and the scene disagree)",
                p.level, p.old_voxels, p.old_nodes, room.voxels, room.nodes
            )));
        }
        if p.voxels > room.voxel_capacity || p.nodes > room.node_capacity {
            return Err(ResourceError::TooLarge(format!(
                "object {object} level {l}: {} voxels and {} lookup nodes, its room holds \
                 {} and {} (upload it with more growth)",
                p.voxels, p.nodes, room.voxel_capacity, room.node_capacity
            )));
        }
        let biggest = 4 * u64::from(p.voxels.max(p.old_voxels))
            .max(NODE_WORDS as u64 * u64::from(p.nodes.max(p.old_nodes)));
        if biggest > limit {
            return Err(ResourceError::TooLarge(format!(
                "object {object} level {l}: splicing it binds {biggest} bytes, the device \
                 binds at most {limit}"
            )));
        }
    }
    Ok(())
}

/// One stream of a level to splice: its words `at..` in `chunks` (bindings of
/// `chunk_words`), rebuilt by kernel `entry` from element `first` on.
struct Stream<'a> {
    entry: &'static str,
    /// Words each thread writes (a colour, two normals, a node).
    words_per_thread: u64,
    chunks: &'a [wgpu::Buffer],
    chunk_words: u64,
    at: u64,
    old_words: u64,
    new_words: u64,
    first: u32,
    segments: (&'a wgpu::Buffer, usize),
    patch: &'a wgpu::Buffer,
    total: u32,
}

impl LevelSplicer {
    /// Records the copy out of the room, the kernel and the copy back of one stream;
    /// returns the buffers to keep until the submit.
    fn splice_stream(
        &self,
        d: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        s: Stream,
    ) -> [wgpu::Buffer; 3] {
        let old = storage(d, "splice old words", s.old_words);
        let out = storage(d, "splice new words", s.new_words);
        copy_words_from_chunks(enc, s.chunks, s.chunk_words, s.at, &old, s.old_words);
        let threads = s.new_words / s.words_per_thread;
        let params = uniform(
            d,
            "splice params",
            &[
                threads as u32,
                s.first,
                s.segments.1 as u32,
                s.first,
                s.total,
                0,
                0,
                0,
            ],
        );
        let bg = self
            .kernels
            .bind_group(d, &[&params, s.segments.0, &old, s.patch, &out]);
        self.kernels.dispatch(enc, s.entry, &bg, groups(threads));
        copy_words(enc, &out, 0, s.chunks, s.chunk_words, s.at, s.new_words);
        [old, out, params]
    }
}

/// Workgroups for `n` threads.
fn groups(n: u64) -> u32 {
    n.div_ceil(u64::from(WORKGROUP)) as u32
}
