//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
//#include "smooth.inc.wgsl"
// Gaussian smoothing of voxel normals (the paper's step 5): a 3x3 Gaussian whose sample
// offset I follows Eq. 1, I = max(0, min(MaxI / (Dist - MinDist)^2, MaxI)), with Dist the
// distance from the camera reconstructed per pixel from depth with the inverse
// view-projection. Two draws, both stencil-tested: voxel pixels get the smoothed normal,
// every other pixel (triangles, background) a bit-exact copy, so triangle pixels are never
// touched.

@group(1) @binding(0) var gbuffer_normal: texture_2d<f32>;
// Depth aspect of the read-only depth-stencil attachment (reversed Z), bound as an
// unfilterable float texture: GLSL has no texel fetch from depth textures.
@group(1) @binding(1) var depth_stencil: texture_2d<f32>;
@group(1) @binding(2) var normal_sampler: sampler;
// Where the device cannot sample the depth-stencil it tests against (GL, WebGL: no
// read-only depth-stencil attachments), or `copy_depth`: the depth's bits, written by
// `fs_copy_depth` in a pass before (smooth.rs).
@group(1) @binding(3) var depth_copy: texture_2d<u32>;

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
