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

/// The largest extent along an axis (cells): the grid of the finest level ssbvb prepares.
pub const MAX_AXIS_CELLS: u64 = 1 << 13;

/// The elements of an array, by type (numpy's dtypes that map to these without a copy;
/// a front end casts the others).
#[derive(Debug, Clone, Copy)]
pub enum ArrayData<'a> {
    /// `bool`.
    Bool(&'a [bool]),
    /// `uint8`.
    U8(&'a [u8]),
    /// `uint16`.
    U16(&'a [u16]),
    /// `uint32`.
    U32(&'a [u32]),
    /// `int32`.
    I32(&'a [i32]),
    /// `int64`.
    I64(&'a [i64]),
    /// `float32`.
    F32(&'a [f32]),
    /// `float64`.
    F64(&'a [f64]),
}

impl ArrayData<'_> {
    /// The element type's name (numpy's spelling).
    pub fn dtype(&self) -> &'static str {
        match self {
            ArrayData::Bool(_) => "bool",
            ArrayData::U8(_) => "uint8",
            ArrayData::U16(_) => "uint16",
            ArrayData::U32(_) => "uint32",
            ArrayData::I32(_) => "int32",
            ArrayData::I64(_) => "int64",
            ArrayData::F32(_) => "float32",
            ArrayData::F64(_) => "float64",
        }
    }

    fn len(&self) -> usize {
        match self {
            ArrayData::Bool(d) => d.len(),
            ArrayData::U8(d) => d.len(),
            ArrayData::U16(d) => d.len(),
            ArrayData::U32(d) => d.len(),
            ArrayData::I32(d) => d.len(),
            ArrayData::I64(d) => d.len(),
            ArrayData::F32(d) => d.len(),
            ArrayData::F64(d) => d.len(),
        }
    }
}

/// An array: its shape, the step between neighbours along each axis (in elements), and its
/// elements. C order (the last axis fastest) is [`Array::new`]; a Fortran-order or
/// axis-permuted view of the same elements is [`Array::strided`], read without a copy.
#[derive(Debug, Clone)]
pub struct Array<'a> {
    shape: Vec<usize>,
    strides: Vec<usize>,
    data: ArrayData<'a>,
}

impl<'a> Array<'a> {
    /// `data` in C order with `shape`.
    pub fn new(shape: Vec<usize>, data: ArrayData<'a>) -> Self {
        let mut strides = vec![1usize; shape.len()];
        for k in (0..shape.len().saturating_sub(1)).rev() {
            strides[k] = strides[k + 1].saturating_mul(shape[k + 1]);
        }
        Self {
            shape,
            strides,
            data,
        }
    }

    /// `data` with `shape`, element `[i, j, ...]` at `i·strides[0] + j·strides[1] + ...`
    /// (checked to lie inside `data` when the arrays are prepared).
    pub fn strided(shape: Vec<usize>, strides: Vec<usize>, data: ArrayData<'a>) -> Self {
        Self {
            shape,
            strides,
            data,
        }
    }

    /// Extent per axis.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// Step per axis, in elements.
    pub fn strides(&self) -> &[usize] {
        &self.strides
    }

    /// The elements.
    pub fn data(&self) -> ArrayData<'a> {
        self.data
    }
}

/// Voxels as arrays. Colour arrays are RGBA (or RGB, opaque) as `uint8` bytes or as floats
/// in `[0, 1]`, sRGB-encoded (as images, matplotlib and voxel editors hold them), alpha
/// linear.
#[derive(Debug, Clone)]
pub enum VoxelArrays<'a> {
    /// `(X, Y, Z, 4)` RGBA, alpha 0 an empty cell; or `(X, Y, Z, 3)` RGB, black an empty
    /// cell.
    Dense(Array<'a>),
    /// `(X, Y, Z)` `bool` or integers, non-zero occupied, every voxel of `color` (sRGB
    /// RGBA bytes).
    Occupancy {
        /// The occupancy grid.
        occupied: Array<'a>,
        /// The voxels' colour.
        color: [u8; 4],
    },
    /// `(X, Y, Z)` integer labels, 0 empty, label `l` coloured `palette[l]` (a `(L, 4)` or
    /// `(L, 3)` colour array; numpy's `palette[labels]`). Any number of labels.
    Labels {
        /// The label grid.
        labels: Array<'a>,
        /// One colour per label (row 0, the empty label's, is not used).
        palette: Array<'a>,
    },
    /// `(N, 3)` integer coordinates (negative ones allowed), coloured by `colors`.
    Sparse {
        /// Coordinates; with [`SparseColors::Palette`], `(N, 4)`: `[x, y, z, label]`.
        coords: Array<'a>,
        /// Their colours.
        colors: SparseColors<'a>,
    },
}

/// The colours of sparse voxels.
#[derive(Debug, Clone)]
pub enum SparseColors<'a> {
    /// One colour for all (sRGB RGBA bytes).
    One([u8; 4]),
    /// `(N, 4)` or `(N, 3)`: one per voxel.
    Each(Array<'a>),
    /// The coordinates are `(N, 4)` `[x, y, z, label]` (K3D's layout), label 0 skipped,
    /// label `l` coloured `palette[l]`.
    Palette(Array<'a>),
}

/// Where the cells lie in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// World position of the minimum corner of cell (or coordinate) `(0, 0, 0)`.
    pub origin: [f64; 3],
    /// Edge of a voxel in world units.
    pub voxel_size: f64,
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            origin: [0.0; 3],
            voxel_size: 1.0,
        }
    }
}

/// Why arrays of voxels were refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArrayError {
    /// An array of the wrong element type.
    #[error("{name} must be {expected}, got {got}")]
    Dtype {
        /// Which array.
        name: &'static str,
        /// The types accepted.
        expected: &'static str,
        /// Its type.
        got: &'static str,
    },
    /// An array of the wrong shape or rank.
    #[error("{name} must have shape {expected}, got {got:?}")]
    Shape {
        /// Which array.
        name: &'static str,
        /// The shape accepted.
        expected: String,
        /// Its shape.
        got: Vec<usize>,
    },
    /// The elements do not fill the shape.
    #[error("{name}: shape {shape:?} holds {want} elements, got {got}")]
    Length {
        /// Which array.
        name: &'static str,
        /// Its shape.
        shape: Vec<usize>,
        /// Elements the shape holds.
        want: usize,
        /// Elements given.
        got: usize,
    },
    /// An element whose value is refused: a colour float outside `[0, 1]` or not a number,
    /// a negative label, a label with no palette row.
    #[error("{name}: {message}")]
    Value {
        /// Which array.
        name: &'static str,
        /// What is wrong, naming the element.
        message: String,
    },
    /// A voxel size that is not a positive finite number.
    #[error("voxel_size must be a positive finite number, got {0}")]
    VoxelSize(f64),
    /// An origin with a coordinate that is not finite.
    #[error("origin must be finite, got {0:?}")]
    Origin([f64; 3]),
    /// More voxels set than a level holds (checked before any of them is copied).
    #[error("{count} voxels set: a level holds at most {max}")]
    TooManyVoxels {
        /// Voxels set.
        count: u64,
        /// The most a level holds (`ssbvb_voxel::voxelize::MAX_VOXELS`).
        max: u64,
    },
    /// The grid's world placement is not representable (an origin or voxel size so large
    /// that the grid's corner or centre is not a finite number).
    #[error("origin and voxel_size place the grid outside finite world coordinates: {0}")]
    Placement(String),
    /// More cells along an axis than the finest level holds.
    #[error("{cells} cells along axis {axis}: a grid holds at most {MAX_AXIS_CELLS} (level 13)")]
    TooLarge {
        /// The axis (0: x).
        axis: usize,
        /// Its extent in cells.
        cells: u64,
    },
}

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
