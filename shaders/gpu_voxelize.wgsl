//#include "voxel_codes.inc.wgsl"
//#include "voxel_texture.inc.wgsl"
// GPU voxelization by conservative rasterization (voxelize/mod.rs drives it): each
// triangle is rasterized along the dominant axis of its normal into a 2^L × 2^L viewport
// (one pixel per cell column), enlarged so that every pixel whose square it
// touches gets a fragment (Hertel et al.: each edge moved out by the pixel's semi-diagonal
// along its normal, new corners where the moved edges meet; the overshoot at sharp corners
// is clipped against the triangle's 2D bounds in the fragment stage). There is no geometry
// shader in wgpu: the vertex stage pulls the triangle's three corners and computes the
// enlarged corner itself. A fragment appends the cells of its column that the triangle's
// plane crosses inside the pixel (clamped to the triangle's depth range) to the voxel
// fragment list with an atomic slot: key (48-bit Morton code), colour, normal.
//
// Positions are in grid units (cell i spans [i, i + 1]), three corners per triangle, with
// the triangle's corner colours (material colour × vertex colour) beside them.

struct VoxParams {
    triangles: u32,
    level: u32,
    capacity: u32,
    _pad: u32,
}

struct Fragment {
    key_lo: u32,
    key_hi: u32,
    color: u32,
    normal: u32,
}

@group(0) @binding(0) var<uniform> params: VoxParams;
@group(0) @binding(1) var<storage, read> corners: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> corner_colors: array<vec4<f32>>;
// Per corner: u, v, texture index (−1: none), 0; and the textures (voxel_texture.inc.wgsl).
@group(0) @binding(5) var<storage, read> corner_uvs: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> textures: array<u32>;
@group(0) @binding(3) var<storage, read_write> fragments: array<Fragment>;
// [0]: fragments written (may exceed the capacity: the host then reruns with more room).
@group(0) @binding(4) var<storage, read_write> counter: array<atomic<u32>>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) triangle: u32,
}

fn dominant_axis(n: vec3<f32>) -> u32 {
    let m = abs(n);
    if m.x >= m.y && m.x >= m.z {
        return 0u;
    }
    if m.y >= m.z {
        return 1u;
    }
    return 2u;
}

fn corner(t: u32, k: u32) -> vec3<f32> {
    return corners[3u * t + k].xyz;
}

fn normal_of(t: u32) -> vec3<f32> {
    return cross(corner(t, 1u) - corner(t, 0u), corner(t, 2u) - corner(t, 0u));
}

// The corner projected on the two axes after the dominant one.
fn project(p: vec3<f32>, a: u32) -> vec2<f32> {
    return vec2(p[(a + 1u) % 3u], p[(a + 2u) % 3u]);
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    let t = vi / 3u;
    let k = vi % 3u;
    let a = dominant_axis(normal_of(t));
    let q0 = project(corner(t, 0u), a);
    let q1 = project(corner(t, 1u), a);
    let q2 = project(corner(t, 2u), a);
    let area = (q1.x - q0.x) * (q2.y - q0.y) - (q1.y - q0.y) * (q2.x - q0.x);
    let s = select(-1.0, 1.0, area >= 0.0);
    var q = array<vec2<f32>, 3>(q0, q1, q2);
    // Edge lines (homogeneous, interior positive), each moved out by the semi-diagonal.
    var lines: array<vec3<f32>, 3>;
    for (var e = 0u; e < 3u; e++) {
        let p = q[e];
        let r = q[(e + 1u) % 3u];
        var l = s * cross(vec3(p, 1.0), vec3(r, 1.0));
        l.z += 0.5 * (abs(l.x) + abs(l.y));
        lines[e] = l;
    }
    // Corner k lies on edges k − 1 and k.
    let h = cross(lines[(k + 2u) % 3u], lines[k]);
    var out: VertexOut;
    out.triangle = t;
    let n = f32(1u << params.level);
    var p2 = q[k];
    if abs(h.z) > 1e-12 * max(abs(h.x), abs(h.y)) && area != 0.0 {
        p2 = h.xy / h.z;
    }
    out.clip = vec4(p2 / n * 2.0 - 1.0, 0.5, 1.0);
    return out;
}

fn pack_color(c: vec4<f32>) -> u32 {
    return pack4x8unorm(clamp(c, vec4(0.0), vec4(1.0)));
}

// The colour target only gives the rasterizer a viewport; the output is the fragment list.
@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    append_cells(in);
    return vec4(1.0);
}

fn append_cells(in: VertexOut) {
    let t = in.triangle;
    let nrm = normal_of(t);
    let a = dominant_axis(nrm);
    let u = (a + 1u) % 3u;
    let v = (a + 2u) % 3u;
    let n = 1u << params.level;
    let nf = f32(n);
    // The pixel's cell column (framebuffer rows run top down, grid v up).
    let iu = u32(in.clip.x);
    let iv = n - 1u - u32(in.clip.y);
    let p0 = corner(t, 0u);
    let p1 = corner(t, 1u);
    let p2 = corner(t, 2u);
    let lo = min(p0, min(p1, p2));
    let hi = max(p0, max(p1, p2));
    // Clip the enlargement's overshoot: the pixel square must touch the 2D bounds.
    let fu = f32(iu);
    let fv = f32(iv);
    if fu > hi[u] || fu + 1.0 < lo[u] || fv > hi[v] || fv + 1.0 < lo[v] {
        return;
    }
    // The plane's depth over the pixel square, clamped to the triangle's depth range.
    var zmin = lo[a];
    var zmax = hi[a];
    if abs(nrm[a]) > 0.0 {
        var dmin = 1e30;
        var dmax = -1e30;
        for (var c = 0u; c < 4u; c++) {
            let cu = fu + f32(c & 1u);
            let cv = fv + f32(c >> 1u);
            let d = p0[a] - (nrm[u] * (cu - p0[u]) + nrm[v] * (cv - p0[v])) / nrm[a];
            dmin = min(dmin, d);
            dmax = max(dmax, d);
        }
        zmin = max(zmin, dmin);
        zmax = min(zmax, dmax);
    }
    // Closed cells: cell c touches [zmin, zmax] when c ≤ zmax and c + 1 ≥ zmin.
    let first = u32(clamp(ceil(zmin) - 1.0, 0.0, nf - 1.0));
    let last = u32(clamp(floor(zmax), 0.0, nf - 1.0));
    // The corner colours at the pixel centre (2D barycentrics, clamped to the triangle).
    let q0 = project(p0, a);
    let q1 = project(p1, a);
    let q2 = project(p2, a);
    let color = voxel_color_at(t, q0, q1, q2, vec2(fu + 0.5, fv + 0.5));
    let packed_color = pack_color(color);
    let packed_normal = encode_octahedral(nrm);
    for (var c = first; c <= last && c < first + 64u; c++) {
        var cell = vec3(0u);
        cell[a] = c;
        cell[u] = iu;
        cell[v] = iv;
        let slot = atomicAdd(&counter[0], 1u);
        if slot < params.capacity {
            let key = morton(cell);
            fragments[slot] = Fragment(key.x, key.y, packed_color, packed_normal);
        }
    }
}
