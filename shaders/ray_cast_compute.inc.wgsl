// The compute form of a ray-casting baseline (the pass parameter `compute`): `cs_main`
// casts each pixel's ray (ray_cast.inc.wgsl's `cast_pixel`, the same code the fragment
// form runs) in 16 × 16 workgroups, one per screen tile that some visible instance's box
// may cover (`mark_cast_tiles`, `list_cast_tiles`: tile_list.inc.wgsl), and keeps its hit
// in `cast_hits`; `fs_resolve`, one
// fullscreen triangle, writes the G-buffer of that hit (`gbuffer_of_best`), so both forms
// write the same G-buffer. Why: a GPU whose fragment work is slow (the H200 of
// docs/benchmarks.md) traces the same rays faster in compute.
// Needs ray_cast.inc.wgsl before it; the includer puts `cast_hits` at the binding after
// its others.

//#include "tile_list.inc.wgsl"

// Words 4p .. 4p + 3 for pixel p (row-major): the hit instance + 1 (0: no hit), the voxel
// id, the entered face and the bits of the hit distance. Then the tile words (from
// `tile_words_at`): the count of listed tiles, a flag per 16 × 16 tile of the screen (cleared
// every frame), the list.
@group(1) @binding(10) var<storage, read_write> cast_hits: array<atomic<u32>>;
// `cs_main`'s indirect dispatch, written by `list_cast_tiles` (the only entry point binding
// it: a dispatch may not bind the buffer it reads its arguments from).
@group(1) @binding(11) var<storage, read_write> cast_dispatch: array<u32, 3>;

fn screen_size() -> vec2<u32> {
    return vec2<u32>(frame.screen.xy);
}

fn tile_words_at() -> u32 {
    let s = screen_size();
    return 4u * s.x * s.y;
}

// The tiles (x0, y0, x1, y1, inclusive) holding every pixel whose ray may enter the
// camera-relative box `lo`..`hi`, or none (x0 > x1). A point c = a F + b R + e U (the
// frame's forward, right and up, which are orthogonal) with a > 0 lies on the ray of NDC
// (b / a, e / a), and a box wholly in front of the camera projects inside the hull of its
// corners: their pixel rectangle, widened by two pixels and f32's rounding of the ratios.
// A box reaching to or behind the camera's plane gets every tile; one wholly behind it
// gets none (a ray's points have a > 0).
fn box_tiles(lo: vec3<f32>, hi: vec3<f32>) -> vec4<u32> {
    let size = screen_size();
    let last = vec2(tiles_per_row(size), (size.y + TILE - 1u) / TILE) - 1u;
    let f = frame.cam_forward.xyz;
    let r = frame.cam_right.xyz;
    let u = frame.cam_up.xyz;
    var lo_ndc = vec2(BIG);
    var hi_ndc = vec2(-BIG);
    var in_front = 0u;
    var behind = 0u;
    for (var i = 0u; i < 8u; i++) {
        let c = select(lo, hi, vec3((i & 1u) != 0u, (i & 2u) != 0u, (i & 4u) != 0u));
        let a = dot(c, f) / dot(f, f);
        let ndc = vec2(dot(c, r) / dot(r, r), dot(c, u) / dot(u, u)) / a;
        in_front += u32(a > 1e-6 * length(c) / length(f) && all(abs(ndc) < vec2(1e6)));
        behind += u32(a < 0.0);
        lo_ndc = min(lo_ndc, ndc);
        hi_ndc = max(hi_ndc, ndc);
    }
    if behind == 8u {
        return vec4(1u, 0u, 0u, 0u);
    }
    if in_front < 8u {
        return vec4(vec2(0u), last);
    }
    // Pixel k's centre ray has NDC ((k + 0.5 + jitter) / size) * 2 - 1 (y flipped).
    let wh = vec2<f32>(size);
    let k_lo = (vec2(lo_ndc.x, -hi_ndc.y) + 1.0) * 0.5 * wh - 0.5 - frame.jitter.xy;
    let k_hi = (vec2(hi_ndc.x, -lo_ndc.y) + 1.0) * 0.5 * wh - 0.5 - frame.jitter.xy;
    let slack = 2.0 + (max(abs(lo_ndc), abs(hi_ndc)) + 1.0) * wh * 1e-5;
    let p_lo = k_lo - slack;
    let p_hi = k_hi + slack;
    if any(p_hi < vec2(0.0)) || any(p_lo > wh) {
        return vec4(1u, 0u, 0u, 0u);
    }
    let t_lo = vec2<u32>(max(p_lo, vec2(0.0))) / TILE;
    let t_hi = min(vec2<u32>(min(p_hi, wh)) / TILE, last);
    return vec4(t_lo, t_hi);
}

