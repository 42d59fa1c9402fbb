//! Barycentric weights and texture sampling against values worked out by hand (from the
//! mutation run: the voxelizer's tests sampled textures only at texel centres and never
//! met a clamped or degenerate weight).

use glam::{DVec3, Vec2};

use super::*;
use crate::voxelize::test_support::unit_randoms;

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9)
}

#[test]
fn barycentric_weights_recover_the_point_project_and_clamp() {
    let mut next = unit_randoms();
    let mut v3 = || DVec3::new(next(), next(), next()) * 20.0 - 10.0;
    for _ in 0..200 {
        let t = [v3(), v3(), v3()];
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        let r = v3().abs() + 0.01;
        let w = [r.x, r.y, r.z].map(|c| c / (r.x + r.y + r.z));
        // A point of the triangle, lifted off its plane: the weights are its projection's.
        let p = t[0] * w[0] + t[1] * w[1] + t[2] * w[2] + n * 3.0;
        assert!(close(barycentric(&t, p), w), "{t:?} {w:?}");
    }
    let t = [DVec3::ZERO, DVec3::X * 4.0, DVec3::Y * 4.0];
    let at = |w: [f64; 3]| t[0] * w[0] + t[1] * w[1] + t[2] * w[2];
    // Beyond the far edge: both weights clamped, then scaled to sum 1.
    assert!(close(
        barycentric(&t, at([-0.5, 0.75, 0.75])),
        [0.0, 0.5, 0.5]
    ));
    assert!(close(
        barycentric(&t, at([-1.0, 1.5, 0.5])), // 1.5 is clamped to 1 first
        [0.0, 2.0 / 3.0, 1.0 / 3.0]
    ));
    // Beyond one side: that weight clamped to 0, the first takes the rest.
    assert!(close(
        barycentric(&t, at([0.5, -0.2, 0.7])),
        [0.3, 0.0, 0.7]
    ));
    assert!(close(
        barycentric(&t, at([0.6, 0.6, -0.2])),
        [0.4, 0.6, 0.0]
    ));
}

#[test]
fn degenerate_triangles_put_all_weight_on_the_nearest_vertex() {
    let seg = [DVec3::ZERO, DVec3::X * 2.0, DVec3::X];
    let p = |x: f64| DVec3::new(x, 0.3, 0.0);
    assert_eq!(barycentric(&seg, p(0.1)), [1.0, 0.0, 0.0]);
    assert_eq!(barycentric(&seg, p(1.9)), [0.0, 1.0, 0.0]);
    assert_eq!(barycentric(&seg, p(1.2)), [0.0, 0.0, 1.0]);
    assert_eq!(barycentric(&seg, p(0.8)), [0.0, 0.0, 1.0]);
    // Equidistant from vertices 0 and 2: the lower index.
    assert_eq!(barycentric(&seg, p(0.5)), [1.0, 0.0, 0.0]);
    // Two vertices in one place (zero edge, zero denominator).
    let pinched = [DVec3::ONE, DVec3::ONE, DVec3::new(3.0, 1.0, 1.0)];
    assert_eq!(
        barycentric(&pinched, DVec3::new(2.5, 1.0, 1.0)),
        [0.0, 0.0, 1.0]
    );
    assert_eq!(
        barycentric(&pinched, DVec3::new(1.5, 1.0, 1.0)),
        [1.0, 0.0, 0.0]
    );
    // A sliver 100 long whose angle has sin² = 1e-13 (under the 1e-12 threshold, which
    // is relative to the edge lengths): nearest vertex, not ill-conditioned weights.
    let sliver = [
        DVec3::ZERO,
        DVec3::X * 100.0,
        DVec3::new(100.0, 100.0 * 1e-13f64.sqrt(), 0.0),
    ];
    assert_eq!(barycentric(&sliver, DVec3::X * 30.0), [1.0, 0.0, 0.0]);
}

/// 3×3 texels (so that the rows above and below a row differ) with distinct channels: red 30·(x + 3y), green 255 − red, blue 100·x.
fn texture() -> Texture {
    Texture {
        width: 3,
        height: 3,
        texels: (0..9)
            .map(|i| {
                let r = 30 * i as u8;
                [r, 255 - r, 100 * (i % 3) as u8, 255]
            })
            .collect(),
    }
}

/// The texel at (x, y) as floats.
fn texel(x: usize, y: usize) -> [f32; 4] {
    texture().texels[y * 3 + x].map(|c| f32::from(c) / 255.0)
}

/// Weighted sum of texels.
fn mix(parts: &[(f32, [f32; 4])]) -> [f32; 4] {
    let mut out = [0.0; 4];
    for (w, t) in parts {
        for k in 0..4 {
            out[k] += w * t[k];
        }
    }
    out
}

#[test]
fn texture_samples_are_bilinear_between_texel_centres_and_wrap_around() {
    let tex = texture();
    // uv of texel coordinates (x, y), whose centres are at half-integers.
    let uv = |x: f64, y: f64| [(x + 0.5) / 3.0, (y + 0.5) / 3.0];
    let near = |a: [f32; 4], b: [f32; 4]| (0..4).all(|k| (a[k] - b[k]).abs() < 1e-6);
    let cases = [
        (uv(1.0, 0.0), texel(1, 0)),
        (uv(2.0, 1.0), texel(2, 1)),
        (uv(1.5, 0.0), mix(&[(0.5, texel(1, 0)), (0.5, texel(2, 0))])),
        (uv(0.0, 0.5), mix(&[(0.5, texel(0, 0)), (0.5, texel(0, 1))])),
        (
            uv(1.25, 0.75),
            mix(&[
                (0.1875, texel(1, 0)),
                (0.0625, texel(2, 0)),
                (0.5625, texel(1, 1)),
                (0.1875, texel(2, 1)),
            ]),
        ),
        // Across the left and top edges: the last column and row.
        (
            uv(-0.5, 0.0),
            mix(&[(0.5, texel(2, 0)), (0.5, texel(0, 0))]),
        ),
        (
            uv(0.0, -0.5),
            mix(&[(0.5, texel(0, 2)), (0.5, texel(0, 0))]),
        ),
        (
            uv(1.0, 1.75),
            mix(&[(0.25, texel(1, 1)), (0.75, texel(1, 2))]),
        ),
        // Whole periods away.
        ([1.5 / 3.0 + 5.0, 0.5 / 3.0 - 3.0], texel(1, 0)),
    ];
    for (at, want) in cases {
        let got = sample_texture(&tex, at);
        assert!(near(got, want), "uv {at:?}: {got:?} against {want:?}");
    }
    // Malformed textures sample as white.
    for bad in [
        Texture {
            width: 0,
            ..texture()
        },
        Texture {
            height: 0,
            ..texture()
        },
        Texture {
            texels: texture().texels[..8].to_vec(),
            ..texture()
        },
    ] {
        assert_eq!(sample_texture(&bad, uv(1.0, 0.0)), [1.0; 4]);
    }
}

#[test]
fn a_non_finite_uv_samples_at_the_origin() {
    let material = Material::DEFAULT;
    let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
    for bad in [Vec2::new(f32::NAN, 0.5), Vec2::new(0.5, f32::INFINITY)] {
        let a = TriAttrs {
            material: &material,
            uv: Some([bad, Vec2::new(0.25, 0.5), Vec2::new(0.5, 0.25)]),
            color: None,
        };
        let (color, uv) = sample(&t, &a, DVec3::new(0.2, 0.2, 0.0));
        assert_eq!(uv, [0.0, 0.0]);
        assert_eq!(color, material.base_color);
    }
}
