//#include "common.inc.wgsl"
// Sparse voxel octree ray casting (baseline; cf. Laine & Karras' ESVO, without contours):
// per pixel, a fullscreen triangle whose fragment casts the pixel's ray through every
// visible instance by a stack-based, front-to-back descent of the object's octree
// (`svo_nodes_*`, group 1) down to the instance's LOD level, and keeps the nearest hit.
//
// Octree layout and bindings: svo_nodes.inc.wgsl.
//
// As in dense_dda.wgsl and the CPU reference (ssbvb_voxel::reference::dda) the ray is moved
// into object space with `world_to_object` without renormalizing (t stays the world
// distance), axes with a negative direction are mirrored (child bit flipped) so the ray
// only moves forward, and every crossing time is computed per plane,
// `t_k = (b_k - o) / d`, with exact dyadic boundaries `b_k`: a node's far plane is the
// same number as its parent's mid or far plane, so the descent sees the same times as a
// cell-by-cell DDA. Inside a node the children are visited as a 2×2×2 DDA (earliest next
// plane first, exact ties: largest |d|); an occupied child above the target level is
// pushed/descended into at the current time, its starting child being the one whose mid
// planes are crossed at or before that time. Axes the ray does not move along use the
// floor cell of the origin. The entered face is the axis last stepped on (at the grid
// entry: the latest slab entry; starting inside: the dominant axis of the direction).
//
// Outputs (as dense_dda.wgsl): location 0 albedo (voxel colour, alpha 1), 1 the voxel's
// stored normal, 2 camera-relative world position (xyz) and linear view depth (w), 3 the
// entered face's normal (octahedral); frag_depth the reversed-Z depth; stencil = STENCIL_VOXEL (set by
// the pass). No hit: discard.
//
// Limit: levels up to 16 (the stack depth).

override MAX_STEPS: u32 = 4096u;

const STACK_DEPTH: u32 = 16u;
//#include "svo_nodes.inc.wgsl"

// Pass-private: the frame's ray counters (ray_cast.inc.wgsl).
@group(1) @binding(9) var<storage, read_write> ray_counters: array<atomic<u32>>;

//#include "ray_cast.inc.wgsl"
//#include "ray_cast_compute.inc.wgsl"

