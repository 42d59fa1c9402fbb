//! The CPU side of the GPU page cache: which 16³ pages are resident where, which leave
//! first (least recently used), and how one page's voxels are laid out in the pools.
//!
//! A resident page owns 1–8 consecutive runs of [`NODE_RUN`] lookup nodes in one slot of
//! [`SLOT_NODES`] (its 4³ leaves, which must be contiguous) and as many blocks of
//! [`BLOCK_VOXELS`] voxels as its leaves need. Small fixed units keep the space a page
//! wastes to a fraction of a run and of a block (a surface page at level 8 holds ~25
//! leaves and ~175 voxels); a leaf never straddles two blocks, so each leaf's `base` is
//! the pool index of its first voxel and blocks need not be contiguous. The GPU side (uploads,
//! feedback) is `streaming.rs`.

use std::collections::BTreeSet;

use ssbvb_voxel::asset::PackedVoxel;
use ssbvb_voxel::svo::morton_encode;

/// Lookup nodes of a node-pool slot: a 16³ page has at most 64 leaves of 4³ cells.
pub const SLOT_NODES: u32 = 64;
/// Nodes of a run, the unit of node allocation (a page with up to 8 leaves takes one).
pub const NODE_RUN: u32 = 8;
const RUNS_PER_SLOT: usize = (SLOT_NODES / NODE_RUN) as usize;
/// Voxels of a pool block: a leaf's voxels (at most 4³) always fit in one.
pub const BLOCK_VOXELS: u32 = 64;

/// One page's leaves and voxels, packed for the pools but not yet placed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PackedPage {
    /// The page node's mask: bit = Morton order of the leaf inside the page.
    pub mask: u64,
    /// Per present leaf (in bit order): its mask, its block (index into the page's blocks)
    /// and its first voxel's offset in that block.
    pub leaves: Vec<(u64, u32, u32)>,
    /// Per block, its voxels' colours and 16-bit normals, in pool order.
    pub blocks: Vec<Vec<(u32, u16)>>,
}

/// Packs the voxels of one page (Morton order, all inside one 16³ page, as
/// `PageFile::read_page` checks) into leaves and blocks.
pub fn pack_page(voxels: &[PackedVoxel]) -> PackedPage {
    let mut page = PackedPage {
        mask: 0,
        leaves: Vec::new(),
        blocks: Vec::new(),
    };
    let mut i = 0;
    while i < voxels.len() {
        let leaf = (morton_encode(voxels[i].cell()) >> 6) & 63;
        let mut j = i;
        let mut mask = 0u64;
        while j < voxels.len() && (morton_encode(voxels[j].cell()) >> 6) & 63 == leaf {
            mask |= 1 << (morton_encode(voxels[j].cell()) & 63);
            j += 1;
        }
        let n = j - i;
        // First fit: a leaf's voxels go to the first block with room for all of them.
        let b = match page
            .blocks
            .iter()
            .position(|b| b.len() + n <= BLOCK_VOXELS as usize)
        {
            Some(b) => b,
            None => {
                page.blocks.push(Vec::with_capacity(BLOCK_VOXELS as usize));
                page.blocks.len() - 1
            }
        };
        let block = &mut page.blocks[b];
        page.leaves.push((mask, b as u32, block.len() as u32));
        block.extend(
            voxels[i..j]
                .iter()
                .map(|v| (v.color, (v.z_normal >> 16) as u16)),
        );
        page.mask |= 1 << leaf;
        i = j;
    }
    page
}

/// Where a resident page lives.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Residence {
    /// Its leaves: the first node (a multiple of [`NODE_RUN`]) in the node pool.
    pub first_node: u32,
    /// Node runs it holds (consecutive).
    pub runs: u32,
    /// Its blocks in the voxel pool.
    pub blocks: Vec<u32>,
}

#[derive(Debug, Clone, Default)]
struct PageState {
    residence: Option<Residence>,
    last_used: u64,
    failed: bool,
}

