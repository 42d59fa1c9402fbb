//! Smoothing and composite through the whole SSBVB pipeline: triangle pixels untouched by
//! smoothing, Eq. 1 at and around MinDist finite, shaded output against the CPU reference.

use glam::DVec3;
use ssbvb_passes::TriangleObject;
use ssbvb_tests::f16_to_f32;
use ssbvb_voxel::camera::Camera;

const SSBVB: &str = include_str!("../../../assets/pipelines/ssbvb.ron");
const SIZE: (u32, u32) = (160, 120);

fn scene(level: u32) -> ssbvb_passes::Scene {
    let mut s =
        ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", level), level);
    s.triangles.push(TriangleObject::ground_plane(
        DVec3::new(0.0, -0.6, 0.0),
        3.0,
        [0.4, 0.5, 0.4, 1.0],
    ));
    s
}

fn camera() -> Camera {
    Camera {
        fov_y_deg: 40.0,
        ..Camera::new(DVec3::new(1.9, 0.9, 2.7), DVec3::new(0.0, -0.15, 0.0))
    }
}

fn with_smooth(max_i: f32, min_dist: f32) -> String {
    SSBVB.replace(
        "Smooth(max_i: 1.0, min_dist: 0.5)",
        &format!("Smooth(max_i: {max_i:?}, min_dist: {min_dist:?})"),
    )
}

#[test]
fn triangle_pixels_are_bit_identical_after_smoothing() {
    let f = ssbvb_tests::render(&with_smooth(2.0, 0.5), scene(6), &camera(), SIZE);
    let before = f.read("gbuffer_normal");
    let after = f.read("smoothed_normal");
    let stencil = f.read_stencil("depth_stencil");
    let (mut tri, mut vox, mut changed) = (0, 0, 0);
    for (i, s) in stencil.iter().enumerate() {
        let (a, b) = (&before[i * 8..i * 8 + 8], &after[i * 8..i * 8 + 8]);
        match s {
            1 => {
                vox += 1;
                changed += (a != b) as usize;
            }
            _ => {
                tri += (*s == 2) as usize;
                assert_eq!(a, b, "pixel {i} (stencil {s}) changed by smoothing");
            }
        }
    }
    assert!(
        tri > 1000 && vox > 1000,
        "both kinds of pixels present: {tri} triangle, {vox} voxel"
    );
    assert!(
        changed * 2 > vox,
        "smoothing changed only {changed} of {vox} voxel pixels"
    );
    // Smoothed normals are unit length (f16) and finite.
    let n: Vec<f32> = after
        .chunks(2)
        .map(|h| f16_to_f32(u16::from_le_bytes([h[0], h[1]])))
        .collect();
    for (i, s) in stencil.iter().enumerate() {
        if *s == 1 {
            let v = &n[i * 4..i * 4 + 3];
            let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            assert!((len - 1.0).abs() < 0.01, "pixel {i}: |n| = {len}");
        }
    }
}

#[test]
fn eq1_at_below_and_above_min_dist_stays_finite() {
    // The bunny is about 3.3 units from the camera: MinDist below, at (the singularity
    // falls inside the object), and far above every pixel's distance.
    for min_dist in [0.0f32, 3.3, 1e6] {
        let f = ssbvb_tests::render(&with_smooth(3.0, min_dist), scene(6), &camera(), SIZE);
        let after = f.read("smoothed_normal");
        for h in after.chunks(2) {
            let v = f16_to_f32(u16::from_le_bytes([h[0], h[1]]));
            assert!(v.is_finite(), "non-finite normal with min_dist {min_dist}");
        }
        let color = f.read("color");
        assert!(color.chunks(4).any(|p| p[3] == 255));
    }
}

#[test]
fn composite_matches_the_reference_shading() {
    // Flat billboards (they carry the voxel's stored normal, as the reference shades) and no
    // smoothing: where the billboard is the reference's voxel, the only differences left
    // are f16 G-buffer storage and f32 vs f64; at silhouettes a neighbouring voxel's
    // billboard may win the depth test (measured separately as coverage / same voxel).
    let src = SSBVB.replace(
        r#""normal": "smoothed_normal""#,
        r#""normal": "gbuffer_normal""#,
    );
    let mut s = scene(6);
    s.triangles.clear();
    let cam = camera();
    let f = ssbvb_tests::render(&src, s.clone(), &cam, SIZE);
    let gpu = f.read("color");
    let reference = ssbvb_tests::reference_of(&s, &cam, SIZE).to_rgba8();
    // Compare where both drew (Flat coverage is checked elsewhere).
    let (mut sq, mut n, mut worst) = (0.0f64, 0usize, 0u8);
    let mut pixel_diffs = Vec::new();
    for (g, r) in gpu.chunks(4).zip(reference.chunks(4)) {
        if g[3] == 255 && r[3] == 255 {
            let mut m = 0;
            for c in 0..3 {
                let d = g[c].abs_diff(r[c]);
                m = m.max(d);
                sq += (d as f64).powi(2);
            }
            worst = worst.max(m);
            pixel_diffs.push(m);
            n += 3;
        }
    }
    pixel_diffs.sort();
    let pct = |q: f64| pixel_diffs[((pixel_diffs.len() - 1) as f64 * q) as usize];
    eprintln!(
        "per-pixel max channel diff: median {}, p90 {}, p99 {}",
        pct(0.5),
        pct(0.9),
        pct(0.99)
    );
    // Most pixels shade identically up to storage precision.
    assert!(
        pct(0.5) <= 1 && pct(0.9) <= 4,
        "median {} p90 {}",
        pct(0.5),
        pct(0.9)
    );
    assert!(n > 3000, "{n}");
    let psnr = 10.0 * (255.0f64 * 255.0 / (sq / n as f64).max(1e-12)).log10();
    eprintln!(
        "composite vs reference: PSNR {psnr:.1} dB over {} pixels, worst channel diff {worst}",
        n / 3
    );
    // Flat billboards can show a neighbouring voxel at a few silhouette pixels, so the
    // bound is on PSNR, not on the worst pixel.
    assert!(psnr > 30.0, "PSNR {psnr:.1} dB");
    // Background stays transparent.
    for (g, r) in gpu.chunks(4).zip(reference.chunks(4)) {
        if r[3] == 0 && g[3] == 0 {
            assert_eq!(g, [0, 0, 0, 0]);
        }
    }
}
