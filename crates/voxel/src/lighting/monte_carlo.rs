//! The exact lighting reference: Monte Carlo rays against the exact voxels (the reference
//! ray caster's [`Tracer`]) for the three quantities defined in [`crate::lighting`].
//!
//! Directions come from a Hammersley set (stratified, so 256 samples leave a standard
//! error well under 0.01 on AO) shifted per receiver by a hash of `seed` (Cranley–Patterson
//! rotation), so neighbouring receivers do not share the same pattern and a result is
//! reproducible.

use glam::DVec3;

use super::{LightingParams, LightingSample, tangent_frame};
use crate::camera::normalize_or;
use crate::reference::Tracer;
use crate::shading::Light;

/// Van der Corput radical inverse in base 2.
fn radical_inverse(i: u32) -> f64 {
    f64::from(i.reverse_bits()) / 4_294_967_296.0
}

/// Two uniform numbers in [0, 1) from a 64-bit seed (splitmix64).
fn rotation(seed: u64) -> (f64, f64) {
    let mut z = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut next = || {
        z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut x = z;
        x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((x ^ (x >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    (next(), next())
}

/// Sample `i` of `n` of the rotated 2D Hammersley set.
fn point(i: u32, n: u32, rot: (f64, f64)) -> (f64, f64) {
    let u = (f64::from(i) + 0.5) / f64::from(n) + rot.0;
    let v = radical_inverse(i) + rot.1;
    (u.fract(), v.fract())
}

/// Radiance a voxel hit sends back (the bounce's source term): its albedo, lambert from
/// its stored normal and the light's hard shadow at it.
fn bounced(
    tracer: &Tracer,
    hit: &crate::reference::Hit,
    light: &Light,
    l: DVec3,
    near: f64,
) -> [f32; 3] {
    let (albedo, normal) = tracer.surface(hit);
    let n = DVec3::from(normal.map(f64::from));
    let ndl = n.dot(l).max(0.0);
    if ndl == 0.0 {
        return [0.0; 3];
    }
    let face = DVec3::from(hit.face_normal.map(f64::from));
    if tracer.trace(hit.position + face * near, l).is_some() {
        return [0.0; 3];
    }
    let k = ndl as f32;
    [
        albedo[0] * light.color[0] * k,
        albedo[1] * light.color[1] * k,
        albedo[2] * light.color[2] * k,
    ]
}

/// AO, shadow and one-bounce indirect light at receiver `p` with normal `n` (world space),
/// each from `samples` rays (the shadow from `samples` rays of its own); `seed` rotates the
/// sample set (use the pixel index).
pub fn monte_carlo(
    tracer: &Tracer,
    light: &Light,
    params: &LightingParams,
    p: DVec3,
    n: DVec3,
    samples: u32,
    seed: u64,
) -> LightingSample {
    let samples = samples.max(1);
    let n = normalize_or(n, DVec3::Z);
    let l = normalize_or(DVec3::from(light.direction.map(f64::from)), DVec3::Z);
    let origin = p + n * params.near;
    let rot = rotation(seed);
    let (t, b) = tangent_frame(n);
    let mut open = 0u32;
    let mut indirect = [0f64; 3];
    for i in 0..samples {
        let (u, v) = point(i, samples, rot);
        // Cosine-weighted: a uniform point of the unit disc lifted onto the hemisphere.
        let r = u.sqrt();
        let phi = std::f64::consts::TAU * v;
        let d = t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).max(0.0).sqrt();
        match tracer
            .trace(origin, d)
            .filter(|h| h.t <= params.max_distance)
        {
            None => open += 1,
            Some(hit) => {
                let c = bounced(tracer, &hit, light, l, params.near);
                for k in 0..3 {
                    indirect[k] += f64::from(c[k]);
                }
            }
        }
    }
    // Shadow: uniform in the solid angle of the light's cone.
    let cos_max = (params.shadow_aperture.to_radians() * 0.5).cos();
    let (lt, lb) = tangent_frame(l);
    let srot = rotation(seed ^ 0x5bd1_e995);
    let mut lit = 0u32;
    for i in 0..samples {
        let (u, v) = point(i, samples, srot);
        let cos = 1.0 - u * (1.0 - cos_max);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * v;
        let d = lt * (sin * phi.cos()) + lb * (sin * phi.sin()) + l * cos;
        if tracer.trace(origin, d).is_none() {
            lit += 1;
        }
    }
    let s = f64::from(samples);
    LightingSample {
        ao: (f64::from(open) / s) as f32,
        shadow: (f64::from(lit) / s) as f32,
        indirect: indirect.map(|x| (x / s) as f32),
    }
}
