//! The one lighting model of the project: the CPU reference uses it and the GPU composite
//! pass reproduces it line by line (all in f32, linear colour).
//!
//! ```text
//! L    = normalize(light.direction)          // towards the light, normalized in f64 first
//!                                            // (Light::unit_direction); (0,0,1) if degenerate
//! N    = normalize(normal)                   // (0,0,1) if degenerate
//! V    = normalize(view_dir)                 // surface → eye; N if degenerate
//! H    = normalize(L + V)                    // N if degenerate (L = -V)
//! ndl  = max(0, dot(N, L))
//! ndh  = max(0, dot(N, H))
//! spec = (ndl > 0 && ndh > 0) ? light.specular · pow(ndh, max(light.shininess, 0)) : 0
//! rgb  = light.ambient · albedo + ndl · albedo · light.color + spec · light.color
//! ```
//!
//! "Degenerate" means a squared length that is not above 1e-20 or is not finite (WGSL:
//! `select(fallback, v * inverseSqrt(l2), l2 > 1e-20 && l2 < INF)`). The specular term is
//! gated by `ndl > 0` so surfaces facing away from the light get no highlight, and by
//! `ndh > 0` because WGSL's `pow(0, y)` is undefined (it is `exp2(y · log2(0))`). The result
//! is linear and not clamped; [`linear_to_srgb`] clamps to [0, 1] on output.

use serde::{Deserialize, Serialize};

/// A directional light plus ambient term.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Direction **towards** the light (world space); normalized on use.
    pub direction: [f32; 3],
    /// Linear RGB intensity of the directional light (diffuse and specular).
    pub color: [f32; 3],
    /// Ambient factor: `ambient · albedo` is added everywhere.
    pub ambient: f32,
    /// Specular strength (white highlight scaled by `color`).
    pub specular: f32,
    /// Blinn-Phong exponent.
    pub shininess: f32,
}

impl Default for Light {
    /// Direction normalize(0.4, 0.8, 0.5), white, ambient 0.2, specular 0.25, shininess 32.
    fn default() -> Self {
        Self {
            direction: [0.4, 0.8, 0.5],
            color: [1.0, 1.0, 1.0],
            ambient: 0.2,
            specular: 0.25,
            shininess: 32.0,
        }
    }
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `v / |v|`, or `fallback` when the squared length is not above 1e-20 or not finite.
fn normalize_or(v: [f32; 3], fallback: [f32; 3]) -> [f32; 3] {
    let l2 = dot(v, v);
    if l2 > 1e-20 && l2.is_finite() {
        let inv = 1.0 / l2.sqrt();
        [v[0] * inv, v[1] * inv, v[2] * inv]
    } else {
        fallback
    }
}

impl Light {
    /// The unit direction towards the light, normalized in f64 (+z when the direction is
    /// zero or not finite): what the GPU's frame constants carry, so that a direction whose
    /// squared length overflows f32 (beyond about 1.8e19) still points where it says.
    pub fn unit_direction(&self) -> [f32; 3] {
        let d = glam::DVec3::from(self.direction.map(f64::from));
        d.normalize_or(glam::DVec3::Z).as_vec3().to_array()
    }
}

/// Blinn-Phong shading of a surface point (formula in the module docs).
///
/// `albedo` is linear RGB, `normal` the surface normal, `view_dir` points from the surface
/// towards the eye (none need be normalized). Returns linear RGB, never NaN for finite
/// `albedo` and light parameters.
pub fn shade(albedo: [f32; 3], normal: [f32; 3], view_dir: [f32; 3], light: &Light) -> [f32; 3] {
    shade_lit(albedo, normal, view_dir, light, &Lit::NONE)
}

/// Light from the voxels at a surface point ([`crate::lighting`]): the ambient term is
/// scaled by `ao`, the directional terms by `shadow`, and `albedo · indirect` is added.
/// [`Lit::NONE`] gives [`shade`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lit {
    /// Ambient occlusion (1 = open).
    pub ao: f32,
    /// Visibility of the light (1 = lit).
    pub shadow: f32,
    /// One-bounce radiance arriving (before the albedo).
    pub indirect: [f32; 3],
}

impl Lit {
    /// Open, lit, no bounce: plain Blinn-Phong.
    pub const NONE: Lit = Lit {
        ao: 1.0,
        shadow: 1.0,
        indirect: [0.0; 3],
    };
}

