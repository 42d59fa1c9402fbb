//#include "voxel_codes.inc.wgsl"
// Region-local updates of a dynamic object's level (level_splice.rs drives it; the plan and
// its CPU twin are ssbvb_voxel::level_splice). New element `e` lies in the last segment
// whose start is ≤ e; a segment is (new start, source start, kind: 0 old / 1 patch, base
// delta), and an old lookup node moved by it gets the delta added to its base.

struct SpliceParams {
    // Outputs to write (words, normal words or nodes).
    count: u32,
    // New element of output 0 (even for normals).
    first: u32,
    // Segments.
    segments: u32,
    // Old element held at word 0 of `old` (even for normals).
    old_first: u32,
    // New elements in all (normal halves past it are written as zero).
    total: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: SpliceParams;
@group(0) @binding(1) var<storage, read> segments: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> old: array<u32>;
@group(0) @binding(3) var<storage, read> patch_words: array<u32>;
@group(0) @binding(4) var<storage, read_write> out: array<u32>;

// (kind, source element, base delta) of new element `e`.
fn source_of(e: u32) -> vec3<u32> {
    // Binary search; segments[0].x is 0 and starts increase.
    var lo = 0u;
    var hi = params.segments;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if segments[mid].x <= e {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let s = segments[lo];
    return vec3(s.z, s.y + (e - s.x), s.w);
}

// 16-bit element `i` of an array of halves, two per word.
fn half_of_old(i: u32) -> u32 {
    return (old[i >> 1u] >> ((i & 1u) * 16u)) & 0xffffu;
}

fn half_of_patch(i: u32) -> u32 {
    return (patch_words[i >> 1u] >> ((i & 1u) * 16u)) & 0xffffu;
}

@compute @workgroup_size(256)
fn splice_colors(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.count {
        return;
    }
    let s = source_of(params.first + i);
    if s.x == 1u {
        out[i] = patch_words[s.y];
    } else {
        out[i] = old[s.y - params.old_first];
    }
}

fn normal_half(e: u32) -> u32 {
    if e >= params.total {
        return 0u;
    }
    let s = source_of(e);
    if s.x == 1u {
        return half_of_patch(s.y);
    }
    return half_of_old(s.y - params.old_first);
}

@compute @workgroup_size(256)
fn splice_normals(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.count {
        return;
    }
    let e = params.first + 2u * i;
    out[i] = normal_half(e) | (normal_half(e + 1u) << 16u);
}

@compute @workgroup_size(256)
fn splice_nodes(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i >= params.count {
        return;
    }
    let e = params.first + i;
    let s = source_of(e);
    if s.x == 1u {
        for (var w = 0u; w < 3u; w++) {
            out[3u * i + w] = patch_words[3u * s.y + w];
        }
    } else {
        let o = 3u * (s.y - params.old_first);
        out[3u * i] = old[o];
        out[3u * i + 1u] = old[o + 1u];
        out[3u * i + 2u] = old[o + 2u] + s.z;
    }
}
