// Shared declarations of every ssbvb pass (included with `//#include "common.inc.wgsl"`).
// Rust mirrors of these structs live in crates/passes/src/gpu_scene.rs; keep them equal.
//
// Spaces: object space is [-1, 1]^3 (the voxel grid); "world" on the GPU is always
// camera-relative world space (world - camera position, in f32) so that objects at 1e7
// world units keep their precision; view space looks down -Z; clip is reversed-Z.

// Per-frame constants (group 0, binding 0).
struct Frame {
    // Camera-relative world -> clip (reversed Z: near -> 1, far -> 0).
    view_proj: mat4x4<f32>,
    // Its inverse (clip -> camera-relative world).
    inv_view_proj: mat4x4<f32>,
    // Camera-relative world -> view (a rotation).
    view: mat4x4<f32>,
    // View -> clip (reversed Z). Instance geometry goes object -> view (Instance
    // `object_to_view`, composed in f64) -> clip: large camera-relative world coordinates
    // would round by more than a pixel in a narrow far view.
    proj: mat4x4<f32>,
    // Ray through NDC (x, y): forward.xyz + x * right.xyz + y * up.xyz (not normalized);
    // right and up are pre-scaled by the half-extents of the view at distance 1.
    cam_right: vec4<f32>,
    cam_up: vec4<f32>,
    cam_forward: vec4<f32>,
    // width, height, 1 / width, 1 / height of the screen in pixels.
    screen: vec4<f32>,
    // Direction towards the light (normalized) in xyz; ambient factor in w.
    light_dir: vec4<f32>,
    // Light colour in rgb; specular strength in w.
    light_color: vec4<f32>,
    // x: shininess, y: near, z: far (0 = infinite), w: number of visible instances.
    shine_near_far_count: vec4<f32>,
    // xy: the frame's sub-pixel jitter in pixels (a temporal pass's; 0 otherwise): pixel
    // `px` shows the unjittered camera's ray through `px + xy`, and `proj` is sheared to
    // match. zw: 0.
    jitter: vec4<f32>,
    // The scene's word stream (scene_streams.inc.wgsl): x = log2 of its words per
    // binding, y = its first colour word, z = its first normal word; w: where the screen
    // tiles' instance lists start in `instance_bvh` (in vec4s; 0: none this frame;
    // instance_bvh.inc.wgsl).
    streams: vec4<u32>,
    // x: 1 when no visible proxy is drawn by its back faces: a texel's nearest proxy entry
    // is then where its ray first meets any instance's proxy (filter_march.inc.wgsl's
    // `prepass_floor`); yzw: 0.
    prepass: vec4<u32>,
}

// One visible instance of a voxel asset (group 0, binding 1), rebuilt every frame.
struct Instance {
    // Object space -> camera-relative world.
    object_to_world: mat4x4<f32>,
    // Object space -> view space (composed in f64: exact lateral offsets at any distance).
    object_to_view: mat4x4<f32>,
    // Camera-relative world -> object space.
    world_to_object: mat4x4<f32>,
    // Camera position in object space (xyz); w: world size of one cell of the chosen LOD.
    camera_object: vec4<f32>,
    // Index into `lods` of the chosen LOD.
    lod: u32,
    // Grid level of the chosen LOD (2^level cells per axis).
    level: u32,
    // Bit 0: the camera is inside this instance's proxy.
    flags: u32,
    // Index of the instance in the scene (stable across frames, for ids in the G-buffer).
    scene_index: u32,
}

// A node of the hierarchy over the visible instances' camera-relative world boxes (group 0,
// binding 2, two vec4s a node: `bvh_node`), rebuilt every frame (ssbvb-voxel
// instance_bvh.rs; node 0 is the root).
struct BvhNode {
    lo: vec3<f32>,
    // Left child, or BVH_LEAF | index into `instances`.
    left: u32,
    hi: vec3<f32>,
    // Right child (unused in a leaf).
    right: u32,
}

const BVH_LEAF: u32 = 0x80000000u;
// Stands in for infinity: WGSL lets implementations assume no infinities at run time.
const BIG: f32 = 3.0e38;
// Most nodes on a traversal stack (instance_bvh.rs MAX_DEPTH, plus one).
const BVH_STACK: u32 = 26u;

