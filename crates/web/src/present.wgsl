// The page's canvas blit: the frame (a copy of the pipeline's output) drawn texel for texel
// into the canvas's texture. WebGPU canvases take no sRGB format, so an sRGB frame, which
// reads back linear, is encoded here; a frame already holding encoded bytes is not.

override ENCODE_SRGB: bool = true;

@group(0) @binding(0) var frame: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the viewport.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn encode(c: f32) -> f32 {
    if c <= 0.0031308 {
        return c * 12.92;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(frame, vec2<i32>(p.xy), 0);
    if ENCODE_SRGB {
        return vec4<f32>(encode(c.r), encode(c.g), encode(c.b), 1.0);
    }
    return vec4<f32>(c.rgb, 1.0);
}
