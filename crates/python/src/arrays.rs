//! numpy arrays handed to the engine in place: an array of a type the engine reads (bool,
//! uint8/16/32, int32/64, float32/64) is borrowed with its strides, no copy, whether C- or
//! Fortran-ordered, a slice or a broadcast view; one with a backward stride, or unaligned
//! data, is made C-contiguous first, and any other integer or float type cast (numpy's
//! `ascontiguousarray`, `astype`).

use numpy::{
    Element, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray,
    PyUntypedArrayMethods, dtype,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use ssbvb_engine::arrays::{Array, ArrayData};

/// A borrowed array of one element type.
enum Held<'py> {
    Bool(PyReadonlyArrayDyn<'py, bool>),
    U8(PyReadonlyArrayDyn<'py, u8>),
    U16(PyReadonlyArrayDyn<'py, u16>),
    U32(PyReadonlyArrayDyn<'py, u32>),
    I32(PyReadonlyArrayDyn<'py, i32>),
    I64(PyReadonlyArrayDyn<'py, i64>),
    F32(PyReadonlyArrayDyn<'py, f32>),
    F64(PyReadonlyArrayDyn<'py, f64>),
}

/// A numpy array borrowed for the engine: its elements, shape and strides (in elements).
pub(crate) struct Input<'py> {
    held: Held<'py>,
    shape: Vec<usize>,
    strides: Vec<usize>,
    /// Elements from the first to the last the shape and strides reach.
    len: usize,
}

impl Input<'_> {
    /// Extent per axis.
    pub(crate) fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// Whether the elements are `bool`.
    pub(crate) fn is_bool(&self) -> bool {
        matches!(self.held, Held::Bool(_))
    }

    /// Whether the elements are floats.
    pub(crate) fn is_float(&self) -> bool {
        matches!(self.held, Held::F32(_) | Held::F64(_))
    }

    /// The engine's view of the array, with its first three axes reversed when
    /// `reverse_grid_axes` (`order="zyx"`).
    pub(crate) fn array(&self, reverse_grid_axes: bool) -> Array<'_> {
        fn slice<'a, T: Element>(a: &'a PyReadonlyArrayDyn<'_, T>, len: usize) -> &'a [T] {
            if len == 0 {
                return &[];
            }
            // SAFETY: `input` checked that the data is aligned for `T`, in native order,
            // and that every element the non-negative strides reach lies in the `len`
            // elements from the data pointer, inside the array's buffer; the read-only
            // borrow keeps the array alive and unwritten from Rust while `a` lives.
            unsafe { std::slice::from_raw_parts(a.data(), len) }
        }
        let data = match &self.held {
            Held::Bool(a) => ArrayData::Bool(slice(a, self.len)),
            Held::U8(a) => ArrayData::U8(slice(a, self.len)),
            Held::U16(a) => ArrayData::U16(slice(a, self.len)),
            Held::U32(a) => ArrayData::U32(slice(a, self.len)),
            Held::I32(a) => ArrayData::I32(slice(a, self.len)),
            Held::I64(a) => ArrayData::I64(slice(a, self.len)),
            Held::F32(a) => ArrayData::F32(slice(a, self.len)),
            Held::F64(a) => ArrayData::F64(slice(a, self.len)),
        };
        let (mut shape, mut strides) = (self.shape.clone(), self.strides.clone());
        if reverse_grid_axes && shape.len() >= 3 {
            shape[..3].reverse();
            strides[..3].reverse();
        }
        Array::strided(shape, strides, data)
    }
}

/// Borrows `obj` (anything `numpy.asarray` takes) as `name` for the engine.
pub(crate) fn input<'py>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<Input<'py>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let a = np.call_method1("asarray", (obj,))?;
    let untyped = a.cast::<PyUntypedArray>()?.clone();
    let descr = untyped.dtype();
    let is = |d: Bound<'py, numpy::PyArrayDescr>| descr.is_equiv_to(&d);
    let native = [
        is(dtype::<bool>(py)),
        is(dtype::<u8>(py)),
        is(dtype::<u16>(py)),
        is(dtype::<u32>(py)),
        is(dtype::<i32>(py)),
        is(dtype::<i64>(py)),
        is(dtype::<f32>(py)),
        is(dtype::<f64>(py)),
    ];
    if !native.contains(&true) {
        // Another integer or float type (int8, int16, uint64, float16, big-endian, …).
        let cast = match descr.kind() {
            b'i' | b'u' => "int64",
            b'f' => "float32",
            _ => {
                return Err(PyTypeError::new_err(format!(
                    "{name} must hold numbers (bool, integers or floats), got dtype {}",
                    descr.str()?
                )));
            }
        };
        return input(name, &a.call_method1("astype", (cast,))?);
    }
    let itemsize = descr.itemsize() as isize;
    let shape = untyped.shape().to_vec();
    // Axes of one element may carry any stride (numpy's relaxed strides): 0 there.
    let byte_strides: Vec<isize> = untyped
        .strides()
        .iter()
        .zip(&shape)
        .map(|(&s, &n)| if n <= 1 { 0 } else { s })
        .collect();
    // Read in place unless a stride runs backwards or splits elements, or the data is
    // unaligned (a field of a record array): then numpy makes a C-contiguous copy.
    let aligned: bool = a.getattr("flags")?.getattr("aligned")?.extract()?;
    let in_place = aligned && byte_strides.iter().all(|&s| s >= 0 && s % itemsize == 0);
    if !in_place {
        let copy = np.call_method1("ascontiguousarray", (&a,))?;
        return input(name, &copy);
    }
    let strides: Vec<usize> = byte_strides
        .iter()
        .map(|&s| (s / itemsize) as usize)
        .collect();
    // The elements the shape and strides reach: up to the last one, from the first.
    let len = if shape.contains(&0) {
        0
    } else {
        shape
            .iter()
            .zip(&strides)
            .map(|(&n, &s)| (n - 1) * s)
            .sum::<usize>()
            + 1
    };
    fn hold<'py, T: Element>(a: &Bound<'py, PyAny>) -> PyResult<PyReadonlyArrayDyn<'py, T>> {
        Ok(a.cast::<PyArrayDyn<T>>()?.try_readonly()?)
    }
    let held = match native.iter().position(|&n| n) {
        Some(0) => Held::Bool(hold(&a)?),
        Some(1) => Held::U8(hold(&a)?),
        Some(2) => Held::U16(hold(&a)?),
        Some(3) => Held::U32(hold(&a)?),
        Some(4) => Held::I32(hold(&a)?),
        Some(5) => Held::I64(hold(&a)?),
        Some(6) => Held::F32(hold(&a)?),
        _ => Held::F64(hold(&a)?),
    };
    Ok(Input {
        held,
        shape,
        strides,
        len,
    })
}

/// A colour given as 3 or 4 numbers: integers 0..=255, or floats in `[0, 1]`.
pub(crate) fn color_arg(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<[u8; 4]> {
    let values: Vec<f64> = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name} must be 3 or 4 numbers (0..255 integers or 0..1 floats)"
        ))
    })?;
    let ints: Option<Vec<i64>> = obj.extract().ok();
    if !matches!(values.len(), 3 | 4) {
        return Err(PyValueError::new_err(format!(
            "{name} must have 3 or 4 components, got {}",
            values.len()
        )));
    }
    let mut out = [0, 0, 0, 255];
    for (k, v) in values.iter().enumerate() {
        out[k] = match &ints {
            Some(i) if (0..=255).contains(&i[k]) => i[k] as u8,
            None if (0.0..=1.0).contains(v) => (v * 255.0).round() as u8,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "{name}: component {k} is {v}; integers lie in 0..=255, floats in [0, 1]"
                )));
            }
        };
    }
    Ok(out)
}