// Where one LOD of one asset lives in the scene's streams (`lod_info`: the word stream).
struct LodInfo {
    level: u32,
    // Depth of the lookup's 64-ary tree (ssbvb-voxel lookup.rs): the root covers 4^depth
    // cells per axis, its leaves 4^3.
    depth: u32,
    // First voxel of this LOD in the colour and normal streams.
    voxel_offset: u32,
    // This LOD's root in the lookup-node stream; child indices are relative to it.
    node_offset: u32,
    // The scene object this LOD belongs to.
    object: u32,
    // log2 of the words per binding of the word stream (as `frame.streams.x`), and of the
    // nodes per binding of the lookup-node stream (the same for every LOD of a scene).
    chunk_bits: u32,
    node_chunk_bits: u32,
    // Under a GPU budget (gpu_scene.rs, `streaming.rs`): the global id of this LOD's first
    // 16^3 page, or NO_PAGES when the LOD is wholly resident; and the first page node (the
    // tree's nodes at depth - 2, one per occupied page, in Morton order), relative to the
    // root. A page node whose page is not resident has base PAGE_MISSING.
    page_base: u32,
    first_page_node: u32,
}

const NO_PAGES: u32 = 0xffffffffu;
const PAGE_MISSING: u32 = 0xffffffffu;

// One node of a lookup tree: a 64-bit mask of the present 4^3 children (bit = Morton
// order of the 2-bit local coordinates) and the index of the first child (inner nodes,
// relative to the LOD's root) or the id of the first voxel (leaves).
struct LookupNode {
    lo: u32,
    hi: u32,
    base: u32,
}

// A point-cloud voxel as packed by ssbvb-voxel (asset.rs, `PackedVoxel`): 16 bytes.
struct PackedVoxel {
    xy: u32,        // x bits 0..16, y bits 16..32
    z_normal: u32,  // z bits 0..16, octahedral normal u bits 16..24, v bits 24..32
    color: u32,     // linear RGBA8, r in the low byte
    uv: u32,        // two 16-bit unorms
}

// One SSBVB entry: the hit voxel of one pixel and where it came from (32 bytes).
struct VoxelSlot {
    // `uv` holds the grid level of the voxel's LOD (ray_march_filter.rs, `VoxelSlot`).
    voxel: PackedVoxel,
    // Index into `instances`.
    instance: u32,
    // y * width + x of the pixel whose ray found it.
    pixel: u32,
    // World distance along the pixel's ray to the voxel's entered face.
    t: f32,
    // Entered face: 0..2 = -X/-Y/-Z side (normal points -axis), 3..5 = +X/+Y/+Z side.
    face: u32,
}

// Stencil values: voxel billboards and triangle objects.
const STENCIL_VOXEL: u32 = 1u;
const STENCIL_TRIANGLE: u32 = 2u;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> instances: array<Instance>;
// Words, not nodes: after the nodes the same buffer holds the screen tiles' instance lists
// (`frame.streams.w`), and one binding keeps a pass within WebGPU's 8 storage buffers.
@group(0) @binding(2) var<storage, read> instance_bvh: array<vec4<u32>>;

