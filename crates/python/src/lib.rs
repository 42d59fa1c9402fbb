//! `ssbvb._ssbvb`: the Python extension of ssbvb, a thin layer over `ssbvb-engine` (the
//! package `ssbvb` re-exports it with an image type and the one-call `render`).
//!
//! - `Voxels` (`voxels`): voxels from a model file (`voxelize`), a dense grid or sparse
//!   coordinates, read back as numpy arrays;
//! - `Renderer` and `Camera` (`renderer`, `camera`): content on a device, rendered into
//!   `(H, W, 4)` `uint8` arrays.
//!
//! Every engine error becomes a Python exception (`TypeError` or `ValueError` for an
//! unusable argument, `FileNotFoundError` for a missing file, else `ssbvb.Error`), every
//! engine warning a `warnings.warn` of `ssbvb.SsbvbWarning`; GPU work runs with the GIL
//! released.

use std::ffi::CString;

use pyo3::exceptions::{PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use ssbvb_engine::arrays::ArrayError;
use ssbvb_engine::{EngineError, Warning};

mod arrays;
mod camera;
mod renderer;
mod voxels;

pyo3::create_exception!(
    ssbvb,
    Error,
    pyo3::exceptions::PyException,
    "An error of the ssbvb engine (a model that cannot be prepared, a device that cannot be made, a pipeline that does not resolve); the message is the engine's."
);
pyo3::create_exception!(
    ssbvb,
    SsbvbWarning,
    PyUserWarning,
    "What ssbvb did instead of what was asked: a missing texture, an empty grid, a budget lowered."
);

/// The Python exception of an engine error: a wrong type is a `TypeError`, any other
/// unusable argument a `ValueError`, the rest `ssbvb.Error`.
pub(crate) fn to_py(e: EngineError) -> PyErr {
    let message = e.to_string();
    match root(&e) {
        EngineError::Arrays(ArrayError::Dtype { .. }) => PyTypeError::new_err(message),
        EngineError::Arrays(_) | EngineError::Invalid(_) => PyValueError::new_err(message),
        _ => Error::new_err(message),
    }
}

/// The error under any context wrappers.
fn root(e: &EngineError) -> &EngineError {
    match e {
        EngineError::Context { error, .. } => root(error),
        other => other,
    }
}

/// Issues each warning as a `warnings.warn(message, ssbvb.SsbvbWarning)`.
pub(crate) fn warn_all(py: Python<'_>, warnings: &[Warning]) -> PyResult<()> {
    let category = py.get_type::<SsbvbWarning>();
    for w in warnings {
        let text = CString::new(w.to_string().replace('\0', " ")).unwrap_or_default();
        PyErr::warn(py, &category, &text, 2)?;
    }
    Ok(())
}

/// PNG bytes of an `(H, W, 4)` `uint8` image (what Jupyter shows).
#[pyfunction]
fn png_bytes(image: numpy::PyReadonlyArray3<'_, u8>) -> PyResult<Vec<u8>> {
    use numpy::PyUntypedArrayMethods;
    let shape = image.shape();
    if shape[2] != 4 {
        return Err(PyValueError::new_err(format!(
            "an image must have shape (H, W, 4), got {shape:?}"
        )));
    }
    let (h, w) = (shape[0] as u32, shape[1] as u32);
    let pixels = image.as_array().iter().copied().collect::<Vec<u8>>();
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        &pixels,
        w,
        h,
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| PyValueError::new_err(format!("encoding the PNG: {e}")))?;
    Ok(out)
}

/// The names of the SSBVB pipeline forms, in the engine's order of preference.
#[pyfunction]
fn forms() -> Vec<&'static str> {
    ssbvb_engine::FORMS.iter().map(|f| f.name).collect()
}

#[pymodule]
fn _ssbvb(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("SsbvbWarning", py.get_type::<SsbvbWarning>())?;
    m.add_class::<voxels::Voxels>()?;
    m.add_class::<camera::Camera>()?;
    m.add_class::<renderer::Renderer>()?;
    m.add_function(wrap_pyfunction!(voxels::voxelize, m)?)?;
    m.add_function(wrap_pyfunction!(png_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(forms, m)?)?;
    Ok(())
}
