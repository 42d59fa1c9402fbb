//! [`Engine`]: content on a device with the pipeline chosen for it, rendered frame by frame
//! and read back. The one object a program needs to draw ssbvb content.

use std::path::{Path, PathBuf};

use ssbvb_gpu::scene::ObjectMemory;
use ssbvb_gpu::{DeviceLimits, wgpu};
use ssbvb_graph::{PassKind, ResolvedPipeline};
use ssbvb_passes::PassTiming;
use ssbvb_voxel::camera::Camera;

use crate::choice::{choose, resolve_pipeline};
use crate::forms::PipelineChoice;
use crate::session::{GpuSession, HostDevice, SessionSource};
use crate::{Content, EngineError, Warning};

/// How an [`Engine`] renders.
#[derive(Clone)]
pub struct RenderOptions {
    /// Image size (width, height), each side 1 to 16384.
    pub size: (u32, u32),
    /// A pipeline file (`None`: the content's, else the form chosen for the adapter).
    pub pipeline: Option<PathBuf>,
    /// The limits an own device is made with.
    pub limits: DeviceLimits,
    /// GPU budget (MiB) for the voxel scene (`None`: the content's, else none): finer
    /// levels stream in as rays need them.
    pub gpu_budget_mib: Option<u64>,
    /// Most frames rendered per [`Engine::render`] until no page is missing.
    pub max_frames: usize,
    /// Seconds at which animated objects are drawn.
    pub time: f64,
    /// Rays find their instances in their screen tile's list (`false`: the hierarchy).
    pub instance_lists: bool,
    /// A host's device to draw with (`None`: the engine makes its own).
    pub host: Option<HostDevice>,
    /// The paper's Gaussian smoothing of normals (`false`: each voxel shaded by its own
    /// normal, the exact cubes' look; the smoothing pass is kept with a zero offset, so
    /// every form and file takes it).
    pub smoothing: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            size: (640, 480),
            pipeline: None,
            limits: DeviceLimits::Adapter,
            gpu_budget_mib: None,
            max_frames: 64,
            time: 0.0,
            instance_lists: true,
            host: None,
            smoothing: true,
        }
    }
}

/// What one [`Engine::render`] did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FrameReport {
    /// Per-pass times of the frame (GPU timestamps; on a software adapter also each pass's
    /// wall time, submitted and waited alone).
    pub passes: Vec<PassTiming>,
    /// Wall time of the frame, ms.
    pub frame_wall_ms: f64,
    /// Instances drawn after culling.
    pub visible_instances: usize,
    /// Frames rendered before it until no page was missing (0 without a budget).
    pub frames_to_converge: usize,
    /// Whether no page was missing within [`RenderOptions::max_frames`].
    pub converged: bool,
}

/// Refuses an image size with a side of 0 or above [`crate::values::MAX_EDGE`] before any
/// GPU work.
fn check_size((w, h): (u32, u32)) -> Result<(), EngineError> {
    let max = crate::values::MAX_EDGE;
    if w == 0 || h == 0 || w > max || h > max {
        return Err(EngineError::Invalid(format!(
            "the image size must be 1..={max} per side, got {w}x{h}"
        )));
    }
    Ok(())
}

/// `pipeline` with its smoothing passes' offset set to 0 when `off` (each pixel samples
/// only its own normal).
fn without_smoothing(pipeline: ResolvedPipeline, off: bool) -> ResolvedPipeline {
    if !off {
        return pipeline;
    }
    let mut p = pipeline;
    let names: Vec<(String, PassKind)> = p
        .passes
        .iter()
        .filter_map(|s| {
            let mut kind = s.kind.clone();
            match &mut kind {
                PassKind::Smooth(k) => k.max_i = 0.0,
                PassKind::SmoothCompute(k) => k.max_i = 0.0,
                _ => return None,
            }
            Some((s.name.clone(), kind))
        })
        .collect();
    for (name, kind) in names {
        if let Some(edited) = p.with_pass_kind(&name, &kind) {
            p = edited;
        }
    }
    p
}

/// Content on a device, ready to render.
pub struct Engine {
    source: SessionSource,
    gpu: GpuSession,
    choice: PipelineChoice,
    camera: Camera,
    warnings: Vec<Warning>,
    notes: Vec<String>,
    max_frames: usize,
    /// What it was opened with (a content change that cannot keep the device opens anew).
    options: RenderOptions,
    /// The pipeline file the content named.
    content_pipeline: Option<PathBuf>,
}