/// The node pool: slots of [`SLOT_NODES`] nodes, each cut into eight runs of [`NODE_RUN`];
/// a page takes 1–8 consecutive runs of one slot (its leaves must be contiguous).
#[derive(Debug, Clone)]
struct NodePool {
    /// Per slot, a bit per taken run.
    taken: Vec<u8>,
    /// Slots by their longest free stretch of runs (index 0..=8).
    by_room: [BTreeSet<u32>; RUNS_PER_SLOT + 1],
}

/// `k` consecutive run bits (k ≤ 8).
fn run_mask(k: u32) -> u8 {
    ((1u16 << k) - 1) as u8
}

/// The longest stretch of free runs in a slot's eight.
fn room(taken: u8) -> usize {
    let mut best = 0;
    let mut cur = 0;
    for i in 0..RUNS_PER_SLOT {
        if taken >> i & 1 == 0 {
            cur += 1;
            best = best.max(cur);
        } else {
            cur = 0;
        }
    }
    best
}

impl NodePool {
    fn new(slots: u32) -> Self {
        let mut by_room: [BTreeSet<u32>; RUNS_PER_SLOT + 1] = Default::default();
        by_room[RUNS_PER_SLOT] = (0..slots).collect();
        Self {
            taken: vec![0; slots as usize],
            by_room,
        }
    }

    fn take(&mut self, runs: u32) -> Option<u32> {
        let k = runs as usize;
        let slot = (k..=RUNS_PER_SLOT).find_map(|r| self.by_room[r].first().copied())?;
        let t = self.taken[slot as usize];
        let at = (0..=RUNS_PER_SLOT - k).find(|&p| (0..k).all(|i| t >> (p + i) & 1 == 0))?;
        self.set(slot, t | (run_mask(k as u32) << at));
        Some(slot * SLOT_NODES + at as u32 * NODE_RUN)
    }

    fn give(&mut self, first_node: u32, runs: u32) {
        let slot = first_node / SLOT_NODES;
        let at = (first_node % SLOT_NODES) / NODE_RUN;
        let t = self.taken[slot as usize];
        self.set(slot, t & !(run_mask(runs) << at));
    }

    fn set(&mut self, slot: u32, taken: u8) {
        let old = room(self.taken[slot as usize]);
        self.by_room[old].remove(&slot);
        self.taken[slot as usize] = taken;
        self.by_room[room(taken)].insert(slot);
    }

    fn runs_taken(&self) -> u32 {
        self.taken.iter().map(|t| t.count_ones()).sum()
    }
}

/// Residency of every page of the scene's paged LODs in a node pool of `slots` slots and
/// a voxel pool of `blocks` blocks, with least-recently-used eviction.
#[derive(Debug, Clone)]
pub struct PageCache {
    nodes: NodePool,
    free_blocks: Vec<u32>,
    slots: u32,
    blocks: u32,
    pages: Vec<PageState>,
    lru: BTreeSet<(u64, u32)>,
}

impl PageCache {
    /// An empty cache for `pages` pages.
    pub fn new(pages: usize, slots: u32, blocks: u32) -> Self {
        Self {
            nodes: NodePool::new(slots),
            free_blocks: (0..blocks).rev().collect(),
            slots,
            blocks,
            pages: vec![PageState::default(); pages],
            lru: BTreeSet::new(),
        }
    }

    /// Whether `page` is resident.
    pub fn is_resident(&self, page: u32) -> bool {
        self.pages
            .get(page as usize)
            .is_some_and(|p| p.residence.is_some())
    }

    /// Whether `page` was refused (it failed to read or check).
    pub fn is_failed(&self, page: u32) -> bool {
        self.pages.get(page as usize).is_some_and(|p| p.failed)
    }

    /// Marks `page` refused: it is never requested again.
    pub fn mark_failed(&mut self, page: u32) {
        if let Some(p) = self.pages.get_mut(page as usize) {
            p.failed = true;
        }
    }

    /// Records that `page` was used in frame `frame`.
    pub fn touch(&mut self, page: u32, frame: u64) {
        let Some(p) = self.pages.get_mut(page as usize) else {
            return;
        };
        if p.residence.is_some() {
            if p.last_used < frame {
                self.lru.remove(&(p.last_used, page));
                p.last_used = frame;
                self.lru.insert((frame, page));
            }
        } else {
            p.last_used = p.last_used.max(frame);
        }
    }

