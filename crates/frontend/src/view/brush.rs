//! The viewer's brush (`ssbvb view --brush`): Ctrl + left click on a voxel object carves
//! or adds a sphere or box there. The voxel under the cursor is found by the CPU reference
//! caster on each editable object's current finest level, whose lookup is kept current by
//! the patches' CPU twin; the edit is applied region-locally ([`LocalEditor`]) and spliced
//! into the object's room on the GPU ([`LevelSplicer`]), so a click costs the touched
//! blocks, not a rebuild. Every instance of the object shows the edit (they share it).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use glam::DVec3;
use ssbvb_gpu::GpuContext;
use ssbvb_gpu::scene::{DynamicRoom, GpuScene, Scene};
use ssbvb_gpu_build::level_splice::LevelSplicer;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::edit::{Edit, level_voxels};
use ssbvb_voxel::edit_journal::JournalOp;
use ssbvb_voxel::local_edit::{LocalEdit, LocalEditor};
use ssbvb_voxel::lookup::SparseLookup;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{Traversal, trace_object_ray};

use super::brush_journal::{Journal, JournalOptions};

/// Room per level for an editable object, as a multiple of its voxels and nodes.
const GROWTH: f64 = 2.0;

/// The largest brush radius in voxels (the overlay's slider and `--brush-radius`): a cube
/// of that half-side stays under `ssbvb_voxel::edit::MAX_BRUSH_CELLS`.
pub const MAX_RADIUS_VOXELS: f64 = 64.0;

/// Carve or add.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BrushMode {
    /// Remove the cells inside the brush.
    Carve,
    /// Add the cells inside the brush, in the brush's colour.
    Add,
}

/// The brush's shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BrushShape {
    /// A ball of the radius.
    Sphere,
    /// A cube of half-side the radius.
    Cube,
}

/// What a click does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrushSettings {
    /// Carve or add.
    pub mode: BrushMode,
    /// Ball or cube.
    pub shape: BrushShape,
    /// Radius in voxels of the object's finest level.
    pub radius_voxels: f64,
    /// Linear RGB of added cells.
    pub color: [f32; 3],
}

impl Default for BrushSettings {
    fn default() -> Self {
        Self {
            mode: BrushMode::Carve,
            shape: BrushShape::Sphere,
            radius_voxels: 6.0,
            color: [0.85, 0.2, 0.15],
        }
    }
}

impl BrushSettings {
    /// The edit centred on `center` (object space) of an object voxelized at `level`.
    pub fn edit_at(&self, center: DVec3, level: u32) -> Edit {
        let r = self.radius_voxels.max(0.5) * cell_size(level);
        let c = (center.x, center.y, center.z);
        let (lo, hi) = ((c.0 - r, c.1 - r, c.2 - r), (c.0 + r, c.1 + r, c.2 + r));
        let [red, green, blue] = self.color.map(|v| v.clamp(0.0, 1.0));
        let color = (red, green, blue, 1.0);
        match (self.mode, self.shape) {
            (BrushMode::Carve, BrushShape::Sphere) => Edit::RemoveSphere {
                center: c,
                radius: r,
            },
            (BrushMode::Add, BrushShape::Sphere) => Edit::AddSphere {
                center: c,
                radius: r,
                color,
            },
            (BrushMode::Carve, BrushShape::Cube) => Edit::RemoveBox { min: lo, max: hi },
            (BrushMode::Add, BrushShape::Cube) => Edit::AddBox {
                min: lo,
                max: hi,
                color,
            },
        }
    }
}

/// One editable object.
pub(super) struct Editable {
    /// Its index in the scene's objects.
    pub(super) object: usize,
    pub(super) editor: LocalEditor,
    /// Its finest level's lookup as edited (for picking).
    lookup: SparseLookup,
}

/// The voxel under a pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pick {
    /// The scene object.
    pub object: usize,
    /// Index of the instance within the object's instances.
    pub instance: usize,
    /// The hit voxel's centre in object space.
    pub center: DVec3,
    /// World distance from the eye.
    pub t: f64,
}

/// One applied brush stroke.
#[derive(Debug, Clone, PartialEq)]
pub struct Painted {
    /// The scene object edited.
    pub object: usize,
    /// The edit, in the object's space (what a scene file's `edits:` would list).
    pub edit: Edit,
    /// What it did and cost, for the status line.
    pub status: String,
}

/// A stroke on the undo or redo stack: the edit, and the change last applied for it (the
/// edit itself, or its undo), whose [`LocalEditor::revert`] takes the other step.
#[derive(Clone)]
pub(super) struct Stroke {
    /// Index among the editable objects.
    pub(super) editable: usize,
    pub(super) edit: Edit,
    pub(super) local: LocalEdit,
}

