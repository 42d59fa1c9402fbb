//! The window and its frame loop (winit's `ApplicationHandler`): creates the window and
//! device on `resumed`, routes events to egui and the camera, and per frame: hot reload,
//! render, overlay, blit + egui onto the surface, screenshots, and the `--frames` limit.

use std::time::{Duration, Instant};

use anyhow::Result;
use ssbvb_graph::{PipelineWatcher, ReloadOutcome, ResolvedPipeline};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::WindowId;

use super::brush_history::Step;
use super::camera_control::CameraRig;
use super::capture;
use super::overlay::{self, Action, ObjectLod, OverlayView};
use super::stats::Stats;

mod editing;
mod open;
mod present;
mod recover;
mod state;

use state::{Fault, Flow, Viewer};
pub use state::{Loaded, Options};

/// How often the pipeline file is checked for changes.
const RELOAD_POLL: Duration = Duration::from_millis(300);

/// The application: waiting for `resumed`, then running, or failed.
pub struct App {
    options: Options,
    loaded: Option<Loaded>,
    viewer: Option<Viewer>,
    error: Option<anyhow::Error>,
}

impl App {
    /// An app that opens its window when the event loop starts.
    pub fn new(options: Options, loaded: Loaded) -> Self {
        Self {
            options,
            loaded: Some(loaded),
            viewer: None,
            error: None,
        }
    }

    /// The error that ended the event loop, if any.
    pub fn into_result(self) -> Result<()> {
        match self.error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        // Release GPU objects while the window (and its display connection) still exists.
        self.viewer = None;
        event_loop.exit();
    }
}

/// Ends the viewer's session (saves on exit, the journal kept or removed) and prints the
/// last camera as `render` flags, so that a view found here can be drawn again.
fn viewer_end(viewer: &mut Option<Viewer>, options: &Options) -> Result<()> {
    match viewer {
        Some(v) => {
            eprintln!(
                "last camera: {}",
                super::script::render_flags(&v.rig.camera())
            );
            v.end_session(options)
        }
        None => Ok(()),
    }
}

