//! Single-frame anti-aliasing (`assets/pipelines/ssbvb_edge_aa.ron`, pass kind `EdgeAa`)
//! against the supersampled CPU reference: the silhouette's coverage (alpha) and the
//! colour over black come closer to 16 samples per pixel than the one-sample frame's, and
//! pixels in flat neighbourhoods are left exactly as the composite wrote them.

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::Scene;
use ssbvb_tests::ctx;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{Instance, SampleGrid, render_supersampled};
use ssbvb_voxel::shading::srgb_to_linear;

const EDGE_AA: &str = include_str!("../../../assets/pipelines/ssbvb_edge_aa.ron");
const PLAIN: &str = include_str!("../../../assets/pipelines/ssbvb_unique.ron");
const SIZE: (u32, u32) = (96, 72);
const LEVEL: u32 = 6;

fn scene() -> Scene {
    ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", LEVEL), LEVEL)
}

/// The output of `pipeline` from `camera`: RGBA8, sRGB, straight alpha.
fn output(pipeline: &str, camera: &Camera) -> Vec<u8> {
    let f = ssbvb_tests::render(pipeline, scene(), camera, SIZE);
    ctx()
        .read_texture(
            &f.renderer.output().texture,
            ssbvb_gpu::wgpu::TextureAspect::All,
        )
        .unwrap()
        .bytes
}

/// Linear RGB over black and coverage of straight-alpha sRGB RGBA8.
fn premultiplied(rgba: &[u8]) -> Vec<[f64; 4]> {
    rgba.chunks_exact(4)
        .map(|p| {
            let a = p[3] as f64 / 255.0;
            std::array::from_fn(|c| {
                if c == 3 {
                    a
                } else {
                    srgb_to_linear(p[c] as f32 / 255.0) as f64 * a
                }
            })
        })
        .collect()
}

/// Mean absolute error of channels `channels` of `a` against `b`.
fn mean_abs_error(a: &[[f64; 4]], b: &[[f64; 4]], channels: std::ops::Range<usize>) -> f64 {
    let n = channels.len();
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| channels.clone().map(|c| (x[c] - y[c]).abs()).sum::<f64>())
        .sum();
    sum / (n * a.len()) as f64
}

#[test]
fn edge_aa_brings_a_still_closer_to_the_supersampled_reference() {
    let s = scene();
    let lod = &s.objects[0].asset.lods[LEVEL as usize];
    let inst = [Instance {
        lod,
        object_to_world: DAffine3::IDENTITY,
        faces: None,
    }];
    for (i, camera) in [
        Camera::new(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.2, 0.4, 1.5), DVec3::new(0.0, 0.1, 0.0)),
    ]
    .iter()
    .enumerate()
    {
        let grid = SampleGrid::from_count(16).unwrap();
        let truth = render_supersampled(&inst, camera, SIZE.0, SIZE.1, &s.light, grid);
        let truth: Vec<[f64; 4]> = truth
            .colors
            .iter()
            .map(|c| std::array::from_fn(|k| c[k] as f64))
            .collect();
        let plain = premultiplied(&output(PLAIN, camera));
        let aa = premultiplied(&output(EDGE_AA, camera));
        let coverage = (
            mean_abs_error(&plain, &truth, 3..4),
            mean_abs_error(&aa, &truth, 3..4),
        );
        let colour = (
            mean_abs_error(&plain, &truth, 0..3),
            mean_abs_error(&aa, &truth, 0..3),
        );
        let partial = aa.iter().filter(|p| p[3] > 0.0 && p[3] < 1.0).count();
        eprintln!(
            "camera {i}: coverage error plain {:.5} edge AA {:.5}; colour error plain {:.5} \
             edge AA {:.5}; {partial} px covered in part",
            coverage.0, coverage.1, colour.0, colour.1
        );
        // Measured on lavapipe: coverage error 0.84× and 0.76× the plain frame's, colour
        // error 0.89× and 0.85×, 378 and 367 pixels covered in part. Bounds: those with a
        // margin; a pass that blends nothing sits at 1×.
        assert!(partial > 100, "camera {i}: {partial}");
        assert!(coverage.1 < 0.92 * coverage.0, "camera {i}: {coverage:?}");
        assert!(colour.1 < 0.96 * colour.0, "camera {i}: {colour:?}");
    }
}

