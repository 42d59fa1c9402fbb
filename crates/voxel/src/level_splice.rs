//! Region-local updates of one level's streams (run-time edits of dynamic objects).
//!
//! A level's voxel ids are Morton ranks and its lookup nodes are stored breadth first with
//! absolute child indices (see [`crate::lookup`]), so changing the voxels of a small region
//! changes the ids of every later voxel and the bases of many nodes. What changes is still
//! simple: the new arrays are the old ones cut at the edited blocks, with each block's new
//! content put in, and every old run between them kept with its node bases moved by one
//! constant. A [`LevelPatch`] says exactly that: a list of [`Segment`]s per array (old run
//! with a base delta, or patch run) and the patch words. Only the blocks' content is
//! computed and uploaded; the GPU (`ssbvb_gpu_build::level_splice`) moves the rest, and
//! [`LevelPatch::apply_colors`] and friends are its CPU twin.
//!
//! [`LevelMirror`] keeps what computing a patch needs: the level's voxels (codes and
//! float attributes, for coarsening the next level's blocks) and the sorted node keys of
//! every tree depth (a depth-`d` node's key is `code >> 6 (depth − d)`). A block is an
//! aligned cube of cells, hence one contiguous range of codes; the nodes whose key range
//! meets it are recomputed (masks from their children, bases by binary search), all others
//! only move.

use crate::asset::PackedVoxel;
use crate::lookup::{NODE_WORDS, tree_depth};
use crate::svo::{LevelVoxels, morton_decode};

/// Where a run of a new array comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The old array from element `from`; for nodes, the base word moves by `base_delta`.
    Old {
        /// First old element.
        from: u32,
        /// Added to each node's base (zero for voxel streams).
        base_delta: i32,
    },
    /// The patch from element `from`.
    Patch {
        /// First patch element.
        from: u32,
    },
}

/// Elements `start..start + len` of a new array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    /// First new element.
    pub start: u32,
    /// Elements.
    pub len: u32,
    /// Where they come from.
    pub source: Source,
}

impl Segment {
    /// The segment as the GPU kernel reads it: new start, source start, kind (0 old,
    /// 1 patch), base delta (two's complement).
    pub fn words(&self) -> [u32; 4] {
        match self.source {
            Source::Old { from, base_delta } => [self.start, from, 0, base_delta as u32],
            Source::Patch { from } => [self.start, from, 1, 0],
        }
    }
}

/// The change of one level's streams: how to build its new colour, normal and node
/// arrays from the old ones.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LevelPatch {
    /// Grid level.
    pub level: u32,
    /// Voxels before and after.
    pub old_voxels: u32,
    /// Voxels after.
    pub voxels: u32,
    /// Lookup nodes before.
    pub old_nodes: u32,
    /// Lookup nodes after.
    pub nodes: u32,
    /// Runs of the new voxel streams (colours and normals alike).
    pub voxel_segments: Vec<Segment>,
    /// Runs of the new node array.
    pub node_segments: Vec<Segment>,
    /// Patch colours (the scene's RGBA8 colour words).
    pub colors: Vec<u32>,
    /// Patch normals (the scene's 16-bit octahedral normals).
    pub normals: Vec<u16>,
    /// Patch nodes, [`NODE_WORDS`] words each.
    pub node_words: Vec<u32>,
}

impl LevelPatch {
    /// The first voxel whose stream entries may change: everything before it is kept in
    /// place, so the GPU only moves the tail.
    pub fn first_changed_voxel(&self) -> u32 {
        match self.voxel_segments.first() {
            Some(Segment {
                len,
                source: Source::Old { from: 0, .. },
                ..
            }) if self.voxel_segments.len() > 1 => *len,
            Some(Segment {
                source: Source::Old { from: 0, .. },
                ..
            }) => self.voxels,
            _ => 0,
        }
    }

    fn build<T: Copy>(
        segments: &[Segment],
        total: u32,
        old: &[T],
        patch: &[T],
        width: usize,
        mut moved: impl FnMut(&mut [T], i32),
    ) -> Vec<T> {
        let mut out = Vec::with_capacity(total as usize * width);
        for s in segments {
            let (from, len) = (s.start as usize, s.len as usize);
            debug_assert_eq!(out.len(), from * width);
            match s.source {
                Source::Old { from, base_delta } => {
                    let src = &old[from as usize * width..][..len * width];
                    let start = out.len();
                    out.extend_from_slice(src);
                    if base_delta != 0 {
                        for e in out[start..].chunks_mut(width) {
                            moved(e, base_delta);
                        }
                    }
                }
                Source::Patch { from } => {
                    out.extend_from_slice(&patch[from as usize * width..][..len * width]);
                }
            }
        }
        out
    }

