//#include "common.inc.wgsl"
//#include "smooth.inc.wgsl"
// Smoothing as a compute pass (`SmoothCompute`), for adapters whose fragment work is slow:
// `smooth.wgsl`'s image, one thread per pixel. Where `smooth.wgsl` stencil-tests two
// fullscreen draws, this reads the stencil as a texture: voxel pixels get the smoothed
// normal (the same function, at the same pixel centre), every other pixel a bit-exact copy.

@group(1) @binding(0) var gbuffer_normal: texture_2d<f32>;
// Depth aspect of the G-buffer's depth-stencil (reversed Z), an unfilterable float texture.
@group(1) @binding(1) var depth_stencil: texture_2d<f32>;
@group(1) @binding(2) var smoothed_normal: texture_storage_2d<rgba16float, write>;
@group(1) @binding(3) var normal_sampler: sampler;
// Stencil aspect of the same depth-stencil (smooth_compute.rs makes the view).
@group(1) @binding(4) var voxel_stencil: texture_2d<u32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(smoothed_normal);
    if any(gid.xy >= size) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    var out = textureLoad(gbuffer_normal, p, 0);
    if textureLoad(voxel_stencil, p, 0).x == STENCIL_VOXEL {
        let centre = vec4(vec2<f32>(gid.xy) + 0.5, 0.0, 1.0);
        out = smoothed(centre, textureLoad(depth_stencil, p, 0).x);
    }
    textureStore(smoothed_normal, p, out);
}
