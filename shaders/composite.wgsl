//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
// Deferred composite: directional + ambient Blinn-Phong, the same formula as the CPU
// reference (ssbvb-voxel shading::shade); pixels where nothing was drawn
// are left alone (transparent black when the output is cleared).

// Encode linear -> sRGB in the shader (for non-sRGB 8-bit targets; sRGB targets encode in
// hardware).
override ENCODE_SRGB: bool = false;

@group(1) @binding(0) var albedo: texture_2d<u32>;
@group(1) @binding(1) var normal: texture_2d<f32>;
// Camera-relative world position (xyz) and linear view depth (w).
@group(1) @binding(2) var position: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(pos.xy);
    let a = unpack4x8unorm(textureLoad(albedo, p, 0).x);
    // Nothing drawn here: keep what the target holds (cleared to transparent black when
    // this pass is the target's first writer, the caller's image when embedded).
    if a.a == 0.0 {
        discard;
    }
    let n = textureLoad(normal, p, 0).xyz;
    let x = textureLoad(position, p, 0).xyz;
    // The eye is the camera-relative origin.
    var rgb = shade(a.rgb, n, -x);
    rgb = clamp(rgb, vec3(0.0), vec3(1.0));
    if ENCODE_SRGB {
        rgb = vec3(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    }
    return vec4(rgb, 1.0);
}
