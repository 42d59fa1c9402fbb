//! Resampling of voxel models onto a level's grid, in exact integer arithmetic.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use super::attributes::gradient_26;
use super::{MAX_VOXELS, VoxelFill, VoxelSet, VoxelizeError, VoxelizeReport, check_level};
use crate::model::{Material, ObjectSpace, VoxelModel};
use crate::progress::Progress;
use crate::svo::{LevelVoxels, morton_decode, morton_encode, normalize_or};

/// The offsets of a cell's six face neighbours.
pub(super) const FACE_OFFSETS: [[i64; 3]; 6] = [
    [-1, 0, 0],
    [1, 0, 0],
    [0, -1, 0],
    [0, 1, 0],
    [0, 0, -1],
    [0, 0, 1],
];

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
    // The loop covers the first voxel too.
    let mut min = first.map(i64::from);
    let mut max = min;
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
    /// The mapping of the source bounds `[min, max)` onto a level-`level` grid.
    fn new(min: [i64; 3], max: [i64; 3], level: u32) -> Resample {
        let extent = (0..3).map(|k| max[k] - min[k]).max().unwrap_or(1);
        Resample {
            a: 1i64 << level,
            e2: 2 * extent,
            s: [0, 1, 2].map(|k| min[k] + max[k] - extent),
        }
    }

    /// The block of target cells a source voxel overlaps, as an inclusive range per axis.
    fn block(&self, v: &[i32; 3]) -> [(i64, i64); 3] {
        [0, 1, 2].map(|k| self.cells_of(k, i64::from(v[k])))
    }

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

    /// Whether the source neighbour of `v` one step along axis `k` in direction `dir` is
    /// empty.
    fn exposed(&self, v: &[i32; 3], k: usize, dir: i64) -> bool {
        let mut q = v.map(i64::from);
        q[k] += dir;
        self.get(q).is_none()
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
    let rs = Resample::new(min, max, level);
    let index = SourceIndex::new(model, min, max);
    let n = 1i64 << level;
    let report = VoxelizeReport {
        source_voxels: model.voxels.len() as u64,
        ..Default::default()
    };

    // The two candidate paths below differ in cost, not in result: upsampling looks at
    // the exposed layers of each block (see `refusal_estimate`) and finds colours per
    // cell, downsampling groups whole blocks.
    let fine = rs.a >= rs.e2 / 2; // cells per source unit A/E >= 1
    let estimate = refusal_estimate(model, &rs, &index, fill);
    if estimate > u128::from(MAX_VOXELS) {
        return Err(VoxelizeError::TooLarge {
            level,
            estimate: estimate.min(u128::from(u64::MAX)) as u64,
            limit: MAX_VOXELS,
        });
    }

    progress.begin("resampling voxels", model.voxels.len() as u64);
    let resampler = Resampler {
        model,
        rs,
        index,
        fill,
        fine,
        n,
        default_color: Material::default().base_color,
    };
    let (codes, grouped_colors) = resampler.candidate_cells(progress);
    progress.end();

    progress.begin("voxel attributes", codes.len() as u64);
    let kept = resampler.cell_attributes(&codes, &grouped_colors, progress);
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

/// A kept target cell: its Morton code, normal and colour.
type Attr = (u64, [f32; 3], [f32; 4]);

/// Everything resampling one voxel model onto one level reads.
struct Resampler<'a> {
    model: &'a VoxelModel,
    rs: Resample,
    index: SourceIndex,
    fill: VoxelFill,
    /// Upsampling: at least one target cell per source unit (A/E >= 1).
    fine: bool,
    /// Cells per axis of the level's grid.
    n: i64,
    /// Colour of a source voxel without one.
    default_color: [f32; 4],
}

