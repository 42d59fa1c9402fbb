//! Region-local brush edits of a dynamic object: only the blocks a brush touches are
//! recomputed, per level, and the result is a [`LevelPatch`] per level for the GPU
//! (`ssbvb_gpu_build::level_splice`) instead of a rebuild of the object's levels.
//!
//! The blocks are aligned cubes of the finest grid, of the smallest power-of-two side that
//! holds the largest brush's box, so a brush touches at most 2 × 2 × 2 of them; each is one
//! contiguous range of Morton codes. At a coarser level the same cubes shrink (one cell at
//! least), and a block's new voxels are the OR-merge of the finer level's, attributes
//! averaged as [`LevelVoxels::coarsen`] does: the edited levels equal the chain
//! [`crate::svo::build_lod_chain`] builds from the edited finest set, bit for bit.

use std::collections::{BTreeMap, BTreeSet};

use crate::asset::{LodLevel, VoxelAsset};
use crate::edit::{Edit, EditError, EditReport, apply_edit, brush_cells, set_of};
use crate::level_splice::{LevelMirror, LevelPatch, voxels_in};
use crate::prepare::{lookup_from_codes, point_cloud_of};
use crate::progress::NoProgress;
use crate::proxy::build_proxy;
use crate::svo::{LevelVoxels, build_lod_chain, morton_encode};

/// A dynamic object's levels kept on the CPU to edit them locally.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalEditor {
    /// `levels[l]` is level `l`; the last is the finest.
    levels: Vec<LevelMirror>,
}

/// What one call of [`LocalEditor::apply`] changed.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalEdit {
    /// Cells added, removed and clipped.
    pub report: EditReport,
    /// `patches[l]`: how level `l`'s streams change.
    pub patches: Vec<LevelPatch>,
    /// Side of the blocks at the finest level (cells).
    pub block_side: u32,
    /// Blocks touched at the finest level.
    pub blocks: usize,
    /// `undo[l]`: the blocks of level `l` as they were ([`LocalEditor::revert`]).
    undo: Vec<Vec<((u64, u64), LevelVoxels)>>,
}

impl LocalEditor {
    /// The editor of the levels built from `finest` (the object's levels must be the CPU
    /// preparation of the same set for the patches to apply to them).
    pub fn new(finest: LevelVoxels) -> Self {
        Self {
            levels: build_lod_chain(finest, &NoProgress)
                .into_iter()
                .map(LevelMirror::new)
                .collect(),
        }
    }

    /// The finest level's voxels as they are now.
    pub fn finest(&self) -> &LevelVoxels {
        &self.levels[self.levels.len() - 1].voxels
    }

    /// Level `l` as it is now.
    pub fn level(&self, l: usize) -> Option<&LevelMirror> {
        self.levels.get(l)
    }

