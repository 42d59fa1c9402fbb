//! Where RGBA volumes come from: a density field (the procedural cloud is one), a voxel
//! model with palette alpha (VOX) and a mesh voxelized with fractional coverage.

use glam::DVec3;

use super::{RgbaVolume, RgbaVolumeError, max_edge};
use crate::model::{Mesh, ObjectSpace, VoxelModel};
use crate::progress::NoProgress;
use crate::svo::morton_decode;
use crate::voxelize::voxelize_mesh;

/// Texel `c`'s centre in object space.
fn centre(dims: [u32; 3], c: [u32; 3]) -> DVec3 {
    DVec3::from(std::array::from_fn::<f64, 3, _>(|k| {
        -1.0 + (f64::from(c[k]) + 0.5) * 2.0 / f64::from(dims[k])
    }))
}

/// A volume of `dims` texels from a field giving, at an object-space point, an extinction
/// (per object-space unit, ≥ 0) and a linear colour. Each texel samples its centre; its
/// alpha is the absorption over the reference length. Non-finite or negative values are
/// refused with the texel.
pub fn from_density(
    dims: [u32; 3],
    field: impl Fn(DVec3) -> (f32, [f32; 3]),
) -> Result<RgbaVolume, RgbaVolumeError> {
    if dims.iter().any(|&d| d == 0 || d > super::MAX_EDGE) {
        return Err(RgbaVolumeError::BadSize(dims));
    }
    let h = 2.0 / f64::from(max_edge(dims));
    let mut texels = Vec::with_capacity(dims.iter().map(|&d| d as usize).product());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let texel = [x, y, z];
                let (sigma, colour) = field(centre(dims, texel));
                if !sigma.is_finite() || colour.iter().any(|c| !c.is_finite()) {
                    return Err(RgbaVolumeError::NonFinite {
                        what: "density or colour",
                        texel,
                    });
                }
                if sigma < 0.0 {
                    return Err(RgbaVolumeError::OutOfRange {
                        what: "density",
                        value: sigma,
                        texel,
                    });
                }
                let a = (1.0 - (-f64::from(sigma) * h).exp()) as f32;
                let c = colour.map(|v| v.clamp(0.0, 1.0) * a);
                texels.push([c[0], c[1], c[2], a]);
            }
        }
    }
    RgbaVolume::from_texels(dims, &texels)
}

/// A few overlapping puffs of value noise: translucent test data with soft edges and fine
/// detail. Deterministic for a `seed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cloud {
    /// Seed of the puff layout and the noise.
    pub seed: u64,
    /// Peak extinction per object-space unit.
    pub density: f32,
    /// Linear colour of the lit side; the bottom is 40 % darker.
    pub colour: [f32; 3],
}

impl Default for Cloud {
    /// Seed 1, density 8, white.
    fn default() -> Self {
        Self {
            seed: 1,
            density: 8.0,
            colour: [1.0, 1.0, 1.0],
        }
    }
}

