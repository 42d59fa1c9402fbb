//! The supersampled reference: the ground truth of an anti-aliased frame. Each pixel is
//! split into `cols × rows` equal strata with one ray in each, jittered inside its stratum,
//! and the shaded samples are averaged (a box filter over the pixel); misses count as
//! transparent black, so alpha is the pixel's coverage and the colour is premultiplied by
//! it. Stratified rather than a regular grid: a regular grid of samples aliases into moiré
//! on the regular voxel lattice it is meant to resolve. N samples take the most nearly
//! square factorization of N (16: 4 × 4, 8: 4 × 2, a prime: N × 1 strips, still one
//! uniform sample per stratum, so unbiased). The jitter is a hash of the pixel and the
//! sample, so a render is reproducible. One sample is the pixel centre: the image of
//! [`render`](super::render), bit for bit.

use rayon::prelude::*;
use thiserror::Error;

use super::{Instance, PreparedScene, ReferenceImage, shade_with, trace_world};
use crate::camera::Camera;
use crate::shading::Light;

/// Most samples per pixel a [`SampleGrid`] takes (32 × 32).
pub const MAX_SAMPLES: u32 = 1024;

/// A sample count outside 1 to [`MAX_SAMPLES`].
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("samples per pixel must be from 1 to {MAX_SAMPLES}, got {0}")]
pub struct SampleCountError(pub u32);

/// `cols × rows` strata per pixel, one sample in each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleGrid {
    cols: u32,
    rows: u32,
}

impl SampleGrid {
    /// One sample: the pixel centre.
    pub const CENTRE: SampleGrid = SampleGrid { cols: 1, rows: 1 };

    /// The grid of `samples` strata (1 to [`MAX_SAMPLES`]): `rows` the largest divisor of
    /// `samples` not above its square root, `cols` the rest.
    pub fn from_count(samples: u32) -> Result<Self, SampleCountError> {
        if !(1..=MAX_SAMPLES).contains(&samples) {
            return Err(SampleCountError(samples));
        }
        let rows = (1..=samples.isqrt())
            .rev()
            .find(|r| samples.is_multiple_of(*r))
            .unwrap_or(1);
        Ok(SampleGrid {
            cols: samples / rows,
            rows,
        })
    }

    /// Samples per pixel (`cols × rows`).
    pub fn count(self) -> u32 {
        self.cols * self.rows
    }

    /// Strata across and down a pixel.
    pub fn strata(self) -> (u32, u32) {
        (self.cols, self.rows)
    }

    /// The position, in pixels from the image's top-left corner, of sample `i` of pixel
    /// `(px, py)`: inside stratum `(i mod cols, i div cols)`; the centre for one sample.
    pub fn position(self, px: u32, py: u32, i: u32) -> (f64, f64) {
        if self.count() == 1 {
            return (px as f64 + 0.5, py as f64 + 0.5);
        }
        let (sx, sy) = (i % self.cols, i / self.cols);
        let (jx, jy) = jitter(px, py, i);
        (
            px as f64 + (sx as f64 + jx) / self.cols as f64,
            py as f64 + (sy as f64 + jy) / self.rows as f64,
        )
    }
}

/// Two numbers in [0, 1) from a hash of the pixel and the sample (splitmix64).
fn jitter(px: u32, py: u32, i: u32) -> (f64, f64) {
    let mut h = (px as u64) << 40 ^ (py as u64) << 16 ^ i as u64;
    h = h.wrapping_add(0x9e37_79b9_7f4a_7c15);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    let unit = |bits: u64| (bits >> 11) as f64 / (1u64 << 53) as f64;
    (unit(h), unit(h.rotate_left(32) ^ 0x5851_f42d_4c95_7f2d))
}

/// Renders the reference with `grid` samples per pixel, box-filtered: `colors` are the
/// samples' mean (linear, premultiplied by coverage, which is the alpha), `hits` the
/// centre ray's as in [`render`](super::render). Rows are traced in parallel (rayon).
pub fn render_supersampled(
    instances: &[Instance],
    camera: &Camera,
    width: u32,
    height: u32,
    light: &Light,
    grid: SampleGrid,
) -> ReferenceImage {
    let scene = PreparedScene::new(instances);
    let rays = camera.pixel_rays(width, height);
    let w = width as usize;
    let len = w * height as usize;
    let mut hits = vec![None; len];
    let mut colors = vec![[0.0f32; 4]; len];
    let shade_ray = |o, d| -> ([f32; 4], _) {
        let hit = trace_world(&scene, o, d, rays.forward());
        let color = match &hit {
            Some(h) => match &scene.instances[h.instance as usize] {
                Some(p) => shade_with(p.lod, p.normal_to_world, h, d, light),
                None => [0.0; 4],
            },
            None => [0.0; 4],
        };
        (color, hit)
    };
    if w > 0 {
        hits.par_chunks_mut(w)
            .zip(colors.par_chunks_mut(w))
            .enumerate()
            .for_each(|(y, (hit_row, color_row))| {
                for x in 0..w {
                    let (px, py) = (x as u32, y as u32);
                    let (o, d) = rays.ray(px, py);
                    let (centre_color, hit) = shade_ray(o, d);
                    hit_row[x] = hit;
                    if grid == SampleGrid::CENTRE {
                        color_row[x] = centre_color;
                        continue;
                    }
                    let mut sum = [0.0f64; 4];
                    for i in 0..grid.count() {
                        let (sx, sy) = grid.position(px, py, i);
                        let (o, d) = rays.ray_at(sx, sy);
                        let (c, _) = shade_ray(o, d);
                        for (s, v) in sum.iter_mut().zip(c) {
                            *s += v as f64;
                        }
                    }
                    let n = grid.count() as f64;
                    color_row[x] = sum.map(|s| (s / n) as f32);
                }
            });
    }
    ReferenceImage {
        width,
        height,
        hits,
        colors,
    }
}