// Flags the tiles of every visible instance's box (a thread per node of the instance
// hierarchy; its leaves hold the instances' boxes, as the walk tests them).
@compute @workgroup_size(64)
fn mark_cast_tiles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let count = u32(max(frame.shine_near_far_count.w, 0.0));
    if count == 0u || gid.x >= 2u * count - 1u {
        return;
    }
    let node = bvh_node(gid.x);
    if (node.left & BVH_LEAF) == 0u {
        return;
    }
    let rect = box_tiles(node.lo, node.hi);
    let per_row = tiles_per_row(screen_size());
    let flags = tile_words_at() + 1u;
    for (var ty = rect.y; ty <= rect.w && rect.x <= rect.z; ty++) {
        for (var tx = rect.x; tx <= rect.z; tx++) {
            let flag = flags + ty * per_row + tx;
            // Read first: a tile many boxes cover costs one store.
            if atomicLoad(&cast_hits[flag]) == 0u {
                atomicStore(&cast_hits[flag], 1u);
            }
        }
    }
}

// tile_list.inc.wgsl's accessors.
fn tile_flagged(tile: u32) -> bool {
    return atomicLoad(&cast_hits[tile_words_at() + 1u + tile]) != 0u;
}

fn store_listed(i: u32, packed: u32) {
    atomicStore(&cast_hits[tile_words_at() + 1u + tile_total(screen_size()) + i], packed);
}

fn store_listing(count: u32, grid: vec3<u32>) {
    atomicStore(&cast_hits[tile_words_at()], count);
    cast_dispatch = array(grid.x, grid.y, grid.z);
}

// One workgroup: lists the flagged tiles, their count and `cs_main`'s grid.
@compute @workgroup_size(256)
fn list_cast_tiles(@builtin(local_invocation_index) li: u32) {
    list_screen_tiles(li, screen_size());
}

// One workgroup per listed tile.
@compute @workgroup_size(16, 16)
fn cs_main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let size = screen_size();
    let at = tile_words_at();
    let i = listed_index(wg);
    if i >= atomicLoad(&cast_hits[at]) {
        return;
    }
    let p = tile_origin(atomicLoad(&cast_hits[at + 1u + tile_total(size) + i])) + lid.xy;
    if any(p >= size) {
        return;
    }
    // The pixel's centre, as the fragment form's `frag.xy`.
    cast_pixel(vec2(f32(p.x) + 0.5, f32(p.y) + 0.5));
    var record = vec4(0u);
    if best.hit {
        record = vec4(best_inst + 1u, best.id, best.face, bitcast<u32>(best.t));
    }
    let w = 4u * (p.y * size.x + p.x);
    atomicStore(&cast_hits[w], record.x);
    atomicStore(&cast_hits[w + 1u], record.y);
    atomicStore(&cast_hits[w + 2u], record.z);
    atomicStore(&cast_hits[w + 3u], record.w);
}

@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> GBufferDepth {
    // A tile that was not listed holds last frame's hits, or none.
    let p = vec2<u32>(frag.xy);
    let size = screen_size();
    if atomicLoad(&cast_hits[tile_words_at() + 1u + (p.y / TILE) * tiles_per_row(size) + p.x / TILE]) == 0u {
        discard;
    }
    let w = 4u * (p.y * size.x + p.x);
    let record = vec4(
        atomicLoad(&cast_hits[w]),
        atomicLoad(&cast_hits[w + 1u]),
        atomicLoad(&cast_hits[w + 2u]),
        atomicLoad(&cast_hits[w + 3u]),
    );
    if record.x == 0u {
        discard;
    }
    best = Hit(true, bitcast<f32>(record.w), record.y, record.z);
    best_inst = record.x - 1u;
    return gbuffer_of_best(pixel_ray(frag.xy));
}
