//#include "common.inc.wgsl"

// ray_march_filter: the voxel filter (docs/architecture.md, "A frame", step 2).
//
// One thread per pixel. From the empty-space prepass's entry point it marches the sparse
// lookup of the pixel's instance with a hierarchical voxel DDA to the first voxel, and
// appends that voxel to the SSBVB (`ssbvb`), counting hits into the indirect draw
// (`billboard_draw`): hits are compacted, so exactly one billboard per covered pixel is
// drawn and the count never exceeds the pixel count.
//
// The march itself (the rules it follows, and the code) is in sparse_march.inc.wgsl.
//
// # Several instances
//
// The prepass names the instance whose proxy is nearest, but a later instance can hold a
// nearer voxel (overlapping boxes, or a ray that crosses a proxy without hitting a voxel).
// When more than one instance is visible, every other instance's box is tested and those
// whose box entry is nearer than the best hit so far are marched up to it: O(instances)
// box tests per covered pixel. Exact ties go to the lower instance index (as the
// reference).

// The indirect draw of the billboard pass (wgpu's DrawIndirectArgs).
struct DrawArgs {
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
}

// Most DDA steps per ray and instance (the pass parameter `max_steps`).
override MAX_STEPS: u32 = 1024u;
// `RayMarchFilter(unique_voxels: true)`: each voxel is appended once per frame.
override UNIQUE_VOXELS: bool = false;

// Output of the prepass: object-space entry point (xyz), instance index + 1 (w).
@group(1) @binding(0) var entry: texture_2d<f32>;
// Compacted hits: entries 0 .. billboard_draw.instance_count are valid.
@group(1) @binding(1) var<storage, read_write> ssbvb: array<VoxelSlot>;
@group(1) @binding(2) var<storage, read_write> billboard_draw: DrawArgs;
// Pass-private (UNIQUE_VOXELS): one bit per voxel of each visible instance's level,
// cleared every frame; instance k's bits start at word `claim_offsets[k]`.
@group(1) @binding(3) var<storage, read_write> claimed_voxels: array<atomic<u32>>;
@group(1) @binding(4) var<storage, read> claim_offsets: array<u32>;

//#include "sparse_march.inc.wgsl"

fn start_time(k: u32, e: vec4<f32>, px: vec2<i32>, size: vec2<i32>, dir: vec3<f32>, r: Ray) -> f32 {
    let inst = instances[k];
    if (inst.flags & 1u) != 0u {
        return 0.0;
    }
    let o = inst.camera_object.xyz;
    let d = (inst.world_to_object * vec4(dir, 0.0)).xyz;
    let dd = dot(d, d);
    if !(dd > 0.0) {
        return 0.0;
    }
    let tp = dot(e.xyz - o, d) / dd;
    var slope = -1.0;
    var offsets = array(vec2(1, 0), vec2(-1, 0), vec2(0, 1), vec2(0, -1));
    for (var i = 0u; i < 4u; i++) {
        let q = px + offsets[i];
        if all(q >= vec2(0)) && all(q < size) {
            let en = textureLoad(entry, q, 0);
            if en.w == e.w {
                slope = max(slope, abs(dot(en.xyz - o, d) / dd - tp));
            }
        }
    }
    if slope < 0.0 {
        return 0.0;
    }
    let margin = r.s * inverseSqrt(dd) + slope * 0.125 + abs(tp) * 1e-5;
    let t = tp - margin;
    return select(0.0, t, t > 0.0);
}

@compute @workgroup_size(1)
fn clear_draw() {
    // Six vertices per billboard quad; the filter counts the instances.
    billboard_draw.vertex_count = 6u;
    atomicStore(&billboard_draw.instance_count, 0u);
    billboard_draw.first_vertex = 0u;
    billboard_draw.first_instance = 0u;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = vec2<i32>(textureDimensions(entry));
    let px = vec2<i32>(gid.xy);
    if px.x >= size.x || px.y >= size.y {
        return;
    }
    let e = textureLoad(entry, px, 0);
    let count = u32(max(frame.misc.w, 0.0));
    // w = instance + 1, an exact small integer; NaN or stale values are ignored.
    if !(e.w >= 1.0 && e.w < f32(count) + 0.5) {
        return;
    }
    let k = u32(e.w) - 1u;
    // The filter may run at a fraction of the screen (`entry` declared ScreenScaled): the
    // prepass rasterized this texel's centre, which is this point of the full screen.
    let dir = pixel_ray((vec2<f32>(px) + vec2(0.5)) * frame.screen.xy / vec2<f32>(size));

    let inst = instances[k];
    let lod = lods[inst.lod];
    let r = make_ray(inst, lod.level, dir);
    var best = march(r, lod, start_time(k, e, px, size, dir, r), BIG);
    var best_inst = k;
    if count > 1u {
        for (var j = 0u; j < count; j++) {
            if j == k {
                continue;
            }
            let inst_j = instances[j];
            let lod_j = lods[inst_j.lod];
            let rj = make_ray(inst_j, lod_j.level, dir);
            let limit = best.t;
            if !(max(rj.t_enter, 0.0) <= min(rj.t_exit, limit)) {
                continue;
            }
            let h = march(rj, lod_j, 0.0, limit);
            if h.found && (!best.found || h.t < best.t || (h.t == best.t && j < best_inst)) {
                best = h;
                best_inst = j;
            }
        }
    }
    if !best.found {
        return;
    }
    let hit_lod = lods[instances[best_inst].lod];
    let voxel_id = hit_lod.voxel_offset + best.id;
    if UNIQUE_VOXELS {
        // Each visible instance owns a range of bits (instances of one object share voxel
        // ids but are distinct billboards): the first pixel to set the bit appends.
        let word = claim_offsets[best_inst] + (best.id >> 5u);
        let bit = 1u << (best.id & 31u);
        if (atomicOr(&claimed_voxels[word], bit) & bit) != 0u {
            return;
        }
    }
    let idx = atomicAdd(&billboard_draw.instance_count, 1u);
    // The SSBVB holds one slot per pixel: the guard only matters for smaller buffers
    // (a pipeline may declare ScreenPixelsScaled), whose overflow is dropped.
    if idx < arrayLength(&ssbvb) {
        ssbvb[idx] = VoxelSlot(
            voxels[voxel_id],
            best_inst,
            u32(px.y) * u32(size.x) + u32(px.x),
            best.t,
            best.face,
        );
    }
}
