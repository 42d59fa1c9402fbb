// The billboard of one SSBVB entry: its quad (the footprint, in slope space) and what a
// pixel of it writes. Shared by billboards.wgsl (rasterized quads) and
// splat_billboards.wgsl (the same quads splatted in compute), so both draw the same
// G-buffer; the geometry is explained in billboards.wgsl's header. Needs common.inc.wgsl.

// Scale of the quad about its middle relative to the footprint's bound.
override SIZE_SCALE: f32 = 1.0;
// Quad bound: true = the bounding rectangle of the cell's eight projected corners (exact
// and tightest), false = the exact bound of the circumscribed sphere's projection (cheaper:
// no corners, independent of the cell's orientation).
override BOX_FOOTPRINT: bool = true;
// Back-face culling by the voxel's stored normal n: a billboard is dropped when
// dot(n, towards the camera) < CULL_COS (-2 disables culling; see billboards.rs).
override CULL_COS: f32 = -2.0;

// A billboard's quad: the rectangle [mid - half, mid + half] in slope space (x / -z,
// y / -z) in the orthonormal frame (axis, perp(axis)), in the view plane z = cz.
struct Quad {
    // False: culled by CULL_COS (or a bad slot): nothing is drawn.
    valid: bool,
    // The camera is within about a cell of the voxel: the quad covers the screen and every
    // pixel intersects its ray with the voxel's box.
    near_field: bool,
    axis: vec2<f32>,
    mid: vec2<f32>,
    half: vec2<f32>,
    // View-space depth of the quad's plane (negative in front of the camera).
    cz: f32,
    // The voxel centre, camera-relative world.
    c: vec3<f32>,
}

// Min and max of x / -z over a sphere's disk (centre (a, z), radius r) in one view plane;
// needs z + r < 0 (then both denominators are positive: t|z| > r|a|).
fn sphere_slopes(a: f32, z: f32, r: f32) -> vec2<f32> {
    let t = sqrt(max(a * a + z * z - r * r, 0.0));
    let s0 = (t * a - r * z) / -(t * z + r * a);
    let s1 = (t * a + r * z) / -(t * z - r * a);
    return vec2(min(s0, s1), max(s0, s1));
}

// Radius of the sphere around a cell of world-space edge vectors a, b, c (the columns of
// object_to_world times the cell size): half the longest of the four diagonals.
fn circumradius(m: mat4x4<f32>, size: f32) -> f32 {
    let a = m[0].xyz;
    let b = m[1].xyz;
    let c = m[2].xyz;
    let l = max(max(length(a + b + c), length(a + b - c)), max(length(a - b + c), length(b + c - a)));
    return 0.5 * size * l;
}

// The centre of entry `slot`'s cell in object space.
fn slot_centre_object(slot: VoxelSlot) -> vec3<f32> {
    // The voxel's level rides in the slot (a coarser LOD's voxel where a page was missing).
    let level = slot.voxel.uv;
    return cell_min(voxel_cell(slot.voxel), level) + 0.5 * cell_size(level);
}

// The centre of entry `slot`'s cell, camera-relative world (the quad's `c`).
fn slot_centre_world(inst: Instance, slot: VoxelSlot) -> vec3<f32> {
    return (inst.object_to_world * vec4(slot_centre_object(slot), 1.0)).xyz;
}

