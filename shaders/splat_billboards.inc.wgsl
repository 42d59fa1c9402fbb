// What the two forms of the compute splat share (splat_billboards.wgsl: 32-bit atomics,
// two steps; splat_billboards_wide.wgsl: 64-bit atomics, one step): the billboards of the
// SSBVB splatted in compute (Schütz, Kerbl and Wimmer's compute rasterization of point
// clouds), for adapters whose raster units are weak (a CPU adapter; data-centre GPUs such
// as the H100/H200). Same quads and the same pixel shading as billboards.wgsl
// (billboard_quad.inc.wgsl):
//
// 0. Arguments (compute, `args_main`, one thread): the splat dispatches' workgroup
//    counts from the filter's entry count: no workgroup for an empty slot of the SSBVB
//    (one slot per pixel; an empty workgroup still costs its launch, docs/benchmarks.md).
// 1. The splat (compute, `splat_main`, one thread per SSBVB entry): every pixel centre
//    inside the entry's quad (the whole screen for a near-field quad) that the billboard
//    covers is offered the entry and its reversed-Z depth; the nearest depth wins, and at
//    equal depths the lowest entry, as the rasterizer's strict depth test keeps the first
//    of equal-depth quads, drawn in entry order. Non-negative floats order like their
//    bits, so the including file decides with integer atomics (`splat_pixel`).
// 2. `vs_main`/`fs_main` (the resolve, into the G-buffer): a pixel with a winner writes
//    what that billboard's fragment writes, with its depth, depth-tested against the
//    triangles already there; a pixel without one is discarded. The resolve draws only
//    the screen's tiles of TILE_PX² pixels that some quad's pixel range touched (the
//    splat marks them): a pass over the whole screen cost llvmpipe as much as the splat
//    itself, mostly for pixels without a quad (docs/benchmarks.md).
//
// The including file declares the words (`splat_pixels`, cleared to 0 every frame: no
// depth, no entry, no tile touched) and defines how they are read and written:
// `store_plane(e, bits)`, `plane_bits(e)`, `splat_pixel(p, depth_bits, e, step)`,
// `pixel_winner(p)` and `mark_tile(t)`.

// Whether the fragment intersects the pixel's ray with the voxel box (RayBox) or is the
// flat quad (Flat, the paper).
override RAY_BOX: bool = false;
// `mode: Pixel`: no quad; each entry is its own pixel's hit (the filter appended every
// pixel), splatted at that pixel alone and written as the ray casters' resolve writes a
// hit (`pixel_fragment`).
override PIXEL: bool = false;
// Pixels per side of a resolve tile (the pass sets it; its vertex buffer has a word pair
// per tile).
override TILE_PX: u32 = 16u;

@group(1) @binding(0) var<storage, read> ssbvb: array<VoxelSlot>;
// Written by the filter: `instance_count` = the number of valid SSBVB entries.
@group(1) @binding(1) var<storage, read> billboard_draw: array<u32, 4>;
// `args_main`'s output, the splat dispatches' indirect arguments: words 0..3 step 0's
// grid (z = 1), words 3..6 step 1's (z = 2; the one-step splat dispatches only step 0).
// Bound only to `args_main`.
@group(1) @binding(3) var<storage, read_write> splat_dispatch: array<u32, 6>;

// A non-near-field quad's plane has a negative view depth: +0.0's bits mark a near field.
const NEAR_FIELD_WORD: u32 = 0u;

// The quad plane's point under pixel centre `px`: view space (s * -cz, cz), taken to world.
fn quad_point_world(cz: f32, px: vec2<f32>) -> vec3<f32> {
    let s = pixel_slope(px);
    let view3 = mat3x3(frame.view[0].xyz, frame.view[1].xyz, frame.view[2].xyz);
    return transpose(view3) * vec3(s * -cz, cz);
}

// The fragment of entry `slot` at pixel centre `px` (screen pixels).
fn fragment_at(slot: VoxelSlot, q: Quad, px: vec2<f32>) -> Fragment {
    if RAY_BOX {
        return ray_box_fragment(slot, px);
    }
    if q.near_field {
        return flat_fragment(slot, q, px, vec3(0.0));
    }
    var f: Fragment;
    f.covered = false;
    if !quad_covers(q, px) {
        return f;
    }
    return flat_fragment(slot, q, px, quad_point_world(q.cz, px));
}

// The parts of entry `e`'s quad that its fragments read, without rebuilding the quad (a
// CPU adapter runs both sides of a branch: a rebuild on a rare path costs every pixel):
// the plane's depth from step 0, the centre.
fn winner_quad(slot: VoxelSlot, e: u32) -> Quad {
    let cz_bits = plane_bits(e);
    var q: Quad;
    q.valid = true;
    q.near_field = cz_bits == NEAR_FIELD_WORD;
    q.cz = bitcast<f32>(cz_bits);
    q.c = slot_centre_world(instances[slot.instance], slot);
    return q;
}

