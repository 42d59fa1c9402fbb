//#include "voxel_codes.inc.wgsl"
//#include "voxel_texture.inc.wgsl"
// Exact GPU voxelization (voxelize/mod.rs, GpuVoxelizeMethod::Exact; needs SHADER_F64): the
// CPU voxelizer's separating-axis test (ssbvb_voxel::voxelize::triangle_box_overlap: closed
// cells, 13 axes, in f64 with the same operations in the same order, each product written
// out so no dot() or cross() builtin can regroup them) on the cells near each triangle's
// plane, appended to the same voxel fragment list as the raster path (voxel_fragments.wgsl
// merges it). Work is balanced by columns: `count_columns` counts the cell columns of each
// triangle's bounds along its dominant axis, a scan (gpu_scan.wgsl) turns the counts into
// offsets, and `exact_columns` runs one thread per column (its triangle found by binary
// search in the offsets). One thread per triangle lost cells on the software adapter for
// triangles spanning hundreds of columns (docs/benchmarks.md), and left the GPU idle
// behind the largest triangle anyway.

struct ExactParams {
    triangles: u32,
    level: u32,
    capacity: u32,
    // Columns of all triangles (`exact_columns`).
    columns: u32,
    // The first column of this submission: `exact_columns` runs in bounded submissions of
    // columns (a GPU driver resets a device whose submission runs for seconds).
    first_column: u32,
    // One past its last column (a chunk's last workgroup runs past it).
    end_column: u32,
    pad1: u32,
    pad2: u32,
}

struct Fragment {
    key_lo: u32,
    key_hi: u32,
    color: u32,
    normal: u32,
}

@group(0) @binding(0) var<uniform> params: ExactParams;
// Nine per triangle: its corners in grid units (cell i spans [i, i + 1]), as the CPU maps them.
@group(0) @binding(1) var<storage, read> verts: array<f64>;
@group(0) @binding(2) var<storage, read> corner_colors: array<vec4<f32>>;
// Per corner: u, v, texture index (−1: none), 0; and the textures (voxel_texture.inc.wgsl).
@group(0) @binding(6) var<storage, read> corner_uvs: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> textures: array<u32>;
@group(0) @binding(3) var<storage, read_write> fragments: array<Fragment>;
@group(0) @binding(4) var<storage, read_write> counter: array<atomic<u32>>;
// Columns per triangle, then (after the scan) the first column of each triangle.
@group(0) @binding(5) var<storage, read_write> column_offsets: array<u32>;

fn vert(t: u32, k: u32) -> vec3<f64> {
    let b = 9u * t + 3u * k;
    return vec3(verts[b], verts[b + 1u], verts[b + 2u]);
}