    /// The new colour stream from the old one (the CPU twin of the GPU kernel).
    pub fn apply_colors(&self, old: &[u32]) -> Vec<u32> {
        Self::build(
            &self.voxel_segments,
            self.voxels,
            old,
            &self.colors,
            1,
            |_, _| {},
        )
    }

    /// The new normal stream from the old one.
    pub fn apply_normals(&self, old: &[u16]) -> Vec<u16> {
        Self::build(
            &self.voxel_segments,
            self.voxels,
            old,
            &self.normals,
            1,
            |_, _| {},
        )
    }

    /// The new node array from the old one (bases of moved nodes shifted).
    pub fn apply_nodes(&self, old: &[u32]) -> Vec<u32> {
        Self::build(
            &self.node_segments,
            self.nodes,
            old,
            &self.node_words,
            NODE_WORDS,
            |n, d| n[2] = n[2].wrapping_add(d as u32),
        )
    }
}

/// One level of a dynamic object as the CPU keeps it to compute patches.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelMirror {
    /// The voxels, Morton-sorted, with float attributes.
    pub voxels: LevelVoxels,
    depth: u32,
    /// `keys[d]`: sorted keys of the depth-`d` nodes (`keys[0] == [0]`, the root).
    keys: Vec<Vec<u64>>,
}

/// Index of the first element of `v` not below `x`.
fn lower_bound(v: &[u64], x: u64) -> usize {
    v.partition_point(|&e| e < x)
}

/// The nodes of one depth that a block's interval of keys replaces.
#[derive(Debug, Clone)]
struct Change {
    /// The interval's last key.
    last_key: u64,
    /// Their indices within the depth, before and after.
    old: std::ops::Range<usize>,
    new: std::ops::Range<usize>,
}

/// Appends a run of `len` elements from `source` at new element `*start` (none if empty).
fn push(segments: &mut Vec<Segment>, start: &mut u32, len: usize, source: Source) {
    if len > 0 {
        segments.push(Segment {
            start: *start,
            len: len as u32,
            source,
        });
        *start += len as u32;
    }
}

/// The voxels of `v` with codes in `range`.
pub fn voxels_in(v: &LevelVoxels, range: (u64, u64)) -> LevelVoxels {
    let (a, b) = (
        lower_bound(&v.codes, range.0),
        lower_bound(&v.codes, range.1),
    );
    LevelVoxels {
        level: v.level,
        codes: v.codes[a..b].to_vec(),
        normals: v.normals[a..b].to_vec(),
        colors: v.colors[a..b].to_vec(),
        uvs: v.uvs[a..b].to_vec(),
    }
}

/// The colour word and normal half the scene's streams hold for voxel `i` of `v`.
pub fn stream_words(v: &LevelVoxels, i: usize) -> (u32, u16) {
    let p = PackedVoxel::new(
        morton_decode(v.codes[i]),
        v.normals[i],
        v.colors[i],
        v.uvs[i],
    );
    (p.color, (p.z_normal >> 16) as u16)
}

/// Per level of `asset`: the colour words, normal halves and lookup nodes the scene's
/// streams hold for it, what a level's patches apply to (for checks and tests).
pub fn asset_streams(asset: &crate::asset::VoxelAsset) -> Vec<(Vec<u32>, Vec<u16>, Vec<u32>)> {
    asset
        .lods
        .iter()
        .map(|lod| {
            let v = &lod.point_cloud.voxels;
            (
                v.iter().map(|p| p.color).collect(),
                v.iter().map(|p| (p.z_normal >> 16) as u16).collect(),
                lod.lookup.nodes.clone(),
            )
        })
        .collect()
}

impl LevelMirror {
    /// The mirror of a level's voxels.
    pub fn new(voxels: LevelVoxels) -> Self {
        let depth = tree_depth(voxels.level);
        let keys = (0..depth)
            .map(|d| {
                if d == 0 {
                    return vec![0];
                }
                let shift = 6 * (depth - d);
                let mut k: Vec<u64> = voxels.codes.iter().map(|c| c >> shift).collect();
                k.dedup();
                k
            })
            .collect();
        Self {
            voxels,
            depth,
            keys,
        }
    }

    /// Lookup nodes of the level.
    pub fn node_count(&self) -> usize {
        self.keys.iter().map(Vec::len).sum()
    }

