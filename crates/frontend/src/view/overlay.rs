//! The egui overlay: what the frame costs (adapter, frame time, per-pass timings, SSBVB
//! fill count, visible instances, residency under a GPU budget) and the controls
//! (technique, pass knobs, LOD, GPU budget, camera, screenshot). It only draws and reports [`Action`]s; the app applies them, so nothing
//! here touches the GPU.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use egui::{Color32, RichText};
use serde_json::{Map, Value};
use ssbvb_gpu::AdapterReport;
use ssbvb_gpu::scene::LodPolicy;
use ssbvb_graph::{PassKind, ResolvedPipeline};

use super::brush::{BrushMode, BrushSettings, BrushShape};
use super::brush_history::{BrushView, Step};
use super::camera_control::CameraMode;
use super::knobs;
use super::stats::{SLOW_SAMPLE_EVERY, Stats, TIMESTAMP_EVERY, TimingSource};
use super::techniques;

/// Something the user asked for in the overlay.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Rebuild the renderer with pass `pass` set to `kind` (same kind, new parameters).
    SetKnob {
        /// Pass name.
        pass: String,
        /// The edited kind.
        kind: PassKind,
    },
    /// Drop every knob edit (back to the file's values).
    ResetKnobs,
    /// Switch to another pipeline file.
    Technique(PathBuf),
    /// Change an object's LOD policy.
    Lod {
        /// Object index in the scene.
        object: usize,
        /// The new policy.
        policy: LodPolicy,
    },
    /// Switch camera.
    CameraMode(CameraMode),
    /// Set the fly speed (world units per second).
    FlySpeed(f64),
    /// Back to the scene's camera.
    ResetCamera,
    /// Write a screenshot.
    Screenshot,
    /// Re-upload the scene under this GPU budget (MiB).
    Budget(u64),
    /// New brush settings.
    Brush(BrushSettings),
    /// Undo or redo a brush stroke.
    BrushStep(Step),
    /// Save the edited objects here.
    Save(PathBuf),
    /// Answer the offer of an earlier session's journal.
    Journal {
        /// Replay it (else set it aside).
        restore: bool,
    },
}

/// One voxel object's LOD as the overlay shows it.
#[derive(Debug, Clone, Copy)]
pub struct ObjectLod {
    /// Current policy.
    pub policy: LodPolicy,
    /// Finest level the asset has (levels are 0..=max).
    pub max_level: u32,
    /// Visible instances drawn at each level last frame (index = level; levels above 16
    /// count at 16).
    pub drawn: [usize; 17],
}

impl ObjectLod {
    /// The non-empty levels of [`ObjectLod::drawn`] as `count at level` pairs, or `None`
    /// when nothing was drawn.
    pub fn histogram_text(&self) -> Option<String> {
        let parts: Vec<String> = self
            .drawn
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(l, n)| format!("{n} at {l}"))
            .collect();
        (!parts.is_empty()).then(|| parts.join(", "))
    }
}

/// What the overlay shows this frame.
pub struct OverlayView<'a> {
    /// The adapter.
    pub adapter: &'a AdapterReport,
    /// Frame statistics.
    pub stats: &'a Stats,
    /// The pipeline file in use (watched for changes).
    pub pipeline_file: &'a Path,
    /// The pipeline being rendered (with knob edits applied).
    pub pipeline: &'a ResolvedPipeline,
    /// Whether knob edits differ from the file.
    pub knobs_edited: bool,
    /// Pipeline files to switch between.
    pub techniques: &'a [PathBuf],
    /// Voxel objects' LOD.
    pub objects: &'a [ObjectLod],
    /// Active camera.
    pub camera_mode: CameraMode,
    /// Fly speed.
    pub fly_speed: f64,
    /// The last reload / rebuild error, shown until the next success.
    pub error: Option<&'a str>,
    /// Latest status line (reloads, screenshots).
    pub status: Option<&'a str>,
    /// What the last GPU fault did (a lost device recovered, a budget lowered).
    pub notice: Option<&'a str>,
    /// Window size in pixels.
    pub size: (u32, u32),
    /// Under a GPU budget: what the page cache holds and did.
    pub streaming: Option<&'a ssbvb_gpu::scene::StreamingStats>,
    /// With --brush: its settings and state.
    pub brush: Option<BrushView>,
    /// The content's and the choice's warnings, each naming its file or field.
    pub warnings: &'a [String],
}

