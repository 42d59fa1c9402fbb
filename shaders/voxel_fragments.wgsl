//#include "voxel_codes.inc.wgsl"
//#include "runs.inc.wgsl"
// The voxel fragment list of gpu_voxelize.wgsl turned into voxels (gpu_voxelize.rs): the
// keys are copied out and radix-sorted (gpu_radix_sort.wgsl) with the fragment index as
// payload, runs of equal keys are found by a scan (gpu_scan.wgsl), and one thread per run
// averages its fragments' colours and normals into one voxel.

struct MergeParams {
    // Fragments.
    n: u32,
    // Runs (voxels), for `merge`.
    runs: u32,
}

struct Fragment {
    key_lo: u32,
    key_hi: u32,
    color: u32,
    normal: u32,
}

@group(0) @binding(0) var<uniform> params: MergeParams;
@group(0) @binding(1) var<storage, read> fragments: array<Fragment>;
@group(0) @binding(2) var<storage, read_write> key_lo: array<u32>;
@group(0) @binding(3) var<storage, read_write> key_hi: array<u32>;
@group(0) @binding(4) var<storage, read_write> val: array<u32>;
@group(0) @binding(5) var<storage, read_write> flags: array<u32>;
@group(0) @binding(6) var<storage, read_write> starts: array<u32>;
// Per voxel: Morton key (low and high words), mean linear RGBA, unit normal: the layout
// gpu_lod_build.wgsl reads, so the voxels never leave the GPU on the way to the renderer.
@group(0) @binding(7) var<storage, read_write> out_lo: array<u32>;
@group(0) @binding(8) var<storage, read_write> out_hi: array<u32>;
@group(0) @binding(9) var<storage, read_write> out_colors: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> out_normals: array<vec4<f32>>;

@compute @workgroup_size(256)
fn fragment_keys(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = thread_id(li, wg, nwg);
    if i < params.n {
        key_lo[i] = fragments[i].key_lo;
        key_hi[i] = fragments[i].key_hi;
        val[i] = i;
    }
}

fn starts_run(i: u32) -> bool {
    return i == 0u || key_lo[i] != key_lo[i - 1u] || key_hi[i] != key_hi[i - 1u];
}

fn store_run_start(run: u32, i: u32) {
    starts[run] = i;
}

@compute @workgroup_size(256)
fn merge(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let r = thread_id(li, wg, nwg);
    if r >= params.runs {
        return;
    }
    let start = starts[r];
    var end = params.n;
    if r + 1u < params.runs {
        end = starts[r + 1u];
    }
    var color = vec4(0.0);
    var normal = vec3(0.0);
    for (var j = start; j < end; j++) {
        let f = fragments[val[j]];
        color += unpack4x8unorm(f.color);
        normal += decode_octahedral(f.normal);
    }
    // The run's key from its first fragment (the sorted keys are the fragments'; reading
    // them here would make `merge` bind 9 storage buffers, WebGPU allows 8).
    let first = fragments[val[start]];
    out_lo[r] = first.key_lo;
    out_hi[r] = first.key_hi;
    out_colors[r] = color / f32(end - start);
    let len = length(normal);
    out_normals[r] = vec4(select(vec3(0.0, 0.0, 1.0), normal / len, len > 0.0), 0.0);
}
