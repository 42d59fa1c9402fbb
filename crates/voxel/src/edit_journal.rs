//! The brush journal: every brush operation of an editing session (an edit, an undo, a
//! redo), appended to a file beside the model before it is shown, so that a session
//! killed at any point can be replayed to where it was.
//!
//! # Format (version [`JOURNAL_VERSION`], integers little-endian)
//!
//! ```text
//! header (32 bytes)
//!   magic        [u8; 8]  b"SSBVBJNL"
//!   version      u32      JOURNAL_VERSION
//!   objects      u32      editable objects in the session
//!   model_key    u64      [`model_key`] of the objects as loaded
//!   checksum     u64      XXH3-64 of the 24 bytes above
//! records, one per operation, each RECORD_BYTES (84) long:
//!   length       u32      72 (the payload's bytes)
//!   payload      op u8 (1 edit, 2 undo, 3 redo), shape u8 (1 add sphere, 2 remove
//!                sphere, 3 add box, 4 remove box; 0 for undo and redo), 2 zero bytes,
//!                object u32, six f64 (centre and radius, or min and max), four f32 (RGBA)
//!   checksum     u64      XXH3-64 of length and payload
//! ```
//!
//! A record is written with one `write` and synced. A process killed in the middle of one
//! leaves a short or mismatched **last** record: [`read_journal`] drops it and says so
//! ([`JournalContents::torn`]); a bad record with records after it is corruption, and
//! the whole journal is refused. The format is the project's own because it is tiny and
//! must detect a torn tail, which general serializations do not.

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::{Xxh3, xxh3_64};

use crate::asset::VoxelAsset;
use crate::edit::Edit;

/// First bytes of a journal.
pub const JOURNAL_MAGIC: [u8; 8] = *b"SSBVBJNL";
/// The version this build writes and reads.
pub const JOURNAL_VERSION: u32 = 1;
/// Header bytes.
const HEADER_BYTES: usize = 32;
/// Payload bytes of a record.
const PAYLOAD_BYTES: usize = 72;
/// Bytes of a whole record.
pub const RECORD_BYTES: usize = 4 + PAYLOAD_BYTES + 8;

/// One brush operation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JournalOp {
    /// An edit of object `object` (an index among the session's editable objects).
    Edit {
        /// The editable object.
        object: u32,
        /// The edit, in the object's space.
        edit: Edit,
    },
    /// Undo of the last operation not undone.
    Undo,
    /// Redo of the last undone operation.
    Redo,
}

/// Why a journal cannot be used. Every variant names the file; a journal that cannot be
/// used is left on disk as it is.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// Reading or writing failed.
    #[error("{}: {error}", .path.display())]
    Io {
        /// The journal.
        path: PathBuf,
        /// The operating system's error.
        error: io::Error,
    },
    /// The file is not a journal.
    #[error("{}: not an ssbvb brush journal", .path.display())]
    NotAJournal {
        /// The file.
        path: PathBuf,
    },
    /// Written by a newer (or unknown) format version.
    #[error(
        "{}: journal format version {found}; this build reads version {JOURNAL_VERSION}",
        .path.display()
    )]
    Version {
        /// The journal.
        path: PathBuf,
        /// The version in the file.
        found: u32,
    },
    /// Written for other objects than those loaded.
    #[error(
        "{}: written for another model ({found_objects} editable objects, key {found_key:016x}; \
         this session has {objects}, key {key:016x})",
        .path.display()
    )]
    OtherModel {
        /// The journal.
        path: PathBuf,
        /// Its object count and key.
        found_objects: u32,
        /// Its key.
        found_key: u64,
        /// This session's object count.
        objects: u32,
        /// This session's key.
        key: u64,
    },
    /// A record before the last is damaged.
    #[error("{}: record {record} of {records} is corrupt ({reason})", .path.display())]
    Corrupt {
        /// The journal.
        path: PathBuf,
        /// The damaged record (from 1).
        record: u64,
        /// Records the file holds (whole or not).
        records: u64,
        /// What is wrong.
        reason: String,
    },
}

impl JournalError {
    fn io(path: &Path, error: io::Error) -> Self {
        JournalError::Io {
            path: path.to_path_buf(),
            error,
        }
    }
}

/// The key of the objects a journal belongs to: XXH3-64 of their finest point clouds,
/// in order. Another model, level or file content gives another key.
pub fn model_key(objects: &[&VoxelAsset]) -> u64 {
    let mut h = Xxh3::new();
    for a in objects {
        h.update(&(a.lods.len() as u64).to_le_bytes());
        if let Some(finest) = a.lods.last() {
            h.update(bytemuck::cast_slice(&finest.point_cloud.voxels));
        }
    }
    h.digest()
}

/// What a journal holds.
#[derive(Debug, Clone, PartialEq)]
pub struct JournalContents {
    /// The whole records' operations, in order.
    pub ops: Vec<JournalOp>,
    /// Set when a torn last record was dropped: what was wrong with it.
    pub torn: Option<String>,
    /// Bytes of the header and the whole records (where appending resumes).
    pub valid_bytes: u64,
}