/// Overlay state kept between frames: knob values being edited.
#[derive(Default)]
pub struct OverlayState {
    /// Per pass: the fields being edited (applied when an edit is finished, so a drag does
    /// not rebuild the renderer at every step).
    drafts: HashMap<String, Map<String, Value>>,
    /// Why the last knob edit was refused.
    knob_error: Option<String>,
    /// The GPU budget being edited (MiB), applied with its button.
    budget_draft: Option<u64>,
    /// The save path being edited.
    save_draft: Option<String>,
}

impl OverlayState {
    /// Forgets edits in progress (the pipeline changed under them).
    pub fn reset(&mut self) {
        self.drafts.clear();
        self.knob_error = None;
    }

    /// Shows the budget in effect again (after the viewer lowered it itself).
    pub fn forget_budget_draft(&mut self) {
        self.budget_draft = None;
    }
}

/// Draws the overlay; returns what the user asked for.
pub fn draw(ctx: &egui::Context, view: &OverlayView<'_>, state: &mut OverlayState) -> Vec<Action> {
    let mut actions = Vec::new();
    // Small windows (automation, tests) start with the panel folded so the scene shows.
    let open = view.size.0 >= 640 && view.size.1 >= 400;
    egui::Window::new("ssbvb view")
        .default_pos([8.0, 8.0])
        .default_width(330.0)
        .default_height((view.size.1 as f32 - 24.0).max(100.0))
        .default_open(open)
        .vscroll(true)
        .show(ctx, |ui| {
            if let Some(n) = view.notice {
                ui.colored_label(Color32::from_rgb(255, 190, 90), n);
                ui.separator();
            }
            for w in view.warnings {
                ui.colored_label(Color32::from_rgb(255, 190, 90), format!("warning: {w}"));
            }
            if !view.warnings.is_empty() {
                ui.separator();
            }
            performance(ui, view);
            ui.separator();
            pipeline(ui, view, state, &mut actions);
            ui.separator();
            lod(ui, view, &mut actions);
            ui.separator();
            if let Some(s) = view.streaming {
                budget(ui, s, state, &mut actions);
                ui.separator();
            }
            camera(ui, view, &mut actions);
            ui.separator();
            if let Some(b) = &view.brush {
                brush(ui, b, state, &mut actions);
                ui.separator();
            }
            ui.horizontal(|ui| {
                if ui.button("Screenshot (F12)").clicked() {
                    actions.push(Action::Screenshot);
                }
            });
            if let Some(s) = view.status {
                ui.label(RichText::new(s).small());
            }
        });
    actions
}

/// The brush section: mode, shape, radius and colour (Ctrl + left click paints), undo and
/// redo, save, and the journal (with an earlier session's offer).
fn brush(ui: &mut egui::Ui, view: &BrushView, state: &mut OverlayState, actions: &mut Vec<Action>) {
    if let Some(n) = view.offered {
        ui.colored_label(
            Color32::from_rgb(240, 180, 60),
            format!("An earlier session left {n} unsaved brush operations."),
        );
        ui.horizontal(|ui| {
            if ui.button("Restore").clicked() {
                actions.push(Action::Journal { restore: true });
            }
            if ui.button("Discard").clicked() {
                actions.push(Action::Journal { restore: false });
            }
        });
    }
    let mut b = view.settings;
    ui.collapsing("Brush (Ctrl + left click)", |ui| {
        ui.horizontal(|ui| {
            ui.radio_value(&mut b.mode, BrushMode::Carve, "Carve");
            ui.radio_value(&mut b.mode, BrushMode::Add, "Add");
            ui.separator();
            ui.radio_value(&mut b.shape, BrushShape::Sphere, "Sphere");
            ui.radio_value(&mut b.shape, BrushShape::Cube, "Cube");
        });
        let range = 0.5..=super::brush::MAX_RADIUS_VOXELS;
        ui.add(egui::Slider::new(&mut b.radius_voxels, range).text("radius (voxels)"));
        if b.mode == BrushMode::Add {
            ui.horizontal(|ui| {
                ui.label("colour");
                ui.color_edit_button_rgb(&mut b.color);
            });
        }
        ui.horizontal(|ui| {
            let undo = ui.add_enabled(view.can_undo, egui::Button::new("Undo (Ctrl+Z)"));
            if undo.clicked() {
                actions.push(Action::BrushStep(Step::Undo));
            }
            let redo = ui.add_enabled(view.can_redo, egui::Button::new("Redo (Ctrl+Shift+Z)"));
            if redo.clicked() {
                actions.push(Action::BrushStep(Step::Redo));
            }
        });
        let draft = state
            .save_draft
            .get_or_insert_with(|| view.save_path.display().to_string());
        ui.horizontal(|ui| {
            ui.text_edit_singleline(draft);
            if ui.button("Save (Ctrl+S)").clicked() {
                actions.push(Action::Save(PathBuf::from(draft.trim())));
            }
        });
        let unsaved = match view.unsaved {
            0 => "saved".to_string(),
            n => format!("{n} operations unsaved"),
        };
        ui.label(RichText::new(format!("{unsaved}; {}", view.journal)).small());
    });
    if b != view.settings {
        actions.push(Action::Brush(b));
    }
}

