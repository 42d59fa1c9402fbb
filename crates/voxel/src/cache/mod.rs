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
//! Morton codes, rebuilt with [`lookup_from_codes`] on read in one linear pass per tree
//! depth (cheaper than reading and checksumming them).
//!
//! Reading never trusts the file: every length is checked against the bytes left in the
//! file before anything is allocated, every section's checksum is verified, and the point
//! clouds are checked to be strictly Morton-ordered and inside the grid before a lookup
//! is built from them. Any problem is a [`CacheError`] naming the file, never a panic.
//! Writing is atomic: a temporary file in the destination folder is written, flushed to
//! disk and renamed over the destination.
//!
//! [`load_or_prepare`] (in `prepare`) puts the cache in front of the preparation stage.

mod deps;
mod page_file;
mod pages;
mod prepare;
mod stream;

use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use bytemuck::{Pod, Zeroable};
use xxhash_rust::xxh3::{Xxh3, xxh3_64};

use crate::asset::{LodLevel, MAX_LEVEL, PackedVoxel, PointCloud, ProxyMesh, VoxelAsset};
use crate::model::ObjectSpace;
use crate::prepare::lookup_from_codes;
use crate::svo::morton_encode;

pub use page_file::PageFile;
pub use pages::{PageEntry, page_index, read_page};
pub use prepare::{CacheStatus, PrepareError, PrepareOutcome, load_or_prepare, prepare_into_cache};
pub use stream::{CacheStream, StreamedLevel};

/// File magic.
pub const MAGIC: [u8; 8] = *b"SSBVBAST";
/// Version of the file format and of the preparation that produced it. Bump it whenever
/// either changes, so stale caches are rebuilt instead of read.
pub const FORMAT_VERSION: u32 = 2;
/// Bytes of the fixed header.
const HEADER_BYTES: usize = 88;
/// Bytes of a section header.
const SECTION_HEADER_BYTES: usize = 24;

const KIND_POINT_CLOUD: u32 = 1;
const KIND_PROXY_POSITIONS: u32 = 2;
const KIND_PROXY_TRIANGLES: u32 = 3;
const KIND_PAGE_INDEX: u32 = 4;

fn kind_name(kind: u32) -> &'static str {
    match kind {
        KIND_PAGE_INDEX => "page_index",
        KIND_POINT_CLOUD => "point_cloud",
        KIND_PROXY_POSITIONS => "proxy_positions",
        KIND_PROXY_TRIANGLES => "proxy_triangles",
        _ => "unknown",
    }
}

/// Why a cache file could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    /// An I/O error (other than a file that ends early). The message already includes
    /// the operating system's error, so it is not repeated as a `source()`.
    #[error("{}: {error}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        error: io::Error,
    },
    /// The file does not start with [`MAGIC`].
    #[error("{}: not an ssbvb asset cache (bad magic)", .path.display())]
    BadMagic {
        /// The file.
        path: PathBuf,
    },
    /// The file was written by another format version.
    #[error("{}: cache format version {found}, expected {expected}", .path.display())]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// Version in the file.
        found: u32,
        /// Version this build reads.
        expected: u32,
    },
    /// The file was prepared from different source bytes.
    #[error("{}: prepared from a different source file (hash mismatch)", .path.display())]
    SourceMismatch {
        /// The file.
        path: PathBuf,
    },
    /// The file holds another level.
    #[error("{}: prepared at level {found}, expected level {expected}", .path.display())]
    LevelMismatch {
        /// The file.
        path: PathBuf,
        /// Level in the file.
        found: u32,
        /// Level asked for.
        expected: u32,
    },
    /// The file ends before `what` is complete.
    #[error("{}: truncated in {what}", .path.display())]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The part that is incomplete.
        what: String,
    },
    /// A checksum does not match.
    #[error("{}: checksum mismatch in section {section}", .path.display())]
    Checksum {
        /// The file.
        path: PathBuf,
        /// The section (`header`, `point_cloud of level 3`, ...).
        section: String,
    },
    /// The content is inconsistent (wrong section order, absurd length, unsorted point
    /// cloud, out-of-range index, ...), or the asset to write is.
    #[error("{}: corrupt cache: {reason}", .path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

