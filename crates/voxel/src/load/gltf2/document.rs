//! The GLB container and the glTF JSON document.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use gltf::json;

use crate::load::error::LoadError;

pub(super) const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// A GLB container's parts: the JSON chunk, its file offset, and the BIN chunk if any.
type GlbParts<'a> = (&'a [u8], u64, Option<&'a [u8]>);

/// Splits a GLB container into its JSON chunk (with its file offset) and BIN chunk.
pub(super) fn split_glb<'a>(bytes: &'a [u8], path: &Path) -> Result<GlbParts<'a>, LoadError> {
    let u32_at = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = u32_at(4).ok_or_else(|| LoadError::at_offset(path, 4, "truncated GLB header"))?;
    if version != 2 {
        return Err(LoadError::at_offset(
            path,
            4,
            format!("GLB version {version} is not supported (only 2)"),
        ));
    }
    let length =
        u32_at(8).ok_or_else(|| LoadError::at_offset(path, 8, "truncated GLB header"))? as usize;
    if length < 12 || length > bytes.len() {
        return Err(LoadError::at_offset(
            path,
            8,
            format!(
                "GLB header declares {length} bytes but the file has {}",
                bytes.len()
            ),
        ));
    }
    let data = &bytes[..length];
    let mut json = None;
    let mut bin = None;
    let mut at = 12usize;
    while at < data.len() {
        let (Some(len), Some(kind)) = (u32_at(at), u32_at(at + 4)) else {
            return Err(LoadError::at_offset(
                path,
                at as u64,
                "truncated GLB chunk header",
            ));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= data.len())
            .ok_or_else(|| {
                LoadError::at_offset(
                    path,
                    at as u64,
                    format!("GLB chunk of {len} bytes runs past the end of the file"),
                )
            })?;
        let chunk = &data[start..end];
        match kind {
            CHUNK_JSON if json.is_none() && at == 12 => json = Some((chunk, start as u64)),
            CHUNK_BIN if json.is_some() && bin.is_none() => bin = Some(chunk),
            CHUNK_JSON | CHUNK_BIN => {
                return Err(LoadError::at_offset(
                    path,
                    at as u64,
                    "unexpected or repeated GLB chunk",
                ));
            }
            _ => {} // unknown chunk types must be ignored
        }
        // Chunks are 4-byte aligned; `end` is at most `u32::MAX + 20`, so no overflow.
        at = end.next_multiple_of(4);
    }
    let (json, offset) =
        json.ok_or_else(|| LoadError::at_offset(path, 12, "GLB file has no JSON chunk first"))?;
    Ok((json, offset, bin))
}

/// Deserialises the JSON document (without the `gltf` crate's validation pass).
pub(super) fn parse_document(
    json_bytes: &[u8],
    json_offset: u64,
    is_glb: bool,
    path: &Path,
) -> Result<json::Root, LoadError> {
    // The `gltf` crate has had panics on malformed input in the past; a panic here must
    // become an error, never take the caller down. This is a last line of defence only:
    // all binary data is handled by this reader's own checked code.
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<json::Root, LoadError> {
        let root: json::Root = json::deserialize::from_slice(json_bytes).map_err(|e| {
            if is_glb {
                LoadError::at_offset(
                    path,
                    json_offset,
                    format!(
                        "invalid glTF JSON chunk (line {}, column {}): {e}",
                        e.line(),
                        e.column()
                    ),
                )
            } else {
                LoadError::at_line(path, e.line().max(1), format!("invalid glTF JSON: {e}"))
            }
        })?;
        // The crate's validation pass is deliberately not run: gltf-json 1.4.1 indexes
        // `accessors[...]` unchecked in its primitive hook and panics on an out-of-range
        // POSITION index (found by fuzzing). Every index this module follows is checked
        // where it is used instead, with `get`.
        Ok(root)
    }));
    result.unwrap_or_else(|_| {
        Err(LoadError::parse(
            path,
            "the glTF JSON parser panicked on this file",
        ))
    })
}