    /// Replaces the voxels in each block (`blocks[i].0`: an aligned cube's code range,
    /// sorted and disjoint) by `blocks[i].1` (codes inside that range, sorted), updates
    /// the mirror, and returns the patch that turns the old streams into the new ones.
    pub fn splice(&mut self, blocks: &[((u64, u64), LevelVoxels)]) -> LevelPatch {
        let old_voxels = self.voxels.len() as u32;
        let old_nodes = self.node_count() as u32;
        let spans: Vec<(usize, usize)> = blocks
            .iter()
            .map(|((lo, hi), _)| {
                let codes = &self.voxels.codes;
                (lower_bound(codes, *lo), lower_bound(codes, *hi))
            })
            .collect();
        let voxel_runs = VoxelRuns::new(blocks, &spans, old_voxels);
        self.splice_voxels(blocks, &spans);
        let (changes, new_keys) = self.spliced_keys(blocks);
        let (node_words, node_segments) = self.node_runs(&changes, &new_keys, &voxel_runs.delta);
        self.keys = new_keys;
        LevelPatch {
            level: self.voxels.level,
            old_voxels,
            voxels: self.voxels.len() as u32,
            old_nodes,
            nodes: self.node_count() as u32,
            voxel_segments: voxel_runs.segments,
            node_segments,
            colors: voxel_runs.colors,
            normals: voxel_runs.normals,
            node_words,
        }
    }

    /// Replaces the mirror's voxels in each block's old span (`spans[i]`, indices into the
    /// old voxels) by the block's content.
    fn splice_voxels(&mut self, blocks: &[((u64, u64), LevelVoxels)], spans: &[(usize, usize)]) {
        // From the last block back (earlier spans stay valid): each splice moves the tail
        // once.
        for (((lo, hi), content), &(r0, r1)) in blocks.iter().zip(spans).rev() {
            debug_assert!(content.codes.iter().all(|c| (*lo..*hi).contains(c)));
            let v = &mut self.voxels;
            v.codes.splice(r0..r1, content.codes.iter().copied());
            v.normals.splice(r0..r1, content.normals.iter().copied());
            v.colors.splice(r0..r1, content.colors.iter().copied());
            v.uvs.splice(r0..r1, content.uvs.iter().copied());
        }
    }

    /// The node keys per depth after the mirror's voxels were spliced, and per depth the
    /// runs of nodes each block's interval of keys replaced.
    fn spliced_keys(
        &self,
        blocks: &[((u64, u64), LevelVoxels)],
    ) -> (Vec<Vec<Change>>, Vec<Vec<u64>>) {
        let new = &self.voxels;
        // Keys per depth, deepest first (a node's mask needs its children's keys).
        let depth = self.depth as usize;
        let mut changes: Vec<Vec<Change>> = vec![Vec::new(); depth];
        let mut new_keys: Vec<Vec<u64>> = vec![Vec::new(); depth];
        for d in (0..depth).rev() {
            let shift = 6 * (depth - d) as u32;
            let mut intervals: Vec<(u64, u64, u64)> = blocks
                .iter()
                .map(|((lo, hi), _)| (lo >> shift, (hi - 1) >> shift, hi - lo))
                .collect();
            intervals.dedup_by_key(|i| (i.0, i.1));
            let old_keys = &self.keys[d];
            let mut keys = Vec::with_capacity(old_keys.len() + 64);
            let mut prev = 0usize;
            for (k0, k1, span) in intervals {
                let (a, b) = (lower_bound(old_keys, k0), lower_bound(old_keys, k1 + 1));
                keys.extend_from_slice(&old_keys[prev..a]);
                let start = keys.len();
                if d == 0 {
                    keys.push(0); // the root is always there
                } else if (1u64 << shift) > span {
                    // A node larger than the block: there if any voxel is under it.
                    let i = lower_bound(&new.codes, k0 << shift);
                    if new.codes.get(i).is_some_and(|&c| c < (k0 + 1) << shift) {
                        keys.push(k0);
                    }
                } else {
                    // Nodes inside the block: one per distinct prefix of its new codes.
                    let i = lower_bound(&new.codes, k0 << shift);
                    let j = lower_bound(&new.codes, (k1 + 1) << shift);
                    for &c in &new.codes[i..j] {
                        // Keys before `start` are below `k0`: no false match.
                        if keys.last() != Some(&(c >> shift)) {
                            keys.push(c >> shift);
                        }
                    }
                }
                changes[d].push(Change {
                    last_key: k1,
                    old: a..b,
                    new: start..keys.len(),
                });
                prev = b;
            }
            keys.extend_from_slice(&old_keys[prev..]);
            new_keys[d] = keys;
        }
        (changes, new_keys)
    }

