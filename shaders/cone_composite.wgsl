//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
// Deferred composite with the cone tracer's light: `composite.wgsl` with `shade_lit`
// (ambient occlusion, soft shadow, one diffuse bounce). Pixels where nothing was drawn are
// left alone.

override ENCODE_SRGB: bool = false;

@group(1) @binding(0) var albedo: texture_2d<f32>;
@group(1) @binding(1) var normal: texture_2d<f32>;
@group(1) @binding(2) var position: texture_2d<f32>;
// r: ambient occlusion, g: light visibility.
@group(1) @binding(3) var occlusion: texture_2d<f32>;
// rgb: one-bounce radiance arriving.
@group(1) @binding(4) var indirect: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(pos.xy);
    let a = textureLoad(albedo, p, 0);
    if a.a == 0.0 {
        discard;
    }
    let n = textureLoad(normal, p, 0).xyz;
    let x = textureLoad(position, p, 0).xyz;
    let o = textureLoad(occlusion, p, 0);
    let b = textureLoad(indirect, p, 0).rgb;
    var rgb = shade_lit(a.rgb, n, -x, o.r, o.g, b);
    rgb = clamp(rgb, vec3(0.0), vec3(1.0));
    if ENCODE_SRGB {
        rgb = vec3(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    }
    return vec4(rgb, 1.0);
}
