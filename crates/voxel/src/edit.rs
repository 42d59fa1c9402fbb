//! Brush edits of a voxel set (dynamic objects: carving and adding at run time or listed
//! in a scene file): spheres and boxes in object space that add cells (with a colour) or
//! remove them. A cell is inside a brush when its centre is. Added cells are solid (the
//! brush's interior too) with normals pointing out of the brush; cells of a brush outside
//! the grid are clipped and counted. The result is a new Morton-sorted voxel set, which the
//! GPU turns into the renderer's levels (`ssbvb_gpu_build::animated::Animator::stream`) or the
//! CPU prepares (`prepare_voxel_set`).

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::asset::LodLevel;
use crate::model::cell_size;
use crate::svo::{LevelVoxels, morton_decode, morton_encode};

/// The most cells one brush may cover (2^24): beyond, it is refused with its size.
pub const MAX_BRUSH_CELLS: u64 = 1 << 24;

/// One edit, in object space ([-1, 1]³).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Edit {
    /// Add the cells of a sphere, coloured `color` (linear RGBA).
    AddSphere {
        /// Centre.
        center: (f64, f64, f64),
        /// Radius.
        radius: f64,
        /// Linear RGBA.
        color: (f32, f32, f32, f32),
    },
    /// Remove the cells of a sphere.
    RemoveSphere {
        /// Centre.
        center: (f64, f64, f64),
        /// Radius.
        radius: f64,
    },
    /// Add the cells of a box, coloured `color`.
    AddBox {
        /// Minimum corner.
        min: (f64, f64, f64),
        /// Maximum corner.
        max: (f64, f64, f64),
        /// Linear RGBA.
        color: (f32, f32, f32, f32),
    },
    /// Remove the cells of a box.
    RemoveBox {
        /// Minimum corner.
        min: (f64, f64, f64),
        /// Maximum corner.
        max: (f64, f64, f64),
    },
}

/// What applying edits did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct EditReport {
    /// Cells added (not there before).
    pub added: u64,
    /// Cells removed.
    pub removed: u64,
    /// Brush cells outside the grid, left out.
    pub clipped: u64,
}

/// Why edits could not be applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EditError {
    /// A parameter is not finite, a radius negative, a box inverted, a colour outside [0, 1].
    #[error("edit {index}: {message}")]
    Invalid {
        /// Which edit.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// A brush covers too many cells.
    #[error("edit {index} covers {cells} cells at this level, more than {MAX_BRUSH_CELLS}")]
    TooLarge {
        /// Which edit.
        index: usize,
        /// Its cells.
        cells: u64,
    },
}

fn v3(t: (f64, f64, f64)) -> DVec3 {
    DVec3::new(t.0, t.1, t.2)
}

impl Edit {
    /// The brush's box and whether a point is inside, its normal at a point, its colour.
    fn shape(&self) -> (DVec3, DVec3) {
        match *self {
            Edit::AddSphere { center, radius, .. } | Edit::RemoveSphere { center, radius } => {
                (v3(center) - radius, v3(center) + radius)
            }
            Edit::AddBox { min, max, .. } | Edit::RemoveBox { min, max } => (v3(min), v3(max)),
        }
    }

    fn contains(&self, p: DVec3) -> bool {
        match *self {
            Edit::AddSphere { center, radius, .. } | Edit::RemoveSphere { center, radius } => {
                p.distance(v3(center)) <= radius
            }
            Edit::AddBox { min, max, .. } | Edit::RemoveBox { min, max } => {
                p.cmpge(v3(min)).all() && p.cmple(v3(max)).all()
            }
        }
    }

    fn normal(&self, p: DVec3) -> [f32; 3] {
        let n = match *self {
            Edit::AddSphere { center, .. } | Edit::RemoveSphere { center, .. } => p - v3(center),
            Edit::AddBox { min, max, .. } | Edit::RemoveBox { min, max } => {
                // Toward the nearest face.
                let (lo, hi) = (p - v3(min), v3(max) - p);
                let d = [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z];
                let k = (0..6).min_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap_or(0);
                let mut n = DVec3::ZERO;
                n[k % 3] = if k < 3 { -1.0 } else { 1.0 };
                n
            }
        };
        let n = n.normalize_or(DVec3::Z);
        [n.x as f32, n.y as f32, n.z as f32]
    }

    fn color(&self) -> Option<[f32; 4]> {
        match *self {
            Edit::AddSphere { color, .. } | Edit::AddBox { color, .. } => {
                Some([color.0, color.1, color.2, color.3])
            }
            _ => None,
        }
    }

