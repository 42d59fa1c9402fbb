//! The cells and colours of [`VoxelArrays`]: each form's arrays checked (element type,
//! shape, strides inside the data, the extent) and its voxels counted, and refused above
//! what a level holds, before any cell is copied.

use ssbvb_voxel::shading::srgb_to_linear;

use super::types::{Array, ArrayData, ArrayError, MAX_AXIS_CELLS, SparseColors, VoxelArrays};

/// Cells (any integer coordinates) and their linear RGBA colours.
pub(super) type Cells = (Vec<[i64; 3]>, Vec<[f32; 4]>);

/// The cells and colours `arrays` hold.
pub(super) fn of(arrays: &VoxelArrays<'_>) -> Result<Cells, ArrayError> {
    match arrays {
        VoxelArrays::Dense(a) => dense(a),
        VoxelArrays::Occupancy { occupied, color } => occupancy(occupied, *color),
        VoxelArrays::Labels { labels, palette } => labelled(labels, palette),
        VoxelArrays::Sparse { coords, colors } => sparse(coords, colors),
    }
}

/// One element of an array, read as what the forms need.
trait Elem: Copy {
    /// The value as an integer (`None` for a float type).
    fn integer(self) -> Option<i64>;
    /// The value as a colour byte: a `u8` as it is, a float in `[0, 1]` scaled to 255
    /// (`None`: outside it, not a number, or another type).
    fn byte(self) -> Option<u8>;
    /// Whether it is not zero (not `false`).
    fn is_set(self) -> bool;
    /// The value, for a message.
    fn show(self) -> String;
}

macro_rules! integer_elem {
    ($($t:ty),*) => {$(
        impl Elem for $t {
            fn integer(self) -> Option<i64> {
                i64::try_from(self).ok()
            }
            fn byte(self) -> Option<u8> {
                None
            }
            fn is_set(self) -> bool {
                self != 0
            }
            fn show(self) -> String {
                self.to_string()
            }
        }
    )*};
}
integer_elem!(u16, u32, i32, i64);

impl Elem for u8 {
    fn integer(self) -> Option<i64> {
        Some(i64::from(self))
    }
    fn byte(self) -> Option<u8> {
        Some(self)
    }
    fn is_set(self) -> bool {
        self != 0
    }
    fn show(self) -> String {
        self.to_string()
    }
}

impl Elem for bool {
    fn integer(self) -> Option<i64> {
        None
    }
    fn byte(self) -> Option<u8> {
        None
    }
    fn is_set(self) -> bool {
        self
    }
    fn show(self) -> String {
        self.to_string()
    }
}

macro_rules! float_elem {
    ($($t:ty),*) => {$(
        impl Elem for $t {
            fn integer(self) -> Option<i64> {
                None
            }
            fn byte(self) -> Option<u8> {
                (0.0..=1.0).contains(&self).then(|| (self * 255.0).round() as u8)
            }
            fn is_set(self) -> bool {
                self != 0.0
            }
            fn show(self) -> String {
                self.to_string()
            }
        }
    )*};
}
float_elem!(f32, f64);

/// Runs `$body` with `$d` bound to the elements of `$data`, whatever their type.
macro_rules! typed {
    ($data:expr, |$d:ident| $body:expr) => {
        match $data {
            ArrayData::Bool($d) => $body,
            ArrayData::U8($d) => $body,
            ArrayData::U16($d) => $body,
            ArrayData::U32($d) => $body,
            ArrayData::I32($d) => $body,
            ArrayData::I64($d) => $body,
            ArrayData::F32($d) => $body,
            ArrayData::F64($d) => $body,
        }
    };
}

const COLOR_TYPES: &str = "uint8, or float32 or float64 in [0, 1]";
const INTEGER_TYPES: &str = "an integer type";

fn is_integer(d: ArrayData<'_>) -> bool {
    !matches!(
        d,
        ArrayData::Bool(_) | ArrayData::F32(_) | ArrayData::F64(_)
    )
}

