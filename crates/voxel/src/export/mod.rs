//! Exports of a prepared asset's level to files other tools open (`ssbvb export`):
//! MagicaVoxel VOX ([`vox`], with a palette of the closest 255 colours, [`palette`]), the
//! project's dense raw grid, NumPy `.npy` ([`npy`]: a dense RGBA grid or a sparse voxel
//! list) and a Wavefront OBJ surface of the voxels' exposed faces ([`obj`]). Every file is
//! written to a temporary file and renamed; an export over a format's limit is refused
//! before anything is written, naming the limit and what avoids it.
//!
//! Grid coordinates are the level's cells: `x` right, `y` up, `z` towards the viewer (the
//! renderer's Y-up object space, cell `(i, j, k)` covering `[-1 + i·s, -1 + (i+1)·s]` per
//! axis with `s = 2 / 2^level`). Colours are written sRGB-encoded, as image and voxel
//! editors expect.

mod common;
pub mod npy;
pub mod obj;
pub mod palette;
pub mod vox;

use std::path::Path;

pub use common::{
    ExportError, ExportFormat, ExportVoxel, MAX_DENSE_BYTES, MAX_VOX_EDGE, check_size, level_voxels,
};

use crate::asset::VoxelAsset;

/// What [`fn@write`] wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Written {
    /// Voxels exported.
    pub voxels: usize,
    /// Merged rectangles (OBJ only).
    pub rectangles: Option<usize>,
}

/// Writes level `level` of `asset` to `path` in `format`.
pub fn write(
    format: ExportFormat,
    path: &Path,
    asset: &VoxelAsset,
    level: u32,
) -> Result<Written, ExportError> {
    let (edge, voxels) = level_voxels(asset, level)?;
    check_size(format, edge)?;
    let mut rectangles = None;
    match format {
        ExportFormat::Vox => vox::write(path, edge, &voxels)?,
        ExportFormat::Raw => write_raw(path, edge, &voxels)?,
        ExportFormat::Npy { sparse: false } => npy::write_dense(path, edge, &voxels)?,
        ExportFormat::Npy { sparse: true } => npy::write_sparse(path, &voxels)?,
        ExportFormat::Obj => {
            rectangles = Some(obj::write(path, edge, &voxels, &asset.object_space)?);
        }
    }
    Ok(Written {
        voxels: voxels.len(),
        rectangles,
    })
}

/// Writes the project's dense raw grid (`load::write_raw`): one byte per cell, 0 empty,
/// else the voxel's grey level (its sRGB colour's luma, at least 1).
pub fn write_raw(path: &Path, edge: u32, voxels: &[ExportVoxel]) -> Result<(), ExportError> {
    check_size(ExportFormat::Raw, edge)?;
    let cells = u64::from(edge).pow(3);
    let mut grid = vec![0u8; cells as usize];
    for v in voxels {
        let [r, g, b, _] = v.rgba.map(f32::from);
        let luma = (0.2126 * r + 0.7152 * g + 0.0722 * b).round() as u8;
        let [x, y, z] = v.cell.map(|c| c as usize);
        let e = edge as usize;
        grid[x + e * (y + e * z)] = luma.max(1);
    }
    crate::load::write_raw(path, edge, edge, edge, &grid)?;
    Ok(())
}

#[cfg(test)]
mod tests;
