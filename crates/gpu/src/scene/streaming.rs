//! Pages by demand under a GPU memory budget: the GPU side of the page cache.
//!
//! Under a budget ([`StreamingOptions`]), the levels above [`PINNED_LEVEL`] are *paged*:
//! their lookup trees are uploaded down to the page nodes (one per occupied 16³ page),
//! and a page's leaves and voxels go to shared pools only when a ray needs them. Each
//! frame:
//!
//! 1. the filter marks, in `page_feedback`, every page it entered (touched) and every page
//!    of an instance's own LOD it needed and did not find (missing), and marches on in the
//!    next coarser LOD (`sparse_march.inc.wgsl`: never a hole);
//! 2. the feedback is copied to a staging buffer and mapped without waiting;
//! 3. before the next frame, every mapped feedback is read: touched pages become the most
//!    recently used ([`PageCache`]), missing pages are read from the asset (the cache file
//!    through [`PageFile`], or the asset in memory), checked, packed ([`pack_page`]) and
//!    written into the pools, evicting the least recently used pages that the latest
//!    frame did not need. A page that fails its checksum is refused and reported; its
//!    rays keep the coarser level.
//!
//! The coarsest levels (≤ [`PINNED_LEVEL`]) are always resident, so a missing page always
//! has a resident coarser cover. A view whose pages do not fit the budget lowers the
//! finest level instances may use ([`StreamingStats::level_cap`]) until they do.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex};

use crate::{GpuContext, wgpu};
use ssbvb_voxel::asset::{PackedVoxel, VoxelAsset};
use ssbvb_voxel::cache::{PageEntry, PageFile};
use ssbvb_voxel::lookup::NODE_WORDS;

use super::page_cache::{BLOCK_VOXELS, NODE_RUN, PageCache, SLOT_NODES, pack_page};
use crate::ResourceError;

/// Levels up to this one are resident whole under a budget (a level-5 grid is 32³ cells:
/// its pages are few and small), so every ray has a resident level to fall back to.
pub const PINNED_LEVEL: u32 = 5;

/// Under a budget, by default levels finer than this one draw this level's proxy in the
/// empty-space prepass ([`StreamingOptions::proxy_level`]).
pub const PROXY_LEVEL_UNDER_BUDGET: u32 = 9;

/// Bytes of a node slot.
pub const SLOT_BYTES: u64 = SLOT_NODES as u64 * NODE_WORDS as u64 * 4;
/// Bytes of a node run (the node pool's unit of allocation).
pub const RUN_BYTES: u64 = NODE_RUN as u64 * NODE_WORDS as u64 * 4;
/// Bytes of a voxel block (colour and normal).
pub const BLOCK_BYTES: u64 = BLOCK_VOXELS as u64 * ssbvb_voxel::asset::GPU_VOXEL_BYTES;
/// Most pool bytes one page can need: a slot and 64 blocks (64 leaves, one per block
/// at worst).
pub const MAX_PAGE_BYTES: u64 = SLOT_BYTES + 64 * BLOCK_BYTES;

/// How a scene is uploaded under a budget.
#[derive(Debug, Clone)]
pub struct StreamingOptions {
    /// GPU bytes the scene's voxel data may take (lookups, voxels, proxies).
    pub budget_bytes: u64,
    /// Per scene object, the cache file its pages are read from (`None`: from the asset
    /// in memory).
    pub page_files: Vec<Option<Arc<PageFile>>>,
    /// Most pages streamed in before one frame (more wait for the next frames, so no
    /// frame stalls on reading).
    pub max_pages_per_frame: usize,
    /// Levels finer than this one draw this level's proxy mesh in the empty-space prepass
    /// rather than their own, which is neither uploaded nor counted in the fixed part.
    /// A coarser proxy encloses every finer voxel, so rays start earlier (more march
    /// steps) but never past a surface; proxies grow 4× per level and would otherwise be
    /// most of the bytes that never leave (docs/architecture.md).
    pub proxy_level: u32,
}

impl StreamingOptions {
    /// A budget of `mib` MiB, pages from memory, 1024 pages per frame.
    pub fn mib(mib: u64) -> Self {
        Self {
            budget_bytes: mib << 20,
            page_files: Vec::new(),
            max_pages_per_frame: 1024,
            proxy_level: PROXY_LEVEL_UNDER_BUDGET,
        }
    }

