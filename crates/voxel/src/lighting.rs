//! Light from the voxels (voxel cone tracing): the pre-filtered scene volume the GPU cone
//! tracer reads ([`volume`]) and the exact Monte Carlo reference its error is measured
//! against ([`monte_carlo`]).
//!
//! Both answer the same three questions for a receiver point `p` with unit normal `n` (a
//! G-buffer sample: a voxel or a triangle pixel). Voxel objects are the only occluders and
//! emitters; triangle objects only receive.
//!
//! - **AO(p)**: the cosine-weighted fraction of the directions `ω` of `n`'s hemisphere along
//!   which the ray from `p + near·n` meets no voxel within `max_distance`.
//! - **indirect(p)**: the cosine-weighted mean, over the same directions, of the radiance of
//!   the first voxel met within `max_distance`: `albedo · light.color · max(0, n_v·L) ·
//!   V`, with `n_v` the voxel's stored normal and `V` the hard shadow of the directional
//!   light at it. The composite multiplies it by the receiver's albedo: one diffuse bounce
//!   in the units of the direct term of [`crate::shading::shade`].
//! - **shadow(p)**: the uniform fraction of the directions in the cone of full apex angle
//!   `shadow_aperture` around the light direction along which the ray from `p + near·n`
//!   meets no voxel (a soft shadow of a light of that angular size).
//!
//! `near` lifts the ray origins above the receiver's own voxel staircase: AO of structure
//! finer than a voxel is the voxelization's blockiness, not the shape. The lit colour
//! combines the three with [`crate::shading::shade_lit`].

pub mod monte_carlo;
pub mod volume;

use glam::DVec3;

/// The knobs the reference and the cone tracer share.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightingParams {
    /// Distance beyond which voxels neither occlude (AO) nor bounce light (world units).
    pub max_distance: f64,
    /// Full apex angle of the shadow cone, degrees.
    pub shadow_aperture: f64,
    /// Offset of ray origins along the receiver's normal (world units).
    pub near: f64,
}

/// The three answers for one receiver.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LightingSample {
    /// Ambient occlusion, 1 = open.
    pub ao: f32,
    /// Visibility of the light, 1 = lit.
    pub shadow: f32,
    /// One-bounce diffuse radiance arriving (before the receiver's albedo).
    pub indirect: [f32; 3],
}

/// `n` unit directions in the tangent frame (z = the normal) spread cosine-weighted over
/// the hemisphere, each standing for an equal share (a spherical Fibonacci set: point `i`
/// at radius `√((i + ½)/n)` of the unit disc, turned by the golden angle, lifted onto the
/// hemisphere). The cone tracer's cone axes: with equal weights their mean estimates a
/// cosine-weighted integral. One cone is the normal itself (the set's single point would
/// lean 45° to one side).
pub fn cone_directions(n: u32) -> Vec<[f32; 3]> {
    if n == 1 {
        return vec![[0.0, 0.0, 1.0]];
    }
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let r = ((f64::from(i) + 0.5) / f64::from(n)).sqrt();
            let phi = golden * f64::from(i);
            let z = (1.0 - r * r).max(0.0).sqrt();
            [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
        })
        .collect()
}

/// An orthonormal basis `(t, b)` completing the unit vector `n` (Duff et al. 2017).
pub fn tangent_frame(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_directions_are_unit_upward_and_cosine_weighted() {
        for n in [1, 6, 16, 64] {
            let dirs = cone_directions(n);
            assert_eq!(dirs.len(), n as usize);
            for d in &dirs {
                let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                assert!((l - 1.0).abs() < 1e-5 && d[2] > 0.0, "{d:?}");
            }
        }
        // Cosine-weighted: the mean of cos θ is 2/3 (∫cos²/∫cos over the hemisphere), the
        // mean of the x component 0.
        let dirs = cone_directions(4096);
        let mean = |k: usize| dirs.iter().map(|d| f64::from(d[k])).sum::<f64>() / 4096.0;
        assert!((mean(2) - 2.0 / 3.0).abs() < 1e-3, "{}", mean(2));
        assert!(mean(0).abs() < 1e-3 && mean(1).abs() < 1e-3);
    }

    #[test]
    fn tangent_frames_are_orthonormal_for_any_normal() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.5, 0.8).normalize(),
            DVec3::new(1e-9, 0.0, -1.0).normalize(),
        ] {
            let (t, b) = tangent_frame(n);
            for (u, v) in [(t, b), (t, n), (b, n)] {
                assert!(u.dot(v).abs() < 1e-12);
            }
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12, "{n}");
        }
    }
}
