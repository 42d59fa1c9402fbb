//#include "common.inc.wgsl"
//#include "fullscreen.inc.wgsl"
// Temporal anti-aliasing: each frame is drawn with a sub-pixel jitter (`frame.jitter`, set
// by the renderer), and this pass blends it into the history, the previous output
// reprojected by the G-buffer's position: a surface point seen now at `px` was at `q` in
// the previous frame (the previous camera's unjittered view), so the history is read at
// `q` less this frame's jitter (a still camera reads its own pixel: no resampling blur).
// With DILATE the motion is that of the nearest surface in the 3 x 3 neighbourhood: at a
// silhouette the background pixels move with the object, and the history's soft edge
// goes with it instead of staying behind as a ghost. The history is clamped to the
// current colour's bounds around the pixel (3 x 3; in motion up to 4 x 4 or, at a pixel of
// motion, a variance clip of the 3 x 3: what it may hold of a surface no longer there), and
// weighted 1 - `taa.delta.w`, less where it moved (up
// to 1 - `taa.motion.x` at a pixel of motion: its resampling blurs). Where it moved, with
// UNJITTER, the current frame enters resampled to the pixel's centre (Catmull-Rom, from
// this frame's jitter): a jittered frame is the image shifted by up to half a pixel, and
// in motion its share is large. Colours are blended premultiplied by coverage; the output
// has straight alpha, like the composite's.

// The targets are 8-bit without hardware sRGB: texels hold sRGB-encoded values.
override ENCODED: bool = false;
// Reproject with the nearest surface's motion in the 3 x 3 neighbourhood.
override DILATE: bool = true;
// In motion, resample the current frame to the pixel centre.
override UNJITTER: bool = true;
// The camera moved since the previous frame. The pass has a pipeline for each case, chosen
// per frame: a still camera reads each pixel's own history texel, and a software
// rasterizer runs every branch of a shader whatever its condition, so the motion's code
// must not be in the still frame's pipeline.
override MOVING: bool = true;

struct Taa {
    // The previous frame's camera-relative world -> clip, unjittered.
    prev_view_proj: mat4x4<f32>,
    // xyz: this frame's camera position minus the previous frame's (world); w: the
    // current frame's weight (1: no history).
    delta: vec4<f32>,
    // x: the current frame's weight where the history moved by a pixel or more; y: the
    // variance clip's standard deviations there.
    motion: vec4<f32>,
}

@group(1) @binding(0) var current: texture_2d<f32>;
// Camera-relative world position in xyz, linear view depth in w (0: nothing drawn).
@group(1) @binding(1) var position: texture_2d<f32>;
@group(1) @binding(2) var<uniform> taa: Taa;
// The previous output, premultiplied (Rgba16Float).
@group(1) @binding(3) var history: texture_2d<f32>;
// Bilinear, clamped to the edge.
@group(1) @binding(4) var history_sampler: sampler;

struct Out {
    @location(0) color: vec4<f32>,
    @location(1) history: vec4<f32>,
    // 1 where the history was rejected: none to reproject (a cut, off screen), or the
    // neighbourhood clamp moved it by more than REJECT in a channel (it held another
    // surface, or in motion detail the narrowed bounds leave out). Read back by the quality
    // preset.
    @location(2) rejected: vec4<f32>,
}

// A clamp that moves the history by more than this (premultiplied linear) rejects it.
const REJECT: f32 = 0.0625;

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

