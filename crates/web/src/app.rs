//! The page's state once the device exists, and what changes it: drawing a frame and
//! reporting its times, a model taking the scene's place, and the frame loop.

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::Arc;

use ssbvb_gpu::GpuContext;
use ssbvb_graph::ResolvedPipeline;
use ssbvb_passes::PassTiming;
use wasm_bindgen::prelude::*;
use wasm_bindgen_futures::spawn_local;

use crate::WebError;
use crate::dom::{clear_error, document, gpu_done, now_ms, show_error, status, yield_now};
use crate::scene_build::{self, MAX_DROPPED_LEVEL};
use crate::view::View;

/// What the page runs on and has measured (`window.ssbvb.stats()`).
#[derive(Debug, Default, Clone)]
pub struct PageInfo {
    /// The scene's stem, or the dropped model's name.
    pub scene: String,
    /// The pipeline's stem.
    pub pipeline: String,
    /// Why that pipeline.
    pub pipeline_reason: String,
    /// The adapter.
    pub adapter: String,
    /// Whether the adapter is a CPU (a browser's fallback adapter): the key of `ssbvb
    /// render --json`.
    pub adapter_is_software: bool,
    /// Render size.
    pub size: (u32, u32),
    /// Time spent loading and voxelizing models, ms.
    pub prepare_ms: f64,
    /// From the page's start to the first frame done on the GPU, ms.
    pub first_frame_ms: f64,
    /// The last frame, from its submission to the GPU's done, ms.
    pub frame_ms: f64,
    /// Per-pass GPU times of the last frame read (empty without timestamps).
    pub passes: Vec<PassTiming>,
    /// What the models' loads could not do (a missing material or texture), each naming
    /// its file.
    pub warnings: Vec<String>,
}

/// The page's state once the device exists.
pub struct App {
    /// The device.
    pub ctx: GpuContext,
    /// The scene, renderer and camera.
    pub view: RefCell<View>,
    /// Reports.
    pub info: RefCell<PageInfo>,
    /// The resolved pipeline (a dropped model is drawn with it too).
    pub pipeline: ResolvedPipeline,
    /// Whether frames follow the canvas's size (no `size` in the URL).
    pub follows_canvas: bool,
    /// Whether a frame is being drawn and waited for (the frame loop skips a tick then).
    pub drawing: Cell<bool>,
}

/// Draws a frame, waits for the GPU, checks what WebGPU reported, reads the per-pass
/// times and shows them.
pub async fn draw_and_report(app: &Rc<App>) -> Result<(), WebError> {
    app.drawing.set(true);
    let t = now_ms();
    // A readback in flight holds the view for a moment.
    let drawn = loop {
        match app.view.try_borrow_mut() {
            Ok(mut view) => break view.draw(&app.ctx),
            Err(_) => yield_now().await,
        }
    };
    if let Err(e) = drawn {
        app.drawing.set(false);
        return Err(e);
    }
    gpu_done(&app.ctx).await;
    let frame_ms = now_ms() - t;
    // WebGPU's uncaptured errors arrive as events: let them.
    yield_now().await;
    let errors = app.ctx.take_uncaptured_errors();
    if !errors.is_empty() {
        app.drawing.set(false);
        return Err(WebError::Gpu(format!(
            "WebGPU reported: {}",
            errors.join("; ")
        )));
    }
    let readout = app.view.borrow().renderer.pass_times_readout();
    let passes = match readout {
        Some(r) => r.read(&app.ctx).await,
        None => Ok(Vec::new()),
    };
    app.drawing.set(false);
    let passes = passes.map_err(|e| WebError::Gpu(e.to_string()))?;
    {
        let mut info = app.info.borrow_mut();
        info.frame_ms = frame_ms;
        info.passes = passes;
    }
    show_stats(app);
    Ok(())
}