    /// The same with a budget of `bytes`.
    pub fn with_budget(mut self, bytes: u64) -> Self {
        self.budget_bytes = bytes;
        self
    }

    /// The same with at most `n` pages streamed before a frame.
    pub fn with_pages_per_frame(mut self, n: usize) -> Self {
        self.max_pages_per_frame = n;
        self
    }
}

/// What streaming did, for reports (`render --json`'s `streaming`, the viewer, the bench).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct StreamingStats {
    /// The budget.
    pub budget_bytes: u64,
    /// Bytes that never leave: lookup trees down to the page nodes, pinned levels, proxies.
    pub fixed_bytes: u64,
    /// GPU bytes of the voxel scene now: the fixed part plus the pool space of the
    /// resident pages.
    pub bytes_resident: u64,
    /// Pages resident now.
    pub pages_resident: u64,
    /// Pages of every paged level.
    pub pages_total: u64,
    /// Pages streamed in since the start.
    pub pages_streamed: u64,
    /// Pages streamed in before the latest frame.
    pub pages_streamed_last_frame: u64,
    /// Pages evicted since the start.
    pub pages_evicted: u64,
    /// Pages the latest read feedback asked for (not resident when its frame ran).
    pub pages_missing: u64,
    /// Pages refused (failed to read or check); their rays keep a coarser level.
    pub pages_failed: u64,
    /// The latest feedback asked for more than fits in the budget beside what its frame
    /// used: some pages stay coarser.
    pub over_budget: bool,
    /// Node pool: runs of 16 nodes in use, and its capacity.
    pub node_runs: [u64; 2],
    /// Voxel pool: blocks of 64 voxels in use, and its capacity.
    pub voxel_blocks: [u64; 2],
    /// The finest level instances may use now (`None`: their own choice). Lowered when a
    /// view's pages do not fit the budget for several frames running, so the view shows
    /// the next coarser level everywhere rather than far coarser fallbacks where pages did
    /// not fit; raised again when the pools stay mostly empty.
    pub level_cap: Option<u32>,
}

/// Where one object's pages come from.
enum PageSource {
    File(Arc<PageFile>),
    Memory(Arc<VoxelAsset>),
}

/// One paged LOD.
struct PagedLod {
    object: usize,
    level: u32,
    /// Absolute index of the LOD's root node.
    node_offset: u32,
    /// Absolute index of its first page node.
    first_page_node: u32,
    entries: Vec<PageEntry>,
    /// Node runs and voxel blocks all its pages take.
    need: (u64, u64),
}

/// A staging buffer of the feedback ring.
struct Staging {
    buffer: wgpu::Buffer,
    /// FREE, RECORDED (copy recorded, not yet mapped), MAPPING, MAPPED, FAILED.
    state: Arc<AtomicU8>,
    frame: u64,
}

const FREE: u8 = 0;
const RECORDED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;
const FAILED: u8 = 4;
/// Converged feedbacks with mostly empty pools before the level cap rises by one.
const RAISE_AFTER: u64 = 30;
/// Frames whose pages are never evicted for another page (see `load`).
const KEEP_FRAMES: u64 = 2;
/// Bit sets of the feedback: missing, touched, ahead (`sparse_march.inc.wgsl`).
const FEEDBACK_SETS: u64 = 3;
/// Staging buffers: feedback of this many frames can be in flight.
const RING: usize = 3;

/// Builds the paged part of the scene (see [`super::GpuScene::streamed`]).
#[derive(Default)]
pub(crate) struct PagedLayoutBuilder {
    lods: Vec<PagedLod>,
    pages: u32,
}

impl PagedLayoutBuilder {
    pub(crate) fn new() -> Self {
        Self {
            lods: Vec::new(),
            pages: 0,
        }
    }

