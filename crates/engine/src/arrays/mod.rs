//! Voxels handed in as arrays, prepared on the fly with no file involved ([`VoxelArrays`]):
//! a dense RGBA or RGB grid `(X, Y, Z, 4|3)`, an occupancy grid `(X, Y, Z)` with one
//! colour, a label grid with a palette, or sparse integer coordinates `(N, 3)` with one
//! colour, a colour each, or K3D's `(N, 4)` `[x, y, z, label]` with a palette. Cell
//! `(i, j, k)` of a grid (or coordinate `(i, j, k)`) is the world box `origin + voxel_size ·
//! [i, i+1] × [j, j+1] × [k, k+1]`; colours are sRGB (as images and numpy users hold them),
//! alpha linear. Arrays are read in place through their strides, so a Fortran-order or
//! axis-permuted view costs no copy.
//!
//! The cells are kept exactly (`ssbvb_voxel::voxelize::voxels_from_cells`): the level is
//! the smallest whose grid holds the largest extent, the LOD chain, lookup and proxies are
//! built as for a model, and the instance places the grid in the world. Types, shapes,
//! strides, the placement and the extent are checked, and the voxels counted, before any
//! cell is copied.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::model::ObjectSpace;
use ssbvb_voxel::progress::Progress;

use crate::{Content, EngineError, Warning};

mod cells;
mod types;

pub use types::{
    Array, ArrayData, ArrayError, MAX_AXIS_CELLS, Placement, SparseColors, VoxelArrays,
};

/// The arrays' voxels prepared: the asset, the instance that places it, its level; `None`
/// with a warning when they hold no voxel.
pub struct PreparedArrays {
    /// The asset (`None`: no voxel).
    pub asset: Option<(Arc<VoxelAsset>, DAffine3, u32)>,
    /// What was noticed (an empty grid).
    pub warnings: Vec<Warning>,
    /// The smallest coordinate per axis: the asset's cell `(0, 0, 0)` is this coordinate
    /// of the arrays (`[0; 3]` without a voxel).
    pub min_cell: [i64; 3],
}

/// Checks and prepares `arrays` placed by `placement`. Shapes, types, the placement and
/// the extent are checked before anything is allocated.
pub fn prepare(
    arrays: &VoxelArrays<'_>,
    placement: Placement,
    progress: &dyn Progress,
) -> Result<PreparedArrays, EngineError> {
    check_placement(placement)?;
    let (cells, colors) = cells::of(arrays)?;
    if cells.is_empty() {
        return Ok(PreparedArrays {
            asset: None,
            warnings: vec![Warning::new(
                "voxel arrays",
                "no voxel is set: the frame shows no voxel object",
            )],
            min_cell: [0; 3],
        });
    }
    // Shift so the smallest coordinate is cell 0 (sparse coordinates may be negative).
    let mut min = [i64::MAX; 3];
    let mut max = [i64::MIN; 3];
    for c in &cells {
        for k in 0..3 {
            min[k] = min[k].min(c[k]);
            max[k] = max[k].max(c[k]);
        }
    }
    let extent = (0..3)
        .map(|k| (max[k] - min[k] + 1) as u64)
        .max()
        .unwrap_or(1);
    let level = extent.next_power_of_two().trailing_zeros().max(1);
    let local: Vec<[u32; 3]> = cells
        .iter()
        .map(|c| [0, 1, 2].map(|k| (c[k] - min[k]) as u32))
        .collect();
    drop(cells);
    let voxels = ssbvb_voxel::voxelize::voxels_from_cells(level, &local, &colors)
        .map_err(|e| EngineError::Invalid(format!("voxel arrays: {e}")))?;
    drop((local, colors));
    // Object space [-1, 1]^3 is the level's grid: half its edge in world units.
    let half = f64::from(1u32 << (level - 1)) * placement.voxel_size;
    let corner = DVec3::from(placement.origin)
        + DVec3::new(min[0] as f64, min[1] as f64, min[2] as f64) * placement.voxel_size;
    let center = corner + DVec3::splat(half);
    if !(half.is_finite() && center.is_finite() && corner.is_finite()) {
        return Err(ArrayError::Placement(format!("corner {corner}, half edge {half}")).into());
    }
    let set = ssbvb_voxel::voxelize::VoxelSet {
        object_space: ObjectSpace {
            center,
            scale: 1.0 / half,
        },
        voxels,
        report: Default::default(),
    };
    let (asset, _) = ssbvb_voxel::prepare::prepare_voxel_set(set, progress);
    let instance = DAffine3::from_scale_rotation_translation(
        DVec3::splat(half),
        glam::DQuat::IDENTITY,
        center,
    );
    Ok(PreparedArrays {
        asset: Some((Arc::new(asset), instance, level)),
        warnings: Vec::new(),
        min_cell: min,
    })
}

impl Content {
    /// Voxels from arrays as content: the grid placed in the world at its finest level,
    /// the camera framing it ([`crate::camera::frame_scene`]). An empty grid is an empty
    /// scene with a warning.
    pub fn from_arrays(
        arrays: &VoxelArrays<'_>,
        placement: Placement,
        progress: &dyn Progress,
    ) -> Result<Self, EngineError> {
        let prepared = prepare(arrays, placement, progress)?;
        let mut content = match prepared.asset {
            Some((asset, instance, level)) => {
                let mut c = Content::of_asset(asset, level);
                c.scene.objects[0].instances = vec![instance];
                c.camera = crate::camera::frame_scene(&c.scene, c.camera.fov_y_deg);
                c
            }
            None => Content::of_scene(Default::default()),
        };
        content.warnings.extend(prepared.warnings);
        Ok(content)
    }
}

fn check_placement(p: Placement) -> Result<(), ArrayError> {
    if !(p.voxel_size.is_finite() && p.voxel_size > 0.0) {
        return Err(ArrayError::VoxelSize(p.voxel_size));
    }
    if !p.origin.iter().all(|x| x.is_finite()) {
        return Err(ArrayError::Origin(p.origin));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
