//! Voxels handed in as arrays, prepared on the fly with no file involved: a dense RGBA
//! grid `(X, Y, Z, 4)` of `u8`, an occupancy grid `(X, Y, Z)` with one colour, or sparse
//! integer coordinates `(N, 3)` with colours `(N, 4)`. Cell `(i, j, k)` of a grid (or
//! coordinate `(i, j, k)`) is the world box `origin + voxel_size · [i, i+1] × [j, j+1] ×
//! [k, k+1]`; colours are sRGB bytes (as images and numpy users hold them), alpha linear.
//!
//! The cells are kept exactly (`ssbvb_voxel::voxelize::voxels_from_cells`): the level is
//! the smallest whose grid holds the largest extent, the LOD chain, lookup and proxies are
//! built as for a model, and the instance places the grid in the world.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::model::ObjectSpace;
use ssbvb_voxel::progress::Progress;
use ssbvb_voxel::shading::srgb_to_linear;

use crate::{Content, EngineError, Warning};

/// The largest extent along an axis (cells): the grid of the finest level ssbvb prepares.
pub const MAX_AXIS_CELLS: u64 = 1 << 13;

/// The elements of an array, by type.
#[derive(Debug, Clone, Copy)]
pub enum ArrayData<'a> {
    /// `u8`.
    U8(&'a [u8]),
    /// `bool`.
    Bool(&'a [bool]),
    /// `i32`.
    I32(&'a [i32]),
    /// `i64`.
    I64(&'a [i64]),
    /// `f32`.
    F32(&'a [f32]),
}

impl ArrayData<'_> {
    /// The element type's name (numpy's spelling).
    pub fn dtype(&self) -> &'static str {
        match self {
            ArrayData::U8(_) => "uint8",
            ArrayData::Bool(_) => "bool",
            ArrayData::I32(_) => "int32",
            ArrayData::I64(_) => "int64",
            ArrayData::F32(_) => "float32",
        }
    }

    fn len(&self) -> usize {
        match self {
            ArrayData::U8(d) => d.len(),
            ArrayData::Bool(d) => d.len(),
            ArrayData::I32(d) => d.len(),
            ArrayData::I64(d) => d.len(),
            ArrayData::F32(d) => d.len(),
        }
    }
}

/// An array: its shape (C order, the last axis fastest) and its elements.
#[derive(Debug, Clone)]
pub struct Array<'a> {
    /// Extent per axis.
    pub shape: Vec<usize>,
    /// The elements, `shape`'s product of them.
    pub data: ArrayData<'a>,
}

/// Voxels as arrays.
#[derive(Debug, Clone)]
pub enum VoxelArrays<'a> {
    /// `(X, Y, Z, 4)` `uint8` RGBA; alpha 0 is an empty cell.
    Dense(Array<'a>),
    /// `(X, Y, Z)` `bool` (or `uint8`, non-zero occupied), every voxel of `color` (sRGB
    /// RGBA bytes).
    Occupancy {
        /// The occupancy grid.
        occupied: Array<'a>,
        /// The voxels' colour.
        color: [u8; 4],
    },
    /// `(N, 3)` `int32` or `int64` coordinates (negative ones allowed) with `(N, 4)` `uint8`
    /// RGBA colours.
    Sparse {
        /// Coordinates.
        coords: Array<'a>,
        /// Colours.
        colors: Array<'a>,
    },
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
}

/// Checks and prepares `arrays` placed by `placement`. Shapes, types, the placement and
/// the extent are checked before anything is allocated.
pub fn prepare(
    arrays: &VoxelArrays<'_>,
    placement: Placement,
    progress: &dyn Progress,
) -> Result<PreparedArrays, EngineError> {
    check_placement(placement)?;
    let (cells, colors) = match arrays {
        VoxelArrays::Dense(a) => dense_cells(a)?,
        VoxelArrays::Occupancy { occupied, color } => occupancy_cells(occupied, *color)?,
        VoxelArrays::Sparse { coords, colors } => sparse_cells(coords, colors)?,
    };
    if cells.is_empty() {
        return Ok(PreparedArrays {
            asset: None,
            warnings: vec![Warning::new(
                "voxel arrays",
                "no voxel is set: the frame shows no voxel object",
            )],
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

/// Checks `a`'s rank, fixed axes and length; returns its shape.
fn check_shape(
    name: &'static str,
    a: &Array<'_>,
    expected: &str,
    fixed: &[Option<usize>],
) -> Result<Vec<usize>, ArrayError> {
    let rank_ok = a.shape.len() == fixed.len();
    let axes_ok = rank_ok
        && a.shape
            .iter()
            .zip(fixed)
            .all(|(&s, f)| f.is_none_or(|f| f == s));
    if !axes_ok {
        return Err(ArrayError::Shape {
            name,
            expected: expected.into(),
            got: a.shape.clone(),
        });
    }
    let want = a
        .shape
        .iter()
        .try_fold(1usize, |n, &s| n.checked_mul(s))
        .unwrap_or(usize::MAX);
    if want != a.data.len() {
        return Err(ArrayError::Length {
            name,
            shape: a.shape.clone(),
            want,
            got: a.data.len(),
        });
    }
    Ok(a.shape.clone())
}

/// A grid's extent, refused past the finest level before anything is allocated.
fn grid_extent(shape: &[usize]) -> Result<[usize; 3], ArrayError> {
    for (axis, &cells) in shape.iter().take(3).enumerate() {
        if cells as u64 > MAX_AXIS_CELLS {
            return Err(ArrayError::TooLarge {
                axis,
                cells: cells as u64,
            });
        }
    }
    Ok([shape[0], shape[1], shape[2]])
}

/// Refuses `count` voxels above what a level holds, before they are copied.
fn check_count(count: usize) -> Result<(), ArrayError> {
    let max = ssbvb_voxel::voxelize::MAX_VOXELS;
    if count as u64 > max {
        return Err(ArrayError::TooManyVoxels {
            count: count as u64,
            max,
        });
    }
    Ok(())
}

fn linear(c: [u8; 4]) -> [f32; 4] {
    let f = |x: u8| srgb_to_linear(f32::from(x) / 255.0);
    [f(c[0]), f(c[1]), f(c[2]), f32::from(c[3]) / 255.0]
}

type Cells = (Vec<[i64; 3]>, Vec<[f32; 4]>);

fn dense_cells(a: &Array<'_>) -> Result<Cells, EngineError> {
    let ArrayData::U8(data) = a.data else {
        return Err(ArrayError::Dtype {
            name: "dense RGBA grid",
            expected: "uint8",
            got: a.data.dtype(),
        }
        .into());
    };
    let shape = check_shape(
        "dense RGBA grid",
        a,
        "(X, Y, Z, 4)",
        &[None, None, None, Some(4)],
    )?;
    let [_, ny, nz] = grid_extent(&shape)?;
    let count = data.chunks_exact(4).filter(|px| px[3] != 0).count();
    check_count(count)?;
    let mut cells = Vec::with_capacity(count);
    let mut colors = Vec::with_capacity(count);
    for (i, px) in data.chunks_exact(4).enumerate() {
        if px[3] == 0 {
            continue;
        }
        let (x, rest) = (i / (ny * nz), i % (ny * nz));
        cells.push([x as i64, (rest / nz) as i64, (rest % nz) as i64]);
        colors.push(linear([px[0], px[1], px[2], px[3]]));
    }
    Ok((cells, colors))
}

fn occupancy_cells(a: &Array<'_>, color: [u8; 4]) -> Result<Cells, EngineError> {
    let shape = check_shape("occupancy grid", a, "(X, Y, Z)", &[None, None, None])?;
    let [_, ny, nz] = grid_extent(&shape)?;
    let cells = match a.data {
        ArrayData::Bool(d) => occupied_cells(d, |v| *v, ny, nz)?,
        ArrayData::U8(d) => occupied_cells(d, |v| *v != 0, ny, nz)?,
        other => {
            return Err(ArrayError::Dtype {
                name: "occupancy grid",
                expected: "bool or uint8",
                got: other.dtype(),
            }
            .into());
        }
    };
    let colors = vec![linear(color); cells.len()];
    Ok((cells, colors))
}

/// The cells of a C-order `(X, ny, nz)` grid whose element is `set`, counted (and refused
/// above what a level holds) before any is copied.
fn occupied_cells<T>(
    d: &[T],
    set: impl Fn(&T) -> bool,
    ny: usize,
    nz: usize,
) -> Result<Vec<[i64; 3]>, ArrayError> {
    check_count(d.iter().filter(|v| set(v)).count())?;
    Ok(d.iter()
        .enumerate()
        .filter(|(_, v)| set(v))
        .map(|(i, _)| {
            let (x, rest) = (i / (ny * nz), i % (ny * nz));
            [x as i64, (rest / nz) as i64, (rest % nz) as i64]
        })
        .collect())
}

fn sparse_cells(coords: &Array<'_>, colors: &Array<'_>) -> Result<Cells, EngineError> {
    let n = coords.shape.first().copied().unwrap_or(0);
    check_shape("sparse coordinates", coords, "(N, 3)", &[None, Some(3)])?;
    check_count(n)?;
    check_shape(
        "sparse colours",
        colors,
        &format!("({n}, 4)"),
        &[Some(n), Some(4)],
    )?;
    let cells: Vec<[i64; 3]> = match coords.data {
        ArrayData::I32(d) => d
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]].map(i64::from))
            .collect(),
        ArrayData::I64(d) => d.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        other => {
            return Err(ArrayError::Dtype {
                name: "sparse coordinates",
                expected: "int32 or int64",
                got: other.dtype(),
            }
            .into());
        }
    };
    let ArrayData::U8(rgba) = colors.data else {
        return Err(ArrayError::Dtype {
            name: "sparse colours",
            expected: "uint8",
            got: colors.data.dtype(),
        }
        .into());
    };
    // The extent is checked before the grid's cells are made.
    for axis in 0..3 {
        let lo = cells.iter().map(|c| c[axis]).min().unwrap_or(0);
        let hi = cells.iter().map(|c| c[axis]).max().unwrap_or(0);
        // In i128: coordinates at both ends of i64 span more than an i64 holds.
        let extent = i128::from(hi) - i128::from(lo) + 1;
        if extent > i128::from(MAX_AXIS_CELLS) {
            return Err(ArrayError::TooLarge {
                axis,
                cells: u64::try_from(extent).unwrap_or(u64::MAX),
            }
            .into());
        }
    }
    let colors = rgba
        .chunks_exact(4)
        .map(|c| linear([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((cells, colors))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ssbvb_voxel::progress::NoProgress;

    fn err(arrays: VoxelArrays<'_>, p: Placement) -> String {
        match prepare(&arrays, p, &NoProgress) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn wrong_types_shapes_and_placements_are_named() {
        let p = Placement::default();
        let rgb = [0u8; 2 * 2 * 2 * 3];
        let e = err(
            VoxelArrays::Dense(Array {
                shape: vec![2, 2, 2, 3],
                data: ArrayData::U8(&rgb),
            }),
            p,
        );
        assert!(
            e.contains("must have shape (X, Y, Z, 4), got [2, 2, 2, 3]"),
            "{e}"
        );
        let f = [0f32; 8];
        let e = err(
            VoxelArrays::Occupancy {
                occupied: Array {
                    shape: vec![2, 2, 2],
                    data: ArrayData::F32(&f),
                },
                color: [255; 4],
            },
            p,
        );
        assert!(e.contains("must be bool or uint8, got float32"), "{e}");
        let short = [true; 7];
        let e = err(
            VoxelArrays::Occupancy {
                occupied: Array {
                    shape: vec![2, 2, 2],
                    data: ArrayData::Bool(&short),
                },
                color: [255; 4],
            },
            p,
        );
        assert!(e.contains("holds 8 elements, got 7"), "{e}");
        let one = [true];
        let occ = || VoxelArrays::Occupancy {
            occupied: Array {
                shape: vec![1, 1, 1],
                data: ArrayData::Bool(&one),
            },
            color: [255; 4],
        };
        for bad in [0.0, f64::NAN, -1.0, f64::INFINITY] {
            let e = err(
                occ(),
                Placement {
                    voxel_size: bad,
                    ..p
                },
            );
            assert!(
                e.contains("voxel_size must be a positive finite number"),
                "{e}"
            );
        }
        let e = err(
            occ(),
            Placement {
                origin: [0.0, f64::NAN, 0.0],
                ..p
            },
        );
        assert!(e.contains("origin must be finite"), "{e}");
        // Finite inputs whose grid does not fit f64 world coordinates (a 3-cell row needs
        // the 4-cell grid: twice 1e308 across).
        let row = [true; 3];
        let e = err(
            VoxelArrays::Occupancy {
                occupied: Array {
                    shape: vec![3, 1, 1],
                    data: ArrayData::Bool(&row),
                },
                color: [255; 4],
            },
            Placement {
                voxel_size: 1e308,
                ..p
            },
        );
        assert!(e.contains("outside finite world coordinates"), "{e}");
    }

    /// A grid past level 13 is refused from its shape alone: the 8193³ array is never
    /// looked at (its data is empty, which a length check after allocation would report).
    #[test]
    fn a_grid_past_the_finest_level_is_refused_before_anything_is_allocated() {
        let e = err(
            VoxelArrays::Occupancy {
                occupied: Array {
                    shape: vec![8193, 1, 1],
                    data: ArrayData::Bool(&vec![false; 8193]),
                },
                color: [255; 4],
            },
            Placement::default(),
        );
        assert!(e.contains("8193 cells along axis 0"), "{e}");
        // Two sparse voxels at x = `a` and x = `b`.
        let two = |a: i64, b: i64| {
            let coords = [a, 0, 0, b, 0, 0];
            let rgba = [255u8; 8];
            err(
                VoxelArrays::Sparse {
                    coords: Array {
                        shape: vec![2, 3],
                        data: ArrayData::I64(&coords),
                    },
                    colors: Array {
                        shape: vec![2, 4],
                        data: ArrayData::U8(&rgba),
                    },
                },
                Placement::default(),
            )
        };
        let e = two(0, 9000);
        assert!(e.contains("9001 cells along axis 0"), "{e}");
        // Coordinates at both ends of i64: refused, not overflowed.
        let e = two(i64::MIN, i64::MAX);
        assert!(e.contains("cells along axis 0"), "{e}");
    }

    #[test]
    fn an_empty_grid_is_a_warning_not_an_error() {
        let none = [false; 8];
        let p = prepare(
            &VoxelArrays::Occupancy {
                occupied: Array {
                    shape: vec![2, 2, 2],
                    data: ArrayData::Bool(&none),
                },
                color: [255; 4],
            },
            Placement::default(),
            &NoProgress,
        )
        .unwrap();
        assert!(p.asset.is_none());
        assert_eq!(p.warnings.len(), 1);
    }

    /// Dense and sparse forms of the same voxels give the same cells, placed where the
    /// origin and voxel size say: each voxel's world box, from the asset's finest level and
    /// the instance, is the box the arrays describe.
    #[test]
    fn dense_and_sparse_agree_and_cells_land_in_their_world_boxes() {
        let (nx, ny, nz) = (3usize, 5usize, 2usize);
        let mut rgba = vec![0u8; nx * ny * nz * 4];
        let set = [[0, 0, 0], [2, 4, 1], [1, 3, 0]];
        let mut coords = Vec::new();
        let mut colors = Vec::new();
        for (n, c) in set.iter().enumerate() {
            let i = ((c[0] * ny + c[1]) * nz + c[2]) * 4;
            let px = [10 * n as u8, 200, 30, 255];
            rgba[i..i + 4].copy_from_slice(&px);
            // Sparse coordinates shifted by (-5, 7, 0), the origin moved back to match.
            coords.extend([c[0] as i32 - 5, c[1] as i32 + 7, c[2] as i32]);
            colors.extend(px);
        }
        let placement = Placement {
            origin: [1.0, -2.0, 0.5],
            voxel_size: 0.25,
        };
        let dense = prepare(
            &VoxelArrays::Dense(Array {
                shape: vec![nx, ny, nz, 4],
                data: ArrayData::U8(&rgba),
            }),
            placement,
            &NoProgress,
        )
        .unwrap();
        let shifted = Placement {
            origin: [1.0 + 5.0 * 0.25, -2.0 - 7.0 * 0.25, 0.5],
            ..placement
        };
        let sparse = prepare(
            &VoxelArrays::Sparse {
                coords: Array {
                    shape: vec![3, 3],
                    data: ArrayData::I32(&coords),
                },
                colors: Array {
                    shape: vec![3, 4],
                    data: ArrayData::U8(&colors),
                },
            },
            shifted,
            &NoProgress,
        )
        .unwrap();
        let boxes = |p: &PreparedArrays| {
            let (asset, xf, level) = p.asset.as_ref().unwrap();
            assert_eq!(*level, 3, "5 cells need the 8-cell grid");
            let lod = &asset.lods[*level as usize].point_cloud;
            let cell = 2.0 / 8.0;
            let mut out: Vec<[i64; 3]> = lod
                .voxels
                .iter()
                .map(|v| {
                    let c = v.cell();
                    let lo = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * cell - 1.0;
                    let w = xf.transform_point3(lo);
                    // World min corner back to the dense grid's cell index.
                    let idx = (w - DVec3::from(placement.origin)) / placement.voxel_size;
                    assert!((idx - idx.round()).abs().max_element() < 1e-9, "{idx}");
                    [idx.x, idx.y, idx.z].map(|x| x.round() as i64)
                })
                .collect();
            out.sort();
            out
        };
        let want: Vec<[i64; 3]> = {
            let mut w: Vec<[i64; 3]> = set.iter().map(|c| c.map(|x| x as i64)).collect();
            w.sort();
            w
        };
        assert_eq!(boxes(&dense), want);
        assert_eq!(boxes(&sparse), want);
    }
}