impl Engine {
    /// Chooses the pipeline (the options', the content's, else the adapter's form), makes
    /// or takes the device and uploads the content. A side of 0 or above 16384 is refused.
    pub fn open(content: Content, options: &RenderOptions) -> Result<Self, EngineError> {
        check_size(options.size)?;
        let choice = match &options.host {
            Some(host) => crate::choice::choose_for_host(
                options.pipeline.clone(),
                content.pipeline.clone(),
                host,
            )?,
            None => choose(
                options.pipeline.clone(),
                content.pipeline.clone(),
                options.limits,
            )?,
        };
        let mut warnings = choice.warnings.clone();
        warnings.extend(content.warnings.iter().cloned());
        let content_pipeline = content.pipeline.clone();
        let mut source = SessionSource {
            pipeline: without_smoothing(resolve_pipeline(&choice.path())?, !options.smoothing),
            scene: content.scene,
            budget: options.gpu_budget_mib.or(content.gpu_budget_mib),
            page_sources: content.page_sources,
            animated: content.animated,
            time: options.time,
            size: options.size,
            time_submissions: false,
            instance_lists: options.instance_lists,
            counting: false,
            limits: options.limits,
            host: options.host.clone(),
        };
        let mut notes = content.notes;
        let opened = source.open_refusing(&mut notes, false)?;
        warnings.extend(
            opened
                .warnings
                .iter()
                .map(|w| Warning::new("GPU memory", w)),
        );
        Ok(Self {
            source,
            gpu: opened.session,
            choice,
            camera: content.camera,
            warnings,
            notes,
            max_frames: options.max_frames.max(1),
            options: options.clone(),
            content_pipeline,
        })
    }

    /// Draws `content` from now on, on the same device: its scene is uploaded in place of
    /// the current one, the compiled pipelines kept when they draw it as pipelines made for
    /// it would ([`ssbvb_passes::Renderer::draws_as_made_for`]: the SSBVB forms for scenes
    /// taking the same bindings), else made again. Content naming another pipeline file,
    /// with animated objects or another budget, opens anew as [`Engine::open`] would. The
    /// camera becomes the content's; the warnings are the choice's and the content's.
    /// Returns whether the compiled pipelines were kept.
    pub fn set_content(&mut self, content: Content) -> Result<bool, EngineError> {
        let budget = self.options.gpu_budget_mib.or(content.gpu_budget_mib);
        let same_pipeline =
            self.options.pipeline.is_some() || content.pipeline == self.content_pipeline;
        if !same_pipeline || !content.animated.is_empty() || budget != self.source.budget {
            *self = Engine::open(content, &self.options.clone())?;
            return Ok(false);
        }
        let mut notes = content.notes;
        self.source.scene = content.scene;
        self.source.page_sources = content.page_sources;
        self.source.animated = Vec::new();
        let kept = self.source.replace_scene(&mut self.gpu, &mut notes)?;
        self.camera = content.camera;
        self.notes = notes;
        self.warnings = self.choice.warnings.clone();
        self.warnings.extend(content.warnings);
        Ok(kept)
    }