fn ms(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.2}"))
}

fn performance(ui: &mut egui::Ui, view: &OverlayView<'_>) {
    ui.label(format!("Adapter: {}", view.adapter.name));
    if view.adapter.is_software {
        ui.colored_label(
            Color32::from_rgb(240, 180, 60),
            "Software adapter: timings are not representative of a GPU",
        );
    }
    let s = view.stats;
    let fps = s.frame_ms.filter(|m| *m > 0.0).map(|m| 1e3 / m);
    ui.label(format!(
        "Frame {} ms ({} fps), render call {} ms",
        ms(s.frame_ms),
        fps.map_or("-".into(), |f| format!("{f:.1}")),
        ms(s.render_ms)
    ));
    let source = match s.source {
        TimingSource::Timestamps => format!("GPU timestamps, every {TIMESTAMP_EVERY} frames"),
        TimingSource::Wall => {
            format!("wall time, each pass alone, every {SLOW_SAMPLE_EVERY} frames")
        }
    };
    ui.collapsing(format!("Passes ({source})"), |ui| {
        egui::Grid::new("pass timings")
            .striped(true)
            .show(ui, |ui| {
                ui.strong("pass");
                ui.strong("GPU ms");
                ui.strong("wall ms");
                ui.end_row();
                for p in &s.passes {
                    ui.label(&p.name);
                    ui.monospace(ms(p.gpu_ms));
                    ui.monospace(ms(p.wall_ms));
                    ui.end_row();
                }
            });
        if s.passes.is_empty() {
            ui.weak("(not sampled yet)");
        }
    });
    let has_filter = view.pipeline.passes.iter().any(|p| {
        matches!(
            p.kind,
            PassKind::RayMarchFilter { .. } | PassKind::RayMarchGBuffer { .. }
        )
    });
    if has_filter {
        match (s.fill, s.covered) {
            (Some(f), Some(c)) => {
                let pct = if c > 0 {
                    format!(" ({:.1}%)", 100.0 * f as f64 / c as f64)
                } else {
                    String::new()
                };
                // One short line: a wrapping line would move the controls below it.
                ui.label(format!("SSBVB fill: {f} / {c} voxel px{pct}"))
            }
            _ => ui.label("SSBVB fill: not sampled yet"),
        }
        .on_hover_text(format!(
            "Entries the ray-march filter appended to the SSBVB (the direct form: pixels \
             its march wrote) vs pixels showing a voxel (stencil) (GPU readbacks every \
             {SLOW_SAMPLE_EVERY} frames)"
        ));
    } else {
        ui.weak("SSBVB fill: no ray-march filter");
    }
    ui.label(format!("Visible instances: {}", s.visible_instances));
}

fn pipeline(
    ui: &mut egui::Ui,
    view: &OverlayView<'_>,
    state: &mut OverlayState,
    actions: &mut Vec<Action>,
) {
    let current = techniques::label(view.pipeline_file);
    egui::ComboBox::from_label("Technique")
        .selected_text(&current)
        .show_ui(ui, |ui| {
            for t in view.techniques {
                let selected = techniques::same_file(t, view.pipeline_file);
                if ui
                    .selectable_label(selected, techniques::label(t))
                    .clicked()
                    && !selected
                {
                    actions.push(Action::Technique(t.clone()));
                }
            }
        });
    ui.label(RichText::new(format!("{} (hot reload)", view.pipeline_file.display())).small());
    if let Some(e) = view.error {
        ui.colored_label(
            Color32::from_rgb(255, 110, 100),
            "Error — still rendering the last good pipeline:",
        );
        ui.label(
            RichText::new(e)
                .monospace()
                .color(Color32::from_rgb(255, 150, 140)),
        );
    }
    ui.collapsing("Knobs", |ui| {
        knob_editors(ui, view.pipeline, state, actions);
        if view.knobs_edited && ui.button("Reset knobs to the file").clicked() {
            actions.push(Action::ResetKnobs);
            state.reset();
        }
        if let Some(e) = &state.knob_error {
            ui.colored_label(Color32::from_rgb(255, 110, 100), e);
        }
        ui.weak("Edits apply to this session only; the file is not written.");
    });
}