    /// A message when a parameter is unusable.
    pub fn problem(&self) -> Option<String> {
        let (lo, hi) = self.shape();
        if !lo.is_finite() || !hi.is_finite() {
            return Some("centre, radius and corners must be finite".into());
        }
        if lo.cmpgt(hi).any() {
            return Some("a negative radius or a box with min above max".into());
        }
        if let Some(c) = self.color() {
            if !c.iter().all(|v| (0.0..=1.0).contains(v)) {
                return Some(format!("colour components must be in [0, 1], got {c:?}"));
            }
        }
        None
    }
}

/// A voxel's normal, colour and texture coordinate.
pub(crate) type Attrs = ([f32; 3], [f32; 4], [f32; 2]);

/// The cells of `level` whose centre may lie inside edit `index` (`e`), first and last per
/// axis (unclipped: they may lie outside the grid); an error when `e` is unusable or
/// covers more than [`MAX_BRUSH_CELLS`].
pub(crate) fn brush_cells(
    index: usize,
    e: &Edit,
    level: u32,
) -> Result<(glam::I64Vec3, glam::I64Vec3), EditError> {
    if let Some(message) = e.problem() {
        return Err(EditError::Invalid { index, message });
    }
    let s = cell_size(level);
    let (lo, hi) = e.shape();
    // Cells whose centre may be inside: centre −1 + (i + ½)s in [lo, hi].
    let first = ((lo + 1.0) / s - 0.5).ceil();
    let last = ((hi + 1.0) / s - 0.5).floor();
    let span = (last - first + 1.0).max(DVec3::ZERO);
    let count = span.x * span.y * span.z;
    if count > MAX_BRUSH_CELLS as f64 {
        return Err(EditError::TooLarge {
            index,
            cells: count as u64,
        });
    }
    Ok((first.as_i64vec3(), last.as_i64vec3()))
}

/// Applies edit `index` (`e`) to `cells` (code → attributes) at `level`, counting into
/// `report`; `cells` need only hold the cells of the brush's box.
pub(crate) fn apply_edit(
    cells: &mut BTreeMap<u64, Attrs>,
    index: usize,
    e: &Edit,
    level: u32,
    report: &mut EditReport,
) -> Result<(), EditError> {
    let n = 1i64 << level;
    let s = cell_size(level);
    let (f, l) = brush_cells(index, e, level)?;
    for z in f.z..=l.z {
        for y in f.y..=l.y {
            for x in f.x..=l.x {
                let p = (DVec3::new(x as f64, y as f64, z as f64) + 0.5) * s - 1.0;
                if !e.contains(p) {
                    continue;
                }
                if [x, y, z].iter().any(|&c| c < 0 || c >= n) {
                    report.clipped += 1;
                    continue;
                }
                let code = morton_encode([x as u32, y as u32, z as u32]);
                match e.color() {
                    Some(color) => {
                        let new = cells.insert(code, (e.normal(p), color, [0.0; 2]));
                        report.added += u64::from(new.is_none());
                    }
                    None => report.removed += u64::from(cells.remove(&code).is_some()),
                }
            }
        }
    }
    Ok(())
}

/// `voxels` with `edits` applied in order.
pub fn apply_edits(
    voxels: &LevelVoxels,
    edits: &[Edit],
) -> Result<(LevelVoxels, EditReport), EditError> {
    let mut report = EditReport::default();
    // code → (normal, colour, uv), in Morton order.
    let mut cells: BTreeMap<u64, Attrs> = voxels
        .codes
        .iter()
        .enumerate()
        .map(|(i, &c)| (c, (voxels.normals[i], voxels.colors[i], voxels.uvs[i])))
        .collect();
    for (index, e) in edits.iter().enumerate() {
        apply_edit(&mut cells, index, e, voxels.level, &mut report)?;
    }
    Ok((set_of(voxels.level, cells), report))
}

/// The voxel set of `cells` (which must come in Morton order, as a `BTreeMap` iterates).
pub(crate) fn set_of(level: u32, cells: impl IntoIterator<Item = (u64, Attrs)>) -> LevelVoxels {
    let mut out = LevelVoxels {
        level,
        ..Default::default()
    };
    for (code, (normal, color, uv)) in cells {
        out.codes.push(code);
        out.normals.push(normal);
        out.colors.push(color);
        out.uvs.push(uv);
    }
    out
}

/// A prepared level as a voxel set (the attributes as the point cloud stores them), to edit.
pub fn level_voxels(lod: &LodLevel) -> LevelVoxels {
    let v = &lod.point_cloud.voxels;
    LevelVoxels {
        level: lod.level,
        codes: v.iter().map(|p| morton_encode(p.cell())).collect(),
        normals: v.iter().map(|p| p.normal()).collect(),
        colors: v.iter().map(|p| p.color()).collect(),
        uvs: v.iter().map(|p| p.uv()).collect(),
    }
}