    /// The camera the next frame is seen by.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Sets the camera of the next frame ([`crate::camera`] has orbits and framing).
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
    }

    /// Renders a frame: under a budget, frames until no page is missing, then the frame
    /// with its pass times. A device lost on the way is made again once and the frame
    /// drawn again.
    pub fn render(&mut self) -> Result<FrameReport, EngineError> {
        match self.render_once() {
            Err(e) if self.gpu.ctx.lost().is_some() && self.source.host.is_none() => {
                let why = self.gpu.ctx.lost().unwrap_or_default();
                let opened = self
                    .source
                    .reopen(&self.camera, self.max_frames, false)
                    .map_err(|e2| e2.context(format!("recreating the lost device ({why}): {e}")))?;
                self.gpu = opened.session;
                self.warnings.push(Warning::new(
                    "GPU device",
                    format!("lost and recreated: {why}"),
                ));
                let lowered = opened.warnings.iter();
                self.warnings
                    .extend(lowered.map(|w| Warning::new("GPU memory", w)));
                self.render_once()
            }
            other => other,
        }
    }

    fn render_once(&mut self) -> Result<FrameReport, EngineError> {
        let s = &mut self.gpu;
        // Under a budget, frames until no page is missing; without one, the timed frame is
        // the first.
        let (frames, converged) = if s.scene.streaming_stats().is_some() {
            crate::budget::converge(
                &s.ctx,
                &mut s.renderer,
                &mut s.scene,
                &self.camera,
                self.max_frames,
            )?
        } else {
            (0, true)
        };
        let stats =
            crate::timing::profiled_frame(&s.ctx, &mut s.renderer, &mut s.scene, &self.camera)?;
        Ok(FrameReport {
            passes: stats.passes,
            frame_wall_ms: stats.frame_wall_ms,
            visible_instances: stats.visible_instances,
            frames_to_converge: frames,
            converged,
        })
    }

    /// Renders a frame for each camera, and reads each back as RGBA8.
    pub fn render_many(&mut self, cameras: &[Camera]) -> Result<Vec<Vec<u8>>, EngineError> {
        let mut out = Vec::with_capacity(cameras.len());
        for c in cameras {
            self.camera = *c;
            self.render()?;
            out.push(self.read_rgba8()?);
        }
        Ok(out)
    }

    /// The last frame as RGBA8, row-major, row 0 at the top (`width · height · 4` bytes).
    pub fn read_rgba8(&self) -> Result<Vec<u8>, EngineError> {
        let s = &self.gpu;
        let out = s
            .ctx
            .read_texture(&s.renderer.output().texture, wgpu::TextureAspect::All)?;
        Ok(out.to_rgba8()?)
    }

    /// Per pixel of the last frame, the distance from the eye to what it shows (`inf`
    /// where it shows no voxel); needs a G-buffer pipeline.
    pub fn read_depth(&self) -> Result<Vec<f32>, EngineError> {
        let s = &self.gpu;
        let hits = ssbvb_passes::measure::gbuffer_hits(&s.ctx, &s.renderer)?;
        Ok(hits
            .iter()
            .map(|h| h.as_ref().map_or(f32::INFINITY, |h| h.t as f32))
            .collect())
    }

    /// Per pixel of the last frame, the scene instance it shows (instances numbered over
    /// the objects in order; `u32::MAX` where none); needs a pipeline with an SSBVB.
    pub fn read_instance_ids(&self) -> Result<Vec<u32>, EngineError> {
        let s = &self.gpu;
        let hits = ssbvb_passes::measure::gbuffer_hits_in(&s.ctx, &s.renderer, &s.scene)?;
        Ok(hits
            .iter()
            .map(|h| h.as_ref().map_or(u32::MAX, |h| h.instance))
            .collect())
    }

    /// Writes the last frame as a PNG (to a temporary file, then renamed).
    pub fn save_png(&self, path: &Path) -> Result<(), EngineError> {
        let (w, h) = self.size();
        let rgba = self.read_rgba8()?;
        Ok(ssbvb_gpu::readback::write_png_rgba8(path, w, h, &rgba)?)
    }

    /// Changes the image size: the frame's targets are made again, the scene stays. A
    /// host's target texture has its own size: drawing into one, make a new engine.
    pub fn resize(&mut self, size: (u32, u32)) -> Result<(), EngineError> {
        if self
            .source
            .host
            .as_ref()
            .is_some_and(|h| h.target.is_some())
        {
            return Err(EngineError::Invalid(
                "the frame is drawn into the host's texture, whose size is the host's".into(),
            ));
        }
        check_size(size)?;
        let s = &mut self.gpu;
        let renderer =
            crate::upload::renderer(&s.ctx, &s.scene, self.source.pipeline.clone(), size)?;
        s.renderer = renderer;
        self.source.size = size;
        Ok(())
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        self.source.size
    }

    /// The pipeline used, who chose it and why.
    pub fn choice(&self) -> &PipelineChoice {
        &self.choice
    }

    /// What the content and the device said (missing textures, a budget lowered, …).
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// One line per asset about the cache.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The adapter (`name [backend, type]`).
    pub fn adapter(&self) -> String {
        self.gpu.ctx.report().to_string()
    }

    /// Draws the camera's view once more counting its work (march steps, rays, boxes
    /// tested, the SSBVB fill), untimed: the counters of the frame [`Engine::render`] drew
    /// and timed without them ([`crate::timing`]). The image stays that frame's.
    pub fn count(&mut self) -> Result<crate::timing::Counted, EngineError> {
        let s = &mut self.gpu;
        crate::timing::counted_frame(&s.ctx, &mut s.renderer, &mut s.scene, &self.camera)
    }

    /// GPU memory per voxel object.
    pub fn memory(&self) -> &[ObjectMemory] {
        &self.gpu.scene.memory
    }

    /// The device, scene and renderer, for what this API does not cover.
    pub fn gpu(&mut self) -> &mut GpuSession {
        &mut self.gpu
    }
}

/// Natively an engine can move between threads (a host renders on a worker, Python
/// renders with the GIL released).
#[cfg(not(target_arch = "wasm32"))]
const _: fn() = || {
    fn send<T: Send>() {}
    send::<Engine>();
};
