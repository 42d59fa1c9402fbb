//! The on-disk asset cache: a prepared [`VoxelAsset`] in a versioned, checksummed file.
//!
//! # Format (version [`FORMAT_VERSION`], all integers little-endian)
//!
//! ```text
//! header (88 bytes)
//!   magic           [u8; 8]   b"SSBVBAST"
//!   version         u32       FORMAT_VERSION
//!   reserved        u32       0
//!   source_hash     [u8; 16]  XXH3-128 of the source model file's bytes
//!   level           u32       finest level
//!   lod_count       u32       level + 1
//!   center          [f64; 3]  ObjectSpace::center
//!   scale           f64       ObjectSpace::scale
//!   section_count   u32       4 · lod_count
//!   reserved        u32       0
//!   header_checksum u64       XXH3-64 of the 80 bytes above
//! sections, for each LOD l = 0 ..= level, in this order:
//!   page_index (kind 4): PageEntry[]      (24 bytes each, one per occupied 16³ page)
//!   point_cloud (kind 1): PackedVoxel[]   (16 bytes each, Morton order)
//!   proxy_positions (kind 2): [f32; 3][]
//!   proxy_triangles (kind 3): [u32; 3][]
//! each section = kind u32, lod u32, length u64 (payload bytes), checksum u64
//!   (XXH3-64 of kind, lod, length and the payload), then the payload.
//! PageEntry = page u64 (Morton code of the page: a voxel's cell code >> 12),
//!   first_voxel u64 (its first voxel in the point cloud; it runs to the next entry's),
//!   checksum u64 (XXH3-64 of the page's voxels as stored).
//! ```
//!
//! In Morton order the voxels of a 16³ page are one run of the point cloud, so the page
//! index lets [`read_page`] read one page of one level — the header, the section headers
//! (skipped by seeking), the level's index and that page's bytes — without reading the
//! rest of the file, and check it on its own checksum.
//!
//! The sparse lookups are not stored: they are a pure function of the point clouds'
//! Morton codes, rebuilt with [`lookup_from_codes`](crate::prepare::lookup_from_codes) on
//! read in one linear pass per tree depth (cheaper than reading and checksumming them).
//!
//! Reading never trusts the file: every length is checked against the bytes left in the
//! file before anything is allocated, every section's checksum is verified, and the point
//! clouds are checked to be strictly Morton-ordered and inside the grid before a lookup
//! is built from them. Any problem is a [`CacheError`] naming the file, never a panic.
//! Writing is atomic: a temporary file in the destination folder is written, flushed to
//! disk and renamed over the destination.
//!
//! [`load_or_prepare`] (in `prepare`) puts the cache in front of the preparation stage.

mod asset_file;
mod deps;
mod format;
mod page_file;
mod pages;
mod prepare;
mod reader;
mod stream;

use std::fs::File;
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::{Xxh3, xxh3_64};

use crate::asset::{LodLevel, PackedVoxel, PointCloud, ProxyMesh, VoxelAsset};
use crate::lookup::SparseLookup;
use crate::model::ObjectSpace;
use crate::svo::morton_encode;
use format::{
    HEADER_BYTES, KIND_PAGE_INDEX, KIND_POINT_CLOUD, KIND_PROXY_POSITIONS, KIND_PROXY_TRIANGLES,
    le_bytes, section_checksum,
};
use reader::Source;

pub use asset_file::{
    ASSET_FILE_EXTENSION, AssetFileHeader, asset_file_header, read_asset_file, write_asset_file,
};
pub use format::{CacheError, FORMAT_VERSION, MAGIC};
pub use page_file::PageFile;
pub use pages::{PageEntry, page_index, read_page};
pub use prepare::{CacheStatus, PrepareError, PrepareOutcome, load_or_prepare, prepare_into_cache};
pub use stream::{CacheStream, StreamedLevel};

/// XXH3-128 of a file's bytes (streamed): the source hash the cache is keyed by.
pub fn hash_source(path: &Path) -> Result<u128, CacheError> {
    let mut file = File::open(path).map_err(|e| CacheError::io(path, e))?;
    let mut hasher = Xxh3::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = file.read(&mut buf).map_err(|e| CacheError::io(path, e))?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher.digest128())
}

