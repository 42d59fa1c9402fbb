//! Writing a cache file from a preparation that streams its voxels, never holding a level.
//!
//! Each level's voxels are appended, in Morton order, to a spill file in a temporary folder
//! beside the destination, while its page index (with each page's checksum), its lookup's
//! node count and nothing else stay in memory. [`CacheStream::finish`] builds the proxies
//! from the page indexes and assembles the cache file atomically, copying each spill file
//! into its point-cloud section (read twice: once for the section checksum, which precedes
//! the payload, once to copy). The file is the one [`super::write_cache`] would write for
//! the same asset (a test compares the bytes).

use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::Path;

use xxhash_rust::xxh3::Xxh3;

use super::format::{CacheError, KIND_PAGE_INDEX, KIND_POINT_CLOUD, le_bytes};
use super::pages::PageEntry;
use super::{header_bytes, write_atomically, write_proxy, write_section, write_section_header};
use crate::asset::{PAGE_SIZE, PackedVoxel};
use crate::lookup::NodeCounter;
use crate::model::ObjectSpace;
use crate::proxy::build_proxy_of_pages;
use crate::svo::{morton_decode, morton_encode};

/// Bits of a cell's Morton code inside its 16³ page.
const PAGE_BITS: u32 = 3 * PAGE_SIZE.trailing_zeros();

/// What the finished file holds of one level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamedLevel {
    /// Voxels.
    pub voxels: u64,
    /// Occupied 16³ pages.
    pub pages: u64,
    /// Nodes of the level's lookup (built when the file is read).
    pub lookup_nodes: u64,
    /// Triangles of the level's proxy.
    pub proxy_triangles: u64,
}

struct LevelSpill {
    file: BufWriter<File>,
    path: std::path::PathBuf,
    voxels: u64,
    index: Vec<PageEntry>,
    page_hash: Xxh3,
    nodes: NodeCounter,
    codes: Vec<u64>,
}

/// A cache file being written level by level (see the module docs).
pub struct CacheStream {
    _spill_dir: tempfile::TempDir,
    levels: Vec<LevelSpill>,
}

impl CacheStream {
    /// A stream of levels `0..=level` whose spill files live in a temporary folder inside
    /// `dir` (created if needed; the destination's folder, so the space is where the
    /// result goes).
    pub fn new(dir: &Path, level: u32) -> Result<Self, CacheError> {
        std::fs::create_dir_all(dir).map_err(|e| CacheError::io(dir, e))?;
        let spill_dir = tempfile::Builder::new()
            .prefix(".ssbvbast-spill-")
            .tempdir_in(dir)
            .map_err(|e| CacheError::io(dir, e))?;
        let levels = (0..=level)
            .map(|l| {
                let path = spill_dir.path().join(format!("level-{l}"));
                let file = File::create(&path).map_err(|e| CacheError::io(&path, e))?;
                Ok(LevelSpill {
                    file: BufWriter::with_capacity(1 << 20, file),
                    path,
                    voxels: 0,
                    index: Vec::new(),
                    page_hash: Xxh3::new(),
                    nodes: NodeCounter::new(l),
                    codes: Vec::new(),
                })
            })
            .collect::<Result<Vec<_>, CacheError>>()?;
        Ok(Self {
            _spill_dir: spill_dir,
            levels,
        })
    }

    /// Appends voxels of level `lod`, continuing its Morton order.
    ///
    /// # Panics
    ///
    /// When `lod` is above the stream's level.
    pub fn push(&mut self, lod: u32, voxels: &[PackedVoxel]) -> Result<(), CacheError> {
        let s = &mut self.levels[lod as usize];
        s.codes.clear();
        s.codes
            .extend(voxels.iter().map(|v| morton_encode(v.cell())));
        s.nodes.extend(&s.codes);
        // Runs of one page: hashed together.
        let mut start = 0;
        while start < voxels.len() {
            let page = s.codes[start] >> PAGE_BITS;
            let end = s.codes[start..]
                .iter()
                .position(|&c| c >> PAGE_BITS != page)
                .map_or(voxels.len(), |n| start + n);
            if s.index.last().is_none_or(|e| e.page != page) {
                if let Some(last) = s.index.last_mut() {
                    last.checksum = s.page_hash.digest();
                }
                s.page_hash.reset();
                s.index.push(PageEntry {
                    page,
                    first_voxel: s.voxels + start as u64,
                    checksum: 0,
                });
            }
            s.page_hash.update(&le_bytes(&voxels[start..end]));
            start = end;
        }
        s.voxels += voxels.len() as u64;
        s.file
            .write_all(&le_bytes(voxels))
            .map_err(|e| CacheError::io(&s.path, e))
    }

    /// Writes the cache file to `path` (atomically) from everything pushed, with the
    /// proxies of the pages; what it holds per level.
    pub fn finish(
        mut self,
        path: &Path,
        source_hash: u128,
        object_space: &ObjectSpace,
    ) -> Result<Vec<StreamedLevel>, CacheError> {
        let level = self.levels.len() as u32 - 1;
        for s in &mut self.levels {
            if let Some(last) = s.index.last_mut() {
                last.checksum = s.page_hash.digest();
            }
            s.file.flush().map_err(|e| CacheError::io(&s.path, e))?;
        }
        let mut out = Vec::with_capacity(self.levels.len());
        let proxies: Vec<_> = self
            .levels
            .iter()
            .enumerate()
            .map(|(l, s)| {
                let pages: Vec<[u32; 3]> = s.index.iter().map(|e| morton_decode(e.page)).collect();
                build_proxy_of_pages(l as u32, &pages)
            })
            .collect();
        for (s, p) in self.levels.iter().zip(&proxies) {
            out.push(StreamedLevel {
                voxels: s.voxels,
                pages: s.index.len() as u64,
                lookup_nodes: s.nodes.nodes(),
                proxy_triangles: p.triangles.len() as u64,
            });
        }
        let size = std::mem::size_of::<PackedVoxel>() as u64;
        write_atomically(path, |w| {
            w.write_all(&header_bytes(source_hash, level, object_space))?;
            for (l, (s, proxy)) in self.levels.iter().zip(&proxies).enumerate() {
                let l = l as u32;
                write_section(w, KIND_PAGE_INDEX, l, &le_bytes(&s.index))?;
                let len = s.voxels * size;
                let mut h = Xxh3::new();
                h.update(&KIND_POINT_CLOUD.to_le_bytes());
                h.update(&l.to_le_bytes());
                h.update(&len.to_le_bytes());
                copy_spill(&s.path, len, &mut |chunk| {
                    h.update(chunk);
                    Ok(())
                })?;
                write_section_header(w, KIND_POINT_CLOUD, l, len, h.digest())?;
                copy_spill(&s.path, len, &mut |chunk| w.write_all(chunk))?;
                write_proxy(w, l, proxy)?;
            }
            Ok(())
        })?;
        Ok(out)
    }
}

/// Feeds the `len` bytes of a spill file to `f` in chunks (an error if it holds fewer).
fn copy_spill(path: &Path, len: u64, f: &mut dyn FnMut(&[u8]) -> io::Result<()>) -> io::Result<()> {
    let mut r = BufReader::with_capacity(1 << 20, File::open(path)?);
    let mut buf = vec![0u8; 1 << 20];
    let mut left = len;
    while left > 0 {
        let n = (left as usize).min(buf.len());
        r.read_exact(&mut buf[..n])?;
        f(&buf[..n])?;
        left -= n as u64;
    }
    Ok(())
}
