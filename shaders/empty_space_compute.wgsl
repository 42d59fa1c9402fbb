//#include "common.inc.wgsl"

// empty_space_compute: the empty-space prepass in compute (`EmptySpaceCompute`), for
// adapters whose raster units are slow. It writes what `empty_space.wgsl` rasterizes:
// per texel of `entry`, xyz = the object-space point where the texel-centre ray enters the
// nearest proxy surface (the camera for a back face), w = instance index + 1 (0 = none).
//
// Proxy triangles are rasterized in software, one thread per triangle of the frame's
// visible instances (`prepass_words` lists them as runs, written per frame by
// empty_space_compute.rs):
//
// 1. `raster` (step 1): each triangle is clipped against the near plane (in clip space, as
//    the rasterizer clips), projected, and every texel centre it covers takes the nearest
//    reversed-Z depth by `atomicMax` on its bits (depth > 0, as a `Greater` test against a
//    cleared 0). Triangles whose pixel rectangle is large are listed instead, and
//    `large` gives each of them a workgroup (one thread walking 100,000 pixels would
//    hold its whole wave back).
// 2. `raster` and `large` again (step 2, dispatched with two layers): where a triangle's depth is the
//    texel's nearest, it offers its facing and index (`atomicMax` of the inverted
//    (back, index) pair). At an exact tie a front face wins over a back face, then the
//    lower triangle, as the rasterizer's strict test keeps the first-drawn fragment (it
//    draws every front face, in instance order, before any back face).
// 3. `resolve`, per texel: the winner's entry point, where the texel-centre ray meets its
//    plane; the camera for a back face; where no proxy covers the texel and the camera is
//    inside some proxy, the camera of the last such instance (the rasterizer's full-screen
//    fill). No branch rebuilds the winner's clipped polygon: a software adapter runs
//    every branch under a lane mask, so a rare costly branch would cost every texel.
//
// Coverage is watertight: a texel centre on a shared edge is inside both triangles. Each
// edge function is evaluated with its endpoints in one canonical order, so the two
// triangles of an edge compute it bit for bit negated, and the test includes zero; near
// clipping interpolates an edge from its inside endpoint in both. The proxies have no
// T-junctions (ssbvb-voxel proxy.rs), so every edge is shared whole.

@group(1) @binding(0) var entry: texture_storage_2d<rgba32float, write>;
// The scene's proxy meshes (object-space positions; triangles counter-clockwise seen from
// outside).
@group(1) @binding(1) var<storage, read> proxy_vertices: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> proxy_indices: array<u32>;
// One buffer (the pass then fits WebGPU's 8 storage buffers per stage beside the scene's
// 5): the frame's header (H_*) and runs of triangles, written by the CPU; two words per
// texel from H_TEXELS on (the nearest depth's bits; the inverted index and facing of the
// nearest triangle); then the count of large triangles and their list.
@group(1) @binding(3) var<storage, read_write> prepass_words: array<atomic<u32>>;
// `large`'s indirect dispatch, written by `large_args` (the only
// entry point binding it).
@group(1) @binding(4) var<storage, read_write> prepass_dispatch: array<u32, 6>;

// Header words.
const H_RUNS: u32 = 0u;
const H_TRIANGLES: u32 = 1u;
const H_FILL: u32 = 2u;
const H_TEXELS: u32 = 3u;
// Runs start here, four words each: first triangle (in the frame's numbering), first
// index, base vertex (i32 bits), instance | BACK_FACES.
const RUNS_AT: u32 = 4u;
const BACK_FACES: u32 = 0x80000000u;

// Threads per workgroup of the per-triangle and large-triangle entry points.
const GROUP: u32 = 64u;
// Pixels of a triangle's clamped rectangle above which it gets a workgroup of its own (set
// per adapter class by empty_space_compute.rs).
override LARGE_PIXELS: u32 = 256u;

// One triangle of a polygon's fan: its corners in pixels and their reversed-Z depths
// (depth is affine in screen space).
struct Fan {
    a: vec2<f32>,
    b: vec2<f32>,
    c: vec2<f32>,
    depth: vec3<f32>,
}

// A clipped, projected polygon (3 or 4 vertices) as a fan of one or two triangles around
// its first vertex (fields, not arrays: a software adapter indexes a private array per
// lane through memory, and the per-texel test would pay that at every texel).
struct Polygon {
    fan0: Fan,
    fan1: Fan,
    // Two triangles (a quad), or one.
    quad: bool,
    // Vertices (0: nothing to draw).
    n: u32,
    instance: u32,
    back: bool,
    // Inclusive texel range of its rectangle (empty when lo > hi).
    lo: vec2<i32>,
    hi: vec2<i32>,
}