fn bvh_node(i: u32) -> BvhNode {
    let a = instance_bvh[2u * i];
    let b = instance_bvh[2u * i + 1u];
    return BvhNode(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}
// The scene's streams (ssbvb-gpu scene_bindings.rs): the word stream holds the LOD table
// (LOD_WORDS words per entry), then per voxel its linear RGBA8 colour, then the 16-bit
// octahedral normals two to a word (low half = even voxel); positions are implied by the
// lookup (the voxel id is the Morton rank of its cell). The lookup-node stream holds the
// trees. No binding may exceed the device's storage binding size, so each stream is split
// into chunks of 2^frame.streams.x words (2^LodInfo.node_chunk_bits nodes) over as many
// bindings as the scene needs; the include declares them and `scene_word` / `lookup_node`.
//#include "scene_streams.inc.wgsl"

const LOD_WORDS: u32 = 9u;

// Entry `i` of the LOD table.
fn lod_info(i: u32) -> LodInfo {
    let w = i * LOD_WORDS;
    return LodInfo(
        scene_word(w),
        scene_word(w + 1u),
        scene_word(w + 2u),
        scene_word(w + 3u),
        scene_word(w + 4u),
        scene_word(w + 5u),
        scene_word(w + 6u),
        scene_word(w + 7u),
        scene_word(w + 8u),
    );
}

// Colour word of voxel `g` (index over all LODs).
fn voxel_color_word(lod: LodInfo, g: u32) -> u32 {
    return scene_word(frame.streams.y + g);
}

// 16-bit normal of voxel `g` (index over all LODs).
fn voxel_normal_bits(lod: LodInfo, g: u32) -> u32 {
    let word = scene_word(frame.streams.z + (g >> 1u));
    return (word >> (16u * (g & 1u))) & 0xffffu;
}

fn voxel_cell(v: PackedVoxel) -> vec3<u32> {
    return vec3(v.xy & 0xffffu, v.xy >> 16u, v.z_normal & 0xffffu);
}

// A packed voxel's stored normal (object space).
fn voxel_normal(v: PackedVoxel) -> vec3<f32> {
    return oct16_normal(v.z_normal >> 16u);
}

// Inverse of the 16-bit octahedral encoding in asset.rs (u in the low byte, v in the high
// one); always a unit vector.
fn oct16_normal(bits: u32) -> vec3<f32> {
    let u = f32(bits & 0xffu) / 255.0 * 2.0 - 1.0;
    let w = f32((bits >> 8u) & 0xffu) / 255.0 * 2.0 - 1.0;
    var n = vec3(u, w, 1.0 - abs(u) - abs(w));
    if n.z < 0.0 {
        let s = select(vec2(-1.0), vec2(1.0), n.xy >= vec2(0.0));
        n = vec3((1.0 - abs(n.yx)) * s, n.z);
    }
    return normalize(n);
}

fn voxel_color(v: PackedVoxel) -> vec4<f32> {
    return unpack4x8unorm(v.color);
}

// Cell size in object units of a level-`level` grid.
fn cell_size(level: u32) -> f32 {
    return 2.0 / f32(1u << level);
}

// The cell of an `n`-cell axis of cell size `s` (over [-1, 1]) holding coordinate `x`.
// `x + 1` can round up onto the next plane (never down: every plane plus one is a float),
// so the plane's exact value, `i * s - 1`, decides.
fn axis_cell(x: f32, s: f32, n: i32) -> i32 {
    let i = i32(floor((x + 1.0) / s));
    return clamp(select(i, i - 1, f32(i) * s - 1.0 > x), 0, n - 1);
}

// Object-space box of a cell.
fn cell_min(cell: vec3<u32>, level: u32) -> vec3<f32> {
    return vec3<f32>(cell) * cell_size(level) - 1.0;
}

// Bit of local child coordinates `l` (in [0, 4)^3) in a lookup node's mask.
fn child_bit(l: vec3<u32>) -> u32 {
    return (l.x & 1u) | ((l.y & 1u) << 1u) | ((l.z & 1u) << 2u) | ((l.x >> 1u) << 3u)
        | ((l.y >> 1u) << 4u) | ((l.z >> 1u) << 5u);
}

// Whether bit `b` of a node's mask is set.
fn node_has(n: LookupNode, b: u32) -> bool {
    return (select(n.lo, n.hi, b >= 32u) & (1u << (b & 31u))) != 0u;
}

// The child (or voxel) index of present bit `b`: base + the ones below it.
fn node_child(n: LookupNode, b: u32) -> u32 {
    let below_lo = select(n.lo & ((1u << (b & 31u)) - 1u), n.lo, b >= 32u);
    let below_hi = select(0u, n.hi & ((1u << (b & 31u)) - 1u), b >= 32u);
    return n.base + countOneBits(below_lo) + countOneBits(below_hi);
}

// Voxel id + 1 at a cell of a LOD (x: 0 when empty, or in a page that is not resident),
// and the page node of the cell's page when that page is not resident (y; PAGE_MISSING
// otherwise). The cell must be inside the grid.
fn lookup_cell_paged(lod: LodInfo, cell: vec3<u32>) -> vec2<u32> {
    var node = lod.node_offset;
    for (var k = 0u; k < lod.depth; k++) {
        let n = lookup_node(lod, node);
        if k + 2u == lod.depth && lod.page_base != NO_PAGES && n.base == PAGE_MISSING {
            return vec2(0u, node);
        }
        let b = child_bit((cell >> vec3(2u * (lod.depth - 1u - k))) & vec3(3u));
        if !node_has(n, b) {
            break;
        }
        if k + 1u == lod.depth {
            return vec2(node_child(n, b) + 1u, PAGE_MISSING);
        }
        node = lod.node_offset + node_child(n, b);
    }
    return vec2(0u, PAGE_MISSING);
}

// Voxel id + 1 at a cell of a LOD (0 when empty, or in a page that is not resident).
fn lookup_cell(lod: LodInfo, cell: vec3<u32>) -> u32 {
    return lookup_cell_paged(lod, cell).x;
}

// A voxel's attributes in the 16-byte layout the SSBVB slots carry (asset.rs
// `PackedVoxel`): its cell from the lookup, the rest from the attribute streams. `id` is
// the voxel id within the LOD.
fn packed_voxel(lod: LodInfo, cell: vec3<u32>, id: u32) -> PackedVoxel {
    let g = lod.voxel_offset + id;
    let normal = voxel_normal_bits(lod, g);
    let color = voxel_color_word(lod, g);
    return PackedVoxel(cell.x | (cell.y << 16u), cell.z | (normal << 16u), color, 0u);
}

// Linear RGBA colour of voxel `id` of a LOD.
fn lod_voxel_color(lod: LodInfo, id: u32) -> vec4<f32> {
    return unpack4x8unorm(voxel_color_word(lod, lod.voxel_offset + id));
}

// Normalized world (camera-relative) direction of the ray through pixel position `px`
// (in pixels, row 0 at the top; pixel centres at +0.5), exactly as the CPU reference.
fn pixel_ray(px_in: vec2<f32>) -> vec3<f32> {
    let px = px_in + frame.jitter.xy;
    let ndc = vec2(px.x * frame.screen.z * 2.0 - 1.0, 1.0 - px.y * frame.screen.w * 2.0);
    return normalize(frame.cam_forward.xyz + ndc.x * frame.cam_right.xyz + ndc.y * frame.cam_up.xyz);
}

// NDC position of a pixel coordinate (pixel centres at + 0.5).
fn pixel_ndc(px_in: vec2<f32>) -> vec2<f32> {
    let px = px_in + frame.jitter.xy;
    return vec2(px.x * frame.screen.z * 2.0 - 1.0, 1.0 - px.y * frame.screen.w * 2.0);
}

// Object units beyond which a camera counts as far from an instance (object_ray).
const FAR_OBJECT: f32 = 64.0;

// A pixel's ray in an instance's object space: `o + t' d`, the world distance from the
// camera being `t_base + t'` (`d` is not normalized). Near the instance the origin is the
// camera. Far from it (|camera| > FAR_OBJECT object units), a camera-relative f32 ray
// cannot resolve a narrow lens's pixels at the object, so the origin is the ray's point
// at the depth of the instance's origin, 4 object units back (outside the [-1, 1]^3 box),
// built from view-space differences of small numbers (the f64-composed `object_to_view`
// and the pixel's slopes from NDC).
struct ObjectRay {
    o: vec3<f32>,
    d: vec3<f32>,
    t_base: f32,
}

fn object_ray(inst: Instance, px: vec2<f32>, dir: vec3<f32>) -> ObjectRay {
    let co = inst.camera_object.xyz;
    let d = (inst.world_to_object * vec4(dir, 0.0)).xyz;
    let cv = inst.object_to_view[3].xyz;
    if dot(co, co) < FAR_OBJECT * FAR_OBJECT || !(cv.z < 0.0) {
        return ObjectRay(co, d, 0.0);
    }
    let s = pixel_ndc(px) * vec2(length(frame.cam_right.xyz), length(frame.cam_up.xyz));
    let dv = normalize(vec3(s, -1.0));
    // The ray's point at view depth cv.z, relative to the instance's origin (view space).
    let depth = -cv.z;
    let p_rel = vec3(s * depth - cv.xy, 0.0);
    let view3 = mat3x3(frame.view[0].xyz, frame.view[1].xyz, frame.view[2].xyz);
    let w2o = mat3x3(
        inst.world_to_object[0].xyz,
        inst.world_to_object[1].xyz,
        inst.world_to_object[2].xyz,
    );
    let v2o = w2o * transpose(view3);
    let d_obj = v2o * dv;
    let back = 4.0 * inverseSqrt(dot(d_obj, d_obj));
    return ObjectRay(v2o * p_rel - d_obj * back, d_obj, depth / -dv.z - back);
}

// World-space unit normal of an entered face (see VoxelSlot.face), through the instance's
// inverse transpose.
fn face_normal_world(inst: Instance, face: u32) -> vec3<f32> {
    var n = vec3(0.0);
    n[face % 3u] = select(-1.0, 1.0, face >= 3u);
    return object_normal_world(inst, n);
}

// World-space unit normal of a voxel's stored normal.
fn voxel_normal_world(inst: Instance, v: PackedVoxel) -> vec3<f32> {
    return object_normal_world(inst, voxel_normal(v));
}

// World-space unit normal of voxel `id` of a LOD (its stored normal).
fn lod_voxel_normal_world(inst: Instance, lod: LodInfo, id: u32) -> vec3<f32> {
    return object_normal_world(inst, oct16_normal(voxel_normal_bits(lod, lod.voxel_offset + id)));
}

// An object-space normal taken to world space and normalized: the inverse transpose of
// object_to_world's linear part is the transpose of world_to_object's.
fn object_normal_world(inst: Instance, n: vec3<f32>) -> vec3<f32> {
    let m = inst.world_to_object;
    return normalize(transpose(mat3x3(m[0].xyz, m[1].xyz, m[2].xyz)) * n);
}

// The G-buffer's geometric normal: octahedral encoding of a unit vector into [-1, 1]^2
// (ssbvb_passes::gbuffer::oct_encode is the CPU twin and documents it).
fn oct_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n / max(abs(n.x) + abs(n.y) + abs(n.z), 1e-30);
    if p.z >= 0.0 {
        return p.xy;
    }
    let s = select(vec2(-1.0), vec2(1.0), p.xy >= vec2(0.0));
    return (1.0 - abs(p.yx)) * s;
}


