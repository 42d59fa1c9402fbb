// Shared by the ray-casting baselines (dense_dda.wgsl, octree_ray_cast.wgsl): the
// G-buffer output with exact depth (common.inc.wgsl's `GBufferDepth`), the hit record, the fullscreen triangle, and the
// per-plane crossing helpers that follow the CPU reference's conventions.
// Needs common.inc.wgsl before it, and the including file must define
// `fn trace(inst: Instance, o: vec3<f32>, d: vec3<f32>, t_best: f32) -> Hit` (the technique:
// the object-space ray `o + t d` of common.inc.wgsl's `object_ray`; hits at or beyond
// `t_best` do not count); `fs_main` below keeps the nearest hit over the
// visible instances its ray meets (the instance hierarchy; exact ties to the lower index,
// as the reference) through `cast_pixel`, which ray_cast_compute.inc.wgsl runs in a
// compute shader instead.

//#include "fullscreen.inc.wgsl"
//#include "instance_bvh.inc.wgsl"

// Loop iterations of `trace` for this pixel (the includer's `trace` adds them: DDA cells,
// or octree nodes visited), for the counters.
var<private> cast_steps: u32;
// Words of the acceleration structure `trace` read for this pixel (the includer adds them:
// 2 per octree node fetched, 1 per dense-grid texel), for the counters.
var<private> cast_words: u32;

// Counters (ray_cast_counters.rs): per lane (pixel x + y mod 64, spreading the atomics)
// the pixels that cast a ray, the steps they took and the words they read (each a low and
// a high word).
const COUNTER_LANES: u32 = 64u;
const COUNTER_LANE_WORDS: u32 = 5u;
// Count into `ray_counters` (off: the pipeline of frames that no report reads).
override COUNT_WORK: bool = true;

struct Hit {
    hit: bool,
    t: f32,
    id: u32,
    face: u32,
}

// Time at which the (mirrored) ray crosses plane k of an axis: origin o, |direction| d.
fn plane_t(k: i32, s: f32, o: f32, d: f32) -> f32 {
    return ((-1.0 + f32(k) * s) - o) / d;
}

// Face index (VoxelSlot.face convention) of entering along axis a with direction sign.
fn entered_face(a: u32, d: vec3<f32>) -> u32 {
    return select(a + 3u, a, d[a] > 0.0);
}

// The pixel's best hit so far and its instance, and the pixel's centre.
var<private> pixel_centre: vec2<f32>;
var<private> best: Hit;
var<private> best_inst: u32;

// Traces visible instance `j` (called by the hierarchy walk): a hit nearer than the best,
// or as near with a lower index, replaces it.
fn bvh_visit(j: u32, dir: vec3<f32>) -> f32 {
    // One ulp beyond the best, so that a hit at exactly its distance comes back (at least
    // the smallest normal float: a denormal may flush to 0 and lose a tie at t = 0).
    let up = max(bitcast<f32>(bitcast<u32>(best.t) + 1u), 1.18e-38);
    let limit = select(up, best.t, best.t >= 1e30);
    let ray = object_ray(instances[j], pixel_centre, dir);
    var h = trace(instances[j], ray.o, ray.d, limit - ray.t_base);
    h.t += ray.t_base;
    if h.hit && (!best.hit || h.t < best.t || (h.t == best.t && j < best_inst)) {
        best = h;
        best_inst = j;
    }
    return best.t;
}

// Adds `v` to the (low, high) pair of words at `word`.
fn add_lane_wide(word: u32, v: u32) {
    let old = atomicAdd(&ray_counters[word], v);
    if old + v < old {
        atomicAdd(&ray_counters[word + 1u], 1u);
    }
}

// Casts the ray of the pixel at `px` (its centre) through the visible instances: the
// nearest hit in `best` / `best_inst`, the work counted. Returns the ray's direction.
fn cast_pixel(px: vec2<f32>) -> vec3<f32> {
    let dir = pixel_ray(px);
    pixel_centre = px;
    best = Hit(false, 1e30, 0u, 0u);
    best_inst = 0u;
    cast_steps = 0u;
    cast_words = 0u;
    instance_walk(px, dir, BIG, u32(frame.shine_near_far_count.w));
    let lane = (u32(px.x) + u32(px.y)) % COUNTER_LANES;
    if COUNT_WORK && cast_steps > 0u {
        atomicAdd(&ray_counters[COUNTER_LANE_WORDS * lane], 1u);
        // Steps and words as (low, high) pairs: a lane of a 4K frame may pass 2^32.
        add_lane_wide(COUNTER_LANE_WORDS * lane + 1u, cast_steps);
        add_lane_wide(COUNTER_LANE_WORDS * lane + 3u, cast_words);
    }
    return dir;
}

// The G-buffer of `best` (a hit) seen along `dir`.
fn gbuffer_of_best(dir: vec3<f32>) -> GBufferDepth {
    let inst = instances[best_inst];
    let p = dir * best.t;
    var out: GBufferDepth;
    let lod = lod_info(inst.lod);
    out.albedo = pack4x8unorm(vec4(lod_voxel_color(lod, best.id).rgb, 1.0));
    out.normal = vec4(lod_voxel_normal_world(inst, lod, best.id), 1.0);
    out.position = vec4(p, dot(p, frame.cam_forward.xyz));
    out.geometric_normal = oct_encode(face_normal_world(inst, best.face));
    out.depth = ndc_depth(p);
    return out;
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> GBufferDepth {
    let dir = cast_pixel(frag.xy);
    if !best.hit {
        discard;
    }
    return gbuffer_of_best(dir);
}