// The history at `p` (pixels, centres at + 0.5), Catmull-Rom filtered: a moving camera
// resamples the history every frame, and a bilinear filter's blur would accumulate frame
// after frame; the cubic's overshoot is removed by the clamp after it. Its 4 x 4 taps as
// five bilinear reads (the middle two taps of each axis merged into one read between them,
// the four corner taps, whose weights are smallest, left out and the rest renormalized).
fn history_at(p: vec2<f32>) -> vec4<f32> {
    let inv = 1.0 / vec2<f32>(textureDimensions(history));
    let centre = floor(p - 0.5) + 0.5;
    let t = p - centre;
    let w0 = t * (-0.5 + t * (1.0 - 0.5 * t));
    let w1 = 1.0 + t * t * (-2.5 + 1.5 * t);
    let w2 = t * (0.5 + t * (2.0 - 1.5 * t));
    let w3 = t * t * (-0.5 + 0.5 * t);
    let w12 = w1 + w2;
    let mid = (centre + w2 / w12) * inv;
    let lo = (centre - 1.0) * inv;
    let hi = (centre + 2.0) * inv;
    let tap = textureSampleLevel(history, history_sampler, mid, 0.0) * (w12.x * w12.y)
        + textureSampleLevel(history, history_sampler, vec2(mid.x, lo.y), 0.0) * (w12.x * w0.y)
        + textureSampleLevel(history, history_sampler, vec2(mid.x, hi.y), 0.0) * (w12.x * w3.y)
        + textureSampleLevel(history, history_sampler, vec2(lo.x, mid.y), 0.0) * (w0.x * w12.y)
        + textureSampleLevel(history, history_sampler, vec2(hi.x, mid.y), 0.0) * (w3.x * w12.y);
    let total = w12.x * w12.y + w12.x * (w0.y + w3.y) + w12.y * (w0.x + w3.x);
    return tap / total;
}

// Catmull-Rom weights of the four taps around `t` (the sample's offset from the second tap).
fn cubic_weights(t: f32) -> vec4<f32> {
    return vec4(
        t * (-0.5 + t * (1.0 - 0.5 * t)),
        1.0 + t * t * (-2.5 + 1.5 * t),
        t * (0.5 + t * (2.0 - 1.5 * t)),
        t * t * (-0.5 + 0.5 * t),
    );
}

// Luminance and chroma (YCoCg), alpha kept: the moving pipeline's bounds are taken in it, so
// that a colour's spread along its luminance does not widen its chroma's bounds.
fn to_ycocg(c: vec4<f32>) -> vec4<f32> {
    return vec4(
        0.25 * c.r + 0.5 * c.g + 0.25 * c.b,
        0.5 * c.r - 0.5 * c.b,
        -0.25 * c.r + 0.5 * c.g - 0.25 * c.b,
        c.a,
    );
}

fn from_ycocg(c: vec4<f32>) -> vec4<f32> {
    return vec4(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z, c.w);
}

// `c` (premultiplied linear) clamped to YCoCg bounds; a box corner can lie a little outside
// the RGB cube.
fn clamp_ycocg(c: vec4<f32>, lo: vec4<f32>, hi: vec4<f32>) -> vec4<f32> {
    return max(from_ycocg(clamp(to_ycocg(c), lo, hi)), vec4(0.0));
}

// In motion: the bounds of the current colour around the pixel (YCoCg) and the current
// frame resampled to the pixel centre, from one 4 x 4 block of texels. The centre is
// `px + 0.5 - jitter`; the block's taps are `first .. first + 3` per axis with `first` =
// px - 1 - (1 where the jitter is positive), so it holds the 3 x 3 neighbourhood and one
// more row and column. The bounds take those in too where the history moved little (`moved`
// pixels): one jittered sample a pixel may miss detail below a pixel in all nine, and the
// converged history, clamped to them, would follow each frame's aliasing. Where it moved
// a pixel or more, the bounds are the 3 x 3 ones narrowed to `taa.motion.y` standard
// deviations about their mean, coverage included: what the resampling blurred into the
// history from a neighbouring surface lies outside them, and left in, it trails. The
// current frame's resample is held to the same bounds, which dims detail below a pixel in
// motion toward its neighbourhood (as the supersampled truth has it): held only to the
// min-max bounds, the path's FLIP was 0.0182 -> 0.0178 but its flicker 0.990 -> 1.000 and
// the one bunny's 0.9994 -> 1.0009 (docs/bench/details.md).
struct Block {
    lo: vec4<f32>,
    hi: vec4<f32>,
    centred: vec4<f32>,
}