// Blinn-Phong exactly as ssbvb-voxel's shading::shade (linear RGB).
fn shade(albedo: vec3<f32>, normal: vec3<f32>, view_dir: vec3<f32>) -> vec3<f32> {
    return shade_lit(albedo, normal, view_dir, 1.0, 1.0, vec3(0.0));
}

// `shade` with the light from the voxels (ssbvb-voxel shading::shade_lit, same
// association): ambient times `ao`, the directional terms times `shadow`, plus
// albedo times the bounce `indirect`.
fn shade_lit(
    albedo: vec3<f32>,
    normal: vec3<f32>,
    view_dir: vec3<f32>,
    ao: f32,
    shadow: f32,
    indirect: vec3<f32>,
) -> vec3<f32> {
    let l = safe_normalize(frame.light_dir.xyz, vec3(0.0, 0.0, 1.0));
    let n = safe_normalize(normal, vec3(0.0, 0.0, 1.0));
    let v = safe_normalize(view_dir, n);
    let h = safe_normalize(l + v, n);
    let ndl = max(dot(n, l), 0.0);
    let ndh = max(dot(n, h), 0.0);
    var spec = 0.0;
    if ndl > 0.0 && ndh > 0.0 {
        spec = frame.light_color.w * pow(ndh, max(frame.shine_near_far_count.x, 0.0));
    }
    let c = frame.light_color.rgb;
    return ao * frame.light_dir.w * albedo + shadow * ndl * albedo * c + shadow * spec * c
        + albedo * indirect;
}