    /// Resident pages.
    pub fn resident(&self) -> usize {
        self.lru.len()
    }

    /// Node runs and voxel blocks in use.
    pub fn used(&self) -> (u32, u32) {
        (
            self.nodes.runs_taken(),
            self.blocks - self.free_blocks.len() as u32,
        )
    }

    /// Pool capacity: node slots and voxel blocks.
    pub fn capacity(&self) -> (u32, u32) {
        (self.slots, self.blocks)
    }

    /// Makes `page` resident with `leaves` leaf nodes and `blocks` voxel blocks, as last
    /// used in frame `frame` (0: never, the first to leave), evicting least recently used pages last used before `keep_from`
    /// (pages the latest frame needed stay) until it fits. Returns where it goes and the
    /// pages evicted (whose page nodes must be marked missing), or `None` (with the pages
    /// evicted on the way, if any) when it does not fit.
    pub fn admit(
        &mut self,
        page: u32,
        leaves: u32,
        blocks: u32,
        frame: u64,
        keep_from: u64,
    ) -> (Option<Residence>, Vec<u32>) {
        let mut evicted = Vec::new();
        if self.is_resident(page) || page as usize >= self.pages.len() || leaves > SLOT_NODES {
            return (None, evicted);
        }
        let runs = leaves.div_ceil(NODE_RUN).max(1);
        if blocks > self.blocks || self.slots == 0 {
            return (None, evicted);
        }
        loop {
            if self.free_blocks.len() >= blocks as usize {
                if let Some(first_node) = self.nodes.take(runs) {
                    let taken = self.free_blocks.len() - blocks as usize;
                    let residence = Residence {
                        first_node,
                        runs,
                        blocks: self.free_blocks.split_off(taken),
                    };
                    let state = &mut self.pages[page as usize];
                    state.residence = Some(residence.clone());
                    state.last_used = frame;
                    self.lru.insert((state.last_used, page));
                    return (Some(residence), evicted);
                }
            }
            match self.lru.first() {
                Some(&(used, p)) if used < keep_from => {
                    self.evict(p);
                    evicted.push(p);
                }
                _ => return (None, evicted),
            }
        }
    }

    fn evict(&mut self, p: u32) {
        let state = &mut self.pages[p as usize];
        self.lru.remove(&(state.last_used, p));
        if let Some(r) = state.residence.take() {
            self.nodes.give(r.first_node, r.runs);
            self.free_blocks.extend(r.blocks);
        }
    }

