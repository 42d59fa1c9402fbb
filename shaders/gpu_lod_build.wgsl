//#include "voxel_codes.inc.wgsl"
//#include "runs.inc.wgsl"
// The renderer's structures of a voxel set built on the GPU (a level-by-level octree
// build; lod_build.rs drives it): the LOD chain (runs of siblings, `code >> 3`,
// averaged bottom-up) and each level's sparse lookup (ssbvb_voxel::lookup: a 64-ary tree
// built from the leaves up, one node per run of `key >> 6`). Runs are found as everywhere
// here: a flag where the shifted key changes, a scan (gpu_scan.wgsl), the starts scattered.
// Keys are Morton codes (lo, hi words).

struct LodParams {
    // Input entries.
    n: u32,
    // Key bits dropped to find runs (3: siblings, 6: lookup children).
    shift: u32,
    // Runs.
    runs: u32,
    // `add_base`: what is added to the inner nodes' bases.
    offset: u32,
}

@group(0) @binding(0) var<uniform> params: LodParams;
@group(0) @binding(1) var<storage, read_write> key_lo: array<u32>;
@group(0) @binding(2) var<storage, read_write> key_hi: array<u32>;
@group(0) @binding(3) var<storage, read_write> flags: array<u32>;
@group(0) @binding(4) var<storage, read_write> starts: array<u32>;
@group(0) @binding(5) var<storage, read_write> out_lo: array<u32>;
@group(0) @binding(6) var<storage, read_write> out_hi: array<u32>;
// Lookup nodes, 3 words each: mask low, mask high, base.
@group(0) @binding(7) var<storage, read_write> nodes: array<u32>;
@group(0) @binding(8) var<storage, read_write> colors_in: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> normals_in: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> colors_out: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> normals_out: array<vec4<f32>>;
// The point cloud as the scene's streams hold it: one RGBA8 colour word per voxel (here),
// and 16-bit octahedral normals two per word (`packed_normals`).
@group(0) @binding(12) var<storage, read_write> packed: array<u32>;
@group(0) @binding(13) var<storage, read_write> packed_normals: array<u32>;

fn key_shifted(i: u32, s: u32) -> vec2<u32> {
    return shift_key(key_lo[i], key_hi[i], s);
}

fn starts_run(i: u32) -> bool {
    return i == 0u || any(key_shifted(i, params.shift) != key_shifted(i - 1u, params.shift));
}

fn store_run_start(run: u32, i: u32) {
    starts[run] = i;
}

fn run_end(r: u32) -> u32 {
    if r + 1u < params.runs {
        return starts[r + 1u];
    }
    return params.n;
}

// One lookup node per run of `key >> 6`: the children's bits OR-ed, the first child's
// index as base (add_base later adds the next depth's start for inner nodes).
@compute @workgroup_size(256)
fn lookup_group(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let r = thread_id(li, wg, nwg);
    if r >= params.runs {
        return;
    }
    let start = starts[r];
    var mask = vec2(0u);
    for (var j = start; j < run_end(r); j++) {
        let bit = key_lo[j] & 63u;
        mask[bit / 32u] |= 1u << (bit % 32u);
    }
    let parent = key_shifted(start, 6u);
    out_lo[r] = parent.x;
    out_hi[r] = parent.y;
    nodes[3u * r] = mask.x;
    nodes[3u * r + 1u] = mask.y;
    nodes[3u * r + 2u] = start;
}

@compute @workgroup_size(256)
fn add_base(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i < params.n && (nodes[3u * i] | nodes[3u * i + 1u]) != 0u {
        nodes[3u * i + 2u] += params.offset;
    }
}

// One parent voxel per run of siblings (`code >> 3`), as svo::LevelVoxels::coarsen: mean
// colour; normalized mean normal, where it cancels the direction away from the children's
// centroid in the parent, then the first child's normal.
@compute @workgroup_size(256)
fn coarsen(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let r = thread_id(li, wg, nwg);
    if r >= params.runs {
        return;
    }
    let start = starts[r];
    let end = run_end(r);
    var color = vec4(0.0);
    var normal = vec3(0.0);
    var offset = vec3(0.0);
    for (var j = start; j < end; j++) {
        color += colors_in[j];
        normal += normals_in[j].xyz;
        let c = key_lo[j] & 7u;
        offset += select(vec3(-0.5), vec3(0.5), ((vec3(c) >> vec3(0u, 1u, 2u)) & vec3(1u)) == vec3(1u));
    }
    colors_out[r] = color / f32(end - start);
    var n = normal;
    if !(length(n) > 1e-12) {
        n = -offset;
        if !(length(n) > 1e-12) {
            n = normals_in[start].xyz;
        }
    }
    let len = length(n);
    normals_out[r] = vec4(select(vec3(0.0, 0.0, 1.0), n / len, len > 1e-12), 0.0);
}

// The parents' keys of `coarsen`'s runs (a kernel of its own: with `coarsen` it would bind
// 9 storage buffers, WebGPU allows 8).
@compute @workgroup_size(256)
fn coarsen_keys(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let r = thread_id(li, wg, nwg);
    if r >= params.runs {
        return;
    }
    let parent = key_shifted(starts[r], 3u);
    out_lo[r] = parent.x;
    out_hi[r] = parent.y;
}

// The point cloud's words (ssbvb_voxel::asset::PackedVoxel's colour and normal): thread i
// packs voxel i's colour and, for even i, the normal word of voxels i and i + 1.
@compute @workgroup_size(256)
fn pack_points(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.n {
        return;
    }
    let c = vec4<u32>(clamp(colors_in[i], vec4(0.0), vec4(1.0)) * 255.0 + 0.5);
    packed[i] = c.x | (c.y << 8u) | (c.z << 16u) | (c.w << 24u);
    if i % 2u == 0u {
        var word = encode_octahedral(normals_in[i].xyz);
        if i + 1u < params.n {
            word |= encode_octahedral(normals_in[i + 1u].xyz) << 16u;
        }
        packed_normals[i / 2u] = word;
    }
}
