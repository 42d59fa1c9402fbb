//! Conservative surface voxelization of triangle meshes: triangles binned into 32³ bricks,
//! bricks voxelized in parallel into per-thread scratch, voxels emitted Morton-sorted.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use super::attributes::{TriAttrs, gradient_26, sample, sanitize};
use super::geometry::{cell_estimate, for_each_cell};
use super::{MAX_VOXELS, VoxelSet, VoxelizeError, VoxelizeReport, check_level, half_cells};
use crate::model::{Material, Mesh, ObjectSpace};
use crate::progress::Progress;
use crate::svo::{LevelVoxels, morton_decode, morton_encode, normalize_or};

/// Log2 of the brick edge in cells: bricks are 32³ (or the whole grid below level 5).
const BRICK_LOG: u32 = 5;

/// Weight of a contribution with zero area (a triangle that only touches the cell, or a
/// degenerate one): far below any real area, so it only decides colour where nothing else
/// contributes.
const TOUCH_WEIGHT: f64 = 1e-9;

/// Object space of a mesh: the bounding box of the finite vertices referenced by its
/// triangles (indices in range). `None` when there is no such vertex.
pub fn mesh_object_space(mesh: &Mesh) -> Option<ObjectSpace> {
    mesh_bounds(mesh).map(|(min, max)| ObjectSpace::from_bounds(min, max))
}

/// The bounding box (model units) of the finite vertices the mesh's triangles reference.
pub fn mesh_bounds(mesh: &Mesh) -> Option<(DVec3, DVec3)> {
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for t in &mesh.triangles {
        for &i in t {
            let Some(p) = mesh.positions.get(i as usize).filter(|p| p.is_finite()) else {
                continue;
            };
            {
                let p = p.as_dvec3();
                min = min.min(p);
                max = max.max(p);
            }
        }
    }
    (min.x <= max.x).then_some((min, max))
}

/// Running sums of one cell in a brick.
#[derive(Clone, Copy, Default)]
struct Acc {
    normal: DVec3,
    area: f64,
    best_area: f64,
    best_normal: DVec3,
    weight: f64,
    color: [f64; 4],
    uv: [f64; 2],
}

/// Per-thread scratch for one brick: accumulators indexed by local Morton code, reset
/// lazily through an epoch stamp so a brick costs only what it touches.
struct Scratch {
    stamp: Vec<u32>,
    acc: Vec<Acc>,
    touched: Vec<u32>,
    epoch: u32,
}

impl Scratch {
    /// Makes room for bricks of `cells` cells (reallocates only when the size changes).
    fn ensure(&mut self, cells: usize) {
        if self.acc.len() != cells {
            *self = Scratch::new(cells);
        }
    }

    fn new(cells: usize) -> Scratch {
        Scratch {
            stamp: vec![0; cells],
            acc: vec![Acc::default(); cells],
            touched: Vec::new(),
            epoch: 0,
        }
    }
}

/// Voxels emitted by a run of bricks (structure of arrays, Morton-sorted).
#[derive(Default)]
pub(super) struct Chunk {
    codes: Vec<u64>,
    normals: Vec<[f32; 3]>,
    colors: Vec<[f32; 4]>,
    uvs: Vec<[f32; 2]>,
    /// Indices (within the chunk) of voxels that still need a normal.
    missing_normal: Vec<usize>,
}

/// Conservative surface voxelization of a triangle mesh on a level-`level` grid.
///
/// See the [module documentation](crate::voxelize) for the method. Fails when the level
/// exceeds [`MAX_LEVEL`](crate::asset::MAX_LEVEL), when no triangle has finite vertices, or
/// when the estimated voxel count exceeds [`MAX_VOXELS`].
pub fn voxelize_mesh(
    mesh: &Mesh,
    level: u32,
    progress: &dyn Progress,
) -> Result<VoxelSet, VoxelizeError> {
    voxelize_mesh_in(mesh, level, None, progress)
}