fn knob_editors(
    ui: &mut egui::Ui,
    pipeline: &ResolvedPipeline,
    state: &mut OverlayState,
    actions: &mut Vec<Action>,
) {
    let mut any = false;
    for pass in &pipeline.passes {
        let (kind_name, current) = knobs::fields(&pass.kind);
        if current.is_empty() {
            continue;
        }
        any = true;
        let draft = state
            .drafts
            .entry(pass.name.clone())
            .or_insert_with(|| current.clone());
        let snapshot = draft.clone();
        let mut commit = false;
        ui.label(RichText::new(format!("{} ({kind_name})", pass.name)).strong());
        egui::Grid::new(("knobs", &pass.name)).show(ui, |ui| {
            for (field, value) in draft.iter_mut() {
                ui.label(field);
                commit |= field_editor(ui, &kind_name, &snapshot, field, value, &pass.name);
                ui.end_row();
            }
        });
        if commit {
            match knobs::with_fields(&kind_name, draft.clone()) {
                Ok(kind) => {
                    state.knob_error = None;
                    if kind != pass.kind {
                        actions.push(Action::SetKnob {
                            pass: pass.name.clone(),
                            kind,
                        });
                    }
                }
                Err(e) => state.knob_error = Some(format!("{}: {e}", pass.name)),
            }
        }
    }
    if !any {
        ui.weak("No pass in this pipeline has parameters.");
    }
}

/// One field's editor; `true` when an edit is finished and should be applied.
fn field_editor(
    ui: &mut egui::Ui,
    kind_name: &str,
    fields: &Map<String, Value>,
    field: &str,
    value: &mut Value,
    pass: &str,
) -> bool {
    // A drag is applied when it stops, typing when the value changes without a drag.
    let finished = |r: &egui::Response| r.drag_stopped() || (r.changed() && !r.dragged());
    match value {
        Value::Number(n) if n.is_i64() || n.is_u64() => {
            let unsigned = n.is_u64();
            let mut v = n.as_i64().unwrap_or(i64::MAX);
            let speed = (v.abs() as f64 / 100.0).max(1.0);
            let mut w = egui::DragValue::new(&mut v).speed(speed);
            if unsigned {
                w = w.range(0..=i64::from(u32::MAX));
            }
            let r = ui.add(w);
            if r.changed() {
                *value = Value::from(v);
            }
            finished(&r)
        }
        Value::Number(n) => {
            let mut v = n.as_f64().unwrap_or(0.0);
            let speed = (v.abs() / 100.0).max(0.001);
            let r = ui.add(egui::DragValue::new(&mut v).speed(speed).max_decimals(4));
            if let (true, Some(num)) = (r.changed(), serde_json::Number::from_f64(v)) {
                *value = Value::Number(num);
            }
            finished(&r)
        }
        Value::Bool(b) => ui.checkbox(b, "").changed(),
        Value::String(s) => {
            let choices = knobs::enum_choices(kind_name, fields, field);
            if choices.is_empty() {
                ui.text_edit_singleline(s).lost_focus()
            } else {
                let mut picked = false;
                egui::ComboBox::from_id_salt(("knob", pass, field))
                    .selected_text(s.as_str())
                    .show_ui(ui, |ui| {
                        for c in &choices {
                            if ui.selectable_label(s == c, c).clicked() && s != c {
                                *s = c.clone();
                                picked = true;
                            }
                        }
                    });
                picked
            }
        }
        other => {
            ui.monospace(other.to_string());
            false
        }
    }
}