/// The cell of a code (for tests and reports).
pub fn cell_of(code: u64) -> [u32; 3] {
    morton_decode(code)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full(level: u32) -> LevelVoxels {
        let n = 1u32 << level;
        let mut codes: Vec<u64> = (0..n * n * n)
            .map(|i| morton_encode([i % n, (i / n) % n, i / (n * n)]))
            .collect();
        codes.sort_unstable();
        let len = codes.len();
        LevelVoxels {
            level,
            codes,
            normals: vec![[0.0, 1.0, 0.0]; len],
            colors: vec![[0.5; 4]; len],
            uvs: vec![[0.0; 2]; len],
        }
    }

    #[test]
    fn a_removed_sphere_takes_exactly_the_cells_whose_centre_it_holds() {
        let v = full(4); // 16³ cells of 0.125
        let e = Edit::RemoveSphere {
            center: (0.0, 0.0, 0.0),
            radius: 0.3,
        };
        let (out, r) = apply_edits(&v, &[e]).unwrap();
        // Brute force: centres within 0.3 of the origin.
        let s = 0.125;
        let inside = (0..16u32)
            .flat_map(|z| (0..16u32).flat_map(move |y| (0..16u32).map(move |x| [x, y, z])))
            .filter(|c| {
                let p = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * s + (s * 0.5 - 1.0);
                p.length() <= 0.3
            })
            .count() as u64;
        assert!(inside > 20);
        assert_eq!(
            r,
            EditReport {
                added: 0,
                removed: inside,
                clipped: 0
            }
        );
        assert_eq!(out.len() as u64, 4096 - inside);
        assert!(out.codes.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn an_added_box_colours_its_cells_clips_the_outside_and_points_out() {
        let empty = LevelVoxels {
            level: 3,
            ..Default::default()
        };
        // x from 0.6 to 1.4: cell centres 0.625, 0.875 inside the grid, 1.125 and 1.375
        // outside; y and z one cell each (centre 0.125).
        let e = Edit::AddBox {
            min: (0.6, 0.0, 0.0),
            max: (1.4, 0.25, 0.25),
            color: (1.0, 0.0, 0.0, 1.0),
        };
        let (out, r) = apply_edits(&empty, &[e]).unwrap();
        assert_eq!(
            r,
            EditReport {
                added: 2,
                removed: 0,
                clipped: 2
            }
        );
        let cells: Vec<[u32; 3]> = out.codes.iter().map(|&c| cell_of(c)).collect();
        assert_eq!(cells, vec![[6, 4, 4], [7, 4, 4]]);
        assert_eq!(out.colors, vec![[1.0, 0.0, 0.0, 1.0]; 2]);
        // Each cell's nearest box face is −X for the first, +X... (the box is 0.8 wide).
        assert_eq!(out.normals[0], [-1.0, 0.0, 0.0]);
        // Adding again adds nothing new; removing the same box takes both back.
        let (again, r2) = apply_edits(&out, &[e]).unwrap();
        assert_eq!((again.len(), r2.added), (2, 0));
        let rm = Edit::RemoveBox {
            min: (0.6, 0.0, 0.0),
            max: (1.4, 0.25, 0.25),
        };
        let (gone, r3) = apply_edits(&out, &[rm]).unwrap();
        assert_eq!((gone.len(), r3.removed, r3.clipped), (0, 2, 2));
    }

    #[test]
    fn unusable_edits_are_refused_with_their_index() {
        let v = full(2);
        let bad = [
            Edit::RemoveSphere {
                center: (f64::NAN, 0.0, 0.0),
                radius: 0.1,
            },
            Edit::RemoveSphere {
                center: (0.0, 0.0, 0.0),
                radius: -0.1,
            },
            Edit::AddBox {
                min: (0.5, 0.0, 0.0),
                max: (0.0, 1.0, 1.0),
                color: (1.0, 1.0, 1.0, 1.0),
            },
            Edit::AddSphere {
                center: (0.0, 0.0, 0.0),
                radius: 0.1,
                color: (2.0, 0.0, 0.0, 1.0),
            },
        ];
        for (i, e) in bad.iter().enumerate() {
            let err = apply_edits(
                &v,
                &[
                    Edit::RemoveBox {
                        min: (9.0, 9.0, 9.0),
                        max: (9.0, 9.0, 9.0),
                    },
                    *e,
                ],
            )
            .unwrap_err();
            assert!(
                matches!(err, EditError::Invalid { index: 1, .. }),
                "case {i}: {err}"
            );
        }
        let huge = Edit::AddBox {
            min: (-1.0, -1.0, -1.0),
            max: (1.0, 1.0, 1.0),
            color: (1.0, 1.0, 1.0, 1.0),
        };
        let big = LevelVoxels {
            level: 9,
            ..Default::default()
        };
        assert!(matches!(
            apply_edits(&big, &[huge]),
            Err(EditError::TooLarge { index: 0, .. })
        ));
    }
}
