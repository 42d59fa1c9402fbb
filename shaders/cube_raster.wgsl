//#include "common.inc.wgsl"
//#include "face_raster.inc.wgsl"
// Instanced cube rasterization (baseline): one instanced draw per
// visible instance draws its LOD level's cubes (`cubes`, group 1: one per voxel, or one
// per completely full octree node when merged; ssbvb_voxel::cube_list). No vertex buffer:
// the 18 vertices of a cube come from `vertex_index` — at most three faces of a box can
// face a viewer, one per axis, so each axis gets two triangles on its camera side — and
// the pass starts each draw at vertex 18 × v, so `vertex_index / 18` is the visible
// instance `v` (index into `instances`) and `instance_index` the cube.
//
// Faces follow VoxelSlot.face: 0..2 = -X/-Y/-Z side, 3..5 = +X/+Y/+Z side. Per axis the
// face whose outer side sees the camera (camera position in object space: exact for any
// affine transform, mirrors included) is drawn; when the camera lies between the cube's
// two planes of that axis, neither face sees it and the triangles collapse to a point,
// which the rasterizer drops. Only front faces shade, and coplanar opposite faces of
// adjacent cubes never fight.
//
// Fragment (face_raster.inc.wgsl): the exact ray–plane hit; the voxel shown is the cell
// just inside that plane (half a voxel inward along the normal) at the hit's other two
// coordinates, clamped to the cube — for a merged cube this is the actual surface voxel,
// since every cell of a full node is a voxel. Its colour comes from the LOD's sparse lookup
// and point cloud (group 0). Stencil = STENCIL_VOXEL (set by the pass).

// One cube (ssbvb_voxel::cube_list::Cube, 8 bytes): minimum cell x | y << 16, and
// z | log2(edge in cells) << 16.
struct Cube {
    xy: u32,
    z_size: u32,
}

@group(1) @binding(0) var<storage, read> cubes: array<Cube>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) cube: u32,
    @location(1) @interpolate(flat) face: u32,
    @location(2) @interpolate(flat) visible: u32,
}

fn cube_min(c: Cube) -> vec3<u32> {
    return vec3(c.xy & 0xffffu, c.xy >> 16u, c.z_size & 0xffffu);
}

fn cube_log2_size(c: Cube) -> u32 {
    return (c.z_size >> 16u) & 0x1fu;
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) ci: u32) -> VertexOut {
    let visible = vi / 18u;
    let corner = vi % 18u;
    let a = corner / 6u;
    let inst = instances[visible];
    let c = cubes[ci];
    let size = 1u << cube_log2_size(c);
    let s = cell_size(inst.level);
    let lo = cube_min(c);
    let cam = inst.camera_object.xyz[a];
    let side = cam > f32(lo[a] + size) * s - 1.0;
    let facing = side || cam < f32(lo[a]) * s - 1.0;
    var out: VertexOut;
    out.cube = ci;
    out.face = a + select(0u, 3u, side);
    out.visible = visible;
    if !facing {
        // Degenerate: every vertex of the face at one point, so nothing is rasterized.
        out.clip = vec4(0.0, 0.0, 0.0, 1.0);
        return out;
    }
    // Cell coordinates of the corner: the face's plane on axis a, the quad on the others.
    let q = QUAD[corner % 6u];
    var cell = lo;
    cell[a] += select(0u, size, side);
    cell[(a + 1u) % 3u] += q.x * size;
    cell[(a + 2u) % 3u] += q.y * size;
    let p_obj = vec3<f32>(cell) * s - 1.0;
    out.clip = frame.proj * (inst.object_to_view * vec4(p_obj, 1.0));
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> GBuffer {
    let inst = instances[in.visible];
    let lod = lod_info(inst.lod);
    let c = cubes[in.cube];
    let size = 1u << cube_log2_size(c);
    let a = in.face % 3u;
    let side = in.face >= 3u;
    let s = cell_size(inst.level);
    let lo = cube_min(c);
    let plane_cell = lo[a] + select(0u, size, side);
    let h = face_hit(inst, a, f32(plane_cell) * s - 1.0, in.clip.xy);
    if !face_hit_valid(h) {
        discard;
    }
    // The cell just inside the plane on axis a; the hit's own cell on the other axes,
    // clamped to the cube (the hit may land a rounding error outside the face's edge).
    let hi = vec3<i32>(lo + vec3(size - 1u));
    var cell_i = clamp(vec3<i32>(floor((h.p_obj + 1.0) / s)), vec3<i32>(lo), hi);
    cell_i[a] = i32(plane_cell) - select(0, 1, side);
    let id = lookup_cell(lod, vec3<u32>(cell_i));
    if id == 0u {
        // Cannot happen when the cube list and the lookup come from the same LOD (every
        // cell of a cube is a voxel). Discarding rather than inventing a colour keeps such
        // a mismatch visible as missing coverage in the accuracy tests.
        discard;
    }
    let g = lod.voxel_offset + id - 1u;
    return face_gbuffer(inst, in.face, h, unpack4x8unorm(voxel_color_word(lod, g)).rgb, voxel_normal_bits(lod, g));
}
