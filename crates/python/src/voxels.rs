//! `ssbvb.Voxels`: prepared voxels (the engine's asset: every LOD, the lookup, the
//! proxies) with where they lie, made from a model file, a dense grid or sparse
//! coordinates, and read back as numpy arrays.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DAffine3, DQuat, DVec3};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;
use ssbvb_engine::arrays::{Placement, SparseColors, VoxelArrays};
use ssbvb_engine::{Content, Warning};
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::export::{ExportVoxel, MAX_DENSE_BYTES, level_voxels};
use ssbvb_voxel::lookup::MAX_LEVEL;
use ssbvb_voxel::progress::NoProgress;

use crate::arrays::{color_arg, input};
use crate::errors::{to_py, warn_all};

/// The colour of an occupancy grid given without one (sRGB bytes).
const DEFAULT_COLOR: [u8; 4] = [200, 200, 200, 255];

/// Voxels ready to render, and where they lie.
///
/// Cell `(i, j, k)` is the world box `origin + voxel_size * ([i, i+1] x [j, j+1] x
/// [k, k+1])`, with `x` right, `y` up and `z` towards the default camera (the renderer's
/// Y-up world). Colours are sRGB RGBA bytes (as images hold them), alpha linear.
#[pyclass(frozen, module = "ssbvb")]
pub struct Voxels {
    /// The asset (`None`: no voxel).
    asset: Option<Arc<VoxelAsset>>,
    /// Its finest level, the one the voxels are.
    level: u32,
    origin: [f64; 3],
    voxel_size: f64,
    /// The coordinate of the asset's cell `(0, 0, 0)`.
    min_cell: [i64; 3],
    /// The shape `dense()` returns when known (a grid's input shape, a model's level grid).
    dense_shape: Option<[usize; 3]>,
    warnings: Vec<Warning>,
}

impl Voxels {
    /// The scene object of these voxels, placed by `transform` after their placement
    /// (`None`: no voxel).
    pub(crate) fn content(&self, transform: DAffine3) -> Option<Content> {
        let asset = self.asset.clone()?;
        let mut content = Content::of_asset(asset, self.level);
        content.scene.objects[0].instances = vec![transform * self.instance()];
        Some(content)
    }

    /// The warnings of the preparation.
    pub(crate) fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// The instance that maps the asset's object space `[-1, 1]³` onto the cells' world
    /// boxes.
    fn instance(&self) -> DAffine3 {
        let half = f64::from(1u32 << self.level.saturating_sub(1).min(31)) * self.voxel_size;
        let corner = DVec3::from(self.origin)
            + DVec3::from(self.min_cell.map(|c| c as f64)) * self.voxel_size;
        DAffine3::from_scale_rotation_translation(
            DVec3::splat(half),
            DQuat::IDENTITY,
            corner + DVec3::splat(half),
        )
    }

    /// Each voxel's coordinate, with its export record.
    fn cells(&self) -> PyResult<Vec<([i64; 3], ExportVoxel)>> {
        let Some(asset) = &self.asset else {
            return Ok(Vec::new());
        };
        let (_, voxels) = level_voxels(asset, self.level)
            .map_err(|e| crate::errors::Error::new_err(e.to_string()))?;
        Ok(voxels
            .into_iter()
            .map(|v| {
                let c = v.cell.map(i64::from);
                ([0, 1, 2].map(|k| c[k] + self.min_cell[k]), v)
            })
            .collect())
    }

    /// The lowest coordinate `dense()` covers per axis: 0, or a negative coordinate's.
    fn dense_low(&self) -> [i64; 3] {
        self.min_cell.map(|c| c.min(0))
    }