#[test]
fn pixels_in_flat_neighbourhoods_are_left_alone() {
    let camera = Camera::new(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO);
    let plain = output(PLAIN, &camera);
    let aa = output(EDGE_AA, &camera);
    let (w, h) = (SIZE.0 as usize, SIZE.1 as usize);
    let px = |img: &[u8], x: usize, y: usize| -> [u8; 4] {
        std::array::from_fn(|c| img[4 * (y * w + x) + c])
    };
    let (mut flat, mut changed) = (0, 0);
    // Every pixel, the border's with its neighbourhood clamped to the screen as the
    // shader clamps it.
    for y in 0..h {
        for x in 0..w {
            let c = px(&plain, x, y);
            let uniform = (0..9).all(|k| {
                let nx = (x + k % 3).saturating_sub(1).min(w - 1);
                let ny = (y + k / 3).saturating_sub(1).min(h - 1);
                px(&plain, nx, ny) == c
            });
            if uniform {
                flat += 1;
                assert_eq!(px(&aa, x, y), c, "flat pixel ({x}, {y}) changed");
            } else if px(&aa, x, y) != c {
                changed += 1;
            }
        }
    }
    eprintln!("{flat} flat pixels untouched, {changed} edge pixels blended");
    assert!(flat > 1000 && changed > 100, "{flat} {changed}");
}

/// A CPU model of `shaders/edge_aa.wgsl`, written from its description (in f32, as the
/// shader computes): `input` is the pass's input (the plain pipeline's output, RGBA8
/// sRGB, straight alpha), the result its output encoded the way the target encodes.
mod model {
    use ssbvb_voxel::shading::{linear_to_srgb8, srgb_to_linear};

    const THRESHOLD: f32 = 0.125;
    const THRESHOLD_MIN: f32 = 0.0312;
    const SUBPIXEL: f32 = 0.75;
    const SEARCH: i32 = 12;
    const COVERAGE_LUMA: f32 = 0.25;

