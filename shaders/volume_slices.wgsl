//#include "common.inc.wgsl"
// Volumetric billboards (volume_slices.rs): the view-aligned slice triangles of every RGBA
// volume, back to front, pulled from `slice_vertices` and blended premultiplied "over"
// into the pass's accumulation target, depth-tested against the opaque depth; then
// `fs_resolve` lays the sum "over" the output colour. The atlas lookup is
// ssbvb_voxel::rgba_volume::atlas::VolumeAtlas::sample, step for step.

// One placed volume this frame (volume_slices.rs `SliceVolume`).
struct SliceVolume {
    // Camera-relative world -> object space [-1, 1]^3.
    to_object: mat4x4<f32>,
    // The chosen level's texels per axis; w: its first brick in `brick_table`.
    dims: vec4<u32>,
    // The level's bricks per axis.
    bricks: vec4<u32>,
    // x: the level's reference length (world); y: slice spacing along the view axis.
    lengths: vec4<f32>,
}

// Read-only: the opaque depth the slices are tested against (the pipeline's depth test).
@group(1) @binding(0) var depth_stencil: texture_2d<f32>;
@group(1) @binding(1) var atlas: texture_3d<f32>;
@group(1) @binding(2) var atlas_sampler: sampler;
// Per brick of every level of every volume: its slot in the atlas, or EMPTY_BRICK.
@group(1) @binding(3) var<storage, read> brick_table: array<u32>;
@group(1) @binding(4) var<storage, read> slice_volumes: array<SliceVolume>;
// Triangle vertices: camera-relative world position (f32 bits), w: the volume's index.
@group(1) @binding(5) var<storage, read> slice_vertices: array<vec4<u32>>;
// The slices' premultiplied sum (volume_slices.rs), read by the resolve.
@group(1) @binding(6) var accumulated: texture_2d<f32>;

const BRICK: u32 = 8u;
const STORED_BRICK: u32 = 10u;
const EMPTY_BRICK: u32 = 0xffffffffu;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel: vec3<f32>,
    @location(1) @interpolate(flat) volume: u32,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VsOut {
    let v = slice_vertices[vi];
    let p = bitcast<vec3<f32>>(v.xyz);
    var out: VsOut;
    out.rel = p;
    out.volume = v.w;
    out.clip = frame.view_proj * vec4(p, 1.0);
    return out;
}

// Premultiplied RGBA of the volume's level at object-space point p: the brick holding the
// footprint's lower texel, then one trilinear fetch inside its apron.
fn atlas_sample(v: SliceVolume, p: vec3<f32>) -> vec4<f32> {
    let dims = vec3<f32>(v.dims.xyz);
    let u = (p + 1.0) * 0.5 * dims;
    let i0 = floor(u - 0.5);
    if any(i0 < vec3(-1.0)) || any(i0 > dims - 1.0) {
        return vec4(0.0);
    }
    let b = min(vec3<u32>(max(floor(i0 / f32(BRICK)), vec3(0.0))), v.bricks.xyz - 1u);
    let slot = brick_table[v.dims.w + b.x + v.bricks.x * (b.y + v.bricks.y * b.z)];
    if slot == EMPTY_BRICK {
        return vec4(0.0);
    }
    let size = textureDimensions(atlas);
    let grid = size / STORED_BRICK;
    let o = vec3(slot % grid.x, (slot / grid.x) % grid.y, slot / (grid.x * grid.y)) * STORED_BRICK;
    let a = u - vec3<f32>(b * BRICK) + 1.0 + vec3<f32>(o);
    return textureSampleLevel(atlas, atlas_sampler, a / vec3<f32>(size), 0.0);
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4<f32> {
    let v = slice_volumes[in.volume];
    let p = (v.to_object * vec4(in.rel, 1.0)).xyz;
    let s = atlas_sample(v, p);
    if !(s.a > 0.0) {
        discard;
    }
    // The slice stands for the slab to the next slice along this pixel's ray: the spacing
    // over cos(ray, view axis). Alpha is per reference length: 1 - (1 - a)^(slab / h).
    let cos_t = max(dot(normalize(in.rel), frame.cam_forward.xyz), 1e-3);
    let a = min(s.a, 0.9999999);
    let corrected = 1.0 - pow(1.0 - a, v.lengths.y / (cos_t * v.lengths.x));
    return vec4(s.rgb * (corrected / s.a), corrected);
}

// The resolve: one fullscreen triangle laying the accumulated slices "over" the colour.
@vertex
fn vs_resolve(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_resolve(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(accumulated, vec2<i32>(pos.xy), 0);
}