/// What a stroke did and cost.
pub(super) struct StrokeCost {
    /// Cells added, removed, clipped.
    pub(super) report: ssbvb_voxel::edit::EditReport,
    /// Blocks touched at the finest level, and their side.
    pub(super) blocks: usize,
    pub(super) block_side: u32,
    /// Words uploaded to the GPU.
    pub(super) words: u64,
    /// Milliseconds spent journaling it (one synced write).
    pub(super) journal_ms: f64,
}

/// The brush tool: its settings, the editable objects, the undo and redo stacks and the
/// journal (`brush_history`).
pub struct Brush {
    /// What a click does.
    pub settings: BrushSettings,
    pub(super) objects: Vec<Editable>,
    splicer: Option<LevelSplicer>,
    /// The objects left out (animated ones), for [`Brush::restarted`].
    skip: Vec<usize>,
    /// Strokes applied and not undone, oldest first: what a device loss must not lose.
    pub(super) done: Vec<Stroke>,
    /// Strokes undone, the last undone last.
    pub(super) undone: Vec<Stroke>,
    /// Where every operation is written before it is shown.
    pub(super) journal: Journal,
    /// Operations since the last save (0: the saved file holds the session).
    pub(super) unsaved: u64,
    /// Where save writes.
    pub save_path: PathBuf,
}

impl Brush {
    /// Editors for the voxel objects of `scene` except `skip` (animated ones), with the
    /// journal `journal` says (a journal found there is read now: offered, restored or set
    /// aside as it says) and saves going to `save_path`.
    pub fn new(
        scene: &Scene,
        skip: &[usize],
        journal: &JournalOptions,
        save_path: PathBuf,
    ) -> Self {
        let objects: Vec<Editable> = scene
            .objects
            .iter()
            .enumerate()
            .filter(|(i, o)| !skip.contains(i) && !o.asset.lods.is_empty())
            .map(|(object, o)| {
                let finest = o.asset.lods.len() - 1;
                Editable {
                    object,
                    editor: LocalEditor::new(level_voxels(&o.asset.lods[finest])),
                    lookup: o.asset.lods[finest].lookup.clone(),
                }
            })
            .collect();
        let assets: Vec<&ssbvb_voxel::asset::VoxelAsset> = objects
            .iter()
            .map(|e| scene.objects[e.object].asset.as_ref())
            .collect();
        let key = ssbvb_voxel::edit_journal::model_key(&assets);
        Self {
            settings: BrushSettings::default(),
            journal: Journal::open(journal, objects.len() as u32, key),
            objects,
            splicer: None,
            skip: skip.to_vec(),
            done: Vec::new(),
            undone: Vec::new(),
            unsaved: 0,
            save_path,
        }
    }

    /// The edits applied and not undone, in order, by scene object.
    pub fn history(&self) -> Vec<(usize, Edit)> {
        self.done
            .iter()
            .map(|s| (self.objects[s.editable].object, s.edit))
            .collect()
    }

    /// A brush with these settings, journal, redo stack and save state on `scene` as it
    /// was before any edit (the scene's assets are never edited: the edits live in the GPU
    /// rooms and the editors), for a new device; [`Brush::replay`] then applies the
    /// history again. The journal moves to the new brush.
    pub fn restarted(&mut self, scene: &Scene) -> Self {
        let mut b = Self::new(scene, &self.skip, &JournalOptions::off(), PathBuf::new());
        b.settings = self.settings;
        b.journal = std::mem::replace(&mut self.journal, Journal::off());
        b.undone = self.undone.clone();
        b.unsaved = self.unsaved;
        b.save_path = self.save_path.clone();
        b
    }

    /// Applies `edits` in order on a scene uploaded with [`Brush::rooms`] (not journaled:
    /// they are already): the same patches as when they were first made, so the rooms end
    /// as they were.
    pub fn replay(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        edits: &[(usize, Edit)],
    ) -> Result<()> {
        let redo = std::mem::take(&mut self.undone);
        for &(object, edit) in edits {
            let k = self.editable(object)?;
            self.stroke(ctx, gpu_scene, k, edit, false)?;
        }
        self.undone = redo;
        ctx.wait_idle()?;
        Ok(())
    }

    /// The index among the editable objects of scene object `object`.
    pub(super) fn editable(&self, object: usize) -> Result<usize> {
        match self.objects.iter().position(|e| e.object == object) {
            Some(k) => Ok(k),
            None => bail!("object {object} is not editable"),
        }
    }

