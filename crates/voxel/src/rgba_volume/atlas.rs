//! The GPU layout of RGBA volumes: every stored brick of every level of every volume in
//! one 3D atlas texture, each with a one-texel apron, and per level a brick table.
//!
//! Hardware trilinear filtering reads the two texels around a sample on each axis. A brick
//! holds texels `8b .. 8b + 7` of its level; stored with its neighbours' texels
//! `8b − 1` and `8b + 8` around it (10³ texels), the whole footprint of any sample whose
//! lower texel lies in the brick is inside the stored block, so one filtered fetch gives
//! [`RgbaVolume::sample`] (exactly on the CPU; on a GPU up to its filter weights'
//! precision, often 8 fractional bits). A brick is stored when any texel of its 10³ block is
//! not empty, so a sample next to an empty brick still sees its neighbour's texels.
//! [`VolumeAtlas::sample`] is the shader's lookup on the CPU (volume_slices.wgsl follows
//! it line by line); the tests hold it to `RgbaVolume::sample`.

use super::{BRICK, EMPTY_BRICK, RgbaVolume, unquantize};

/// Texels per stored brick edge: the brick and its apron.
pub const STORED_BRICK: u32 = BRICK + 2;

/// Where one level of one volume lives in the atlas.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AtlasLevel {
    /// Texels per axis of the level.
    pub dims: [u32; 3],
    /// Bricks per axis.
    pub bricks: [u32; 3],
    /// Index of its first brick in [`VolumeAtlas::table`].
    pub table_offset: u32,
}

/// Every volume's stored bricks, packed.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeAtlas {
    /// Stored bricks per atlas axis.
    pub grid: [u32; 3],
    /// Texels per atlas axis (`grid × STORED_BRICK`).
    pub dims: [u32; 3],
    /// The atlas texels, x fastest, premultiplied RGBA8.
    pub texels: Vec<[u8; 4]>,
    /// Per brick of every level: its stored slot, or [`EMPTY_BRICK`].
    pub table: Vec<u32>,
    /// `levels[v][l]`: level `l` of volume `v`.
    pub levels: Vec<Vec<AtlasLevel>>,
    /// Bricks stored.
    pub stored: u32,
}

/// The atlas would not fit the device.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "the RGBA volumes need {bricks} bricks of {STORED_BRICK}³ texels, an atlas of {needed:?} \
     texels; the device allows {limit} per 3D texture axis"
)]
pub struct AtlasTooLarge {
    /// Bricks to store.
    pub bricks: u32,
    /// The atlas size they need.
    pub needed: [u32; 3],
    /// The device's largest 3D texture edge.
    pub limit: u32,
}

fn brick_block(level: &super::BrickedLevel, b: [u32; 3]) -> Option<Vec<[u8; 4]>> {
    let n = STORED_BRICK as usize;
    let mut block = vec![[0u8; 4]; n * n * n];
    let mut any = false;
    for z in 0..STORED_BRICK {
        for y in 0..STORED_BRICK {
            for x in 0..STORED_BRICK {
                let c: [i64; 3] =
                    std::array::from_fn(|k| i64::from(b[k] * BRICK) + i64::from([x, y, z][k]) - 1);
                let t = level.texel(c);
                any |= t != [0; 4];
                block[x as usize + n * (y as usize + n * z as usize)] = t;
            }
        }
    }
    any.then_some(block)
}