    /// Applies `edits` in order (as [`crate::edit::apply_edits`] would to the finest set)
    /// and returns every level's patch. Nothing changes when an edit is refused.
    pub fn apply(&mut self, edits: &[Edit]) -> Result<LocalEdit, EditError> {
        let top = self.levels.len() - 1;
        let level = self.levels[top].voxels.level;
        let n = 1i64 << level;
        // Every edit's cells inside the grid (checked before anything changes).
        let mut boxes = Vec::new();
        for (index, e) in edits.iter().enumerate() {
            let (f, l) = brush_cells(index, e, level)?;
            let (f, l) = (
                f.max(glam::I64Vec3::ZERO),
                l.min(glam::I64Vec3::splat(n - 1)),
            );
            if f.cmple(l).all() {
                boxes.push((f, l));
            }
        }
        let side = boxes
            .iter()
            .map(|(f, l)| (*l - *f + 1).max_element() as u64)
            .max()
            .unwrap_or(1)
            .next_power_of_two() as i64;
        let mut origins = BTreeSet::new();
        for (f, l) in &boxes {
            for z in f.z / side..=l.z / side {
                for y in f.y / side..=l.y / side {
                    for x in f.x / side..=l.x / side {
                        origins.insert([x, y, z].map(|c| (c * side) as u32));
                    }
                }
            }
        }
        let ranges = |origins: &BTreeSet<[u32; 3]>, side: u64| -> Vec<(u64, u64)> {
            let mut r: Vec<(u64, u64)> = origins
                .iter()
                .map(|&o| (morton_encode(o), morton_encode(o) + side.pow(3)))
                .collect();
            r.sort_unstable();
            r
        };
        let finest_ranges = ranges(&origins, side as u64);

        // The finest blocks' cells, edited.
        let finest = &self.levels[top].voxels;
        let mut cells = BTreeMap::new();
        for &r in &finest_ranges {
            let v = voxels_in(finest, r);
            for i in 0..v.len() {
                cells.insert(v.codes[i], (v.normals[i], v.colors[i], v.uvs[i]));
            }
        }
        let mut report = EditReport::default();
        for (index, e) in edits.iter().enumerate() {
            apply_edit(&mut cells, index, e, level, &mut report)?;
        }
        let contents: Vec<((u64, u64), LevelVoxels)> = finest_ranges
            .iter()
            .map(|&r| {
                (
                    r,
                    set_of(level, cells.range(r.0..r.1).map(|(&c, &a)| (c, a))),
                )
            })
            .collect();

        let mut undo = vec![keep(&self.levels[top], &contents)];
        let mut patches = vec![self.levels[top].splice(&contents)];
        for l in (0..top).rev() {
            let shift = top - l;
            let side_l = ((side as u64) >> shift).max(1);
            let origins_l: BTreeSet<[u32; 3]> = origins
                .iter()
                .map(|o| o.map(|c| (c >> shift) & !(side_l as u32 - 1)))
                .collect();
            let finer = &self.levels[l + 1].voxels;
            let contents: Vec<((u64, u64), LevelVoxels)> = ranges(&origins_l, side_l)
                .into_iter()
                .map(|r| (r, voxels_in(finer, (r.0 << 3, r.1 << 3)).coarsen()))
                .collect();
            undo.push(keep(&self.levels[l], &contents));
            patches.push(self.levels[l].splice(&contents));
        }
        patches.reverse();
        undo.reverse();
        Ok(LocalEdit {
            report,
            patches,
            block_side: side as u32,
            blocks: finest_ranges.len(),
            undo,
        })
    }

    /// Undoes `edit`, the last edit applied (or the last [`LocalEditor::revert`]), by
    /// splicing its blocks' old content back: every level is restored exactly, and the
    /// result is the inverse edit — its patches take the GPU's rooms back, and reverting it
    /// in turn redoes `edit`. It touches the blocks `edit` touched, so undoing a click
    /// costs what the click cost. Also used when a click's patches could not reach the GPU
    /// (a room too small, a device error).
    pub fn revert(&mut self, edit: &LocalEdit) -> LocalEdit {
        let mut undo = Vec::with_capacity(self.levels.len());
        let mut patches = Vec::with_capacity(self.levels.len());
        for (level, old) in self.levels.iter_mut().zip(&edit.undo) {
            undo.push(keep(level, old));
            patches.push(level.splice(old));
        }
        LocalEdit {
            report: EditReport {
                added: edit.report.removed,
                removed: edit.report.added,
                clipped: edit.report.clipped,
            },
            patches,
            block_side: edit.block_side,
            blocks: edit.blocks,
            undo,
        }
    }