// The winning entry's fragment at a pixel centre the splat found its quad to cover: as
// `fragment_at` there.
fn winner_fragment(slot: VoxelSlot, q: Quad, px: vec2<f32>) -> Fragment {
    if RAY_BOX {
        return ray_box_fragment(slot, px);
    }
    // A near-field fragment intersects its ray with the box and ignores the plane point.
    return flat_fragment(slot, q, px, quad_point_world(q.cz, px));
}

// Pixels of slack around a quad's pixel bounds: far more than the f32 rounding of the
// slope-to-pixel mapping (about 1e-3 px at 4K), far less than the whole pixel it once was
// (a quad a pixel wide then looped over 16 pixels for 1 to 4 centres; docs/benchmarks.md).
const BOUNDS_SLACK: f32 = 1.0 / 64.0;

// The pixel rectangle (min x, min y, max x, max y; inclusive) whose centres may lie in the
// quad: the screen for a near-field quad or a ray-box fragment's quad... the quad's
// corners otherwise.
fn pixel_bounds(q: Quad) -> vec4<i32> {
    let size = vec2<i32>(frame.screen.xy);
    let all_px = vec4(0, 0, size.x - 1, size.y - 1);
    if q.near_field {
        return all_px;
    }
    let tan_xy = vec2(length(frame.cam_right.xyz), length(frame.cam_up.xyz));
    var lo = vec2(3.0e38);
    var hi = vec2(-3.0e38);
    for (var k = 0u; k < 4u; k++) {
        let uv = vec2(f32(k & 1u), f32(k >> 1u));
        let p = q.mid + (uv * 2.0 - 1.0) * q.half;
        let s = p.x * q.axis + p.y * vec2(-q.axis.y, q.axis.x);
        let ndc = s / tan_xy;
        let pix = vec2((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * frame.screen.xy;
        lo = min(lo, pix);
        hi = max(hi, pix);
    }
    if !(all(lo == lo) && all(hi == hi)) {
        return all_px;
    }
    // Clamped in f32 first: a quad far off screen (slopes of a very narrow lens) must not
    // convert out of i32's range. Pixel x covers centre x + 0.5: the centres in [lo, hi],
    // with BOUNDS_SLACK for the rounding of this mapping (quad_covers decides exactly).
    let sz = frame.screen.xy;
    let lo_c = clamp(lo, vec2(-2.0), sz + 2.0);
    let hi_c = clamp(hi, vec2(-2.0), sz + 2.0);
    let a = clamp(vec2<i32>(ceil(lo_c - 0.5 - BOUNDS_SLACK)), vec2(0), size - 1);
    let b = clamp(vec2<i32>(floor(hi_c - 0.5 + BOUNDS_SLACK)), vec2(-1), size - 1);
    return vec4(a, b);
}

// Entry index of a thread of a dispatch of 64-thread workgroups (every layer covers entries).
fn entry_index(wg: vec3<u32>, nwg: vec3<u32>, li: u32) -> u32 {
    return ((wg.z * nwg.y + wg.y) * nwg.x + wg.x) * 64u + li;
}

// A grid of `layers` layers with at least `groups` workgroups in all, x at most 65535
// (WebGPU's default limit per dimension); no workgroup when `groups` is 0.
fn splat_grid(groups: u32, layers: u32) -> vec3<u32> {
    let per_layer = (groups + layers - 1u) / layers;
    let x = min(per_layer, 65535u);
    let y = select(0u, (per_layer + x - 1u) / x, x > 0u);
    return vec3(x, y, layers);
}

@compute @workgroup_size(1)
fn args_main() {
    let entries = min(billboard_draw[1], arrayLength(&ssbvb));
    let groups = (entries + 63u) / 64u;
    let first = splat_grid(groups, 1u);
    let second = splat_grid(groups, 2u);
    splat_dispatch = array(first.x, first.y, first.z, second.x, second.y, second.z);
}

// Splats entry `e`: step 0 keeps its quad's plane and splats its pixels (the one-step
// splat's only step), step 1 splats them again (`splat_pixel` says what a step does).
fn splat(e: u32, splat_step: u32) {
    if e >= min(billboard_draw[1], arrayLength(&ssbvb)) {
        return;
    }
    let slot = ssbvb[e];
    if PIXEL {
        splat_own_pixel(slot, e, splat_step);
        return;
    }
    let q = billboard_quad(slot);
    if !q.valid {
        return;
    }
    let b = pixel_bounds(q);
    if splat_step == 0u {
        store_plane(e, select(bitcast<u32>(q.cz), NEAR_FIELD_WORD, q.near_field));
        mark_tiles(b);
    }
    let width = u32(frame.screen.x);
    // A near-field quad (rare) intersects each pixel's ray with its box: a loop of its own,
    // so that the flat quads' loop holds only the rectangle test (llvmpipe would run the
    // ray-box test, masked, at every pixel of every quad; docs/benchmarks.md).
    if RAY_BOX || q.near_field {
        for (var y = b.y; y <= b.w; y++) {
            for (var x = b.x; x <= b.z; x++) {
                let f = fragment_at(slot, q, vec2<f32>(f32(x), f32(y)) + 0.5);
                if !f.covered {
                    continue;
                }
                let p = u32(y) * width + u32(x);
                splat_pixel(p, bitcast<u32>(clamp(f.depth, 0.0, 1.0)), e, splat_step);
            }
        }
        return;
    }
    let depth_bits = bitcast<u32>(flat_quad_depth(q));
    for (var y = b.y; y <= b.w; y++) {
        for (var x = b.x; x <= b.z; x++) {
            if quad_covers(q, vec2<f32>(f32(x), f32(y)) + 0.5) {
                splat_pixel(u32(y) * width + u32(x), depth_bits, e, splat_step);
            }
        }
    }
}

// The pixel whose ray found entry `slot` (at the screen's resolution: the pipeline check).
fn own_pixel(slot: VoxelSlot) -> vec2<u32> {
    let width = u32(frame.screen.x);
    return vec2(slot.pixel % width, slot.pixel / width);
}

// A Pixel entry (the filter's, on this screen: the pipeline check): its hit's depth at its
// own pixel, and that pixel's tile marked.
fn splat_own_pixel(slot: VoxelSlot, e: u32, splat_step: u32) {
    let p = own_pixel(slot);
    if splat_step == 0u {
        mark_tile(p.y / TILE_PX * tiles_across() + p.x / TILE_PX);
    }
    let f = pixel_fragment(slot, vec2<f32>(p) + 0.5);
    splat_pixel(slot.pixel, bitcast<u32>(f.depth), e, splat_step);
}

// Tiles across the screen.
fn tiles_across() -> u32 {
    return (u32(frame.screen.x) + TILE_PX - 1u) / TILE_PX;
}

// Marks the tiles that pixel range `b` (min x, min y, max x, max y; inclusive) touches.
fn mark_tiles(b: vec4<i32>) {
    if b.x > b.z || b.y > b.w {
        return;
    }
    let lo = vec2<u32>(b.xy) / TILE_PX;
    let hi = vec2<u32>(b.zw) / TILE_PX;
    let across = tiles_across();
    for (var ty = lo.y; ty <= hi.y; ty++) {
        for (var tx = lo.x; tx <= hi.x; tx++) {
            mark_tile(ty * across + tx);
        }
    }
}

// The resolve's vertices: six per tile (two triangles), instance `t` being tile `t`, whose
// word pair the splat's tile words fill (`seen`, copied into the vertex buffer). A tile no
// quad touched collapses to a point outside the screen: no fragment.
@vertex
fn vs_main(
    @builtin(vertex_index) v: u32,
    @builtin(instance_index) t: u32,
    @location(0) seen: vec2<u32>,
) -> @builtin(position) vec4<f32> {
    if seen.x == 0u {
        return vec4(2.0, 2.0, 0.0, 1.0);
    }
    return screen_tile_vertex(v, t, tiles_across(), TILE_PX);
}

// The splat steps are this one pipeline: a grid of one layer (z = 1) is step 0, one of
// two layers (z = 2) step 1. One compiled shader, so the depth a pixel is compared with in
// the second step is bit for bit the one written in the first (two pipelines could
// contract floating-point operations differently).
@compute @workgroup_size(64)
fn splat_main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    splat(entry_index(wg, nwg, li), nwg.z - 1u);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> GBufferDepth {
    let pix = vec2<u32>(frag.xy);
    let p = pix.y * u32(frame.screen.x) + pix.x;
    let winner = pixel_winner(p);
    if winner.x == 0u {
        discard;
    }
    let e = ~winner.x;
    let slot = ssbvb[e];
    var f: Fragment;
    if PIXEL {
        f = pixel_fragment(slot, frag.xy);
    } else {
        let q = winner_quad(slot, e);
        f = winner_fragment(slot, q, frag.xy);
        if !f.covered {
            // The splat found this pixel covered; a recomputation here (another pipeline)
            // may round a pixel on the box's edge the other way. Never a hole: the voxel's
            // colour and stored normal at its centre.
            var flat_q = q;
            flat_q.near_field = false;
            f = flat_fragment(slot, flat_q, frag.xy, q.c);
        }
    }
    var out: GBufferDepth;
    out.albedo = pack4x8unorm(f.albedo);
    out.normal = f.normal;
    out.position = f.position;
    out.geometric_normal = f.geometric;
    out.depth = bitcast<f32>(winner.y);
    return out;
}
