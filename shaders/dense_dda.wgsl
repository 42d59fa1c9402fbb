//#include "common.inc.wgsl"
// Dense DDA (baseline): per pixel, a fullscreen triangle whose fragment casts the pixel's
// ray through every visible instance with a plain cell-by-cell Amanatides–Woo DDA over a
// dense 3D texture (`dense`, group 1: voxel id + 1 per cell, 0 = empty) of the chosen LOD,
// and keeps the nearest hit. No empty-space skipping: this is the baseline the SSBVB
// filter is compared with.
//
// The ray is moved into object space with the instance's `world_to_object`; the direction
// is not renormalized, so the ray parameter stays the world distance from the eye. As in
// the CPU reference (ssbvb_voxel::reference::dda) crossing times are computed per plane,
// `t_k = (b_k - o) / d` with exact dyadic boundaries `b_k`, and axes with a negative
// direction are mirrored so the loop only steps forward. The entered face is the axis the
// DDA last stepped on (at the entry into the grid: the axis of the latest slab entry; a ray
// starting inside a voxel uses the dominant axis of the direction). Exact f32 ties between
// axes (rays through voxel edges) step the axis of the largest |d| first, which may pick a
// different one of the touched cells than the f64 reference's tie rule.
//
// Outputs (as billboards.wgsl's RayBox mode): location 0 albedo (the voxel colour, alpha 1),
// 1 the voxel's stored normal, 2 camera-relative world position (xyz) and linear view
// depth (w), 3 the entered face's normal (octahedral); frag_depth the reversed-Z depth of the hit point;
// stencil = STENCIL_VOXEL (set by the pass). No hit: discard.
//
// The dense grids of every visible (object, level) pair are stacked along z in one atlas;
// `dense_slices[lod]` is where the instance's LOD starts (0xffffffff: not there).

override MAX_STEPS: u32 = 4096u;

@group(1) @binding(0) var dense: texture_3d<u32>;
@group(1) @binding(1) var<storage, read> dense_slices: array<u32>;

// Pass-private: the frame's ray counters (ray_cast.inc.wgsl).
@group(1) @binding(2) var<storage, read_write> ray_counters: array<atomic<u32>>;

//#include "ray_cast.inc.wgsl"

// Cell-by-cell DDA of one instance; only hits nearer than `t_best` count.
fn trace(inst: Instance, o: vec3<f32>, d: vec3<f32>, t_best: f32) -> Hit {
    var out = Hit(false, t_best, 0u, 0u);
    let z0 = dense_slices[inst.lod];
    if z0 == 0xffffffffu {
        return out;
    }
    let level = inst.level;
    let n = i32(1u << level);
    let s = cell_size(level);
    // Mirrored frame: om, da >= 0 on moving axes.
    var mirrored = vec3(false);
    var moving = vec3(false);
    var om = o;
    var da = vec3(1.0);
    var t_enter = -1e30;
    var t_exit = 1e30;
    var enter_axis = 0u;
    for (var a = 0u; a < 3u; a++) {
        if d[a] == 0.0 {
            if o[a] < -1.0 || o[a] > 1.0 {
                return out;
            }
        } else {
            moving[a] = true;
            mirrored[a] = d[a] < 0.0;
            om[a] = select(o[a], -o[a], mirrored[a]);
            da[a] = abs(d[a]);
            let te = plane_t(0, s, om[a], da[a]);
            if te > t_enter || (te == t_enter && da[a] > da[enter_axis]) {
                t_enter = te;
                enter_axis = a;
            }
            t_exit = min(t_exit, plane_t(n, s, om[a], da[a]));
        }
    }
    let t0 = max(t_enter, 0.0);
    if !(t0 <= t_exit) || t0 >= t_best {
        return out;
    }
    // Starting cell (mirrored frame) and next plane per moving axis.
    var cell = vec3(0);
    var t_next = vec3(1e30);
    for (var a = 0u; a < 3u; a++) {
        // A static axis keeps the origin's cell (the ray stays at the origin there).
        var i = axis_cell(o[a], s, n);
        if moving[a] {
            i = clamp(i32(floor((om[a] + t0 * da[a] + 1.0) / s)), 0, n - 1);
            // Settle on exact crossing times: the cell whose far plane is crossed after t0.
            for (var k = 0; k < 4; k++) {
                if i < n - 1 && plane_t(i + 1, s, om[a], da[a]) <= t0 {
                    i += 1;
                } else if i > 0 && plane_t(i, s, om[a], da[a]) > t0 {
                    i -= 1;
                }
            }
            t_next[a] = plane_t(i + 1, s, om[a], da[a]);
        }
        cell[a] = i;
    }
    var t = t0;
    var face_axis = enter_axis;
    if t_enter < 0.0 {
        // Starts inside the grid: the dominant axis of the direction.
        let ad = abs(d);
        face_axis = select(select(2u, 1u, ad.y >= ad.z), 0u, ad.x >= ad.y && ad.x >= ad.z);
    }
    for (var step = 0u; step < MAX_STEPS; step++) {
        cast_steps += 1u;
        if t >= t_best {
            return out;
        }
        let orig = select(cell, vec3(n - 1) - cell, mirrored);
        let v = textureLoad(dense, vec3<u32>(orig) + vec3(0u, 0u, z0), 0).x;
        cast_words += 1u;
        if v != 0u {
            out.hit = true;
            out.t = t;
            out.id = v - 1u;
            out.face = entered_face(face_axis, d);
            return out;
        }
        // Step the axis with the earliest next crossing (ties: largest |d|).
        var a = 0u;
        for (var b = 1u; b < 3u; b++) {
            if t_next[b] < t_next[a] || (t_next[b] == t_next[a] && da[b] > da[a]) {
                a = b;
            }
        }
        if !moving[a] || t_next[a] > t_exit {
            return out;
        }
        t = t_next[a];
        cell[a] += 1;
        if cell[a] >= n {
            return out;
        }
        t_next[a] = plane_t(cell[a] + 1, s, om[a], da[a]);
        face_axis = a;
    }
    return out;
}