impl Resampler<'_> {
    /// Candidate cells, sorted and unique, and for downsampling their averaged colours
    /// (empty when upsampling).
    ///
    /// Upsampling (`fine`): the shell layers or whole blocks as codes, colours looked up
    /// later (a cell overlaps at most 2 source voxels per axis). Downsampling: every block
    /// cell with the index of its source voxel, so that colours are averaged by grouping
    /// instead of scanning large source ranges per cell; the codes are then the complete
    /// occupancy, searched for neighbours.
    fn candidate_cells(&self, progress: &dyn Progress) -> (Vec<u64>, Vec<[f32; 4]>) {
        if self.fine {
            let mut codes = per_source(self.model, progress, |id, v, out| {
                self.candidates_of(id, v, &mut |c| out.push(c));
            });
            codes.par_sort_unstable();
            codes.dedup();
            (codes, Vec::new())
        } else {
            // Every occupied cell with the source voxel it came from: colours are averaged
            // by grouping instead of scanning large source ranges per cell, and the codes
            // are the complete occupancy, searched for neighbours later.
            let mut pairs: Vec<(u64, u32)> = per_source(self.model, progress, |id, v, out| {
                self.candidates_of(id, v, &mut |c| out.push((c, id)));
            });
            pairs.par_sort_unstable();
            self.group_colors(&pairs)
        }
    }

    /// Calls `emit(code)` for each candidate cell of source voxel `id` at `v`.
    fn candidates_of(&self, id: u32, v: &[i32; 3], emit: &mut dyn FnMut(u64)) {
        let b = self.rs.block(v);
        let mut cell = |p: [i64; 3]| emit(morton_encode(p.map(|x| x as u32)));
        if self.fill == VoxelFill::Solid || !self.fine {
            // A duplicated source position contributes once (the index's entry).
            if !self.fine && self.index.get(v.map(i64::from)) != Some(id) {
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
                if !self.index.exposed(v, k, dir) {
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
    }

    /// Collapses sorted `(code, source index)` pairs into unique codes and the mean colour
    /// of each code's sources.
    fn group_colors(&self, pairs: &[(u64, u32)]) -> (Vec<u64>, Vec<[f32; 4]>) {
        let mut codes = Vec::with_capacity(pairs.len());
        let mut grouped_colors: Vec<[f32; 4]> = Vec::new();
        let mut start = 0;
        for i in 1..=pairs.len() {
            if i < pairs.len() && pairs[i].0 == pairs[start].0 {
                continue;
            }
            codes.push(pairs[start].0);
            let mut sum = [0.0f64; 4];
            for &(_, id) in &pairs[start..i] {
                let col = self.source_color(id);
                for (s, c) in sum.iter_mut().zip(col) {
                    *s += f64::from(*c);
                }
            }
            let count = (i - start) as f64;
            grouped_colors.push(sum.map(|s| (s / count).clamp(0.0, 1.0) as f32));
            start = i;
        }
        (codes, grouped_colors)
    }

    /// Colour of source voxel `id`, the default grey when it has none.
    fn source_color(&self, id: u32) -> &[f32; 4] {
        self.model
            .colors
            .get(id as usize)
            .unwrap_or(&self.default_color)
    }

    /// Attributes of every candidate cell in parallel chunks, in code order; `None` for a
    /// cell the fill drops.
    fn cell_attributes(
        &self,
        codes: &[u64],
        grouped_colors: &[[f32; 4]],
        progress: &dyn Progress,
    ) -> Vec<Option<Attr>> {
        const CHUNK: usize = 4096;
        codes
            .par_chunks(CHUNK)
            .enumerate()
            .flat_map_iter(|(chunk, cs)| {
                let out: Vec<Option<Attr>> = (0..cs.len())
                    .map(|j| self.attributes_of(codes, grouped_colors, chunk * CHUNK + j))
                    .collect();
                progress.advance(cs.len() as u64);
                out
            })
            .collect()
    }

    /// Attributes of candidate cell `ci`, or `None` when [`VoxelFill::Shell`] drops it as
    /// interior.
    fn attributes_of(&self, codes: &[u64], grouped_colors: &[[f32; 4]], ci: usize) -> Option<Attr> {
        let code = codes[ci];
        let c = morton_decode(code).map(i64::from);
        let occ = self.neighbourhood(c, codes);
        let at = |d: [i64; 3]| occ[(d[0] + 1 + 3 * (d[1] + 1) + 9 * (d[2] + 1)) as usize];
        if self.fill == VoxelFill::Shell && FACE_OFFSETS.iter().all(|&d| at(d)) {
            return None;
        }
        let g = gradient_26(at);
        let from_center = c.map(|x| x as f64 + 0.5 - self.n as f64 * 0.5);
        let normal = normalize_or(g, || from_center);
        let color = if self.fine {
            self.overlapped_color(c)
        } else {
            grouped_colors[ci]
        };
        Some((code, normal, color))
    }

    /// Mean colour of the source voxels target cell `c` overlaps (upsampling only).
    fn overlapped_color(&self, c: [i64; 3]) -> [f32; 4] {
        let r = [0, 1, 2].map(|k| self.rs.sources_of(k, c[k]));
        let mut sum = [0.0f64; 4];
        let mut count = 0u64;
        for z in r[2].0..=r[2].1 {
            for y in r[1].0..=r[1].1 {
                for x in r[0].0..=r[0].1 {
                    if let Some(i) = self.index.get([x, y, z]) {
                        let col = self.source_color(i);
                        for (s, c) in sum.iter_mut().zip(col) {
                            *s += f64::from(*c);
                        }
                        count += 1;
                    }
                }
            }
        }
        sum.map(|s| (s / count.max(1) as f64).clamp(0.0, 1.0) as f32)
    }

    /// Occupancy of the 3×3×3 neighbourhood of cell `c` (index `dx+1 + 3(dy+1) + 9(dz+1)`):
    /// from the source when upsampling, else from the sorted candidate `codes`.
    fn neighbourhood(&self, c: [i64; 3], codes: &[u64]) -> [bool; 27] {
        let n = self.n;
        let mut occ = [false; 27];
        if self.fine {
            // The source ranges of the three slabs per axis, computed once.
            let ranges: [[Option<(i64, i64)>; 3]; 3] = [0, 1, 2].map(|k| {
                [-1i64, 0, 1].map(|d| {
                    (0..n)
                        .contains(&(c[k] + d))
                        .then(|| self.rs.sources_of(k, c[k] + d))
                })
            });
            for (i, o) in occ.iter_mut().enumerate() {
                if let (Some(x), Some(y), Some(z)) =
                    (ranges[0][i % 3], ranges[1][(i / 3) % 3], ranges[2][i / 9])
                {
                    *o = self.any_source([x, y, z]);
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
    }

    /// Whether any source voxel lies in the box of source coordinates `r` (upsampling
    /// only: the box is at most 2×2×2).
    fn any_source(&self, r: [(i64, i64); 3]) -> bool {
        for z in r[2].0..=r[2].1 {
            for y in r[1].0..=r[1].1 {
                for x in r[0].0..=r[0].1 {
                    if self.index.get([x, y, z]).is_some() {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// Calls `each(index, voxel, out)` for every source voxel, in parallel chunks, and
/// concatenates the outputs in source order.
fn per_source<T: Send>(
    model: &VoxelModel,
    progress: &dyn Progress,
    each: impl Fn(u32, &[i32; 3], &mut Vec<T>) + Sync,
) -> Vec<T> {
    const CHUNK: usize = 1024;
    model
        .voxels
        .par_chunks(CHUNK)
        .enumerate()
        .flat_map_iter(|(chunk, vs)| {
            let mut out = Vec::new();
            for (i, v) in vs.iter().enumerate() {
                each((chunk * CHUNK + i) as u32, v, &mut out);
            }
            progress.advance(vs.len() as u64);
            out
        })
        .collect()
}

/// Upper bound of the cells a resampling keeps, summed per source voxel before anything is
/// allocated: its whole block ([`VoxelFill::Solid`]), or for [`VoxelFill::Shell`] the
/// smaller of the block and its layers facing an absent source neighbour.
fn refusal_estimate(
    model: &VoxelModel,
    rs: &Resample,
    index: &SourceIndex,
    fill: VoxelFill,
) -> u128 {
    model
        .voxels
        .par_iter()
        .map(|v| {
            let d = rs.block(v).map(|(lo, hi)| (hi - lo + 1).max(0) as u128);
            let volume = d[0] * d[1] * d[2];
            match fill {
                VoxelFill::Solid => volume,
                // Only these layers can hold shell cells, at any cell size: along an axis
                // where a shell cell's neighbour cell is empty, the source voxel reaching
                // furthest into the cell has no source neighbour. Small blocks have more
                // face area than volume.
                VoxelFill::Shell => volume.min(
                    (0..6)
                        .filter(|f| {
                            index.exposed(v, f / 2, if f.is_multiple_of(2) { -1 } else { 1 })
                        })
                        .map(|f| d[(f / 2 + 1) % 3] * d[(f / 2 + 2) % 3])
                        .sum(),
                ),
            }
        })
        .sum()
}

#[cfg(test)]
#[path = "resample_tests.rs"]
mod tests;
