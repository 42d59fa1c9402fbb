//! The pre-filtered scene volume of the cone tracer: one regular grid over every voxel
//! instance's world box, each cell holding premultiplied reflected radiance (rgb) and
//! opacity (a), mipmapped.
//!
//! - **Finest level.** A cell is opaque (a = 1) when a voxel of some instance lies in it:
//!   each instance contributes the coarsest of its LODs whose voxels are no larger than a
//!   cell, each voxel to the cell holding its centre (a connected voxel surface stays a
//!   connected cell surface since voxels are no larger than cells); an instance whose finest
//!   voxels are larger than a cell marks every cell its voxels' world boxes overlap. The
//!   Empty cells the surface encloses are opaque too ([`crate::enclosure`]: a hollow shell would
//!   turn transparent in the mips) and emit nothing. A surface
//!   cell's albedo and normal are its voxels' means; its radiance is `albedo · light.color ·
//!   max(0, n·L) · V`, with `V` the light's hard shadow marched through the opaque cells
//!   (half-cell steps from 1.5 cells out, so a cell does not shadow itself).
//! - **Mip levels** average 2×2×2 children (those inside the grid): *isotropic* filtering.
//!   Anisotropic filtering (six directional volumes) would stop light leaking through thin
//!   walls at coarse levels, for six times the memory and six fetches per sample; the error
//!   against the Monte Carlo reference (docs/benchmarks.md) is what decides whether that is
//!   worth it, and on the measured scenes it is not the dominant error.
//! - **Size.** Cells are cubes; the longest axis of the padded scene box gets `resolution`
//!   cells, the others what their extent needs; each is then rounded up to a multiple of 64
//!   (six exact mip levels), and the resolution is lowered until the grid has at most
//!   [`MAX_CELLS`]. Memory is 8 bytes per cell
//!   (Rgba16Float) plus 1/7 for the mips; the cost of a build grows with the instances'
//!   voxels at the chosen LODs, which shrink as the scene (and so a cell) grows.

use glam::{DAffine3, DVec3};

use crate::asset::VoxelAsset;
use crate::camera::normalize_or;
use crate::instance_bvh::Aabb;
use crate::rgba_volume::{children, index};
use crate::shading::Light;

/// One placed voxel object for the volume.
#[derive(Debug, Clone, Copy)]
pub struct VolumeInstance<'a> {
    /// The asset (every LOD).
    pub asset: &'a VoxelAsset,
    /// Object space → world.
    pub object_to_world: DAffine3,
}

/// The mipmapped radiance/opacity volume.
#[derive(Debug, Clone, PartialEq)]
pub struct RadianceVolume {
    /// World position of the low corner of cell (0, 0, 0).
    pub origin: DVec3,
    /// Edge of a finest cell (world units).
    pub cell: f64,
    /// Cells per axis at the finest level.
    pub dims: [u32; 3],
    /// `mips[k]`: level `k` (dims `max(1, dims >> k)`), x fastest then y then z; texels are
    /// premultiplied linear radiance and opacity.
    pub mips: Vec<Vec<[f32; 4]>>,
    /// Surface cells of the finest level (cells holding voxels; enclosed cells are opaque
    /// too but not counted).
    pub occupied: usize,
}

/// Every axis of the finest level is a multiple of this (six exact mip levels).
pub const EXACT_MULTIPLE: u32 = 64;

/// The most finest-level cells a volume may have (2^24: about 1 GiB of CPU memory while
/// building); `build` lowers the resolution to fit.
pub const MAX_CELLS: u64 = 1 << 24;

/// Dims of mip `k`.
pub fn mip_dims(dims: [u32; 3], k: u32) -> [u32; 3] {
    dims.map(|d| (d >> k).max(1))
}

/// Per-cell sums of the finest level.
#[derive(Clone, Copy, Default)]
struct CellSum {
    count: u32,
    albedo: [f32; 3],
    normal: DVec3,
}

