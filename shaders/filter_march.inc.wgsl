// The filter's march of one pixel (RayMarchFilter's `ray_march_filter.wgsl`, whose hits go to
// the SSBVB, and RayMarchGBuffer's `ray_march_gbuffer.wgsl`, whose hits go straight into the
// G-buffer): from the empty-space prepass's entry point the pixel's instance is marched
// through its sparse lookup (sparse_march.inc.wgsl), then the other instances whose boxes
// the ray enters before that hit (instance_bvh.inc.wgsl), from the prepass entry on
// (`prepass_floor`); the nearest hit is `best`, its instance `best_inst`; and the frame's
// counters.
//
// The includer declares, before including this file:
// - `entry: texture_2d<f32>` (the prepass: object-space entry point in xyz, instance + 1
//   in w), `filter_words: array<atomic<u32>>` (the counters from word 0, layout below) and
//   `page_feedback: array<atomic<u32>>` (sparse_march.inc.wgsl);
// - the overrides MAX_STEPS, FAST_MARCH and PAGED (sparse_march.inc.wgsl),
//   SEVERAL_INSTANCES (more than one instance may be visible: the walk is compiled in) and
//   COUNT_WORK (count the work into the counters).

// Words of the counters: rays, then (low, high) pairs of sums, then the histogram
// (RayMarchFilter::counters reads them).
const C_RAYS: u32 = 0u;
const C_STEPS: u32 = 1u;
const C_BOXES: u32 = 3u;
const C_MARCHES: u32 = 5u;
const C_WORDS: u32 = 7u;
const C_HISTOGRAM: u32 = 9u;

var<private> marches: u32;

//#include "sparse_march.inc.wgsl"
//#include "instance_bvh.inc.wgsl"

// How far (in `t`) before the prepass entry `e` the march of the prepass instance starts:
// one cell, plus an eighth of how much the entry moves along the ray to a neighbouring
// pixel of the same instance (rasterizers snap vertices to 1/16 px or finer, and on faces
// seen at grazing angles that moves the interpolated entry along the ray by that fraction
// of the per-pixel change), plus 1e-4 object units for rounding. A pixel without such a
// neighbour starts 3.5 object units back, outside the object's box ([-1, 1]^3 has a
// diagonal of 3.46). Entry points are small object-space numbers, so this is exact
// whatever the camera's distance.
fn entry_margin(e: vec4<f32>, px: vec2<i32>, size: vec2<i32>, d: vec3<f32>, s: f32) -> f32 {
    let dd = dot(d, d);
    var slope = -1.0;
    var offsets = array(vec2(1, 0), vec2(-1, 0), vec2(0, 1), vec2(0, -1));
    for (var i = 0u; i < 4u; i++) {
        let q = px + offsets[i];
        if all(q >= vec2(0)) && all(q < size) {
            let en = textureLoad(entry, q, 0);
            if en.w == e.w {
                slope = max(slope, abs(dot(en.xyz - e.xyz, d)) / dd);
            }
        }
    }
    if slope < 0.0 {
        return 3.5 * inverseSqrt(dd);
    }
    return (s + 1e-4) * inverseSqrt(dd) + slope * 0.125;
}

// Marches the prepass instance `k` for a pixel with entry `e`: the pixel's ray in the
// instance's object space as every other instance gets it (`object_ray`: from the camera,
// or for a far camera from a point near the instance, so that a camera 1e6 units away
// loses no precision), from the entry point moved back by `entry_margin` (never behind
// the camera; a proxy holding the camera: from the camera). The plane times are the ones
// of a march from the camera, so ties are decided as in the reference, and two instances
// hit at the same distance compute the same `t`.
//
// Where that start is the walk's too (`prepass_floor`): when no proxy of the frame is drawn
// by its back faces, every proxy is entered from outside through a front face, and the
// prepass kept the nearest; every voxel lies in its instance's proxy, so no voxel of any
// instance is on the ray before that entry, less the same margin for the interpolated
// entry's error (one cell, the slope, and the depth test's f32 ties). The walk then passes
// over the boxes the ray leaves before it and starts each march there (in a crowd most
// marched boxes lie in front of the prepass instance; docs/benchmarks.md).
fn march_prepass(k: u32, e: vec4<f32>, px: vec2<i32>, size: vec2<i32>, dir: vec3<f32>) -> Hit {
    let inst = instances[k];
    let lod = lod_info(inst.lod);
    let ray = object_ray(inst, pixel_centre, dir);
    var t_from = 0.0;
    prepass_floor = 0.0;
    if (inst.flags & 1u) == 0u {
        // The entry's parameter on the ray (its f32 rounding only moves where the march
        // starts, within the margin).
        let tp = dot(e.xyz - ray.o, ray.d) / dot(ray.d, ray.d);
        t_from = tp - min(entry_margin(e, px, size, ray.d, cell_size(lod.level)), max(tp, 0.0));
        if frame.prepass.x == 1u {
            prepass_floor = max(t_from + ray.t_base, 0.0);
        }
    }
    var h = march_resident(ray.o, ray.d, inst.lod, t_from, BIG);
    h.t += ray.t_base;
    return h;
}


