//! The CPU side of the GPU page cache: which 16³ pages are resident where, which leave
//! first (least recently used), and how one page's voxels are laid out in the pools.
//!
//! A resident page owns one slot of [`SLOT_NODES`] lookup nodes (its 4³ leaves) and as
//! many blocks of [`BLOCK_VOXELS`] voxels as its leaves need. Fixed-size slots and blocks
//! never fragment; a leaf never straddles two blocks, so each leaf's `base` is the pool
//! index of its first voxel and blocks need not be contiguous. The GPU side (uploads,
//! feedback) is `streaming.rs`.

use std::collections::BTreeSet;

use ssbvb_voxel::asset::PackedVoxel;
use ssbvb_voxel::svo::morton_encode;

/// Lookup nodes of a page slot: a 16³ page has at most 64 leaves of 4³ cells.
pub const SLOT_NODES: u32 = 64;
/// Voxels of a pool block (a power of two, so no block straddles a binding chunk).
pub const BLOCK_VOXELS: u32 = 256;

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
        if page
            .blocks
            .last()
            .is_none_or(|b| b.len() + n > BLOCK_VOXELS as usize)
        {
            page.blocks.push(Vec::with_capacity(BLOCK_VOXELS as usize));
        }
        let b = page.blocks.len() - 1;
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
    /// Its slot in the node pool.
    pub slot: u32,
    /// Its blocks in the voxel pool.
    pub blocks: Vec<u32>,
}

#[derive(Debug, Clone, Default)]
struct PageState {
    residence: Option<Residence>,
    last_used: u64,
    failed: bool,
}

/// Residency of every page of the scene's paged LODs in pools of `slots` node slots and
/// `blocks` voxel blocks, with least-recently-used eviction.
#[derive(Debug, Clone)]
pub struct PageCache {
    free_slots: Vec<u32>,
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
            free_slots: (0..slots).rev().collect(),
            free_blocks: (0..blocks).rev().collect(),
            slots,
            blocks,
            pages: vec![PageState::default(); pages],
            lru: BTreeSet::new(),
        }
    }

    /// Pages known.
    pub fn page_count(&self) -> usize {
        self.pages.len()
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
        if p.residence.is_some() && p.last_used < frame {
            self.lru.remove(&(p.last_used, page));
            p.last_used = frame;
            self.lru.insert((frame, page));
        } else if p.residence.is_none() {
            p.last_used = p.last_used.max(frame);
        }
    }

    /// Resident pages.
    pub fn resident(&self) -> usize {
        self.lru.len()
    }

    /// Node slots and voxel blocks in use.
    pub fn used(&self) -> (u32, u32) {
        (
            self.slots - self.free_slots.len() as u32,
            self.blocks - self.free_blocks.len() as u32,
        )
    }

    /// Pool capacity: node slots and voxel blocks.
    pub fn capacity(&self) -> (u32, u32) {
        (self.slots, self.blocks)
    }

    /// Makes `page` resident with `blocks` blocks, used in frame `frame`: takes free slots
    /// and blocks, evicting the least recently used pages last used before `keep_from`
    /// (pages the latest frames needed stay). Returns where it goes and the pages evicted
    /// (whose page nodes must be marked missing), or `None` when even evicting every
    /// evictable page would not make room (nothing is evicted then).
    pub fn admit(
        &mut self,
        page: u32,
        blocks: u32,
        frame: u64,
        keep_from: u64,
    ) -> Option<(Residence, Vec<u32>)> {
        if self.is_resident(page) || page as usize >= self.pages.len() {
            return None;
        }
        // Room: free, plus what the evictable pages hold.
        let mut slots_room = self.free_slots.len() as u64;
        let mut blocks_room = self.free_blocks.len() as u64;
        let mut victims = 0;
        for &(used, p) in &self.lru {
            if slots_room >= 1 && blocks_room >= blocks as u64 {
                break;
            }
            if used >= keep_from {
                return None;
            }
            let r = self.pages[p as usize].residence.as_ref()?;
            slots_room += 1;
            blocks_room += r.blocks.len() as u64;
            victims += 1;
        }
        if slots_room < 1 || blocks_room < blocks as u64 {
            return None;
        }
        let mut evicted = Vec::with_capacity(victims);
        for _ in 0..victims {
            let (used, p) = self.lru.pop_first()?;
            debug_assert!(used < keep_from);
            if let Some(r) = self.pages[p as usize].residence.take() {
                self.free_slots.push(r.slot);
                self.free_blocks.extend(r.blocks);
            }
            evicted.push(p);
        }
        let slot = self.free_slots.pop()?;
        let taken = self.free_blocks.len() - blocks as usize;
        let residence = Residence {
            slot,
            blocks: self.free_blocks.split_off(taken),
        };
        let state = &mut self.pages[page as usize];
        state.residence = Some(residence.clone());
        state.last_used = state.last_used.max(frame);
        self.lru.insert((state.last_used, page));
        Some((residence, evicted))
    }

    /// Evicts every page (pinned pages are not in the cache at all).
    pub fn clear(&mut self) -> Vec<u32> {
        let mut out = Vec::new();
        while let Some((_, p)) = self.lru.pop_first() {
            if let Some(r) = self.pages[p as usize].residence.take() {
                self.free_slots.push(r.slot);
                self.free_blocks.extend(r.blocks);
            }
            out.push(p);
        }
        out
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
            assert!(packed.blocks.len() <= page_voxels.len().div_ceil(64) + 1);
            seen += n;
        }
        assert_eq!(seen, voxels.len());
        assert!(index.len() > 20, "{} pages", index.len());
    }

    #[test]
    fn least_recently_used_pages_leave_first_and_recent_ones_stay() {
        let mut c = PageCache::new(10, 3, 6);
        // Frames 1..3 admit pages 0, 1, 2 (two blocks each): the pools are full.
        for p in 0..3 {
            let (r, ev) = c.admit(p, 2, p as u64 + 1, 0).unwrap();
            assert!(ev.is_empty());
            assert_eq!(r.blocks.len(), 2);
        }
        assert_eq!(c.used(), (3, 6));
        // Page 0 is used again in frame 4: page 1 is now the oldest.
        c.touch(0, 4);
        let (_, ev) = c.admit(3, 2, 5, 5).unwrap();
        assert_eq!(ev, vec![1]);
        assert!(!c.is_resident(1) && c.is_resident(0) && c.is_resident(3));
        // A page needing more blocks evicts as many as it needs, oldest first (2, then 0).
        let (r, ev) = c.admit(4, 4, 6, 6).unwrap();
        assert_eq!(ev, vec![2, 0]);
        assert_eq!(r.blocks.len(), 4);
        // Pages used in the frames to keep are never evicted: no room, nothing evicted.
        assert!(c.admit(5, 1, 7, 5).is_none());
        assert!(c.is_resident(3) && c.is_resident(4));
        assert_eq!(c.resident(), 2);
        // A page larger than the whole pool never fits.
        assert!(c.admit(6, 7, 8, 100).is_none());
        assert_eq!(c.resident(), 2);
        // Slots and blocks are conserved.
        let evicted = c.clear();
        assert_eq!(evicted.len(), 2);
        assert_eq!(c.used(), (0, 0));
        c.mark_failed(7);
        assert!(c.is_failed(7) && !c.is_failed(6));
    }
}