    /// Appends the tree of a paged LOD (down to its page nodes, all missing) to `nodes`:
    /// returns (page_base, first_page_node relative to the root).
    pub(crate) fn push_lod(
        &mut self,
        object: usize,
        level: u32,
        entries: Vec<PageEntry>,
        need: (u64, u64),
        nodes: &mut Vec<u32>,
    ) -> Result<(u32, u32), ResourceError> {
        let codes: Vec<u64> = entries.iter().map(|e| e.page).collect();
        // The tree over the level's pages is the top of the level's own tree: the same
        // Morton digits, two tree levels fewer (a page is 4² × 4 cells per axis).
        let top = ssbvb_voxel::lookup::SparseLookup::from_codes(level - 4, &codes);
        if top.depth + 2 != ssbvb_voxel::lookup::tree_depth(level) {
            return Err(ResourceError::BadScene(format!(
                "level {level} cannot be paged (tree depth {})",
                top.depth
            )));
        }
        let root = nodes.len() / NODE_WORDS;
        let top_nodes = top.node_count() as u32;
        // The top tree's leaves point at pages by rank: make them point at page nodes.
        let leaf_start = leaf_start(&top);
        for (i, n) in top.nodes.chunks_exact(NODE_WORDS).enumerate() {
            let base = if i >= leaf_start {
                n[2] + top_nodes
            } else {
                n[2]
            };
            nodes.extend_from_slice(&[n[0], n[1], base]);
        }
        for _ in &entries {
            nodes.extend_from_slice(&MISSING_PAGE_NODE);
        }
        let page_base = self.pages;
        self.pages = self
            .pages
            .checked_add(entries.len() as u32)
            .ok_or_else(|| ResourceError::TooLarge("more than 2^32 pages".into()))?;
        self.lods.push(PagedLod {
            object,
            level,
            node_offset: root as u32,
            first_page_node: root as u32 + top_nodes,
            entries,
            need,
        });
        Ok((page_base, top_nodes))
    }

    /// Node runs and voxel blocks all pages of every paged LOD take.
    pub(crate) fn need(&self) -> (u64, u64) {
        self.lods
            .iter()
            .fold((0, 0), |a, l| (a.0 + l.need.0, a.1 + l.need.1))
    }

    /// Pages of every paged LOD.
    pub(crate) fn pages(&self) -> u32 {
        self.pages
    }
}

/// A page node whose page is not resident: every leaf possibly present, no leaves.
const MISSING_PAGE_NODE: [u32; 3] = [u32::MAX, u32::MAX, u32::MAX];

/// Index of the first node at the deepest depth of a lookup tree (breadth-first order).
pub(crate) fn leaf_start(l: &ssbvb_voxel::lookup::SparseLookup) -> usize {
    depth_range(l, l.depth - 1).start
}

/// The nodes at tree depth `d` (0 = the root) of a lookup tree (breadth-first order).
fn depth_range(l: &ssbvb_voxel::lookup::SparseLookup, d: u32) -> std::ops::Range<usize> {
    let (mut start, mut count) = (0usize, 1usize);
    for _ in 0..d {
        let next: usize = l.nodes[start * NODE_WORDS..(start + count) * NODE_WORDS]
            .chunks_exact(NODE_WORDS)
            .map(|n| (n[0].count_ones() + n[1].count_ones()) as usize)
            .sum();
        start += count;
        count = next;
    }
    start..start + count
}

/// Node runs and voxel blocks all pages of a level take (blocks estimated: first fit
/// leaves a block about a tenth empty).
pub(crate) fn pool_need(
    l: &ssbvb_voxel::lookup::SparseLookup,
    entries: &[PageEntry],
) -> (u64, u64) {
    let runs = if l.depth >= 2 {
        l.nodes[depth_range(l, l.depth - 2).start * NODE_WORDS..]
            .chunks_exact(NODE_WORDS)
            .take(entries.len())
            .map(|n| ((n[0].count_ones() + n[1].count_ones()) as u64).div_ceil(NODE_RUN as u64))
            .sum()
    } else {
        0
    };
    let voxels = l.voxel_count();
    let blocks: u64 = (0..entries.len())
        .map(|k| {
            let end = entries.get(k + 1).map_or(voxels, |n| n.first_voxel);
            (end - entries[k].first_voxel).div_ceil(BLOCK_VOXELS as u64)
        })
        .sum();
    (runs, blocks + blocks / 10)
}

