//! A cache file opened for streaming pages: the page indices of every level read once,
//! then any page read on its own (one seek and one read) and checked on its own checksum.
//! [`super::read_page`] reads one page with no state; this is for a renderer that reads
//! thousands of pages from one file.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use bytemuck::Zeroable;

use super::format::{
    CacheError, KIND_PAGE_INDEX, KIND_POINT_CLOUD, KIND_PROXY_POSITIONS, KIND_PROXY_TRIANGLES,
};
use super::pages::{PAGE_BITS, PageEntry, check_page, page_coords};
use super::reader::Source;
use crate::asset::PackedVoxel;

/// One level of a [`PageFile`].
#[derive(Debug, Clone)]
struct LevelPages {
    /// The level's page index.
    pages: Vec<PageEntry>,
    /// Voxels of the level.
    voxels: u64,
    /// File offset of the level's first voxel.
    offset: u64,
}

/// A cache file's page indices, and the file, for reading single pages.
#[derive(Debug)]
pub struct PageFile {
    path: PathBuf,
    file: Mutex<File>,
    levels: Vec<LevelPages>,
}

impl PageFile {
    /// Opens the cache file `path` written for `level` from a source with key
    /// `source_hash`: checks its header, reads and checks every level's page index (each
    /// section's checksum; entries in strict order, inside the grid and the point cloud)
    /// and skips the rest.
    pub fn open(path: &Path, source_hash: u128, level: u32) -> Result<Self, CacheError> {
        let mut src = Source::open(path, 1 << 16)?;
        src.header(source_hash, level)?;
        let mut levels = Vec::with_capacity(level as usize + 1);
        for l in 0..=level {
            let pages: Vec<PageEntry> = src.section(KIND_PAGE_INDEX, l)?;
            let (len, _) = src.section_header(KIND_POINT_CLOUD, l)?;
            let size = std::mem::size_of::<PackedVoxel>() as u64;
            if len % size != 0 {
                return Err(CacheError::corrupt(
                    path,
                    format!("point_cloud of level {l} has {len} bytes"),
                ));
            }
            let voxels = len / size;
            check_entries(path, l, &pages, voxels)?;
            levels.push(LevelPages {
                pages,
                voxels,
                offset: src.position(),
            });
            src.skip(len)?;
            src.skip_section(KIND_PROXY_POSITIONS, l)?;
            src.skip_section(KIND_PROXY_TRIANGLES, l)?;
        }
        let file = File::open(path).map_err(|e| CacheError::io(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            file: Mutex::new(file),
            levels,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The page index of level `lod` (empty for a level the file does not have).
    pub fn pages(&self, lod: u32) -> &[PageEntry] {
        self.levels.get(lod as usize).map_or(&[], |l| &l.pages)
    }

    /// Voxels of level `lod`.
    pub fn voxels(&self, lod: u32) -> u64 {
        self.levels.get(lod as usize).map_or(0, |l| l.voxels)
    }

    /// Voxels of page `k` of level `lod`.
    pub fn page_voxels(&self, lod: u32, k: usize) -> u64 {
        let Some(l) = self.levels.get(lod as usize) else {
            return 0;
        };
        match l.pages.get(k) {
            Some(e) => l.pages.get(k + 1).map_or(l.voxels, |n| n.first_voxel) - e.first_voxel,
            None => 0,
        }
    }

    /// Reads page `k` of level `lod`'s index and checks it (checksum, and every voxel in
    /// the page in strict Morton order): a damaged page is an error naming the page.
    pub fn read_page(&self, lod: u32, k: usize) -> Result<Vec<PackedVoxel>, CacheError> {
        let l = self.levels.get(lod as usize).ok_or_else(|| {
            CacheError::corrupt(&self.path, format!("no level {lod} in this cache"))
        })?;
        let e = *l.pages.get(k).ok_or_else(|| {
            CacheError::corrupt(&self.path, format!("level {lod} has no page {k}"))
        })?;
        let n = self.page_voxels(lod, k) as usize;
        let mut out = vec![PackedVoxel::zeroed(); n];
        let size = std::mem::size_of::<PackedVoxel>() as u64;
        let name = format!("page {:?} of level {lod}", page_coords(e.page));
        {
            // A poisoned lock only means another reader panicked mid-read; the file
            // position is set before every read, so the file is still usable.
            let mut f = self.file.lock().unwrap_or_else(|p| p.into_inner());
            f.seek(SeekFrom::Start(l.offset + e.first_voxel * size))
                .and_then(|_| f.read_exact(bytemuck::cast_slice_mut(&mut out)))
                .map_err(|error| {
                    if error.kind() == std::io::ErrorKind::UnexpectedEof {
                        CacheError::Truncated {
                            path: self.path.clone(),
                            what: name.clone(),
                        }
                    } else {
                        CacheError::io(&self.path, error)
                    }
                })?;
        }
        check_page(&self.path, lod, &e, &mut out)?;
        Ok(out)
    }
}

/// A level's page index must be usable for seeking: pages in strict Morton order inside
/// the grid, first voxels strictly increasing from 0 and inside the point cloud.
pub(super) fn check_entries(
    path: &Path,
    lod: u32,
    pages: &[PageEntry],
    voxels: u64,
) -> Result<(), CacheError> {
    let bad =
        |what: String| CacheError::corrupt(path, format!("page index of level {lod}: {what}"));
    let page_codes = 1u64 << (3 * lod).saturating_sub(PAGE_BITS).min(63);
    if pages.is_empty() != (voxels == 0) {
        return Err(bad(format!("{} entries for {voxels} voxels", pages.len())));
    }
    if pages.first().is_some_and(|e| e.first_voxel != 0) {
        return Err(bad("the first page does not start at voxel 0".into()));
    }
    for (k, e) in pages.iter().enumerate() {
        let next = pages.get(k + 1);
        let end = next.map_or(voxels, |n| n.first_voxel);
        let page_cells = 1u64 << PAGE_BITS;
        if e.page >= page_codes
            || e.first_voxel >= end
            || end - e.first_voxel > page_cells
            || next.is_some_and(|n| n.page <= e.page)
        {
            return Err(bad(format!("entry {k} out of order or range")));
        }
    }
    Ok(())
}