fn dot3(a: vec3<f64>, b: vec3<f64>) -> f64 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn cross3(a: vec3<f64>, b: vec3<f64>) -> vec3<f64> {
    return vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

fn abs_sum(a: vec3<f64>) -> f64 {
    return abs(a.x) + abs(a.y) + abs(a.z);
}

fn overlap(t0: vec3<f64>, t1: vec3<f64>, t2: vec3<f64>, center: vec3<f64>) -> bool {
    let half = f64(0.5);
    let v0 = t0 - center;
    let v1 = t1 - center;
    let v2 = t2 - center;
    let mn = min(min(v0, v1), v2);
    let mx = max(max(v0, v1), v2);
    if max(max(mn.x, mn.y), mn.z) > half || min(min(mx.x, mx.y), mx.z) < -half {
        return false;
    }
    let edges = array<vec3<f64>, 3>(v1 - v0, v2 - v1, v0 - v2);
    for (var i = 0u; i < 3u; i++) {
        let e = edges[i];
        for (var k = 0u; k < 3u; k++) {
            var axis = vec3(f64(0.0), -e.z, e.y);
            if k == 1u {
                axis = vec3(e.z, f64(0.0), -e.x);
            } else if k == 2u {
                axis = vec3(-e.y, e.x, f64(0.0));
            }
            let p0 = dot3(axis, v0);
            let p1 = dot3(axis, v1);
            let p2 = dot3(axis, v2);
            let r = half * abs_sum(axis);
            if min(min(p0, p1), p2) > r || max(max(p0, p1), p2) < -r {
                return false;
            }
        }
    }
    let n = cross3(v1 - v0, v2 - v0);
    let d = dot3(n, v0);
    let r = half * abs_sum(n);
    return abs(d) <= r;
}

// A triangle's dominant axis and its candidate bounds (cells, f32: exact for indices).
struct TriFrame {
    a: u32,
    u: u32,
    v: u32,
    lo: vec3<u32>,
    hi: vec3<u32>,
}

fn frame_of(p0: vec3<f64>, p1: vec3<f64>, p2: vec3<f64>) -> TriFrame {
    let m = abs(vec3<f32>(cross3(p1 - p0, p2 - p0)));
    var a = 2u;
    if m.x >= m.y && m.x >= m.z {
        a = 0u;
    } else if m.y >= m.z {
        a = 1u;
    }
    // Widened by a cell (the f64 test decides).
    let lastf = f32((1u << params.level) - 1u);
    let bmin = vec3<f32>(min(min(p0, p1), p2));
    let bmax = vec3<f32>(max(max(p0, p1), p2));
    let lo = vec3<u32>(clamp(floor(bmin) - 1.0, vec3(0.0), vec3(lastf)));
    let hi = vec3<u32>(clamp(floor(bmax) + 1.0, vec3(0.0), vec3(lastf)));
    return TriFrame(a, (a + 1u) % 3u, (a + 2u) % 3u, lo, hi);
}

@compute @workgroup_size(256)
fn count_columns(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let t = thread_id(li, wg, nwg);
    if t >= params.triangles {
        return;
    }
    let f = frame_of(vert(t, 0u), vert(t, 1u), vert(t, 2u));
    column_offsets[t] = (f.hi[f.u] - f.lo[f.u] + 1u) * (f.hi[f.v] - f.lo[f.v] + 1u);
}

@compute @workgroup_size(256)
fn exact_columns(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let i = params.first_column + thread_id(li, wg, nwg);
    if i >= params.columns || i >= params.end_column {
        return;
    }
    // The triangle: the last whose first column is at or before i.
    var lo_t = 0u;
    var hi_t = params.triangles;
    while hi_t - lo_t > 1u {
        let mid = (lo_t + hi_t) / 2u;
        if column_offsets[mid] <= i {
            lo_t = mid;
        } else {
            hi_t = mid;
        }
    }
    let t = lo_t;
    let p0 = vert(t, 0u);
    let p1 = vert(t, 1u);
    let p2 = vert(t, 2u);
    let f = frame_of(p0, p1, p2);
    let a = f.a;
    let u = f.u;
    let v = f.v;
    let local = i - column_offsets[t];
    let rows = f.hi[v] - f.lo[v] + 1u;
    let cu = f.lo[u] + local / rows;
    let cv = f.lo[v] + local % rows;
    let nd = cross3(p1 - p0, p2 - p0);
    let nrm = vec3<f32>(nd);
    // The cells the plane can reach over the column's square, a cell of margin either way.
    var first = f.lo[a];
    var last_c = f.hi[a];
    let pf = vec3<f32>(p0);
    if abs(nrm[a]) > 1e-6 * max(abs(nrm[u]), abs(nrm[v])) {
        var dmin = 1e30;
        var dmax = -1e30;
        for (var k = 0u; k < 4u; k++) {
            let xu = f32(cu + (k & 1u));
            let xv = f32(cv + (k >> 1u));
            let d = pf[a] - (nrm[u] * (xu - pf[u]) + nrm[v] * (xv - pf[v])) / nrm[a];
            dmin = min(dmin, d);
            dmax = max(dmax, d);
        }
        first = u32(clamp(floor(dmin) - 1.0, f32(f.lo[a]), f32(f.hi[a])));
        last_c = u32(clamp(floor(dmax) + 1.0, f32(f.lo[a]), f32(f.hi[a])));
    }
    // Corner colours at the column centre (2D barycentrics, clamped to the triangle), as
    // the raster path.
    let q0 = vec2(f32(p0[u]), f32(p0[v]));
    let q1 = vec2(f32(p1[u]), f32(p1[v]));
    let q2 = vec2(f32(p2[u]), f32(p2[v]));
    let color = voxel_color_at(t, q0, q1, q2, vec2(f32(cu) + 0.5, f32(cv) + 0.5));
    let packed_color = pack4x8unorm(clamp(color, vec4(0.0), vec4(1.0)));
    let packed_normal = encode_octahedral(nrm);
    for (var cw = first; cw <= last_c; cw++) {
        var cell = vec3(0u);
        cell[a] = cw;
        cell[u] = cu;
        cell[v] = cv;
        let center = vec3<f64>(vec3<f32>(cell)) + vec3(f64(0.5));
        if !overlap(p0, p1, p2, center) {
            continue;
        }
        let slot = atomicAdd(&counter[0], 1u);
        if slot < params.capacity {
            let key = morton(cell);
            fragments[slot] = Fragment(key.x, key.y, packed_color, packed_normal);
        }
    }
}