fn is_color(d: ArrayData<'_>) -> bool {
    matches!(d, ArrayData::U8(_) | ArrayData::F32(_) | ArrayData::F64(_))
}

fn dtype_error(name: &'static str, expected: &'static str, a: &Array<'_>) -> ArrayError {
    ArrayError::Dtype {
        name,
        expected,
        got: a.data.dtype(),
    }
}

/// Checks `a`'s rank and fixed axes, and that every element its shape and strides reach
/// lies inside its data.
fn check_shape(
    name: &'static str,
    a: &Array<'_>,
    expected: &str,
    fixed: &[Option<usize>],
) -> Result<(), ArrayError> {
    let axes_ok = a.shape.len() == fixed.len()
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
    if a.strides.len() != a.shape.len() {
        return Err(ArrayError::Shape {
            name,
            expected: format!("{} strides", a.shape.len()),
            got: a.strides.clone(),
        });
    }
    if a.shape.contains(&0) {
        return Ok(());
    }
    // The last element reached, plus one: the elements the data must hold.
    let want = a
        .shape
        .iter()
        .zip(&a.strides)
        .try_fold(1usize, |n, (&s, &st)| {
            (s - 1).checked_mul(st)?.checked_add(n)
        });
    match want {
        Some(want) if want <= a.data.len() => Ok(()),
        _ => Err(ArrayError::Length {
            name,
            shape: a.shape.clone(),
            want: want.unwrap_or(usize::MAX),
            got: a.data.len(),
        }),
    }
}

/// A grid's extent, refused past the finest level before anything is allocated.
fn grid_extent(shape: &[usize]) -> Result<(), ArrayError> {
    for (axis, &cells) in shape.iter().take(3).enumerate() {
        if cells as u64 > MAX_AXIS_CELLS {
            return Err(ArrayError::TooLarge {
                axis,
                cells: cells as u64,
            });
        }
    }
    Ok(())
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

/// Visits the cells of the first three axes in C order with the offset of their first
/// element.
fn walk(
    a: &Array<'_>,
    mut f: impl FnMut([usize; 3], usize) -> Result<(), ArrayError>,
) -> Result<(), ArrayError> {
    let (s, st) = (&a.shape, &a.strides);
    for x in 0..s[0] {
        for y in 0..s[1] {
            let base = x * st[0] + y * st[1];
            for z in 0..s[2] {
                f([x, y, z], base + z * st[2])?;
            }
        }
    }
    Ok(())
}

/// sRGB bytes to linear RGBA, through a table of the 256 values.
struct Linear([f32; 256]);

impl Linear {
    fn new() -> Self {
        Self(std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)))
    }

    fn of(&self, c: [u8; 4]) -> [f32; 4] {
        [
            self.0[usize::from(c[0])],
            self.0[usize::from(c[1])],
            self.0[usize::from(c[2])],
            f32::from(c[3]) / 255.0,
        ]
    }
}

/// Grid cells chosen by `colour` (`None`: empty), counted before they are copied.
fn grid_cells(
    a: &Array<'_>,
    mut colour: impl FnMut([usize; 3], usize) -> Result<Option<[u8; 4]>, ArrayError>,
) -> Result<Cells, ArrayError> {
    let mut count = 0usize;
    walk(a, |c, o| {
        count += usize::from(colour(c, o)?.is_some());
        Ok(())
    })?;
    check_count(count)?;
    let linear = Linear::new();
    let (mut cells, mut colors) = (Vec::with_capacity(count), Vec::with_capacity(count));
    walk(a, |c, o| {
        if let Some(px) = colour(c, o)? {
            cells.push(c.map(|x| x as i64));
            colors.push(linear.of(px));
        }
        Ok(())
    })?;
    Ok((cells, colors))
}