    pub struct Image<'a> {
        pub rgba: &'a [u8],
        pub w: i32,
        pub h: i32,
    }

    impl Image<'_> {
        /// Premultiplied linear texel at `p`, clamped to the image.
        fn texel(&self, x: i32, y: i32) -> [f32; 4] {
            let (x, y) = (x.clamp(0, self.w - 1), y.clamp(0, self.h - 1));
            let i = 4 * (y * self.w + x) as usize;
            let a = self.rgba[i + 3] as f32 / 255.0;
            let c = |k: usize| srgb_to_linear(self.rgba[i + k] as f32 / 255.0) * a;
            [c(0), c(1), c(2), a]
        }

        fn luma(&self, x: i32, y: i32) -> f32 {
            luma(self.texel(x, y))
        }
    }

    fn luma(c: [f32; 4]) -> f32 {
        (c[0] * 0.299 + c[1] * 0.587 + c[2] * 0.114)
            .max(0.0)
            .sqrt()
            .max(COVERAGE_LUMA * c[3])
    }

    /// The output pixel at (x, y), RGBA8 sRGB straight alpha.
    pub fn pixel(img: &Image, x: i32, y: i32) -> [u8; 4] {
        let i = 4 * (y * img.w + x) as usize;
        let untouched = [
            img.rgba[i],
            img.rgba[i + 1],
            img.rgba[i + 2],
            img.rgba[i + 3],
        ];
        let centre = img.texel(x, y);
        let m = luma(centre);
        let (n, s, w, e) = (
            img.luma(x, y - 1),
            img.luma(x, y + 1),
            img.luma(x - 1, y),
            img.luma(x + 1, y),
        );
        let lo = m.min(n.min(s).min(w.min(e)));
        let hi = m.max(n.max(s).max(w.max(e)));
        let range = hi - lo;
        if range < THRESHOLD_MIN.max(hi * THRESHOLD) {
            return untouched;
        }
        let (nw, ne, sw, se) = (
            img.luma(x - 1, y - 1),
            img.luma(x + 1, y - 1),
            img.luma(x - 1, y + 1),
            img.luma(x + 1, y + 1),
        );
        let across_y =
            (nw + sw - 2.0 * w).abs() + 2.0 * (n + s - 2.0 * m).abs() + (ne + se - 2.0 * e).abs();
        let across_x =
            (nw + ne - 2.0 * n).abs() + 2.0 * (w + e - 2.0 * m).abs() + (sw + se - 2.0 * s).abs();
        let along_x = across_y >= across_x;
        let (mut step, dir) = if along_x {
            ((0, 1), (1, 0))
        } else {
            ((1, 0), (0, 1))
        };
        let l_neg = if along_x { n } else { w };
        let mut l_pos = if along_x { s } else { e };
        if (l_neg - m).abs() > (l_pos - m).abs() {
            step = (-step.0, -step.1);
            l_pos = l_neg;
        }
        let gradient = (l_pos - m).abs();
        let mid = 0.5 * (m + l_pos);
        let search = |sign: i32| -> (i32, f32) {
            for k in 1..=SEARCH {
                let (qx, qy) = (x + sign * dir.0 * k, y + sign * dir.1 * k);
                let pair = 0.5 * (img.luma(qx, qy) + img.luma(qx + step.0, qy + step.1));
                if (pair - mid).abs() >= 0.25 * gradient {
                    return (k, pair);
                }
            }
            (SEARCH, mid)
        };
        let ((d_neg, end_neg), (d_pos, end_pos)) = (search(-1), search(1));
        let end = if d_neg < d_pos { end_neg } else { end_pos };
        let dist = d_neg.min(d_pos) as f32;
        let span = (d_neg + d_pos) as f32;
        let edge_blend = if (m - mid < 0.0) != (end - mid < 0.0) {
            0.5 - dist / span
        } else {
            0.0
        };
        let average = (2.0 * (n + s + w + e) + nw + ne + sw + se) / 12.0;
        let unlike = ((average - m).abs() / range).clamp(0.0, 1.0);
        let smooth_unlike = (3.0 - 2.0 * unlike) * unlike * unlike;
        let blend = edge_blend.max(smooth_unlike * smooth_unlike * SUBPIXEL * 0.5);
        let other = img.texel(x + step.0, y + step.1);
        let c: [f32; 4] = std::array::from_fn(|k| centre[k] + (other[k] - centre[k]) * blend);
        if c[3] <= 0.0 {
            return [0; 4];
        }
        [
            linear_to_srgb8(c[0] / c[3]),
            linear_to_srgb8(c[1] / c[3]),
            linear_to_srgb8(c[2] / c[3]),
            (c[3] * 255.0).round().clamp(0.0, 255.0) as u8,
        ]
    }
}

/// The pass's output against the CPU model of it, per pixel, on the plain frame it reads
/// (the same passes draw it): every channel within 1 of the model's except where a
/// comparison of nearly equal values went the other way (under 1 % of the blended pixels).
#[test]
fn edge_aa_matches_its_cpu_model() {
    for camera in [
        Camera::new(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.2, 0.4, 1.5), DVec3::new(0.0, 0.1, 0.0)),
    ] {
        let plain = output(PLAIN, &camera);
        let aa = output(EDGE_AA, &camera);
        let img = model::Image {
            rgba: &plain,
            w: SIZE.0 as i32,
            h: SIZE.1 as i32,
        };
        let (mut off, mut blended) = (0, 0);
        for y in 0..img.h {
            for x in 0..img.w {
                let want = model::pixel(&img, x, y);
                let i = 4 * (y * img.w + x) as usize;
                let got = &aa[i..i + 4];
                if want[..] != plain[i..i + 4] {
                    blended += 1;
                }
                if (0..4).any(|k| (got[k] as i32 - want[k] as i32).abs() > 1) {
                    off += 1;
                }
            }
        }
        eprintln!("{blended} pixels blended by the model, {off} off by more than 1");
        // Measured on lavapipe: 5 of 734 and 2 of 695 (the GPU's sqrt is not the CPU's,
        // and near-ties of the edge tests go the other way). Bound: 2 % of the blended.
        assert!(blended > 300, "{blended}");
        assert!(
            off * 50 <= blended,
            "{off} of {blended} pixels differ from the model"
        );
    }
}
