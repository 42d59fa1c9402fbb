//! The screen tiles' instance lists: for each tile of [`LIST_TILE_PX`] × [`LIST_TILE_PX`]
//! pixels, the visible instances whose boxes may cover one of its pixels, nearest box first.
//! A ray of a crowd then tests the boxes of its tile only, in the order in which they can
//! hold its nearest hit, and stops at the first box farther than its best hit
//! (`instance_walk`, `shaders/instance_bvh.inc.wgsl`); the filter and every ray caster read
//! the same lists, so the baselines walk as cheaply as SSBVB does.
//!
//! **Why on the CPU:** the frame's hierarchy is built here already (a few thousand boxes),
//! sorting the boxes once by distance makes every tile's list sorted, and the lists then
//! cost one upload instead of a GPU scan and sort.
//!
//! **Conservative:** a box's tiles come from the same rule as the casters' tile flags
//! (`box_tiles`, `shaders/ray_cast_compute.inc.wgsl`): the pixel rectangle of its corners'
//! projections, widened by two pixels and by f32's rounding of the ratios; a box reaching
//! to or behind the camera's plane covers every tile. Every box a pixel's ray can enter is
//! on its tile's list, so the lists change which boxes are tested, never which instances
//! are hit.
//!
//! **Bounded:** a tile with more than [`MAX_TILE_LIST`] boxes has no list (its rays walk
//! the hierarchy, which tests fewer boxes there), and a frame whose boxes would fill more
//! than [`MAX_FILLS_PER_TILE`] entries a tile on average gets no lists at all, so the
//! build's time and memory follow the screen, not the crowd.
//!
//! **Layout** (u32 words, from a vec4-aligned word `base` of the hierarchy's buffer):
//! `tiles a row, tiles a column, tile side in pixels, 0`; then per tile (row-major) the
//! absolute word of its first entry and its count ([`LIST_WALK`]: no list); then the
//! entries, each the node index of an instance's leaf.

use super::layout::{FrameUniform, GpuBvhNode};

/// A tile's side in pixels.
pub const LIST_TILE_PX: u32 = 16;

/// A tile's count that means "no list: walk the hierarchy".
pub const LIST_WALK: u32 = u32::MAX;

/// Most boxes a tile lists; a tile with more walks the hierarchy.
pub const MAX_TILE_LIST: u32 = 64;

/// Most entries a tile on average (before the per-tile cap) for which a frame builds lists.
pub const MAX_FILLS_PER_TILE: u64 = 256;

/// Words before the first tile's pair.
const HEADER_WORDS: usize = 4;