// Octree descent of one instance; only hits nearer than `t_best` count.
fn trace(inst: Instance, o: vec3<f32>, d: vec3<f32>, t_best: f32) -> Hit {
    var out = Hit(false, t_best, 0u, 0u);
    let target_level = inst.level;
    let base = lod_info(inst.lod).object * SVO_STRIDE;
    if target_level > STACK_DEPTH || arrayLength(&svo_level_offsets) < base + SVO_STRIDE {
        return out;
    }
    // An empty octree has no root.
    if svo_level_offsets[base + 1u] == svo_level_offsets[base] {
        return out;
    }
    let n = i32(1u << target_level);
    let s_target = cell_size(target_level);
    // Mirrored frame: om, da >= 0 on moving axes.
    var mirror_bits = 0u;
    var moving = vec3(false);
    var om = o;
    var da = vec3(1.0);
    var t_enter = -1e30;
    var t_exit = 1e30;
    var enter_axis = 0u;
    // Target-level cell of the origin on axes the ray does not move along.
    var fixed_cell = vec3(0);
    for (var a = 0u; a < 3u; a++) {
        if d[a] == 0.0 {
            if o[a] < -1.0 || o[a] > 1.0 {
                return out;
            }
            fixed_cell[a] = axis_cell(o[a], s_target, n);
        } else {
            moving[a] = true;
            if d[a] < 0.0 {
                mirror_bits |= 1u << a;
                om[a] = -o[a];
            }
            da[a] = abs(d[a]);
            let te = plane_t(0, 2.0, om[a], da[a]);
            if te > t_enter || (te == t_enter && da[a] > da[enter_axis]) {
                t_enter = te;
                enter_axis = a;
            }
            t_exit = min(t_exit, plane_t(1, 2.0, om[a], da[a]));
        }
    }
    let t0 = max(t_enter, 0.0);
    if !(t0 <= t_exit) || t0 >= t_best {
        return out;
    }
    var face_axis = enter_axis;
    if t_enter < 0.0 {
        // Starts inside the grid: the dominant axis of the direction.
        let ad = abs(d);
        face_axis = select(select(2u, 1u, ad.y >= ad.z), 0u, ad.x >= ad.y && ad.x >= ad.z);
    }
    var t = t0;
    if target_level == 0u {
        out.hit = true;
        out.t = t;
        out.id = 0u;
        out.face = entered_face(face_axis, d);
        return out;
    }

    // Stack of the ancestors of the current node: node index, cell (mirrored frame) and
    // the child being visited in it; the current node's depth equals its level.
    var stack_node: array<u32, STACK_DEPTH>;
    var stack_cell: array<vec3<i32>, STACK_DEPTH>;
    var stack_child: array<u32, STACK_DEPTH>;
    var depth = 0u;
    var node = svo_level_offsets[base];
    var cell = vec3(0);
    var child = 0u;
    // Starting child of the root.
    for (var a = 0u; a < 3u; a++) {
        var bit = 0;
        if moving[a] {
            bit = select(0, 1, plane_t(1, 1.0, om[a], da[a]) <= t);
        } else {
            bit = (fixed_cell[a] >> (target_level - 1u)) & 1;
        }
        child |= u32(bit) << a;
    }
    var check = true;
    for (var step = 0u; step < MAX_STEPS; step++) {
        cast_steps += 1u;
        if t >= t_best {
            return out;
        }
        let s_child = cell_size(depth + 1u);
        if check {
            let nd = svo_node(node);
            cast_words += 2u;
            let orig = child ^ mirror_bits;
            if (nd.child_mask & (1u << orig)) != 0u {
                let child_node = nd.first_child + countOneBits(nd.child_mask & ((1u << orig) - 1u));
                let child_cell = cell * 2 + vec3(i32(child & 1u), i32((child >> 1u) & 1u), i32(child >> 2u));
                if depth + 1u == target_level {
                    out.hit = true;
                    out.t = t;
                    out.id = child_node - svo_level_offsets[base + target_level];
                    out.face = entered_face(face_axis, d);
                    return out;
                }
                // Push and descend at the current time.
                stack_node[depth] = node;
                stack_cell[depth] = cell;
                stack_child[depth] = child;
                depth += 1u;
                node = child_node;
                cell = child_cell;
                let s_grand = cell_size(depth + 1u);
                let shift = target_level - depth - 1u;
                child = 0u;
                for (var a = 0u; a < 3u; a++) {
                    var bit = 0;
                    if moving[a] {
                        bit = select(0, 1, plane_t(2 * cell[a] + 1, s_grand, om[a], da[a]) <= t);
                    } else {
                        bit = (fixed_cell[a] >> shift) & 1;
                    }
                    child |= u32(bit) << a;
                }
                continue;
            }
        }
        // Next plane of the current child per moving axis: its far plane (the node's mid
        // plane or, for an upper child, the node's far plane). Earliest first, ties: largest |d|.
        var a_next = 3u;
        var t_next = 1e30;
        for (var a = 0u; a < 3u; a++) {
            if moving[a] {
                let b = (child >> a) & 1u;
                let tn = plane_t(2 * cell[a] + 1 + i32(b), s_child, om[a], da[a]);
                if a_next == 3u || tn < t_next || (tn == t_next && da[a] > da[a_next]) {
                    a_next = a;
                    t_next = tn;
                }
            }
        }
        if a_next == 3u {
            return out;
        }
        if ((child >> a_next) & 1u) != 0u {
            // Leaves the node: pop (the parent steps across the same plane).
            if depth == 0u {
                return out;
            }
            depth -= 1u;
            node = stack_node[depth];
            cell = stack_cell[depth];
            child = stack_child[depth];
            check = false;
            continue;
        }
        child |= 1u << a_next;
        t = t_next;
        face_axis = a_next;
        check = true;
    }
    return out;
}
