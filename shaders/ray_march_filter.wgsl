//#include "common.inc.wgsl"

// ray_march_filter: the voxel filter (docs/architecture.md, "A frame", step 2).
//
// One thread per pixel with a proxy. From the empty-space prepass's entry point on, it marches the
// pixel's ray through the sparse lookup of the pixel's instance with a hierarchical voxel
// DDA to the first voxel, and
// appends that voxel to the SSBVB (`ssbvb`), counting hits into the indirect draw
// (`billboard_draw`): hits are compacted, so exactly one billboard per covered pixel is
// drawn and the count never exceeds the pixel count.
//
// The march itself (the rules it follows, and the code) is in sparse_march.inc.wgsl.
//
// # Several instances
//
// The prepass names the instance whose proxy is nearest, but another instance can hold a
// nearer voxel (overlapping boxes, or a ray that crosses a proxy without hitting a voxel).
// After marching the prepass instance, the ray walks the hierarchy over the visible
// instances' boxes (`instance_bvh`), nearer child first, skipping every box it enters
// beyond the best hit so far, and marches the instances of the boxes it reaches up to that
// hit: a pixel's cost follows the instances its ray meets. Exact ties go to the lower
// instance index (as the reference, which walks the same hierarchy).
//
// # Only the tiles with a proxy
//
// `mark_tiles` (one thread per texel) flags the 16 × 16 tiles of `entry` in which the
// prepass drew some proxy, `list_tiles` lists them and makes the list `main`'s indirect
// dispatch, and `main` runs one workgroup per listed tile. A workgroup without a ray costs a software
// adapter what one with rays costs: llvmpipe runs every branch of the shader under a lane
// mask, so its early return skips nothing (docs/benchmarks.md); most of a frame's tiles
// have no proxy.
//
// # Counters
//
// Per frame, for `render --json` and the bench (RayMarchFilter::counters): rays cast,
// march steps, hierarchy boxes tested, instances marched and lookup-node words read
// (64-bit sums), and a histogram of steps per ray for the p99.

// The indirect draw of the billboard pass (wgpu's DrawIndirectArgs).
struct DrawArgs {
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
}

// Most DDA steps per ray and instance (the pass parameter `max_steps`).
override MAX_STEPS: u32 = 1024u;
// `RayMarchFilter(march: Fast)`: the fast march (sparse_march.inc.wgsl).
override FAST_MARCH: bool = false;
// `RayMarchFilter(unique_voxels: true)`: each voxel is appended once per frame.
override UNIQUE_VOXELS: bool = false;
// Chosen per frame (ray_march_filter.rs, `MainVariant`): some LOD has pages (a GPU budget),
// and more than one instance is visible. Off, their code is left out of the pipeline,
// which the software adapter runs faster (docs/benchmarks.md, "The crowd's walk, taken
// apart"); on, it is correct for any scene.
override PAGED: bool = true;
override SEVERAL_INSTANCES: bool = true;
// Count the frame's work into the counters of `filter_words` (off: the pipeline of frames that no report
// reads; the march is the same).
override COUNT_WORK: bool = true;

// Output of the prepass: object-space entry point (xyz), instance index + 1 (w).
@group(1) @binding(0) var entry: texture_2d<f32>;
// Compacted hits: entries 0 .. billboard_draw.instance_count are valid.
@group(1) @binding(1) var<storage, read_write> ssbvb: array<VoxelSlot>;
@group(1) @binding(2) var<storage, read_write> billboard_draw: DrawArgs;
// Pass-private, one buffer (WebGPU allows 8 storage buffers per stage; ray_march_filter.rs,
// `FilterWords`):
// - words 0 .. TILE_AT: the frame's counters (layout below), cleared every counted frame;
// - word TILE_AT: where the tile words start: the count of listed tiles, then a flag per
//   tile of `entry`, then the list (the count and the flags cleared every frame);
// - (UNIQUE_VOXELS) word CLAIM_HEADER: where the claim table starts; CLAIM_HEADER + 1: its
//   size - 1 (a power of two); from CLAIM_HEADER + 2: instance k's first key. The table is
//   the set of (instance, voxel) keys appended this frame, an open-addressing hash table of
//   2 x pixels words or more (cleared every frame), so its memory follows the screen, not
//   the scene. Instance k's keys are its first key + voxel id (NO_DEDUP: its keys do not
//   fit 32 bits; each of its pixels appends).
@group(1) @binding(3) var<storage, read_write> filter_words: array<atomic<u32>>;
override TILE_AT: u32 = 0u;
override CLAIM_HEADER: u32 = 1u;
// `main`'s indirect dispatch, written by `list_tiles` (the only entry point binding it:
// a dispatch may not bind the buffer it reads its arguments from).
@group(1) @binding(4) var<storage, read_write> filter_dispatch: array<u32, 3>;

// Page feedback (sparse_march.inc.wgsl's; only compute shaders see group 0's).
@group(0) @binding(3) var<storage, read_write> page_feedback: array<atomic<u32>>;

//#include "filter_march.inc.wgsl"
//#include "tile_list.inc.wgsl"

// The slot's voxel: `packed_voxel` with the grid level of its cell in `uv` (the billboard
// pass sizes the voxel by it: a voxel of a coarser LOD is larger).
fn slot_voxel(lod: LodInfo, cell: vec3<u32>, id: u32) -> PackedVoxel {
    var v = packed_voxel(lod, cell, id);
    v.uv = lod.level;
    return v;
}

