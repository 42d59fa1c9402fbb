//! What every export shares: the voxels as exported, the formats, the size limits, the
//! errors.

use crate::asset::{LodLevel, VoxelAsset};
use crate::load::LoadError;
use crate::shading::linear_to_srgb8;

/// The largest dense grid written (bytes): a level-9 RGBA grid is 512 MiB; level 10's
/// 4 GiB is refused.
pub const MAX_DENSE_BYTES: u64 = 1 << 30;

/// Most cells per axis of one VOX model.
pub const MAX_VOX_EDGE: u32 = 256;

/// Most cells per axis of a VOX export: larger grids are split into 256³ models placed by
/// the scene graph, up to 16³ of them (level 12). The format allows more; this writer
/// stops there because every model's nodes and chunk are held in memory at once.
pub const MAX_VOX_SCENE_EDGE: u32 = 4096;

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
        if bytes > MAX_DENSE_BYTES {
            Err(ExportError::TooLarge {
                format: name,
                what: format!("a dense {edge}³ grid ({} MiB)", bytes >> 20),
                limit: format!("{} MiB", MAX_DENSE_BYTES >> 20),
                hint: hint.into(),
            })
        } else {
            Ok(())
        }
    };
    let cells = u64::from(edge).pow(3);
    match format {
        ExportFormat::Vox if edge > MAX_VOX_SCENE_EDGE => Err(ExportError::TooLarge {
            format: "vox",
            what: format!("a {edge}³ grid"),
            limit: format!(
                "{MAX_VOX_SCENE_EDGE}³ cells ({}³ models of {MAX_VOX_EDGE}³ in the scene graph)",
                MAX_VOX_SCENE_EDGE / MAX_VOX_EDGE
            ),
            hint: "export --level 12 or coarser, or use --format npy --sparse or obj".into(),
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