fn hash(mut x: u64) -> f64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((x ^ (x >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// Trilinear value noise in [0, 1] on the integer lattice.
fn value_noise(p: DVec3, seed: u64) -> f64 {
    let b = p.floor();
    let f = p - b;
    let s = f * f * (DVec3::splat(3.0) - 2.0 * f);
    let mut v = 0.0;
    for corner in 0..8u32 {
        let o = [corner & 1, (corner >> 1) & 1, corner >> 2].map(f64::from);
        let c = b + DVec3::from(o);
        let key = (c.x as i64 as u64).wrapping_mul(73_856_093)
            ^ (c.y as i64 as u64).wrapping_mul(19_349_663)
            ^ (c.z as i64 as u64).wrapping_mul(83_492_791)
            ^ seed;
        let w = (0..3)
            .map(|k| if o[k] == 1.0 { s[k] } else { 1.0 - s[k] })
            .product::<f64>();
        v += w * hash(key);
    }
    v
}

impl Cloud {
    /// Extinction and colour at an object-space point.
    pub fn at(&self, p: DVec3) -> (f32, [f32; 3]) {
        // Five puffs around the centre, flattened at the bottom like a cumulus.
        let mut shape = 0.0f64;
        for i in 0..5u64 {
            let r = |k: u64| hash(self.seed.wrapping_mul(31).wrapping_add(i * 7 + k)) * 2.0 - 1.0;
            let c = DVec3::new(r(0) * 0.45, r(1) * 0.2, r(2) * 0.45);
            let radius = 0.45 + 0.25 * (r(3) * 0.5 + 0.5);
            let d = (p - c).length() / radius;
            shape = shape.max(1.0 - d);
        }
        let bottom = ((p.y + 0.35) * 4.0).clamp(0.0, 1.0);
        let mut fbm = 0.0;
        let mut amp = 0.5;
        let mut freq = 4.0;
        for octave in 0..4u64 {
            fbm += amp * value_noise(p * freq, self.seed ^ (octave << 32));
            amp *= 0.5;
            freq *= 2.0;
        }
        let density = ((shape * 1.5 + fbm - 0.6) * 2.0).clamp(0.0, 1.0) * bottom;
        let shade = 0.6 + 0.4 * ((p.y + 0.5) * 1.2).clamp(0.0, 1.0) as f32;
        (
            self.density * density as f32,
            self.colour.map(|c| c * shade),
        )
    }

    /// The cloud as a volume of `edge`³ texels.
    pub fn volume(&self, edge: u32) -> Result<RgbaVolume, RgbaVolumeError> {
        from_density([edge; 3], |p| self.at(p))
    }
}

/// A voxel model (VOX: each voxel's palette colour with its alpha; a palette without alpha
/// is opaque) fitted into object space like opaque objects (bounding box centred, longest
/// extent → [-1, 1]) and resampled onto `edge`³ texels (a power of two) by box overlap: a
/// voxel's alpha holds over its own edge, so it becomes an extinction; a texel takes the
/// overlap-weighted mean extinction of the voxels covering it and turns it back into alpha
/// over its own edge, its colour their extinction-weighted mean. At the model's own
/// resolution, with a cubic bounding box, texels are its voxels; twice as fine, a
/// half-transparent voxel becomes texels of alpha 1 − 0.5^½.
pub fn from_voxel_model(model: &VoxelModel, edge: u32) -> Result<RgbaVolume, RgbaVolumeError> {
    if edge == 0 || edge > super::MAX_EDGE {
        return Err(RgbaVolumeError::BadSize([edge; 3]));
    }
    let dims = [edge; 3];
    let n = (edge as usize).pow(3);
    let Some(first) = model.voxels.first() else {
        return RgbaVolume::from_texels(dims, &vec![[0.0; 4]; n]);
    };
    let (mut lo, mut hi) = (*first, first.map(|v| v + 1));
    for v in &model.voxels {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k] + 1);
        }
    }
    let space = ObjectSpace::from_bounds(
        DVec3::from(lo.map(f64::from)),
        DVec3::from(hi.map(f64::from)),
    );
    let to_texel = |p: DVec3| (space.to_object(p) + DVec3::ONE) * (0.5 * f64::from(edge));
    // A voxel's edge in texels: its alpha holds over that length.
    let voxel_len = to_texel(DVec3::ONE).x - to_texel(DVec3::ZERO).x;
    let mut sum = vec![[0f64; 4]; n];
    for (v, c) in model.voxels.iter().zip(&model.colors) {
        let a0 = to_texel(DVec3::from(v.map(f64::from)));
        let a1 = to_texel(DVec3::from(v.map(|x| f64::from(x) + 1.0)));
        // Extinction per texel length.
        let sigma = -(1.0 - f64::from(c[3].clamp(0.0, 1.0)).min(1.0 - 1e-6)).ln() / voxel_len;
        let range = |k: usize| {
            let first = (a0[k].floor().max(0.0) as u32).min(edge - 1);
            let last = ((a1[k].ceil() as u32).saturating_sub(1)).clamp(first, edge - 1);
            first..=last
        };
        for z in range(2) {
            for y in range(1) {
                for x in range(0) {
                    let t = [x, y, z];
                    let overlap: f64 = (0..3)
                        .map(|k| {
                            let (t0, t1) = (f64::from(t[k]), f64::from(t[k]) + 1.0);
                            (a1[k].min(t1) - a0[k].max(t0)).max(0.0)
                        })
                        .product();
                    let w = sigma * overlap;
                    let i = x as usize + edge as usize * (y as usize + edge as usize * z as usize);
                    for k in 0..3 {
                        sum[i][k] += f64::from(c[k].clamp(0.0, 1.0)) * w;
                    }
                    sum[i][3] += w;
                }
            }
        }
    }
    let texels: Vec<[f32; 4]> = sum
        .iter()
        .map(|s| {
            // s[3]: the texel's extinction per texel length.
            let a = 1.0 - (-s[3]).exp();
            let k = if s[3] > 0.0 { a / s[3] } else { 0.0 };
            [
                (s[0] * k) as f32,
                (s[1] * k) as f32,
                (s[2] * k) as f32,
                a as f32,
            ]
        })
        .collect();
    RgbaVolume::from_texels(dims, &texels)
}

