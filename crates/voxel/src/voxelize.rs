//! Conservative surface voxelization of meshes and resampling of voxel models.
//!
//! # Meshes
//!
//! A cell is set when its closed box overlaps a triangle (the separating axis test of
//! Akenine-Möller, in f64): the voxelization is *conservative*, so a triangle lying exactly
//! on a cell face sets the cells on both sides and one touching a cell corner sets all
//! eight. The work is organised so that no dense 2^L³ grid ever exists:
//!
//! 1. Vertices are mapped to grid units (`g = (object + 1) · 2^L / 2`, cell `i` = `[i, i+1]`,
//!    the exact [`ObjectSpace`] convention; the power-of-two factor is exact in f64).
//! 2. The grid is cut into bricks of 32³ cells. Each triangle is binned into the bricks
//!    it overlaps (the same cell walk and test, at brick scale), and the (brick, triangle)
//!    pairs are sorted.
//! 3. Bricks are processed in parallel in Morton order. Inside a brick a triangle is walked
//!    row by row and column by column along its dominant normal axis: the triangle is
//!    clipped to the row slab, then to the column slab, and the clipped polygon's depth
//!    range gives the few candidate cells of the column. A candidate is kept when the
//!    separating axis test says so, or (a shortcut that skips the test) when the triangle
//!    part clipped to it has its vertex mean well inside the cell, which proves overlap.
//!    That part also gives the triangle's area inside the cell and its centroid, which
//!    weight and place the attribute samples.
//! 4. A brick's cells accumulate in a per-thread scratch of 32³ entries indexed by local
//!    Morton code (only touched entries are reset), and are emitted sorted, so the
//!    concatenated output is globally Morton-sorted without a global sort of the voxels.
//!
//! Per voxel: normal = area-weighted sum of the unit face normals of the triangles inside
//! the cell, normalized; where that cancels (two opposite faces in one cell) the normal of
//! the triangle with the largest area in the cell; where no triangle has a normal (only
//! degenerate ones touched the cell) the occupancy gradient of the 26-neighbourhood; last
//! resort +Z. Colour = material base colour × texture at the interpolated uv × vertex
//! colour, sampled at the centroid of each triangle's part in the cell and averaged with
//! area weights (degenerate contributions get a tiny weight, so they only count where
//! nothing else does). Degenerate triangles (segments, points) still set every cell they
//! touch; triangles with a non-finite vertex or an out-of-range index are skipped and
//! counted in [`VoxelizeReport`].
//!
//! # Voxel models
//!
//! The union of the unit cubes is fitted into object space; a target cell is occupied when
//! it overlaps a source cube with positive volume. The cell ranges are computed in exact
//! integer arithmetic so that boundaries that coincide (the model's centre, aligned
//! resolutions) never produce sliver cells from rounding. See [`VoxelFill`] for which
//! occupied cells are kept.

use std::collections::HashMap;
use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::asset::MAX_LEVEL;
use crate::model::{Material, Mesh, ObjectSpace, Texture, VoxelModel};
use crate::progress::Progress;
use crate::svo::{LevelVoxels, morton_decode, morton_encode, normalize_or};

/// Most voxels (or candidate cells) one voxelization may produce. Above it the request is
/// refused up front instead of exhausting memory (each voxel costs ~44 bytes while being
/// built, plus its point cloud and lookup).
pub const MAX_VOXELS: u64 = 1 << 28;

/// Log2 of the brick edge in cells: bricks are 32³ (or the whole grid below level 5).
const BRICK_LOG: u32 = 5;

/// Tolerance, in cells, by which candidate ranges and clip slabs are widened so that
/// rounding never drops a cell the exact separating-axis test would keep. Candidates are
/// always confirmed (by that test, or by a point of the triangle strictly inside the
/// cell), so the tolerance adds work, never voxels.
const EPS: f64 = 1e-7;

/// Weight of a contribution with zero area (a triangle that only touches the cell, or a
/// degenerate one): far below any real area, so it only decides colour where nothing else
/// contributes.
const TOUCH_WEIGHT: f64 = 1e-9;

/// A voxelization result: the finest level of an asset before the LOD chain is built.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelSet {
    /// How the model's coordinates map into object space.
    pub object_space: ObjectSpace,
    /// The occupied cells with attributes (Morton-sorted).
    pub voxels: LevelVoxels,
    /// What was skipped or patched on the way.
    pub report: VoxelizeReport,
}

/// Counts of what the voxelizer met: inputs it skipped and fallbacks it took.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct VoxelizeReport {
    /// Triangles in the mesh (0 for voxel models).
    pub triangles: u64,
    /// Triangles skipped because a vertex is NaN or infinite.
    pub skipped_non_finite: u64,
    /// Triangles skipped because an index is out of range.
    pub skipped_bad_index: u64,
    /// Zero-area triangles (segments or points): voxelized, but without a normal.
    pub degenerate: u64,
    /// Voxels of the source model (0 for meshes).
    pub source_voxels: u64,
    /// Voxels whose normal came from the occupancy gradient or the fixed fallback because
    /// no triangle in them had a usable normal.
    pub normal_fallbacks: u64,
}

/// Which occupied cells a voxel-model resampling keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum VoxelFill {
    /// Only occupied cells with at least one unoccupied face neighbour (or on the grid
    /// border): the visible boundary of the union, as for meshes. Upsampling a model keeps
    /// a surface-sized voxel count (a 21³ model at level 12 would otherwise be billions of
    /// interior cells that no ray can reach).
    #[default]
    Shell,
    /// Every occupied cell. Refused with [`VoxelizeError::TooLarge`] when that exceeds
    /// [`MAX_VOXELS`].
    Solid,
}

/// Why a voxelization could not be done.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum VoxelizeError {
    /// The requested level is above what the asset format can address or what the caller
    /// allows.
    #[error("voxelization level {level} is above the maximum level {max}")]
    LevelTooHigh {
        /// Requested level.
        level: u32,
        /// Highest level allowed.
        max: u32,
    },
    /// Nothing to voxelize.
    #[error("the model has nothing to voxelize: {0}")]
    Empty(String),
    /// The result would exceed [`MAX_VOXELS`].
    #[error(
        "level {level} would produce about {estimate} voxels, more than the limit of {limit}; choose a lower level"
    )]
    TooLarge {
        /// Requested level.
        level: u32,
        /// Estimated (upper bound) voxel count.
        estimate: u64,
        /// The limit.
        limit: u64,
    },
}

// ---------------------------------------------------------------------------------------
// Geometry: separating axis test and polygon clipping
// ---------------------------------------------------------------------------------------

/// Whether triangle `tri` overlaps the closed axis-aligned box of centre `center` and half
/// edge `half` (Akenine-Möller's separating axis test, 13 axes). Touching counts as
/// overlapping. Degenerate triangles (segments, points) are handled: their vanishing axes
/// separate nothing, and the remaining axes are exactly the segment/box (or point/box) test.
pub fn triangle_box_overlap(tri: &[DVec3; 3], center: DVec3, half: f64) -> bool {
    let v = [tri[0] - center, tri[1] - center, tri[2] - center];
    // Box face normals: the triangle's bounding box against the box.
    let min = v[0].min(v[1]).min(v[2]);
    let max = v[0].max(v[1]).max(v[2]);
    if min.max_element() > half || max.min_element() < -half {
        return false;
    }
    // Cross products of the triangle edges with the box axes.
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    for e in edges {
        for k in 0..3 {
            // axis = unit_k × e
            let axis = match k {
                0 => DVec3::new(0.0, -e.z, e.y),
                1 => DVec3::new(e.z, 0.0, -e.x),
                _ => DVec3::new(-e.y, e.x, 0.0),
            };
            let p0 = axis.dot(v[0]);
            let p1 = axis.dot(v[1]);
            let p2 = axis.dot(v[2]);
            let r = half * (axis.x.abs() + axis.y.abs() + axis.z.abs());
            if p0.min(p1).min(p2) > r || p0.max(p1).max(p2) < -r {
                return false;
            }
        }
    }
    // The triangle's plane.
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let d = n.dot(v[0]);
    let r = half * (n.x.abs() + n.y.abs() + n.z.abs());
    d.abs() <= r
}

/// A convex polygon (a triangle clipped by up to six planes has at most 9 vertices).
#[derive(Clone, Copy)]
struct Poly {
    n: usize,
    p: [DVec3; 10],
}

impl Poly {
    fn triangle(t: &[DVec3; 3]) -> Poly {
        let mut p = [DVec3::ZERO; 10];
        p[..3].copy_from_slice(t);
        Poly { n: 3, p }
    }

