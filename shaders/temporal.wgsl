//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
// Temporal anti-aliasing: each frame is drawn with a sub-pixel jitter (`frame.jitter`, set
// by the renderer), and this pass blends it into the history, the previous output
// reprojected by the G-buffer's position: a surface point seen now at `px` was at `q` in
// the previous frame (the previous camera's unjittered view), so the history is read at
// `q` less this frame's jitter (a still camera reads its own pixel: no resampling blur).
// The history is clamped to the current colour's 3 x 3 neighbourhood (what it may hold
// of a surface no longer there), and weighted 1 - `taa.delta.w`. Colours are blended
// premultiplied by coverage; the output has straight alpha, like the composite's.

// The targets are 8-bit without hardware sRGB: texels hold sRGB-encoded values.
override ENCODED: bool = false;

struct Taa {
    // The previous frame's camera-relative world -> clip, unjittered.
    prev_view_proj: mat4x4<f32>,
    // xyz: this frame's camera position minus the previous frame's (world); w: the
    // current frame's weight (1: no history).
    delta: vec4<f32>,
}

@group(1) @binding(0) var current: texture_2d<f32>;
// Camera-relative world position in xyz, linear view depth in w (0: nothing drawn).
@group(1) @binding(1) var position: texture_2d<f32>;
@group(1) @binding(2) var<uniform> taa: Taa;
// The previous output, premultiplied (Rgba16Float).
@group(1) @binding(3) var history: texture_2d<f32>;

struct Out {
    @location(0) color: vec4<f32>,
    @location(1) history: vec4<f32>,
}

fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.04045 {
        return x / 12.92;
    }
    return pow((x + 0.055) / 1.055, 2.4);
}

// The current colour at `p`, linear and premultiplied.
fn current_at(p: vec2<i32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(current));
    var c = textureLoad(current, clamp(p, vec2(0), size - 1), 0);
    if ENCODED {
        c = vec4(srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b), c.a);
    }
    return vec4(c.rgb * c.a, c.a);
}

// The history bilinearly at `p` (pixels, centres at + 0.5).
fn history_at(p: vec2<f32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(history));
    let q = p - 0.5;
    let i = vec2<i32>(floor(q));
    let f = q - floor(q);
    var s = vec4(0.0);
    for (var dy = 0; dy < 2; dy++) {
        for (var dx = 0; dx < 2; dx++) {
            let w = select(1.0 - f.x, f.x, dx == 1) * select(1.0 - f.y, f.y, dy == 1);
            s += w * textureLoad(history, clamp(i + vec2(dx, dy), vec2(0), size - 1), 0);
        }
    }
    return s;
}

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> Out {
    let px = vec2<i32>(pos.xy);
    let cur = current_at(px);
    var lo = cur;
    var hi = cur;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let n = current_at(px + vec2(dx, dy));
            lo = min(lo, n);
            hi = max(hi, n);
        }
    }
    var result = cur;
    if taa.delta.w < 1.0 {
        let p = textureLoad(position, px, 0);
        var clip: vec4<f32>;
        if p.w > 0.0 {
            clip = taa.prev_view_proj * vec4(p.xyz + taa.delta.xyz, 1.0);
        } else {
            // Nothing drawn: the direction, seen at infinity.
            clip = taa.prev_view_proj * vec4(pixel_ray(pos.xy), 0.0);
        }
        if clip.w > 0.0 {
            let ndc = clip.xy / clip.w;
            let q = vec2((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * frame.screen.xy
                - frame.jitter.xy;
            if all(q >= vec2(0.0)) && all(q <= frame.screen.xy) {
                let h = clamp(history_at(q), lo, hi);
                result = mix(h, cur, taa.delta.w);
            }
        }
    }
    var out: Out;
    out.history = result;
    var rgb = vec3(0.0);
    if result.a > 0.0 {
        rgb = result.rgb / result.a;
    }
    if ENCODED {
        rgb = vec3(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    }
    out.color = vec4(rgb, result.a);
    return out;
}
