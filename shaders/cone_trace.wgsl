//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
// Voxel cone tracing (cone_trace.rs): per G-buffer pixel, `cones` diffuse cones over the
// normal's hemisphere (AO and one bounce) and one cone towards the light (soft shadow)
// through the pre-filtered scene volume. What each estimates: ssbvb-voxel lighting.rs.

// The pass's constants (cone_trace.rs `ConeUniform`).
struct Cone {
    // Camera-relative world position of the volume's low corner; w: finest cell edge.
    origin: vec4<f32>,
    // 1 / the volume's world extent per axis; w: the coarsest mip level sampled (the last
    // whose texels halve exactly, volume.rs `exact_levels`).
    inv_extent: vec4<f32>,
    // max_distance, tan(aperture / 2), step_scale, tan(shadow_aperture / 2).
    knobs: vec4<f32>,
    // x: number of cones; y: origin offset along the normal, z: first sample's distance,
    // both in cells; w: G-buffer pixels per target texel along each axis (1 at full
    // resolution, 2 when the targets are half the screen: texel q lights pixel 2q).
    misc: vec4<f32>,
    // Cone axes in the tangent frame (z = normal), cosine-weighted, equal weights.
    dirs: array<vec4<f32>, 64>,
}

@group(1) @binding(0) var albedo: texture_2d<u32>;
@group(1) @binding(1) var normal: texture_2d<f32>;
@group(1) @binding(2) var position: texture_2d<f32>;
@group(1) @binding(3) var volume: texture_3d<f32>;
@group(1) @binding(4) var volume_sampler: sampler;
@group(1) @binding(5) var<uniform> cone: Cone;

// Samples along one cone at most (a guard; max_distance and the step scale end it first).
const MAX_STEPS: u32 = 512u;

struct Targets {
    // r: ambient occlusion, g: light visibility.
    @location(0) occlusion: vec4<f32>,
    // rgb: one-bounce radiance arriving.
    @location(1) indirect: vec4<f32>,
}

fn volume_at(x: vec3<f32>, lod: f32) -> vec4<f32> {
    let uvw = (x - cone.origin.xyz) * cone.inv_extent.xyz;
    if any(uvw < vec3(0.0)) || any(uvw > vec3(1.0)) {
        return vec4(0.0);
    }
    return textureSampleLevel(volume, volume_sampler, uvw, min(lod, cone.inv_extent.w));
}

// Where the ray p + t d leaves the volume's box (0 when it never meets it).
fn volume_exit(p: vec3<f32>, d: vec3<f32>) -> f32 {
    let lo = cone.origin.xyz;
    let hi = lo + 1.0 / cone.inv_extent.xyz;
    let inv = 1.0 / select(d, vec3(1e-30), abs(d) < vec3(1e-30));
    let a = (lo - p) * inv;
    let b = (hi - p) * inv;
    let t_far = min(min(max(a.x, b.x), max(a.y, b.y)), max(a.z, b.z));
    let t_near = max(max(min(a.x, b.x), min(a.y, b.y)), min(a.z, b.z));
    return select(0.0, t_far, t_far >= max(t_near, 0.0));
}

// Front-to-back accumulation of premultiplied radiance and opacity along one cone of
// half-angle tangent `tan_half` up to `max_t`. `height` is the origin's height above the
// receiver's tangent plane and `rise` the cosine between the axis and the normal: a
// footprint is kept above that plane (a cone near the horizon would otherwise sample the
// receiver's own surface, which its hemisphere does not contain). A trilinear lookup of
// texels of width D blends texels whose boxes reach about 2D from the sample (further
// along a diagonal), hence D <= height / 2: a looser bound costs AO accuracy and a tighter
// one gains little (against Monte Carlo, docs/benchmarks.md).
fn trace_cone(
    p: vec3<f32>,
    d: vec3<f32>,
    tan_half: f32,
    max_t: f32,
    height: f32,
    rise: f32,
    step_scale: f32,
) -> vec4<f32> {
    let cell = cone.origin.w;
    var acc = vec4(0.0);
    var t = cell * cone.misc.z;
    for (var i = 0u; i < MAX_STEPS && t < max_t && acc.a < 0.995; i++) {
        let above = 0.5 * (height + t * rise);
        let diameter = max(cell, min(2.0 * tan_half * t, above));
        let s = volume_at(p + d * t, log2(diameter / cell));
        // A texel's opacity holds over its own width (the diameter); the step is
        // step_scale of it.
        let a = 1.0 - pow(max(1.0 - s.a, 0.0), step_scale);
        if s.a > 0.0 {
            acc += (1.0 - acc.a) * vec4(s.rgb * (a / s.a), a);
        }
        t += diameter * step_scale;
    }
    return acc;
}

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> Targets {
    let dims = vec2<i32>(textureDimensions(albedo));
    let px = min(vec2<i32>(floor(pos.xy) * cone.misc.w), dims - 1);
    if unpack4x8unorm(textureLoad(albedo, px, 0).x).a == 0.0 {
        discard;
    }
    let n = safe_normalize(textureLoad(normal, px, 0).xyz, vec3(0.0, 0.0, 1.0));
    let offset = cone.misc.y * cone.origin.w;
    let p = textureLoad(position, px, 0).xyz + n * offset;
    // Tangent frame (Duff et al. 2017; lighting.rs `tangent_frame`).
    // The sign bit, as Rust's copysign reads it (-0.0 counts as negative).
    let sgn = select(-1.0, 1.0, (bitcast<u32>(n.z) >> 31u) == 0u);
    let k = -1.0 / (sgn + n.z);
    let m = n.x * n.y * k;
    let t = vec3(1.0 + sgn * n.x * n.x * k, sgn * m, -sgn * n.x);
    let b = vec3(m, sgn + n.y * n.y * k, -n.y);
    let count = u32(cone.misc.x);
    var occluded = 0.0;
    var bounce = vec3(0.0);
    for (var i = 0u; i < count; i++) {
        let c = cone.dirs[i].xyz;
        let d = t * c.x + b * c.y + n * c.z;
        let r = trace_cone(p, d, cone.knobs.y, cone.knobs.x, offset, c.z, cone.knobs.z);
        occluded += r.a;
        bounce += r.rgb;
    }
    let l = safe_normalize(frame.light_dir.xyz, vec3(0.0, 0.0, 1.0));
    let s = trace_cone(p, l, cone.knobs.w, volume_exit(p, l), offset, max(dot(l, n), 0.0), cone.knobs.z);
    let w = 1.0 / f32(max(count, 1u));
    var out: Targets;
    out.occlusion = vec4(1.0 - occluded * w, 1.0 - s.a, 0.0, 1.0);
    out.indirect = vec4(bounce * w, 1.0);
    return out;
}
