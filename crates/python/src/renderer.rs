//! `ssbvb.Renderer`: content added from voxels, model files or scene files, put on a
//! device by the engine (opened again only when content is added), rendered into numpy
//! arrays with the GIL released.

use std::path::PathBuf;

use glam::{DAffine3, DMat3, DVec3};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use ssbvb_engine::{Content, Engine, FrameReport, RenderOptions};
use ssbvb_voxel::progress::NoProgress;

use crate::camera::Camera;
use crate::errors::{to_py, warn_all};
use crate::voxels::{Voxels, check_level};

/// Renders voxels and scenes headless into numpy arrays.
///
/// `size` is `(width, height)`. `pipeline` is a form name (`ssbvb.forms()`), a pipeline
/// file of the bundled set by name (`"esvo"`, `"dense_dda"`, …) or a path to a `.ron`
/// pipeline; `None` lets the engine choose the fastest form for the adapter. `smooth=False`
/// turns the paper's Gaussian normal smoothing off: the exact cubes, each shaded by its
/// own normal. `backend` (`"vulkan"`, `"gl"`, `"metal"`, `"dx12"`) sets `WGPU_BACKEND` for
/// the process before the first device is made. `gpu_budget_mib` streams finer levels in
/// under a GPU memory budget.
#[pyclass(module = "ssbvb")]
pub struct Renderer {
    options: RenderOptions,
    /// What was added, each already placed.
    items: Vec<Content>,
    /// The camera of content added from a file (a scene's, a model's default).
    file_camera: Option<ssbvb_voxel::camera::Camera>,
    /// Engine warnings already issued (content warnings are issued when added).
    issued: Vec<String>,
    engine: Option<Engine>,
    last: Option<FrameReport>,
    /// Wall time of the last frame inside the engine: render and readback (ms).
    engine_ms: Option<f64>,
    /// The last frame's counters, counted in a frame of their own when `info` is first
    /// read after it.
    counted: Option<serde_json::Value>,
    /// Content was added or cleared since the engine last took it.
    dirty: bool,
    /// Whether the engine kept its compiled pipelines when it last took new content.
    pipelines_kept: Option<bool>,
}

/// The pipeline file `name` stands for.
fn pipeline_path(name: &str) -> PyResult<PathBuf> {
    let assets = ssbvb_engine::assets::assets_dir();
    if let Some(form) = ssbvb_engine::forms::by_name(name) {
        return Ok(assets.join(form.file));
    }
    let bundled = assets
        .join("pipelines")
        .join(format!("{}.ron", name.replace('-', "_")));
    if bundled.is_file() {
        return Ok(bundled);
    }
    let path = PathBuf::from(name);
    if path.is_file() {
        return Ok(path);
    }
    let forms: Vec<&str> = ssbvb_engine::FORMS.iter().map(|f| f.name).collect();
    Err(PyValueError::new_err(format!(
        "pipeline {name:?} is neither a form ({}), a bundled pipeline (a file of {}) nor a \
         pipeline file",
        forms.join(", "),
        assets.join("pipelines").display()
    )))
}

/// A 4×4 (or 3×4) affine matrix, row-major, acting on column vectors `[x, y, z, 1]`.
fn transform_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<DAffine3> {
    let Some(obj) = obj else {
        return Ok(DAffine3::IDENTITY);
    };
    let rows: Vec<Vec<f64>> = obj
        .extract()
        .map_err(|_| PyTypeError::new_err("transform must be a 4x4 (or 3x4) matrix of numbers"))?;
    let shape_ok = matches!(rows.len(), 3 | 4) && rows.iter().all(|r| r.len() == 4);
    if !shape_ok {
        return Err(PyValueError::new_err(
            "transform must be a 4x4 (or 3x4) matrix of numbers",
        ));
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(PyValueError::new_err("transform must be finite"));
    }
    if rows.len() == 4 && rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(PyValueError::new_err(
            "transform must be affine: its last row [0, 0, 0, 1]",
        ));
    }
    let col = |c: usize| DVec3::new(rows[0][c], rows[1][c], rows[2][c]);
    let m = DAffine3::from_mat3_translation(DMat3::from_cols(col(0), col(1), col(2)), col(3));
    if m.matrix3.determinant() == 0.0 {
        return Err(PyValueError::new_err("transform must be invertible"));
    }
    Ok(m)
}

