//! RGBA volumes (volumetric billboards): translucent objects stored as
//! premultiplied RGBA texels over object space [-1, 1]³, mipmapped, kept sparse in bricks.
//!
//! - **Texels.** Level 0 has `dims` texels per axis; texel `c`'s centre is at
//!   `-1 + (c + ½) · 2 / dims` per axis. A texel holds premultiplied linear colour and an
//!   alpha that means "the fraction of light absorbed over the reference length `h`", the
//!   level's texel edge along its longest axis (`2 / max(dims)` in object space; texels are
//!   cubes when the volume is): the extinction is `σ = -ln(1 - α) / h`, and the emitted
//!   colour per unit of absorbed light is `rgb / α`. Slicing one slice per texel slab with
//!   the "over" operator reproduces the integral ([`integrate`]); other spacings correct
//!   alpha to `1 - (1 - α)^(step / h)`.
//! - **Mip levels** halve each axis (at least 1). A coarser texel holds the mean
//!   extinction and mean emission of its children, converted back for its doubled length,
//!   so a homogeneous medium keeps its transmittance at every level (plain alpha averaging
//!   would make a coarse level half as opaque).
//! - **Bricks.** Each level is cut into 8³ bricks; bricks whose texels are all empty are not
//!   stored (volumetric billboards' empty-space removal at a fixed granularity). Texels are 4 bytes
//!   (RGBA8, premultiplied), what the GPU samples; the CPU reference reads the same values.
//!
//! Sources ([`sources`]): a procedural cloud, a VOX model (palette alpha) and a mesh
//! voxelized with fractional coverage.

pub mod atlas;
pub mod integrate;
pub mod slicing;
pub mod sources;

use thiserror::Error;

/// Texels per brick edge.
pub const BRICK: u32 = 8;
/// The largest level-0 edge accepted (512³ texels are 512 MiB before brick removal).
pub const MAX_EDGE: u32 = 512;
/// No brick here (`BrickedLevel::table`).
pub const EMPTY_BRICK: u32 = u32::MAX;

/// Why a volume could not be built.
#[derive(Debug, Error, PartialEq)]
pub enum RgbaVolumeError {
    /// An edge that is not a power of two from 1 to [`MAX_EDGE`] (the mip levels of a
    /// texture halve exactly only then).
    #[error("a volume of {0:?} texels: each edge must be a power of two from 1 to {MAX_EDGE}")]
    BadSize([u32; 3]),
    /// A density, alpha or colour that is NaN or infinite.
    #[error("a non-finite {what} at texel {texel:?}")]
    NonFinite {
        /// Which value.
        what: &'static str,
        /// Where (level-0 texel).
        texel: [u32; 3],
    },
    /// The mesh could not be voxelized.
    #[error("voxelizing the mesh: {0}")]
    Voxelize(String),
    /// A value outside its range (a negative density, an alpha above 1).
    #[error("{what} {value} at texel {texel:?} is outside its range")]
    OutOfRange {
        /// Which value.
        what: &'static str,
        /// The value.
        value: f32,
        /// Where (level-0 texel).
        texel: [u32; 3],
    },
}

/// One mip level, bricked.
#[derive(Debug, Clone, PartialEq)]
pub struct BrickedLevel {
    /// Texels per axis.
    pub dims: [u32; 3],
    /// Bricks per axis (`ceil(dims / BRICK)`).
    pub bricks: [u32; 3],
    /// Per brick (x fastest): its index in `data` (in bricks), or [`EMPTY_BRICK`].
    pub table: Vec<u32>,
    /// The stored bricks' texels, `BRICK³` each (x fastest), premultiplied RGBA8.
    pub data: Vec<[u8; 4]>,
}

/// A mipmapped, bricked RGBA volume.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbaVolume {
    /// `levels[0]` is the finest.
    pub levels: Vec<BrickedLevel>,
}

/// The longest of three edges.
pub fn max_edge(dims: [u32; 3]) -> u32 {
    dims[0].max(dims[1]).max(dims[2])
}

/// Index of cell `c` in an x-fastest grid of `dims`.
pub(crate) fn index(dims: [u32; 3], c: [u32; 3]) -> usize {
    c[0] as usize + dims[0] as usize * (c[1] as usize + dims[1] as usize * c[2] as usize)
}

