// The compute form of a ray-casting baseline (the pass parameter `compute`): `cs_main`
// casts each pixel's ray (ray_cast.inc.wgsl's `cast_pixel`, the same code the fragment
// form runs) in 8×8 workgroups and keeps its hit in `cast_hits`; `fs_resolve`, one
// fullscreen triangle, writes the G-buffer of that hit (`gbuffer_of_best`), so both forms
// write the same G-buffer. Why: a GPU whose fragment work is slow (the H200 of
// docs/benchmarks.md) traces the same rays faster in compute.
// Needs ray_cast.inc.wgsl before it; the includer puts `cast_hits` at the binding after
// its others.

// Per pixel (row-major): the hit instance + 1 (0: no hit), the voxel id, the entered face
// and the bits of the hit distance.
@group(1) @binding(10) var<storage, read_write> cast_hits: array<vec4<u32>>;

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = u32(frame.screen.x);
    if gid.x >= w || gid.y >= u32(frame.screen.y) {
        return;
    }
    // The pixel's centre, as the fragment form's `frag.xy`.
    cast_pixel(vec2(f32(gid.x) + 0.5, f32(gid.y) + 0.5));
    var record = vec4(0u);
    if best.hit {
        record = vec4(best_inst + 1u, best.id, best.face, bitcast<u32>(best.t));
    }
    cast_hits[gid.y * w + gid.x] = record;
}

@fragment
fn fs_resolve(@builtin(position) frag: vec4<f32>) -> GBufferDepth {
    let record = cast_hits[u32(frag.y) * u32(frame.screen.x) + u32(frag.x)];
    if record.x == 0u {
        discard;
    }
    best = Hit(true, bitcast<f32>(record.w), record.y, record.z);
    best_inst = record.x - 1u;
    return gbuffer_of_best(pixel_ray(frag.xy));
}