impl Renderer {
    /// The last frame's counters (counted once per frame, in a frame of their own).
    fn count(&mut self, py: Python<'_>) -> PyResult<serde_json::Value> {
        if let Some(c) = &self.counted {
            return Ok(c.clone());
        }
        let engine = self.engine(py)?;
        let counted = py.detach(|| engine.count()).map_err(to_py)?;
        let json = serde_json::json!({
            "counters": counted.counters,
            "fill_count": counted.fill_count,
        });
        self.counted = Some(json.clone());
        Ok(json)
    }

    /// Everything added, as one content with its default camera.
    fn content(&self) -> Content {
        let mut content = Content::default();
        for item in &self.items {
            content.merge(item.clone(), DAffine3::IDENTITY);
        }
        content.camera = match self.file_camera {
            Some(c) if self.items.len() == 1 => c,
            _ => ssbvb_engine::camera::frame_scene(&content.scene, 40.0),
        };
        if self.items.len() == 1 {
            content.pipeline = self.items[0].pipeline.clone();
            content.gpu_budget_mib = self.items[0].gpu_budget_mib;
        }
        content
    }

    /// The engine for the content added so far: opened (with the GIL released) the first
    /// time, and handed the content again when it changed (the device kept, and the
    /// compiled pipelines where they draw the new scene as they would a fresh one).
    fn engine(&mut self, py: Python<'_>) -> PyResult<&mut Engine> {
        if self.engine.is_none() || self.dirty {
            let content = self.content();
            let options = self.options.clone();
            let engine = match self.engine.take() {
                Some(mut engine) => {
                    let kept = py
                        .detach(|| engine.set_content(content).map(|kept| (engine, kept)))
                        .map_err(to_py)?;
                    self.pipelines_kept = Some(kept.1);
                    kept.0
                }
                None => py
                    .detach(|| Engine::open(content, &options))
                    .map_err(to_py)?,
            };
            self.dirty = false;
            let fresh: Vec<_> = engine
                .warnings()
                .iter()
                .filter(|w| !self.issued.contains(&w.to_string()))
                .cloned()
                .collect();
            self.issued.extend(fresh.iter().map(ToString::to_string));
            warn_all(py, &fresh)?;
            self.engine = Some(engine);
        }
        Ok(self.engine.as_mut().expect("opened above"))
    }

    /// Renders one frame seen by `camera` (`None`: the default) and reads it back.
    fn frame(&mut self, py: Python<'_>, camera: Option<&Camera>) -> PyResult<Vec<u8>> {
        let default = self.engine(py)?.camera().to_owned();
        let engine = self.engine.as_mut().expect("opened above");
        let camera = camera.map_or(default, |c| c.inner);
        let (report, rgba, engine_ms) = py
            .detach(|| {
                let t0 = std::time::Instant::now();
                engine.set_camera(camera);
                let report = engine.render()?;
                let rgba = engine.read_rgba8()?;
                Ok((report, rgba, t0.elapsed().as_secs_f64() * 1e3))
            })
            .map_err(to_py)?;
        engine.set_camera(default);
        self.last = Some(report);
        self.engine_ms = Some(engine_ms);
        self.counted = None;
        Ok(rgba)
    }

