//! Opening the viewer's GPU side: the device that presents to the window, the scene on it,
//! the renderer and the overlay's renderer ([`GpuParts`]), made from what stays on the CPU
//! so that a lost device can be replaced (`super::recover`).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use ssbvb_gpu::scene::GpuScene;
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::Renderer;
use winit::event_loop::{ActiveEventLoop, OwnedDisplayHandle};
use winit::window::Window;

use super::super::blit::Blit;
use super::super::camera_control::CameraRig;
use super::super::input::CameraInput;
use super::super::overlay::OverlayState;
use super::super::stats::Stats;
use super::super::surface::WindowGpu;
use super::state::{Loaded, Options, Viewer};
use ssbvb_engine::faults::Recoveries;

/// Everything on the device.
pub(super) struct GpuParts {
    gpu: WindowGpu,
    blit: Blit,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    scene: GpuScene,
    renderer: Renderer,
    animator: Option<ssbvb_gpu_build::animated::Animator>,
}

impl GpuParts {
    /// A device for `window` that runs `pipeline`, with `loaded`'s scene uploaded (under
    /// its budget, with room for its animated and brushed objects) and the renderer built.
    /// With `refuse`, the device refuses its first large allocation
    /// (`--inject-fault oom@FRAME`).
    pub(super) fn open(
        window: &Arc<Window>,
        display: &OwnedDisplayHandle,
        loaded: &Loaded,
        pipeline: ResolvedPipeline,
        refuse: bool,
    ) -> Result<Self> {
        let requirements = crate::adapter_cmd::requirements_of(&[&pipeline]);
        let gpu = WindowGpu::new(window.clone(), display.clone(), &requirements)?;
        let ctx = &gpu.ctx;
        if refuse {
            ctx.refuse_allocation(ssbvb_engine::faults::INJECTED_OOM_MIN_BYTES);
        }
        let blit = Blit::new(ctx, gpu.config.format)?;
        let mut rooms = ssbvb_engine::animation::rooms(&loaded.animated);
        rooms.extend(loaded.brush.iter().flat_map(|b| b.rooms()));
        let scene = loaded.scene.clone();
        let scene = match &loaded.streaming {
            Some(o) => ssbvb_engine::upload::upload_scene(
                ctx,
                scene,
                ssbvb_engine::upload::Residency::Streamed(o),
            ),
            None if !rooms.is_empty() => ssbvb_engine::upload::upload_scene(
                ctx,
                scene,
                ssbvb_engine::upload::Residency::Dynamic(&rooms),
            ),
            None => ssbvb_engine::upload::upload_scene(
                ctx,
                scene,
                ssbvb_engine::upload::Residency::Whole,
            ),
        }
        .context("uploading the scene")?;
        let animator = if loaded.animated.is_empty() {
            None
        } else {
            Some(ssbvb_gpu_build::animated::Animator::new(ctx)?)
        };
        let renderer = ssbvb_engine::upload::renderer(ctx, &scene, pipeline, gpu.size())
            .with_context(|| format!("building {}", loaded.watcher.path().display()))?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            window.as_ref(),
            Some(window.scale_factor() as f32),
            window.theme(),
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&ctx.device, gpu.config.format, Default::default());
        Ok(Self {
            blit,
            egui_ctx,
            egui_state,
            egui_renderer,
            scene,
            renderer,
            animator,
            gpu,
        })
    }

    /// [`GpuParts::open`], and while the driver refuses an allocation under a budget, again
    /// under half the budget (kept in `loaded`); the lines say what was lowered. The
    /// injected refusal is of the first device's allocation only.
    pub(super) fn open_within_memory(
        window: &Arc<Window>,
        display: &OwnedDisplayHandle,
        loaded: &mut Loaded,
        pipeline: ResolvedPipeline,
        refuse: bool,
    ) -> Result<(Self, Vec<String>)> {
        let mut lowered = Vec::new();
        let mut refuse = refuse;
        loop {
            let opened = Self::open(window, display, loaded, pipeline.clone(), refuse);
            refuse = false;
            let e = match opened {
                Ok(p) => {
                    p.gpu.ctx.clear_refusal();
                    return Ok((p, lowered));
                }
                Err(e) => e,
            };
            match (
                ssbvb_engine::faults::out_of_memory(e.as_ref()),
                &mut loaded.streaming,
            ) {
                (Some((resource, _)), _) if !ssbvb_engine::faults::is_scene_resource(&resource) => {
                    return Err(e.context(ssbvb_engine::faults::frame_out_of_memory_hint()));
                }
                (Some((resource, bytes)), Some(o)) if o.budget_bytes > 1 << 20 => {
                    let mib = o.budget_bytes >> 20;
                    o.budget_bytes = (mib / 2) << 20;
                    lowered.push(format!(
                        "the driver refused {} for {resource}; GPU budget lowered from {mib} \
                         to {} MiB",
                        ssbvb_gpu::alloc::mib_text(bytes),
                        mib / 2
                    ));
                }
                _ => return Err(explain_out_of_memory(e, loaded.streaming.is_some())),
            }
        }
    }
}

