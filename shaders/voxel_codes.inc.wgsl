// What the GPU build steps share (surface_build, gpu_voxelize, gpu_voxelize_exact,
// gpu_lod_build, voxel_fragments): the thread index of a dispatch split over x and y
// (compute_kernels.rs), 48-bit Morton codes, and the 8-bit octahedral normal code of
// ssbvb_voxel::asset::PackedVoxel.

// Thread `i` of a dispatch of 256-thread workgroups numbered `x + y · num_workgroups.x`.
fn thread_id(li: u32, wg: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return (wg.x + wg.y * nwg.x) * 256u + li;
}

// A 64-bit key (low, high word) shifted right by `s` bits.
fn shift_key(lo: u32, hi: u32, s: u32) -> vec2<u32> {
    if s == 0u {
        return vec2(lo, hi);
    }
    if s >= 32u {
        return vec2(hi >> (s - 32u), 0u);
    }
    return vec2((lo >> s) | (hi << (32u - s)), hi >> s);
}

// Morton code of a cell (16 bits per axis): bits 0..32 and 32..48 (low, high word).
fn morton(c: vec3<u32>) -> vec2<u32> {
    var lo = 0u;
    var hi = 0u;
    for (var j = 0u; j < 16u; j++) {
        for (var a = 0u; a < 3u; a++) {
            let bit = 3u * j + a;
            let b = (c[a] >> j) & 1u;
            if bit < 32u {
                lo |= b << bit;
            } else {
                hi |= b << (bit - 32u);
            }
        }
    }
    return vec2(lo, hi);
}

// Rust's f32::signum for the codes: +1 for +0.
fn sign_nz(x: f32) -> f32 {
    return select(1.0, -1.0, x < 0.0);
}

// The octahedral code (u | v << 8) of a direction; +Z for a zero vector. floor(v + 0.5)
// is Rust's round on these non-negative values (WGSL's round goes half to even).
fn encode_octahedral(n: vec3<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    var p = vec3(0.0, 0.0, 1.0);
    if l1 > 0.0 {
        p = n / l1;
    }
    var x = p.x;
    var y = p.y;
    if p.z < 0.0 {
        x = (1.0 - abs(p.y)) * sign_nz(p.x);
        y = (1.0 - abs(p.x)) * sign_nz(p.y);
    }
    let qx = u32(floor((clamp(x, -1.0, 1.0) * 0.5 + 0.5) * 255.0 + 0.5));
    let qy = u32(floor((clamp(y, -1.0, 1.0) * 0.5 + 0.5) * 255.0 + 0.5));
    return qx | (qy << 8u);
}

// The unit direction of an octahedral code (as ssbvb_voxel's decode).
fn decode_octahedral(code: u32) -> vec3<f32> {
    let u = f32(code & 0xffu) / 255.0 * 2.0 - 1.0;
    let v = f32((code >> 8u) & 0xffu) / 255.0 * 2.0 - 1.0;
    var n = vec3(u, v, 1.0 - abs(u) - abs(v));
    if n.z < 0.0 {
        n = vec3((1.0 - abs(v)) * sign_nz(u), (1.0 - abs(u)) * sign_nz(v), n.z);
    }
    return n / length(n);
}
