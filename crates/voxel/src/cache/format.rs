//! The cache file's constants, its error type, and the byte order and checksums of its
//! sections (see the format in the parent module).

use std::io;
use std::path::{Path, PathBuf};

use bytemuck::Pod;
use xxhash_rust::xxh3::Xxh3;

/// File magic.
pub const MAGIC: [u8; 8] = *b"SSBVBAST";
/// Version of the file format and of the preparation that produced it. Bump it whenever
/// either changes, so stale caches are rebuilt instead of read.
pub const FORMAT_VERSION: u32 = 2;
/// Bytes of the fixed header.
pub(super) const HEADER_BYTES: usize = 88;
/// Bytes of a section header.
pub(super) const SECTION_HEADER_BYTES: usize = 24;

pub(super) const KIND_POINT_CLOUD: u32 = 1;
pub(super) const KIND_PROXY_POSITIONS: u32 = 2;
pub(super) const KIND_PROXY_TRIANGLES: u32 = 3;
pub(super) const KIND_PAGE_INDEX: u32 = 4;

/// The name of a section kind, for messages.
pub(super) fn kind_name(kind: u32) -> &'static str {
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
    pub(super) fn io(path: &Path, error: io::Error) -> CacheError {
        CacheError::Io {
            path: path.to_path_buf(),
            error,
        }
    }

    pub(super) fn corrupt(path: &Path, reason: impl Into<String>) -> CacheError {
        CacheError::Corrupt {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }
}

/// Reinterprets a slice of plain data as bytes in file order (little-endian).
pub(super) fn le_bytes<T: Pod>(data: &[T]) -> std::borrow::Cow<'_, [u8]> {
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
pub(super) const fn checksums_checked() -> bool {
    !cfg!(fuzzing)
}

/// Checksum of a section: XXH3-64 of its kind, level, length and payload.
pub(super) fn section_checksum(kind: u32, lod: u32, payload: &[u8]) -> u64 {
    let mut h = Xxh3::new();
    h.update(&kind.to_le_bytes());
    h.update(&lod.to_le_bytes());
    h.update(&(payload.len() as u64).to_le_bytes());
    h.update(payload);
    h.digest()
}