/// The cells of a grid of `dims` under cell `parent` of the next coarser grid: its 2×2×2
/// children that lie inside `dims`, x fastest, then y, then z.
pub(crate) fn children(dims: [u32; 3], parent: [u32; 3]) -> impl Iterator<Item = [u32; 3]> {
    (0..2)
        .flat_map(move |dz| {
            (0..2).flat_map(move |dy| {
                (0..2).map(move |dx| [2 * parent[0] + dx, 2 * parent[1] + dy, 2 * parent[2] + dz])
            })
        })
        .filter(move |c| c.iter().zip(dims).all(|(&c, d)| c < d))
}

/// Premultiplied f32 RGBA → RGBA8 (rounded; colour clamped to alpha so it stays
/// premultiplied).
fn quantize(t: [f32; 4]) -> [u8; 4] {
    let a = t[3].clamp(0.0, 1.0);
    let q = |v: f32| (v.clamp(0.0, a) * 255.0 + 0.5) as u8;
    [q(t[0]), q(t[1]), q(t[2]), (a * 255.0 + 0.5) as u8]
}

/// RGBA8 → premultiplied f32 RGBA.
pub fn unquantize(t: [u8; 4]) -> [f32; 4] {
    t.map(|v| f32::from(v) / 255.0)
}

impl BrickedLevel {
    fn from_dense(dims: [u32; 3], texels: &[[u8; 4]]) -> Self {
        let bricks = dims.map(|d| d.div_ceil(BRICK));
        let count = bricks.iter().map(|&b| b as usize).product();
        let mut table = vec![EMPTY_BRICK; count];
        let mut data = Vec::new();
        let b3 = (BRICK * BRICK * BRICK) as usize;
        for bz in 0..bricks[2] {
            for by in 0..bricks[1] {
                for bx in 0..bricks[0] {
                    let mut brick = vec![[0u8; 4]; b3];
                    let mut any = false;
                    for z in 0..BRICK {
                        for y in 0..BRICK {
                            for x in 0..BRICK {
                                let c = [bx * BRICK + x, by * BRICK + y, bz * BRICK + z];
                                if c.iter().zip(dims).any(|(&c, d)| c >= d) {
                                    continue;
                                }
                                let t = texels[index(dims, c)];
                                any |= t != [0; 4];
                                brick[index([BRICK; 3], [x, y, z])] = t;
                            }
                        }
                    }
                    if any {
                        table[index(bricks, [bx, by, bz])] = (data.len() / b3) as u32;
                        data.extend_from_slice(&brick);
                    }
                }
            }
        }
        Self {
            dims,
            bricks,
            table,
            data,
        }
    }

    /// The texel at `c` (transparent black outside the level or in an empty brick).
    pub fn texel(&self, c: [i64; 3]) -> [u8; 4] {
        if c.iter()
            .zip(self.dims)
            .any(|(&c, d)| c < 0 || c >= i64::from(d))
        {
            return [0; 4];
        }
        let c = c.map(|v| v as u32);
        let b = c.map(|v| v / BRICK);
        let slot = self.table[index(self.bricks, b)];
        if slot == EMPTY_BRICK {
            return [0; 4];
        }
        let local = c.map(|v| v % BRICK);
        let b3 = (BRICK * BRICK * BRICK) as usize;
        self.data[slot as usize * b3 + index([BRICK; 3], local)]
    }

    /// Stored bricks.
    pub fn stored_bricks(&self) -> usize {
        self.table.iter().filter(|&&s| s != EMPTY_BRICK).count()
    }
}