/// With `--frames` (a scripted run, whose screenshot must not depend on how fast frames
/// come), the overlay's animations are off: egui times them by the wall clock, and a
/// window fading in after a device recovery drew differently from run to run.
fn still_overlay(v: &Viewer, options: &Options) {
    if options.frames.is_some() {
        v.egui_ctx.all_styles_mut(|s| s.animation_time = 0.0);
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(loaded) = self.loaded.take() else {
            return;
        };
        match Viewer::new(event_loop, &self.options, loaded) {
            Ok(v) => {
                still_overlay(&v, &self.options);
                v.window.request_redraw();
                self.viewer = Some(v);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        let outcome = match viewer.event(&self.options, &event) {
            // What fails on a lost device is the loss.
            Err(e) => match viewer.gpu.ctx.lost() {
                Some(reason) => Ok(Flow::Recover(Fault::Lost(reason))),
                None => Err(e),
            },
            ok => ok,
        };
        match outcome {
            Ok(Flow::Continue) => {}
            Ok(Flow::Recover(fault)) => {
                let Some(viewer) = self.viewer.take() else {
                    return;
                };
                match viewer.recovered(fault) {
                    Ok(v) => {
                        still_overlay(&v, &self.options);
                        v.window.request_redraw();
                        self.viewer = Some(v);
                    }
                    Err(e) => self.fail(event_loop, e),
                }
            }
            Ok(Flow::Exit) => {
                let ended = viewer_end(&mut self.viewer, &self.options);
                self.viewer = None;
                if let Err(e) = ended {
                    self.fail(event_loop, e);
                }
                event_loop.exit();
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        // Redraw continuously: the overlay's timings are live.
        if let Some(v) = &self.viewer {
            v.window.request_redraw();
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.viewer = None;
    }
}

impl Viewer {
    fn event(&mut self, options: &Options, event: &WindowEvent) -> Result<Flow> {
        let _ = self.egui_state.on_window_event(&self.window, event);
        if let WindowEvent::CursorMoved { position, .. } = event {
            self.cursor = Some((position.x, position.y));
        }
        // Only typing goes to egui exclusively: a clicked button also holds egui's focus,
        // and that must not take WASD and Tab away from the camera.
        let egui_wants_keys = self.egui_ctx.text_edit_focused();
        let over_overlay = self.over_overlay();
        match event {
            WindowEvent::CloseRequested => return self.quit(options),
            WindowEvent::Resized(_) => self.sync_size()?,
            WindowEvent::RedrawRequested => return self.frame(options),
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.input.key(code, event.state, egui_wants_keys);
                    let pressed =
                        event.state == ElementState::Pressed && !event.repeat && !egui_wants_keys;
                    match code {
                        KeyCode::Tab if pressed => self.rig.toggle(),
                        KeyCode::F12 if pressed => {
                            self.screenshot_next = Some(capture::default_path());
                        }
                        KeyCode::Escape if pressed => return self.quit(options),
                        KeyCode::KeyZ if pressed && self.input.ctrl_held() => {
                            self.brush_step(if self.input.shift_held() {
                                Step::Redo
                            } else {
                                Step::Undo
                            });
                        }
                        KeyCode::KeyY if pressed && self.input.ctrl_held() => {
                            self.brush_step(Step::Redo);
                        }
                        KeyCode::KeyS if pressed && self.input.ctrl_held() => self.save(None),
                        _ => {}
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let paint = *button == MouseButton::Left
                    && *state == ElementState::Pressed
                    && !over_overlay
                    && self.input.ctrl_held()
                    && self.brush.is_some();
                match self.cursor {
                    // A brush click does not start an orbit drag.
                    Some((x, y)) if paint => self.paint(x as u32, y as u32),
                    _ => self.input.button(*button, *state, over_overlay),
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let h = f64::from(self.gpu.size().1);
                self.input
                    .cursor_moved(position.x, position.y, &mut self.rig, h);
            }
            WindowEvent::CursorLeft { .. } => {
                self.cursor = None;
                self.input.cursor_left();
            }
            WindowEvent::MouseWheel { delta, .. } if !over_overlay => {
                self.input.wheel(*delta, &mut self.rig);
            }
            _ => {}
        }
        Ok(Flow::Continue)
    }

    /// The user closes the viewer. Without --frames, --screenshot is the frame on screen
    /// at that moment: draw it once more into the screenshot.
    fn quit(&mut self, options: &Options) -> Result<Flow> {
        if let (Some(path), false) = (&options.screenshot, self.screenshot_written) {
            self.screenshot_next = Some(path.clone());
            // A fault found now is recovered (the window stays; the screenshot is drawn
            // at the next close) rather than exiting without it.
            if let Flow::Recover(fault) = self.frame(options)? {
                return Ok(Flow::Recover(fault));
            }
        }
        Ok(Flow::Exit)
    }

    /// Whether the cursor is on the overlay (or egui is dragging something). Tested
    /// against the overlay's areas from the last frame with the cursor's position now:
    /// egui's own pointer state only moves when a frame runs, and on a slow adapter a
    /// press can arrive before the frame that saw the cursor leave the overlay.
    fn over_overlay(&self) -> bool {
        if self.egui_ctx.egui_is_using_pointer() {
            return true;
        }
        let Some((x, y)) = self.cursor else {
            return false;
        };
        let ppp = f64::from(self.egui_ctx.pixels_per_point());
        let pos = egui::pos2((x / ppp) as f32, (y / ppp) as f32);
        self.egui_ctx
            .layer_id_at(pos)
            .is_some_and(|l| l.order != egui::Order::Background)
    }

    /// Follows the window's size: reconfigures the surface and, when the size changed,
    /// has the renderer rebuilt at the next frame (not per event: a drag-resize sends
    /// many).
    fn sync_size(&mut self) -> Result<()> {
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(());
        }
        self.gpu.resize(size.width, size.height)?;
        if self.renderer.screen != self.gpu.size() {
            self.needs_rebuild = true;
        }
        Ok(())
    }

    /// The file's pipeline with the knob edits applied.
    fn effective_pipeline(&self) -> ResolvedPipeline {
        let mut p = self.watcher.current().clone();
        for (pass, kind) in &self.knob_edits {
            if let Some(edited) = p.with_pass_kind(pass, kind) {
                p = edited;
            }
        }
        p
    }

    /// Rebuilds the renderer (new pipeline, knobs or size). On failure the old renderer
    /// keeps drawing and the error is shown.
    fn rebuild(&mut self) -> bool {
        self.needs_rebuild = false;
        let pipeline = self.effective_pipeline();
        match ssbvb_engine::upload::renderer(&self.gpu.ctx, &self.scene, pipeline, self.gpu.size())
        {
            Ok(r) => {
                self.renderer = r;
                self.error = None;
                self.stats.reset_pipeline();
                self.sample_base = self.frame;
                true
            }
            Err(e) => {
                self.error = Some(format!("cannot build the pipeline: {e}"));
                false
            }
        }
    }

    fn poll_reload(&mut self) {
        if self.last_poll.elapsed() < RELOAD_POLL {
            return;
        }
        self.last_poll = Instant::now();
        match self.watcher.poll() {
            ReloadOutcome::Unchanged => {}
            ReloadOutcome::Reloaded => {
                // The file is the truth again: knob edits made for the old version go.
                self.knob_edits.clear();
                self.overlay.reset();
                if self.rebuild() {
                    self.reloads.0 += 1;
                    self.status = Some(format!("reloaded {}", self.watcher.path().display()));
                }
            }
            ReloadOutcome::Failed(errors) => {
                self.reloads.1 += 1;
                self.error = Some(errors.to_string().trim_end().to_string());
            }
        }
    }

    fn apply(&mut self, action: Action) {
        match action {
            Action::SetKnob { pass, kind } => {
                self.knob_edits.insert(pass, kind);
                self.rebuild();
            }
            Action::ResetKnobs => {
                self.knob_edits.clear();
                self.rebuild();
            }
            Action::Technique(path) => match PipelineWatcher::new(&path) {
                Ok(w) => {
                    let old = std::mem::replace(&mut self.watcher, w);
                    let edits = std::mem::take(&mut self.knob_edits);
                    if self.rebuild() {
                        self.overlay.reset();
                        self.status = Some(format!("switched to {}", path.display()));
                    } else {
                        self.watcher = old;
                        self.knob_edits = edits;
                    }
                }
                Err(e) => self.error = Some(e.to_string().trim_end().to_string()),
            },
            Action::Lod { object, policy } => {
                if let Some(o) = self.scene.scene.objects.get_mut(object) {
                    o.lod = policy;
                }
            }
            Action::CameraMode(m) => self.rig.set_mode(m),
            Action::FlySpeed(s) => self.rig.fly_speed = s,
            Action::ResetCamera => {
                let speed = self.rig.fly_speed;
                self.rig = CameraRig::new(self.initial_camera);
                self.rig.fly_speed = speed;
            }
            Action::Screenshot => self.screenshot_next = Some(capture::default_path()),
            Action::Budget(mib) => self.set_budget(mib),
            Action::Brush(settings) => {
                if let Some(b) = &mut self.brush {
                    b.settings = settings;
                }
            }
            Action::BrushStep(step) => self.brush_step(step),
            Action::Save(path) => self.save(Some(path)),
            Action::Journal { restore } => self.restore_journal(Some(restore)),
        }
    }

    /// Re-uploads the scene under a budget of `mib` MiB (its pages stream in again over
    /// the next frames); a budget too small is refused with the minimum, and the old
    /// scene keeps drawing.
    fn set_budget(&mut self, mib: u64) {
        let Some(options) = &self.streaming else {
            return;
        };
        let mut options = options.clone();
        options.budget_bytes = mib << 20;
        let scene = self.scene.scene.clone();
        match ssbvb_engine::upload::upload_scene(
            &self.gpu.ctx,
            scene,
            ssbvb_engine::upload::Residency::Streamed(&options),
        ) {
            Ok(s) => {
                self.scene = s;
                self.streaming = Some(options);
                if self.rebuild() {
                    self.status = Some(format!("GPU budget {mib} MiB"));
                }
            }
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    /// Fill count and covered pixels of the last frame (GPU readbacks: sampled rarely).
    fn sample_fill(&mut self) {
        let ctx = &self.gpu.ctx;
        match self.renderer.fill_count(ctx) {
            Ok(Some(fill)) => {
                self.stats.fill = Some(fill);
                // Pixels showing a voxel (stencil), not the triangles' or background.
                self.stats.covered =
                    ssbvb_passes::measure::voxel_pixels(ctx, &self.renderer).unwrap_or(None);
            }
            Ok(None) => {
                self.stats.fill = None;
                self.stats.covered = None;
            }
            Err(e) => self.error = Some(format!("fill count: {e}")),
        }
    }

    fn frame(&mut self, options: &Options) -> Result<Flow> {
        if let Some(fault) = self.fault_now(options) {
            return Ok(Flow::Recover(fault));
        }
        let now = Instant::now();
        let dt = (now - self.last_frame).as_secs_f64().min(0.25);
        self.last_frame = now;
        self.input.update(&mut self.rig, dt);
        if let Some(deg) = options.orbit_deg.filter(|_| self.frame >= 1) {
            self.rig.orbit.yaw += deg.to_radians();
        }
        self.poll_reload();
        // Automation: --paint, once the first frame has set the view.
        if self.frame == 1 {
            for &step in &options.paint {
                self.script_step(step);
            }
        }
        if self.needs_rebuild {
            self.rebuild();
        }

        // Automation: the last frame of --frames is the one --screenshot shows.
        if let (Some(limit), Some(path)) = (options.frames, &options.screenshot) {
            if self.frame + 1 >= limit && !self.screenshot_written {
                self.screenshot_next = Some(path.clone());
            }
        }

        // Animated objects at the time since start.
        if let Some(animator) = &self.animator {
            let t = self.started.elapsed().as_secs_f64();
            match ssbvb_engine::animation::update_all(
                &self.gpu.ctx,
                &mut self.scene,
                animator,
                &self.animated,
                t,
            ) {
                Ok(r) => {
                    let ms: f64 = r.objects.iter().map(|o| o.total_ms).sum();
                    self.status = Some(format!("animation t = {t:.2} s: update {ms:.1} ms"));
                }
                Err(e) => self.error = Some(format!("animation: {e:#}")),
            }
        }

        // The scene.
        let camera = self.rig.camera();
        // Counted from the last rebuild, so a new pipeline is measured at its first frame.
        let sample_frame = self.frame - self.sample_base;
        let profiling = self.stats.profiling(sample_frame);
        // The counted frame (never a timed one) counts its work: the direct form
        // (`RayMarchGBuffer`) has a fill count only then; other frames run the passes'
        // uncounted variants.
        self.renderer
            .set_counting(Stats::samples_fill(sample_frame));
        match self
            .renderer
            .render(&self.gpu.ctx, &mut self.scene, &camera, profiling)
        {
            Ok(s) => self.stats.record(&s, profiling),
            Err(e) => self.error = Some(format!("frame: {e}")),
        }
        if Stats::samples_fill(sample_frame) {
            self.sample_fill();
        }

        // The overlay.
        let raw_input = self.egui_state.take_egui_input(&self.window);
        let objects: Vec<ObjectLod> = self
            .scene
            .scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let mut drawn = [0usize; 17];
                for v in self.scene.visible.iter().filter(|v| v.object == i) {
                    drawn[(v.level as usize).min(16)] += 1;
                }
                ObjectLod {
                    policy: o.lod,
                    max_level: o.asset.lods.len().saturating_sub(1) as u32,
                    drawn,
                }
            })
            .collect();
        let view = OverlayView {
            adapter: self.gpu.ctx.report(),
            stats: &self.stats,
            pipeline_file: self.watcher.path(),
            pipeline: &self.renderer.pipeline,
            knobs_edited: !self.knob_edits.is_empty(),
            techniques: &options.techniques,
            objects: &objects,
            camera_mode: self.rig.mode,
            fly_speed: self.rig.fly_speed,
            error: self.error.as_deref(),
            status: self.status.as_deref(),
            notice: self.notice.as_deref(),
            size: self.gpu.size(),
            streaming: self.scene.streaming_stats(),
            brush: self.brush.as_ref().map(|b| b.view()),
            warnings: &options.warnings,
        };
        let overlay_state = &mut self.overlay;
        let mut actions = Vec::new();
        let mut full = self.egui_ctx.run_pass(raw_input, |ctx| {
            actions = overlay::draw(ctx, &view, overlay_state);
        });
        self.egui_state
            .handle_platform_output(&self.window, full.platform_output);

        // egui's texture changes are applied whether or not this frame is presented
        // (epaint insists: a dropped delta would lose the font atlas).
        let mut textures = std::mem::take(&mut full.textures_delta);
        for (id, deltas) in textures.set.drain() {
            for delta in &deltas {
                self.egui_renderer.update_texture(
                    &self.gpu.ctx.device,
                    &self.gpu.ctx.queue,
                    id,
                    delta,
                );
            }
        }
        let free: Vec<egui::TextureId> = textures.free.drain().collect();
        let result = self.present(options, full.shapes, full.pixels_per_point);
        for id in &free {
            self.egui_renderer.free_texture(id);
        }
        // After presenting (a rebuild must not change what this frame drew), and also
        // when the surface skipped this frame: a click is not lost.
        if result.is_ok() {
            for a in actions {
                self.apply(a);
            }
        }
        result
    }
}