/// The page cache of a scene on the GPU.
pub struct Streaming {
    cache: PageCache,
    /// Global page id → (paged LOD, page index in it).
    pages: Vec<(u32, u32)>,
    lods: Vec<PagedLod>,
    sources: Vec<PageSource>,
    node_pool_start: u32,
    voxel_pool_start: u32,
    /// The frame's feedback (missing bits, then touched bits).
    pub(crate) feedback: wgpu::Buffer,
    feedback_words: u64,
    ring: Vec<Staging>,
    frame: u64,
    max_pages_per_frame: usize,
    stats: StreamingStats,
    errors: Mutex<Vec<String>>,
    /// Feedbacks in a row over budget, and converged with the pools mostly empty.
    over_streak: u64,
    roomy_streak: u64,
    /// The finest paged level of the scene.
    finest: u32,
    proxy_level: u32,
}

/// Buffers the streamer writes into (the scene's streams).
pub(crate) struct StreamBuffers<'a> {
    /// The word stream's bindings (LOD table, colours, normals).
    pub words: &'a [wgpu::Buffer],
    /// First word of the colours in the word stream.
    pub color_word_base: u64,
    /// First word of the normals in the word stream.
    pub normal_word_base: u64,
    pub nodes: &'a [wgpu::Buffer],
    /// Bytes per binding of the word stream.
    pub word_chunk_bytes: u64,
    /// Bytes per binding of the node stream.
    pub node_chunk_bytes: u64,
}

impl StreamBuffers<'_> {
    /// Writes lookup nodes (`NODE_WORDS` words each) from absolute node `first` on.
    fn write_nodes(&self, ctx: &GpuContext, first: u64, words: &[u32]) {
        let at = first * NODE_WORDS as u64 * 4;
        write_stream(
            ctx,
            self.nodes,
            self.node_chunk_bytes,
            at,
            bytemuck::cast_slice(words),
        );
    }
}

/// Writes `data` at byte `offset` of a stream split into bindings of `chunk` bytes.
fn write_stream(ctx: &GpuContext, buffers: &[wgpu::Buffer], chunk: u64, offset: u64, data: &[u8]) {
    let mut at = offset;
    let mut rest = data;
    while !rest.is_empty() {
        let (i, o) = ((at / chunk) as usize, at % chunk);
        let n = rest.len().min((chunk - o) as usize);
        if let Some(b) = buffers.get(i) {
            ctx.queue.write_buffer(b, o, &rest[..n]);
        }
        rest = &rest[n..];
        at += n as u64;
    }
}

