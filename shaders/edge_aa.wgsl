//#include "fullscreen.inc.wgsl"
// Single-frame anti-aliasing for stills (`EdgeAa`), FXAA-style (after Lottes' FXAA: the
// contrast test, the edge orientation from the 3 x 3 luma, the search along the edge and
// the sub-pixel blend), on the output colour with straight alpha: colours are taken
// premultiplied by alpha and luma counts coverage (COVERAGE_LUMA), so a silhouette against
// the empty background (alpha 0) is an edge like any other, a dark object's too, and the
// output is straight alpha again.
//
// Per pixel: skip unless the 3 x 3 luma range exceeds THRESHOLD of its maximum (and an
// absolute floor); the edge runs along x when the vertical second differences dominate.
// Across it the neighbour with the steeper step is the pixel's partner; along the edge,
// up to SEARCH steps each way, the mean luma of the pixel pair stays near the edge's
// midpoint luma while the edge goes on. Where the pixel lies on the edge's ends (the
// stair's step) it takes 0.5 - (distance to the nearer end) / (edge length) of its
// partner: the coverage of the straight line through the step's middle. A pixel unlike
// all its neighbours (a sub-pixel feature) blends towards the neighbourhood by SUBPIXEL.
// The larger of the two blends wins.

override THRESHOLD: f32 = 0.125;
// Contrast below this (absolute luma) is never an edge: noise in dark regions.
const THRESHOLD_MIN: f32 = 0.0312;
override SUBPIXEL: f32 = 0.75;
// Pixels searched each way along an edge.
const SEARCH: i32 = 12;

@group(1) @binding(0) var current: texture_2d<f32>;

// The texel at `p` clamped to the screen, premultiplied.
fn texel(p: vec2<i32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(current));
    let c = textureLoad(current, clamp(p, vec2(0), size - 1), 0);
    return vec4(c.rgb * c.a, c.a);
}

// The least luma of a covered pixel: a dark object against the empty background still
// has a silhouette of this contrast.
const COVERAGE_LUMA: f32 = 0.25;

// Perceptual brightness of a premultiplied colour, at least COVERAGE_LUMA times its
// coverage.
fn luma(c: vec4<f32>) -> f32 {
    return max(sqrt(max(dot(c.rgb, vec3(0.299, 0.587, 0.114)), 0.0)), COVERAGE_LUMA * c.a);
}

fn luma_at(p: vec2<i32>) -> f32 {
    return luma(texel(p));
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(frag.xy);
    let centre = texel(p);
    let m = luma(centre);
    let n = luma_at(p + vec2(0, -1));
    let s = luma_at(p + vec2(0, 1));
    let w = luma_at(p + vec2(-1, 0));
    let e = luma_at(p + vec2(1, 0));
    let lo = min(m, min(min(n, s), min(w, e)));
    let hi = max(m, max(max(n, s), max(w, e)));
    let range = hi - lo;
    if range < max(THRESHOLD_MIN, hi * THRESHOLD) {
        // Untouched: the texel as it was.
        return textureLoad(current, p, 0);
    }
    let nw = luma_at(p + vec2(-1, -1));
    let ne = luma_at(p + vec2(1, -1));
    let sw = luma_at(p + vec2(-1, 1));
    let se = luma_at(p + vec2(1, 1));
    // Second differences: large across the edge.
    let across_y = abs(nw + sw - 2.0 * w) + 2.0 * abs(n + s - 2.0 * m) + abs(ne + se - 2.0 * e);
    let across_x = abs(nw + ne - 2.0 * n) + 2.0 * abs(w + e - 2.0 * m) + abs(sw + se - 2.0 * s);
    let along_x = across_y >= across_x;
    // `step`: towards the partner across the edge; `dir`: along the edge.
    var step = select(vec2(1, 0), vec2(0, 1), along_x);
    let dir = select(vec2(0, 1), vec2(1, 0), along_x);
    let l_neg = select(w, n, along_x);
    var l_pos = select(e, s, along_x);
    if abs(l_neg - m) > abs(l_pos - m) {
        step = -step;
        l_pos = l_neg;
    }
    let partner = l_pos;
    let gradient = abs(partner - m);
    let mid = 0.5 * (m + partner);
    // Search along the edge for where the pair's mean leaves the midpoint.
    var d_neg = SEARCH;
    var end_neg = mid;
    for (var k = 1; k <= SEARCH; k++) {
        let q = p - dir * k;
        let pair = 0.5 * (luma_at(q) + luma_at(q + step));
        if abs(pair - mid) >= 0.25 * gradient {
            d_neg = k;
            end_neg = pair;
            break;
        }
    }
    var d_pos = SEARCH;
    var end_pos = mid;
    for (var k = 1; k <= SEARCH; k++) {
        let q = p + dir * k;
        let pair = 0.5 * (luma_at(q) + luma_at(q + step));
        if abs(pair - mid) >= 0.25 * gradient {
            d_pos = k;
            end_pos = pair;
            break;
        }
    }
    // The nearer end decides: the pixel is on the step's lower side when the pair's mean
    // there moved the way the centre differs from the midpoint.
    let near_neg = d_neg < d_pos;
    let end = select(end_pos, end_neg, near_neg);
    let dist = f32(min(d_neg, d_pos));
    let span = f32(d_neg + d_pos);
    var edge_blend = 0.0;
    if (m - mid < 0.0) != (end - mid < 0.0) {
        edge_blend = 0.5 - dist / span;
    }
    // Sub-pixel: how unlike its neighbourhood the pixel is.
    let average = (2.0 * (n + s + w + e) + nw + ne + sw + se) / 12.0;
    let unlike = clamp(abs(average - m) / range, 0.0, 1.0);
    let smooth_unlike = (3.0 - 2.0 * unlike) * unlike * unlike;
    let sub_blend = smooth_unlike * smooth_unlike * SUBPIXEL * 0.5;
    let blend = max(edge_blend, sub_blend);
    return straight(mix(centre, texel(p + step), blend));
}

// Straight alpha from premultiplied.
fn straight(c: vec4<f32>) -> vec4<f32> {
    if c.a <= 0.0 {
        return vec4(0.0);
    }
    return vec4(c.rgb / c.a, c.a);
}