/// The inclusive tile rectangle `[x0, y0, x1, y1]` holding every pixel whose ray may enter
/// the camera-relative box `lo..hi` under `frame`'s camera, or `None` when no ray can.
/// The rule of the shaders' `box_tiles`, in f64.
pub(crate) fn box_tiles(
    lo: [f32; 3],
    hi: [f32; 3],
    frame: &FrameUniform,
    tile: u32,
) -> Option<[u32; 4]> {
    let v = |a: [f32; 4]| glam::DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let (f, r, u) = (v(frame.cam_forward), v(frame.cam_right), v(frame.cam_up));
    let (w, h) = (frame.screen[0] as f64, frame.screen[1] as f64);
    let tiles = [
        (w as u32).div_ceil(tile).max(1) - 1,
        (h as u32).div_ceil(tile).max(1) - 1,
    ];
    let (mut lo_ndc, mut hi_ndc) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let (mut in_front, mut behind) = (0, 0);
    for i in 0..8 {
        let pick = |a: usize| if i & (1 << a) != 0 { hi[a] } else { lo[a] } as f64;
        let c = glam::DVec3::new(pick(0), pick(1), pick(2));
        let a = c.dot(f) / f.dot(f);
        let ndc = [c.dot(r) / r.dot(r) / a, c.dot(u) / u.dot(u) / a];
        let finite = ndc.iter().all(|n| n.abs() < 1e6);
        in_front += usize::from(a > 1e-6 * c.length() / f.length() && finite);
        behind += usize::from(a < 0.0);
        for k in 0..2 {
            lo_ndc[k] = lo_ndc[k].min(ndc[k]);
            hi_ndc[k] = hi_ndc[k].max(ndc[k]);
        }
    }
    if behind == 8 {
        return None;
    }
    if in_front < 8 {
        return Some([0, 0, tiles[0], tiles[1]]);
    }
    let jitter = [frame.jitter[0] as f64, frame.jitter[1] as f64];
    let size = [w, h];
    // Pixel k's centre ray has NDC ((k + 0.5 + jitter) / size) * 2 - 1 (y flipped).
    let k_lo = [
        (lo_ndc[0] + 1.0) * 0.5 * w - 0.5 - jitter[0],
        (-hi_ndc[1] + 1.0) * 0.5 * h - 0.5 - jitter[1],
    ];
    let k_hi = [
        (hi_ndc[0] + 1.0) * 0.5 * w - 0.5 - jitter[0],
        (-lo_ndc[1] + 1.0) * 0.5 * h - 0.5 - jitter[1],
    ];
    let mut rect = [0u32; 4];
    for k in 0..2 {
        let slack = 2.0 + (lo_ndc[k].abs().max(hi_ndc[k].abs()) + 1.0) * size[k] * 1e-5;
        let (p_lo, p_hi) = (k_lo[k] - slack, k_hi[k] + slack);
        if p_hi < 0.0 || p_lo > size[k] {
            return None;
        }
        rect[k] = (p_lo.max(0.0) as u32 / tile).min(tiles[k]);
        rect[k + 2] = (p_hi.min(size[k]) as u32 / tile).min(tiles[k]);
    }
    Some(rect)
}

/// The distance from the camera (the origin) to a camera-relative box: a lower bound on
/// where any ray from the camera enters it.
fn box_distance(n: &GpuBvhNode) -> f64 {
    let gap = |a: usize| (n.lo[a] as f64).max(-(n.hi[a] as f64)).max(0.0);
    glam::DVec3::new(gap(0), gap(1), gap(2)).length()
}

