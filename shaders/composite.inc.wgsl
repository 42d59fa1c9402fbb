// Shared by the deferred composites (composite.wgsl, cone_composite.wgsl): the G-buffer
// they read (group 1, bindings 0 to 2), the pixel's surface, and the output encoding.
// Needs common.inc.wgsl and fullscreen.inc.wgsl before it.

// Encode linear -> sRGB in the shader (for non-sRGB 8-bit targets; sRGB targets encode in
// hardware).
override ENCODE_SRGB: bool = false;

@group(1) @binding(0) var albedo: texture_2d<u32>;
@group(1) @binding(1) var normal: texture_2d<f32>;
// Camera-relative world position (xyz) and linear view depth (w).
@group(1) @binding(2) var position: texture_2d<f32>;

// What the G-buffer holds at a pixel.
struct Surface {
    // Linear RGBA.
    albedo: vec4<f32>,
    normal: vec3<f32>,
    // Camera-relative world position.
    position: vec3<f32>,
}

// The G-buffer at pixel `p`. Where nothing was drawn (alpha 0) the fragment is discarded:
// the target keeps what it holds (cleared to transparent black when this pass is the
// target's first writer, the caller's image when embedded).
fn surface_at(p: vec2<i32>) -> Surface {
    let a = unpack4x8unorm(textureLoad(albedo, p, 0).x);
    if a.a == 0.0 {
        discard;
    }
    let n = textureLoad(normal, p, 0).xyz;
    let x = textureLoad(position, p, 0).xyz;
    return Surface(a, n, x);
}

// The output colour of lit `rgb`: clamped to [0, 1], sRGB-encoded when ENCODE_SRGB.
fn composite_output(lit: vec3<f32>) -> vec4<f32> {
    var rgb = clamp(lit, vec3(0.0), vec3(1.0));
    if ENCODE_SRGB {
        rgb = vec3(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    }
    return vec4(rgb, 1.0);
}