impl Streaming {
    /// The streamer of a built layout: pools of `slots` node slots at node
    /// `node_pool_start` and `blocks` voxel blocks at voxel `voxel_pool_start`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        ctx: &GpuContext,
        layout: PagedLayoutBuilder,
        assets: Vec<Arc<VoxelAsset>>,
        options: &StreamingOptions,
        node_pool_start: u32,
        voxel_pool_start: u32,
        slots: u32,
        blocks: u32,
        fixed_bytes: u64,
    ) -> Self {
        let finest = layout.lods.iter().map(|l| l.level).max().unwrap_or(0);
        let mut pages = Vec::with_capacity(layout.pages as usize);
        for (i, l) in layout.lods.iter().enumerate() {
            pages.extend((0..l.entries.len() as u32).map(|k| (i as u32, k)));
        }
        let sources = assets
            .into_iter()
            .enumerate()
            .map(
                |(o, a)| match options.page_files.get(o).cloned().flatten() {
                    Some(f) => PageSource::File(f),
                    None => PageSource::Memory(a),
                },
            )
            .collect();
        // Three bit sets (missing, touched, ahead); at least one word each.
        let feedback_words = (layout.pages as u64).div_ceil(32).max(1);
        let feedback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("page feedback"),
            size: FEEDBACK_SETS * 4 * feedback_words,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let ring = (0..RING)
            .map(|_| Staging {
                buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("page feedback readback"),
                    size: FEEDBACK_SETS * 4 * feedback_words,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                state: Arc::new(AtomicU8::new(FREE)),
                frame: 0,
            })
            .collect();
        let stats = StreamingStats {
            budget_bytes: options.budget_bytes,
            fixed_bytes,
            bytes_resident: fixed_bytes,
            pages_total: layout.pages as u64,
            ..Default::default()
        };
        Self {
            cache: PageCache::new(layout.pages as usize, slots, blocks),
            pages,
            lods: layout.lods,
            sources,
            node_pool_start,
            voxel_pool_start,
            feedback,
            feedback_words,
            ring,
            frame: 0,
            max_pages_per_frame: options.max_pages_per_frame.max(1),
            finest,
            proxy_level: options.proxy_level,
            stats,
            errors: Mutex::new(Vec::new()),
            over_streak: 0,
            roomy_streak: 0,
        }
    }

    /// The finest level instances may use now (see [`StreamingStats::level_cap`]).
    pub fn level_cap(&self) -> Option<u32> {
        self.stats.level_cap
    }

    /// The finest level whose own proxy is drawn ([`StreamingOptions::proxy_level`]).
    pub fn proxy_level(&self) -> u32 {
        self.proxy_level
    }

    /// What streaming did so far.
    pub fn stats(&self) -> &StreamingStats {
        &self.stats
    }

    /// Pages refused so far, with why (each once).
    pub fn errors(&self) -> Vec<String> {
        self.errors.lock().map(|e| e.clone()).unwrap_or_default()
    }

    /// Clears the frame's feedback (at the start of the frame's commands).
    pub(crate) fn begin_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        self.frame += 1;
        encoder.clear_buffer(&self.feedback, 0, None);
    }

    /// Copies the frame's feedback to a free staging buffer (at the end of the frame's
    /// commands); when none is free the frame's feedback is dropped (a later frame asks
    /// again), never waited for.
    pub(crate) fn end_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(s) = self
            .ring
            .iter_mut()
            .find(|s| s.state.load(Ordering::Acquire) == FREE)
        {
            encoder.copy_buffer_to_buffer(
                &self.feedback,
                0,
                &s.buffer,
                0,
                FEEDBACK_SETS * 4 * self.feedback_words,
            );
            s.frame = self.frame;
            s.state.store(RECORDED, Ordering::Release);
        }
    }

    /// Maps the staging buffers whose copies were just submitted.
    pub(crate) fn after_submit(&mut self) {
        for s in &self.ring {
            if s.state.load(Ordering::Acquire) == RECORDED {
                s.state.store(MAPPING, Ordering::Release);
                let state = s.state.clone();
                s.buffer.map_async(wgpu::MapMode::Read, .., move |r| {
                    state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
                });
            }
        }
    }

    /// Whether a feedback copy is in flight (mapped or being mapped).
    pub fn feedback_pending(&self) -> bool {
        self.ring
            .iter()
            .any(|s| s.state.load(Ordering::Acquire) != FREE)
    }

    /// Reads every feedback that is ready (oldest first) and streams the pages it asks for
    /// (at most `max_pages_per_frame`). With `wait`, first waits for the GPU so that the
    /// latest frame's feedback is ready (offline rendering); otherwise never blocks.
    pub(crate) fn service(
        &mut self,
        ctx: &GpuContext,
        buffers: &StreamBuffers<'_>,
        wait: bool,
    ) -> Result<(), ResourceError> {
        let poll = if wait {
            wgpu::PollType::wait_indefinitely()
        } else {
            wgpu::PollType::Poll
        };
        ctx.device.poll(poll).map_err(|e| {
            ResourceError::Gpu(crate::GpuError::Readback {
                label: "page feedback".into(),
                message: e.to_string(),
            })
        })?;
        let mut ready: Vec<usize> = (0..self.ring.len())
            .filter(|&i| matches!(self.ring[i].state.load(Ordering::Acquire), MAPPED | FAILED))
            .collect();
        ready.sort_by_key(|&i| self.ring[i].frame);
        self.stats.pages_streamed_last_frame = 0;
        for i in ready {
            let s = &self.ring[i];
            let frame = s.frame;
            let words: Option<Vec<u32>> = if s.state.load(Ordering::Acquire) == MAPPED {
                let w = s
                    .buffer
                    .slice(..)
                    .get_mapped_range()
                    .ok()
                    .map(|m| bytemuck::pod_collect_to_vec(&m[..]));
                s.buffer.unmap();
                w
            } else {
                None
            };
            s.state.store(FREE, Ordering::Release);
            if let Some(words) = words {
                self.apply_feedback(ctx, buffers, &words, frame);
            }
        }
        Ok(())
    }

    /// Touches the pages of `frame`'s feedback and streams in its missing ones.
    fn apply_feedback(
        &mut self,
        ctx: &GpuContext,
        buffers: &StreamBuffers<'_>,
        words: &[u32],
        frame: u64,
    ) {
        let half = self.feedback_words as usize;
        let bits = |w: &[u32]| -> Vec<u32> {
            let mut out = Vec::new();
            for (i, &word) in w.iter().enumerate() {
                let mut m = word;
                while m != 0 {
                    out.push(i as u32 * 32 + m.trailing_zeros());
                    m &= m - 1;
                }
            }
            out
        };
        let total = self.pages.len() as u32;
        if words.len() < 3 * half {
            return;
        }
        for p in bits(&words[half..2 * half]) {
            if p < total {
                self.cache.touch(p, frame);
            }
        }
        let wanted = |w: &[u32], cache: &PageCache| -> Vec<u32> {
            bits(w)
                .into_iter()
                .filter(|&p| p < total && !cache.is_failed(p) && !cache.is_resident(p))
                .collect()
        };
        let missing = wanted(&words[..half], &self.cache);
        let ahead = wanted(&words[2 * half..3 * half], &self.cache);
        self.stats.pages_missing = missing.len() as u64;
        self.stats.over_budget = false;
        // Needed pages first, as used in `frame`; then pages found looking ahead, as never
        // used (the first to leave, and they evict only each other), while they fit.
        let needed = missing.iter().map(|&p| (p, frame));
        let later = ahead.iter().map(|&p| (p, 0));
        for (p, used) in needed.chain(later).take(self.max_pages_per_frame) {
            if self.cache.is_resident(p) {
                continue;
            }
            match self.load(ctx, buffers, p, used, frame) {
                Ok(true) => {}
                Ok(false) if used == 0 => break,
                Ok(false) => {
                    self.stats.over_budget = true;
                    break;
                }
                Err(e) => {
                    self.cache.mark_failed(p);
                    self.stats.pages_failed += 1;
                    if let Ok(mut errors) = self.errors.lock() {
                        errors.push(e);
                    }
                }
            }
        }
        self.adjust_level_cap(&missing);
        let (runs, blocks) = self.cache.used();
        let (slots, capacity) = self.cache.capacity();
        self.stats.node_runs = [runs as u64, slots as u64 * (SLOT_NODES / NODE_RUN) as u64];
        self.stats.voxel_blocks = [blocks as u64, capacity as u64];
        self.stats.pages_resident = self.cache.resident() as u64;
        self.stats.bytes_resident =
            self.stats.fixed_bytes + runs as u64 * RUN_BYTES + blocks as u64 * BLOCK_BYTES;
    }

    /// Lowers the level cap below the finest missing level after `KEEP_FRAMES + 1`
    /// feedbacks in a row over budget (by then the pages of an earlier view have become
    /// evictable, so the view itself does not fit); raises it one level after
    /// `RAISE_AFTER` converged feedbacks with less than a quarter of the pools in use.
    fn adjust_level_cap(&mut self, missing: &[u32]) {
        let level_of = |p: u32| self.lods[self.pages[p as usize].0 as usize].level;
        if self.stats.over_budget {
            self.over_streak += 1;
            self.roomy_streak = 0;
            if self.over_streak > KEEP_FRAMES {
                self.over_streak = 0;
                if let Some(finest) = missing.iter().map(|&p| level_of(p)).max() {
                    let cap = (finest - 1).max(PINNED_LEVEL);
                    self.stats.level_cap = Some(self.stats.level_cap.map_or(cap, |c| c.min(cap)));
                }
            }
            return;
        }
        self.over_streak = 0;
        let (runs, blocks) = self.cache.used();
        let (slots, capacity) = self.cache.capacity();
        let used = runs as u64 * RUN_BYTES + blocks as u64 * BLOCK_BYTES;
        let pool = slots as u64 * SLOT_BYTES + capacity as u64 * BLOCK_BYTES;
        if missing.is_empty() && self.stats.level_cap.is_some() && used * 4 < pool {
            self.roomy_streak += 1;
            if self.roomy_streak >= RAISE_AFTER {
                self.roomy_streak = 0;
                self.stats.level_cap = self
                    .stats
                    .level_cap
                    .map(|c| c + 1)
                    .filter(|&c| c < self.finest);
            }
        } else {
            self.roomy_streak = 0;
        }
    }

    /// Reads, packs and uploads page `p`: `Ok(false)` when it does not fit beside the
    /// pages of the latest frame, an error (naming the page) when it cannot be read.
    fn load(
        &mut self,
        ctx: &GpuContext,
        buffers: &StreamBuffers<'_>,
        p: u32,
        used: u64,
        frame: u64,
    ) -> Result<bool, String> {
        let (li, k) = self.pages[p as usize];
        let lod = &self.lods[li as usize];
        let voxels: Vec<PackedVoxel> = match &self.sources[lod.object] {
            PageSource::File(f) => f
                .read_page(lod.level, k as usize)
                .map_err(|e| e.to_string())?,
            PageSource::Memory(a) => {
                let cloud = &a.lods[lod.level as usize].point_cloud.voxels;
                let e = lod.entries[k as usize];
                let end = lod
                    .entries
                    .get(k as usize + 1)
                    .map_or(cloud.len() as u64, |n| n.first_voxel);
                cloud[e.first_voxel as usize..end as usize].to_vec()
            }
        };
        let packed = pack_page(&voxels);
        // Pages used in the last KEEP_FRAMES frames stay: a view needs pages its rays did
        // not reach this frame (they stopped at a missing page before), and evicting them
        // would make the view thrash instead of settling at coarser voxels.
        let (res, evicted) = self.cache.admit(
            p,
            packed.leaves.len() as u32,
            packed.blocks.len() as u32,
            used,
            if used == 0 {
                1
            } else {
                frame.saturating_sub(KEEP_FRAMES)
            },
        );
        for q in evicted {
            self.write_page_node(ctx, buffers, q, MISSING_PAGE_NODE);
            self.stats.pages_evicted += 1;
        }
        let Some(res) = res else {
            return Ok(false);
        };
        let lod = &self.lods[li as usize];
        let block_start = |b: u32| {
            self.voxel_pool_start as u64 + res.blocks[b as usize] as u64 * BLOCK_VOXELS as u64
        };
        // Leaves into the page's slot.
        let slot_node = self.node_pool_start as u64 + res.first_node as u64;
        let leaves: Vec<u32> = packed
            .leaves
            .iter()
            .flat_map(|&(mask, b, o)| {
                [
                    mask as u32,
                    (mask >> 32) as u32,
                    (block_start(b) + o as u64) as u32,
                ]
            })
            .collect();
        buffers.write_nodes(ctx, slot_node, &leaves);
        // Voxels into the blocks (a block starts at an even voxel: whole normal words).
        for (b, block) in packed.blocks.iter().enumerate() {
            let g = block_start(b as u32);
            let colors: Vec<u32> = block.iter().map(|v| v.0).collect();
            let mut normals: Vec<u16> = block.iter().map(|v| v.1).collect();
            if normals.len() % 2 == 1 {
                normals.push(0);
            }
            write_stream(
                ctx,
                buffers.words,
                buffers.word_chunk_bytes,
                (buffers.color_word_base + g) * 4,
                bytemuck::cast_slice(&colors),
            );
            write_stream(
                ctx,
                buffers.words,
                buffers.word_chunk_bytes,
                buffers.normal_word_base * 4 + g * 2,
                bytemuck::cast_slice(&normals),
            );
        }
        // Last, the page node: the page is now reachable.
        let base = slot_node as u32 - lod.node_offset;
        self.write_page_node(
            ctx,
            buffers,
            p,
            [packed.mask as u32, (packed.mask >> 32) as u32, base],
        );
        self.stats.pages_streamed += 1;
        self.stats.pages_streamed_last_frame += 1;
        Ok(true)
    }

    fn write_page_node(
        &self,
        ctx: &GpuContext,
        buffers: &StreamBuffers<'_>,
        p: u32,
        node: [u32; 3],
    ) {
        let (li, k) = self.pages[p as usize];
        let n = self.lods[li as usize].first_page_node as u64 + k as u64;
        buffers.write_nodes(ctx, n, &node);
    }

    /// Evicts every page (the next frames stream them again).
    pub(crate) fn evict_all(&mut self, ctx: &GpuContext, buffers: &StreamBuffers<'_>) {
        for p in self.cache.clear() {
            self.write_page_node(ctx, buffers, p, MISSING_PAGE_NODE);
            self.stats.pages_evicted += 1;
        }
        self.stats.pages_resident = 0;
        self.stats.bytes_resident = self.stats.fixed_bytes;
    }
}
