//! The arrays' types: what [`super::prepare`] takes and how it refuses them.

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

    pub(super) fn len(&self) -> usize {
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
    pub(super) shape: Vec<usize>,
    pub(super) strides: Vec<usize>,
    pub(super) data: ArrayData<'a>,
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