impl VolumeAtlas {
    /// Packs `volumes` into one atlas whose edges are at most `max_edge` texels.
    pub fn build(volumes: &[&RgbaVolume], max_edge: u32) -> Result<Self, AtlasTooLarge> {
        let mut blocks = Vec::new();
        let mut table = Vec::new();
        let mut levels = Vec::new();
        for v in volumes {
            let mut lv = Vec::new();
            for level in &v.levels {
                lv.push(AtlasLevel {
                    dims: level.dims,
                    bricks: level.bricks,
                    table_offset: table.len() as u32,
                });
                for bz in 0..level.bricks[2] {
                    for by in 0..level.bricks[1] {
                        for bx in 0..level.bricks[0] {
                            match brick_block(level, [bx, by, bz]) {
                                Some(block) => {
                                    table.push(blocks.len() as u32);
                                    blocks.push(block);
                                }
                                None => table.push(EMPTY_BRICK),
                            }
                        }
                    }
                }
            }
            levels.push(lv);
        }
        let n = blocks.len().max(1) as u32;
        // A near-cubic grid: the fewest texels per axis for the bricks.
        let side = (f64::from(n).cbrt().ceil() as u32).max(1);
        let gx = side;
        let gy = n.div_ceil(gx).min(side);
        let gz = n.div_ceil(gx * gy);
        let grid = [gx, gy, gz];
        let dims = grid.map(|g| g * STORED_BRICK);
        if dims.iter().any(|&d| d > max_edge) {
            return Err(AtlasTooLarge {
                bricks: blocks.len() as u32,
                needed: dims,
                limit: max_edge,
            });
        }
        let mut texels = vec![[0u8; 4]; dims.iter().map(|&d| d as usize).product()];
        let s = STORED_BRICK as usize;
        for (i, block) in blocks.iter().enumerate() {
            let o = Self::slot_origin_in(grid, i as u32).map(|v| v as usize);
            for z in 0..s {
                for y in 0..s {
                    let row = o[0] + dims[0] as usize * (o[1] + y + dims[1] as usize * (o[2] + z));
                    texels[row..row + s].copy_from_slice(&block[s * (y + s * z)..][..s]);
                }
            }
        }
        Ok(Self {
            grid,
            dims,
            texels,
            table,
            levels,
            stored: blocks.len() as u32,
        })
    }

    fn slot_origin_in(grid: [u32; 3], slot: u32) -> [u32; 3] {
        [
            slot % grid[0],
            (slot / grid[0]) % grid[1],
            slot / (grid[0] * grid[1]),
        ]
        .map(|g| g * STORED_BRICK)
    }

    /// The atlas texel of stored slot `slot`'s apron corner (its texel `8b − 1`).
    pub fn slot_origin(&self, slot: u32) -> [u32; 3] {
        Self::slot_origin_in(self.grid, slot)
    }

    /// Bytes on the GPU: the atlas texels and the brick tables.
    pub fn bytes(&self) -> u64 {
        self.texels.len() as u64 * 4 + self.table.len() as u64 * 4
    }