impl RadianceVolume {
    /// Builds the volume of `instances` lit by `light`, with `resolution` cells (at least 3)
    /// along the longest axis of their world boxes padded by one cell on each side, fewer
    /// when the volume would pass [`MAX_CELLS`]. With no visible instance the volume is one
    /// empty cell at the origin.
    pub fn build(instances: &[VolumeInstance], light: &Light, resolution: u32) -> Self {
        let boxes: Vec<Aabb> = instances
            .iter()
            .filter_map(|i| Aabb::of_instance(&i.object_to_world))
            .collect();
        let Some(bounds) = boxes.iter().copied().reduce(Aabb::union) else {
            return Self {
                origin: DVec3::ZERO,
                cell: 1.0,
                dims: [1; 3],
                mips: vec![vec![[0.0; 4]]],
                occupied: 0,
            };
        };
        let extent = bounds.hi - bounds.lo;
        // Multiples of 64 so the first six mip levels halve exactly (a texture's mip of an
        // odd size drops a cell row and shifts the coarser levels): the default cones reach
        // level 5 (a diameter of ~36 cells at max_distance).
        let layout = |resolution: u32| {
            let cell = (extent.max_element() / f64::from(resolution - 2)).max(1e-30);
            let dims = [extent.x, extent.y, extent.z].map(|e| {
                ((e / cell).ceil() as u32 + 2)
                    .clamp(1, resolution)
                    .next_multiple_of(EXACT_MULTIPLE)
            });
            (cell, dims)
        };
        let mut resolution = resolution.max(3);
        let (mut cell, mut dims) = layout(resolution);
        while dims.iter().map(|&d| u64::from(d)).product::<u64>() > MAX_CELLS && resolution > 3 {
            resolution = (resolution * 7 / 8).max(3);
            (cell, dims) = layout(resolution);
        }
        let origin = bounds.lo - DVec3::splat(cell);
        let mut sums = vec![CellSum::default(); dims.iter().map(|&d| d as usize).product()];
        for inst in instances {
            splat_instance(inst, origin, cell, dims, &mut sums);
        }
        let l = normalize_or(DVec3::from(light.direction.map(f64::from)), DVec3::Z);
        let surface: Vec<bool> = sums.iter().map(|s| s.count > 0).collect();
        let opaque = crate::enclosure::enclosed(&surface, dims);
        let mut finest = vec![[0f32; 4]; sums.len()];
        // Surface coverage per texel: the mips average radiance over surface cells only.
        let mut weight: Vec<f32> = surface.iter().map(|&s| f32::from(u8::from(s))).collect();
        let mut occupied = 0;
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let i = index(dims, [x, y, z]);
                    let s = &sums[i];
                    if s.count == 0 {
                        if opaque[i] {
                            // Inside a closed surface: opaque, emits nothing.
                            finest[i] = [0.0, 0.0, 0.0, 1.0];
                            weight[i] = 0.0;
                        }
                        continue;
                    }
                    occupied += 1;
                    let n = normalize_or(s.normal, DVec3::ZERO);
                    let ndl = n.dot(l).max(0.0);
                    let lit = ndl > 0.0 && !shadowed(&opaque, dims, [x, y, z], l);
                    let k = if lit {
                        ndl as f32 / s.count as f32
                    } else {
                        0.0
                    };
                    finest[i] = [
                        s.albedo[0] * k * light.color[0],
                        s.albedo[1] * k * light.color[1],
                        s.albedo[2] * k * light.color[2],
                        1.0,
                    ];
                }
            }
        }
        let mut mips = vec![finest];
        let mut k = 0;
        while mip_dims(dims, k) != [1, 1, 1] {
            let (next, w) = downsample(&mips[k as usize], &weight, mip_dims(dims, k));
            mips.push(next);
            weight = w;
            k += 1;
        }
        Self {
            origin,
            cell,
            dims,
            mips,
            occupied,
        }
    }

    /// Mip levels whose texels halve the level above exactly on every axis (level 0
    /// counts; the cone tracer samples no coarser one).
    pub fn exact_levels(&self) -> usize {
        let mut n = 1;
        while n < self.mips.len() && self.dims.iter().all(|&d| d % (1 << n) == 0) {
            n += 1;
        }
        n
    }

    /// Bytes of all levels at 8 bytes per texel (Rgba16Float on the GPU).
    pub fn bytes(&self) -> u64 {
        self.mips.iter().map(|m| m.len() as u64 * 8).sum()
    }
}