/// The colour of `channels` elements from `o`, `step` apart (RGB: opaque).
fn color_at<T: Elem>(
    name: &'static str,
    d: &[T],
    o: usize,
    step: usize,
    channels: usize,
    at: impl Fn() -> String,
) -> Result<[u8; 4], ArrayError> {
    let mut px = [0, 0, 0, 255];
    for (k, p) in px.iter_mut().enumerate().take(channels) {
        let v = d[o + k * step];
        *p = v.byte().ok_or_else(|| ArrayError::Value {
            name,
            message: format!(
                "element {} is {}: float colours must lie in [0, 1]",
                at().replace(']', &format!(", {k}]")),
                v.show()
            ),
        })?;
    }
    Ok(px)
}

fn dense(a: &Array<'_>) -> Result<Cells, ArrayError> {
    const NAME: &str = "dense colour grid";
    let channels = a.shape.get(3).copied().filter(|c| matches!(c, 3 | 4));
    let Some(channels) = channels else {
        return Err(ArrayError::Shape {
            name: NAME,
            expected: "(X, Y, Z, 4) or (X, Y, Z, 3)".into(),
            got: a.shape.clone(),
        });
    };
    check_shape(NAME, a, "(X, Y, Z, 4)", &[None, None, None, Some(channels)])?;
    if !is_color(a.data) {
        return Err(dtype_error(NAME, COLOR_TYPES, a));
    }
    grid_extent(&a.shape)?;
    let step = a.strides[3];
    typed!(a.data, |d| grid_cells(a, |c, o| {
        let px = color_at(NAME, d, o, step, channels, || format!("{c:?}"))?;
        let set = if channels == 4 {
            px[3] != 0
        } else {
            px[..3] != [0, 0, 0]
        };
        Ok(set.then_some(px))
    }))
}

fn occupancy(a: &Array<'_>, color: [u8; 4]) -> Result<Cells, ArrayError> {
    const NAME: &str = "occupancy grid";
    check_shape(NAME, a, "(X, Y, Z)", &[None, None, None])?;
    if !(is_integer(a.data) || matches!(a.data, ArrayData::Bool(_))) {
        return Err(dtype_error(NAME, "bool or an integer type", a));
    }
    grid_extent(&a.shape)?;
    typed!(a.data, |d| grid_cells(a, |_, o| Ok(d[o]
        .is_set()
        .then_some(color))))
}

/// A palette's rows as sRGB RGBA bytes.
fn palette_rows(p: &Array<'_>) -> Result<Vec<[u8; 4]>, ArrayError> {
    const NAME: &str = "palette";
    let channels = p.shape.get(1).copied().filter(|c| matches!(c, 3 | 4));
    let Some(channels) = channels.filter(|_| p.shape.len() == 2) else {
        return Err(ArrayError::Shape {
            name: NAME,
            expected: "(L, 4) or (L, 3)".into(),
            got: p.shape.clone(),
        });
    };
    check_shape(NAME, p, "(L, 4)", &[None, Some(channels)])?;
    if !is_color(p.data) {
        return Err(dtype_error(NAME, COLOR_TYPES, p));
    }
    let (rows, step) = (p.shape[0], p.strides[1]);
    typed!(p.data, |d| (0..rows)
        .map(
            |r| color_at(NAME, d, r * p.strides[0], step, channels, || format!(
                "[{r}]"
            ))
        )
        .collect())
}

/// The palette row of `label` at `at` (`None`: label 0, empty).
fn label_color<T: Elem>(
    name: &'static str,
    label: T,
    palette: &[[u8; 4]],
    at: impl Fn() -> String,
) -> Result<Option<[u8; 4]>, ArrayError> {
    match label.integer() {
        Some(0) => Ok(None),
        Some(l) if l > 0 && (l as u64) < palette.len() as u64 => Ok(Some(palette[l as usize])),
        _ => Err(ArrayError::Value {
            name,
            message: format!(
                "label {} at {} has no palette row (labels are 1..{} for a palette of {} rows; 0 is empty)",
                label.show(),
                at(),
                palette.len().saturating_sub(1),
                palette.len()
            ),
        }),
    }
}