fn show_stats(app: &App) {
    let info = app.info.borrow();
    let mut text = format!(
        "{} · {} ({}) · {}x{} · frame {:.1} ms (submit to done) · {}",
        info.scene,
        info.pipeline,
        info.pipeline_reason,
        info.size.0,
        info.size.1,
        info.frame_ms,
        info.adapter
    );
    let timed: Vec<String> = info
        .passes
        .iter()
        .filter_map(|p| p.gpu_ms.map(|ms| format!("{} {ms:.2}", p.name)))
        .collect();
    if !timed.is_empty() {
        text.push_str(&format!("\nGPU ms per pass: {}", timed.join(", ")));
    }
    for w in &info.warnings {
        text.push_str(&format!("\nwarning: {w}"));
    }
    if let Some(e) = document().get_element_by_id("stats") {
        e.set_text_content(Some(&text));
    }
}

/// Prepares a model from its bytes at `level` and draws it in place of the scene.
pub async fn load_model(
    app: &Rc<App>,
    name: &str,
    bytes: Vec<u8>,
    level: u32,
) -> Result<(), WebError> {
    if !(1..=MAX_DROPPED_LEVEL).contains(&level) {
        return Err(WebError::Model {
            name: name.to_string(),
            message: format!("level {level}: the page voxelizes at levels 1..={MAX_DROPPED_LEVEL}"),
        });
    }
    clear_error();
    let t = now_ms();
    let asset = Arc::new(crate::worker_client::prepare(name, bytes, level).await?);
    let prepare_ms = now_ms() - t;
    let (scene, camera) = scene_build::model_scene(asset);
    // Wait for a frame or readback in flight: it holds the view.
    while app.drawing.get() || app.view.try_borrow_mut().is_err() {
        yield_now().await;
    }
    {
        let mut view = app.view.borrow_mut();
        let size = view.renderer.screen;
        let presenter = view.presenter.take();
        let opened = View::open(&app.ctx, scene, camera, app.pipeline.clone(), size, None);
        match opened {
            Ok(mut new) => {
                new.presenter = presenter;
                *view = new;
            }
            Err(e) => {
                view.presenter = presenter;
                return Err(e);
            }
        }
    }
    {
        let mut info = app.info.borrow_mut();
        info.scene = name.to_string();
        info.prepare_ms = prepare_ms;
        info.warnings = crate::worker_client::take_warnings();
    }
    draw_and_report(app).await?;
    status("");
    document().set_title(&format!("ssbvb ready: {name} at level {level}"));
    Ok(())
}

/// Draws when something changed (the camera, the canvas's size), once per animation
/// frame.
pub fn request_frames(app: Rc<App>) {
    type Tick = Rc<std::cell::RefCell<Option<Closure<dyn FnMut()>>>>;
    let tick: Tick = Default::default();
    let again = tick.clone();
    *tick.borrow_mut() = Some(Closure::new(move || {
        follow_canvas(&app);
        if app.view.borrow().dirty && !app.drawing.get() {
            let a = app.clone();
            spawn_local(async move {
                if let Err(e) = draw_and_report(&a).await {
                    show_error(&e.to_string());
                }
            });
        }
        if let (Some(w), Some(f)) = (web_sys::window(), again.borrow().as_ref()) {
            let _ = w.request_animation_frame(f.as_ref().unchecked_ref());
        }
    }));
    if let (Some(w), Some(f)) = (web_sys::window(), tick.borrow().as_ref()) {
        let _ = w.request_animation_frame(f.as_ref().unchecked_ref());
    }
}

/// Renders at the canvas's new size after the window changed, where frames follow it.
pub fn follow_canvas(app: &App) {
    if !app.follows_canvas || app.drawing.get() {
        return;
    }
    let canvas = crate::dom::canvas();
    let size = crate::dom::canvas_size(&canvas);
    let Ok(mut view) = app.view.try_borrow_mut() else {
        return;
    };
    if view.renderer.screen == size {
        return;
    }
    canvas.set_width(size.0);
    canvas.set_height(size.1);
    match view.resize(&app.ctx, size) {
        Ok(()) => app.info.borrow_mut().size = size,
        Err(e) => show_error(&e.to_string()),
    }
}