/// The coarsest LOD of `asset` whose voxels, placed by `m`, are no larger than `cell`; and
/// whether even the finest is larger.
fn level_for(asset: &VoxelAsset, m: &DAffine3, cell: f64) -> Option<(usize, bool)> {
    let scale = m
        .matrix3
        .to_cols_array_2d()
        .iter()
        .map(|c| DVec3::from(*c).length())
        .fold(0.0, f64::max);
    let size = |level: u32| 2.0 / f64::from(1u32 << level.min(31)) * scale;
    let finest = asset.lods.len().checked_sub(1)?;
    let fits = asset.lods.iter().position(|l| size(l.level) <= cell);
    Some(fits.map_or((finest, true), |i| (i, false)))
}

fn splat_instance(
    inst: &VolumeInstance,
    origin: DVec3,
    cell: f64,
    dims: [u32; 3],
    sums: &mut [CellSum],
) {
    let m = inst.object_to_world;
    let det = m.matrix3.determinant();
    if !(det != 0.0 && det.is_finite() && m.translation.is_finite()) {
        return;
    }
    let Some((lod, boxes)) = level_for(inst.asset, &m, cell) else {
        return;
    };
    let lod = &inst.asset.lods[lod];
    let normal_to_world = m.matrix3.inverse().transpose();
    let edge = 2.0 / f64::from(1u32 << lod.level.min(31));
    // Half the world box of one voxel (|M| times the half edge).
    let half = DVec3::new(
        m.matrix3.row(0).abs().element_sum(),
        m.matrix3.row(1).abs().element_sum(),
        m.matrix3.row(2).abs().element_sum(),
    ) * (edge * 0.5);
    let to_cell = |w: DVec3| (w - origin) / cell;
    let clamp = |v: f64, d: u32| (v.floor().max(0.0) as u32).min(d - 1);
    for v in &lod.point_cloud.voxels {
        let c = v.cell().map(|c| -1.0 + (f64::from(c) + 0.5) * edge);
        let w = m.transform_point3(DVec3::from(c));
        let color = v.color();
        let n = normal_to_world * DVec3::from(v.normal().map(f64::from));
        let mut add = |i: usize| {
            let s = &mut sums[i];
            s.count += 1;
            for (a, c) in s.albedo.iter_mut().zip(color) {
                *a += c;
            }
            s.normal += normalize_or(n, DVec3::ZERO);
        };
        if boxes {
            let lo = to_cell(w - half);
            let hi = to_cell(w + half);
            for z in clamp(lo.z, dims[2])..=clamp(hi.z, dims[2]) {
                for y in clamp(lo.y, dims[1])..=clamp(hi.y, dims[1]) {
                    for x in clamp(lo.x, dims[0])..=clamp(hi.x, dims[0]) {
                        add(index(dims, [x, y, z]));
                    }
                }
            }
        } else {
            let p = to_cell(w);
            add(index(
                dims,
                [
                    clamp(p.x, dims[0]),
                    clamp(p.y, dims[1]),
                    clamp(p.z, dims[2]),
                ],
            ));
        }
    }
}

