//#include "common.inc.wgsl"
//#include "face_raster.inc.wgsl"
// RastaVox: surface voxels rasterized as their masked camera-facing faces
// (rastavox.rs picks, per visible chunk of each instance, the pixel-error LOD and issues
// one instanced draw of that chunk's voxels). No vertex buffer and no geometry shader:
// the draw starts at vertex 18 × d, so `vertex_index / 18` is the draw `d` (its instance,
// LOD grid level and chunk origin in `draws`) and `instance_index` the voxel in the LOD's
// buffer. Per axis the face whose outer side sees the camera is emitted when its bit is in
// the voxel's mask (the paper's back-face culling on the face mask); otherwise its two
// triangles collapse to a point.
//
// The fragment stage is the face rasterizers' (face_raster.inc.wgsl): the exact ray–plane
// hit and the face's normal, the voxel's own colour and normal from the attribute buffer.

// One draw: visible instance, grid level of the LOD, chunk origin in that level's cells.
struct Draw {
    visible: u32,
    level: u32,
    _pad0: u32,
    _pad1: u32,
    origin: vec4<u32>,
}

@group(1) @binding(0) var<storage, read> draws: array<Draw>;
// x | y << 8 | z << 16 | face mask << 24 (ssbvb_voxel::surface::SurfaceVoxel).
@group(1) @binding(1) var<storage, read> surface: array<u32>;
// Per voxel: linear RGBA8 colour, octahedral normal.
@group(1) @binding(2) var<storage, read> attrs: array<u32>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) voxel: u32,
    @location(1) @interpolate(flat) face: u32,
    @location(2) @interpolate(flat) draw: u32,
}

fn surface_voxel_cell(dr: Draw, v: u32) -> vec3<u32> {
    return dr.origin.xyz + vec3(v & 0xffu, (v >> 8u) & 0xffu, (v >> 16u) & 0xffu);
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VertexOut {
    let d = vi / 18u;
    let corner = vi % 18u;
    let a = corner / 6u;
    let dr = draws[d];
    let inst = instances[dr.visible];
    let v = surface[ii];
    let s = cell_size(dr.level);
    let lo = surface_voxel_cell(dr, v);
    let cam = inst.camera_object.xyz[a];
    let side = cam > f32(lo[a] + 1u) * s - 1.0;
    let facing = side || cam < f32(lo[a]) * s - 1.0;
    let face = a + select(0u, 3u, side);
    var out: VertexOut;
    out.voxel = ii;
    out.face = face;
    out.draw = d;
    if !facing || ((v >> 24u) & (1u << face)) == 0u {
        out.clip = vec4(0.0, 0.0, 0.0, 1.0);
        return out;
    }
    let q = QUAD[corner % 6u];
    var cell = lo;
    cell[a] += select(0u, 1u, side);
    cell[(a + 1u) % 3u] += q.x;
    cell[(a + 2u) % 3u] += q.y;
    let p_obj = vec3<f32>(cell) * s - 1.0;
    out.clip = frame.proj * (inst.object_to_view * vec4(p_obj, 1.0));
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> GBuffer {
    let dr = draws[in.draw];
    let inst = instances[dr.visible];
    let a = in.face % 3u;
    let cell = surface_voxel_cell(dr, surface[in.voxel]);
    let plane = cell[a] + select(0u, 1u, in.face >= 3u);
    let h = face_hit(inst, a, f32(plane) * cell_size(dr.level) - 1.0, in.clip.xy);
    if !face_hit_valid(h) {
        discard;
    }
    let albedo = unpack4x8unorm(attrs[2u * in.voxel]).rgb;
    return face_gbuffer(inst, in.face, h, albedo, attrs[2u * in.voxel + 1u]);
}