    /// Clips to the closed slab `lo <= x[axis] <= hi`.
    fn clip_slab(&self, axis: usize, lo: f64, hi: f64) -> Poly {
        self.clip_half(axis, hi, 1.0).clip_half(axis, -lo, -1.0)
    }

    /// Keeps the part with `sign · x[axis] <= bound` (Sutherland–Hodgman, closed).
    fn clip_half(&self, axis: usize, bound: f64, sign: f64) -> Poly {
        let mut out = Poly {
            n: 0,
            p: [DVec3::ZERO; 10],
        };
        let mut push = |q: DVec3| {
            if out.n < out.p.len() {
                out.p[out.n] = q;
                out.n += 1;
            }
        };
        match self.n {
            0 => {}
            1 => {
                if sign * self.p[0][axis] - bound <= 0.0 {
                    push(self.p[0]);
                }
            }
            n => {
                for i in 0..n {
                    let a = self.p[i];
                    let b = self.p[(i + 1) % n];
                    let da = sign * a[axis] - bound;
                    let db = sign * b[axis] - bound;
                    if da <= 0.0 {
                        push(a);
                    }
                    if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
                        let t = da / (da - db);
                        let mut q = a + (b - a) * t;
                        // Land exactly on the plane so later range tests see it there.
                        q[axis] = sign * bound;
                        push(q);
                    }
                }
            }
        }
        out
    }

    fn range(&self, axis: usize) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for q in &self.p[..self.n] {
            lo = lo.min(q[axis]);
            hi = hi.max(q[axis]);
        }
        (lo, hi)
    }

    /// Mean of the vertices (inside the polygon, as it is convex).
    fn mean(&self) -> DVec3 {
        self.p[..self.n].iter().copied().sum::<DVec3>() / self.n.max(1) as f64
    }

    /// Area of the (planar, convex) polygon.
    fn area(&self) -> f64 {
        let pts = &self.p[..self.n];
        let mut sum = DVec3::ZERO;
        for i in 1..self.n.saturating_sub(1) {
            sum += (pts[i] - pts[0]).cross(pts[i + 1] - pts[0]);
        }
        0.5 * sum.length()
    }

    /// Area and area centroid; for a polygon of (near) zero area, the vertex mean.
    fn area_centroid(&self) -> (f64, DVec3) {
        if self.n == 0 {
            return (0.0, DVec3::ZERO);
        }
        let pts = &self.p[..self.n];
        let mean = self.mean();
        let mut area = 0.0;
        let mut c = DVec3::ZERO;
        for i in 1..self.n.saturating_sub(1) {
            let a = 0.5 * (pts[i] - pts[0]).cross(pts[i + 1] - pts[0]).length();
            area += a;
            c += (pts[0] + pts[i] + pts[i + 1]) * (a / 3.0);
        }
        if area > 1e-14 && c.is_finite() {
            (area, c / area)
        } else {
            (0.0, mean)
        }
    }
}

/// Lowest cell index whose closed box `[i, i+1]` may touch coordinate `x` (widened by EPS).
fn cell_lo(x: f64) -> i64 {
    (x - EPS).ceil() as i64 - 1
}

/// Highest cell index whose closed box may touch coordinate `x` (widened by EPS).
fn cell_hi(x: f64) -> i64 {
    (x + EPS).floor() as i64
}

/// The axis to walk in depth: the dominant normal axis, or for a degenerate triangle the
/// axis of its largest extent (so a segment becomes a few long columns).
fn depth_axis(t: &[DVec3; 3]) -> usize {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    let v = if n.max_element() > 0.0 {
        n
    } else {
        t[0].max(t[1]).max(t[2]) - t[0].min(t[1]).min(t[2])
    };
    if v.x >= v.y && v.x >= v.z {
        0
    } else if v.y >= v.z {
        1
    } else {
        2
    }
}

/// Calls `f(cell, part)` for every unit cell with index in `lo..=hi` (per axis) whose
/// closed box overlaps the triangle, where `part` is the triangle clipped to the cell.
fn for_each_cell(tri: &[DVec3; 3], lo: [i64; 3], hi: [i64; 3], mut f: impl FnMut([i64; 3], &Poly)) {
    let w = depth_axis(tri);
    let a = (w + 1) % 3;
    let b = (w + 2) % 3;
    let full = Poly::triangle(tri);
    let (amin, amax) = full.range(a);
    for i in cell_lo(amin).max(lo[a])..=cell_hi(amax).min(hi[a]) {
        let row = full.clip_slab(a, i as f64 - EPS, (i + 1) as f64 + EPS);
        if row.n == 0 {
            continue;
        }
        let (bmin, bmax) = row.range(b);
        for j in cell_lo(bmin).max(lo[b])..=cell_hi(bmax).min(hi[b]) {
            let col = row.clip_slab(b, j as f64 - EPS, (j + 1) as f64 + EPS);
            if col.n == 0 {
                continue;
            }
            let (wmin, wmax) = col.range(w);
            for k in cell_lo(wmin).max(lo[w])..=cell_hi(wmax).min(hi[w]) {
                let mut cell = [0i64; 3];
                cell[a] = i;
                cell[b] = j;
                cell[w] = k;
                let center = DVec3::new(
                    cell[0] as f64 + 0.5,
                    cell[1] as f64 + 0.5,
                    cell[2] as f64 + 0.5,
                );
                let part = col.clip_slab(w, k as f64 - EPS, (k + 1) as f64 + EPS);
                if part.n == 0 {
                    continue;
                }
                // The vertex mean of the clipped part is a point of the triangle; when it
                // lies well inside the cell the overlap is certain and the separating
                // axis test (the exact arbiter for the near-boundary cases) is skipped.
                let mean = part.mean();
                let inside = (0..3).all(|q| {
                    let c = cell[q] as f64;
                    mean[q] > c + 1e-6 && mean[q] < c + 1.0 - 1e-6
                });
                if inside || triangle_box_overlap(tri, center, 0.5) {
                    f(cell, &part);
                }
            }
        }
    }
}

/// Rough upper bound of the cells a triangle (in grid units) overlaps: its projection on
/// the dominant plane grown by the touched border, times the cells per column, plus its
/// depth extent (which is what a degenerate, segment-like triangle covers).
fn cell_estimate(t: &[DVec3; 3]) -> f64 {
    let w = depth_axis(t);
    let a = (w + 1) % 3;
    let b = (w + 2) % 3;
    let p = |v: DVec3| glam::DVec2::new(v[a], v[b]);
    let (p0, p1, p2) = (p(t[0]), p(t[1]), p(t[2]));
    let area = 0.5 * (p1 - p0).perp_dot(p2 - p0).abs();
    let perim = (p1 - p0).length() + (p2 - p1).length() + (p0 - p2).length();
    let depth = t[0][w].max(t[1][w]).max(t[2][w]) - t[0][w].min(t[1][w]).min(t[2][w]);
    (area + 2.0 * perim + 4.0) * 3.0 + depth + 2.0
}

// ---------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------

/// Object space of a mesh: the bounding box of the finite vertices referenced by its
/// triangles (indices in range). `None` when there is no such vertex.
pub fn mesh_object_space(mesh: &Mesh) -> Option<ObjectSpace> {
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
    (min.x <= max.x).then(|| ObjectSpace::from_bounds(min, max))
}

/// Grid-unit factor of a level: grid = (object + 1) · half_cells.
fn half_cells(level: u32) -> f64 {
    (1u64 << level) as f64 * 0.5
}

fn check_level(level: u32) -> Result<(), VoxelizeError> {
    if level > MAX_LEVEL {
        return Err(VoxelizeError::LevelTooHigh {
            level,
            max: MAX_LEVEL,
        });
    }
    Ok(())
}

/// Per-triangle attribute sources, resolved once per (brick, triangle).
struct TriAttrs<'a> {
    material: &'a Material,
    uv: Option<[glam::Vec2; 3]>,
    color: Option<[[f32; 4]; 3]>,
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
struct Chunk {
    codes: Vec<u64>,
    normals: Vec<[f32; 3]>,
    colors: Vec<[f32; 4]>,
    uvs: Vec<[f32; 2]>,
    /// Indices (within the chunk) of voxels that still need a normal.
    missing_normal: Vec<usize>,
}

