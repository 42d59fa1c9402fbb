//! What keeps the brush's work: undo and redo (each the inverse splice of the blocks the
//! stroke touched, so undoing a click costs what the click cost), replaying a journal,
//! and saving the edited objects as prepared asset files (every level, as edited) that
//! `ssbvb render FILE` and `ssbvb view FILE` open.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{GpuScene, Scene};
use ssbvb_voxel::edit_journal::JournalOp;
use ssbvb_voxel::export::ExportFormat;

use super::brush::{Brush, BrushSettings, Stroke};

/// What the overlay shows of the brush.
#[derive(Debug, Clone)]
pub struct BrushView {
    /// Its settings.
    pub settings: BrushSettings,
    /// Whether undo and redo have something to take.
    pub can_undo: bool,
    /// See `can_undo`.
    pub can_redo: bool,
    /// Operations since the last save.
    pub unsaved: u64,
    /// Where save writes.
    pub save_path: PathBuf,
    /// The journal's line.
    pub journal: String,
    /// Operations of an earlier session waiting for an answer.
    pub offered: Option<usize>,
}

/// Undo or redo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Take the last stroke back.
    Undo,
    /// Apply the last undone stroke again.
    Redo,
}

impl Brush {
    /// Whether there is something to undo and to redo.
    pub fn can_step(&self) -> (bool, bool) {
        (!self.done.is_empty(), !self.undone.is_empty())
    }

    /// Undoes or redoes one stroke (journaled first): the status line, or `None` when
    /// there is nothing to take.
    pub fn step(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        step: Step,
    ) -> Result<Option<String>> {
        let t0 = Instant::now();
        let Some(words) = self.step_inner(ctx, gpu_scene, step, true)? else {
            return Ok(None);
        };
        ctx.wait_idle()?;
        let (verb, stroke) = match step {
            Step::Undo => ("undid", self.undone.last()),
            Step::Redo => ("redid", self.done.last()),
        };
        let Some(s) = stroke else {
            bail!("the stroke left its stack");
        };
        Ok(Some(format!(
            "brush: {verb} on object {}: +{} −{} voxels ({} blocks, {words} words uploaded) \
             in {:.1} ms",
            self.objects[s.editable].object,
            s.local.report.added,
            s.local.report.removed,
            s.local.blocks,
            t0.elapsed().as_secs_f64() * 1e3
        )))
    }

    /// [`Brush::step`] without the status: the words uploaded, or `None` with nothing to
    /// take. Nothing changes when any step fails.
    fn step_inner(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        step: Step,
        record: bool,
    ) -> Result<Option<u64>> {
        let (from, op) = match step {
            Step::Undo => (&mut self.done, JournalOp::Undo),
            Step::Redo => (&mut self.undone, JournalOp::Redo),
        };
        let Some(stroke) = from.pop() else {
            return Ok(None);
        };
        if record {
            if let Err(e) = self.journal.record(&op) {
                self.push_back(step, stroke);
                return Err(e);
            }
        }
        let k = stroke.editable;
        let inverse = self.objects[k].editor.revert(&stroke.local);
        match self.splice(ctx, gpu_scene, k, &inverse) {
            Ok(words) => {
                let moved = Stroke {
                    local: inverse,
                    ..stroke
                };
                match step {
                    Step::Undo => self.undone.push(moved),
                    Step::Redo => self.done.push(moved),
                }
                self.unsaved += 1;
                Ok(Some(words))
            }
            Err(e) => {
                self.objects[k].editor.revert(&inverse);
                self.push_back(step, stroke);
                if record {
                    let back = match step {
                        Step::Undo => JournalOp::Redo,
                        Step::Redo => JournalOp::Undo,
                    };
                    let _ = self.journal.record(&back);
                }
                Err(e)
            }
        }
    }

    fn push_back(&mut self, step: Step, stroke: Stroke) {
        match step {
            Step::Undo => self.done.push(stroke),
            Step::Redo => self.undone.push(stroke),
        }
    }

    /// Replays journaled operations (not journaled again): the session as it was.
    /// Returns the status line.
    pub fn replay_journal(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        ops: &[JournalOp],
    ) -> Result<String> {
        let t0 = Instant::now();
        for (i, op) in ops.iter().enumerate() {
            let what = || format!("replaying journal operation {} of {}", i + 1, ops.len());
            match *op {
                JournalOp::Edit { object, edit } => {
                    let k = object as usize;
                    if k >= self.objects.len() {
                        bail!("{}: no editable object {object}", what());
                    }
                    self.stroke(ctx, gpu_scene, k, edit, false)
                        .with_context(what)?;
                }
                JournalOp::Undo => {
                    self.step_inner(ctx, gpu_scene, Step::Undo, false)
                        .with_context(what)?;
                }
                JournalOp::Redo => {
                    self.step_inner(ctx, gpu_scene, Step::Redo, false)
                        .with_context(what)?;
                }
            }
        }
        ctx.wait_idle()?;
        Ok(format!(
            "brush: restored {} journaled operations ({} strokes applied) in {:.0} ms",
            ops.len(),
            self.done.len(),
            t0.elapsed().as_secs_f64() * 1e3
        ))
    }