/// `e` with the flag that would help when it is a refused allocation without a budget.
fn explain_out_of_memory(e: anyhow::Error, budgeted: bool) -> anyhow::Error {
    match (ssbvb_engine::faults::out_of_memory(e.as_ref()), budgeted) {
        (None, _) => e,
        (Some(_), false) => e.context(format!(
            "the scene does not fit the GPU's memory; {}",
            ssbvb_engine::faults::out_of_memory_hint()
        )),
        (Some(_), true) => {
            e.context("the scene does not fit the GPU's memory even under a 1 MiB budget")
        }
    }
}

impl Viewer {
    /// Opens the window and its GPU side.
    pub(super) fn new(
        event_loop: &ActiveEventLoop,
        options: &Options,
        loaded: Loaded,
    ) -> Result<Self> {
        let attributes = Window::default_attributes()
            .with_title(options.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(
                options.size.0,
                options.size.1,
            ));
        let window = Arc::new(event_loop.create_window(attributes).map_err(|e| {
            anyhow!(super::super::display::no_display_message(&format!(
                "cannot create a window: {e}"
            )))
        })?);
        let display = event_loop.owned_display_handle();
        let refuse = ssbvb_engine::faults::runs_out_of_memory_at(&options.faults, 0);
        let pipeline = loaded.watcher.current().clone();
        let mut loaded = loaded;
        let (parts, lowered) =
            GpuParts::open_within_memory(&window, &display, &mut loaded, pipeline, refuse)?;
        let mut v = Self::assemble(window, display, parts, loaded);
        // `--restore`: the journal replays before the first frame.
        v.restore_journal(None);
        if !lowered.is_empty() {
            let notice = format!("out of GPU memory at the start: {}", lowered.join("; "));
            eprintln!("view: {notice}");
            v.notice = Some(notice);
        }
        Ok(v)
    }

    /// The viewer of `parts` on `window`, at the start of its run.
    pub(super) fn assemble(
        window: Arc<Window>,
        display: OwnedDisplayHandle,
        parts: GpuParts,
        loaded: Loaded,
    ) -> Self {
        let GpuParts {
            gpu,
            blit,
            egui_ctx,
            egui_state,
            egui_renderer,
            scene,
            renderer,
            animator,
        } = parts;
        let stats = Stats::new(gpu.ctx.report());
        Self {
            window,
            display,
            blit,
            egui_ctx,
            egui_state,
            egui_renderer,
            scene,
            renderer,
            animated: loaded.animated,
            animator,
            brush: loaded.brush,
            started: Instant::now(),
            watcher: loaded.watcher,
            streaming: loaded.streaming,
            knob_edits: BTreeMap::new(),
            rig: CameraRig::new(loaded.camera),
            initial_camera: loaded.camera,
            input: CameraInput::default(),
            cursor: None,
            stats,
            overlay: OverlayState::default(),
            error: None,
            status: None,
            notice: None,
            frame: 0,
            sample_base: 0,
            last_frame: Instant::now(),
            last_poll: Instant::now(),
            needs_rebuild: false,
            screenshot_next: None,
            screenshot_written: false,
            reloads: (0, 0),
            memory_samples: Vec::new(),
            recoveries: Recoveries::default(),
            faults_injected_at: None,
            gpu,
        }
    }
}