    /// Prepares `arrays` (the GIL released), warning of what the preparation noticed.
    fn prepare(
        py: Python<'_>,
        arrays: &VoxelArrays<'_>,
        placement: Placement,
        dense_shape: Option<[usize; 3]>,
    ) -> PyResult<Self> {
        let prepared = py
            .detach(|| ssbvb_engine::arrays::prepare(arrays, placement, &NoProgress))
            .map_err(to_py)?;
        warn_all(py, &prepared.warnings)?;
        let (asset, level) = match prepared.asset {
            Some((asset, _, level)) => (Some(asset), level),
            None => (None, 1),
        };
        Ok(Self {
            asset,
            level,
            origin: placement.origin,
            voxel_size: placement.voxel_size,
            min_cell: prepared.min_cell,
            dense_shape,
            warnings: prepared.warnings,
        })
    }
}

fn placement(origin: [f64; 3], voxel_size: f64) -> Placement {
    Placement { origin, voxel_size }
}

/// `order` as whether the grid's axes are reversed (`"zyx"`).
fn reversed(order: &str) -> PyResult<bool> {
    match order {
        "xyz" => Ok(false),
        "zyx" => Ok(true),
        other => Err(PyValueError::new_err(format!(
            "order must be \"xyz\" or \"zyx\", got {other:?}"
        ))),
    }
}

#[pymethods]
impl Voxels {
    /// Voxels from a dense grid.
    ///
    /// `array` is one of:
    /// - `(X, Y, Z)` bool occupancy, every voxel of `color` (default light grey);
    /// - `(X, Y, Z)` integer labels, 0 empty, label `l` coloured `palette[l]` (a `(L, 3)`
    ///   or `(L, 4)` colour array, any number of labels); integers with `color` and no
    ///   palette are occupancy;
    /// - `(X, Y, Z, 4)` RGBA or `(X, Y, Z, 3)` RGB, `uint8` or floats in `[0, 1]`; alpha 0
    ///   (RGB: black) is an empty cell.
    ///
    /// `array[i, j, k]` is cell `(x, y, z) = (i, j, k)`, or `(k, j, i)` with
    /// `order="zyx"` (a view, never a transpose copy). C- and Fortran-ordered arrays of
    /// bool, uint8/16/32, int32/64 and float32/64 are read in place.
    #[staticmethod]
    #[pyo3(signature = (array, origin=(0.0, 0.0, 0.0), voxel_size=1.0, order="xyz", color=None, palette=None))]
    fn from_dense(
        py: Python<'_>,
        array: &Bound<'_, PyAny>,
        origin: (f64, f64, f64),
        voxel_size: f64,
        order: &str,
        color: Option<&Bound<'_, PyAny>>,
        palette: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let reverse = reversed(order)?;
        let grid = input("array", array)?;
        let palette = palette.map(|p| input("palette", p)).transpose()?;
        let color = color.map(|c| color_arg("color", c)).transpose()?;
        let a = grid.array(reverse);
        let shape = a.shape().to_vec();
        let arrays = match (shape.len(), &palette) {
            (4, _) => VoxelArrays::Dense(a),
            (3, Some(p)) if !grid.is_bool() && !grid.is_float() => VoxelArrays::Labels {
                labels: a,
                palette: p.array(false),
            },
            (3, None) if !grid.is_bool() && !grid.is_float() && color.is_none() => {
                return Err(PyValueError::new_err(
                    "an integer grid is labels: give palette= (one colour per label, row 0 \
                     unused), or color= to draw every non-zero cell in one colour",
                ));
            }
            (3, _) => VoxelArrays::Occupancy {
                occupied: a,
                color: color.unwrap_or(DEFAULT_COLOR),
            },
            _ => {
                return Err(PyValueError::new_err(format!(
                    "array must have shape (X, Y, Z) (occupancy or labels) or (X, Y, Z, 4|3) \
                     (colours), got {shape:?}"
                )));
            }
        };
        let dense_shape = [shape[0], shape[1], shape[2]];
        Self::prepare(
            py,
            &arrays,
            placement(origin.into(), voxel_size),
            Some(dense_shape),
        )
    }

