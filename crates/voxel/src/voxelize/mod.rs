//! Conservative surface voxelization of meshes and resampling of voxel models.
//!
//! # Meshes
//!
//! A cell is set when its closed box overlaps a triangle (the separating axis test of
//! Akenine-Möller, in f64): the voxelization is *conservative*, so a triangle lying exactly
//! on a cell face sets the cells on both sides and one touching a cell corner sets all
//! eight. The work is organised so that no dense 2^L³ grid ever exists:
//!
//! 1. Vertices are mapped to grid units (`g = (object + 1) · 2^L / 2`, cell `i` = `[i, i+1]`,
//!    the exact [`ObjectSpace`] convention; the power-of-two factor is exact in f64).
//! 2. The grid is cut into bricks of 32³ cells. Each triangle is binned into the bricks
//!    it overlaps (the same cell walk and test, at brick scale), and the (brick, triangle)
//!    pairs are sorted.
//! 3. Bricks are processed in parallel in Morton order. Inside a brick a triangle is walked
//!    row by row and column by column along its dominant normal axis: the triangle is
//!    clipped to the row slab, then to the column slab, and the clipped polygon's depth
//!    range gives the few candidate cells of the column. A candidate is kept when the
//!    separating axis test says so, or (a shortcut that skips the test) when the triangle
//!    part clipped to it has its vertex mean well inside the cell, which proves overlap.
//!    That part also gives the triangle's area inside the cell and its centroid, which
//!    weight and place the attribute samples.
//! 4. A brick's cells accumulate in a per-thread scratch of 32³ entries indexed by local
//!    Morton code (only touched entries are reset), and are emitted sorted, so the
//!    concatenated output is globally Morton-sorted without a global sort of the voxels.
//!
//! Per voxel: normal = area-weighted sum of the unit face normals of the triangles inside
//! the cell, normalized; where that cancels (two opposite faces in one cell) the normal of
//! the triangle with the largest area in the cell; where no triangle has a normal (only
//! degenerate ones touched the cell) the occupancy gradient of the 26-neighbourhood; last
//! resort +Z. Colour = material base colour × texture at the interpolated uv × vertex
//! colour, sampled at the centroid of each triangle's part in the cell and averaged with
//! area weights (degenerate contributions get a tiny weight, so they only count where
//! nothing else does). Degenerate triangles (segments, points) still set every cell they
//! touch; triangles with a non-finite vertex or an out-of-range index are skipped and
//! counted in [`VoxelizeReport`].
//!
//! # Voxel models
//!
//! The union of the unit cubes is fitted into object space; a target cell is occupied when
//! it overlaps a source cube with positive volume. The cell ranges are computed in exact
//! integer arithmetic so that boundaries that coincide (the model's centre, aligned
//! resolutions) never produce sliver cells from rounding. See [`VoxelFill`] for which
//! occupied cells are kept.
//!
//! # Layout
//!
//! [`triangle_box_overlap`] and the clipped cell walk live in `geometry`, the mesh
//! pipeline (binning, bricks, per-cell sums) in `mesh`, its region-by-region driver for
//! bounded memory in `regions`, colour and normal sampling in `attributes`, and the
//! resampling of voxel models in `resample`.

#[cfg(test)]
mod attribute_tests;
mod attributes;
mod cells;
mod geometry;
mod mesh;
mod regions;
mod resample;
#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;

use serde::Serialize;

use crate::asset::MAX_LEVEL;
use crate::model::ObjectSpace;
use crate::svo::LevelVoxels;

pub(crate) use attributes::gradient_26;
pub use cells::voxels_from_cells;
pub use geometry::triangle_box_overlap;
pub use mesh::{mesh_bounds, mesh_object_space, voxelize_mesh, voxelize_mesh_in};
pub use regions::voxelize_mesh_regions;
pub use resample::{voxel_model_object_space, voxelize_voxels, voxelize_voxels_with};