/// The finest level [`from_mesh_coverage`] accepts: it voxelizes two levels finer and
/// keeps two flags per fine cell (2 × 512³ bytes at level 7).
pub const MAX_COVERAGE_LEVEL: u32 = 7;

/// A mesh as an RGBA volume of `2^level` texels per axis with fractional coverage: the
/// mesh is voxelized four times finer, the cells its surface encloses are filled
/// ([`crate::enclosure`]), and each texel's alpha is the fraction of its 4³ fine cells that
/// are filled, its colour the mean of its surface cells' colours (the mesh's mean colour
/// for a texel wholly inside).
pub fn from_mesh_coverage(mesh: &Mesh, level: u32) -> Result<RgbaVolume, RgbaVolumeError> {
    if level > MAX_COVERAGE_LEVEL {
        return Err(RgbaVolumeError::BadSize([1 << level.min(16); 3]));
    }
    let fine = voxelize_mesh(mesh, level + 2, &NoProgress)
        .map_err(|e| RgbaVolumeError::Voxelize(e.to_string()))?;
    let edge = 1u32 << level;
    let fine_edge = edge * 4;
    let fdims = [fine_edge; 3];
    let idx = |c: [u32; 3]| {
        c[0] as usize + fine_edge as usize * (c[1] as usize + fine_edge as usize * c[2] as usize)
    };
    let mut surface = vec![false; (fine_edge as usize).pow(3)];
    let mut mean = [0f64; 3];
    for (code, c) in fine.voxels.codes.iter().zip(&fine.voxels.colors) {
        surface[idx(morton_decode(*code))] = true;
        for k in 0..3 {
            mean[k] += f64::from(c[k]);
        }
    }
    let count = fine.voxels.codes.len().max(1) as f64;
    let mean = mean.map(|m| (m / count) as f32);
    let filled = crate::enclosure::enclosed(&surface, fdims);
    // Colours of surface cells by Morton code (the codes are sorted).
    let colour_of = |c: [u32; 3]| {
        let code = crate::svo::morton_encode(c);
        fine.voxels
            .codes
            .binary_search(&code)
            .ok()
            .map(|i| fine.voxels.colors[i])
    };
    let mut texels = vec![[0f32; 4]; (edge as usize).pow(3)];
    for z in 0..edge {
        for y in 0..edge {
            for x in 0..edge {
                let (mut inside, mut on) = (0u32, 0u32);
                let mut sum = [0f32; 3];
                for dz in 0..4 {
                    for dy in 0..4 {
                        for dx in 0..4 {
                            let c = [x * 4 + dx, y * 4 + dy, z * 4 + dz];
                            inside += u32::from(filled[idx(c)]);
                            if let Some(col) = surface[idx(c)].then(|| colour_of(c)).flatten() {
                                on += 1;
                                for k in 0..3 {
                                    sum[k] += col[k];
                                }
                            }
                        }
                    }
                }
                let a = inside as f32 / 64.0;
                let c = if on > 0 {
                    sum.map(|s| s / on as f32)
                } else {
                    mean
                };
                let t = x as usize + edge as usize * (y as usize + edge as usize * z as usize);
                texels[t] = [c[0] * a, c[1] * a, c[2] * a, a];
            }
        }
    }
    RgbaVolume::from_texels([edge; 3], &texels)
}
