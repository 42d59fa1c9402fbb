//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
//#include "composite.inc.wgsl"
// The deferred composite as a compute pass (`CompositeCompute`), for adapters whose
// fragment work is slow: composite.wgsl's lighting, one thread per pixel, into an
// `Rgba8Unorm` storage texture (sRGB formats cannot be storage textures), encoded in the
// shader as `Composite` encodes for such a target. Where nothing was drawn the pass writes
// transparent black when it is the output's first writer (CLEAR), and leaves the pixel
// alone otherwise, as the fragment pass's discard does.

@group(1) @binding(3) var color: texture_storage_2d<rgba8unorm, write>;

override CLEAR: bool = true;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if any(gid.xy >= textureDimensions(color)) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let a = unpack4x8unorm(textureLoad(albedo, p, 0).x);
    if a.a == 0.0 {
        if CLEAR {
            textureStore(color, p, vec4(0.0));
        }
        return;
    }
    let n = textureLoad(normal, p, 0).xyz;
    let x = textureLoad(position, p, 0).xyz;
    // The eye is the camera-relative origin.
    textureStore(color, p, composite_output(shade(a.rgb, n, -x)));
}