fn safe_normalize(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l2 = dot(v, v);
    if l2 > 1e-20 && l2 < 1e30 {
        return v * inverseSqrt(l2);
    }
    return fallback;
}

// Vertex `v` (0..6: two triangles) of screen tile `t` (row-major, `across` a row) of
// `tile_px` pixels, in clip space: the quads passes draw over the tiles that hold work.
fn screen_tile_vertex(v: u32, t: u32, across: u32, tile_px: u32) -> vec4<f32> {
    let corner = vec2(
        select(0u, 1u, v == 1u || v == 4u || v == 5u),
        select(0u, 1u, v == 2u || v == 3u || v == 5u),
    );
    let px = vec2<f32>((vec2(t % across, t / across) + corner) * tile_px);
    return vec4(px.x * frame.screen.z * 2.0 - 1.0, 1.0 - px.y * frame.screen.w * 2.0, 0.0, 1.0);
}

// Reversed-Z NDC depth of a camera-relative world point, clamped to [0, 1] (1 = near: a
// point at or behind the eye, which the CPU reference still sees at t >= 0).
fn ndc_depth(p: vec3<f32>) -> f32 {
    let clip = frame.view_proj * vec4(p, 1.0);
    if !(clip.w > 0.0) {
        return 1.0;
    }
    return clamp(clip.z / clip.w, 0.0, 1.0);
}

// The G-buffer outputs of a geometry pass (its colour attachments, in slot order).
struct GBuffer {
    // Linear RGBA8, packed (pack4x8unorm).
    @location(0) albedo: u32,
    @location(1) normal: vec4<f32>,
    @location(2) position: vec4<f32>,
    @location(3) geometric_normal: vec2<f32>,
}

// The G-buffer outputs with the fragment's depth written (ray casters, ray-box billboards).
struct GBufferDepth {
    // Linear RGBA8, packed (pack4x8unorm).
    @location(0) albedo: u32,
    @location(1) normal: vec4<f32>,
    @location(2) position: vec4<f32>,
    @location(3) geometric_normal: vec2<f32>,
    @builtin(frag_depth) depth: f32,
}