    /// The shader's filtered lookup of level `level` of volume `volume` at object-space
    /// point `p`: the brick holding the footprint's lower texel, then trilinear filtering
    /// of the atlas (texel centres at `+ ½`, clamped to the atlas).
    pub fn sample(&self, volume: usize, level: usize, p: [f64; 3]) -> [f32; 4] {
        let l = self.levels[volume][level];
        let u: [f64; 3] = std::array::from_fn(|k| (p[k] + 1.0) * 0.5 * f64::from(l.dims[k]));
        let i0 = u.map(|v| (v - 0.5).floor());
        // Both texels of the footprint outside the level on some axis: nothing there.
        if (0..3).any(|k| i0[k] < -1.0 || i0[k] > f64::from(l.dims[k]) - 1.0) {
            return [0.0; 4];
        }
        let b: [u32; 3] = std::array::from_fn(|k| {
            ((i0[k] / f64::from(BRICK)).floor().max(0.0) as u32).min(l.bricks[k] - 1)
        });
        let slot = self.table
            [(l.table_offset + b[0] + l.bricks[0] * (b[1] + l.bricks[1] * b[2])) as usize];
        if slot == EMPTY_BRICK {
            return [0.0; 4];
        }
        let o = self.slot_origin(slot);
        // Atlas texel coordinate: the level's, moved so texel 8b − 1 lands on the slot's
        // corner.
        let a: [f64; 3] =
            std::array::from_fn(|k| u[k] - f64::from(b[k] * BRICK) + 1.0 + f64::from(o[k]));
        let f = a.map(|v| v - 0.5);
        let base = f.map(f64::floor);
        let mut out = [0f64; 4];
        for corner in 0..8u32 {
            let off = [corner & 1, (corner >> 1) & 1, corner >> 2];
            let w: f64 = (0..3)
                .map(|k| {
                    let t = f[k] - base[k];
                    if off[k] == 1 { t } else { 1.0 - t }
                })
                .product();
            let c: [usize; 3] = std::array::from_fn(|k| {
                (base[k] + f64::from(off[k])).clamp(0.0, f64::from(self.dims[k] - 1)) as usize
            });
            let t = unquantize(
                self.texels[c[0] + self.dims[0] as usize * (c[1] + self.dims[1] as usize * c[2])],
            );
            for k in 0..4 {
                out[k] += w * f64::from(t[k]);
            }
        }
        out.map(|v| v as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rgba_volume::sources::Cloud;

    /// The atlas lookup equals the volume's own trilinear sample everywhere: inside
    /// bricks, across brick edges, next to empty bricks, in the half-texel fade outside
    /// the box and beyond it, at every level.
    #[test]
    fn the_atlas_lookup_is_the_volumes_sample() {
        let cloud = Cloud {
            seed: 7,
            density: 6.0,
            colour: [0.9, 0.8, 0.7],
        }
        .volume(32)
        .unwrap();
        let mut sparse = vec![[0f32; 4]; 16 * 16 * 16];
        // One texel lit in a corner brick, the rest empty: its neighbours' aprons matter.
        sparse[7 + 16 * (8 + 16 * 3)] = [0.2, 0.1, 0.0, 0.5];
        let sparse = RgbaVolume::from_texels([16; 3], &sparse).unwrap();
        let atlas = VolumeAtlas::build(&[&cloud, &sparse], 2048).unwrap();
        assert!(atlas.stored > 0 && atlas.dims.iter().all(|&d| d <= 2048));
        let mut worst = 0f32;
        let mut lit = 0;
        for (vi, v) in [&cloud, &sparse].iter().enumerate() {
            for level in 0..v.levels.len() {
                let n = 23;
                for i in 0..n * n * n {
                    let g = [i % n, (i / n) % n, i / (n * n)];
                    // -1.2 .. 1.2: outside, the fade and inside; irrational-ish offsets.
                    let p = g.map(|c| -1.2 + 2.4 * (c as f64 + 0.37) / n as f64);
                    let want = v.sample(level, p);
                    let got = atlas.sample(vi, level, p);
                    lit += (want[3] > 0.0) as usize;
                    for k in 0..4 {
                        worst = worst.max((want[k] - got[k]).abs());
                    }
                }
            }
        }
        assert!(lit > 1000, "{lit}");
        assert!(worst < 1e-6, "{worst}");
        // The grid holds every stored brick without a wasted layer of slots.
        let slots = atlas.grid.iter().product::<u32>();
        assert!(
            slots >= atlas.stored && slots < atlas.stored + atlas.grid[0] * atlas.grid[1],
            "{:?} for {}",
            atlas.grid,
            atlas.stored
        );
        assert_eq!(atlas.dims, atlas.grid.map(|g| g * 10));
    }

    /// Empty bricks are not stored, and a too-small device limit names what is needed.
    #[test]
    fn sparse_volumes_store_few_bricks_and_oversize_atlases_are_refused() {
        // A 7³ block in the corner: inside brick 0, clear of its neighbours' aprons, and
        // dense enough to stay visible at every level.
        let mut texels = vec![[0f32; 4]; 64 * 64 * 64];
        for z in 0..7 {
            for y in 0..7 {
                for x in 0..7 {
                    texels[x + 64 * (y + 64 * z)] = [0.1, 0.1, 0.1, 0.5];
                }
            }
        }
        let v = RgbaVolume::from_texels([64; 3], &texels).unwrap();
        let atlas = VolumeAtlas::build(&[&v], 2048).unwrap();
        // One brick per level, 7 levels (64 → 1).
        assert_eq!(atlas.stored, 7);
        // Seven 10³ blocks in a 2×2×2 grid: 20³ texels of 4 bytes, and one table entry per
        // brick position of every level (512 + 64 + 8 + 1 + 1 + 1 + 1).
        assert_eq!(atlas.dims, [20; 3]);
        assert_eq!(atlas.bytes(), 20 * 20 * 20 * 4 + 588 * 4);
        // An edge limit equal to the size needed is enough; one less is refused.
        assert!(VolumeAtlas::build(&[&v], 20).is_ok());
        let err = VolumeAtlas::build(&[&v], 19).unwrap_err();
        assert_eq!(err.limit, 19);
        assert_eq!(err.needed, [20; 3]);
        assert!(err.to_string().contains("7 bricks"), "{err}");
    }
}