// The pixel's best hit so far and its instance; the prepass instance (marched first).
var<private> best: Hit;
// A world distance before which no instance has a voxel on the pixel's ray (0: none
// known; `march_prepass`).
var<private> prepass_floor: f32;
var<private> best_inst: u32;
var<private> prepass_inst: u32;
// The pixel's centre in screen pixels (for object_ray).
var<private> pixel_centre: vec2<f32>;

// Marches visible instance `j` from the walk's floor up to the best hit; keeps its hit when
// nearer, or as near with a lower index. Called by the hierarchy walk.
fn bvh_visit(j: u32, dir: vec3<f32>) -> f32 {
    if j == prepass_inst {
        return best.t;
    }
    let inst_j = instances[j];
    let lod_j = lod_info(inst_j.lod);
    let ray = object_ray(inst_j, pixel_centre, dir);
    let rj = make_ray_od(ray.o, ray.d, lod_j.level);
    let limit = best.t - ray.t_base;
    let t_low = max(walk_t_min - ray.t_base, 0.0);
    if !(max(rj.t_enter, t_low) <= min(rj.t_exit, limit)) {
        return best.t;
    }
    marches += 1u;
    var h = march_resident(ray.o, ray.d, inst_j.lod, t_low, limit);
    h.t += ray.t_base;
    if h.found && (!best.found || h.t < best.t || (h.t == best.t && j < best_inst)) {
        best = h;
        best_inst = j;
    }
    return best.t;
}

// Whether a prepass texel names a visible instance: w = instance + 1, an exact small
// integer (NaN or stale values are ignored).
fn has_proxy(e: vec4<f32>, count: u32) -> bool {
    return e.w >= 1.0 && e.w < f32(count) + 0.5;
}

// The visible instances of the frame.
fn visible_count() -> u32 {
    return u32(max(frame.shine_near_far_count.w, 0.0));
}


// Marches texel `px`'s ray (the prepass's instance, then the others its ray meets before
// that hit): the nearest hit in `best` / `best_inst`. Returns whether it cast a ray (the
// texel is on the prepass and has a proxy).
fn march_pixel(px: vec2<i32>) -> bool {
    let size = vec2<i32>(textureDimensions(entry));
    if px.x >= size.x || px.y >= size.y {
        return false;
    }
    let e = textureLoad(entry, px, 0);
    let count = visible_count();
    if !has_proxy(e, count) {
        return false;
    }
    let k = u32(e.w) - 1u;
    // The filter may run at a fraction of the screen (`entry` declared ScreenScaled): the
    // prepass rasterized this texel's centre, which is this point of the full screen.
    // (At full resolution exactly the pixel's centre, as the reference's.)
    let texel_centre = vec2<f32>(px) + vec2(0.5);
    let full = all(vec2<f32>(size) == frame.screen.xy);
    pixel_centre = select(texel_centre * frame.screen.xy / vec2<f32>(size), texel_centre, full);
    let dir = pixel_ray(pixel_centre);

    marches = 1u;
    best = march_prepass(k, e, px, size, dir);
    best_inst = k;
    prepass_inst = k;
    // Every voxel of another instance lies behind the floor: a hit before it needs no
    // walk, and the walk passes over boxes the ray leaves before it.
    let floor = prepass_floor;
    if floor >= 0.0 {
        walk_t_min = floor;
    }
    let before_others = best.found && best.t < floor;
    if SEVERAL_INSTANCES && count > 1u && !before_others {
        instance_walk(pixel_centre, dir, best.t, count);
    }
    return true;
}

// Histogram bin of a step count: exact below 32, then 8 bins per power of two (the top
// three bits after the leading one). RayMarchFilter::counters inverts it.
fn steps_bin(s: u32) -> u32 {
    if s < 32u {
        return s;
    }
    let e = firstLeadingBit(s);
    return 32u + (e - 5u) * 8u + ((s >> (e - 3u)) & 7u);
}

// Adds to a (low, high) pair of words.
fn add_wide(word: u32, v: u32) {
    if v == 0u {
        return;
    }
    let old = atomicAdd(&filter_words[word], v);
    if old + v < old {
        atomicAdd(&filter_words[word + 1u], 1u);
    }
}

// Resets the pixel's counts (before `march_pixel`).
fn reset_counts() {
    march_steps = 0u;
    march_words = 0u;
    boxes_tested = 0u;
    marches = 0u;
}

// Adds a pixel that cast a ray to the frame's counters (with COUNT_WORK).
fn count_ray() {
    if COUNT_WORK {
        atomicAdd(&filter_words[C_RAYS], 1u);
        add_wide(C_STEPS, march_steps);
        add_wide(C_BOXES, boxes_tested);
        add_wide(C_MARCHES, marches);
        add_wide(C_WORDS, march_words);
        atomicAdd(&filter_words[C_HISTOGRAM + steps_bin(march_steps)], 1u);
    }
}