    /// The asset of the levels as they are now (point clouds, lookups and proxies built
    /// from the editor's levels, not rebuilt from the finest: they are the same chain),
    /// in `object_space`. What the viewer saves.
    pub fn asset(&self, object_space: crate::model::ObjectSpace) -> VoxelAsset {
        let lods = self
            .levels
            .iter()
            .map(|m| {
                let lookup = lookup_from_codes(m.voxels.level, &m.voxels.codes);
                LodLevel {
                    level: m.voxels.level,
                    point_cloud: point_cloud_of(&m.voxels),
                    proxy: build_proxy(&lookup),
                    lookup,
                }
            })
            .collect();
        VoxelAsset { object_space, lods }
    }
}

/// The voxels of `level` in the blocks of `contents`, to undo their splice.
fn keep(
    level: &LevelMirror,
    contents: &[((u64, u64), LevelVoxels)],
) -> Vec<((u64, u64), LevelVoxels)> {
    contents
        .iter()
        .map(|(r, _)| (*r, voxels_in(&level.voxels, *r)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asset::VoxelAsset;
    use crate::edit::apply_edits;
    use crate::level_splice::asset_streams;
    use crate::lookup::SparseLookup;
    use crate::model::ObjectSpace;
    use crate::prepare::prepare_voxel_set;
    use crate::svo::morton_decode;
    use crate::voxelize::VoxelSet;

    /// A sphere shell at `level`, attributes from the position.
    fn shell(level: u32) -> LevelVoxels {
        let n = 1u32 << level;
        let c = f64::from(n) / 2.0;
        let mut v = LevelVoxels {
            level,
            ..Default::default()
        };
        let mut codes: Vec<u64> = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let d = [x, y, z].map(|a| f64::from(a) + 0.5 - c);
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if (r - 0.35 * f64::from(n)).abs() < 0.9 {
                        codes.push(morton_encode([x, y, z]));
                    }
                }
            }
        }
        codes.sort_unstable();
        for code in codes {
            let p = morton_decode(code).map(|a| (a as f32 + 0.5) / n as f32);
            v.codes.push(code);
            v.normals.push([p[0] - 0.5, p[1] - 0.5, p[2] - 0.5]);
            v.colors.push([p[0], p[1], p[2], 1.0]);
            v.uvs.push([p[0], p[1]]);
        }
        v
    }

    fn prepared(v: LevelVoxels) -> VoxelAsset {
        let set = VoxelSet {
            object_space: ObjectSpace {
                center: glam::DVec3::ZERO,
                scale: 1.0,
            },
            voxels: v,
            report: Default::default(),
        };
        prepare_voxel_set(set, &NoProgress).0
    }

    /// Local edits equal the whole-set edit, and their patches turn the prepared streams of
    /// the old set into those of the edited set exactly, at every level.
    fn check(level: u32, edits: &[Edit]) -> LocalEdit {
        let before = shell(level);
        let (expected, report) = apply_edits(&before, edits).unwrap();
        let mut editor = LocalEditor::new(before.clone());
        let edit = editor.apply(edits).unwrap();
        assert_eq!(edit.report, report);
        assert_eq!(editor.finest(), &expected);
        let old = asset_streams(&prepared(before));
        let new = asset_streams(&prepared(expected.clone()));
        assert_eq!(edit.patches.len(), new.len());
        for (l, p) in edit.patches.iter().enumerate() {
            assert_eq!(p.level, l as u32);
            assert_eq!(p.apply_colors(&old[l].0), new[l].0, "level {l} colours");
            assert_eq!(p.apply_normals(&old[l].1), new[l].1, "level {l} normals");
            assert_eq!(p.apply_nodes(&old[l].2), new[l].2, "level {l} nodes");
        }
        // The mirror of every level is the chain of the edited set.
        let chain = build_lod_chain(expected, &NoProgress);
        for (l, v) in chain.into_iter().enumerate() {
            assert_eq!(editor.level(l).unwrap(), &LevelMirror::new(v), "level {l}");
        }
        edit
    }

    #[test]
    fn carving_adding_and_boxes_patch_every_level_exactly() {
        let s = crate::model::cell_size(6);
        let e = check(
            6,
            &[
                Edit::RemoveSphere {
                    center: (0.7, 0.0, 0.0),
                    radius: 4.0 * s,
                },
                Edit::AddSphere {
                    center: (0.0, 0.0, 0.0),
                    radius: 5.0 * s,
                    color: (0.9, 0.1, 0.1, 1.0),
                },
                Edit::AddBox {
                    min: (-0.8, 0.5, -0.1),
                    max: (-0.6, 0.7, 0.1),
                    color: (0.1, 0.2, 0.9, 1.0),
                },
                Edit::RemoveBox {
                    min: (-0.05, -0.05, -0.15),
                    max: (0.05, 0.05, 0.15),
                },
            ],
        );
        assert!(
            e.report.added > 100 && e.report.removed > 50,
            "{:?}",
            e.report
        );
        // The largest brush box is 11 cells across (the added ball, radius 5 cells).
        assert_eq!(e.block_side, 16);
        // The blocks stay few: far fewer than the 64 blocks of 16³ in the grid.
        assert!(e.blocks <= 4 * 8, "{}", e.blocks);
    }

    #[test]
    fn edits_across_the_grid_centre_and_at_its_border_patch_exactly() {
        let s = crate::model::cell_size(5);
        // Centred on the grid's centre: 8 blocks, in different root subtrees.
        let e = check(
            5,
            &[Edit::AddSphere {
                center: (0.0, 0.0, 0.0),
                radius: 3.0 * s,
                color: (1.0, 1.0, 0.0, 1.0),
            }],
        );
        assert_eq!(e.blocks, 8);
        // Half outside the grid: clipped and counted.
        let e = check(
            5,
            &[Edit::AddBox {
                min: (0.9, 0.9, 0.9),
                max: (1.3, 1.3, 1.3),
                color: (1.0, 1.0, 1.0, 1.0),
            }],
        );
        assert!(e.report.clipped > 0 && e.report.added > 0, "{:?}", e.report);
        // Wholly outside: nothing changes, every patch keeps its level.
        let e = check(
            5,
            &[Edit::RemoveSphere {
                center: (3.0, 3.0, 3.0),
                radius: 0.5,
            }],
        );
        assert_eq!((e.blocks, e.report.removed), (0, 0));
        assert!(
            e.patches
                .iter()
                .all(|p| p.old_voxels == p.voxels && p.colors.is_empty())
        );
        // Removing everything leaves empty levels with a root.
        let e = check(
            4,
            &[Edit::RemoveBox {
                min: (-2.0, -2.0, -2.0),
                max: (2.0, 2.0, 2.0),
            }],
        );
        assert_eq!(e.patches[4].voxels, 0);
        assert_eq!(
            e.patches[4].nodes as usize,
            SparseLookup::default().node_count()
        );
    }

    #[test]
    fn a_refused_edit_changes_nothing() {
        let mut editor = LocalEditor::new(shell(4));
        let before = editor.clone();
        let err = editor
            .apply(&[
                Edit::RemoveSphere {
                    center: (0.0, 0.0, 0.0),
                    radius: 0.2,
                },
                Edit::RemoveSphere {
                    center: (0.0, f64::NAN, 0.0),
                    radius: 0.2,
                },
            ])
            .unwrap_err();
        assert!(matches!(err, EditError::Invalid { index: 1, .. }), "{err}");
        assert_eq!(editor, before);
        // An applied edit reverted (its patches could not be spliced) restores every level.
        let s = crate::model::cell_size(4);
        let edit = editor
            .apply(&[Edit::AddSphere {
                center: (0.3, 0.0, 0.0),
                radius: 3.0 * s,
                color: (1.0, 0.0, 0.0, 1.0),
            }])
            .unwrap();
        assert!(edit.report.added > 0);
        assert_ne!(editor, before);
        editor.revert(&edit);
        assert_eq!(editor, before);
    }

    #[test]
    fn a_sequence_of_edits_stays_exact() {
        let level = 5;
        let s = crate::model::cell_size(level);
        let mut editor = LocalEditor::new(shell(level));
        let mut expected = shell(level);
        for k in 0..6 {
            let t = f64::from(k) * 0.3 - 0.75;
            let e = if k % 2 == 0 {
                Edit::RemoveSphere {
                    center: (t, 0.2, 0.6),
                    radius: 3.0 * s,
                }
            } else {
                Edit::AddSphere {
                    center: (0.1, t, -0.6),
                    radius: 2.0 * s,
                    color: (0.2, 0.8, 0.2, 1.0),
                }
            };
            editor.apply(&[e]).unwrap();
            expected = apply_edits(&expected, &[e]).unwrap().0;
        }
        let chain = build_lod_chain(expected, &NoProgress);
        for (l, v) in chain.into_iter().enumerate() {
            assert_eq!(editor.level(l).unwrap(), &LevelMirror::new(v), "level {l}");
        }
    }

    /// Undo and redo as a stack: each revert's patches turn the streams of the state
    /// before it into those of the state after it (the whole-set preparation of each is
    /// the oracle), reverting the inverse redoes, and the saved asset of every state is
    /// its whole-set preparation.
    #[test]
    fn undo_and_redo_patch_the_streams_back_and_forth_exactly() {
        let s = crate::model::cell_size(5);
        let strokes = [
            Edit::RemoveSphere {
                center: (0.7, 0.0, 0.0),
                radius: 4.0 * s,
            },
            Edit::AddBox {
                min: (-0.3, -0.2, 0.1),
                max: (0.1, 0.2, 0.4),
                color: (0.2, 0.8, 0.3, 1.0),
            },
            Edit::AddSphere {
                center: (0.65, 0.05, 0.0),
                radius: 2.0 * s,
                color: (0.9, 0.1, 0.1, 1.0),
            },
        ];
        let mut editor = LocalEditor::new(shell(5));
        let mut states = vec![editor.finest().clone()];
        let mut done = Vec::new();
        for e in &strokes {
            done.push(editor.apply(&[*e]).unwrap());
            states.push(editor.finest().clone());
        }
        let streams = |v: &LevelVoxels| asset_streams(&prepared(v.clone()));
        let space = ObjectSpace {
            center: glam::DVec3::ZERO,
            scale: 1.0,
        };
        let patched = |patches: &[LevelPatch], from: &LevelVoxels, to: &LevelVoxels| {
            let (old, new) = (streams(from), streams(to));
            for (l, p) in patches.iter().enumerate() {
                assert_eq!(p.apply_colors(&old[l].0), new[l].0, "level {l} colours");
                assert_eq!(p.apply_normals(&old[l].1), new[l].1, "level {l} normals");
                assert_eq!(p.apply_nodes(&old[l].2), new[l].2, "level {l} nodes");
            }
        };
        // Undo the last two strokes.
        let mut redo = Vec::new();
        for k in [3, 2] {
            let inverse = editor.revert(&done.pop().unwrap());
            assert_eq!(editor.finest(), &states[k - 1]);
            patched(&inverse.patches, &states[k], &states[k - 1]);
            assert_eq!(editor.asset(space), prepared(states[k - 1].clone()));
            redo.push(inverse);
        }
        // Redo one: the state after the second stroke, its report the stroke's.
        let again = editor.revert(&redo.pop().unwrap());
        assert_eq!(editor.finest(), &states[2]);
        patched(&again.patches, &states[1], &states[2]);
        let (_, report) = apply_edits(&states[1], &strokes[1..2]).unwrap();
        assert_eq!(again.report, report);
        assert_eq!(editor.asset(space), prepared(states[2].clone()));
        // Undo everything left: the shell as it was.
        editor.revert(&again);
        editor.revert(&done.pop().unwrap());
        assert_eq!(editor.finest(), &states[0]);
    }
}
