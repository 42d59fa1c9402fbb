//! The page index of a cached level: one entry per occupied 16³ page, so that one page can
//! be read and checked without reading the rest of the file (see the format in the parent
//! module).

use std::path::Path;

use bytemuck::{Pod, Zeroable};
use xxhash_rust::xxh3::xxh3_64;

use super::format::{
    CacheError, KIND_PAGE_INDEX, KIND_POINT_CLOUD, KIND_PROXY_POSITIONS, KIND_PROXY_TRIANGLES,
    checksums_checked, le_bytes,
};
use super::reader::Source;
use crate::asset::{PAGE_SIZE, PackedVoxel};
use crate::svo::morton_encode;

/// Bits of a cell's Morton code inside its 16³ page.
pub(super) const PAGE_BITS: u32 = 3 * PAGE_SIZE.trailing_zeros();

/// One occupied page of a cached level.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct PageEntry {
    /// Morton code of the page (a voxel's cell code >> 12).
    pub page: u64,
    /// Index of the page's first voxel in the level's point cloud; its voxels run to the
    /// next entry's first voxel (the last one's to the end).
    pub first_voxel: u64,
    /// XXH3-64 of the page's voxels as stored (little-endian `PackedVoxel`s).
    pub checksum: u64,
}

/// The page index of a Morton-ordered point cloud.
pub fn page_index(voxels: &[PackedVoxel]) -> Vec<PageEntry> {
    let mut out: Vec<PageEntry> = Vec::new();
    for (i, v) in voxels.iter().enumerate() {
        let page = morton_encode(v.cell()) >> PAGE_BITS;
        if out.last().is_none_or(|e| e.page != page) {
            out.push(PageEntry {
                page,
                first_voxel: i as u64,
                checksum: 0,
            });
        }
    }
    for k in 0..out.len() {
        let end = out
            .get(k + 1)
            .map_or(voxels.len(), |e| e.first_voxel as usize);
        out[k].checksum = xxh3_64(&le_bytes(&voxels[out[k].first_voxel as usize..end]));
    }
    out
}

/// Checks a level's page index against its point cloud (and its codes): exactly the index
/// [`page_index`] writes, so each page's checksum is verified too.
pub(super) fn check_index(
    path: &Path,
    level: u32,
    index: &[PageEntry],
    voxels: &[PackedVoxel],
    codes: &[u64],
) -> Result<(), CacheError> {
    let bad =
        |what: String| CacheError::corrupt(path, format!("page index of level {level}: {what}"));
    let mut k = 0usize;
    for (i, &code) in codes.iter().enumerate() {
        let page = code >> PAGE_BITS;
        if i == 0 || page != codes[i - 1] >> PAGE_BITS {
            let e = index
                .get(k)
                .ok_or_else(|| bad(format!("no entry for the page of voxel {i}")))?;
            if e.page != page || e.first_voxel != i as u64 {
                return Err(bad(format!("entry {k} does not match voxel {i}")));
            }
            k += 1;
        }
    }
    if k != index.len() {
        return Err(bad(format!("{} entries for {k} pages", index.len())));
    }
    for (k, e) in index.iter().enumerate() {
        let end = index
            .get(k + 1)
            .map_or(voxels.len(), |n| n.first_voxel as usize);
        if checksums_checked()
            && xxh3_64(&le_bytes(&voxels[e.first_voxel as usize..end])) != e.checksum
        {
            return Err(CacheError::Checksum {
                path: path.to_path_buf(),
                section: format!("page {} of level {level}", e.page),
            });
        }
    }
    Ok(())
}

/// Reads the voxels of one 16³ page (page coordinates: a cell divided by 16) of level
/// `lod` from a cache file written for `level` from a source with hash `source_hash`.
/// Reads the header, the section headers up to `lod` (skipping their payloads), `lod`'s
/// page index and the page's bytes, nothing else; checks the page on its own checksum
/// and its voxels to lie in the page in strict Morton order. An unoccupied page is empty.
pub fn read_page(
    path: &Path,
    source_hash: u128,
    level: u32,
    lod: u32,
    page: [u32; 3],
) -> Result<Vec<PackedVoxel>, CacheError> {
    if lod > level {
        return Err(CacheError::corrupt(
            path,
            format!("level {lod} asked of a cache of levels 0..={level}"),
        ));
    }
    // Small buffer: the reads are a few headers and one page.
    let mut src = Source::open(path, 4096)?;
    src.header(source_hash, level)?;
    for l in 0..lod {
        for kind in [
            KIND_PAGE_INDEX,
            KIND_POINT_CLOUD,
            KIND_PROXY_POSITIONS,
            KIND_PROXY_TRIANGLES,
        ] {
            src.skip_section(kind, l)?;
        }
    }
    let index: Vec<PageEntry> = src.section(KIND_PAGE_INDEX, lod)?;
    let (len, _) = src.section_header(KIND_POINT_CLOUD, lod)?;
    let size = std::mem::size_of::<PackedVoxel>() as u64;
    let voxels = len / size;
    let code = morton_encode(page);
    let Ok(k) = index.binary_search_by_key(&code, |e| e.page) else {
        return Ok(Vec::new());
    };
    let e = index[k];
    let end = index.get(k + 1).map_or(voxels, |n| n.first_voxel);
    let name = format!("page {page:?} of level {lod}");
    if len % size != 0 || !(e.first_voxel < end && end <= voxels) {
        return Err(CacheError::corrupt(
            path,
            format!("{name}: bad index entry"),
        ));
    }
    src.skip(e.first_voxel * size)?;
    let mut out = vec![PackedVoxel::zeroed(); (end - e.first_voxel) as usize];
    src.read_exact(bytemuck::cast_slice_mut(&mut out), &name)?;
    check_page(path, lod, &e, &mut out)?;
    Ok(out)
}

/// Checks the voxels of one page as read from `path` (little-endian, `entry` its index
/// entry in level `lod`): its checksum, then that every voxel lies in the page, inside the
/// grid, in strict Morton order; converts them to native byte order.
pub(super) fn check_page(
    path: &Path,
    lod: u32,
    entry: &PageEntry,
    voxels: &mut [PackedVoxel],
) -> Result<(), CacheError> {
    let name = format!("page {:?} of level {lod}", page_coords(entry.page));
    if checksums_checked() && xxh3_64(bytemuck::cast_slice(voxels)) != entry.checksum {
        return Err(CacheError::Checksum {
            path: path.to_path_buf(),
            section: name,
        });
    }
    if cfg!(target_endian = "big") {
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(voxels);
        bytes.chunks_exact_mut(4).for_each(|w| w.reverse());
    }
    let n = 1u32 << lod.min(16);
    let mut last = None;
    for v in voxels.iter() {
        let c = v.cell();
        let code = morton_encode(c);
        if c.iter().any(|&x| x >= n) || code >> PAGE_BITS != entry.page || last >= Some(code) {
            return Err(CacheError::corrupt(
                path,
                format!("{name}: voxel {c:?} out of place"),
            ));
        }
        last = Some(code);
    }
    Ok(())
}

/// The page coordinates (a cell divided by 16) of a page's Morton code.
pub fn page_coords(code: u64) -> [u32; 3] {
    crate::svo::morton_decode(code)
}