/// Conservative surface voxelization of a triangle mesh on a level-`level` grid.
///
/// See the module documentation for the method. Fails when the level exceeds
/// [`MAX_LEVEL`], when no triangle has finite vertices, or when the estimated voxel count
/// exceeds [`MAX_VOXELS`].
pub fn voxelize_mesh(
    mesh: &Mesh,
    level: u32,
    progress: &dyn Progress,
) -> Result<VoxelSet, VoxelizeError> {
    check_level(level)?;
    let mut report = VoxelizeReport {
        triangles: mesh.triangles.len() as u64,
        ..Default::default()
    };
    let object_space = mesh_object_space(mesh)
        .ok_or_else(|| VoxelizeError::Empty("no triangle references a finite vertex".into()))?;

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
    if estimate > MAX_VOXELS {
        return Err(VoxelizeError::TooLarge {
            level,
            estimate,
            limit: MAX_VOXELS,
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

    let default_material = Material::default();
    let attrs = |t: u32| -> TriAttrs<'_> {
        let idx = mesh.triangles[t as usize];
        let m = mesh
            .triangle_materials
            .get(t as usize)
            .copied()
            .unwrap_or(0);
        let material = mesh.materials.get(m as usize).unwrap_or(&default_material);
        let n = mesh.positions.len();
        TriAttrs {
            material,
            uv: (mesh.uvs.len() == n).then(|| idx.map(|i| mesh.uvs[i as usize])),
            color: (mesh.colors.len() == n).then(|| idx.map(|i| mesh.colors[i as usize])),
        }
    };

    let local_cells = 1usize << (3 * brick_log);
    let brick = BrickGeometry {
        log: brick_log,
        cells: brick_cells,
    };
    let process = |run: &[(u64, Range<usize>)]| -> Chunk {
        SCRATCH.with(|cell| {
            let mut scratch = cell.borrow_mut();
            scratch.ensure(local_cells);
            let mut chunk = Chunk::default();
            for (code, range) in run {
                let tris = pairs[range.clone()]
                    .iter()
                    .map(|&(_, t)| (tri(t), attrs(t)));
                voxelize_brick(&mut scratch, &brick, *code, tris, &mut chunk);
            }
            progress.advance(run.len() as u64);
            chunk
        })
    };

    // Bricks go in batches so that only one batch of per-chunk output exists next to the
    // result, which is reserved from the estimate (untouched capacity costs no memory).
    let capacity = (estimate as usize).min(1 << 26);
    let mut voxels = LevelVoxels {
        level,
        codes: Vec::with_capacity(capacity),
        normals: Vec::with_capacity(capacity),
        colors: Vec::with_capacity(capacity),
        uvs: Vec::with_capacity(capacity),
    };
    let mut missing: Vec<usize> = Vec::new();
    progress.begin("voxelizing", bricks.len() as u64);
    for batch in bricks.chunks(4096) {
        let chunks: Vec<Chunk> = batch.par_chunks(16).map(process).collect();
        for c in chunks {
            let base = voxels.codes.len();
            missing.extend(c.missing_normal.iter().map(|i| base + i));
            voxels.codes.extend_from_slice(&c.codes);
            voxels.normals.extend_from_slice(&c.normals);
            voxels.colors.extend_from_slice(&c.colors);
            voxels.uvs.extend_from_slice(&c.uvs);
        }
    }
    progress.end();
    drop(pairs);
    voxels.codes.shrink_to_fit();
    voxels.normals.shrink_to_fit();
    voxels.colors.shrink_to_fit();
    voxels.uvs.shrink_to_fit();

    report.normal_fallbacks = missing.len() as u64;
    fill_gradient_normals(&mut voxels, &missing);
    Ok(VoxelSet {
        object_space,
        voxels,
        report,
    })
}

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

/// Gives each voxel in `missing` the normal of the occupancy gradient of its
/// 26-neighbourhood (pointing away from the occupied side); where that is zero, the
/// direction from the grid centre; last resort +Z.
fn fill_gradient_normals(voxels: &mut LevelVoxels, missing: &[usize]) {
    let n = 1i64 << voxels.level;
    let fixed: Vec<(usize, [f32; 3])> = missing
        .par_iter()
        .map(|&i| {
            let c = voxels.cell(i).map(i64::from);
            let occupied = |d: [i64; 3]| {
                let q = [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
                q.iter().all(|&x| (0..n).contains(&x)) && voxels.find(q.map(|x| x as u32)).is_some()
            };
            let g = gradient_26(occupied);
            let from_center = c.map(|x| x as f64 + 0.5 - n as f64 * 0.5);
            (i, normalize_or(g, || from_center))
        })
        .collect();
    for (i, normal) in fixed {
        voxels.normals[i] = normal;
    }
}

/// Minus the occupancy-weighted sum of the 26 neighbour offsets (each divided by its
/// length): points from the occupied side of a cell towards the empty side.
pub(crate) fn gradient_26(mut occupied: impl FnMut([i64; 3]) -> bool) -> [f64; 3] {
    let mut g = [0.0f64; 3];
    for dz in -1i64..=1 {
        for dy in -1i64..=1 {
            for dx in -1i64..=1 {
                if (dx, dy, dz) == (0, 0, 0) || !occupied([dx, dy, dz]) {
                    continue;
                }
                let inv = 1.0 / ((dx * dx + dy * dy + dz * dz) as f64).sqrt();
                g[0] -= dx as f64 * inv;
                g[1] -= dy as f64 * inv;
                g[2] -= dz as f64 * inv;
            }
        }
    }
    g
}

/// Colour and uv of a triangle at point `p` (grid units) on it.
fn sample(v: &[DVec3; 3], a: &TriAttrs<'_>, p: DVec3) -> ([f32; 4], [f64; 2]) {
    let w = barycentric(v, p);
    let mut color = a.material.base_color;
    let mut uv = [0.0f64; 2];
    if let Some(uvs) = a.uv {
        for k in 0..3 {
            uv[0] += w[k] * f64::from(uvs[k].x);
            uv[1] += w[k] * f64::from(uvs[k].y);
        }
        if !(uv[0].is_finite() && uv[1].is_finite()) {
            uv = [0.0; 2];
        }
        if let Some(tex) = &a.material.base_color_texture {
            let t = sample_texture(tex, uv);
            for k in 0..4 {
                color[k] *= t[k];
            }
        }
    }
    if let Some(cols) = a.color {
        for k in 0..4 {
            let c = (0..3).map(|i| w[i] * f64::from(cols[i][k])).sum::<f64>();
            color[k] *= c as f32;
        }
    }
    (sanitize(color), uv)
}

/// A colour clamped into [0, 1], non-finite components as 0.
fn sanitize(color: [f32; 4]) -> [f32; 4] {
    color.map(|c| {
        if c.is_finite() {
            c.clamp(0.0, 1.0)
        } else {
            0.0
        }
    })
}

/// Barycentric weights of `p` (projected onto the triangle, clamped into it). For a
/// degenerate triangle: all weight on the vertex nearest to `p`.
fn barycentric(t: &[DVec3; 3], p: DVec3) -> [f64; 3] {
    let e0 = t[1] - t[0];
    let e1 = t[2] - t[0];
    let ep = p - t[0];
    let d00 = e0.dot(e0);
    let d01 = e0.dot(e1);
    let d11 = e1.dot(e1);
    let d20 = ep.dot(e0);
    let d21 = ep.dot(e1);
    let denom = d00 * d11 - d01 * d01;
    if denom > 1e-12 * d00 * d11 && denom.is_finite() {
        let v = ((d11 * d20 - d01 * d21) / denom).clamp(0.0, 1.0);
        let w = ((d00 * d21 - d01 * d20) / denom).clamp(0.0, 1.0);
        let s = v + w;
        let (v, w) = if s > 1.0 { (v / s, w / s) } else { (v, w) };
        [1.0 - v - w, v, w]
    } else {
        let d = t.map(|q| q.distance_squared(p));
        let i = if d[0] <= d[1] && d[0] <= d[2] {
            0
        } else if d[1] <= d[2] {
            1
        } else {
            2
        };
        let mut w = [0.0; 3];
        w[i] = 1.0;
        w
    }
}

/// Bilinear, wrap-around sample of an RGBA8 texture; `uv` (0, 0) is the top-left corner
/// of texel row 0 (the glTF convention the loaders convert to). A malformed texture
/// (zero size, too few texels) samples as white.
fn sample_texture(tex: &Texture, uv: [f64; 2]) -> [f32; 4] {
    let (w, h) = (tex.width as i64, tex.height as i64);
    if w == 0 || h == 0 || (tex.texels.len() as i64) < w * h {
        return [1.0; 4];
    }
    let x = uv[0] * w as f64 - 0.5;
    let y = uv[1] * h as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let texel = |xi: i64, yi: i64| {
        let t = tex.texels[(yi.rem_euclid(h) * w + xi.rem_euclid(w)) as usize];
        t.map(|c| f32::from(c) / 255.0)
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (a, b, c, d) = (
        texel(x0, y0),
        texel(x0 + 1, y0),
        texel(x0, y0 + 1),
        texel(x0 + 1, y0 + 1),
    );
    let mut out = [0.0f32; 4];
    for k in 0..4 {
        let top = a[k] + (b[k] - a[k]) * fx;
        let bottom = c[k] + (d[k] - c[k]) * fx;
        out[k] = top + (bottom - top) * fy;
    }
    out
}

// ---------------------------------------------------------------------------------------
// Voxel models
// ---------------------------------------------------------------------------------------

/// Object space of a voxel model: the bounding box of the union of its unit cubes.
pub fn voxel_model_object_space(model: &VoxelModel) -> Option<ObjectSpace> {
    let (min, max) = voxel_bounds(model)?;
    Some(ObjectSpace::from_bounds(
        DVec3::new(min[0] as f64, min[1] as f64, min[2] as f64),
        DVec3::new(max[0] as f64, max[1] as f64, max[2] as f64),
    ))
}

/// Integer bounds `[min, max)` of a voxel model's cubes.
fn voxel_bounds(model: &VoxelModel) -> Option<([i64; 3], [i64; 3])> {
    let first = model.voxels.first()?;
    let mut min = first.map(i64::from);
    let mut max = min.map(|v| v + 1);
    for v in &model.voxels {
        for k in 0..3 {
            min[k] = min[k].min(i64::from(v[k]));
            max[k] = max[k].max(i64::from(v[k]) + 1);
        }
    }
    Some((min, max))
}

/// Exact mapping between source voxel coordinates and target cells of one level.
///
/// Along axis k, source coordinate x maps to grid coordinate `A·(2x − S_k) / (2E)` with
/// `A = 2^level`, `E` the largest extent and `S_k = min_k + max_k − E` (this is the
/// [`ObjectSpace`] formula `((x − c)·2/E + 1)·A/2` with the centre `c = (min + max)/2`,
/// multiplied out over integers so that no rounding can create or drop a cell).
struct Resample {
    a: i64,
    e2: i64,
    s: [i64; 3],
}

// i64 suffices: source coordinates are i32 (extent < 2^33, |S| < 2^34) and A ≤ 2^16, so
// every product below stays under 2^51.
impl Resample {
    /// Target cells overlapping source voxel coordinate `x` with positive length.
    fn cells_of(&self, k: usize, x: i64) -> (i64, i64) {
        let lo = (self.a * (2 * x - self.s[k])).div_euclid(self.e2);
        let hi_num = self.a * (2 * x + 2 - self.s[k]);
        let hi = -((-hi_num).div_euclid(self.e2)) - 1; // ceil(hi_num / e2) - 1
        (lo, hi)
    }

    /// Source coordinates whose unit interval overlaps target cell `i` with positive
    /// length.
    fn sources_of(&self, k: usize, i: i64) -> (i64, i64) {
        let two_a = 2 * self.a;
        // x < (e2·(i+1) + A·S) / 2A  and  x > (e2·i + A·S − 2A) / 2A
        let upper = self.e2 * (i + 1) + self.a * self.s[k];
        let hi = -((-upper).div_euclid(two_a)) - 1;
        let lower = self.e2 * i + self.a * self.s[k] - two_a;
        let lo = lower.div_euclid(two_a) + 1;
        (lo, hi)
    }
}

/// Source voxel lookup: a dense index over the bounding box when it is small, a hash map
/// otherwise.
struct SourceIndex {
    min: [i64; 3],
    dims: [i64; 3],
    dense: Vec<u32>,
    sparse: HashMap<[i64; 3], u32>,
}

impl SourceIndex {
    const DENSE_LIMIT: i64 = 1 << 24;

    fn new(model: &VoxelModel, min: [i64; 3], max: [i64; 3]) -> SourceIndex {
        let dims = [max[0] - min[0], max[1] - min[1], max[2] - min[2]];
        let volume = dims[0].saturating_mul(dims[1]).saturating_mul(dims[2]);
        let mut index = SourceIndex {
            min,
            dims,
            dense: Vec::new(),
            sparse: HashMap::new(),
        };
        if volume <= Self::DENSE_LIMIT {
            index.dense = vec![0; volume as usize];
            for (i, v) in model.voxels.iter().enumerate() {
                let slot = index.slot(v.map(i64::from)).unwrap_or(0);
                index.dense[slot] = i as u32 + 1;
            }
        } else {
            index.sparse.reserve(model.voxels.len());
            for (i, v) in model.voxels.iter().enumerate() {
                index.sparse.insert(v.map(i64::from), i as u32);
            }
        }
        index
    }

    fn slot(&self, p: [i64; 3]) -> Option<usize> {
        let l = [p[0] - self.min[0], p[1] - self.min[1], p[2] - self.min[2]];
        (0..3)
            .all(|k| (0..self.dims[k]).contains(&l[k]))
            .then(|| (l[0] + self.dims[0] * (l[1] + self.dims[1] * l[2])) as usize)
    }

    fn get(&self, p: [i64; 3]) -> Option<u32> {
        if self.dense.is_empty() {
            self.sparse.get(&p).copied()
        } else {
            self.slot(p).and_then(|s| self.dense[s].checked_sub(1))
        }
    }
}

/// Resamples a voxel model onto a level-`level` grid keeping the boundary cells
/// ([`VoxelFill::Shell`]); see [`voxelize_voxels_with`].
pub fn voxelize_voxels(
    model: &VoxelModel,
    level: u32,
    progress: &dyn Progress,
) -> Result<VoxelSet, VoxelizeError> {
    voxelize_voxels_with(model, level, VoxelFill::Shell, progress)
}

/// Resamples a voxel model onto a level-`level` grid.
///
/// The union of the unit cubes is fitted into object space ([`voxel_model_object_space`]);
/// a target cell is occupied when it overlaps a source cube with positive volume; `fill`
/// says which occupied cells are kept. Colour: the mean colour of the source voxels the
/// cell overlaps (missing colours count as the default grey). Normal: the occupancy
/// gradient of the 26-neighbourhood, falling back to the direction from the grid centre.
pub fn voxelize_voxels_with(
    model: &VoxelModel,
    level: u32,
    fill: VoxelFill,
    progress: &dyn Progress,
) -> Result<VoxelSet, VoxelizeError> {
    check_level(level)?;
    let (min, max) = voxel_bounds(model)
        .ok_or_else(|| VoxelizeError::Empty("the voxel model has no voxels".into()))?;
    let object_space = voxel_model_object_space(model)
        .ok_or_else(|| VoxelizeError::Empty("the voxel model has no voxels".into()))?;
    let extent = (0..3).map(|k| max[k] - min[k]).max().unwrap_or(1);
    let rs = Resample {
        a: 1i64 << level,
        e2: 2 * extent,
        s: [0, 1, 2].map(|k| min[k] + max[k] - extent),
    };
    let index = SourceIndex::new(model, min, max);
    let n = 1i64 << level;
    let report = VoxelizeReport {
        source_voxels: model.voxels.len() as u64,
        ..Default::default()
    };

    // The target cells overlapped by a source voxel form a block; only its boundary layer
    // can hold shell cells, and with cells no larger than a source voxel only the layers
    // facing an absent source neighbour can (the cells across a face with a source
    // neighbour overlap that neighbour, so they are occupied).
    let block =
        |v: &[i32; 3]| -> [(i64, i64); 3] { [0, 1, 2].map(|k| rs.cells_of(k, i64::from(v[k]))) };
    let fine = rs.a >= rs.e2 / 2; // cells per source unit A/E >= 1
    let exposed = |v: &[i32; 3], k: usize, dir: i64| {
        let mut q = v.map(i64::from);
        q[k] += dir;
        index.get(q).is_none()
    };
    let estimate: u128 = model
        .voxels
        .par_iter()
        .map(|v| {
            let b = block(v);
            let d = b.map(|(lo, hi)| (hi - lo + 1).max(0) as u128);
            match fill {
                VoxelFill::Solid => d[0] * d[1] * d[2],
                VoxelFill::Shell if !fine => d[0] * d[1] * d[2],
                VoxelFill::Shell => (0..6)
                    .filter(|f| exposed(v, f / 2, if f.is_multiple_of(2) { -1 } else { 1 }))
                    .map(|f| d[(f / 2 + 1) % 3] * d[(f / 2 + 2) % 3])
                    .sum(),
            }
        })
        .sum();
    if estimate > u128::from(MAX_VOXELS) {
        return Err(VoxelizeError::TooLarge {
            level,
            estimate: estimate.min(u128::from(u64::MAX)) as u64,
            limit: MAX_VOXELS,
        });
    }

    // Candidate cells. Upsampling (`fine`): the shell layers or whole blocks as codes,
    // colours looked up later (a cell overlaps at most 2 source voxels per axis).
    // Downsampling: every block cell with the index of its source voxel, so that colours
    // are averaged by grouping instead of scanning large source ranges per cell; the
    // codes are then the complete occupancy, searched for neighbours.
    progress.begin("resampling voxels", model.voxels.len() as u64);
    let default_color = Material::default().base_color;
    // Calls `emit(code)` for each candidate cell of source voxel `id`.
    let candidates_of = |id: u32, v: &[i32; 3], emit: &mut dyn FnMut(u64)| {
        let b = block(v);
        let mut cell = |p: [i64; 3]| emit(morton_encode(p.map(|x| x as u32)));
        if fill == VoxelFill::Solid || !fine {
            // A duplicated source position contributes once (the index's entry).
            if !fine && index.get(v.map(i64::from)) != Some(id) {
                return;
            }
            for z in b[2].0..=b[2].1 {
                for y in b[1].0..=b[1].1 {
                    for x in b[0].0..=b[0].1 {
                        cell([x, y, z]);
                    }
                }
            }
            return;
        }
        for k in 0..3 {
            for (dir, layer) in [(-1, b[k].0), (1, b[k].1)] {
                if !exposed(v, k, dir) {
                    continue;
                }
                let (a, c) = ((k + 1) % 3, (k + 2) % 3);
                for i in b[a].0..=b[a].1 {
                    for j in b[c].0..=b[c].1 {
                        let mut p = [0i64; 3];
                        p[k] = layer;
                        p[a] = i;
                        p[c] = j;
                        cell(p);
                    }
                }
            }
        }
    };
    let mut codes: Vec<u64>;
    let mut grouped_colors: Vec<[f32; 4]> = Vec::new();
    if fine {
        codes = model
            .voxels
            .par_chunks(1024)
            .enumerate()
            .flat_map_iter(|(chunk, vs)| {
                let mut out = Vec::new();
                for (i, v) in vs.iter().enumerate() {
                    candidates_of((chunk * 1024 + i) as u32, v, &mut |c| out.push(c));
                }
                progress.advance(vs.len() as u64);
                out
            })
            .collect();
        codes.par_sort_unstable();
        codes.dedup();
    } else {
        // Every occupied cell with the source voxel it came from: colours are averaged by
        // grouping instead of scanning large source ranges per cell, and the codes are
        // the complete occupancy, searched for neighbours below.
        let mut pairs: Vec<(u64, u32)> = model
            .voxels
            .par_chunks(1024)
            .enumerate()
            .flat_map_iter(|(chunk, vs)| {
                let mut out = Vec::new();
                for (i, v) in vs.iter().enumerate() {
                    let id = (chunk * 1024 + i) as u32;
                    candidates_of(id, v, &mut |c| out.push((c, id)));
                }
                progress.advance(vs.len() as u64);
                out
            })
            .collect();
        pairs.par_sort_unstable();
        codes = Vec::with_capacity(pairs.len());
        let mut start = 0;
        for i in 1..=pairs.len() {
            if i < pairs.len() && pairs[i].0 == pairs[start].0 {
                continue;
            }
            codes.push(pairs[start].0);
            let mut sum = [0.0f64; 4];
            for &(_, id) in &pairs[start..i] {
                let col = model.colors.get(id as usize).unwrap_or(&default_color);
                for (s, c) in sum.iter_mut().zip(col) {
                    *s += f64::from(*c);
                }
            }
            let count = (i - start) as f64;
            grouped_colors.push(sum.map(|s| (s / count).clamp(0.0, 1.0) as f32));
            start = i;
        }
    }
    progress.end();

    // Whether any source voxel lies in the box of source coordinates `r` (upsampling only:
    // the box is at most 2×2×2).
    let any_source = |r: [(i64, i64); 3]| -> bool {
        for z in r[2].0..=r[2].1 {
            for y in r[1].0..=r[1].1 {
                for x in r[0].0..=r[0].1 {
                    if index.get([x, y, z]).is_some() {
                        return true;
                    }
                }
            }
        }
        false
    };
    // Occupancy of the 3×3×3 neighbourhood of a cell (index `dx+1 + 3(dy+1) + 9(dz+1)`).
    let neighbourhood = |c: [i64; 3]| -> [bool; 27] {
        let mut occ = [false; 27];
        if fine {
            // The source ranges of the three slabs per axis, computed once.
            let ranges: [[Option<(i64, i64)>; 3]; 3] = [0, 1, 2].map(|k| {
                [-1i64, 0, 1].map(|d| {
                    (0..n)
                        .contains(&(c[k] + d))
                        .then(|| rs.sources_of(k, c[k] + d))
                })
            });
            for (i, o) in occ.iter_mut().enumerate() {
                if let (Some(x), Some(y), Some(z)) =
                    (ranges[0][i % 3], ranges[1][(i / 3) % 3], ranges[2][i / 9])
                {
                    *o = any_source([x, y, z]);
                }
            }
        } else {
            for (i, o) in occ.iter_mut().enumerate() {
                let q = [
                    c[0] + (i % 3) as i64 - 1,
                    c[1] + ((i / 3) % 3) as i64 - 1,
                    c[2] + (i / 9) as i64 - 1,
                ];
                *o = q.iter().all(|x| (0..n).contains(x))
                    && codes
                        .binary_search(&morton_encode(q.map(|x| x as u32)))
                        .is_ok();
            }
        }
        occ
    };

    progress.begin("voxel attributes", codes.len() as u64);
    type Attr = (u64, [f32; 3], [f32; 4]);
    let attrs = |ci: usize| -> Option<Attr> {
        let code = codes[ci];
        let c = morton_decode(code).map(i64::from);
        let occ = neighbourhood(c);
        let at = |d: [i64; 3]| occ[(d[0] + 1 + 3 * (d[1] + 1) + 9 * (d[2] + 1)) as usize];
        if fill == VoxelFill::Shell {
            let faces = [
                [-1, 0, 0],
                [1, 0, 0],
                [0, -1, 0],
                [0, 1, 0],
                [0, 0, -1],
                [0, 0, 1],
            ];
            if faces.iter().all(|&d| at(d)) {
                return None;
            }
        }
        let g = gradient_26(at);
        let from_center = c.map(|x| x as f64 + 0.5 - n as f64 * 0.5);
        let normal = normalize_or(g, || from_center);
        let color = if fine {
            let r = [0, 1, 2].map(|k| rs.sources_of(k, c[k]));
            let mut sum = [0.0f64; 4];
            let mut count = 0u64;
            for z in r[2].0..=r[2].1 {
                for y in r[1].0..=r[1].1 {
                    for x in r[0].0..=r[0].1 {
                        if let Some(i) = index.get([x, y, z]) {
                            let col = model.colors.get(i as usize).unwrap_or(&default_color);
                            for (s, c) in sum.iter_mut().zip(col) {
                                *s += f64::from(*c);
                            }
                            count += 1;
                        }
                    }
                }
            }
            sum.map(|s| (s / count.max(1) as f64).clamp(0.0, 1.0) as f32)
        } else {
            grouped_colors[ci]
        };
        Some((code, normal, color))
    };
    const CHUNK: usize = 4096;
    let kept: Vec<Option<Attr>> = codes
        .par_chunks(CHUNK)
        .enumerate()
        .flat_map_iter(|(chunk, cs)| {
            let out: Vec<Option<Attr>> = (0..cs.len()).map(|j| attrs(chunk * CHUNK + j)).collect();
            progress.advance(cs.len() as u64);
            out
        })
        .collect();
    progress.end();
    drop((codes, grouped_colors));

    let kept: Vec<Attr> = kept.into_iter().flatten().collect();
    let voxels = LevelVoxels {
        level,
        codes: kept.iter().map(|a| a.0).collect(),
        normals: kept.iter().map(|a| a.1).collect(),
        colors: kept.iter().map(|a| a.2).collect(),
        uvs: vec![[0.0; 2]; kept.len()],
    };
    Ok(VoxelSet {
        object_space,
        voxels,
        report,
    })
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use glam::Vec3;

    use super::*;
    use crate::model::cell_size;
    use crate::progress::NoProgress;

    fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            positions,
            triangles,
            ..Default::default()
        }
    }

    /// Axis-aligned box mesh, outward-facing triangles.
    fn box_mesh(min: Vec3, max: Vec3) -> Mesh {
        let p = |x: bool, y: bool, z: bool| {
            Vec3::new(
                if x { max.x } else { min.x },
                if y { max.y } else { min.y },
                if z { max.z } else { min.z },
            )
        };
        let positions = (0..8)
            .map(|i| p(i & 1 != 0, i & 2 != 0, i & 4 != 0))
            .collect();
        let quads = [
            [0, 2, 6, 4],
            [1, 5, 7, 3],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 6, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[2], q[1]], [q[0], q[3], q[2]]])
            .collect();
        mesh(positions, triangles)
    }

    /// UV sphere of radius `r` around `c`.
    pub(crate) fn sphere_mesh(c: Vec3, r: f32, rings: u32, segments: u32) -> Mesh {
        let mut positions = vec![c + Vec3::new(0.0, 0.0, r), c - Vec3::new(0.0, 0.0, r)];
        for i in 1..rings {
            let th = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..segments {
                let ph = std::f32::consts::TAU * j as f32 / segments as f32;
                positions
                    .push(c + r * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
            }
        }
        let v = |i: u32, j: u32| 2 + (i - 1) * segments + (j % segments);
        let mut triangles = Vec::new();
        for j in 0..segments {
            triangles.push([0, v(1, j), v(1, j + 1)]);
            triangles.push([1, v(rings - 1, j + 1), v(rings - 1, j)]);
            for i in 1..rings - 1 {
                triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        mesh(positions, triangles)
    }

    fn cells(set: &VoxelSet) -> BTreeSet<[u32; 3]> {
        (0..set.voxels.len()).map(|i| set.voxels.cell(i)).collect()
    }

    /// Brute force oracle: every cell in each valid triangle's bounding box, tested with
    /// the separating axis test (no row/column walk, no bricks).
    fn oracle(mesh: &Mesh, level: u32) -> BTreeSet<[u32; 3]> {
        let os = mesh_object_space(mesh).unwrap();
        let hc = half_cells(level);
        let n = 1i64 << level;
        let mut out = BTreeSet::new();
        for t in &mesh.triangles {
            if t.iter().any(|&i| i as usize >= mesh.positions.len()) {
                continue;
            }
            let v =
                t.map(|i| (os.to_object(mesh.positions[i as usize].as_dvec3()) + DVec3::ONE) * hc);
            if !v.iter().all(|p| p.is_finite()) {
                continue;
            }
            let lo = v[0].min(v[1]).min(v[2]);
            let hi = v[0].max(v[1]).max(v[2]);
            let r = |a: f64, b: f64| {
                ((a.floor() as i64 - 1).max(0))..=((b.floor() as i64 + 1).min(n - 1))
            };
            for z in r(lo.z, hi.z) {
                for y in r(lo.y, hi.y) {
                    for x in r(lo.x, hi.x) {
                        let c = DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5);
                        if triangle_box_overlap(&v, c, 0.5) {
                            out.insert([x as u32, y as u32, z as u32]);
                        }
                    }
                }
            }
        }
        out
    }

    fn assert_sane(set: &VoxelSet) {
        set.voxels.check().unwrap();
        for n in &set.voxels.normals {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-4, "normal {n:?}");
        }
    }

    #[test]
    fn sat_basics() {
        let t = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        assert!(triangle_box_overlap(&t, DVec3::new(0.5, 0.5, 0.5), 0.5)); // touches z = 0 face
        assert!(triangle_box_overlap(&t, DVec3::new(0.5, 0.5, -0.5), 0.5));
        assert!(!triangle_box_overlap(&t, DVec3::new(0.5, 0.5, 1.5), 0.5));
        // Beyond the hypotenuse x + y = 2: the box [1.5, 2.5]² misses it.
        assert!(!triangle_box_overlap(&t, DVec3::new(2.0, 2.0, 0.0), 0.5));
        // Corner of box (1, 1) lies on the hypotenuse: touching.
        assert!(triangle_box_overlap(&t, DVec3::new(1.5, 1.5, 0.0), 0.5));
        // A point triangle and a segment triangle.
        let p = [DVec3::splat(1.0); 3];
        assert!(triangle_box_overlap(&p, DVec3::splat(0.5), 0.5));
        assert!(!triangle_box_overlap(&p, DVec3::splat(-0.5), 0.5));
        let s = [DVec3::ZERO, DVec3::splat(3.0), DVec3::splat(3.0)];
        assert!(triangle_box_overlap(&s, DVec3::splat(1.5), 0.5));
        assert!(!triangle_box_overlap(&s, DVec3::new(2.5, 0.5, 0.5), 0.5));
    }

    #[test]
    fn single_triangle_matches_brute_force() {
        let m = mesh(
            vec![
                Vec3::new(-0.9, -0.7, 0.13),
                Vec3::new(0.8, -0.2, -0.6),
                Vec3::new(0.1, 0.9, 0.7),
            ],
            vec![[0, 1, 2]],
        );
        for level in 0..=6 {
            let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
            assert_sane(&set);
            assert_eq!(cells(&set), oracle(&m, level), "level {level}");
            // The face normal, everywhere.
            let n = (m.positions[1] - m.positions[0])
                .cross(m.positions[2] - m.positions[0])
                .normalize();
            for v in &set.voxels.normals {
                assert!(Vec3::from(*v).dot(n) > 0.9999, "{v:?} vs {n:?}");
            }
            assert!(
                set.voxels
                    .colors
                    .iter()
                    .all(|c| *c == Material::default().base_color)
            );
        }
    }

    #[test]
    fn quad_on_cell_boundaries_sets_both_sides() {
        // Bounds [-1, 1]² × {0}: object space is the identity, the quad lies on z = 0,
        // which is a cell boundary at every level ≥ 1.
        let m = mesh(
            vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        for level in 1..=5u32 {
            let n = 1u32 << level;
            let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
            assert_sane(&set);
            let mut expected = BTreeSet::new();
            for y in 0..n {
                for x in 0..n {
                    expected.insert([x, y, n / 2 - 1]);
                    expected.insert([x, y, n / 2]);
                }
            }
            assert_eq!(cells(&set), expected, "level {level}");
            for v in &set.voxels.normals {
                assert!(v[2] > 0.9999, "{v:?}");
            }
        }
    }

    #[test]
    fn box_surface_cells_exactly() {
        // Object space is the identity (centre 0, extent 2); the y and z faces fall inside
        // cells, the x faces on the grid border.
        let (lo, hi) = (Vec3::new(-1.0, -0.65, -0.55), Vec3::new(1.0, 0.65, 0.55));
        let m = box_mesh(lo, hi);
        for level in 1..=6u32 {
            let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
            assert_sane(&set);
            // Analytic oracle: the closed cell meets the box surface iff it meets the closed
            // box and is not inside its open interior.
            let s = cell_size(level);
            let n = 1u32 << level;
            let mut expected = BTreeSet::new();
            for z in 0..n {
                for y in 0..n {
                    for x in 0..n {
                        let c = [x, y, z];
                        let (bl, bh): (Vec<f64>, Vec<f64>) = (0..3)
                            .map(|k| (-1.0 + c[k] as f64 * s, -1.0 + (c[k] + 1) as f64 * s))
                            .unzip();
                        let meets =
                            (0..3).all(|k| bl[k] <= f64::from(hi[k]) && bh[k] >= f64::from(lo[k]));
                        let inside =
                            (0..3).all(|k| bl[k] > f64::from(lo[k]) && bh[k] < f64::from(hi[k]));
                        if meets && !inside {
                            expected.insert(c);
                        }
                    }
                }
            }
            assert_eq!(cells(&set), expected, "level {level}");
        }
        // Normals on face centres point out of the box.
        let set = voxelize_mesh(&m, 5, &NoProgress).unwrap();
        let at = |c: [u32; 3]| set.voxels.normals[set.voxels.find(c).unwrap()];
        let top_y = ((0.65f64 + 1.0) / cell_size(5)) as u32;
        assert!(at([16, top_y, 16])[1] > 0.9999);
        assert!(at([16, 16, ((1.0 - 0.55f64) / cell_size(5)) as u32])[2] < -0.9999);
        assert!(at([0, 16, 16])[0] < -0.9999);
    }

    #[test]
    fn sphere_matches_brute_force_and_stays_near_the_surface() {
        let m = sphere_mesh(Vec3::new(0.3, -2.0, 5.0), 1.7, 12, 20);
        let set = voxelize_mesh(&m, 5, &NoProgress).unwrap();
        assert_sane(&set);
        let got = cells(&set);
        assert_eq!(got, oracle(&m, 5));
        // Far from the surface: nothing. The tessellation's sagitta is below 4% of r.
        let r_grid = 16.0;
        for c in &got {
            let p = DVec3::new(c[0] as f64 + 0.5, c[1] as f64 + 0.5, c[2] as f64 + 0.5)
                - DVec3::splat(16.0);
            let d = (p.length() - r_grid).abs();
            assert!(
                d <= 3f64.sqrt() / 2.0 + 0.04 * r_grid,
                "{c:?} at distance {d}"
            );
            // Normals point outwards.
            let n =
                DVec3::from_array(set.voxels.normals[set.voxels.find(*c).unwrap()].map(f64::from));
            assert!(n.dot(p.normalize()) > 0.5, "{c:?} {n:?}");
        }
        // Watertight surface: the centre and the corners are never set.
        assert!(!got.contains(&[16, 16, 16]) && !got.contains(&[0, 0, 0]));
    }

    #[test]
    fn scaling_the_mesh_does_not_change_the_voxels() {
        let base = sphere_mesh(Vec3::new(0.25, 0.5, -0.125), 1.0, 9, 14);
        let reference = voxelize_mesh(&base, 6, &NoProgress).unwrap();
        for s in [1e-6f32, 1e7] {
            let mut m = base.clone();
            for p in &mut m.positions {
                *p *= s;
            }
            let set = voxelize_mesh(&m, 6, &NoProgress).unwrap();
            assert_eq!(set.voxels.codes, reference.voxels.codes, "scale {s}");
            for (a, b) in set.voxels.normals.iter().zip(&reference.voxels.normals) {
                assert!(Vec3::from(*a).dot(Vec3::from(*b)) > 0.9999);
            }
        }
    }

    #[test]
    fn degenerate_and_invalid_triangles() {
        // A segment, a point, a proper triangle, a NaN triangle, a bad index.
        let m = mesh(
            vec![
                Vec3::new(-1.0, -0.3, 0.2),
                Vec3::new(1.0, 0.9, -0.7),
                Vec3::new(0.31, 0.27, 0.11),
                Vec3::new(-0.6, 0.5, 0.5),
                Vec3::new(-0.2, 0.6, 0.55),
                Vec3::new(-0.5, 0.9, 0.3),
                Vec3::new(f32::NAN, 0.0, 0.0),
            ],
            vec![[0, 1, 1], [2, 2, 2], [3, 4, 5], [3, 4, 6], [0, 1, 99]],
        );
        for level in [0, 1, 3, 6] {
            let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
            assert_sane(&set);
            assert_eq!(set.report.skipped_non_finite, 1);
            assert_eq!(set.report.skipped_bad_index, 1);
            assert_eq!(set.report.degenerate, 2);
            assert_eq!(cells(&set), oracle(&m, level), "level {level}");
        }
        // Only degenerate triangles: still voxelized, normals finite (fallbacks counted).
        let seg = mesh(vec![Vec3::ZERO, Vec3::new(1.0, 0.5, 0.25)], vec![[0, 1, 1]]);
        let set = voxelize_mesh(&seg, 5, &NoProgress).unwrap();
        assert_sane(&set);
        assert_eq!(cells(&set), oracle(&seg, 5));
        assert_eq!(set.report.normal_fallbacks as usize, set.voxels.len());
        let point = mesh(vec![Vec3::splat(3.0)], vec![[0, 0, 0]]);
        let set = voxelize_mesh(&point, 4, &NoProgress).unwrap();
        assert_sane(&set);
        // A zero-extent model maps to the origin: the eight cells around it.
        assert_eq!(set.voxels.len(), 8);
        // Nothing valid at all: an error, not a panic.
        let bad = mesh(vec![Vec3::NAN], vec![[0, 0, 0], [5, 6, 7]]);
        assert!(matches!(
            voxelize_mesh(&bad, 4, &NoProgress),
            Err(VoxelizeError::Empty(_))
        ));
        assert!(matches!(
            voxelize_mesh(&Mesh::default(), 4, &NoProgress),
            Err(VoxelizeError::Empty(_))
        ));
        assert!(matches!(
            voxelize_mesh(&seg, 17, &NoProgress),
            Err(VoxelizeError::LevelTooHigh { .. })
        ));
    }

    #[test]
    fn oversized_requests_are_refused_before_allocating() {
        // One triangle across the whole grid at level 16 is ~2^31 cells.
        let m = mesh(
            vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.3),
                Vec3::new(0.0, 1.0, 1.0),
            ],
            vec![[0, 1, 2]],
        );
        assert!(matches!(
            voxelize_mesh(&m, 16, &NoProgress),
            Err(VoxelizeError::TooLarge { level: 16, .. })
        ));
        // A segment at level 16 is small and fine.
        let seg = mesh(vec![Vec3::ZERO, Vec3::new(1.0, 0.3, 0.2)], vec![[0, 1, 1]]);
        let set = voxelize_mesh(&seg, 16, &NoProgress).unwrap();
        assert_sane(&set);
        assert!(set.voxels.len() >= 65536);
    }

    #[test]
    fn opposite_faces_in_one_cell_keep_a_finite_normal() {
        // A slab thinner than a cell: its two big faces cancel in every cell.
        let m = box_mesh(Vec3::new(-1.0, -1.0, -0.001), Vec3::new(1.0, 1.0, 0.001));
        let set = voxelize_mesh(&m, 4, &NoProgress).unwrap();
        assert_sane(&set);
        let interior = set.voxels.find([8, 8, 7]).unwrap();
        assert!(set.voxels.normals[interior][2].abs() > 0.9999);
    }

    #[test]
    fn vertex_colours_and_textures_colour_the_voxels() {
        let mut m = mesh(
            vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2]],
        );
        m.colors = vec![
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0, 1.0],
            [0.0, 0.0, 1.0, 1.0],
        ];
        m.materials = vec![Material {
            base_color: [1.0; 4],
            base_color_texture: None,
        }];
        let set = voxelize_mesh(&m, 4, &NoProgress).unwrap();
        let red = set.voxels.colors[set.voxels.find([0, 0, 7]).unwrap()];
        assert!(red[0] > 0.85 && red[1] < 0.15 && red[2] < 0.15, "{red:?}");
        let green = set.voxels.colors[set.voxels.find([15, 0, 8]).unwrap()];
        assert!(green[1] > 0.85, "{green:?}");

        // A 2×1 texture: left texel black, right texel white; u runs along x.
        m.colors.clear();
        m.uvs = vec![
            glam::Vec2::new(0.0, 0.0),
            glam::Vec2::new(1.0, 0.0),
            glam::Vec2::new(0.0, 1.0),
        ];
        m.materials[0].base_color_texture = Some(Texture {
            width: 2,
            height: 1,
            texels: vec![[0, 0, 0, 255], [255, 255, 255, 255]],
        });
        let set = voxelize_mesh(&m, 4, &NoProgress).unwrap();
        let left = set.voxels.colors[set.voxels.find([4, 1, 8]).unwrap()];
        let right = set.voxels.colors[set.voxels.find([12, 1, 8]).unwrap()];
        assert!(left[0] < 0.3 && right[0] > 0.7, "{left:?} {right:?}");
        let uv = set.voxels.uvs[set.voxels.find([12, 1, 8]).unwrap()];
        assert!(uv[0] > 0.7 && uv[1] < 0.2, "{uv:?}");
        // A malformed texture samples as white instead of panicking.
        m.materials[0].base_color_texture = Some(Texture {
            width: 4,
            height: 4,
            texels: vec![],
        });
        assert_sane(&voxelize_mesh(&m, 3, &NoProgress).unwrap());
    }

    #[test]
    fn all_levels_up_to_12_on_a_needle() {
        // A long thin triangle across the grid keeps level 12 small (~ 4096·√3 · 3 cells).
        let m = mesh(
            vec![
                Vec3::new(-1.0, -1.0, -1.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(0.999, 1.0, 0.9995),
            ],
            vec![[0, 1, 2]],
        );
        let mut prev: Option<VoxelSet> = None;
        for level in 1..=12u32 {
            let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
            assert_sane(&set);
            if level <= 7 {
                assert_eq!(cells(&set), oracle(&m, level), "level {level}");
            } else {
                // Sample points along the triangle: their cells must be set.
                let os = set.object_space;
                let hc = half_cells(level);
                let v = [0, 1, 2]
                    .map(|i| m.positions[i])
                    .map(|p| (os.to_object(p.as_dvec3()) + DVec3::ONE) * hc);
                for i in 0..=1000 {
                    let a = i as f64 / 1000.0;
                    let p = v[0] + (v[1] - v[0]) * a + (v[2] - v[1]) * (a * 0.5);
                    let c = p
                        .to_array()
                        .map(|x| (x.floor() as i64).clamp(0, (1 << level) - 1) as u32);
                    assert!(set.voxels.find(c).is_some(), "level {level}: {c:?} missing");
                }
            }
            // The parents of this level's cells contain the previous level's cells.
            if let Some(p) = &prev {
                let parents: BTreeSet<u64> = set.voxels.codes.iter().map(|c| c >> 3).collect();
                assert!(
                    p.voxels.codes.iter().all(|c| parents.contains(c)),
                    "level {level}"
                );
            }
            prev = Some(set);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]
        /// Random triangles, optionally snapped to a lattice of cell boundaries (with the
        /// object space pinned to the identity by two point triangles at the corners),
        /// so exact touching cases are common: the walk must find what brute force finds.
        #[test]
        fn random_triangles_match_brute_force(
            c in proptest::array::uniform9(-1.0f32..1.0),
            level in 0u32..6,
            snap in proptest::bool::ANY,
        ) {
            let c = if snap { c.map(|x| (x * 4.0).round() / 4.0) } else { c };
            let m = mesh(
                vec![
                    Vec3::new(c[0], c[1], c[2]),
                    Vec3::new(c[3], c[4], c[5]),
                    Vec3::new(c[6], c[7], c[8]),
                    Vec3::splat(-1.0),
                    Vec3::splat(1.0),
                ],
                vec![[0, 1, 2], [3, 3, 3], [4, 4, 4]],
            );
            let set = voxelize_mesh(&m, level, &NoProgress).unwrap();
            assert_sane(&set);
            proptest::prop_assert_eq!(cells(&set), oracle(&m, level));
        }
    }

    // ----- voxel models -----

    /// Independent occupancy oracle in f64 object space with a tolerance for boundaries
    /// that coincide (true overlaps are far larger than it).
    fn voxel_oracle(model: &VoxelModel, level: u32, fill: VoxelFill) -> BTreeSet<[u32; 3]> {
        let os = voxel_model_object_space(model).unwrap();
        let s = cell_size(level);
        let n = 1i64 << level;
        let occ = |c: [i64; 3]| -> bool {
            if c.iter().any(|&x| !(0..n).contains(&x)) {
                return false;
            }
            model.voxels.iter().any(|v| {
                let lo = os.to_object(DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64));
                let hi = os.to_object(DVec3::new(
                    v[0] as f64 + 1.0,
                    v[1] as f64 + 1.0,
                    v[2] as f64 + 1.0,
                ));
                (0..3).all(|k| {
                    let (cl, ch) = (-1.0 + c[k] as f64 * s, -1.0 + (c[k] + 1) as f64 * s);
                    ch.min(hi[k]) - cl.max(lo[k]) > 1e-9
                })
            })
        };
        let mut out = BTreeSet::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    if !occ([x, y, z]) {
                        continue;
                    }
                    let faces = [
                        [-1, 0, 0],
                        [1, 0, 0],
                        [0, -1, 0],
                        [0, 1, 0],
                        [0, 0, -1],
                        [0, 0, 1],
                    ];
                    let boundary = faces.iter().any(|d| !occ([x + d[0], y + d[1], z + d[2]]));
                    if fill == VoxelFill::Solid || boundary {
                        out.insert([x as u32, y as u32, z as u32]);
                    }
                }
            }
        }
        out
    }

    fn blob() -> VoxelModel {
        // A lumpy ball of radius ~3.4 with a hole, at odd coordinates.
        let mut voxels = Vec::new();
        for z in -4..4 {
            for y in -4..4 {
                for x in -3..5 {
                    let d = ((x * x + y * y + z * z) as f32).sqrt();
                    if d < 3.4 && !(x == 0 && y == 0) && (x + y + z) % 7 != 3 {
                        voxels.push([x + 10, y - 20, z + 3]);
                    }
                }
            }
        }
        let colors = voxels
            .iter()
            .map(|v| [((v[0] & 1) as f32), 0.5, 0.25, 1.0])
            .collect();
        VoxelModel { voxels, colors }
    }

    #[test]
    fn voxel_models_match_the_occupancy_oracle() {
        let m = blob();
        for level in 0..=5u32 {
            for fill in [VoxelFill::Shell, VoxelFill::Solid] {
                let set = voxelize_voxels_with(&m, level, fill, &NoProgress).unwrap();
                assert_sane(&set);
                assert_eq!(
                    cells(&set),
                    voxel_oracle(&m, level, fill),
                    "level {level} {fill:?}"
                );
            }
        }
        // A 3³ cube of voxels: all cells of a level-2 grid occupied; the shell drops the 2³
        // interior.
        let cube = VoxelModel {
            voxels: (0..27).map(|i| [i % 3, (i / 3) % 3, i / 9]).collect(),
            colors: vec![[0.2, 0.4, 0.6, 1.0]; 27],
        };
        assert_eq!(
            voxelize_voxels_with(&cube, 2, VoxelFill::Solid, &NoProgress)
                .unwrap()
                .voxels
                .len(),
            64
        );
        let shell = voxelize_voxels(&cube, 2, &NoProgress).unwrap();
        assert_eq!(shell.voxels.len(), 56);
        assert!(
            shell
                .voxels
                .colors
                .iter()
                .all(|c| (c[2] - 0.6).abs() < 1e-6)
        );
        // Upsampled: face-centre cells get the face normal.
        let up = voxelize_voxels(&cube, 6, &NoProgress).unwrap();
        assert_sane(&up);
        assert!(up.voxels.normals[up.voxels.find([32, 32, 63]).unwrap()][2] > 0.9999);
        assert!(up.voxels.normals[up.voxels.find([0, 32, 32]).unwrap()][0] < -0.9999);
        assert_eq!(up.voxels.len(), 64usize.pow(3) - 62usize.pow(3));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 64, ..Default::default() })]
        /// Random voxel sets (any extents and offsets) at low levels, both fills.
        #[test]
        fn random_voxel_models_match_the_oracle(
            voxels in proptest::collection::vec(proptest::array::uniform3(-6i32..6), 1..40),
            offset in proptest::array::uniform3(-1000i32..1000),
            level in 0u32..5,
            solid in proptest::bool::ANY,
        ) {
            let voxels: Vec<[i32; 3]> =
                voxels.iter().map(|v| [v[0] + offset[0], v[1] + offset[1], v[2] + offset[2]]).collect();
            let model = VoxelModel { colors: vec![[0.5; 4]; voxels.len()], voxels };
            let fill = if solid { VoxelFill::Solid } else { VoxelFill::Shell };
            let set = voxelize_voxels_with(&model, level, fill, &NoProgress).unwrap();
            assert_sane(&set);
            proptest::prop_assert_eq!(cells(&set), voxel_oracle(&model, level, fill));
        }
    }

    #[test]
    fn voxel_model_edge_cases() {
        let one = VoxelModel {
            voxels: vec![[-7, 100, 3]],
            colors: vec![],
        };
        let set = voxelize_voxels(&one, 3, &NoProgress).unwrap();
        assert_sane(&set);
        assert_eq!(set.voxels.len(), 8 * 8 * 8 - 6 * 6 * 6);
        assert_eq!(set.voxels.colors[0], Material::default().base_color);
        assert!(matches!(
            voxelize_voxels(&VoxelModel::default(), 3, &NoProgress),
            Err(VoxelizeError::Empty(_))
        ));
        // Solid upsampling to a huge grid is refused up front.
        assert!(matches!(
            voxelize_voxels_with(&one, 12, VoxelFill::Solid, &NoProgress),
            Err(VoxelizeError::TooLarge { .. })
        ));
        // Downsampling a large solid block: grouped, not scanned per cell.
        let block = VoxelModel {
            voxels: (0..64 * 64 * 64)
                .map(|i| [i % 64, (i / 64) % 64, i / 4096])
                .collect(),
            colors: vec![[0.25, 0.5, 0.75, 1.0]; 64 * 64 * 64],
        };
        let solid = voxelize_voxels_with(&block, 3, VoxelFill::Solid, &NoProgress).unwrap();
        assert_eq!(solid.voxels.len(), 512);
        assert!(
            solid
                .voxels
                .colors
                .iter()
                .all(|c| (c[1] - 0.5).abs() < 1e-6)
        );
        assert_eq!(
            voxelize_voxels(&block, 3, &NoProgress)
                .unwrap()
                .voxels
                .len(),
            512 - 216
        );
        // Far-apart voxels use the hash index.
        let sparse = VoxelModel {
            voxels: vec![[0, 0, 0], [1000, 1000, 1000]],
            colors: vec![[1.0; 4]; 2],
        };
        let set = voxelize_voxels(&sparse, 4, &NoProgress).unwrap();
        assert_eq!(cells(&set), voxel_oracle(&sparse, 4, VoxelFill::Shell));
    }
}