// The quad of SSBVB entry `slot`.
fn billboard_quad(slot: VoxelSlot) -> Quad {
    var q: Quad;
    q.valid = false;
    q.near_field = false;
    if slot.instance >= u32(frame.shine_near_far_count.w) {
        return q;
    }
    let inst = instances[slot.instance];
    let size = cell_size(slot.voxel.uv);
    let centre_obj = slot_centre_object(slot);
    // The centre in view space straight from object space (f64-composed matrix): exact
    // lateral offsets however far the instance is; `c` (world) for what needs no more.
    let cv_exact = (inst.object_to_view * vec4(centre_obj, 1.0)).xyz;
    let c = slot_centre_world(inst, slot);
    let n = voxel_normal_world(inst, slot.voxel);
    if dot(n, -c) < CULL_COS * length(c) {
        return q;
    }
    let r = circumradius(inst.object_to_world, size);
    let view3 = mat3x3(frame.view[0].xyz, frame.view[1].xyz, frame.view[2].xyz);
    let cv = cv_exact;
    let near = frame.shine_near_far_count.y;
    q.valid = true;
    q.cz = cv.z;
    q.c = c;
    if cv.z + r >= -near * 1.001 || !(r > 0.0) {
        // Near field: a screen-covering quad at the centre's depth (clamped), each fragment
        // tests its ray against the box.
        q.near_field = true;
        return q;
    }
    // The quad in slope space (x / -z, y / -z) is the rectangle [lo, hi] in the orthonormal
    // frame (axis, perp(axis)).
    var axis = vec2(1.0, 0.0);
    var lo: vec2<f32>;
    var hi: vec2<f32>;
    if BOX_FOOTPRINT {
        // The eight corners of the cell, all in front of the near plane (they lie on the
        // sphere, which is).
        let m = inst.object_to_world;
        let e0 = view3 * (m[0].xyz * (0.5 * size));
        let e1 = view3 * (m[1].xyz * (0.5 * size));
        let e2 = view3 * (m[2].xyz * (0.5 * size));
        var proj: array<vec2<f32>, 8>;
        for (var k = 0u; k < 8u; k++) {
            let sgn = vec3(f32(k & 1u), f32((k >> 1u) & 1u), f32((k >> 2u) & 1u)) * 2.0 - 1.0;
            let p = cv + sgn.x * e0 + sgn.y * e1 + sgn.z * e2;
            proj[k] = p.xy / -p.z;
        }
        // The smallest of the bounding rectangles aligned with the screen or with one of
        // the cell's projected edges (the hull of a projected box is bounded by edges of
        // these directions, so the best of them is the tightest rectangle or close to it).
        // Every candidate bounds all eight corners: whichever wins, the quad covers the
        // cell's projection.
        var best = 3.0e38;
        for (var c = 0u; c < 4u; c++) {
            var u = vec2(1.0, 0.0);
            if c > 0u {
                let e = proj[1u << (c - 1u)] - proj[0];
                let l = length(e);
                if !(l > 1e-12) {
                    continue;
                }
                u = e / l;
            }
            let v = vec2(-u.y, u.x);
            var c_lo = vec2(3.0e38);
            var c_hi = vec2(-3.0e38);
            for (var k = 0u; k < 8u; k++) {
                let q = vec2(dot(proj[k], u), dot(proj[k], v));
                c_lo = min(c_lo, q);
                c_hi = max(c_hi, q);
            }
            let ext = c_hi - c_lo;
            if ext.x * ext.y < best {
                best = ext.x * ext.y;
                axis = u;
                lo = c_lo;
                hi = c_hi;
            }
        }
    } else {
        let sx = sphere_slopes(cv.x, cv.z, r);
        let sy = sphere_slopes(cv.y, cv.z, r);
        lo = vec2(sx.x, sy.x);
        hi = vec2(sx.y, sy.y);
    }
    let mid = (lo + hi) * 0.5;
    // Plus 1/1024 pixel, so that a quad edge through a pixel centre (axis-aligned views)
    // still covers it: every billboard must cover at least its own pixel.
    let guard = 2.0 * length(frame.cam_up.xyz) * frame.screen.w / 1024.0;
    q.axis = axis;
    q.mid = mid;
    q.half = (hi - lo) * (0.5 * SIZE_SCALE) + guard;
    return q;
}

// Pixels by which a rasterized quad is widened and then trimmed back per fragment with
// `quad_covers`: the rasterizer snaps vertices to its sub-pixel grid (Vulkan guarantees
// 1/16 pixel or finer), which moves a quad's edge by up to 1/32 pixel, more than its
// guard. Voxels smaller than a pixel lost their own pixel to that (docs/benchmarks.md).
const RASTER_MARGIN: f32 = 0.0625;

// The slope (x / -z, y / -z in view space) of the ray through pixel position `px`,
// straight from its NDC position (not from a normalized direction, whose f32 components
// cannot resolve the slopes of a 0.0002-degree lens).
fn pixel_slope(px: vec2<f32>) -> vec2<f32> {
    // (The frame's jitter included: the rasterizer drew the jittered projection.)
    return pixel_ndc(px) * vec2(length(frame.cam_right.xyz), length(frame.cam_up.xyz));
}

// Whether pixel position `px` lies in the rectangle of a (not near-field) quad, in the
// frame (axis, perp(axis)) of slope space.
fn quad_covers(q: Quad, px: vec2<f32>) -> bool {
    let s = pixel_slope(px);
    let local = vec2(dot(s, q.axis), dot(s, vec2(-q.axis.y, q.axis.x))) - q.mid;
    return all(abs(local) <= q.half);
}

// The view-space point of the quad at `uv` in [0, 1]^2 (its corners at 0 and 1).
fn quad_point_view(q: Quad, uv: vec2<f32>) -> vec3<f32> {
    let p = q.mid + (uv * 2.0 - 1.0) * q.half;
    let s = p.x * q.axis + p.y * vec2(-q.axis.y, q.axis.x);
    return vec3(s * -q.cz, q.cz);
}

// A ray against a closed box.
struct BoxHit {
    hit: bool,
    // Ray parameter of the entry point (0 when the origin is inside).
    t: f32,
    // Entered face (VoxelSlot.face numbering: axis for the low side, 3 + axis for the high);
    // on a miss, the face the rule below picks all the same (a Flat billboard's pixel
    // beside its voxel's silhouette still gets a face of that voxel).
    face: u32,
}