impl CacheError {
    fn io(path: &Path, error: io::Error) -> CacheError {
        CacheError::Io {
            path: path.to_path_buf(),
            error,
        }
    }

    fn corrupt(path: &Path, reason: impl Into<String>) -> CacheError {
        CacheError::Corrupt {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }
}

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

/// Reinterprets a slice of plain data as bytes in file order (little-endian).
fn le_bytes<T: Pod>(data: &[T]) -> std::borrow::Cow<'_, [u8]> {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    if cfg!(target_endian = "little") {
        std::borrow::Cow::Borrowed(bytes)
    } else {
        // Every payload type is made of 4-byte words.
        let mut v = bytes.to_vec();
        v.chunks_exact_mut(4).for_each(|w| w.reverse());
        std::borrow::Cow::Owned(v)
    }
}

/// Whether stored checksums are compared. Fuzz builds (`cfg(fuzzing)`) skip the comparison
/// so the fuzzer reaches the structure checks behind it: a hostile file can carry valid
/// checksums, so those checks must hold on their own.
const fn checksums_checked() -> bool {
    !cfg!(fuzzing)
}

fn section_checksum(kind: u32, lod: u32, payload: &[u8]) -> u64 {
    let mut h = Xxh3::new();
    h.update(&kind.to_le_bytes());
    h.update(&lod.to_le_bytes());
    h.update(&(payload.len() as u64).to_le_bytes());
    h.update(payload);
    h.digest()
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

/// A reader that knows how many bytes the file has left, so lengths read from the file are
/// checked before anything is allocated for them.
struct Source<'a> {
    path: &'a Path,
    reader: BufReader<File>,
    size: u64,
    remaining: u64,
}

impl<'a> Source<'a> {
    /// Opens a cache file for reading with a buffer of `buffer` bytes.
    fn open(path: &'a Path, buffer: usize) -> Result<Self, CacheError> {
        let file = File::open(path).map_err(|e| CacheError::io(path, e))?;
        let size = file.metadata().map_err(|e| CacheError::io(path, e))?.len();
        Ok(Source {
            path,
            reader: BufReader::with_capacity(buffer, file),
            size,
            remaining: size,
        })
    }

    /// Bytes read or skipped so far: the file offset of what comes next.
    fn position(&self) -> u64 {
        self.size - self.remaining
    }

    /// Reads and checks the header (magic, version, checksum, source hash, level, counts):
    /// the asset's object space.
    fn header(
        &mut self,
        expected_source_hash: u128,
        level: u32,
    ) -> Result<ObjectSpace, CacheError> {
        let path = self.path;
        let size = self.remaining;
        let mut h = [0u8; HEADER_BYTES];
        if size < MAGIC.len() as u64 {
            return Err(CacheError::BadMagic {
                path: path.to_path_buf(),
            });
        }
        self.read_exact(&mut h[..MAGIC.len()], "header")?;
        if h[..8] != MAGIC {
            return Err(CacheError::BadMagic {
                path: path.to_path_buf(),
            });
        }
        self.read_exact(&mut h[MAGIC.len()..], "header")?;
        let u32_at = |o: usize| u32::from_le_bytes(h[o..o + 4].try_into().unwrap_or_default());
        let f64_at = |o: usize| f64::from_le_bytes(h[o..o + 8].try_into().unwrap_or_default());
        let version = u32_at(8);
        if version != FORMAT_VERSION {
            return Err(CacheError::UnsupportedVersion {
                path: path.to_path_buf(),
                found: version,
                expected: FORMAT_VERSION,
            });
        }
        let stored_checksum = u64::from_le_bytes(h[80..88].try_into().unwrap_or_default());
        if checksums_checked() && xxh3_64(&h[..80]) != stored_checksum {
            return Err(CacheError::Checksum {
                path: path.to_path_buf(),
                section: "header".into(),
            });
        }
        let source_hash = u128::from_le_bytes(h[16..32].try_into().unwrap_or_default());
        if source_hash != expected_source_hash {
            return Err(CacheError::SourceMismatch {
                path: path.to_path_buf(),
            });
        }
        let found_level = u32_at(32);
        if found_level != level {
            return Err(CacheError::LevelMismatch {
                path: path.to_path_buf(),
                found: found_level,
                expected: level,
            });
        }
        if level > MAX_LEVEL || u32_at(36) != level + 1 || u32_at(72) != 4 * (level + 1) {
            return Err(CacheError::corrupt(
                path,
                "inconsistent level / section counts",
            ));
        }
        let object_space = ObjectSpace {
            center: glam::DVec3::new(f64_at(40), f64_at(48), f64_at(56)),
            scale: f64_at(64),
        };
        let scale_ok = object_space.scale.is_finite() && object_space.scale > 0.0;
        if !(object_space.center.is_finite() && scale_ok) {
            return Err(CacheError::corrupt(path, "non-finite object space"));
        }
        Ok(object_space)
    }