fn block_at(px: vec2<i32>, moved: f32) -> Block {
    let p = vec2<f32>(px) + 0.5 - frame.jitter.xy;
    let centre = floor(p - 0.5) + 0.5;
    let t = p - centre;
    let wx = cubic_weights(t.x);
    let wy = cubic_weights(t.y);
    let first = vec2<i32>(floor(centre)) - 1;
    var b: Block;
    b.lo = vec4(3.4e38);
    b.hi = vec4(-3.4e38);
    var wide_lo = b.lo;
    var wide_hi = b.hi;
    b.centred = vec4(0.0);
    var m1 = vec4(0.0);
    var m2 = vec4(0.0);
    for (var j = 0; j < 4; j++) {
        for (var i = 0; i < 4; i++) {
            let at = first + vec2(i, j);
            let rgb = current_at(at);
            b.centred += rgb * (wx[i] * wy[j]);
            let c = to_ycocg(rgb);
            wide_lo = min(wide_lo, c);
            wide_hi = max(wide_hi, c);
            if all(abs(at - px) <= vec2(1)) {
                b.lo = min(b.lo, c);
                b.hi = max(b.hi, c);
                m1 += c;
                m2 += c * c;
            }
        }
    }
    let mean = m1 / 9.0;
    let sigma = sqrt(max(m2 / 9.0 - mean * mean, vec4(0.0)));
    let tight_lo = max(b.lo, mean - taa.motion.y * sigma);
    let tight_hi = min(b.hi, mean + taa.motion.y * sigma);
    b.lo = mix(wide_lo, tight_lo, moved);
    b.hi = mix(wide_hi, tight_hi, moved);
    return b;
}

// The pixel whose surface moves `px`: itself, or with DILATE and a moving camera the
// nearest drawn pixel of its 3 x 3 neighbourhood (itself when none is drawn).
fn motion_source(px: vec2<i32>) -> vec2<i32> {
    if !DILATE {
        return px;
    }
    var best = px;
    var depth = 3.4e38;
    let last = vec2<i32>(textureDimensions(position)) - 1;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let n = clamp(px + vec2(dx, dy), vec2(0), last);
            let d = textureLoad(position, n, 0).w;
            if d > 0.0 && d < depth {
                depth = d;
                best = n;
            }
        }
    }
    return best;
}

// The 3 x 3 neighbourhood's bounds of the current colour (a still frame's).
fn neighbourhood(px: vec2<i32>) -> array<vec4<f32>, 2> {
    var lo = vec4(3.4e38);
    var hi = vec4(-3.4e38);
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let n = current_at(px + vec2(dx, dy));
            lo = min(lo, n);
            hi = max(hi, n);
        }
    }
    return array(lo, hi);
}

// Whether clamping `held` to [lo, hi] moved it by more than REJECT in a channel.
fn is_rejected(held: vec4<f32>, h: vec4<f32>) -> f32 {
    let clamped = abs(held - h);
    return select(0.0, 1.0, max(max(clamped.r, clamped.g), max(clamped.b, clamped.a)) > REJECT);
}

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> Out {
    let px = vec2<i32>(pos.xy);
    let cur = current_at(px);
    var result = cur;
    var rejected = 1.0;
    if !MOVING {
        if taa.delta.w < 1.0 {
            // Every pixel reprojects to itself.
            let bounds = neighbourhood(px);
            let held = textureLoad(history, px, 0);
            let h = clamp(held, bounds[0], bounds[1]);
            rejected = is_rejected(held, h);
            result = mix(h, cur, taa.delta.w);
        }
    } else if taa.delta.w < 1.0 {
        let source = motion_source(px);
        let p = textureLoad(position, source, 0);
        var clip: vec4<f32>;
        if p.w > 0.0 {
            clip = taa.prev_view_proj * vec4(p.xyz + taa.delta.xyz, 1.0);
        } else {
            // Nothing drawn: the direction, seen at infinity.
            clip = taa.prev_view_proj * vec4(pixel_ray(pos.xy), 0.0);
        }
        if clip.w > 0.0 {
            let ndc = clip.xy / clip.w;
            // Where `source`'s centre was, moved back to this pixel.
            let q = vec2((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * frame.screen.xy
                - frame.jitter.xy + vec2<f32>(px - source);
            if all(q >= vec2(0.0)) && all(q <= frame.screen.xy) {
                let moved = clamp(length(q - (vec2<f32>(px) + 0.5)), 0.0, 1.0);
                let b = block_at(px, moved);
                let held = history_at(q);
                let h = clamp_ycocg(held, b.lo, b.hi);
                rejected = is_rejected(held, h);
                var c = cur;
                if UNJITTER {
                    c = mix(cur, clamp_ycocg(b.centred, b.lo, b.hi), moved);
                }
                result = mix(h, c, mix(taa.delta.w, taa.motion.x, moved));
            }
        }
    }
    var out: Out;
    out.history = result;
    out.rejected = vec4(rejected, 0.0, 0.0, 0.0);
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