    fn image<'py>(&self, py: Python<'py>, rgba: Vec<u8>) -> PyResult<Bound<'py, PyAny>> {
        let (w, h) = self.options.size;
        let array = PyArray1::from_vec(py, rgba).reshape([h as usize, w as usize, 4])?;
        let image = py.import("ssbvb._image")?.getattr("Image")?;
        array.call_method1("view", (image,))
    }

    /// The last frame's per-pixel values read by `read`, as an `(H, W)` array.
    fn per_pixel<'py, T: numpy::Element>(
        &mut self,
        py: Python<'py>,
        read: impl FnOnce(&Engine) -> Result<Vec<T>, ssbvb_engine::EngineError>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if self.last.is_none() {
            return Err(PyValueError::new_err("render a frame first"));
        }
        let engine = self.engine(py)?;
        let values = read(engine).map_err(to_py)?;
        let (w, h) = self.options.size;
        Ok(PyArray1::from_vec(py, values)
            .reshape([h as usize, w as usize])?
            .into_any())
    }
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (size=(640, 480), pipeline=None, backend=None, smooth=true, gpu_budget_mib=None))]
    fn new(
        py: Python<'_>,
        size: (u32, u32),
        pipeline: Option<&str>,
        backend: Option<&str>,
        smooth: bool,
        gpu_budget_mib: Option<u64>,
    ) -> PyResult<Self> {
        let max = ssbvb_engine::values::MAX_EDGE;
        if size.0 == 0 || size.1 == 0 || size.0 > max || size.1 > max {
            return Err(PyValueError::new_err(format!(
                "size must be (width, height) with each side 1..={max}, got {size:?}"
            )));
        }
        let max_budget = ssbvb_engine::budget::MAX_BUDGET_MIB;
        if let Some(mib) = gpu_budget_mib.filter(|&m| m == 0 || m > max_budget) {
            return Err(PyValueError::new_err(format!(
                "gpu_budget_mib must be 1..={max_budget}, got {mib}"
            )));
        }
        if let Some(b) = backend {
            if !matches!(b, "vulkan" | "gl" | "metal" | "dx12") {
                return Err(PyValueError::new_err(format!(
                    "backend must be \"vulkan\", \"gl\", \"metal\" or \"dx12\", got {b:?}"
                )));
            }
            py.import("os")?
                .getattr("environ")?
                .set_item("WGPU_BACKEND", b)?;
        }
        Ok(Self {
            options: RenderOptions {
                size,
                pipeline: pipeline.map(pipeline_path).transpose()?,
                smoothing: smooth,
                gpu_budget_mib,
                ..RenderOptions::default()
            },
            items: Vec::new(),
            file_camera: None,
            issued: Vec::new(),
            engine: None,
            last: None,
            engine_ms: None,
            counted: None,
            dirty: false,
            pipelines_kept: None,
        })
    }

    /// Adds content: `Voxels`, or the path of a model file (voxelized at `level`, default
    /// 8, through the asset cache) or a scene file (`.ron`). `transform` is a 4x4 affine
    /// matrix (row-major, acting on `[x, y, z, 1]`) placing it in the world.
    #[pyo3(signature = (x, transform=None, level=None))]
    fn add(
        &mut self,
        py: Python<'_>,
        x: &Bound<'_, PyAny>,
        transform: Option<&Bound<'_, PyAny>>,
        level: Option<u32>,
    ) -> PyResult<()> {
        let transform = transform_arg(transform)?;
        let mut content = if let Ok(v) = x.cast::<Voxels>() {
            if level.is_some() {
                return Err(PyValueError::new_err(
                    "level applies to a model file; Voxels have theirs",
                ));
            }
            let v = v.get();
            match v.content(DAffine3::IDENTITY) {
                Some(c) => c,
                None => {
                    warn_all(py, v.warnings())?;
                    return Ok(());
                }
            }
        } else {
            let type_name = x.get_type().name()?.to_string();
            let path: PathBuf = x.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "add takes Voxels or the path of a model or scene file, got {type_name}"
                ))
            })?;
            if !path.exists() {
                return Err(PyFileNotFoundError::new_err((
                    2,
                    "No such file or directory",
                    path.display().to_string(),
                )));
            }
            check_level(level)?;
            let scene = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("ron"));
            if scene && level.is_some() {
                return Err(PyValueError::new_err(format!(
                    "{}: level applies to a model file; a scene names each object's level",
                    path.display()
                )));
            }
            let content = py
                .detach(|| Content::open(&path, level, &NoProgress))
                .map_err(to_py)?;
            warn_all(py, &content.warnings)?;
            self.file_camera = Some(content.camera);
            content
        };
        if transform != DAffine3::IDENTITY {
            let mut placed = Content {
                camera: content.camera,
                pipeline: content.pipeline.clone(),
                gpu_budget_mib: content.gpu_budget_mib,
                ..Content::default()
            };
            placed.merge(content, transform);
            content = placed;
        }
        self.issued
            .extend(content.warnings.iter().map(ToString::to_string));
        self.items.push(content);
        self.dirty = true;
        self.last = None;
        self.counted = None;
        Ok(())
    }

    /// Removes all content; the device and the compiled pipelines stay for the next.
    fn clear(&mut self) {
        self.items.clear();
        self.file_camera = None;
        self.dirty = true;
        self.last = None;
        self.counted = None;
    }

    /// Renders the content seen by `camera` (`None`: a scene file's camera, else a view
    /// framing everything added) into an `(H, W, 4)` `uint8` RGBA image, row 0 at the top
    /// (an `ssbvb.Image`: a numpy array that Jupyter shows).
    #[pyo3(signature = (camera=None))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        camera: Option<&Camera>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let rgba = self.frame(py, camera)?;
        self.image(py, rgba)
    }

    /// Renders a frame per camera into an `(N, H, W, 4)` `uint8` array. Ctrl-C stops it
    /// between frames.
    fn render_many<'py>(
        &mut self,
        py: Python<'py>,
        cameras: Vec<Bound<'py, Camera>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (w, h) = self.options.size;
        let mut all = Vec::with_capacity(cameras.len() * (w * h * 4) as usize);
        for camera in &cameras {
            all.extend(self.frame(py, Some(camera.get()))?);
            py.check_signals()?;
        }
        Ok(PyArray1::from_vec(py, all)
            .reshape([cameras.len(), h as usize, w as usize, 4])?
            .into_any())
    }

    /// The last frame's distance from the eye per pixel, `(H, W)` `float32` (`inf` where
    /// no voxel is seen).
    fn depth<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.per_pixel(py, Engine::read_depth)
    }

    /// The last frame's instance per pixel, `(H, W)` `uint32`: instances numbered over the
    /// added content in order, `2**32 - 1` where none.
    fn instance_ids<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.per_pixel(py, Engine::read_instance_ids)
    }

    /// One more frame of the last view, counting its work: march steps, rays, billboards
    /// and the other counters of the form (`counters`), and the billboards the SSBVB was
    /// filled with (`fill_count`), as a dict.
    fn counters<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let counted = self.count(py)?;
        py.import("json")?
            .call_method1("loads", (counted.to_string(),))
    }

    /// The image size, `(width, height)`.
    #[getter]
    fn size(&self) -> (u32, u32) {
        self.options.size
    }

    /// What the renderer chose and measured: the pipeline form and why, the adapter, the
    /// last frame's per-pass times (ms), its wall time, the instances drawn, the wall time
    /// of the last `render` inside the engine (`engine_ms`: the frame and its readback, what
    /// the Python call adds nothing to), whether the engine kept its compiled pipelines
    /// when the content last changed (`pipelines_kept`), its counters (`counted`, counted in one more frame
    /// of the same view when first read), GPU memory per object and the warnings.
    #[getter]
    fn info<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let last = self.last.clone();
        let engine_ms = self.engine_ms;
        let pipelines_kept = self.pipelines_kept;
        let counted = match last {
            Some(_) => Some(self.count(py)?),
            None => None,
        };
        let engine = self.engine(py)?;
        let choice = engine.choice();
        let form = ssbvb_engine::FORMS
            .iter()
            .find(|f| choice.pipeline.ends_with(f.file))
            .map(|f| f.name);
        let json = serde_json::json!({
            "pipeline": choice.pipeline,
            "form": form,
            "chosen_by": choice.by,
            "reason": choice.reason,
            "adapter": engine.adapter(),
            "size": engine.size(),
            "frame": last,
            "engine_ms": engine_ms,
            "pipelines_kept": pipelines_kept,
            "counted": counted,
            "memory": engine.memory(),
            "warnings": engine.warnings().iter().map(ToString::to_string).collect::<Vec<_>>(),
        });
        Ok(py
            .import("json")?
            .call_method1("loads", (json.to_string(),))?
            .cast_into::<PyDict>()?)
    }

    /// Releases the device; the next frame makes it again.
    fn close(&mut self) {
        self.engine = None;
        self.last = None;
        self.counted = None;
    }

    fn __repr__(&self) -> String {
        format!(
            "Renderer(size={:?}, {} item(s) added)",
            self.options.size,
            self.items.len()
        )
    }
}