/// [`voxelize_mesh`] in a given object space (an animated mesh keeps the space of its
/// whole motion, so its voxels do not rescale from frame to frame); every vertex must map
/// into [-1, 1]³ there, else [`VoxelizeError::OutsideObjectSpace`]. `None`: the mesh's own
/// bounds ([`mesh_object_space`]).
pub fn voxelize_mesh_in(
    mesh: &Mesh,
    level: u32,
    space: Option<ObjectSpace>,
    progress: &dyn Progress,
) -> Result<VoxelSet, VoxelizeError> {
    let bricks = MeshBricks::new(mesh, level, MAX_VOXELS, space, progress)?;
    // Bricks go in batches so that only one batch of per-chunk output exists next to the
    // result, which is reserved from the estimate (untouched capacity costs no memory).
    let capacity = (bricks.estimate as usize).min(1 << 26);
    let mut voxels = LevelVoxels {
        level,
        codes: Vec::with_capacity(capacity),
        normals: Vec::with_capacity(capacity),
        colors: Vec::with_capacity(capacity),
        uvs: Vec::with_capacity(capacity),
    };
    let mut missing: Vec<usize> = Vec::new();
    progress.begin("voxelizing", bricks.bricks.len() as u64);
    for batch in bricks.bricks.chunks(4096) {
        let chunks: Vec<Chunk> = batch
            .par_chunks(16)
            .map(|run| {
                let c = bricks.voxelize_run(run);
                progress.advance(run.len() as u64);
                c
            })
            .collect();
        for c in chunks {
            c.append_to(&mut voxels, &mut missing);
        }
    }
    progress.end();
    voxels.codes.shrink_to_fit();
    voxels.normals.shrink_to_fit();
    voxels.colors.shrink_to_fit();
    voxels.uvs.shrink_to_fit();

    let mut report = bricks.report.clone();
    report.normal_fallbacks = missing.len() as u64;
    let object_space = bricks.object_space;
    let fixed = gradient_normals(&voxels, &missing, |q| voxels.find(q).is_some());
    for (i, normal) in fixed {
        voxels.normals[i] = normal;
    }
    Ok(VoxelSet {
        object_space,
        voxels,
        report,
    })
}

impl Chunk {
    /// Appends the chunk's voxels to `voxels` and the indices of those missing a normal to
    /// `missing`.
    pub(super) fn append_to(self, voxels: &mut LevelVoxels, missing: &mut Vec<usize>) {
        let base = voxels.codes.len();
        missing.extend(self.missing_normal.iter().map(|i| base + i));
        voxels.codes.extend_from_slice(&self.codes);
        voxels.normals.extend_from_slice(&self.normals);
        voxels.colors.extend_from_slice(&self.colors);
        voxels.uvs.extend_from_slice(&self.uvs);
    }
}

/// A mesh binned into the bricks of one voxelization: everything needed to voxelize any
/// run of bricks on its own (the whole grid at once, or region by region).
pub(crate) struct MeshBricks<'a> {
    mesh: &'a Mesh,
    /// Vertices in grid units.
    grid: Vec<DVec3>,
    /// (brick Morton code, triangle), sorted.
    pairs: Vec<(u64, u32)>,
    /// Every brick that some triangle overlaps, in Morton order, with its pairs.
    pub(super) bricks: Vec<(u64, Range<usize>)>,
    brick: BrickGeometry,
    /// Upper bound of the voxel count.
    pub(super) estimate: u64,
    /// Skipped and degenerate triangles (`normal_fallbacks` is left to the caller).
    pub(super) report: VoxelizeReport,
    /// The mesh's object space.
    pub(super) object_space: ObjectSpace,
}

