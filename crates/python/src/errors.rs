//! The module's exceptions and warnings, and the engine's errors and warnings made into
//! them.

use std::ffi::CString;

use pyo3::exceptions::{PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use ssbvb_engine::arrays::ArrayError;
use ssbvb_engine::{EngineError, Warning};

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