/// Residency under a GPU budget, and the budget itself (changed live).
fn budget(
    ui: &mut egui::Ui,
    s: &ssbvb_gpu::scene::StreamingStats,
    state: &mut OverlayState,
    actions: &mut Vec<Action>,
) {
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    ui.label(RichText::new("GPU budget").strong());
    ui.label(format!(
        "resident {:.1} of {:.0} MiB ({:.1} MiB fixed: lookups down to pages, pinned levels, proxies)",
        mib(s.bytes_resident),
        mib(s.budget_bytes),
        mib(s.fixed_bytes)
    ));
    ui.label(format!(
        "pages: {} of {} resident, {} streamed last frame, {} missing, {} evicted in all",
        s.pages_resident,
        s.pages_total,
        s.pages_streamed_last_frame,
        s.pages_missing,
        s.pages_evicted
    ));
    if s.over_budget {
        ui.colored_label(
            Color32::YELLOW,
            "the view needs more pages than the budget holds: some show coarser voxels",
        );
    }
    if s.pages_failed > 0 {
        ui.colored_label(
            Color32::LIGHT_RED,
            format!("{} pages refused (damaged cache)", s.pages_failed),
        );
    }
    let current = s.budget_bytes >> 20;
    let draft = state.budget_draft.get_or_insert(current);
    ui.horizontal(|ui| {
        ui.add(
            egui::DragValue::new(draft)
                .range(1..=ssbvb_engine::budget::MAX_BUDGET_MIB)
                .suffix(" MiB"),
        );
        if ui.button("Apply budget").clicked() && *draft != current {
            actions.push(Action::Budget(*draft));
        }
    });
}

fn lod(ui: &mut egui::Ui, view: &OverlayView<'_>, actions: &mut Vec<Action>) {
    ui.label(RichText::new("LOD").strong());
    if view.objects.is_empty() {
        ui.weak("No voxel objects.");
    }
    for (i, o) in view.objects.iter().enumerate() {
        let mut policy = o.policy;
        ui.horizontal(|ui| {
            ui.label(format!("object {i}"));
            let mut auto = matches!(policy, LodPolicy::Auto { .. });
            let was_auto = auto;
            ui.radio_value(&mut auto, false, "fixed");
            ui.radio_value(&mut auto, true, "auto");
            match o.histogram_text() {
                Some(h) => ui.weak(format!("drawn: {h}")),
                None => ui.weak("not visible"),
            };
            if auto != was_auto {
                policy = if auto {
                    LodPolicy::AUTO
                } else {
                    LodPolicy::Fixed(o.max_level)
                };
            }
        });
        match &mut policy {
            LodPolicy::Fixed(level) => {
                ui.add(egui::Slider::new(level, 0..=o.max_level).text("level"));
            }
            LodPolicy::Auto { bias, pixel_error } => {
                let m = o.max_level as i32;
                ui.add(egui::Slider::new(pixel_error, 0.0..=16.0).text("pixel error"));
                ui.add(egui::Slider::new(bias, -m..=m).text("bias (+ finer)"));
            }
        }
        if policy != o.policy {
            actions.push(Action::Lod { object: i, policy });
        }
    }
}

fn camera(ui: &mut egui::Ui, view: &OverlayView<'_>, actions: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        ui.label(RichText::new("Camera").strong());
        let mut mode = view.camera_mode;
        ui.radio_value(&mut mode, CameraMode::Orbit, "orbit");
        ui.radio_value(&mut mode, CameraMode::Fly, "fly");
        ui.label("(Tab)");
        if mode != view.camera_mode {
            actions.push(Action::CameraMode(mode));
        }
        if ui.button("Reset").clicked() {
            actions.push(Action::ResetCamera);
        }
    });
    match view.camera_mode {
        CameraMode::Orbit => {
            ui.weak("Left drag: rotate · right/middle drag: pan · wheel: zoom");
        }
        CameraMode::Fly => {
            let mut speed = view.fly_speed;
            let step = speed * 0.01;
            let r = ui.add(
                egui::DragValue::new(&mut speed)
                    .speed(step)
                    .range(1e-4..=1e7)
                    .prefix("speed ")
                    .suffix(" /s"),
            );
            if r.changed() {
                actions.push(Action::FlySpeed(speed));
            }
            ui.weak("WASD move · Q/E down/up · right drag: look · Shift: ×4 · wheel: speed");
        }
    }
}

#[cfg(test)]
mod lod_tests {
    use super::*;

    #[test]
    fn the_level_histogram_lists_drawn_levels_in_order() {
        let mut drawn = [0usize; 17];
        drawn[3] = 12;
        drawn[5] = 1;
        let o = ObjectLod {
            policy: LodPolicy::AUTO,
            max_level: 8,
            drawn,
        };
        assert_eq!(o.histogram_text().as_deref(), Some("12 at 3, 1 at 5"));
        let none = ObjectLod {
            drawn: [0; 17],
            ..o
        };
        assert_eq!(none.histogram_text(), None);
    }
}