fn word(i: u32) -> u32 {
    return atomicLoad(&prepass_words[i]);
}

// Where the large triangles' count is, their list following it.
fn large_at(size: vec2<u32>) -> u32 {
    return word(H_TEXELS) + 2u * size.x * size.y;
}

// The run holding triangle `g`: the last run whose first triangle is at most `g`.
fn run_of(g: u32) -> u32 {
    var lo = 0u;
    var hi = word(H_RUNS);
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if word(RUNS_AT + 4u * mid) <= g {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// The edge function of `p` against the directed edge a -> b (positive on its left in
// pixel coordinates), computed from the endpoints in a canonical order, so that the
// reversed edge gives exactly the negated value.
fn edge(a: vec2<f32>, b: vec2<f32>, p: vec2<f32>) -> f32 {
    if a.x < b.x || (a.x == b.x && a.y < b.y) {
        return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    }
    return -((a.x - b.x) * (p.y - b.y) - (a.y - b.y) * (p.x - b.x));
}

// Triangle `g` of the frame, clipped against the near plane and projected onto `size`
// texels; `n = 0` when nothing of it can be drawn (clipped away, degenerate, or a back
// face of an instance that does not draw them).
fn polygon(g: u32, size: vec2<u32>) -> Polygon {
    var out: Polygon;
    out.n = 0u;
    let r = RUNS_AT + 4u * run_of(g);
    let tri = g - word(r);
    let first = word(r + 1u) + 3u * tri;
    let base = bitcast<i32>(word(r + 2u));
    let tagged = word(r + 3u);
    out.instance = tagged & ~BACK_FACES;
    let to_clip = frame.proj * instances[out.instance].object_to_view;
    var clip: array<vec4<f32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        let v = u32(i32(proxy_indices[first + k]) + base);
        clip[k] = to_clip * vec4(proxy_vertices[v].xyz, 1.0);
    }
    // Sutherland–Hodgman against the near plane (reversed Z: depth <= 1, i.e. w - z >= 0).
    var cp: array<vec4<f32>, 4>;
    var n = 0u;
    for (var k = 0u; k < 3u; k++) {
        let k1 = (k + 1u) % 3u;
        let dk = clip[k].w - clip[k].z;
        let d1 = clip[k1].w - clip[k1].z;
        if dk >= 0.0 {
            cp[n] = clip[k];
            n++;
        }
        if (dk >= 0.0) != (d1 >= 0.0) {
            // From the inside endpoint, so both triangles of an edge make the same point.
            let i = select(k1, k, dk >= 0.0);
            let o = select(k, k1, dk >= 0.0);
            let di = clip[i].w - clip[i].z;
            let s = di / (di - (clip[o].w - clip[o].z));
            cp[n] = clip[i] + s * (clip[o] - clip[i]);
            n++;
        }
    }
    if n < 3u {
        return out;
    }
    let fsize = vec2<f32>(size);
    var lo = vec2(1e30);
    var hi = vec2(-1e30);
    var p: array<vec2<f32>, 4>;
    var depth: array<f32, 4>;
    for (var k = 0u; k < n; k++) {
        if !(cp[k].w > 0.0) {
            return out;
        }
        let ndc = cp[k].xyz / cp[k].w;
        p[k] = vec2(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * fsize;
        depth[k] = ndc.z;
        lo = min(lo, p[k]);
        hi = max(hi, p[k]);
    }
    // Twice the signed area in pixel coordinates (y down): negative for a polygon that is
    // counter-clockwise in NDC, the rasterizer's front face.
    var area = 0.0;
    for (var k = 0u; k < n; k++) {
        let a = p[k];
        let b = p[(k + 1u) % n];
        area += a.x * b.y - b.x * a.y;
    }
    out.fan0 = Fan(p[0], p[1], p[2], vec3(depth[0], depth[1], depth[2]));
    out.quad = n == 4u;
    out.fan1 = Fan(p[0], p[2], p[3], vec3(depth[0], depth[2], depth[3]));
    if !(area != 0.0) {
        return out;
    }
    out.back = area > 0.0;
    if out.back && (tagged & BACK_FACES) == 0u {
        return out;
    }
    // Texels whose centre (x + 0.5) lies in [lo, hi], clamped before the conversion.
    out.lo = vec2<i32>(ceil(clamp(lo - 0.5, vec2(-1.0), fsize)));
    out.hi = vec2<i32>(floor(clamp(hi - 0.5, vec2(-1.0), fsize)));
    out.lo = max(out.lo, vec2(0));
    out.hi = min(out.hi, vec2<i32>(size) - 1);
    out.n = n;
    return out;
}

// Texels in the polygon's rectangle.
fn rect_texels(poly: Polygon) -> u32 {
    if poly.n == 0u || any(poly.hi < poly.lo) {
        return 0u;
    }
    let d = vec2<u32>(poly.hi - poly.lo) + 1u;
    return d.x * d.y;
}

// A fan triangle's depth at `p`, or -1 where it does not cover `p` (`sign`: +1 where the
// inside is on the edges' left).
fn fan_depth(f: Fan, p: vec2<f32>, sign: f32) -> f32 {
    // Weights of a, b and c: the edge functions of the opposite edges, oriented so that
    // the inside is positive.
    let w = sign * vec3(edge(f.b, f.c, p), edge(f.c, f.a, p), edge(f.a, f.b, p));
    let sum = w.x + w.y + w.z;
    if all(w >= vec3(0.0)) && sum > 0.0 {
        return dot(w / sum, f.depth);
    }
    return -1.0;
}

// The polygon's depth at texel `t`'s centre, -1 or less where it is not drawn there.
fn sample_depth(poly: Polygon, t: vec2<i32>) -> f32 {
    let p = vec2<f32>(t) + 0.5;
    let sign = select(-1.0, 1.0, poly.back);
    // Where both triangles cover the centre (on their shared diagonal) their depths agree
    // but for rounding; the nearer counts.
    let d0 = fan_depth(poly.fan0, p, sign);
    return select(d0, max(d0, fan_depth(poly.fan1, p, sign)), poly.quad);
}

// The polygon's depth at `t` when it is drawn there (0 when not: a `Greater` test against
// the cleared far end passes nothing at 0, and the far plane clips depths below 0).
fn depth_at(poly: Polygon, t: vec2<i32>) -> u32 {
    let depth = sample_depth(poly, t);
    if !(depth > 0.0) {
        return 0u;
    }
    return bitcast<u32>(min(depth, 1.0));
}

fn texel_word(t: vec2<i32>, size: vec2<u32>) -> u32 {
    return word(H_TEXELS) + 2u * (u32(t.y) * size.x + u32(t.x));
}

// Which step a dispatch of `raster` or `large` runs, and whether this workgroup has work
// in it. One pipeline runs both steps, so that the depth step 2 compares is computed by
// the same compiled code as step 1's (two pipelines might contract a multiply-add in one
// and not the other, and then no triangle would match): step 1 is dispatched with one
// layer of workgroups, step 2 with two, of which the first returns at once.
struct Step {
    id_step: bool,
    idle: bool,
}

fn step_of(wg: vec3<u32>, groups: vec3<u32>) -> Step {
    let id_step = groups.z == 2u;
    return Step(id_step, id_step && wg.z == 0u);
}

// The polygon of triangle `g` offers itself at texel `t`: in step 1 its depth, in step 2,
// where that depth is the nearest, its facing and index.
fn offer(poly: Polygon, g: u32, t: vec2<i32>, size: vec2<u32>, id_step: bool) {
    let d = depth_at(poly, t);
    let at = texel_word(t, size);
    if d == 0u {
        return;
    }
    if !id_step {
        atomicMax(&prepass_words[at], d);
    } else if d == atomicLoad(&prepass_words[at]) {
        // Its facing and index: a front face, then the lower triangle, wins a tie.
        atomicMax(&prepass_words[at + 1u], ~((u32(poly.back) << 31u) | g));
    }
}

// The workgroup's index in a (possibly two-dimensional) grid.
fn group_index(wg: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wg.y * groups.x + wg.x;
}

// The triangle of a per-triangle thread, and its polygon; n = 0 past the last triangle.
fn thread_polygon(g: u32, size: vec2<u32>) -> Polygon {
    if g >= word(H_TRIANGLES) {
        var none: Polygon;
        none.n = 0u;
        return none;
    }
    return polygon(g, size);
}

// Per triangle: a small one walks its rectangle; a large one is listed in step 1 (and
// left to `large` in both steps).
@compute @workgroup_size(64)
fn raster(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let step = step_of(wg, groups);
    if step.idle {
        return;
    }
    let size = textureDimensions(entry);
    let g = group_index(wg, groups) * GROUP + li;
    let poly = thread_polygon(g, size);
    let texels = rect_texels(poly);
    if texels == 0u {
        return;
    }
    if texels > LARGE_PIXELS {
        if !step.id_step {
            let at = large_at(size);
            let i = atomicAdd(&prepass_words[at], 1u);
            atomicStore(&prepass_words[at + 1u + i], g);
        }
        return;
    }
    for (var y = poly.lo.y; y <= poly.hi.y; y++) {
        for (var x = poly.lo.x; x <= poly.hi.x; x++) {
            offer(poly, g, vec2(x, y), size, step.id_step);
        }
    }
}

// One thread: the large triangles' grids for both steps (at most 65,535 workgroups a
// dimension; one layer, then two).
@compute @workgroup_size(1)
fn large_args() {
    let n = atomicLoad(&prepass_words[large_at(textureDimensions(entry))]);
    let x = min(n, 65535u);
    let y = select(0u, (n + x - 1u) / max(x, 1u), n > 0u);
    prepass_dispatch = array(x, y, 1u, x, y, 2u);
}

// A large triangle's workgroup: its threads stride over its rectangle.
fn large_triangle(wg: vec3<u32>, groups: vec3<u32>) -> u32 {
    let i = group_index(wg, groups);
    let at = large_at(textureDimensions(entry));
    if i >= atomicLoad(&prepass_words[at]) {
        return 0xffffffffu;
    }
    return atomicLoad(&prepass_words[at + 1u + i]);
}

@compute @workgroup_size(64)
fn large(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let step = step_of(wg, groups);
    if step.idle {
        return;
    }
    let g = large_triangle(wg, groups);
    if g == 0xffffffffu {
        return;
    }
    let size = textureDimensions(entry);
    let poly = polygon(g, size);
    let w = u32(poly.hi.x - poly.lo.x) + 1u;
    for (var i = li; i < rect_texels(poly); i += GROUP) {
        offer(poly, g, poly.lo + vec2(i32(i % w), i32(i / w)), size, step.id_step);
    }
}

// The entry of a texel that front-facing triangle `g` won: where the texel-centre ray
// meets the triangle's plane, exactly on the ray in the instance's object space as the
// filter casts it (the point the rasterizer interpolates, without its snapping; a
// triangle the near plane clipped has the same plane).
fn entry_of(g: u32, t: vec2<i32>, size: vec2<u32>) -> vec4<f32> {
    let r = RUNS_AT + 4u * run_of(g);
    let k = word(r + 3u) & ~BACK_FACES;
    let inst = instances[k];
    let first = word(r + 1u) + 3u * (g - word(r));
    let base = bitcast<i32>(word(r + 2u));
    let a = proxy_vertices[u32(i32(proxy_indices[first]) + base)].xyz;
    let b = proxy_vertices[u32(i32(proxy_indices[first + 1u]) + base)].xyz;
    let c = proxy_vertices[u32(i32(proxy_indices[first + 2u]) + base)].xyz;
    // The texel's centre on the full screen (`entry` may be a fraction of it).
    let centre = (vec2<f32>(t) + 0.5) * frame.screen.xy / vec2<f32>(size);
    let ray = object_ray(inst, centre, pixel_ray(centre));
    let n = cross(b - a, c - a);
    let s = dot(n, a - ray.o) / dot(n, ray.d);
    // The ray meets the triangle between its corners' parameters on the ray. A face seen
    // nearly edge-on puts the plane point anywhere: there the nearest corner's parameter,
    // which is never beyond the true entry (a late start could skip a voxel; an early one
    // only costs steps), and never behind the camera.
    let dd = dot(ray.d, ray.d);
    let sa = dot(a - ray.o, ray.d) / dd;
    let sb = dot(b - ray.o, ray.d) / dd;
    let sc = dot(c - ray.o, ray.d) / dd;
    let lo = min(sa, min(sb, sc));
    let hi = max(sa, max(sb, sc));
    let start = max(select(lo, s, s >= lo && s <= hi), 0.0);
    return vec4(ray.o + start * ray.d, f32(k + 1u));
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(entry);
    if any(gid.xy >= size) {
        return;
    }
    let t = vec2<i32>(gid.xy);
    let at = texel_word(t, size);
    var out = vec4(0.0);
    let id = atomicLoad(&prepass_words[at + 1u]);
    if atomicLoad(&prepass_words[at]) != 0u && id != 0u {
        let key = ~id;
        let g = key & ~BACK_FACES;
        if (key & BACK_FACES) != 0u {
            // A back face is nearest only where the ray starts inside the proxy (or its
            // front face was clipped): the march starts at the camera.
            let k = word(RUNS_AT + 4u * run_of(g) + 3u) & ~BACK_FACES;
            out = vec4(instances[k].camera_object.xyz, f32(k + 1u));
        } else {
            out = entry_of(g, t, size);
        }
    } else {
        let fill = word(H_FILL);
        if fill != 0u {
            out = vec4(instances[fill - 1u].camera_object.xyz, f32(fill));
        }
    }
    textureStore(entry, t, out);
}