/// The tile lists of the hierarchy `nodes` (the visible instances' leaves) for `frame`'s
/// camera and screen, as words to be written at word `base` (a multiple of 4) of the
/// hierarchy's buffer; empty when the frame gets no lists (no leaf, or too many entries).
pub(crate) fn tile_lists(nodes: &[GpuBvhNode], frame: &FrameUniform, base: usize) -> Vec<u32> {
    let tile = LIST_TILE_PX;
    let tiles_x = (frame.screen[0] as u32).div_ceil(tile).max(1);
    let tiles_y = (frame.screen[1] as u32).div_ceil(tile).max(1);
    let tile_count = (tiles_x * tiles_y) as usize;
    let mut leaves: Vec<(f64, u32, [u32; 4])> = nodes
        .iter()
        .enumerate()
        .filter(|(_, n)| n.left & ssbvb_voxel::instance_bvh::LEAF != 0)
        .filter_map(|(i, n)| {
            let rect = box_tiles(n.lo, n.hi, frame, tile)?;
            Some((box_distance(n), i as u32, rect))
        })
        .collect();
    let area = |r: &[u32; 4]| (r[2] - r[0] + 1) as u64 * (r[3] - r[1] + 1) as u64;
    let fills: u64 = leaves.iter().map(|l| area(&l.2)).sum();
    if nodes.is_empty() || fills > MAX_FILLS_PER_TILE * tile_count as u64 {
        return Vec::new();
    }
    // Sorted once: each tile's entries are then appended nearest first.
    leaves.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut counts = vec![0u32; tile_count];
    for (_, _, r) in &leaves {
        for ty in r[1]..=r[3] {
            for c in &mut counts[(ty * tiles_x + r[0]) as usize..=(ty * tiles_x + r[2]) as usize] {
                *c += 1;
            }
        }
    }
    let entries_at = HEADER_WORDS + 2 * tile_count;
    let mut words = vec![0u32; entries_at];
    words[..3].copy_from_slice(&[tiles_x, tiles_y, tile]);
    let mut next = vec![0usize; tile_count];
    let mut end = entries_at;
    for (t, &c) in counts.iter().enumerate() {
        let listed = c <= MAX_TILE_LIST;
        words[HEADER_WORDS + 2 * t] = (base + end) as u32;
        words[HEADER_WORDS + 2 * t + 1] = if listed { c } else { LIST_WALK };
        next[t] = end;
        end += if listed { c as usize } else { 0 };
    }
    words.resize(end, 0);
    for (_, node, r) in &leaves {
        for ty in r[1]..=r[3] {
            for tx in r[0]..=r[2] {
                let t = (ty * tiles_x + tx) as usize;
                if counts[t] <= MAX_TILE_LIST {
                    words[next[t]] = *node;
                    next[t] += 1;
                }
            }
        }
    }
    words
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::visibility::jittered_frame_uniform;
    use glam::DVec3;
    use ssbvb_voxel::camera::Camera;
    use ssbvb_voxel::instance_bvh::{Aabb, LEAF};
    use ssbvb_voxel::shading::Light;

    /// A small deterministic generator (xorshift64*), uniform in [0, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next()
        }
    }

    fn leaf(item: u32, lo: DVec3, hi: DVec3) -> GpuBvhNode {
        GpuBvhNode {
            lo: lo.as_vec3().to_array(),
            left: LEAF | item,
            hi: hi.as_vec3().to_array(),
            right: 0,
        }
    }

    /// The entries of the tile holding pixel (x, y), or `None` where it walks the hierarchy.
    fn tile_entries(words: &[u32], base: usize, x: u32, y: u32) -> Option<Vec<u32>> {
        let per_row = words[0];
        let t = (y / words[2] * per_row + x / words[2]) as usize;
        let (first, count) = (words[4 + 2 * t] as usize, words[5 + 2 * t]);
        (count != LIST_WALK).then(|| words[first - base..first - base + count as usize].to_vec())
    }

    /// Every box the reference's ray through a pixel (jittered) enters is on that pixel's
    /// tile list, in order of distance; boxes near, far, beside, behind and around the
    /// camera, under cameras from four sides with jitter.
    #[test]
    fn every_box_a_pixel_ray_enters_is_on_its_tile_list_nearest_first() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let (w, h) = (96u32, 72u32);
        let mut checked = 0usize;
        let mut left_out = 0usize;
        for round in 0..8 {
            let eye = DVec3::new(rng.range(-3.0, 3.0), rng.range(-1.0, 1.0), 10.0);
            let look = DVec3::new(rng.range(-2.0, 2.0), 0.0, rng.range(-2.0, 2.0));
            let mut camera = Camera::new(eye, look);
            camera.fov_y_deg = [20.0, 45.0, 70.0, 100.0][round % 4];
            let jitter = [rng.range(-0.5, 0.5), rng.range(-0.5, 0.5)];
            let frame = jittered_frame_uniform(&camera, (w, h), &Light::default(), jitter);
            // Internal nodes are skipped: one before the leaves.
            let mut nodes = vec![GpuBvhNode {
                lo: [-1e3; 3],
                left: 1,
                hi: [1e3; 3],
                right: 2,
            }];
            let mut boxes = Vec::new();
            for i in 0..60 {
                let c = DVec3::new(
                    rng.range(-8.0, 8.0),
                    rng.range(-3.0, 3.0),
                    rng.range(-8.0, 12.0),
                );
                let half = DVec3::new(
                    rng.range(0.01, 1.5),
                    rng.range(0.01, 1.5),
                    rng.range(0.01, 1.5),
                );
                // Camera-relative, as the GPU's.
                let (lo, hi) = (c - half - eye, c + half - eye);
                nodes.push(leaf(i, lo, hi));
                boxes.push(Aabb {
                    lo: lo.as_vec3().as_dvec3(),
                    hi: hi.as_vec3().as_dvec3(),
                });
            }
            let base = 8 * nodes.len();
            let words = tile_lists(&nodes, &frame, base);
            assert!(!words.is_empty(), "round {round}: no lists");
            let rays = camera.pixel_rays(w, h);
            for y in 0..h {
                for x in 0..w {
                    let (_, d) =
                        rays.ray_at(x as f64 + 0.5 + jitter[0], y as f64 + 0.5 + jitter[1]);
                    let Some(list) = tile_entries(&words, base, x, y) else {
                        continue;
                    };
                    let dist: Vec<f64> = list
                        .iter()
                        .map(|&n| box_distance(&nodes[n as usize]))
                        .collect();
                    assert!(
                        dist.windows(2).all(|p| p[0] <= p[1]),
                        "round {round}: not nearest first"
                    );
                    for (i, b) in boxes.iter().enumerate() {
                        let listed = list.contains(&(i as u32 + 1));
                        if b.ray_interval(DVec3::ZERO, d).is_some() {
                            checked += 1;
                            assert!(
                                listed,
                                "round {round}: pixel ({x}, {y}) enters box {i}, not listed"
                            );
                        } else if !listed {
                            left_out += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 10_000, "too few hits to say anything: {checked}");
        // The lists are not everything: most boxes a pixel's ray misses are off its list.
        assert!(
            left_out > 20 * checked,
            "lists barely narrow: {left_out} left out, {checked} hits"
        );
    }

    /// A tile of more than [`MAX_TILE_LIST`] boxes walks the hierarchy and stores none; a
    /// frame of more than [`MAX_FILLS_PER_TILE`] entries a tile gets no lists.
    #[test]
    fn crowded_tiles_and_frames_fall_back_to_the_hierarchy() {
        let camera = Camera::new(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO);
        let (w, h) = (64u32, 48u32);
        let frame = jittered_frame_uniform(&camera, (w, h), &Light::default(), [0.0; 2]);
        let rays = camera.pixel_rays(w, h);
        // Small boxes on the ray through pixel (4, 4): all in tile 0.
        let (_, d) = rays.ray_at(4.5, 4.5);
        let small = |i: u32| {
            let c = d * (5.0 + 0.01 * i as f64);
            leaf(i, c - 0.01, c + 0.01)
        };
        let one_off = (0..=MAX_TILE_LIST).map(small).collect::<Vec<_>>();
        let base = 8 * one_off.len();
        let words = tile_lists(&one_off, &frame, base);
        assert_eq!(tile_entries(&words, base, 4, 4), None, "65 boxes: no list");
        assert_eq!(
            tile_entries(&words, base, 40, 40),
            Some(vec![]),
            "an empty tile"
        );
        let fewer = &one_off[..MAX_TILE_LIST as usize];
        let words = tile_lists(fewer, &frame, base);
        let listed = tile_entries(&words, base, 4, 4).expect("64 boxes: a list");
        assert_eq!(listed.len(), MAX_TILE_LIST as usize);
        // Boxes around the camera cover every tile (12 of them): 256 × 12 fills at most.
        let around = |i: u32| leaf(i, DVec3::splat(-1.0), DVec3::splat(1.0));
        let at_cap = (0..MAX_FILLS_PER_TILE as u32)
            .map(around)
            .collect::<Vec<_>>();
        assert!(!tile_lists(&at_cap, &frame, base).is_empty());
        let over = (0..=MAX_FILLS_PER_TILE as u32)
            .map(around)
            .collect::<Vec<_>>();
        assert!(
            tile_lists(&over, &frame, base).is_empty(),
            "over the cap: no lists"
        );
    }
}