    /// Evicts every page.
    pub fn clear(&mut self) -> Vec<u32> {
        let all: Vec<u32> = self.lru.iter().map(|&(_, p)| p).collect();
        for &p in &all {
            self.evict(p);
        }
        all
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ssbvb_voxel::asset::SparseLookup;

    #[test]
    fn a_packed_page_has_the_lookups_leaves() {
        // Level 6 (4 pages per axis): a sphere shell, checked page by page against the
        // full lookup's leaf nodes.
        let mut cells = Vec::new();
        for x in 0..64u32 {
            for y in 0..64u32 {
                for z in 0..64u32 {
                    let d = [x, y, z].map(|c| c as f64 - 31.5);
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if (20.0..24.0).contains(&r) || (x == 5 && y < 40) {
                        cells.push([x, y, z]);
                    }
                }
            }
        }
        let lookup = SparseLookup::from_cells(6, cells.iter().copied());
        let mut voxels: Vec<PackedVoxel> = cells
            .iter()
            .map(|&c| {
                PackedVoxel::new(
                    c,
                    [0.0, 1.0, 0.0],
                    [c[0] as f32 / 64.0, 0.5, 0.0, 1.0],
                    [0.0; 2],
                )
            })
            .collect();
        voxels.sort_by_key(|v| morton_encode(v.cell()));
        let index = ssbvb_voxel::cache::page_index(&voxels);
        let mut seen = 0;
        for (k, e) in index.iter().enumerate() {
            let end = index
                .get(k + 1)
                .map_or(voxels.len(), |n| n.first_voxel as usize);
            let page_voxels = &voxels[e.first_voxel as usize..end];
            let packed = pack_page(page_voxels);
            // Every voxel is found again through mask, leaf and block.
            let mut n = 0;
            for (li, &(mask, block, offset)) in packed.leaves.iter().enumerate() {
                let leaf_bit = (0..64)
                    .filter(|b| packed.mask >> b & 1 == 1)
                    .nth(li)
                    .unwrap();
                for (r, bit) in (0..64).filter(|b| mask >> b & 1 == 1).enumerate() {
                    let code = (e.page << 12) | (leaf_bit << 6) | bit;
                    let cell = ssbvb_voxel::svo::morton_decode(code);
                    let id = lookup.get(cell).expect("a packed voxel is in the lookup");
                    let (color, normal) =
                        packed.blocks[block as usize][(offset + r as u32) as usize];
                    assert_eq!(color, voxels[id as usize].color);
                    assert_eq!(normal as u32, voxels[id as usize].z_normal >> 16);
                    n += 1;
                }
            }
            assert_eq!(n, page_voxels.len());
            assert!(
                packed
                    .blocks
                    .iter()
                    .all(|b| b.len() <= BLOCK_VOXELS as usize)
            );
            // First fit fills blocks at least half on average.
            assert!(packed.blocks.len() <= 2 * page_voxels.len().div_ceil(64));
            seen += n;
        }
        assert_eq!(seen, voxels.len());
        assert!(index.len() > 20, "{} pages", index.len());
    }

    #[test]
    fn least_recently_used_pages_leave_first_and_recent_ones_stay() {
        // One slot (8 runs of 8 nodes), 6 blocks.
        let mut c = PageCache::new(10, 1, 6);
        // Frames 1..3 admit pages 0 and 1 (20 leaves: three runs) and 2 (16: two runs),
        // two blocks each: runs and blocks are full.
        for p in 0..2 {
            let (r, ev) = c.admit(p, 20, 2, p as u64 + 1, 0);
            assert!(ev.is_empty());
            let r = r.unwrap();
            assert_eq!(
                (r.runs, r.blocks.len(), r.first_node),
                (3, 2, 3 * NODE_RUN * p)
            );
        }
        assert_eq!(c.used(), (6, 4));
        let (r, ev) = c.admit(2, 16, 2, 3, 0);
        assert_eq!((r.unwrap().runs, ev), (2, vec![]));
        assert_eq!(c.used(), (8, 6));
        // Page 0 is used again in frame 4: page 1 is now the oldest.
        c.touch(0, 4);
        let (r, ev) = c.admit(3, 16, 2, 5, 5);
        assert!(r.is_some());
        assert_eq!(ev, vec![1]);
        assert!(!c.is_resident(1) && c.is_resident(0) && c.is_resident(3));
        // A page with 40 leaves needs five consecutive runs: it evicts the oldest pages
        // until five free runs are adjacent (2, then 0: runs 0..=2 and 6..=7 free, not
        // adjacent; then 3).
        let (r, ev) = c.admit(4, 40, 2, 6, 6);
        let r = r.unwrap();
        assert_eq!(r.runs, 5);
        assert_eq!(ev, vec![2, 0, 3]);
        assert_eq!(c.used(), (5, 2));
        // Pages used in the frames to keep are never evicted: no room, nothing evicted.
        assert!(c.admit(5, 30, 1, 7, 6).0.is_none());
        assert!(c.is_resident(4));
        // A page with more blocks than the pool never fits, and evicts nothing.
        assert_eq!(c.admit(6, 1, 7, 8, 100), (None, vec![]));
        // Runs and blocks are conserved.
        let evicted = c.clear();
        assert_eq!(c.used(), (0, 0));
        assert_eq!(evicted, vec![4]);
        assert_eq!(c.resident(), 0);
        c.mark_failed(7);
        assert!(c.is_failed(7) && !c.is_failed(6));
        assert_eq!(room(0), 8);
        assert_eq!(room(0b0110_0110), 2);
        assert_eq!(room(0b1000_0000), 7);
        assert_eq!(run_mask(8), 0xff);
    }
}