impl<'a> MeshBricks<'a> {
    /// Maps the vertices to grid units, checks the triangles and the size (at most
    /// `max_voxels` by the upper-bound estimate), and bins the triangles into bricks.
    pub(super) fn new(
        mesh: &'a Mesh,
        level: u32,
        max_voxels: u64,
        space: Option<ObjectSpace>,
        progress: &dyn Progress,
    ) -> Result<Self, VoxelizeError> {
        check_level(level)?;
        let mut report = VoxelizeReport {
            triangles: mesh.triangles.len() as u64,
            ..Default::default()
        };
        let (lo, hi) = mesh_bounds(mesh)
            .ok_or_else(|| VoxelizeError::Empty("no triangle references a finite vertex".into()))?;
        let object_space = match space {
            Some(s) => {
                // Every referenced finite vertex inside [-1, 1]³ of the given space.
                let inside = |p: DVec3| s.to_object(p).abs().max_element() <= 1.0;
                if !(inside(lo) && inside(hi)) {
                    return Err(VoxelizeError::OutsideObjectSpace);
                }
                s
            }
            None => ObjectSpace::from_bounds(lo, hi),
        };

        // Vertices in grid units (f64): cell i covers [i, i+1].
        let hc = half_cells(level);
        let grid: Vec<DVec3> = mesh
            .positions
            .par_iter()
            .map(|p| (object_space.to_object(p.as_dvec3()) + DVec3::ONE) * hc)
            .collect();

        // Valid triangles (indices in range, all vertices finite).
        let mut valid: Vec<u32> = Vec::with_capacity(mesh.triangles.len());
        for (t, idx) in mesh.triangles.iter().enumerate() {
            if idx.iter().any(|&i| i as usize >= grid.len()) {
                report.skipped_bad_index += 1;
                continue;
            }
            let v = idx.map(|i| grid[i as usize]);
            if !v.iter().all(|p| p.is_finite()) {
                report.skipped_non_finite += 1;
                continue;
            }
            if (v[1] - v[0]).cross(v[2] - v[0]) == DVec3::ZERO {
                report.degenerate += 1;
            }
            valid.push(t as u32);
        }
        if valid.is_empty() {
            return Err(VoxelizeError::Empty(
                "no triangle with finite vertices".into(),
            ));
        }
        let tri = |t: u32| mesh.triangles[t as usize].map(|i| grid[i as usize]);

        // Refuse requests that cannot fit before allocating anything per voxel.
        let estimate: f64 = valid.par_iter().map(|&t| cell_estimate(&tri(t))).sum();
        let cells_total = (1u128 << (3 * level)) as f64;
        let estimate = estimate.min(cells_total) as u64;
        if estimate > max_voxels {
            return Err(VoxelizeError::TooLarge {
                level,
                estimate,
                limit: max_voxels,
            });
        }

        // Bin triangles into bricks.
        let brick_log = level.min(BRICK_LOG);
        let brick_cells = 1i64 << brick_log;
        let bricks_per_axis = 1i64 << (level - brick_log);
        let inv_brick = 1.0 / brick_cells as f64;
        progress.begin("binning triangles", valid.len() as u64);
        let mut pairs: Vec<(u64, u32)> = valid
            .par_chunks(4096)
            .flat_map_iter(|ts| {
                let mut out = Vec::new();
                for &t in ts {
                    let v = tri(t).map(|p| p * inv_brick);
                    for_each_cell(&v, [0; 3], [bricks_per_axis - 1; 3], |b, _| {
                        out.push((morton_encode(b.map(|c| c as u32)), t));
                    });
                }
                progress.advance(ts.len() as u64);
                out
            })
            .collect();
        pairs.par_sort_unstable();
        progress.end();

        // Group pairs by brick.
        let mut bricks: Vec<(u64, Range<usize>)> = Vec::new();
        let mut start = 0;
        for i in 1..=pairs.len() {
            if i == pairs.len() || pairs[i].0 != pairs[start].0 {
                bricks.push((pairs[start].0, start..i));
                start = i;
            }
        }
        Ok(Self {
            mesh,
            grid,
            pairs,
            bricks,
            brick: BrickGeometry {
                log: brick_log,
                cells: brick_cells,
            },
            estimate,
            report,
            object_space,
        })
    }

    /// Log2 of the brick edge in cells.
    pub(super) fn brick_log(&self) -> u32 {
        self.brick.log
    }

    fn tri(&self, t: u32) -> [DVec3; 3] {
        self.mesh.triangles[t as usize].map(|i| self.grid[i as usize])
    }

    fn attrs(&self, t: u32) -> TriAttrs<'a> {
        let mesh = self.mesh;
        let idx = mesh.triangles[t as usize];
        let m = mesh
            .triangle_materials
            .get(t as usize)
            .copied()
            .unwrap_or(0);
        let material = mesh.materials.get(m as usize).unwrap_or(&DEFAULT_MATERIAL);
        let n = mesh.positions.len();
        TriAttrs {
            material,
            uv: (mesh.uvs.len() == n).then(|| idx.map(|i| mesh.uvs[i as usize])),
            color: (mesh.colors.len() == n).then(|| idx.map(|i| mesh.colors[i as usize])),
        }
    }

    /// Voxelizes a run of bricks (in Morton order) on the calling thread.
    pub(super) fn voxelize_run(&self, run: &[(u64, Range<usize>)]) -> Chunk {
        let local_cells = 1usize << (3 * self.brick.log);
        SCRATCH.with(|cell| {
            let mut scratch = cell.borrow_mut();
            scratch.ensure(local_cells);
            let mut chunk = Chunk::default();
            for (code, range) in run {
                let tris = self.pairs[range.clone()]
                    .iter()
                    .map(|&(_, t)| (self.tri(t), self.attrs(t)));
                voxelize_brick(&mut scratch, &self.brick, *code, tris, &mut chunk);
            }
            chunk
        })
    }

    /// The Morton codes of the voxels of one brick (none when no triangle overlaps it).
    pub(super) fn brick_codes(&self, brick: u64) -> Vec<u64> {
        match self.bricks.binary_search_by_key(&brick, |b| b.0) {
            Ok(i) => self.voxelize_run(&self.bricks[i..=i]).codes,
            Err(_) => Vec::new(),
        }
    }
}

/// The material of triangles without one.
static DEFAULT_MATERIAL: Material = Material::DEFAULT;

