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

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

mod arrays;
mod camera;
mod errors;
mod renderer;
mod voxels;

use errors::{Error, SsbvbWarning};

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