    fn read_exact(&mut self, buf: &mut [u8], what: &str) -> Result<(), CacheError> {
        if (buf.len() as u64) > self.remaining {
            return Err(CacheError::Truncated {
                path: self.path.to_path_buf(),
                what: what.into(),
            });
        }
        self.reader.read_exact(buf).map_err(|e| {
            if e.kind() == io::ErrorKind::UnexpectedEof {
                CacheError::Truncated {
                    path: self.path.to_path_buf(),
                    what: what.into(),
                }
            } else {
                CacheError::io(self.path, e)
            }
        })?;
        self.remaining -= buf.len() as u64;
        Ok(())
    }

    /// Reads the header of the next section, which must be of `kind` for `lod` and fit in
    /// the file: its payload length and checksum.
    fn section_header(&mut self, kind: u32, lod: u32) -> Result<(u64, u64), CacheError> {
        let name = format!("{} of level {lod}", kind_name(kind));
        let mut head = [0u8; SECTION_HEADER_BYTES];
        self.read_exact(&mut head, &name)?;
        let u32_at = |o: usize| u32::from_le_bytes(head[o..o + 4].try_into().unwrap_or_default());
        let u64_at = |o: usize| u64::from_le_bytes(head[o..o + 8].try_into().unwrap_or_default());
        let (found_kind, found_lod, len, checksum) = (u32_at(0), u32_at(4), u64_at(8), u64_at(16));
        if found_kind != kind || found_lod != lod {
            return Err(CacheError::corrupt(
                self.path,
                format!(
                    "expected section {name}, found {} of level {found_lod}",
                    kind_name(found_kind)
                ),
            ));
        }
        if len > self.remaining {
            return Err(CacheError::Truncated {
                path: self.path.to_path_buf(),
                what: name,
            });
        }
        Ok((len, checksum))
    }

    /// Skips the next section (of `kind` for `lod`) without reading its payload.
    fn skip_section(&mut self, kind: u32, lod: u32) -> Result<(), CacheError> {
        let (len, _) = self.section_header(kind, lod)?;
        self.skip(len)
    }

    /// Skips `len` bytes (at most what is left).
    fn skip(&mut self, len: u64) -> Result<(), CacheError> {
        let jump =
            i64::try_from(len).map_err(|_| CacheError::corrupt(self.path, "absurd length"))?;
        self.reader
            .seek_relative(jump)
            .map_err(|e| CacheError::io(self.path, e))?;
        self.remaining -= len;
        Ok(())
    }

    /// Reads one section, which must be of `kind` for `lod`, as a vector of `T`.
    fn section<T: Pod + Zeroable>(&mut self, kind: u32, lod: u32) -> Result<Vec<T>, CacheError> {
        let name = format!("{} of level {lod}", kind_name(kind));
        let (len, checksum) = self.section_header(kind, lod)?;
        let size = std::mem::size_of::<T>() as u64;
        if !len.is_multiple_of(size) {
            return Err(CacheError::corrupt(
                self.path,
                format!("section {name} has {len} bytes, not a multiple of {size}"),
            ));
        }
        let mut data: Vec<T> = vec![T::zeroed(); (len / size) as usize];
        self.read_exact(bytemuck::cast_slice_mut(&mut data), &name)?;
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut data);
        if checksums_checked() && section_checksum(kind, lod, bytes) != checksum {
            return Err(CacheError::Checksum {
                path: self.path.to_path_buf(),
                section: name,
            });
        }
        if cfg!(target_endian = "big") {
            bytes.chunks_exact_mut(4).for_each(|w| w.reverse());
        }
        Ok(data)
    }
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
        let lookup = lookup_from_codes(l, &codes);
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
