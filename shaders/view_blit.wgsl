// `ssbvb view`: copies the renderer's output (the pipeline's `output`, already lit) onto the
// window's surface with one fullscreen triangle. Not a pass kind: no graph slots.
//
// The source is sampled with textureLoad (same size as the surface: the renderer is rebuilt
// on resize), so pixels are copied 1:1 without filtering. Where the frame drew nothing
// (alpha 0) a background colour shows through.

//#include "fullscreen.inc.wgsl"

// 1: the surface format is not sRGB, so encode linear -> sRGB here (sRGB surfaces encode in
// hardware, and reading the Rgba8UnormSrgb source decodes in hardware).
override ENCODE_SRGB: bool = false;

// Linear RGB of the background behind empty pixels.
const BACKGROUND: vec3<f32> = vec3<f32>(0.018, 0.022, 0.03);

@group(0) @binding(0) var frame_color: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let size = textureDimensions(frame_color);
    let p = min(vec2<u32>(pos.xy), size - vec2(1u));
    let c = textureLoad(frame_color, p, 0);
    var rgb = mix(BACKGROUND, c.rgb, clamp(c.a, 0.0, 1.0));
    if ENCODE_SRGB {
        rgb = vec3(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    }
    return vec4(rgb, 1.0);
}