// Slab test of the ray o + t d (t >= 0) against the closed box [lo, hi], with the CPU
// reference's face rule: the entered face is on the axis whose slab is entered last; on a
// tie the axis along which the ray moves fastest, then the lower axis; from inside, the
// dominant axis of d. The normal of the face points against the ray.
fn ray_box(o: vec3<f32>, d: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> BoxHit {
    var t_near = -3.0e38;
    var t_far = 3.0e38;
    var axis = 0u;
    var entered = false;
    var inside_axis = 0u;
    // Parallel to a slab and outside it: never inside the box.
    var outside = false;
    for (var a = 0u; a < 3u; a++) {
        let da = d[a];
        if abs(da) > abs(d[inside_axis]) {
            inside_axis = a;
        }
        if abs(da) < 1e-30 {
            outside = outside || o[a] < lo[a] || o[a] > hi[a];
            continue;
        }
        let t0 = (lo[a] - o[a]) / da;
        let t1 = (hi[a] - o[a]) / da;
        let enter = min(t0, t1);
        t_far = min(t_far, max(t0, t1));
        if !entered || enter > t_near || (enter == t_near && abs(da) > abs(d[axis])) {
            t_near = enter;
            axis = a;
            entered = true;
        }
    }
    if !entered || t_near < 0.0 {
        axis = inside_axis;
    }
    let face = select(axis + 3u, axis, d[axis] > 0.0);
    let hit = !outside && t_near <= t_far && t_far >= 0.0;
    return BoxHit(hit, select(0.0, max(t_near, 0.0), hit), face);
}

// The pixel's ray (from the eye, camera-relative) against a slot's voxel box.
fn slot_ray_box(slot: VoxelSlot, px: vec2<f32>) -> BoxHit {
    let inst = instances[slot.instance];
    let dir = pixel_ray(px);
    let m = inst.world_to_object;
    // Not renormalized: the object-space ray parameter is the world distance.
    let d = (m * vec4(dir, 0.0)).xyz;
    let o = m[3].xyz;
    let lo = cell_min(voxel_cell(slot.voxel), slot.voxel.uv);
    return ray_box(o, d, lo, lo + cell_size(slot.voxel.uv));
}

// What one pixel of a billboard writes into the G-buffer.
struct Fragment {
    covered: bool,
    albedo: vec4<f32>,
    // Shading normal (the voxel's stored one), w = 1.
    normal: vec4<f32>,
    position: vec4<f32>,
    // Geometric normal (the entered face's), octahedral.
    geometric: vec2<f32>,
    // Reversed-Z depth.
    depth: f32,
}

// The depth of a (not near-field) quad's plane, in [0, 1]: one depth for the whole quad,
// as the rasterizer interpolates it.
fn flat_quad_depth(q: Quad) -> f32 {
    let clip = frame.proj * vec4(0.0, 0.0, q.cz, 1.0);
    return clamp(clip.z / clip.w, 0.0, 1.0);
}

// A Flat billboard's pixel (the paper): on the quad at `world` (camera-relative; the quad
// plane's point under the pixel), or for a near-field quad the pixel's ray against the box
// (depth: the quad's, at the voxel centre).
fn flat_fragment(slot: VoxelSlot, q: Quad, px: vec2<f32>, world_on_quad: vec3<f32>) -> Fragment {
    var f: Fragment;
    f.covered = true;
    var world = world_on_quad;
    f.depth = flat_quad_depth(q);
    let h = slot_ray_box(slot, px);
    if q.near_field {
        if !h.hit {
            f.covered = false;
            return f;
        }
        world = pixel_ray(px) * h.t;
        f.depth = ndc_depth(q.c);
    }
    let inst = instances[slot.instance];
    f.albedo = vec4(voxel_color(slot.voxel).rgb, 1.0);
    f.normal = vec4(voxel_normal_world(inst, slot.voxel), 1.0);
    f.position = vec4(world, dot(world, frame.cam_forward.xyz));
    f.geometric = oct_encode(face_normal_world(inst, h.face));
    return f;
}

// A ray-box billboard's pixel: exact coverage, depth and entered face.
fn ray_box_fragment(slot: VoxelSlot, px: vec2<f32>) -> Fragment {
    let h = slot_ray_box(slot, px);
    if !h.hit {
        var f: Fragment;
        f.covered = false;
        return f;
    }
    return hit_fragment(slot, px, h.t, h.face);
}

// What pixel `px` writes where its ray meets `slot`'s voxel at distance `t` through face
// `face`.
fn hit_fragment(slot: VoxelSlot, px: vec2<f32>, t: f32, face: u32) -> Fragment {
    var f: Fragment;
    f.covered = true;
    let inst = instances[slot.instance];
    let dir = pixel_ray(px);
    let p = dir * t;
    f.albedo = vec4(voxel_color(slot.voxel).rgb, 1.0);
    f.normal = vec4(voxel_normal_world(inst, slot.voxel), 1.0);
    f.position = vec4(p, t * dot(dir, frame.cam_forward.xyz));
    f.geometric = oct_encode(face_normal_world(inst, face));
    f.depth = ndc_depth(p);
    return f;
}

// A Pixel entry's fragment at its own pixel `px`: the filter's hit, at its distance along
// the pixel's ray with its entered face, as the ray casters' resolve writes a hit (no box
// test: the march found the face).
fn pixel_fragment(slot: VoxelSlot, px: vec2<f32>) -> Fragment {
    return hit_fragment(slot, px, slot.t, slot.face);
}