fn labelled(labels: &Array<'_>, palette: &Array<'_>) -> Result<Cells, ArrayError> {
    const NAME: &str = "label grid";
    check_shape(NAME, labels, "(X, Y, Z)", &[None, None, None])?;
    if !is_integer(labels.data) {
        return Err(dtype_error(NAME, INTEGER_TYPES, labels));
    }
    grid_extent(&labels.shape)?;
    let rows = palette_rows(palette)?;
    typed!(labels.data, |d| grid_cells(labels, |c, o| label_color(
        NAME,
        d[o],
        &rows,
        || format!("{c:?}")
    )))
}

fn sparse(coords: &Array<'_>, colors: &SparseColors<'_>) -> Result<Cells, ArrayError> {
    const NAME: &str = "sparse coordinates";
    let labelled = matches!(colors, SparseColors::Palette(_));
    let (width, expected) = if labelled {
        (4, "(N, 4): x, y, z, label")
    } else {
        (3, "(N, 3)")
    };
    check_shape(NAME, coords, expected, &[None, Some(width)])?;
    if !is_integer(coords.data) {
        return Err(dtype_error(NAME, INTEGER_TYPES, coords));
    }
    let n = coords.shape[0];
    let (s0, s1) = (coords.strides[0], coords.strides[1]);
    // Rows whose colour is chosen below: every row, or the labelled rows not 0.
    let rows: Vec<usize> = match colors {
        SparseColors::Palette(_) => typed!(coords.data, |d| (0..n)
            .filter(|&i| d[i * s0 + 3 * s1].is_set())
            .collect()),
        _ => (0..n).collect(),
    };
    check_count(rows.len())?;
    let cells: Vec<[i64; 3]> = typed!(coords.data, |d| rows
        .iter()
        .map(|&i| [0, 1, 2].map(|k| d[i * s0 + k * s1].integer().unwrap_or(0)))
        .collect());
    check_extent(&cells)?;
    let linear = Linear::new();
    let colors: Vec<[f32; 4]> = match colors {
        SparseColors::One(c) => vec![linear.of(*c); cells.len()],
        SparseColors::Each(a) => {
            const CNAME: &str = "sparse colours";
            let channels = a.shape.get(1).copied().filter(|c| matches!(c, 3 | 4));
            let expected = format!("({n}, 4) or ({n}, 3)");
            let Some(channels) = channels else {
                return Err(ArrayError::Shape {
                    name: CNAME,
                    expected,
                    got: a.shape.clone(),
                });
            };
            check_shape(CNAME, a, &expected, &[Some(n), Some(channels)])?;
            if !is_color(a.data) {
                return Err(dtype_error(CNAME, COLOR_TYPES, a));
            }
            let (c0, c1) = (a.strides[0], a.strides[1]);
            typed!(a.data, |d| rows
                .iter()
                .map(|&i| {
                    color_at(CNAME, d, i * c0, c1, channels, || format!("[{i}]"))
                        .map(|px| linear.of(px))
                })
                .collect::<Result<_, _>>())?
        }
        SparseColors::Palette(p) => {
            let palette = palette_rows(p)?;
            typed!(coords.data, |d| rows
                .iter()
                .map(|&i| {
                    label_color(NAME, d[i * s0 + 3 * s1], &palette, || format!("row {i}"))
                        .map(|px| linear.of(px.unwrap_or_default()))
                })
                .collect::<Result<_, _>>())?
        }
    };
    Ok((cells, colors))
}

/// Refuses sparse coordinates spanning more than the finest level's grid on an axis.
fn check_extent(cells: &[[i64; 3]]) -> Result<(), ArrayError> {
    for axis in 0..3 {
        let lo = cells.iter().map(|c| c[axis]).min().unwrap_or(0);
        let hi = cells.iter().map(|c| c[axis]).max().unwrap_or(0);
        // In i128: coordinates at both ends of i64 span more than an i64 holds.
        let extent = i128::from(hi) - i128::from(lo) + 1;
        if extent > i128::from(MAX_AXIS_CELLS) {
            return Err(ArrayError::TooLarge {
                axis,
                cells: u64::try_from(extent).unwrap_or(u64::MAX),
            });
        }
    }
    Ok(())
}
