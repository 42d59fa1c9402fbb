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

pub mod npy;
pub mod obj;
pub mod palette;
pub mod vox;

use std::path::Path;

use crate::asset::{LodLevel, VoxelAsset};
use crate::load::LoadError;
use crate::shading::linear_to_srgb8;

/// Why an export was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The export would exceed what the format (or memory) allows.
    #[error("{format}: {what} is over the limit of {limit}; {hint}")]
    TooLarge {
        /// The format.
        format: &'static str,
        /// What is too large.
        what: String,
        /// The limit.
        limit: String,
        /// What avoids it.
        hint: String,
    },
    /// The asset has no such level.
    #[error("the asset has levels 0 to {max}, not {level}")]
    NoLevel {
        /// Asked for.
        level: u32,
        /// Finest level.
        max: u32,
    },
    /// Writing the file failed (the previous file, if any, is whole).
    #[error(transparent)]
    Write(#[from] LoadError),
}

/// One voxel as exported: its cell and sRGB-encoded RGBA colour, and its unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExportVoxel {
    /// Cell at the exported level.
    pub cell: [u32; 3],
    /// sRGB-encoded RGBA8 colour (alpha as stored).
    pub rgba: [u8; 4],
    /// Unit normal.
    pub normal: [f32; 3],
}

/// The voxels of `asset`'s level `level`, in the point cloud's (Morton) order.
pub fn level_voxels(
    asset: &VoxelAsset,
    level: u32,
) -> Result<(u32, Vec<ExportVoxel>), ExportError> {
    let max = asset.lods.len() as u32 - 1;
    let lod: &LodLevel = asset
        .lods
        .get(level as usize)
        .ok_or(ExportError::NoLevel { level, max })?;
    let voxels = lod
        .point_cloud
        .voxels
        .iter()
        .map(|v| {
            let c = v.color();
            ExportVoxel {
                cell: v.cell(),
                rgba: [
                    linear_to_srgb8(c[0]),
                    linear_to_srgb8(c[1]),
                    linear_to_srgb8(c[2]),
                    (c[3] * 255.0 + 0.5) as u8,
                ],
                normal: v.normal(),
            }
        })
        .collect();
    Ok((1u32 << lod.level, voxels))
}

/// The formats `ssbvb export` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// MagicaVoxel `.vox`.
    Vox,
    /// The project's dense raw grid.
    Raw,
    /// NumPy `.npy`: dense RGBA, or with `sparse` a record per voxel.
    Npy {
        /// One record per voxel instead of the dense grid.
        sparse: bool,
    },
    /// Wavefront OBJ of the exposed faces.
    Obj,
}

/// Refuses an export of an `edge`³ grid that `format` cannot hold, before anything is
/// voxelized or written (the writers check the same).
pub fn check_size(format: ExportFormat, edge: u32) -> Result<(), ExportError> {
    let dense = |name: &'static str, bytes: u64, hint: &str| {
        if bytes > npy::MAX_DENSE_BYTES {
            Err(ExportError::TooLarge {
                format: name,
                what: format!("a dense {edge}³ grid ({} MiB)", bytes >> 20),
                limit: format!("{} MiB", npy::MAX_DENSE_BYTES >> 20),
                hint: hint.into(),
            })
        } else {
            Ok(())
        }
    };
    let cells = u64::from(edge).pow(3);
    match format {
        ExportFormat::Vox if edge > vox::MAX_EDGE => Err(ExportError::TooLarge {
            format: "vox",
            what: format!("a {edge}³ grid"),
            limit: format!("{}³ cells per model", vox::MAX_EDGE),
            hint: "export --level 8 or coarser (several models placed by the scene graph \
                   are not written yet), or use --format npy or obj"
                .into(),
        }),
        ExportFormat::Raw => dense(
            "raw",
            cells,
            "export a coarser --level, or --format npy --sparse",
        ),
        ExportFormat::Npy { sparse: false } => dense(
            "npy",
            cells * 4,
            "export a coarser --level, or --sparse (one record per voxel)",
        ),
        _ => Ok(()),
    }
}

/// What [`write`] wrote.
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
