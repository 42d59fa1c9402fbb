//! Reading a cache file: a reader that checks every length against the bytes left, the
//! header, and checksummed sections.

use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::Path;

use bytemuck::{Pod, Zeroable};
use xxhash_rust::xxh3::xxh3_64;

use super::format::{
    CacheError, FORMAT_VERSION, HEADER_BYTES, MAGIC, SECTION_HEADER_BYTES, checksums_checked,
    kind_name, section_checksum,
};
use crate::asset::MAX_LEVEL;
use crate::model::ObjectSpace;

/// A reader that knows how many bytes the file has left, so lengths read from the file are
/// checked before anything is allocated for them.
pub(super) struct Source<'a> {
    path: &'a Path,
    reader: BufReader<File>,
    size: u64,
    pub(super) remaining: u64,
}

impl<'a> Source<'a> {
    /// Opens a cache file for reading with a buffer of `buffer` bytes.
    pub(super) fn open(path: &'a Path, buffer: usize) -> Result<Self, CacheError> {
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
    pub(super) fn position(&self) -> u64 {
        self.size - self.remaining
    }

    /// Reads and checks the header (magic, version, checksum, source hash, level, counts):
    /// the asset's object space.
    pub(super) fn header(
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

    pub(super) fn read_exact(&mut self, buf: &mut [u8], what: &str) -> Result<(), CacheError> {
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
    pub(super) fn section_header(&mut self, kind: u32, lod: u32) -> Result<(u64, u64), CacheError> {
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
    pub(super) fn skip_section(&mut self, kind: u32, lod: u32) -> Result<(), CacheError> {
        let (len, _) = self.section_header(kind, lod)?;
        self.skip(len)
    }

    /// Skips `len` bytes (at most what is left).
    pub(super) fn skip(&mut self, len: u64) -> Result<(), CacheError> {
        let jump =
            i64::try_from(len).map_err(|_| CacheError::corrupt(self.path, "absurd length"))?;
        self.reader
            .seek_relative(jump)
            .map_err(|e| CacheError::io(self.path, e))?;
        self.remaining -= len;
        Ok(())
    }

    /// Reads one section, which must be of `kind` for `lod`, as a vector of `T`.
    pub(super) fn section<T: Pod + Zeroable>(
        &mut self,
        kind: u32,
        lod: u32,
    ) -> Result<Vec<T>, CacheError> {
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
