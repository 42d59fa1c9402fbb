//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
//#include "composite.inc.wgsl"
// Deferred composite with the cone tracer's light: `composite.wgsl` with `shade_lit`
// (ambient occlusion, soft shadow, one diffuse bounce). Pixels where nothing was drawn are
// left alone.

// r: ambient occlusion, g: light visibility.
@group(1) @binding(3) var occlusion: texture_2d<f32>;
// rgb: one-bounce radiance arriving.
@group(1) @binding(4) var indirect: texture_2d<f32>;

struct Upsampled {
    occlusion: vec4<f32>,
    indirect: vec3<f32>,
}

// Joint bilateral upsampling of targets traced at one pixel of each `ratio`² block (texel
// q holds pixel q · ratio; cone_trace.wgsl): the four texels around the pixel, weighted
// bilinearly and by how well their pixel's depth and normal match this one's, so light
// does not bleed across silhouettes. A pixel traced itself takes its own texel.
fn upsample(p: vec2<i32>, x: vec3<f32>, n: vec3<f32>, low: vec2<i32>, full: vec2<i32>) -> Upsampled {
    // As cone_trace.rs computes it: the targets are a whole fraction of the screen
    // (checked), so full / low is within a texel of a whole k (161 pixels over 81 texels:
    // 2).
    let ratio = max(floor(f32(full.x) / f32(low.x) + 0.5), 1.0);
    let f = vec2<f32>(p) / ratio;
    let base = vec2<i32>(floor(f));
    let frac = f - vec2<f32>(base);
    let depth = length(x);
    var sum_o = vec4(0.0);
    var sum_b = vec3(0.0);
    var sum_w = 0.0;
    for (var j = 0; j < 4; j++) {
        let q = min(base + vec2(j & 1, j >> 1u), low - 1);
        let bw = select(1.0 - frac.x, frac.x, (j & 1) == 1) * select(1.0 - frac.y, frac.y, (j >> 1u) == 1);
        let src = min(vec2<i32>(vec2<f32>(q) * ratio), full - 1);
        if bw <= 0.0 || unpack4x8unorm(textureLoad(albedo, src, 0).x).a == 0.0 {
            continue;
        }
        let xs = textureLoad(position, src, 0).xyz;
        let ns = textureLoad(normal, src, 0).xyz;
        let dz = abs(length(xs) - depth) / max(depth, 1e-6);
        let w = bw * exp(-dz * 100.0) * pow(max(dot(ns, n), 0.0), 8.0) + 1e-6 * bw;
        sum_o += w * textureLoad(occlusion, q, 0);
        sum_b += w * textureLoad(indirect, q, 0).rgb;
        sum_w += w;
    }
    if sum_w <= 0.0 {
        return Upsampled(vec4(1.0, 1.0, 0.0, 1.0), vec3(0.0));
    }
    return Upsampled(sum_o / sum_w, sum_b / sum_w);
}

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(pos.xy);
    let s = surface_at(p);
    let n = s.normal;
    let x = s.position;
    var o = textureLoad(occlusion, p, 0);
    var b = textureLoad(indirect, p, 0).rgb;
    let low = vec2<i32>(textureDimensions(occlusion));
    let full = vec2<i32>(textureDimensions(albedo));
    if any(low != full) {
        let lit = upsample(p, x, n, low, full);
        o = lit.occlusion;
        b = lit.indirect;
    }
    return composite_output(shade_lit(s.albedo.rgb, n, -x, o.r, o.g, b));
}