/// Reads the journal at `path`, which must belong to `objects` editable objects of key
/// `key`. A torn last record is dropped and reported; anything else wrong is an error.
pub fn read_journal(path: &Path, objects: u32, key: u64) -> Result<JournalContents, JournalError> {
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| JournalError::io(path, e))?;
    if bytes.len() < HEADER_BYTES || bytes[..8] != JOURNAL_MAGIC {
        return Err(JournalError::NotAJournal {
            path: path.to_path_buf(),
        });
    }
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap_or_default());
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap_or_default());
    let version = u32_at(8);
    if version != JOURNAL_VERSION {
        return Err(JournalError::Version {
            path: path.to_path_buf(),
            found: version,
        });
    }
    if xxh3_64(&bytes[..24]) != u64_at(24) {
        return Err(JournalError::NotAJournal {
            path: path.to_path_buf(),
        });
    }
    let (found_objects, found_key) = (u32_at(12), u64_at(16));
    if (found_objects, found_key) != (objects, key) {
        return Err(JournalError::OtherModel {
            path: path.to_path_buf(),
            found_objects,
            found_key,
            objects,
            key,
        });
    }
    let body = &bytes[HEADER_BYTES..];
    let records = body.len().div_ceil(RECORD_BYTES) as u64;
    let mut ops = Vec::new();
    let mut torn = None;
    for (i, record) in body.chunks(RECORD_BYTES).enumerate() {
        let last = i as u64 + 1 == records;
        match decode(record, objects) {
            Ok(op) => ops.push(op),
            Err(reason) if last => {
                torn = Some(format!(
                    "record {} of {records} was torn ({reason}) and is dropped",
                    i + 1
                ));
            }
            Err(reason) => {
                return Err(JournalError::Corrupt {
                    path: path.to_path_buf(),
                    record: i as u64 + 1,
                    records,
                    reason,
                });
            }
        }
    }
    Ok(JournalContents {
        valid_bytes: (HEADER_BYTES + ops.len() * RECORD_BYTES) as u64,
        ops,
        torn,
    })
}

/// A journal open for appending.
#[derive(Debug)]
pub struct JournalWriter {
    path: PathBuf,
    file: File,
    objects: u32,
}

impl JournalWriter {
    /// Starts a new journal at `path` for `objects` editable objects of key `key`. The
    /// header is written to a temporary file that is renamed over `path`, so a journal
    /// never exists without its header.
    pub fn create(path: &Path, objects: u32, key: u64) -> Result<Self, JournalError> {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let mut tmp = tempfile::Builder::new()
            .prefix(".ssbvb-journal-")
            .tempfile_in(&dir)
            .map_err(|e| JournalError::io(&dir, e))?;
        let mut header = Vec::with_capacity(HEADER_BYTES);
        header.extend_from_slice(&JOURNAL_MAGIC);
        header.extend_from_slice(&JOURNAL_VERSION.to_le_bytes());
        header.extend_from_slice(&objects.to_le_bytes());
        header.extend_from_slice(&key.to_le_bytes());
        let checksum = xxh3_64(&header);
        header.extend_from_slice(&checksum.to_le_bytes());
        tmp.write_all(&header)
            .and_then(|()| tmp.as_file().sync_all())
            .map_err(|e| JournalError::io(tmp.path(), e))?;
        tmp.persist(path)
            .map_err(|e| JournalError::io(path, e.error))?;
        Self::resume(path, objects, HEADER_BYTES as u64)
    }

    /// Opens the journal at `path` to append after its first `valid_bytes` (a torn tail
    /// beyond them is cut off first).
    pub fn resume(path: &Path, objects: u32, valid_bytes: u64) -> Result<Self, JournalError> {
        let file = OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| JournalError::io(path, e))?;
        file.set_len(valid_bytes)
            .and_then(|()| file.sync_all())
            .map_err(|e| JournalError::io(path, e))?;
        let mut w = Self {
            path: path.to_path_buf(),
            file,
            objects,
        };
        use std::io::Seek;
        w.file
            .seek(io::SeekFrom::End(0))
            .map_err(|e| JournalError::io(path, e))?;
        Ok(w)
    }

    /// The journal's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends `op` in one write and syncs it to disk before returning.
    pub fn record(&mut self, op: &JournalOp) -> Result<(), JournalError> {
        let bytes = self.encoded(op)?;
        self.write_synced(&bytes)
    }

    /// Fault injection for tests: writes the first `keep` bytes of `op`'s record, as a
    /// process killed in the middle of [`JournalWriter::record`] would leave it.
    #[doc(hidden)]
    pub fn record_torn(&mut self, op: &JournalOp, keep: usize) -> Result<(), JournalError> {
        let bytes = self.encoded(op)?;
        self.write_synced(&bytes[..keep.min(bytes.len())])
    }

    fn encoded(&self, op: &JournalOp) -> Result<Vec<u8>, JournalError> {
        encode(op, self.objects).map_err(|reason| {
            JournalError::io(
                &self.path,
                io::Error::new(io::ErrorKind::InvalidInput, reason),
            )
        })
    }

    fn write_synced(&mut self, bytes: &[u8]) -> Result<(), JournalError> {
        self.file
            .write_all(bytes)
            .and_then(|()| self.file.sync_data())
            .map_err(|e| JournalError::io(&self.path, e))
    }
}

