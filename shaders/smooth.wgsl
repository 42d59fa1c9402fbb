//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
// Gaussian smoothing of voxel normals (the paper's step 5): a 3x3 Gaussian whose sample
// offset I follows Eq. 1, I = max(0, min(MaxI / (Dist - MinDist)^2, MaxI)), with Dist the
// distance from the camera reconstructed per pixel from depth with the inverse
// view-projection. Two draws, both stencil-tested: voxel pixels get the smoothed normal,
// every other pixel (triangles, background) a bit-exact copy, so triangle pixels are never
// touched.

// MaxI: the largest offset in pixels; MinDist: distance (world units) at and below which
// the offset is MaxI (see smoothing_offset).
override MAX_I: f32 = 1.0;
override MIN_DIST: f32 = 0.5;

@group(1) @binding(0) var gbuffer_normal: texture_2d<f32>;
// Depth aspect of the read-only depth-stencil attachment (reversed Z), bound as an
// unfilterable float texture: GLSL has no texel fetch from depth textures.
@group(1) @binding(1) var depth_stencil: texture_2d<f32>;
@group(1) @binding(2) var normal_sampler: sampler;
// Where the device cannot sample the depth-stencil it tests against (GL, WebGL: no
// read-only depth-stencil attachments), or `copy_depth`: the depth's bits, written by
// `fs_copy_depth` in a pass before (smooth.rs).
@group(1) @binding(3) var depth_copy: texture_2d<u32>;

// Fullscreen triangle.
// Eq. 1 made total: at Dist = MinDist the quotient is infinite and below it the parabola
// turns back up, so for every Dist <= MinDist (and NaN) the offset is MaxI, which is also
// the limit of Eq. 1 from above. The result is always finite and in [0, MaxI].
fn smoothing_offset(dist: f32) -> f32 {
    let x = dist - MIN_DIST;
    if !(x > 0.0) {
        return MAX_I;
    }
    let q = MAX_I / (x * x);
    return clamp(q, 0.0, MAX_I);
}

// Camera distance of the surface at a pixel, from its depth.
fn camera_distance(px: vec2<f32>, depth: f32) -> f32 {
    let ndc = vec3(px.x * frame.screen.z * 2.0 - 1.0, 1.0 - px.y * frame.screen.w * 2.0, depth);
    let p = frame.inv_view_proj * vec4(ndc, 1.0);
    return length(p.xyz / p.w);
}

// The smoothed normal of the voxel pixel at `pos` whose depth is `depth`.
fn smoothed(pos: vec4<f32>, depth: f32) -> vec4<f32> {
    let p = vec2<i32>(pos.xy);
    let center = textureLoad(gbuffer_normal, p, 0);
    let offset = smoothing_offset(camera_distance(pos.xy, depth));
    var sum = vec3(0.0);
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            // Weights 1-2-1 x 1-2-1 (sum 16; the normalization below makes it irrelevant).
            let w = f32((2 - abs(dx)) * (2 - abs(dy)));
            let uv = (pos.xy + vec2(f32(dx), f32(dy)) * offset) * frame.screen.zw;
            sum += w * textureSampleLevel(gbuffer_normal, normal_sampler, uv, 0.0).xyz;
        }
    }
    return vec4(safe_normalize(sum, center.xyz), center.w);
}

@fragment
fn fs_smooth(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return smoothed(pos, textureLoad(depth_stencil, vec2<i32>(pos.xy), 0).x);
}

@fragment
fn fs_smooth_copied(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return smoothed(pos, bitcast<f32>(textureLoad(depth_copy, vec2<i32>(pos.xy), 0).x));
}

// The depth's bits, for `fs_smooth_copied` (a pass with no depth-stencil attachment).
@fragment
fn fs_copy_depth(@builtin(position) pos: vec4<f32>) -> @location(0) u32 {
    return bitcast<u32>(textureLoad(depth_stencil, vec2<i32>(pos.xy), 0).x);
}

// Everything that is not a voxel pixel: copied bit for bit.
@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(gbuffer_normal, vec2<i32>(pos.xy), 0);
}
