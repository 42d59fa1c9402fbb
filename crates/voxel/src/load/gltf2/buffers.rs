//! Buffers and URIs: the GLB BIN chunk, base64 data URIs and files beside the model.

use std::path::{Path, PathBuf};

use gltf::json;

use crate::load::common::read_file;
use crate::load::error::LoadError;

/// Loads every buffer: the GLB BIN chunk, a base64 data URI, or a file beside the model.
pub(super) fn load_buffers(
    root: &json::Root,
    mut bin: Option<&[u8]>,
    path: &Path,
    base_dir: Option<&Path>,
) -> Result<Vec<Vec<u8>>, LoadError> {
    let mut out = Vec::with_capacity(root.buffers.len().min(1024));
    for (i, buffer) in root.buffers.iter().enumerate() {
        let declared = buffer.byte_length.0;
        let mut data = match &buffer.uri {
            None => bin
                .take()
                .ok_or_else(|| {
                    LoadError::parse(
                        path,
                        format!("buffer {i} has no uri and there is no GLB BIN chunk"),
                    )
                })?
                .to_vec(),
            Some(uri) => read_uri(uri, path, base_dir)
                .map_err(|e| e.in_context(path, &format!("buffer {i}")))?,
        };
        if (data.len() as u64) < declared {
            return Err(LoadError::parse(
                path,
                format!(
                    "buffer {i} declares {declared} bytes but holds only {}",
                    data.len()
                ),
            ));
        }
        data.truncate(declared as usize);
        out.push(data);
    }
    Ok(out)
}

/// Why a URI could not be read.
pub(super) enum UriError {
    Load(LoadError),
    Message(String),
}

impl UriError {
    fn in_context(self, path: &Path, what: &str) -> LoadError {
        match self {
            UriError::Load(e) => e,
            UriError::Message(m) => LoadError::parse(path, format!("{what}: {m}")),
        }
    }

    pub(super) fn describe(self) -> String {
        match self {
            UriError::Load(e) => e.to_string(),
            UriError::Message(m) => m,
        }
    }
}

/// The bytes a glTF URI points at.
pub(super) fn read_uri(
    uri: &str,
    path: &Path,
    base_dir: Option<&Path>,
) -> Result<Vec<u8>, UriError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err(UriError::Message(
                "only base64 data URIs are supported".into(),
            ));
        };
        return base64_decode(payload).map_err(|at| {
            UriError::Message(format!("invalid base64 at character {at} of the data URI"))
        });
    }
    if uri.contains("://") {
        return Err(UriError::Message(format!(
            "URI scheme of {uri:?} is not supported (only relative files)"
        )));
    }
    let Some(dir) = base_dir else {
        return Err(UriError::Message(format!(
            "external file {uri:?} cannot be opened (no base folder given for {})",
            path.display()
        )));
    };
    let relative =
        percent_decode(uri).ok_or_else(|| UriError::Message(format!("malformed URI {uri:?}")))?;
    let file: PathBuf = dir.join(relative);
    read_file(&file).map_err(UriError::Load)
}

/// Decodes `%XX` escapes (URIs in glTF are URI-encoded); `None` if malformed or not UTF-8.
pub(super) fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Standard base64 (padding optional); on error, the index of the offending character.
pub(super) fn base64_decode(s: &str) -> Result<Vec<u8>, usize> {
    fn sextet(c: u8) -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    }
    let bytes = s.trim_end().as_bytes();
    let unpadded = bytes
        .strip_suffix(b"==")
        .or_else(|| bytes.strip_suffix(b"="))
        .unwrap_or(bytes);
    if unpadded.len() % 4 == 1 {
        return Err(unpadded.len().saturating_sub(1));
    }
    let mut out = Vec::with_capacity(unpadded.len() / 4 * 3 + 2);
    for (chunk_index, chunk) in unpadded.chunks(4).enumerate() {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc = (acc << 6) | sextet(c).ok_or(chunk_index * 4 + k)?;
        }
        match chunk.len() {
            4 => out.extend_from_slice(&[(acc >> 16) as u8, (acc >> 8) as u8, acc as u8]),
            3 => out.extend_from_slice(&[(acc >> 10) as u8, (acc >> 2) as u8]),
            2 => out.push((acc >> 4) as u8),
            _ => {}
        }
    }
    Ok(out)
}