/// The record of `op` (its object checked against `objects`).
fn encode(op: &JournalOp, objects: u32) -> Result<Vec<u8>, String> {
    let (code, shape, object, values, color) = match *op {
        JournalOp::Undo => (2u8, 0u8, 0u32, [0.0; 6], (0.0, 0.0, 0.0, 0.0)),
        JournalOp::Redo => (3, 0, 0, [0.0; 6], (0.0, 0.0, 0.0, 0.0)),
        JournalOp::Edit { object, edit } => {
            if object >= objects {
                return Err(format!("object {object} of {objects}"));
            }
            let (shape, values, color) = edit_fields(&edit);
            (1, shape, object, values, color)
        }
    };
    let mut r = Vec::with_capacity(RECORD_BYTES);
    r.extend_from_slice(&(PAYLOAD_BYTES as u32).to_le_bytes());
    r.extend_from_slice(&[code, shape, 0, 0]);
    r.extend_from_slice(&object.to_le_bytes());
    for v in values {
        r.extend_from_slice(&v.to_le_bytes());
    }
    for c in [color.0, color.1, color.2, color.3] {
        r.extend_from_slice(&c.to_le_bytes());
    }
    let checksum = xxh3_64(&r);
    r.extend_from_slice(&checksum.to_le_bytes());
    debug_assert_eq!(r.len(), RECORD_BYTES);
    Ok(r)
}

type Rgba = (f32, f32, f32, f32);

/// An edit's shape code, six numbers and colour.
fn edit_fields(edit: &Edit) -> (u8, [f64; 6], Rgba) {
    let none = (0.0, 0.0, 0.0, 0.0);
    match *edit {
        Edit::AddSphere {
            center: c,
            radius,
            color,
        } => (1, [c.0, c.1, c.2, radius, 0.0, 0.0], color),
        Edit::RemoveSphere { center: c, radius } => (2, [c.0, c.1, c.2, radius, 0.0, 0.0], none),
        Edit::AddBox { min, max, color } => (3, [min.0, min.1, min.2, max.0, max.1, max.2], color),
        Edit::RemoveBox { min, max } => (4, [min.0, min.1, min.2, max.0, max.1, max.2], none),
    }
}

/// The operation of a whole record, or what is wrong with it.
fn decode(record: &[u8], objects: u32) -> Result<JournalOp, String> {
    if record.len() < RECORD_BYTES {
        return Err(format!("{} of {RECORD_BYTES} bytes", record.len()));
    }
    let u32_at = |o: usize| u32::from_le_bytes(record[o..o + 4].try_into().unwrap_or_default());
    let f64_at = |o: usize| f64::from_le_bytes(record[o..o + 8].try_into().unwrap_or_default());
    let f32_at = |o: usize| f32::from_le_bytes(record[o..o + 4].try_into().unwrap_or_default());
    let stored = u64::from_le_bytes(record[76..84].try_into().unwrap_or_default());
    if xxh3_64(&record[..76]) != stored {
        return Err("checksum mismatch".into());
    }
    if u32_at(0) as usize != PAYLOAD_BYTES {
        return Err(format!("payload of {} bytes", u32_at(0)));
    }
    let (code, shape, object) = (record[4], record[5], u32_at(8));
    let v: [f64; 6] = std::array::from_fn(|i| f64_at(12 + 8 * i));
    let color = (f32_at(60), f32_at(64), f32_at(68), f32_at(72));
    let edit = match (code, shape) {
        (2, 0) => return Ok(JournalOp::Undo),
        (3, 0) => return Ok(JournalOp::Redo),
        (1, 1) => Edit::AddSphere {
            center: (v[0], v[1], v[2]),
            radius: v[3],
            color,
        },
        (1, 2) => Edit::RemoveSphere {
            center: (v[0], v[1], v[2]),
            radius: v[3],
        },
        (1, 3) => Edit::AddBox {
            min: (v[0], v[1], v[2]),
            max: (v[3], v[4], v[5]),
            color,
        },
        (1, 4) => Edit::RemoveBox {
            min: (v[0], v[1], v[2]),
            max: (v[3], v[4], v[5]),
        },
        _ => return Err(format!("unknown operation {code}/{shape}")),
    };
    if object >= objects {
        return Err(format!("object {object} of {objects}"));
    }
    Ok(JournalOp::Edit { object, edit })
}

#[cfg(test)]
#[path = "edit_journal_tests.rs"]
mod tests;