/// Whether the ray from the centre of cell `c` towards `l` meets an opaque cell after 1.5
/// cells (half-cell steps until it leaves the grid).
fn shadowed(opaque: &[bool], dims: [u32; 3], c: [u32; 3], l: DVec3) -> bool {
    let start = DVec3::from(c.map(f64::from)) + DVec3::splat(0.5);
    let max = dims.iter().map(|&d| f64::from(d)).fold(0.0, f64::max) * 2.0;
    let mut t = 1.5;
    while t < max {
        let p = start + l * t;
        if p.min_element() < 0.0
            || p.x >= f64::from(dims[0])
            || p.y >= f64::from(dims[1])
            || p.z >= f64::from(dims[2])
        {
            return false;
        }
        if opaque[index(dims, [p.x as u32, p.y as u32, p.z as u32])] {
            return true;
        }
        t += 0.5;
    }
    false
}

/// The next coarser level: opacity the mean of the 2×2×2 children inside the grid;
/// radiance the mean over their surface cells (weighted by each child's surface
/// coverage), premultiplied by that opacity, so the dark inside of a solid does not dim
/// what its surface sends out. Returns the texels and their surface coverage.
fn downsample(src: &[[f32; 4]], weight: &[f32], dims: [u32; 3]) -> (Vec<[f32; 4]>, Vec<f32>) {
    let out = dims.map(|d| (d >> 1).max(1));
    let len = out.iter().map(|&d| d as usize).product();
    let mut dst = vec![[0f32; 4]; len];
    let mut dst_weight = vec![0f32; len];
    for z in 0..out[2] {
        for y in 0..out[1] {
            for x in 0..out[0] {
                let mut alpha = 0f32;
                let mut color = [0f32; 3];
                let mut w = 0f32;
                let mut n = 0u32;
                for c in children(dims, [x, y, z]) {
                    let i = index(dims, c);
                    let t = src[i];
                    alpha += t[3];
                    if t[3] > 0.0 && weight[i] > 0.0 {
                        // Unpremultiplied colour, weighted by surface coverage.
                        for k in 0..3 {
                            color[k] += t[k] / t[3] * weight[i];
                        }
                        w += weight[i];
                    }
                    n += 1;
                }
                let n = n.max(1) as f32;
                let a = alpha / n;
                let o = index(out, [x, y, z]);
                let k = if w > 0.0 { a / w } else { 0.0 };
                dst[o] = [color[0] * k, color[1] * k, color[2] * k, a];
                dst_weight[o] = w / n;
            }
        }
    }
    (dst, dst_weight)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mips_keep_mean_opacity_and_the_surface_colour() {
        // A 4³ level: one opaque surface texel of radiance 0.8, one interior (opaque, dark)
        // texel, in the same 2×2×2 block.
        let dims = [4; 3];
        let mut src = vec![[0f32; 4]; 64];
        let mut weight = vec![0f32; 64];
        src[index(dims, [0, 0, 0])] = [0.8, 0.4, 0.2, 1.0];
        weight[index(dims, [0, 0, 0])] = 1.0;
        src[index(dims, [1, 0, 0])] = [0.0, 0.0, 0.0, 1.0];
        let (mip, w) = downsample(&src, &weight, dims);
        assert_eq!(mip.len(), 8);
        let t = mip[0];
        // Opacity 2/8; colour that of the surface texel alone, premultiplied.
        assert!((t[3] - 0.25).abs() < 1e-6, "{t:?}");
        for (k, c) in [0.8f32, 0.4, 0.2].iter().enumerate() {
            assert!((t[k] - c * 0.25).abs() < 1e-6, "{t:?}");
        }
        assert!((w[0] - 0.125).abs() < 1e-6);
        assert!(mip[1..].iter().all(|t| *t == [0.0; 4]));
    }

    #[test]
    fn no_instance_gives_one_empty_cell() {
        let v = RadianceVolume::build(&[], &Light::default(), 64);
        assert_eq!((v.dims, v.occupied, v.mips.len()), ([1; 3], 0, 1));
    }
}
