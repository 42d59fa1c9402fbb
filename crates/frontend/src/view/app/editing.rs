//! The viewer's brush work: a click, undo and redo, save (Ctrl+S, the overlay,
//! `--save-on-exit`), the journal's restore, and the end of the session. Failures go to
//! the overlay's error line; the session stays open.

use std::path::PathBuf;

use anyhow::Result;

use super::super::brush_history::Step;
use super::super::script::ScriptStep;
use super::state::{Options, Viewer};

impl Viewer {
    /// One `--paint` step.
    pub(super) fn script_step(&mut self, step: ScriptStep) {
        match step {
            ScriptStep::Paint(x, y) => self.paint(x, y),
            ScriptStep::Step(s) => self.brush_step(s),
            ScriptStep::Save => self.save(None),
        }
    }

    /// Applies the brush at window pixel `(x, y)` of the frame on screen. Each edit is
    /// printed in a scene file's syntax (a session's edits can go into `edits:`).
    pub(super) fn paint(&mut self, x: u32, y: u32) {
        let Some(brush) = &mut self.brush else {
            return;
        };
        let camera = self.rig.camera();
        match brush.paint(&self.gpu.ctx, &mut self.scene, &camera, x, y) {
            Ok(Some(p)) => {
                let edit = ron::to_string(&p.edit).unwrap_or_else(|e| e.to_string());
                eprintln!("brush: object {}: {edit}", p.object);
                eprintln!("{}", p.status);
                self.status = Some(p.status);
            }
            Ok(None) => self.status = Some("brush: no editable voxel under the cursor".into()),
            Err(e) => self.brush_error(format!("brush: {e:#}")),
        }
    }

    /// Undo or redo one stroke.
    pub(super) fn brush_step(&mut self, step: Step) {
        let Some(brush) = &mut self.brush else {
            return;
        };
        match brush.step(&self.gpu.ctx, &mut self.scene, step) {
            Ok(Some(line)) => {
                eprintln!("{line}");
                self.status = Some(line);
            }
            Ok(None) => {
                let what = match step {
                    Step::Undo => "nothing to undo",
                    Step::Redo => "nothing to redo",
                };
                self.status = Some(format!("brush: {what}"));
            }
            Err(e) => self.brush_error(format!("brush: {e:#}")),
        }
    }

    /// Saves the edited objects to `path` (which becomes the save path) or the save path.
    pub(super) fn save(&mut self, path: Option<PathBuf>) {
        let Some(brush) = &mut self.brush else {
            return;
        };
        if let Some(p) = path {
            brush.save_path = p;
        }
        let target = brush.save_path.clone();
        match brush.save(&self.scene.scene, &target) {
            Ok(line) => {
                eprintln!("brush: {line}");
                self.status = Some(format!("brush: {line}"));
            }
            Err(e) => self.brush_error(format!("brush: {e:#}")),
        }
    }

    /// Replays the journal `--restore` asked for (`answer` `None`), or answers the
    /// overlay's offer.
    pub(super) fn restore_journal(&mut self, answer: Option<bool>) {
        let Some(brush) = &mut self.brush else {
            return;
        };
        match brush.restore(&self.gpu.ctx, &mut self.scene, answer) {
            Ok(Some(line)) => {
                eprintln!("{line}");
                self.status = Some(line);
            }
            Ok(None) => {}
            Err(e) => self.brush_error(format!("brush: restoring the journal: {e:#}")),
        }
    }

    /// A brush failure: in the overlay, and on the terminal for scripted runs.
    fn brush_error(&mut self, line: String) {
        eprintln!("{line}");
        self.error = Some(line);
    }

    /// The session ends: `--save-on-exit` is written (a failure is the viewer's error,
    /// and the journal stays), and the journal is removed when nothing is unsaved.
    pub(super) fn end_session(&mut self, options: &Options) -> Result<()> {
        let Some(brush) = &mut self.brush else {
            return Ok(());
        };
        for line in brush.finish(&self.scene.scene, options.save_on_exit.as_deref())? {
            eprintln!("{line}");
        }
        Ok(())
    }
}