    /// Voxels from sparse integer coordinates `(N, 3)` (negative ones allowed), coloured by
    /// `colors` (`(N, 4)` RGBA or `(N, 3)` RGB, `uint8` or floats in `[0, 1]`), else all
    /// `color` (default light grey). With `palette`, `coords` is K3D's `(N, 4)`
    /// `[x, y, z, label]`: label 0 is skipped, label `l` coloured `palette[l]`.
    #[staticmethod]
    #[pyo3(signature = (coords, colors=None, origin=(0.0, 0.0, 0.0), voxel_size=1.0, color=None, palette=None))]
    fn from_sparse(
        py: Python<'_>,
        coords: &Bound<'_, PyAny>,
        colors: Option<&Bound<'_, PyAny>>,
        origin: (f64, f64, f64),
        voxel_size: f64,
        color: Option<&Bound<'_, PyAny>>,
        palette: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let coords = input("coords", coords)?;
        let colors = colors.map(|c| input("colors", c)).transpose()?;
        let palette = palette.map(|p| input("palette", p)).transpose()?;
        let color = color.map(|c| color_arg("color", c)).transpose()?;
        let labelled = coords.shape().len() == 2 && coords.shape()[1] == 4;
        let sparse_colors = match (&colors, &palette) {
            (Some(_), Some(_)) => {
                return Err(PyValueError::new_err("give colors= or palette=, not both"));
            }
            (Some(c), None) => SparseColors::Each(c.array(false)),
            (None, Some(p)) => SparseColors::Palette(p.array(false)),
            (None, None) if labelled => {
                return Err(PyValueError::new_err(
                    "coords of shape (N, 4) are [x, y, z, label] rows: give palette= (one \
                     colour per label, row 0 unused)",
                ));
            }
            (None, None) => SparseColors::One(color.unwrap_or(DEFAULT_COLOR)),
        };
        let arrays = VoxelArrays::Sparse {
            coords: coords.array(false),
            colors: sparse_colors,
        };
        Self::prepare(py, &arrays, placement(origin.into(), voxel_size), None)
    }

    /// World position of the minimum corner of cell `(0, 0, 0)`.
    #[getter]
    fn origin(&self) -> (f64, f64, f64) {
        self.origin.into()
    }

    /// Edge of a voxel in world units.
    #[getter]
    fn voxel_size(&self) -> f64 {
        self.voxel_size
    }

    /// The level of the voxels: the grid of `2**level` cells per axis they were prepared
    /// in (a model's level; for arrays, the smallest that holds their extent).
    #[getter]
    fn level(&self) -> u32 {
        self.level
    }

    /// World position of the minimum corner of `dense()[0, 0, 0]` (the origin unless a
    /// coordinate is negative).
    #[getter]
    fn dense_origin(&self) -> (f64, f64, f64) {
        let low = self.dense_low();
        let o = DVec3::from(self.origin) + DVec3::from(low.map(|c| c as f64)) * self.voxel_size;
        (o.x, o.y, o.z)
    }

    /// What the preparation noticed (also issued as warnings).
    #[getter(warnings)]
    fn warning_lines(&self) -> Vec<String> {
        self.warnings.iter().map(ToString::to_string).collect()
    }

    /// The number of voxels.
    fn __len__(&self) -> usize {
        self.asset.as_ref().map_or(0, |a| {
            a.lods
                .get(self.level as usize)
                .map_or(0, |l| l.point_cloud.voxels.len())
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Voxels({} voxels, level {}, origin {:?}, voxel_size {})",
            self.__len__(),
            self.level,
            self.origin,
            self.voxel_size
        )
    }

    /// The voxels as a dense `(X, Y, Z, 4)` `uint8` RGBA grid, alpha 0 where a cell is
    /// empty (an occupied cell's alpha is at least 1), indexed `[x, y, z]` from
    /// `dense_origin`: `ssbvb export --format npy`'s grid for a model.
    fn dense<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let cells = self.cells()?;
        let low = self.dense_low();
        let high = cells.iter().fold([0i64; 3], |h, (c, _)| {
            [0, 1, 2].map(|k| h[k].max(c[k] - low[k] + 1))
        });
        let shape: [usize; 3] = match self.dense_shape {
            Some(s) if low == [0; 3] => s,
            _ => high.map(|h| h.max(0) as usize),
        };
        let bytes = shape.iter().map(|&s| s as u64).product::<u64>() * 4;
        if bytes > MAX_DENSE_BYTES {
            return Err(PyValueError::new_err(format!(
                "the dense grid {shape:?} would take {bytes} bytes, above {MAX_DENSE_BYTES}: \
                 use sparse()"
            )));
        }
        let grid = ssbvb_voxel::export::npy::dense_grid(
            shape,
            cells
                .iter()
                .map(|(c, v)| ([0, 1, 2].map(|k| (c[k] - low[k]) as usize), v.rgba)),
        );
        PyArray1::from_vec(py, grid)
            .reshape([shape[0], shape[1], shape[2], 4])
            .map(Bound::into_any)
    }

