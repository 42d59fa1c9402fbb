//! What the loaders share: size limits, reading files (and recording which were read),
//! and sRGB decoding of colours and textures.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use super::error::LoadError;

/// Most vertices a mesh may have (after de-indexing / instancing).
pub const MAX_VERTICES: usize = 1 << 28;
/// Most triangles a mesh may have (after triangulation / instancing).
pub const MAX_TRIANGLES: usize = 1 << 28;
/// Most voxels a voxel model may have (after scene-graph instancing).
pub const MAX_VOXELS: usize = 1 << 28;
/// Largest raw grid edge: a raw grid holds at most `4096³` cells.
pub const MAX_RAW_DIM: u32 = 4096;
/// Largest file the in-memory loaders read (raw grids are streamed and exempt).
pub const MAX_FILE_BYTES: u64 = 8 << 30;

thread_local! {
    /// The files the load running on this thread has read or looked for (see
    /// [`Loaded::sources`](super::Loaded::sources)); `None` outside
    /// [`load_model_with`](super::load_model_with). The loaders read every file on the
    /// calling thread, so a thread-local sees them all without passing a recorder through
    /// every parser.
    pub(super) static SOURCES: std::cell::RefCell<Option<Vec<PathBuf>>> =
        const { std::cell::RefCell::new(None) };
}

/// Notes that the running load depends on `path` (read, or looked for and not found).
pub(crate) fn record_source(path: &Path) {
    SOURCES.with(|s| {
        if let Some(v) = s.borrow_mut().as_mut() {
            if !v.iter().any(|p| p == path) {
                v.push(path.to_path_buf());
            }
        }
    });
}

/// Reads a whole file, refusing files larger than [`MAX_FILE_BYTES`] before reading.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    record_source(path);
    let meta = fs::metadata(path).map_err(|e| LoadError::io(path, e))?;
    if meta.is_dir() {
        return Err(LoadError::io(
            path,
            io::Error::other("is a directory, not a file"),
        ));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(LoadError::too_large(
            path,
            "bytes in the file",
            meta.len(),
            MAX_FILE_BYTES,
        ));
    }
    fs::read(path).map_err(|e| LoadError::io(path, e))
}

/// sRGB transfer function decode: an sRGB-encoded value in [0, 1] to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB byte → linear float, as a table (256 `powf` calls once per load instead of one per
/// voxel or vertex).
pub(crate) fn srgb_u8_table() -> [f32; 256] {
    let mut t = [0.0; 256];
    for (i, v) in t.iter_mut().enumerate() {
        *v = srgb_to_linear(i as f32 / 255.0);
    }
    t
}

/// Decodes an image file's bytes to a linear RGBA8 [`Texture`](crate::model::Texture):
/// colour channels are sRGB-decoded and re-quantised, alpha is kept.
pub(crate) fn decode_texture(bytes: &[u8]) -> Result<crate::model::Texture, String> {
    let reader = image::ImageReader::new(io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    // `ImageReader` applies the `image` crate's default limits (at most 512 MiB per
    // allocation), so a forged header cannot make us allocate without bound.
    let img = reader.decode().map_err(|e| e.to_string())?.to_rgba8();
    let (width, height) = img.dimensions();
    let mut lut = [0u8; 256];
    for (i, v) in lut.iter_mut().enumerate() {
        *v = (srgb_to_linear(i as f32 / 255.0) * 255.0).round() as u8;
    }
    let texels = img
        .pixels()
        .map(|p| {
            [
                lut[p.0[0] as usize],
                lut[p.0[1] as usize],
                lut[p.0[2] as usize],
                p.0[3],
            ]
        })
        .collect();
    Ok(crate::model::Texture {
        width,
        height,
        texels,
    })
}
