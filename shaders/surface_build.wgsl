//#include "voxel_codes.inc.wgsl"
//#include "runs.inc.wgsl"
// The RastaVox build on the GPU (surface_build.rs drives it): surface
// extraction with an atomic output slot, then per LOD the OR-merge of runs of children.
// The sort between them is gpu_radix_sort.wgsl, the run starts come from gpu_scan.wgsl.
//
// Keys are 48-bit Morton codes of a voxel's cell at its level in (key_lo, key_hi bits
// 0..16); bits 24..30 of key_hi carry the voxel's face mask through the sort. A surface
// voxel is x | y << 8 | z << 16 | mask << 24 in its chunk (ssbvb_voxel::surface), its
// attributes two words: linear RGBA8 colour, 16-bit octahedral normal.

struct BuildParams {
    // Entries of the input (points for `extract`, voxels of level k otherwise).
    n: u32,
    // Grid level of the points (the finest surface level).
    level: u32,
    // log2 of the chunk edge at the finest level.
    chunk_log2: u32,
    // LOD of the input (0 = finest).
    k: u32,
    // Runs of level k (`merge`), or chunks (`chunk_bounds`).
    count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: BuildParams;
// The asset's point cloud (ssbvb_voxel::asset::PackedVoxel: xy, z | normal << 16, colour, uv).
@group(0) @binding(1) var<storage, read> points: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> key_lo: array<u32>;
@group(0) @binding(3) var<storage, read_write> key_hi: array<u32>;
// Point index per key (extraction), then run starts (merge).
@group(0) @binding(4) var<storage, read_write> val: array<u32>;
@group(0) @binding(5) var<storage, read_write> next_lo: array<u32>;
@group(0) @binding(6) var<storage, read_write> next_hi: array<u32>;
@group(0) @binding(7) var<storage, read_write> flags: array<u32>;
// [0]: output slot counter; `chunk_bounds`: 6 per chunk from [1]; `chunk_starts`: [0] the
// slot counter of the starts written to `flags`.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read> surface_in: array<u32>;
@group(0) @binding(10) var<storage, read> attrs_in: array<u32>;
@group(0) @binding(11) var<storage, read_write> surface_out: array<u32>;
@group(0) @binding(12) var<storage, read_write> attrs_out: array<u32>;

fn point_cell(p: vec4<u32>) -> vec3<u32> {
    return vec3(p.x & 0xffffu, p.x >> 16u, p.y & 0xffffu);
}

// Morton order without codes: the axis whose coordinates differ in the highest bit decides
// (ties to the higher axis, whose bit sits higher in the code).
fn morton_less(a: vec3<u32>, b: vec3<u32>) -> bool {
    let x = a ^ b;
    var axis = 0u;
    var top = firstLeadingBit(x.x);
    for (var i = 1u; i < 3u; i++) {
        let t = firstLeadingBit(x[i]);
        if x[i] != 0u && (x[axis] == 0u || t >= top) {
            axis = i;
            top = t;
        }
    }
    return a[axis] < b[axis];
}

// Whether `c` is a voxel of the (Morton-sorted) point cloud: binary search.
fn is_voxel(c: vec3<u32>) -> bool {
    var lo = 0u;
    var hi = params.n;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        let m = point_cell(points[mid]);
        if all(m == c) {
            return true;
        }
        if morton_less(m, c) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return false;
}

@compute @workgroup_size(256)
fn extract(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.n {
        return;
    }
    let c = point_cell(points[i]);
    let last = (1u << params.level) - 1u;
    var mask = 0u;
    for (var a = 0u; a < 3u; a++) {
        var lo = c;
        lo[a] -= 1u;
        if c[a] == 0u || !is_voxel(lo) {
            mask |= 1u << a;
        }
        var hi = c;
        hi[a] += 1u;
        if c[a] == last || !is_voxel(hi) {
            mask |= 8u << a;
        }
    }
    if mask == 0u {
        return;
    }
    let slot = atomicAdd(&counters[0], 1u);
    let key = morton(c);
    key_lo[slot] = key.x;
    key_hi[slot] = key.y | (mask << 24u);
    val[slot] = i;
}

@compute @workgroup_size(256)
fn gather_finest(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.n {
        return;
    }
    let p = points[val[i]];
    let local = point_cell(p) & vec3((1u << params.chunk_log2) - 1u);
    let mask = (key_hi[i] >> 24u) & 63u;
    surface_out[i] = local.x | (local.y << 8u) | (local.z << 16u) | (mask << 24u);
    attrs_out[2u * i] = p.z;
    attrs_out[2u * i + 1u] = p.y >> 16u;
}

// Key of `i` shifted right by 3·s bits (mask bits dropped).
fn shifted(i: u32, s: u32) -> vec2<u32> {
    return shift_key(key_lo[i], key_hi[i] & 0xffffffu, 3u * s);
}

fn starts_run(i: u32) -> bool {
    return i == 0u || any(shifted(i, 1u) != shifted(i - 1u, 1u));
}

fn store_run_start(run: u32, i: u32) {
    val[run] = i;
}

fn octahedral_l1(code: u32) -> vec3<f32> {
    let unit = decode_octahedral(code);
    return unit / (abs(unit.x) + abs(unit.y) + abs(unit.z));
}

// One thread per run of level k: the parent voxel of level k + 1.
@compute @workgroup_size(256)
fn merge(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let r = thread_id(li, wg, nwg);
    if r >= params.count {
        return;
    }
    let run = run_range(r);
    var rgba = vec4(0u);
    var normal = vec3(0.0);
    for (var j = run.x; j < run.y; j++) {
        let c = attrs_in[2u * j];
        rgba += vec4(c & 0xffu, (c >> 8u) & 0xffu, (c >> 16u) & 0xffu, c >> 24u);
        normal += octahedral_l1(attrs_in[2u * j + 1u]);
    }
    let count = run.y - run.x;
    let avg = (rgba + vec4(count / 2u)) / count;
    let mask = run_mask(run);
    let child = surface_in[run.x];
    let pos = vec3(child & 0xffu, (child >> 8u) & 0xffu, (child >> 16u) & 0xffu) >> vec3(1u);
    surface_out[r] = pos.x | (pos.y << 8u) | (pos.z << 16u) | (mask << 24u);
    attrs_out[2u * r] = avg.x | (avg.y << 8u) | (avg.z << 16u) | (avg.w << 24u);
    attrs_out[2u * r + 1u] = encode_octahedral(normal);
}

// The parents' keys of `merge`'s runs, with their child masks in the high key's top byte
// (a kernel of its own: with `merge` it would bind 9 storage buffers, WebGPU allows 8).
@compute @workgroup_size(256)
fn merge_keys(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let r = thread_id(li, wg, nwg);
    if r >= params.count {
        return;
    }
    let run = run_range(r);
    let parent = shifted(run.x, 1u);
    next_lo[r] = parent.x;
    next_hi[r] = parent.y | (run_mask(run) << 24u);
}

// Run `r`'s first and one-past-last voxel.
fn run_range(r: u32) -> vec2<u32> {
    var end = params.n;
    if r + 1u < params.count {
        end = val[r + 1u];
    }
    return vec2(val[r], end);
}

// The union of a run's child masks.
fn run_mask(run: vec2<u32>) -> u32 {
    var mask = 0u;
    for (var j = run.x; j < run.y; j++) {
        mask |= (surface_in[j] >> 24u) & 63u;
    }
    return mask;
}

// The first voxel of each chunk at level k (unordered; the host sorts them): a voxel whose
// chunk (key >> 3·(chunk_log2 − k)) differs from its predecessor's.
@compute @workgroup_size(256)
fn chunk_starts(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.n {
        return;
    }
    let s = params.chunk_log2 - params.k;
    if i == 0u || any(shifted(i, s) != shifted(i - 1u, s)) {
        flags[atomicAdd(&counters[0], 1u)] = i;
    }
}

// Tight bounds of each chunk's finest voxels in chunk-local cells (min, max + 1; the host
// adds the chunk origin), by atomics: the chunk of voxel i is found by binary search in the
// sorted chunk starts (`val[0..count]`); `surface_in` is the finest level.
@compute @workgroup_size(256)
fn chunk_bounds(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.n {
        return;
    }
    var lo = 0u;
    var hi = params.count;
    // The last start <= i.
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if val[mid] <= i {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let v = surface_in[i];
    let c = vec3(v & 0xffu, (v >> 8u) & 0xffu, (v >> 16u) & 0xffu);
    for (var a = 0u; a < 3u; a++) {
        atomicMin(&counters[1u + 6u * lo + a], c[a]);
        atomicMax(&counters[1u + 6u * lo + 3u + a], c[a] + 1u);
    }
}