    /// The voxels as sparse arrays `(coords, colors, normals)`: `(N, 3)` `int32` cell
    /// coordinates, `(N, 4)` `uint8` sRGB RGBA and `(N, 3)` `float32` unit normals, in the
    /// order of `ssbvb export --format npy --sparse`.
    fn sparse<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let cells = self.cells()?;
        let n = cells.len();
        let coords: Vec<i32> = cells
            .iter()
            .flat_map(|(c, _)| c.map(|x| x as i32))
            .collect();
        let colors: Vec<u8> = cells.iter().flat_map(|(_, v)| v.rgba).collect();
        let normals: Vec<f32> = cells.iter().flat_map(|(_, v)| v.normal).collect();
        Ok((
            PyArray1::from_vec(py, coords).reshape([n, 3])?.into_any(),
            PyArray1::from_vec(py, colors).reshape([n, 4])?.into_any(),
            PyArray1::from_vec(py, normals).reshape([n, 3])?.into_any(),
        ))
    }
}

/// Voxelizes a model file (OBJ, PLY, glTF/GLB, VOX, raw grid, or a prepared `.ssbvb`
/// asset) at `level` (`2**level` cells per axis, 1..=16; default 8), through the asset
/// cache as `ssbvb render` and `ssbvb export` do. The voxels lie in the model's box
/// `[-1, 1]³`: `origin` is `(-1, -1, -1)` and `voxel_size` is `2 / 2**level`, so
/// `sparse()` is `ssbvb export MODEL --level L --format npy --sparse`'s cells.
#[pyfunction]
#[pyo3(signature = (path, level=None))]
pub fn voxelize(py: Python<'_>, path: PathBuf, level: Option<u32>) -> PyResult<Voxels> {
    if !path.exists() {
        return Err(PyFileNotFoundError::new_err((
            2,
            "No such file or directory",
            path.display().to_string(),
        )));
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"))
    {
        return Err(PyValueError::new_err(format!(
            "{}: voxelize takes a model file; render a scene with ssbvb.render or \
             Renderer.add",
            path.display()
        )));
    }
    check_level(level)?;
    let content = py
        .detach(|| Content::open(&path, level, &NoProgress))
        .map_err(to_py)?;
    warn_all(py, &content.warnings)?;
    let object = content.scene.objects.first().ok_or_else(|| {
        crate::errors::Error::new_err(format!("{}: the model holds no voxel", path.display()))
    })?;
    let asset = object.asset.clone();
    let level = match object.lod {
        ssbvb_gpu::scene::LodPolicy::Fixed(l) => l,
        _ => asset.lods.len() as u32 - 1,
    };
    let edge = 1usize << level;
    Ok(Voxels {
        asset: Some(asset),
        level,
        origin: [-1.0; 3],
        voxel_size: 2.0 / edge as f64,
        min_cell: [0; 3],
        dense_shape: Some([edge; 3]),
        warnings: content.warnings,
    })
}

/// Refuses a level past the finest a model is prepared at.
pub(crate) fn check_level(level: Option<u32>) -> PyResult<()> {
    match level {
        Some(l) if !(1..=MAX_LEVEL).contains(&l) => Err(PyValueError::new_err(format!(
            "level must be 1..={MAX_LEVEL}, got {l}"
        ))),
        _ => Ok(()),
    }
}