    /// The patch node words and the runs of the new node array, from the old keys (still
    /// in the mirror), the `changes` and `new_keys` of [`Self::spliced_keys`] and the
    /// voxel deltas of [`VoxelRuns`].
    fn node_runs(
        &self,
        changes: &[Vec<Change>],
        new_keys: &[Vec<u64>],
        voxel_delta: &[(u64, i64)],
    ) -> (Vec<u32>, Vec<Segment>) {
        let new = &self.voxels;
        let depth = self.depth as usize;
        let (old_off, new_off) = (depth_offsets(&self.keys), depth_offsets(new_keys));
        let mut node_words = Vec::new();
        let mut node_segments = Vec::new();
        let mut at = 0u32;
        for d in 0..depth {
            let leaf = d + 1 == depth;
            // The base delta of old nodes whose first child key is `child`.
            let moved = |child: u64| -> i32 {
                if leaf {
                    let v = voxel_delta.iter().take_while(|(end, _)| *end <= child);
                    v.last().map_or(0, |e| e.1) as i32
                } else {
                    let before: i64 = changes[d + 1]
                        .iter()
                        .take_while(|c| c.last_key < child)
                        .map(|c| c.new.len() as i64 - c.old.len() as i64)
                        .sum();
                    (new_off[d + 1] as i64 - old_off[d + 1] as i64 + before) as i32
                }
            };
            let mut prev = 0usize;
            let old_keys = &self.keys[d];
            for c in &changes[d] {
                let (a, b, s, e) = (c.old.start, c.old.end, c.new.start, c.new.end);
                if a > prev {
                    let source = Source::Old {
                        from: (old_off[d] + prev) as u32,
                        base_delta: moved(old_keys[prev] << 6),
                    };
                    push(&mut node_segments, &mut at, a - prev, source);
                }
                let from = (node_words.len() / NODE_WORDS) as u32;
                for &key in &new_keys[d][s..e] {
                    let (lo, hi) = (key << 6, (key + 1) << 6);
                    let children: &[u64] = if leaf { &new.codes } else { &new_keys[d + 1] };
                    let first = lower_bound(children, lo);
                    let mask = children[first..]
                        .iter()
                        .take_while(|&&c| c < hi)
                        .fold(0u64, |m, &c| m | 1 << (c & 63));
                    let base = if leaf {
                        first
                    } else if mask == 0 {
                        0
                    } else {
                        new_off[d + 1] + first
                    };
                    node_words.extend_from_slice(&[mask as u32, (mask >> 32) as u32, base as u32]);
                }
                push(&mut node_segments, &mut at, e - s, Source::Patch { from });
                prev = b;
            }
            if old_keys.len() > prev {
                let source = Source::Old {
                    from: (old_off[d] + prev) as u32,
                    base_delta: moved(old_keys[prev] << 6),
                };
                push(&mut node_segments, &mut at, old_keys.len() - prev, source);
            }
        }
        (node_words, node_segments)
    }
}

/// Index of each depth's first node in the level's node array, from the keys per depth.
fn depth_offsets(keys: &[Vec<u64>]) -> Vec<usize> {
    keys.iter()
        .scan(0usize, |s, v| {
            let o = *s;
            *s += v.len();
            Some(o)
        })
        .collect()
}

/// The voxel half of a level's patch: runs of the new voxel streams and the patch words.
struct VoxelRuns {
    /// Runs of the new colour and normal streams.
    segments: Vec<Segment>,
    /// Patch colours.
    colors: Vec<u32>,
    /// Patch normals.
    normals: Vec<u16>,
    /// (end of block, voxels added minus removed up to it): leaf bases after it move.
    delta: Vec<(u64, i64)>,
}

impl VoxelRuns {
    /// The runs that put each block's content in place of its old span (`spans[i]`) of a
    /// level of `old_voxels` voxels.
    fn new(
        blocks: &[((u64, u64), LevelVoxels)],
        spans: &[(usize, usize)],
        old_voxels: u32,
    ) -> Self {
        let (mut colors, mut normals) = (Vec::new(), Vec::new());
        let mut voxel_segments = Vec::new();
        let mut voxel_delta: Vec<(u64, i64)> = Vec::new();
        let (mut prev, mut delta, mut at) = (0usize, 0i64, 0u32);
        for (((_, hi), content), &(r0, r1)) in blocks.iter().zip(spans) {
            let head = Source::Old {
                from: prev as u32,
                base_delta: 0,
            };
            push(&mut voxel_segments, &mut at, r0 - prev, head);
            let from = colors.len() as u32;
            push(
                &mut voxel_segments,
                &mut at,
                content.len(),
                Source::Patch { from },
            );
            for i in 0..content.len() {
                let (c, n) = stream_words(content, i);
                colors.push(c);
                normals.push(n);
            }
            delta += content.len() as i64 - (r1 - r0) as i64;
            voxel_delta.push((*hi, delta));
            prev = r1;
        }
        let tail = Source::Old {
            from: prev as u32,
            base_delta: 0,
        };
        push(
            &mut voxel_segments,
            &mut at,
            old_voxels as usize - prev,
            tail,
        );
        Self {
            segments: voxel_segments,
            colors,
            normals,
            delta: voxel_delta,
        }
    }
}

#[cfg(test)]
mod tests;