impl RgbaVolume {
    /// Builds the volume from level-0 premultiplied linear RGBA texels (x fastest), alpha
    /// per texel length. Rejects a bad size and non-finite or out-of-range values, naming
    /// the texel.
    pub fn from_texels(dims: [u32; 3], texels: &[[f32; 4]]) -> Result<Self, RgbaVolumeError> {
        if dims.iter().any(|&d| !d.is_power_of_two() || d > MAX_EDGE)
            || texels.len() != dims.iter().map(|&d| d as usize).product::<usize>()
        {
            return Err(RgbaVolumeError::BadSize(dims));
        }
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let t = texels[index(dims, [x, y, z])];
                    let texel = [x, y, z];
                    if t.iter().any(|v| !v.is_finite()) {
                        return Err(RgbaVolumeError::NonFinite {
                            what: "colour or alpha",
                            texel,
                        });
                    }
                    if !(0.0..=1.0).contains(&t[3]) {
                        return Err(RgbaVolumeError::OutOfRange {
                            what: "alpha",
                            value: t[3],
                            texel,
                        });
                    }
                }
            }
        }
        let mut dense: Vec<[f32; 4]> = texels.to_vec();
        let mut d = dims;
        let mut levels = vec![BrickedLevel::from_dense(
            d,
            &dense.iter().map(|&t| quantize(t)).collect::<Vec<_>>(),
        )];
        while d != [1, 1, 1] {
            let (next, nd) = downsample(&dense, d);
            levels.push(BrickedLevel::from_dense(
                nd,
                &next.iter().map(|&t| quantize(t)).collect::<Vec<_>>(),
            ));
            dense = next;
            d = nd;
        }
        Ok(Self { levels })
    }

    /// Texels per axis of level 0.
    pub fn dims(&self) -> [u32; 3] {
        self.levels[0].dims
    }

    /// Bytes of the stored bricks of every level (4 per texel) plus the brick tables.
    pub fn bytes(&self) -> u64 {
        self.levels
            .iter()
            .map(|l| l.data.len() as u64 * 4 + l.table.len() as u64 * 4)
            .sum()
    }

    /// Bytes the same levels would take dense (4 per texel, no bricks).
    pub fn dense_bytes(&self) -> u64 {
        self.levels
            .iter()
            .map(|l| l.dims.iter().map(|&d| u64::from(d)).product::<u64>() * 4)
            .sum()
    }

    /// Trilinearly filtered premultiplied RGBA of level `level` at object-space point `p`
    /// (texel centres as in the module docs; transparent outside the volume, so edges fade
    /// over half a texel).
    pub fn sample(&self, level: usize, p: [f64; 3]) -> [f32; 4] {
        let l = &self.levels[level.min(self.levels.len() - 1)];
        let f: [f64; 3] = std::array::from_fn(|k| (p[k] + 1.0) * 0.5 * f64::from(l.dims[k]) - 0.5);
        let base = f.map(|v| v.floor());
        let w = [f[0] - base[0], f[1] - base[1], f[2] - base[2]];
        let mut out = [0f64; 4];
        for corner in 0..8u32 {
            let o = [corner & 1, (corner >> 1) & 1, corner >> 2];
            let weight: f64 = (0..3)
                .map(|k| if o[k] == 1 { w[k] } else { 1.0 - w[k] })
                .product();
            if weight == 0.0 {
                continue;
            }
            let c: [i64; 3] = std::array::from_fn(|k| base[k] as i64 + i64::from(o[k]));
            let t = unquantize(l.texel(c));
            for k in 0..4 {
                out[k] += weight * f64::from(t[k]);
            }
        }
        out.map(|v| v as f32)
    }
}