    /// Replays what `--restore` asked for, or the answer to the overlay's offer.
    pub fn restore(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        answer: Option<bool>,
    ) -> Result<Option<String>> {
        let ops = match answer {
            Some(restore) => self.journal.decide(restore),
            None => self.journal.take_pending(),
        };
        if ops.is_empty() {
            return Ok(answer.map(|r| {
                if r {
                    "brush: nothing to restore".into()
                } else {
                    "brush: the earlier session's journal was set aside".into()
                }
            }));
        }
        self.replay_journal(ctx, gpu_scene, &ops).map(Some)
    }

    /// Writes the edited objects to `path` (one editable object) or to `path` with the
    /// object's index before the extension (several), atomically: each as a prepared asset
    /// file with every level it has, or exported at its finest level when the extension
    /// names an export format (`.vox`, `.raw`, `.npy`, `.obj`). Returns the status line.
    pub fn save(&mut self, scene: &Scene, path: &Path) -> Result<String> {
        let t0 = Instant::now();
        if self.objects.is_empty() {
            bail!("no editable object to save");
        }
        let mut written = Vec::new();
        for (k, e) in self.objects.iter().enumerate() {
            let target = if self.objects.len() == 1 {
                path.to_path_buf()
            } else {
                numbered(path, k)
            };
            let asset = e.editor.asset(scene.objects[e.object].asset.object_space);
            let what = || format!("saving object {} to {}", e.object, target.display());
            match export_format(&target) {
                Some(format) => {
                    let level = asset.lods.len() as u32 - 1;
                    ssbvb_voxel::export::write(format, &target, &asset, level)
                        .map(|_| ())
                        .with_context(what)?;
                }
                None => {
                    ssbvb_voxel::cache::write_asset_file(&target, &asset)
                        .map(|_| ())
                        .with_context(what)?;
                }
            }
            let bytes = std::fs::metadata(&target).map_or(0, |m| m.len());
            written.push(format!("{} ({bytes} bytes)", target.display()));
        }
        self.unsaved = 0;
        Ok(format!(
            "saved {} in {:.0} ms",
            written.join(", "),
            t0.elapsed().as_secs_f64() * 1e3
        ))
    }

    /// What the overlay shows.
    pub fn view(&self) -> BrushView {
        let (can_undo, can_redo) = self.can_step();
        BrushView {
            settings: self.settings,
            can_undo,
            can_redo,
            unsaved: self.unsaved,
            save_path: self.save_path.clone(),
            journal: self.journal.line(),
            offered: self.journal.offered(),
        }
    }

    /// What the journal said at start.
    pub fn journal_notes(&self) -> &[String] {
        &self.journal.notes
    }

    /// At the end of the session: `save_on_exit` written, then the journal removed when
    /// nothing is unsaved (kept otherwise). The lines to print.
    pub fn finish(&mut self, scene: &Scene, save_on_exit: Option<&Path>) -> Result<Vec<String>> {
        let mut lines = Vec::new();
        if let Some(path) = save_on_exit {
            lines.push(format!("brush: {}", self.save(scene, path)?));
        }
        lines.extend(self.journal.finish(self.unsaved));
        Ok(lines)
    }
}

/// The export format a save path names by its extension (`.vox`, `.raw`, `.npy`, `.obj`;
/// the finest level, dense for npy), `None` for the project's asset file.
fn export_format(path: &Path) -> Option<ExportFormat> {
    let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
    match ext.as_str() {
        "vox" => Some(ExportFormat::Vox),
        "raw" => Some(ExportFormat::Raw),
        "npy" => Some(ExportFormat::Npy { sparse: false }),
        "obj" => Some(ExportFormat::Obj),
        _ => None,
    }
}

/// `dir/name.K.ext` for `dir/name.ext`.
fn numbered(path: &Path, k: usize) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(|| "edited".into(), |s| s.to_string_lossy().into_owned());
    let name = match path.extension() {
        Some(ext) => format!("{stem}.{k}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{k}"),
    };
    path.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_objects_save_to_numbered_files() {
        assert_eq!(
            numbered(Path::new("out/e.ssbvb"), 2),
            PathBuf::from("out/e.2.ssbvb")
        );
        assert_eq!(numbered(Path::new("e"), 0), PathBuf::from("e.0"));
        assert_eq!(export_format(Path::new("a/b.VOX")), Some(ExportFormat::Vox));
        assert_eq!(export_format(Path::new("b.ssbvb")), None);
        assert_eq!(
            export_format(Path::new("b.npy")),
            Some(ExportFormat::Npy { sparse: false })
        );
    }
}