/// [`shade`] with the light from the voxels `lit` (the cone composite's formula):
/// `ao · ambient · albedo + shadow · ndl · albedo · color + shadow · spec · color +
/// albedo · indirect`.
pub fn shade_lit(
    albedo: [f32; 3],
    normal: [f32; 3],
    view_dir: [f32; 3],
    light: &Light,
    lit: &Lit,
) -> [f32; 3] {
    let l = normalize_or(light.unit_direction(), [0.0, 0.0, 1.0]);
    let n = normalize_or(normal, [0.0, 0.0, 1.0]);
    let v = normalize_or(view_dir, n);
    let h = normalize_or([l[0] + v[0], l[1] + v[1], l[2] + v[2]], n);
    let ndl = dot(n, l).max(0.0);
    let ndh = dot(n, h).max(0.0);
    let spec = if ndl > 0.0 && ndh > 0.0 {
        light.specular * ndh.powf(light.shininess.max(0.0))
    } else {
        0.0
    };
    let mut out = [0.0; 3];
    for c in 0..3 {
        // Associated as in `shade` before the factors were added (1 · x and x + 0 are
        // exact, so `Lit::NONE` reproduces it bit for bit).
        out[c] = lit.ao * light.ambient * albedo[c]
            + lit.shadow * ndl * albedo[c] * light.color[c]
            + lit.shadow * spec * light.color[c]
            + albedo[c] * lit.indirect[c];
    }
    out
}

/// Linear → sRGB transfer function (IEC 61966-2-1) of one channel; input clamped to
/// [0, 1], NaN maps to 0.
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB → linear transfer function of one channel (inverse of [`linear_to_srgb`]).
pub fn srgb_to_linear(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// A linear colour channel as an 8-bit sRGB value (rounded).
pub fn linear_to_srgb8(x: f32) -> u8 {
    (linear_to_srgb(x) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light direction's length does not matter, even past f32's square root of its
    /// largest value (the GPU's frame constants normalize it in f64); zero or infinite
    /// falls back to +z.
    #[test]
    fn the_light_direction_is_normalized_whatever_its_length() {
        let at = |direction: [f32; 3]| {
            let light = Light {
                direction,
                ..Light::default()
            };
            (
                light.unit_direction(),
                shade([0.5, 0.6, 0.7], [0.3, 0.5, 0.8], [0.1, 0.2, 1.0], &light),
            )
        };
        let (unit, rgb) = at([3.0, -1.0, 2.0]);
        assert_eq!(at([3e19, -1e19, 2e19]), (unit, rgb));
        assert_eq!(at([3e-19, -1e-19, 2e-19]), (unit, rgb));
        assert!((unit[0] - 3.0 / 14f32.sqrt()).abs() < 1e-7, "{unit:?}");
        let z = at([0.0, 0.0, 1.0]);
        assert_eq!(at([0.0; 3]), z);
        assert_eq!(at([f32::INFINITY, 0.0, 0.0]), z);
    }

    #[test]
    fn blinn_phong_matches_the_documented_formula() {
        let light = Light {
            direction: [0.0, 0.0, 2.0],
            ..Light::default()
        };
        // Normal, light and view all along +Z: ndl = ndh = 1.
        let c = shade([0.5, 0.25, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 5.0], &light);
        let expect = |a: f32| 0.2 * a + a + 0.25;
        for (got, a) in c.iter().zip([0.5, 0.25, 1.0]) {
            assert!((got - expect(a)).abs() < 1e-6, "{c:?}");
        }
        // Facing away from the light: ambient only, no highlight.
        let c = shade([1.0; 3], [0.0, 0.0, -1.0], [0.0, 0.0, -1.0], &light);
        assert!(c.iter().all(|&v| (v - 0.2).abs() < 1e-6), "{c:?}");
        // 60 degrees: ndl = 0.5; view along the normal: H halfway, ndh = cos 30°.
        let n = [0.0, 3f32.sqrt() / 2.0, 0.5];
        let c = shade([1.0; 3], n, n, &light);
        let want = 0.2 + 0.5 + 0.25 * (30f32.to_radians().cos()).powf(32.0);
        assert!((c[0] - want).abs() < 1e-5, "{c:?} vs {want}");
    }

    #[test]
    fn degenerate_inputs_never_give_nan() {
        let light = Light {
            direction: [0.0; 3],
            ..Light::default()
        };
        for n in [[0.0; 3], [f32::NAN; 3], [f32::INFINITY, 0.0, 0.0]] {
            for v in [[0.0; 3], [0.0, 0.0, -1.0], [f32::NAN; 3]] {
                let c = shade([1.0; 3], n, v, &light);
                assert!(c.iter().all(|x| x.is_finite()), "{n:?} {v:?} {c:?}");
                let c = shade([1.0; 3], n, v, &Light::default());
                assert!(c.iter().all(|x| x.is_finite()), "{n:?} {v:?} {c:?}");
            }
        }
    }

    #[test]
    fn srgb_round_trips_and_clamps() {
        for i in 0..=255 {
            let x = i as f32 / 255.0;
            assert!((srgb_to_linear(linear_to_srgb(x)) - x).abs() < 1e-5);
        }
        assert_eq!(linear_to_srgb(f32::NAN), 0.0);
        assert!((linear_to_srgb(7.0) - 1.0).abs() < 1e-6);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(0.214_041_14), 128);
    }
}