/// The next coarser level of premultiplied f32 texels: mean extinction and emission of the
/// children present, back to alpha over the doubled texel length (module docs).
fn downsample(src: &[[f32; 4]], dims: [u32; 3]) -> (Vec<[f32; 4]>, [u32; 3]) {
    let out = dims.map(|d| (d / 2).max(1));
    // Alpha is per reference length (module docs), which grows with the longest edge.
    let length = f64::from(max_edge(dims)) / f64::from(max_edge(out));
    let mut dst = vec![[0f32; 4]; out.iter().map(|&d| d as usize).product()];
    for z in 0..out[2] {
        for y in 0..out[1] {
            for x in 0..out[0] {
                let mut sigma = 0f64;
                let mut emit = [0f64; 3];
                let mut n = 0u32;
                for c in children(dims, [x, y, z]) {
                    let t = src[index(dims, c)];
                    let a = f64::from(t[3]).min(1.0 - 1e-7);
                    let s = -(1.0 - a).ln();
                    sigma += s;
                    if a > 0.0 {
                        for k in 0..3 {
                            emit[k] += f64::from(t[k]) / a * s;
                        }
                    }
                    n += 1;
                }
                let n = f64::from(n.max(1));
                let (sigma, emit) = (sigma / n, emit.map(|e| e / n));
                let alpha = 1.0 - (-sigma * length).exp();
                let colour = if sigma > 0.0 {
                    emit.map(|e| e / sigma * alpha)
                } else {
                    [0.0; 3]
                };
                dst[index(out, [x, y, z])] = [
                    colour[0] as f32,
                    colour[1] as f32,
                    colour[2] as f32,
                    alpha as f32,
                ];
            }
        }
    }
    (dst, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bricks_keep_every_texel_and_drop_empty_ones() {
        // 32×32×16 with one opaque texel in the far corner brick and one in the first.
        let dims = [32, 32, 16];
        let mut t = vec![[0f32; 4]; 32 * 32 * 16];
        t[index(dims, [1, 2, 3])] = [0.5, 0.25, 0.0, 0.5];
        t[index(dims, [31, 31, 15])] = [1.0, 1.0, 1.0, 1.0];
        let v = RgbaVolume::from_texels(dims, &t).unwrap();
        let l = &v.levels[0];
        assert_eq!(l.bricks, [4, 4, 2]);
        assert_eq!(l.stored_bricks(), 2);
        assert_eq!(l.texel([1, 2, 3]), [128, 64, 0, 128]);
        assert_eq!(l.texel([31, 31, 15]), [255; 4]);
        assert_eq!(l.texel([5, 5, 5]), [0; 4]);
        assert_eq!(l.texel([-1, 0, 0]), [0; 4]);
        // Level 0 keeps 2 of 32 bricks (coarse levels of a small volume are smaller dense
        // than in whole bricks).
        assert_eq!(l.data.len(), 2 * 512);
        assert!(v.bytes() < v.dense_bytes());
        // 32 → 16 → 8 → 4 → 2 → 1 (the short axis reaches 1 first).
        let edges: Vec<[u32; 3]> = v.levels.iter().map(|l| l.dims).collect();
        assert_eq!(edges[4], [2, 2, 1]);
        assert_eq!(edges.len(), 6);
        assert!(RgbaVolume::from_texels([20, 20, 20], &vec![[0.0; 4]; 8000]).is_err());
    }

    #[test]
    fn a_homogeneous_medium_keeps_its_transmittance_at_every_level() {
        // Alpha 0.2 per texel over 16 texels: transmittance 0.8^16 along an axis; at level
        // k there are 16 / 2^k texels of alpha 1 - 0.8^(2^k).
        let dims = [16; 3];
        let v = RgbaVolume::from_texels(dims, &vec![[0.1, 0.1, 0.1, 0.2]; 4096]).unwrap();
        for (k, l) in v.levels.iter().enumerate().take(4) {
            let a = unquantize(l.texel([0, 0, 0]))[3];
            let want = 1.0 - 0.8f32.powi(1 << k);
            assert!((a - want).abs() < 0.6 / 255.0, "level {k}: {a} vs {want}");
            // The colour per unit alpha (0.5) is kept.
            let c = unquantize(l.texel([0, 0, 0]))[0] / a;
            assert!((c - 0.5).abs() < 0.02, "level {k}: {c}");
        }
    }

    #[test]
    fn bad_sizes_and_values_are_refused_with_the_texel() {
        assert_eq!(
            RgbaVolume::from_texels([0, 4, 4], &[]),
            Err(RgbaVolumeError::BadSize([0, 4, 4]))
        );
        assert!(RgbaVolume::from_texels([513, 1, 1], &vec![[0.0; 4]; 513]).is_err());
        let mut t = vec![[0f32; 4]; 8];
        t[index([2; 3], [1, 0, 1])] = [0.0, f32::NAN, 0.0, 0.5];
        assert_eq!(
            RgbaVolume::from_texels([2; 3], &t),
            Err(RgbaVolumeError::NonFinite {
                what: "colour or alpha",
                texel: [1, 0, 1]
            })
        );
        t[index([2; 3], [1, 0, 1])] = [0.0, 0.0, 0.0, 1.5];
        assert!(matches!(
            RgbaVolume::from_texels([2; 3], &t),
            Err(RgbaVolumeError::OutOfRange { what: "alpha", .. })
        ));
    }

    #[test]
    fn trilinear_sampling_hits_texel_centres_and_fades_at_the_edge() {
        let dims = [4, 4, 4];
        let v = RgbaVolume::from_texels(dims, &vec![[0.4, 0.4, 0.4, 0.4]; 64]).unwrap();
        // Texel (1, 1, 1)'s centre: -1 + 1.5 · 0.5 = -0.25.
        let s = v.sample(0, [-0.25, -0.25, -0.25]);
        assert!((s[3] - 102.0 / 255.0).abs() < 1e-6, "{s:?}");
        // At the volume's face, half the weight is outside: half the alpha.
        let e = v.sample(0, [1.0, 0.0, 0.0]);
        assert!((e[3] - 51.0 / 255.0).abs() < 1e-6, "{e:?}");
        assert_eq!(v.sample(0, [1.5, 0.0, 0.0]), [0.0; 4]);
    }
}
