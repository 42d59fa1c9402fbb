//#include "common.inc.wgsl"
// ESVO ray casting (Laine & Karras 2010, "Efficient Sparse Voxel Octrees", the traversal
// of their appendix, without contours): per pixel, a fullscreen triangle whose fragment
// casts the pixel's ray through every visible instance by ESVO's descent of the object's
// octree down to the instance's LOD level, and keeps the nearest hit. Same octree data and
// bindings as octree_ray_cast.wgsl (svo_nodes.inc.wgsl), same outputs (ray_cast.inc.wgsl).
//
// ESVO's frame: the octree's box [-1, 1]^3 is moved to [1, 2]^3 (p' = p / 2 + 1.5, d' =
// d / 2, so the ray parameter, the world distance, is unchanged), where a voxel of scale s
// has edge 2^(s - S_MAX) and its corner's coordinates are floats whose mantissa bits above
// s are the path from the root: the highest bit in which two positions differ names the
// scale of their common ancestor (POP, without walking up the stack). Axes are mirrored
// (x' -> 3 - x') so that the direction is negative on every axis; then every plane
// crossing is `t = x * coef - bias` with `coef = -1 / |d|`, the current cube's exit is its
// lower corner and children are entered from the upper ones. The parent stack holds, per
// scale, the node and the end of the active t-span (`t_max`) to restore on POP; a parent
// is written only when its child ends before it (`h`), as in the paper.
//
// Differences from the paper: the descent stops at the instance's LOD level (the voxel of
// scale S_MAX - level) instead of ESVO's projected-size test, and a node's children are
// found in its `child_mask` / `first_child` (ssbvb's octree) instead of ESVO's 32-bit
// child descriptors with far pointers. The ray has no end but `t_best`.
//
// Conventions kept from octree_ray_cast.wgsl (the hit is the first occupied voxel, t its
// entry distance): the face is the axis of the last ADVANCE (several axes on an exact
// tie: the one with the largest |d|, as the reference); in the first cell the axis of the
// latest entry plane, or when the ray starts inside the box the dominant axis of the
// direction. Unlike the reference, ESVO steps diagonally through an exact edge or corner
// tie and so skips the cells touching the ray only there, and its times are accumulated
// (`corner + half * coef` for the centre) rather than computed per plane: rays that
// graze voxel edges may hit a neighbour of the reference's voxel.
//
// Limit: levels up to 16 (the octree data's; ESVO's 23-bit scale allows 23).

override MAX_STEPS: u32 = 4096u;

// ESVO's scales: positions in [1, 2) carry 23 mantissa bits.
const S_MAX: i32 = 23;
// The finest level the octree data holds (SVO_STRIDE); the stack holds scales from
// S_MAX - MAX_LEVEL (the parent of a level-16 voxel is pushed at scale 8) to S_MAX - 1.
const MAX_LEVEL: u32 = 16u;
const STACK_BASE: i32 = 7;

//#include "svo_nodes.inc.wgsl"

// Pass-private: the frame's ray counters (ray_cast.inc.wgsl).
@group(1) @binding(9) var<storage, read_write> ray_counters: array<atomic<u32>>;

//#include "ray_cast.inc.wgsl"
//#include "ray_cast_compute.inc.wgsl"

// `eps` with the sign of `x` (WGSL has no copysign; -0 keeps its sign bit).
fn copysign_eps(x: f32, eps: f32) -> f32 {
    return select(eps, -eps, (bitcast<u32>(x) >> 31u) != 0u);
}

// Among the axes in `mask`, the one along which the ray moves fastest (ties: lower index).
fn fastest_axis(mask: u32, ad: vec3<f32>) -> u32 {
    var best = 3u;
    for (var a = 0u; a < 3u; a++) {
        if (mask & (1u << a)) != 0u && (best == 3u || ad[a] > ad[best]) {
            best = a;
        }
    }
    return best;
}

// A hit on the voxel `node` of level `level` entered at `t` through a face of axis `axis`.
fn esvo_hit(base: u32, level: u32, node: u32, t: f32, axis: u32, d: vec3<f32>) -> Hit {
    return Hit(true, t, node - svo_level_offsets[base + level], entered_face(axis, d));
}

