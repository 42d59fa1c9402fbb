//#include "common.inc.wgsl"

// ray_march_gbuffer: the filter's march with each pixel's hit written straight into the
// G-buffer (RayMarchGBuffer; docs/architecture.md, "A frame"). The SSBVB frame of
// `ssbvb_pixel.ron` without the SSBVB: there the filter appends every pixel's hit and
// SplatBillboards(mode: Pixel) writes each at its pixel; here the fragment shader that
// marches a pixel writes it, with the same values (the same march, filter_march.inc.wgsl,
// and the same fragment as that resolve's `pixel_fragment`).
//
// 1. `mark_tiles` (compute, one thread per texel of `entry`) flags the 16 × 16 tiles in
//    which the prepass drew some proxy, after the counters in `filter_words`.
// 2. The pass copies the flags into a vertex buffer; `vs_main` draws two triangles per
//    flagged tile (an unflagged one collapses to a point off the screen): a software
//    adapter runs a fragment shader over every pixel it covers, and most tiles have no
//    proxy (docs/benchmarks.md, "The filter over tiles with a proxy").
// 3. `fs_main` marches its pixel and writes the hit's G-buffer with its depth, tested
//    against what is there (the triangles); a pixel without a hit is discarded.
//
// A fragment shader cannot see group 0's page feedback (compute only), and WebGPU refuses
// a draw or dispatch whose bind groups hold two writable bindings of one buffer (whatever
// their stages). So under a GPU budget the fragment shader sets the bits in the pass's own
// feedback buffer (group 1, binding 2), and 4. `merge_feedback` (compute) ORs them into
// the scene's (group 0, binding 3).

override MAX_STEPS: u32 = 1024u;
override FAST_MARCH: bool = false;
// As RayMarchFilter's (ray_march_gbuffer.rs, `Variant`).
override PAGED: bool = true;
override SEVERAL_INSTANCES: bool = true;
override COUNT_WORK: bool = true;
// The word of `filter_words` counting the pixels written (with COUNT_WORK), after the
// counters; then the tile flags.
override HITS_AT: u32 = 0u;
override FLAGS_AT: u32 = 1u;

// Pixels per side of a tile (`mark_tiles`'s workgroup).
const TILE_PX: u32 = 16u;

// Output of the prepass: object-space entry point (xyz), instance index + 1 (w); the
// screen's size (the pipeline check).
@group(1) @binding(0) var entry: texture_2d<f32>;
// The frame's counters (filter_march.inc.wgsl), the pixels written, then a flag per tile.
@group(1) @binding(1) var<storage, read_write> filter_words: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read_write> page_feedback: array<atomic<u32>>;
// The scene's page feedback (group 0; `merge_feedback` only).
@group(0) @binding(3) var<storage, read_write> scene_feedback: array<atomic<u32>>;

//#include "filter_march.inc.wgsl"

// Tiles across the prepass.
fn tiles_across() -> u32 {
    return (textureDimensions(entry).x + TILE_PX - 1u) / TILE_PX;
}

// Flags the tile of a texel with a proxy (workgroup = tile).
@compute @workgroup_size(16, 16)
fn mark_tiles(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let size = textureDimensions(entry);
    if any(gid.xy >= size) || !has_proxy(textureLoad(entry, vec2<i32>(gid.xy), 0), visible_count()) {
        return;
    }
    let flag = FLAGS_AT + wg.y * tiles_across() + wg.x;
    // Read first, so that a tile costs one store, not one per texel.
    if atomicLoad(&filter_words[flag]) == 0u {
        atomicStore(&filter_words[flag], 1u);
    }
}

// Six vertices (two triangles) per tile, instance `t` being tile `t` with its flag.
@vertex
fn vs_main(
    @builtin(vertex_index) v: u32,
    @builtin(instance_index) t: u32,
    @location(0) flagged: u32,
) -> @builtin(position) vec4<f32> {
    if flagged == 0u {
        return vec4(2.0, 2.0, 0.0, 1.0);
    }
    return screen_tile_vertex(v, t, tiles_across(), TILE_PX);
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> GBufferDepth {
    reset_counts();
    let marched = march_pixel(vec2<i32>(frag.xy));
    if marched {
        count_ray();
    }
    if !marched || !best.found {
        discard;
    }
    if COUNT_WORK {
        atomicAdd(&filter_words[HITS_AT], 1u);
    }
    // What SplatBillboards(mode: Pixel) writes of the filter's entry (`hit_fragment`).
    let inst = instances[best_inst];
    let voxel = packed_voxel(lod_info(best.lod), best.cell, best.id);
    let dir = pixel_ray(frag.xy);
    let p = dir * best.t;
    var out: GBufferDepth;
    out.albedo = pack4x8unorm(vec4(voxel_color(voxel).rgb, 1.0));
    out.normal = vec4(voxel_normal_world(inst, voxel), 1.0);
    out.position = vec4(p, best.t * dot(dir, frame.cam_forward.xyz));
    out.geometric_normal = oct_encode(face_normal_world(inst, best.face));
    out.depth = ndc_depth(p);
    return out;
}

// ORs the pass's page feedback into the scene's (under a GPU budget, after the draw; both
// buffers hold the same sets of page bits), a word per thread and pass over the grid.
@compute @workgroup_size(64)
fn merge_feedback(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let n = min(arrayLength(&page_feedback), arrayLength(&scene_feedback));
    for (var i = gid.x; i < n; i += groups.x * 64u) {
        let bits = atomicLoad(&page_feedback[i]);
        if bits != 0u {
            atomicOr(&scene_feedback[i], bits);
        }
    }
}