    /// Applies `edit` to editable object `k` as a new stroke: its editor, the journal
    /// (when `record`), its room on the GPU, the lookup used for picking; the redo stack
    /// is cleared. Nothing changes when any step fails.
    pub(super) fn stroke(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        k: usize,
        edit: Edit,
        record: bool,
    ) -> Result<StrokeCost> {
        let local = self.objects[k].editor.apply(&[edit])?;
        let t_journal = Instant::now();
        if record {
            let op = JournalOp::Edit {
                object: k as u32,
                edit,
            };
            if let Err(e) = self.journal.record(&op) {
                self.objects[k].editor.revert(&local);
                return Err(e.context("the edit was not applied"));
            }
        }
        let journal_ms = t_journal.elapsed().as_secs_f64() * 1e3;
        let words = match self.splice(ctx, gpu_scene, k, &local) {
            Ok(w) => w,
            Err(err) => {
                // Nothing reached the GPU: the editor goes back to what the room holds,
                // and the journal says the edit was taken back.
                self.objects[k].editor.revert(&local);
                if record {
                    let _ = self.journal.record(&JournalOp::Undo);
                }
                return Err(err);
            }
        };
        let out = StrokeCost {
            report: local.report,
            blocks: local.blocks,
            block_side: local.block_side,
            words,
            journal_ms,
        };
        self.done.push(Stroke {
            editable: k,
            edit,
            local,
        });
        self.undone.clear();
        self.unsaved += 1;
        Ok(out)
    }

    /// Sends `local`'s patches to editable object `k`'s room and updates its picking
    /// lookup: the words uploaded.
    pub(super) fn splice(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        k: usize,
        local: &LocalEdit,
    ) -> Result<u64> {
        if self.splicer.is_none() {
            self.splicer = Some(LevelSplicer::new(ctx)?);
        }
        let Some(splicer) = &self.splicer else {
            bail!("the splice kernels did not compile");
        };
        let e = &mut self.objects[k];
        let stats = splicer.apply(ctx, gpu_scene, e.object, &local.patches)?;
        if let Some(finest) = local.patches.last() {
            e.lookup.nodes = finest.apply_nodes(&e.lookup.nodes);
        }
        Ok(stats.words_uploaded)
    }

    /// The room the editable objects need in the GPU scene.
    pub fn rooms(&self) -> Vec<DynamicRoom> {
        self.objects
            .iter()
            .map(|e| DynamicRoom {
                object: e.object,
                growth: GROWTH,
            })
            .collect()
    }

    /// The first voxel of an editable object under pixel `(px, py)` of a `size` view
    /// (`None` for a pixel outside it).
    pub fn pick(
        &self,
        scene: &Scene,
        camera: &Camera,
        px: u32,
        py: u32,
        size: (u32, u32),
    ) -> Option<Pick> {
        if px >= size.0 || py >= size.1 {
            return None; // outside the view (`--paint` can name any pixel)
        }
        let (origin, dir) = camera.pixel_rays(size.0, size.1).ray(px, py);
        let mut best: Option<Pick> = None;
        for e in &self.objects {
            let s = cell_size(e.lookup.level);
            for (instance, xf) in scene.objects[e.object].instances.iter().enumerate() {
                let inv = xf.inverse();
                if !inv.matrix3.is_finite() || !inv.translation.is_finite() {
                    continue;
                }
                // An affine map keeps the ray parameter: t is the world distance.
                let (o, d) = (inv.transform_point3(origin), inv.transform_vector3(dir));
                let Some(h) = trace_object_ray(&e.lookup, o, d, Traversal::Hierarchical) else {
                    continue;
                };
                if best.is_none_or(|b| h.t < b.t) {
                    let center = DVec3::from(h.cell.map(|c| (f64::from(c) + 0.5) * s - 1.0));
                    best = Some(Pick {
                        object: e.object,
                        instance,
                        center,
                        t: h.t,
                    });
                }
            }
        }
        best
    }