// ESVO descent of one instance; only hits nearer than `t_best` count.
fn trace(inst: Instance, o: vec3<f32>, d: vec3<f32>, t_best: f32) -> Hit {
    let miss = Hit(false, t_best, 0u, 0u);
    let target_level = inst.level;
    let base = lod_info(inst.lod).object * SVO_STRIDE;
    if target_level > MAX_LEVEL || arrayLength(&svo_level_offsets) < base + SVO_STRIDE {
        return miss;
    }
    // An empty octree has no root.
    if svo_level_offsets[base + 1u] == svo_level_offsets[base] {
        return miss;
    }
    // Into [1, 2]^3; tiny direction components become ±2^-S_MAX (ESVO's epsilon: no
    // division by zero, and such an axis's planes are crossed far beyond the box).
    let eps = exp2(-f32(S_MAX));
    var dir = d * 0.5;
    for (var a = 0u; a < 3u; a++) {
        if abs(dir[a]) < eps {
            dir[a] = copysign_eps(dir[a], eps);
        }
    }
    let origin = o * 0.5 + 1.5;
    let coef = 1.0 / -abs(dir);
    var bias = coef * origin;
    // Mirror the axes along which the ray moves up; `mirror` maps a mirrored child slot
    // to the octree's.
    var mirror = 0u;
    for (var a = 0u; a < 3u; a++) {
        if dir[a] > 0.0 {
            mirror |= 1u << a;
            bias[a] = 3.0 * coef[a] - bias[a];
        }
    }
    // The active t-span: the box's entry (its upper planes) to its exit (lower planes).
    let t_in = 2.0 * coef - bias;
    let t_out = coef - bias;
    let t_enter = max(max(t_in.x, t_in.y), t_in.z);
    var t_min = max(t_enter, 0.0);
    var t_max = min(min(t_out.x, t_out.y), t_out.z);
    if !(t_min <= t_max) || t_min >= t_best {
        return miss;
    }
    let ad = abs(d);
    var face_axis: u32;
    if t_enter < 0.0 {
        // Starts inside the box: the dominant axis of the direction.
        face_axis = select(select(2u, 1u, ad.y >= ad.z), 0u, ad.x >= ad.y && ad.x >= ad.z);
    } else {
        let entering = select(0u, 1u, t_in.x == t_enter) | select(0u, 2u, t_in.y == t_enter)
            | select(0u, 4u, t_in.z == t_enter);
        face_axis = fastest_axis(entering, ad);
    }
    if target_level == 0u {
        return esvo_hit(base, 0u, svo_level_offsets[base], t_min, face_axis, d);
    }
    let target_scale = S_MAX - i32(target_level);

    var stack_node: array<u32, MAX_LEVEL>;
    var stack_t_max: array<f32, MAX_LEVEL>;
    // The current cube: child `idx` (mirrored slot) of `parent`, lower corner `pos`, edge
    // `scale_exp2` = 2^(scale - S_MAX); `desc` is the parent's node once read.
    var parent = svo_level_offsets[base];
    var desc = SvoNode(0u, 0u);
    var have_desc = false;
    var idx = 0u;
    var pos = vec3(1.0);
    var scale = S_MAX - 1;
    var scale_exp2 = 0.5;
    var h = t_max;
    // The root's child the ray enters first: the upper half on the axes whose mid plane it
    // crosses after t_min.
    for (var a = 0u; a < 3u; a++) {
        if 1.5 * coef[a] - bias[a] > t_min {
            idx ^= 1u << a;
            pos[a] = 1.5;
        }
    }
    for (var step = 0u; step < MAX_STEPS; step++) {
        cast_steps += 1u;
        if t_min >= t_best {
            return miss;
        }
        if !have_desc {
            desc = svo_node(parent);
            cast_words += 2u;
            have_desc = true;
        }
        // The cube's exit: the earliest of its lower corner's planes.
        let t_corner = pos * coef - bias;
        let tc_max = min(min(t_corner.x, t_corner.y), t_corner.z);
        let slot = idx ^ mirror;
        if (desc.child_mask & (1u << slot)) != 0u && t_min <= t_max {
            let child = desc.first_child + countOneBits(desc.child_mask & ((1u << slot) - 1u));
            if scale == target_scale {
                return esvo_hit(base, target_level, child, t_min, face_axis, d);
            }
            // INTERSECT: the span within the cube, and its mid planes' times.
            let tv_max = min(t_max, tc_max);
            let half = scale_exp2 * 0.5;
            let t_center = half * coef + t_corner;
            if t_min <= tv_max {
                // PUSH: the parent is needed again only if the ray leaves the cube before it.
                if tc_max < h {
                    stack_node[scale - STACK_BASE] = parent;
                    stack_t_max[scale - STACK_BASE] = t_max;
                }
                h = tc_max;
                parent = child;
                have_desc = false;
                idx = 0u;
                scale -= 1;
                scale_exp2 = half;
                for (var a = 0u; a < 3u; a++) {
                    if t_center[a] > t_min {
                        idx ^= 1u << a;
                        pos[a] += scale_exp2;
                    }
                }
                t_max = tv_max;
                continue;
            }
        }
        // ADVANCE: across every plane of the exit corner crossed at tc_max.
        var step_mask = 0u;
        for (var a = 0u; a < 3u; a++) {
            if t_corner[a] <= tc_max {
                step_mask |= 1u << a;
                pos[a] -= scale_exp2;
            }
        }
        t_min = tc_max;
        idx ^= step_mask;
        face_axis = fastest_axis(step_mask, ad);
        if (idx & step_mask) != 0u {
            // POP: a flipped bit went 0 -> 1, so the ray left the parent. The highest bit
            // in which the old and new corners differ is the scale of the cube now entered.
            var differing = 0u;
            for (var a = 0u; a < 3u; a++) {
                if (step_mask & (1u << a)) != 0u {
                    differing |= bitcast<u32>(pos[a]) ^ bitcast<u32>(pos[a] + scale_exp2);
                }
            }
            scale = i32(bitcast<u32>(f32(differing)) >> 23u) - 127;
            if scale >= S_MAX {
                // Left the octree.
                return miss;
            }
            scale_exp2 = bitcast<f32>(u32(scale - S_MAX + 127) << 23u);
            parent = stack_node[scale - STACK_BASE];
            t_max = stack_t_max[scale - STACK_BASE];
            // Round the corner down to the new scale and take its child slot.
            let sh = bitcast<vec3<u32>>(pos) >> vec3(u32(scale));
            pos = bitcast<vec3<f32>>(sh << vec3(u32(scale)));
            idx = (sh.x & 1u) | ((sh.y & 1u) << 1u) | ((sh.z & 1u) << 2u);
            // Do not store the same parent again; its node is read anew.
            h = 0.0;
            have_desc = false;
        }
    }
    return miss;
}