@compute @workgroup_size(1)
fn clear_draw() {
    // A strip of four vertices per billboard (billboards.wgsl); the filter counts the
    // instances.
    billboard_draw.vertex_count = 4u;
    atomicStore(&billboard_draw.instance_count, 0u);
    billboard_draw.first_vertex = 0u;
    billboard_draw.first_instance = 0u;
}

const NO_DEDUP: u32 = 0xffffffffu;
// Probes before a crowded table gives up (then the pixel appends: a duplicate billboard,
// never a hole). At a load factor of at most 1/2 a probe sequence averages under 3.
const MAX_PROBES: u32 = 32u;

// A 32-bit integer mix (lowbias32, Chris Wellons): neighbouring voxel ids land far apart.
fn hash32(v: u32) -> u32 {
    var x = v;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

// Claims `key` (< 2^32 - 1) in the claim table: true for the first claim this frame.
fn claim(key: u32) -> bool {
    let table = atomicLoad(&filter_words[CLAIM_HEADER]);
    let mask = atomicLoad(&filter_words[CLAIM_HEADER + 1u]);
    let stored = key + 1u;
    var h = hash32(key) & mask;
    for (var i = 0u; i < MAX_PROBES; i++) {
        let r = atomicCompareExchangeWeak(&filter_words[table + h], 0u, stored);
        if r.exchanged {
            return true;
        }
        if r.old_value == stored {
            return false;
        }
        // Another key: the next slot. (A weak exchange may fail spuriously with the slot
        // still empty: then the same slot is tried again.)
        if r.old_value != 0u {
            h = (h + 1u) & mask;
        }
    }
    return true;
}

// Filters one pixel; returns whether it cast a ray.
fn filter_pixel(px: vec2<i32>) -> bool {
    if !march_pixel(px) {
        return false;
    }
    if !best.found {
        return true;
    }
    // The voxel's own LOD: the instance's, or a coarser one where a page was not resident.
    let hit_lod = lod_info(best.lod);
    if UNIQUE_VOXELS {
        // Instances of one object share voxel ids but are distinct billboards: each owns a
        // range of keys. The first pixel to claim a key appends. Keys count from the
        // instance's LOD's first voxel: its voxel ids, or (under a budget, where a hit may
        // come from a coarser LOD) every voxel index of the scene (the first keys).
        let base = atomicLoad(&filter_words[CLAIM_HEADER + 2u + best_inst]);
        let key = hit_lod.voxel_offset + best.id - lod_info(instances[best_inst].lod).voxel_offset;
        if base != NO_DEDUP && !claim(base + key) {
            return true;
        }
    }
    let idx = atomicAdd(&billboard_draw.instance_count, 1u);
    // The SSBVB holds one slot per pixel: the guard only matters for smaller buffers
    // (a pipeline may declare ScreenPixelsScaled), whose overflow is dropped.
    if idx < arrayLength(&ssbvb) {
        ssbvb[idx] = VoxelSlot(
            slot_voxel(hit_lod, best.cell, best.id),
            best_inst,
            u32(px.y) * textureDimensions(entry).x + u32(px.x),
            best.t,
            best.face,
        );
    }
    return true;
}


// Flags the tile of a texel with a proxy (workgroup = tile).
@compute @workgroup_size(16, 16)
fn mark_tiles(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let size = textureDimensions(entry);
    if any(gid.xy >= size) || !has_proxy(textureLoad(entry, vec2<i32>(gid.xy), 0), visible_count()) {
        return;
    }
    let flag = atomicLoad(&filter_words[TILE_AT]) + 1u + wg.y * tiles_per_row(size) + wg.x;
    // Read first, so that a tile costs one store, not one per texel.
    if atomicLoad(&filter_words[flag]) == 0u {
        atomicStore(&filter_words[flag], 1u);
    }
}

// tile_list.inc.wgsl's accessors: after the count, a flag per tile, then the list.
fn tile_flagged(tile: u32) -> bool {
    return atomicLoad(&filter_words[atomicLoad(&filter_words[TILE_AT]) + 1u + tile]) != 0u;
}

fn store_listed(i: u32, packed: u32) {
    let at = atomicLoad(&filter_words[TILE_AT]);
    atomicStore(&filter_words[at + 1u + tile_total(textureDimensions(entry)) + i], packed);
}

fn store_listing(count: u32, grid: vec3<u32>) {
    atomicStore(&filter_words[atomicLoad(&filter_words[TILE_AT])], count);
    filter_dispatch = array(grid.x, grid.y, grid.z);
}

// One workgroup: lists the flagged tiles, their count and `main`'s grid.
@compute @workgroup_size(256)
fn list_tiles(@builtin(local_invocation_index) li: u32) {
    list_screen_tiles(li, textureDimensions(entry));
}

@compute @workgroup_size(16, 16)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let at = atomicLoad(&filter_words[TILE_AT]);
    let i = listed_index(wg);
    if i >= atomicLoad(&filter_words[at]) {
        return;
    }
    let n = tile_total(textureDimensions(entry));
    let px = tile_origin(atomicLoad(&filter_words[at + 1u + n + i])) + lid.xy;
    reset_counts();
    if filter_pixel(vec2<i32>(px)) {
        count_ray();
    }
}