/// Size of the bricks of one voxelization.
struct BrickGeometry {
    /// Log2 of the brick edge in cells.
    log: u32,
    /// Brick edge in cells.
    cells: i64,
}

thread_local! {
    /// Per-thread brick scratch, reused across bricks and calls (rayon's worker threads
    /// live for the whole process, so it is allocated once per thread and size).
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::new(0));
}

/// Voxelizes the triangles overlapping one brick and appends the brick's voxels, sorted by
/// Morton code, to `chunk`.
fn voxelize_brick<'a>(
    scratch: &mut Scratch,
    brick: &BrickGeometry,
    code: u64,
    tris: impl Iterator<Item = ([DVec3; 3], TriAttrs<'a>)>,
    chunk: &mut Chunk,
) {
    let origin = morton_decode(code).map(|c| i64::from(c) * brick.cells);
    let hi = origin.map(|o| o + brick.cells - 1);
    scratch.epoch = scratch.epoch.wrapping_add(1);
    if scratch.epoch == 0 {
        scratch.stamp.fill(0);
        scratch.epoch = 1;
    }
    scratch.touched.clear();
    for (v, a) in tris {
        let cross = (v[1] - v[0]).cross(v[2] - v[0]);
        let len = cross.length();
        let unit = if len > 0.0 && len.is_finite() {
            cross / len
        } else {
            DVec3::ZERO
        };
        for_each_cell(&v, origin, hi, |cell, part| {
            let local = morton_encode([0, 1, 2].map(|k| (cell[k] - origin[k]) as u32)) as usize;
            if scratch.stamp[local] != scratch.epoch {
                scratch.stamp[local] = scratch.epoch;
                scratch.acc[local] = Acc::default();
                scratch.touched.push(local as u32);
            }
            // Without per-vertex colours or uvs the colour is the material's: only the
            // area is needed, not the sample point.
            let (area, color, uv) = if a.uv.is_none() && a.color.is_none() {
                (part.area(), sanitize(a.material.base_color), [0.0; 2])
            } else {
                let (area, centroid) = part.area_centroid();
                let (color, uv) = sample(&v, &a, centroid);
                (area, color, uv)
            };
            let area = if area > 1e-14 && area.is_finite() {
                area
            } else {
                0.0
            };
            let acc = &mut scratch.acc[local];
            if unit != DVec3::ZERO {
                acc.normal += unit * area;
                acc.area += area;
                if area > acc.best_area {
                    acc.best_area = area;
                    acc.best_normal = unit;
                }
            }
            let wgt = area + TOUCH_WEIGHT;
            acc.weight += wgt;
            for (sum, c) in acc.color.iter_mut().zip(color) {
                *sum += f64::from(c) * wgt;
            }
            acc.uv[0] += uv[0] * wgt;
            acc.uv[1] += uv[1] * wgt;
        });
    }
    scratch.touched.sort_unstable();
    let base = code << (3 * brick.log);
    for &local in &scratch.touched {
        let acc = &scratch.acc[local as usize];
        chunk.codes.push(base | u64::from(local));
        let sum_len = acc.normal.length();
        let normal = if acc.area > 0.0 && sum_len > 1e-6 * acc.area {
            acc.normal / sum_len
        } else if acc.best_area > 0.0 {
            acc.best_normal
        } else {
            chunk.missing_normal.push(chunk.normals.len());
            DVec3::ZERO
        };
        chunk.normals.push(normal.to_array().map(|c| c as f32));
        let w = acc.weight;
        chunk
            .colors
            .push(acc.color.map(|c| (c / w).clamp(0.0, 1.0) as f32));
        chunk.uvs.push(acc.uv.map(|c| (c / w) as f32));
    }
}

/// The normal of each voxel in `missing`: the occupancy gradient of its 26-neighbourhood
/// (pointing away from the occupied side); where that is zero, the direction from the grid
/// centre; last resort +Z. `occupied` says whether a cell inside the grid is a voxel.
pub(super) fn gradient_normals(
    voxels: &LevelVoxels,
    missing: &[usize],
    occupied: impl Fn([u32; 3]) -> bool + Sync,
) -> Vec<(usize, [f32; 3])> {
    let n = 1i64 << voxels.level;
    missing
        .par_iter()
        .map(|&i| {
            let c = voxels.cell(i).map(i64::from);
            let occupied = |d: [i64; 3]| {
                let q = [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
                q.iter().all(|&x| (0..n).contains(&x)) && occupied(q.map(|x| x as u32))
            };
            let g = gradient_26(occupied);
            let from_center = c.map(|x| x as f64 + 0.5 - n as f64 * 0.5);
            (i, normalize_or(g, || from_center))
        })
        .collect()
}