    /// Applies the brush at pixel `(px, py)`: the stroke, or `None` when no editable voxel
    /// is under it.
    pub fn paint(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &mut GpuScene,
        camera: &Camera,
        px: u32,
        py: u32,
    ) -> Result<Option<Painted>> {
        let size = gpu_scene.screen;
        let Some(pick) = self.pick(&gpu_scene.scene, camera, px, py, size) else {
            return Ok(None);
        };
        let k = self.editable(pick.object)?;
        let level = self.objects[k].lookup.level;
        let t0 = Instant::now();
        let edit = self.settings.edit_at(pick.center, level);
        let c = self.stroke(ctx, gpu_scene, k, edit, true)?;
        ctx.wait_idle()?;
        let status = format!(
            "brush on object {}: +{} −{} voxels ({} blocks of {}³, {} words uploaded) in \
             {:.1} ms (journal {:.2} ms)",
            pick.object,
            c.report.added,
            c.report.removed,
            c.blocks,
            c.block_side,
            c.words,
            t0.elapsed().as_secs_f64() * 1e3,
            c.journal_ms
        );
        Ok(Some(Painted {
            object: pick.object,
            edit,
            status,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DAffine3;
    use ssbvb_gpu::scene::{LodPolicy, VoxelObject};
    use ssbvb_voxel::procedural::ProceduralModel;
    use ssbvb_voxel::progress::NoProgress;
    use std::sync::Arc;

    /// The filled ball inscribed in the grid at level 5, two instances: at the origin, and
    /// moved +3 x and scaled 0.5.
    fn scene() -> Scene {
        let set = ProceduralModel::FilledBall.voxels(5).unwrap();
        let (asset, _) = ssbvb_voxel::prepare::prepare_voxel_set(set, &NoProgress);
        Scene {
            objects: vec![VoxelObject {
                asset: Arc::new(asset),
                instances: vec![
                    DAffine3::IDENTITY,
                    DAffine3::from_translation(DVec3::new(3.0, 0.0, 0.0))
                        * DAffine3::from_scale(DVec3::splat(0.5)),
                ],
                lod: LodPolicy::Fixed(5),
            }],
            ..Default::default()
        }
    }

    #[test]
    fn the_pick_is_the_nearest_voxel_under_the_pixel_in_object_space() {
        let scene = scene();
        let brush = Brush::new(&scene, &[], &JournalOptions::off(), PathBuf::new());
        let size = (64, 64);
        // Looking down −z at the first instance: the centre pixel hits the ball's front.
        let cam = Camera::new(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO);
        let p = brush.pick(&scene, &cam, 32, 32, size).unwrap();
        assert_eq!((p.object, p.instance), (0, 0));
        // The front cell's centre is half a cell (1/32) inside the ball's surface at z = 1.
        assert!((p.center.z - (1.0 - 1.0 / 32.0)).abs() < 1e-9, "{p:?}");
        assert!(p.center.x.abs() < 0.07 && p.center.y.abs() < 0.07, "{p:?}");
        assert!((p.t - 3.0).abs() < 0.01, "{p:?}");
        // The second instance, seen along the same axis: object space is scaled by 2.
        let cam = Camera::new(DVec3::new(3.0, 0.0, 4.0), DVec3::new(3.0, 0.0, 0.0));
        let p = brush.pick(&scene, &cam, 32, 32, size).unwrap();
        assert_eq!((p.object, p.instance), (0, 1));
        assert!((p.center.z - (1.0 - 1.0 / 32.0)).abs() < 1e-9, "{p:?}");
        assert!((p.t - 3.5).abs() < 0.01, "{p:?}");
        // A corner pixel misses, and so does a pixel outside the view.
        assert_eq!(brush.pick(&scene, &cam, 0, 0, size), None);
        assert_eq!(brush.pick(&scene, &cam, 64, 32, size), None);
        // Nothing is editable when the object is skipped (animated).
        let none = Brush::new(&scene, &[0], &JournalOptions::off(), PathBuf::new());
        assert!(none.rooms().is_empty());
        assert_eq!(none.pick(&scene, &cam, 32, 32, size), None);
    }

    #[test]
    fn brush_settings_make_the_edit_of_their_mode_shape_and_radius() {
        let s = cell_size(6);
        let c = DVec3::new(0.1, -0.2, 0.3);
        let mut b = BrushSettings::default();
        assert_eq!(
            b.edit_at(c, 6),
            Edit::RemoveSphere {
                center: (0.1, -0.2, 0.3),
                radius: 6.0 * s
            }
        );
        b.mode = BrushMode::Add;
        b.shape = BrushShape::Cube;
        b.radius_voxels = 2.0;
        b.color = [2.0, 0.5, -1.0];
        let Edit::AddBox { min, max, color } = b.edit_at(c, 6) else {
            panic!("an added cube");
        };
        assert!((min.0 - (0.1 - 2.0 * s)).abs() < 1e-12 && (max.2 - (0.3 + 2.0 * s)).abs() < 1e-12);
        // Colours are clamped into [0, 1].
        assert_eq!(color, (1.0, 0.5, 0.0, 1.0));
        // A radius under half a voxel still covers one.
        b.radius_voxels = 0.0;
        let Edit::AddBox { min, max, .. } = b.edit_at(c, 6) else {
            panic!("an added cube");
        };
        assert!((max.0 - min.0 - s).abs() < 1e-12);
    }
}