/// Where caches go by default: `$SSBVB_CACHE_DIR`, else `$XDG_CACHE_HOME/ssbvb`, else
/// `$HOME/.cache/ssbvb`, else `<temp dir>/ssbvb-cache` (never next to the source).
pub fn default_cache_dir() -> PathBuf {
    cache_dir_from(|k| std::env::var_os(k))
}

/// [`default_cache_dir`] with the environment read through `var` (empty values count as
/// unset).
fn cache_dir_from(var: impl Fn(&str) -> Option<std::ffi::OsString>) -> PathBuf {
    let env = |k: &str| var(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    if let Some(d) = env("SSBVB_CACHE_DIR") {
        return d;
    }
    if let Some(d) = env("XDG_CACHE_HOME") {
        return d.join("ssbvb");
    }
    if let Some(h) = env("HOME") {
        return h.join(".cache").join("ssbvb");
    }
    std::env::temp_dir().join("ssbvb-cache")
}

/// File name of the cache of a source (by hash) at a level.
pub fn cache_file_name(source_hash: u128, level: u32) -> String {
    format!("{source_hash:032x}-L{level}.ssbvbast")
}

/// Writes `asset` (prepared at `level` from a source with hash `source_hash`) to `path`
/// atomically: a temporary file in the same folder is written, synced and renamed. The
/// folder is created if needed.
pub fn write_cache(
    path: &Path,
    asset: &VoxelAsset,
    source_hash: u128,
    level: u32,
) -> Result<(), CacheError> {
    if asset.lods.len() != level as usize + 1
        || asset
            .lods
            .iter()
            .enumerate()
            .any(|(l, lod)| lod.level != l as u32)
    {
        return Err(CacheError::corrupt(
            path,
            format!("asset to write does not hold levels 0..={level}"),
        ));
    }
    write_atomically(path, |w| {
        w.write_all(&header_bytes(source_hash, level, &asset.object_space))?;
        for lod in &asset.lods {
            let index = page_index(&lod.point_cloud.voxels);
            write_section(w, KIND_PAGE_INDEX, lod.level, &le_bytes(&index))?;
            write_section(
                w,
                KIND_POINT_CLOUD,
                lod.level,
                &le_bytes(&lod.point_cloud.voxels),
            )?;
            write_proxy(w, lod.level, &lod.proxy)?;
        }
        Ok(())
    })
}

/// The file header of a cache of levels `0..=level`.
fn header_bytes(source_hash: u128, level: u32, object_space: &ObjectSpace) -> Vec<u8> {
    let mut h = Vec::with_capacity(HEADER_BYTES);
    h.extend_from_slice(&MAGIC);
    h.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    h.extend_from_slice(&0u32.to_le_bytes());
    h.extend_from_slice(&source_hash.to_le_bytes());
    h.extend_from_slice(&level.to_le_bytes());
    h.extend_from_slice(&(level + 1).to_le_bytes());
    for c in object_space.center.to_array() {
        h.extend_from_slice(&c.to_le_bytes());
    }
    h.extend_from_slice(&object_space.scale.to_le_bytes());
    h.extend_from_slice(&(4 * (level + 1)).to_le_bytes());
    h.extend_from_slice(&0u32.to_le_bytes());
    let checksum = xxh3_64(&h);
    h.extend_from_slice(&checksum.to_le_bytes());
    debug_assert_eq!(h.len(), HEADER_BYTES);
    h
}

/// Writes a section header and its payload.
fn write_section(w: &mut impl Write, kind: u32, lod: u32, payload: &[u8]) -> io::Result<()> {
    write_section_header(
        w,
        kind,
        lod,
        payload.len() as u64,
        section_checksum(kind, lod, payload),
    )?;
    w.write_all(payload)
}

/// Writes a section header.
fn write_section_header(
    w: &mut impl Write,
    kind: u32,
    lod: u32,
    len: u64,
    checksum: u64,
) -> io::Result<()> {
    w.write_all(&kind.to_le_bytes())?;
    w.write_all(&lod.to_le_bytes())?;
    w.write_all(&len.to_le_bytes())?;
    w.write_all(&checksum.to_le_bytes())
}

/// Writes a level's two proxy sections.
fn write_proxy(w: &mut impl Write, lod: u32, proxy: &ProxyMesh) -> io::Result<()> {
    write_section(w, KIND_PROXY_POSITIONS, lod, &le_bytes(&proxy.positions))?;
    write_section(w, KIND_PROXY_TRIANGLES, lod, &le_bytes(&proxy.triangles))
}

/// Creates `path` atomically: `write` fills a temporary file in the same folder (created
/// if needed), which is synced and renamed over `path`.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&File>) -> io::Result<()>,
) -> Result<(), CacheError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| CacheError::io(&dir, e))?;
    let tmp = tempfile::Builder::new()
        .prefix(".ssbvbast-")
        .suffix(".tmp")
        .tempfile_in(&dir)
        .map_err(|e| CacheError::io(&dir, e))?;
    // Temporary files are created private (0600); a cache is ordinary data.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = tmp
            .as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644));
    }
    let fill = |file: &File| -> io::Result<()> {
        let mut w = BufWriter::with_capacity(1 << 20, file);
        write(&mut w)?;
        w.flush()?;
        drop(w);
        file.sync_all()
    };
    fill(tmp.as_file()).map_err(|e| CacheError::io(tmp.path(), e))?;
    tmp.persist(path)
        .map_err(|e| CacheError::io(path, e.error))?;
    // Make the rename itself durable (best effort: not every platform can sync a folder).
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Reads a cache file written by [`write_cache`], expecting the given source hash and
/// level. Every inconsistency is an error; nothing in the file can cause a panic or an
/// allocation larger than the file.
pub fn read_cache(
    path: &Path,
    expected_source_hash: u128,
    level: u32,
) -> Result<VoxelAsset, CacheError> {
    let mut src = Source::open(path, 1 << 20)?;
    let object_space = src.header(expected_source_hash, level)?;
    let mut lods = Vec::with_capacity(level as usize + 1);
    for l in 0..=level {
        let index: Vec<PageEntry> = src.section(KIND_PAGE_INDEX, l)?;
        let voxels: Vec<PackedVoxel> = src.section(KIND_POINT_CLOUD, l)?;
        let codes = validated_codes(path, l, &voxels)?;
        pages::check_index(path, l, &index, &voxels, &codes)?;
        let positions: Vec<[f32; 3]> = src.section(KIND_PROXY_POSITIONS, l)?;
        let triangles: Vec<[u32; 3]> = src.section(KIND_PROXY_TRIANGLES, l)?;
        if !positions.iter().flatten().all(|c| c.is_finite()) {
            return Err(CacheError::corrupt(
                path,
                format!("non-finite proxy vertex in level {l}"),
            ));
        }
        if triangles
            .iter()
            .flatten()
            .any(|&i| i as usize >= positions.len())
        {
            return Err(CacheError::corrupt(
                path,
                format!("proxy index out of range in level {l}"),
            ));
        }
        let lookup = SparseLookup::from_codes(l, &codes);
        lods.push(LodLevel {
            level: l,
            point_cloud: PointCloud { voxels },
            lookup,
            proxy: ProxyMesh {
                positions,
                triangles,
            },
        });
    }
    if src.remaining != 0 {
        return Err(CacheError::corrupt(
            path,
            format!("{} trailing bytes", src.remaining),
        ));
    }
    Ok(VoxelAsset { object_space, lods })
}

/// Morton codes of a point cloud read from a file, checked to be inside the level's grid
/// and strictly increasing (distinct), which the lookup construction relies on.
fn validated_codes(
    path: &Path,
    level: u32,
    voxels: &[PackedVoxel],
) -> Result<Vec<u64>, CacheError> {
    if level < 32 && voxels.len() as u64 > 1u64 << (3 * level).min(63) {
        return Err(CacheError::corrupt(
            path,
            format!("too many voxels for level {level}"),
        ));
    }
    let n = 1u32 << level;
    let mut codes = Vec::with_capacity(voxels.len());
    for v in voxels {
        let c = v.cell();
        if c.iter().any(|&x| x >= n) {
            return Err(CacheError::corrupt(
                path,
                format!("voxel cell {c:?} outside level {level}"),
            ));
        }
        let code = morton_encode(c);
        if codes.last().is_some_and(|&p| p >= code) {
            return Err(CacheError::corrupt(
                path,
                format!("point cloud of level {level} not in strict Morton order"),
            ));
        }
        codes.push(code);
    }
    Ok(codes)
}

#[cfg(test)]
mod page_tests;
#[cfg(test)]
mod tests;