/// Most voxels (or candidate cells) one voxelization may produce. Above it the request is
/// refused up front instead of exhausting memory (each voxel costs ~44 bytes while being
/// built, plus its point cloud and lookup).
pub const MAX_VOXELS: u64 = 1 << 28;

/// [`MAX_VOXELS`] of the region-by-region voxelization ([`voxelize_mesh_regions`]), which
/// keeps no float attributes of the whole level: the asset's 16 bytes per voxel bound it
/// (the estimate is an upper bound: about twice the bunny's real count).
pub const MAX_REGION_VOXELS: u64 = 1 << 30;

/// A voxelization result: the finest level of an asset before the LOD chain is built.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelSet {
    /// How the model's coordinates map into object space.
    pub object_space: ObjectSpace,
    /// The occupied cells with attributes (Morton-sorted).
    pub voxels: LevelVoxels,
    /// What was skipped or patched on the way.
    pub report: VoxelizeReport,
}

/// Counts of what the voxelizer met: inputs it skipped and fallbacks it took.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct VoxelizeReport {
    /// Triangles in the mesh (0 for voxel models).
    pub triangles: u64,
    /// Triangles skipped because a vertex is NaN or infinite.
    pub skipped_non_finite: u64,
    /// Triangles skipped because an index is out of range.
    pub skipped_bad_index: u64,
    /// Zero-area triangles (segments or points): voxelized, but without a normal.
    pub degenerate: u64,
    /// Voxels of the source model (0 for meshes).
    pub source_voxels: u64,
    /// Voxels whose normal came from the occupancy gradient or the fixed fallback because
    /// no triangle in them had a usable normal.
    pub normal_fallbacks: u64,
}

/// Which occupied cells a voxel-model resampling keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum VoxelFill {
    /// Only occupied cells with at least one unoccupied face neighbour (or on the grid
    /// border): the visible boundary of the union, as for meshes. Upsampling a model keeps
    /// a surface-sized voxel count (a 21³ model at level 12 would otherwise be billions of
    /// interior cells that no ray can reach).
    #[default]
    Shell,
    /// Every occupied cell. Refused with [`VoxelizeError::TooLarge`] when that exceeds
    /// [`MAX_VOXELS`].
    Solid,
}

/// Why a voxelization could not be done.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum VoxelizeError {
    /// The requested level is above what the asset format can address or what the caller
    /// allows.
    #[error("voxelization level {level} is above the maximum level {max}")]
    LevelTooHigh {
        /// Requested level.
        level: u32,
        /// Highest level allowed.
        max: u32,
    },
    /// Nothing to voxelize.
    #[error("the model has nothing to voxelize: {0}")]
    Empty(String),
    /// Cells given one by one do not fit their grid or their colours
    /// ([`voxels_from_cells`]).
    #[error("{0}")]
    BadCells(String),
    /// A vertex lies outside the object space the mesh was asked to be voxelized in.
    #[error("the mesh leaves the object space it was given (a vertex maps outside [-1, 1]³)")]
    OutsideObjectSpace,
    /// The result would exceed [`MAX_VOXELS`] (or [`MAX_REGION_VOXELS`]).
    #[error(
        "level {level} would produce about {estimate} voxels, more than the limit of {limit}; choose a lower level"
    )]
    TooLarge {
        /// Requested level.
        level: u32,
        /// Estimated (upper bound) voxel count.
        estimate: u64,
        /// The limit.
        limit: u64,
    },
}

/// Grid-unit factor of a level: grid = (object + 1) · half_cells.
fn half_cells(level: u32) -> f64 {
    (1u64 << level) as f64 * 0.5
}

fn check_level(level: u32) -> Result<(), VoxelizeError> {
    if level > MAX_LEVEL {
        return Err(VoxelizeError::LevelTooHigh {
            level,
            max: MAX_LEVEL,
        });
    }
    Ok(())
}
