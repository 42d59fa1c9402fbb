// Shared by the fullscreen passes (composite, smooth, the ray-casting baselines) and the
// viewer's blit: one triangle that covers the screen (draw 3 vertices), and the linear ->
// sRGB encoding for 8-bit targets that do not encode in hardware.

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn linear_to_srgb(x: f32) -> f32 {
    let c = clamp(x, 0.0, 1.0);
    if c <= 0.0031308 {
        return c * 12.92;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
