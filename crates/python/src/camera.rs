//! `ssbvb.Camera`: a pinhole camera in the world (Y up), with no far plane.

use glam::DVec3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A pinhole camera: at `eye`, looking at `target`, `up` roughly up, `fov_y` degrees of
/// vertical field of view. The near plane is a thousandth of the eye's distance to the
/// target unless `near` is given; there is no far plane.
#[pyclass(frozen, module = "ssbvb")]
#[derive(Clone, Copy)]
pub struct Camera {
    pub(crate) inner: ssbvb_voxel::camera::Camera,
}

fn vec3(name: &str, v: (f64, f64, f64)) -> PyResult<DVec3> {
    let d = DVec3::new(v.0, v.1, v.2);
    if !d.is_finite() {
        return Err(PyValueError::new_err(format!(
            "{name} must be finite, got {v:?}"
        )));
    }
    Ok(d)
}

fn check_fov(fov_y: f64) -> PyResult<()> {
    if !(fov_y > 0.0 && fov_y < 180.0) {
        return Err(PyValueError::new_err(format!(
            "fov_y must lie strictly between 0 and 180 degrees, got {fov_y}"
        )));
    }
    Ok(())
}

#[pymethods]
impl Camera {
    #[new]
    #[pyo3(signature = (eye, target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov_y=40.0, near=None))]
    fn new(
        eye: (f64, f64, f64),
        target: (f64, f64, f64),
        up: (f64, f64, f64),
        fov_y: f64,
        near: Option<f64>,
    ) -> PyResult<Self> {
        let (position, look_at, up) = (vec3("eye", eye)?, vec3("target", target)?, vec3("up", up)?);
        let distance = position.distance(look_at);
        if distance == 0.0 {
            return Err(PyValueError::new_err("eye and target must differ"));
        }
        check_fov(fov_y)?;
        let near = near.unwrap_or((distance * 1e-3).max(1e-6));
        if !(near.is_finite() && near > 0.0) {
            return Err(PyValueError::new_err(format!(
                "near must be a positive finite number, got {near}"
            )));
        }
        Ok(Self {
            inner: ssbvb_voxel::camera::Camera {
                position,
                look_at,
                up,
                fov_y_deg: fov_y,
                near,
                far: f64::INFINITY,
            },
        })
    }

    /// A camera on a sphere of `distance` around `target`: `azimuth` degrees about +Y
    /// from +Z (90 looks from +X), `elevation` degrees above the horizontal plane
    /// (clamped to ±89.9), +Y up.
    #[staticmethod]
    #[pyo3(signature = (azimuth, elevation, distance, target=(0.0, 0.0, 0.0), fov_y=40.0))]
    fn orbit(
        azimuth: f64,
        elevation: f64,
        distance: f64,
        target: (f64, f64, f64),
        fov_y: f64,
    ) -> PyResult<Self> {
        let target = vec3("target", target)?;
        if !(azimuth.is_finite() && elevation.is_finite()) {
            return Err(PyValueError::new_err(
                "azimuth and elevation must be finite",
            ));
        }
        if !(distance.is_finite() && distance > 0.0) {
            return Err(PyValueError::new_err(format!(
                "distance must be a positive finite number, got {distance}"
            )));
        }
        check_fov(fov_y)?;
        Ok(Self {
            inner: ssbvb_engine::camera::orbit(target, distance, azimuth, elevation, fov_y),
        })
    }

    /// The eye position.
    #[getter]
    fn eye(&self) -> (f64, f64, f64) {
        self.inner.position.into()
    }

    /// The point looked at.
    #[getter]
    fn target(&self) -> (f64, f64, f64) {
        self.inner.look_at.into()
    }

    /// The up direction.
    #[getter]
    fn up(&self) -> (f64, f64, f64) {
        self.inner.up.into()
    }

    /// Vertical field of view, degrees.
    #[getter]
    fn fov_y(&self) -> f64 {
        self.inner.fov_y_deg
    }

    /// Near plane distance.
    #[getter]
    fn near(&self) -> f64 {
        self.inner.near
    }

    fn __repr__(&self) -> String {
        format!(
            "Camera(eye={:?}, target={:?}, up={:?}, fov_y={})",
            self.eye(),
            self.target(),
            self.up(),
            self.inner.fov_y_deg
        )
    }
}
