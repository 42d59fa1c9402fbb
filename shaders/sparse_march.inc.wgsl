// The sparse march: the first voxel along a ray through one LOD's sparse lookup (the
// 64-ary occupancy tree `lookup_nodes_*`, common.inc.wgsl), the GPU side of the CPU reference's
// hierarchical DDA. Included by ray_march_filter.wgsl; the includer declares
// `override MAX_STEPS: u32`, `override FAST_MARCH: bool` and `override PAGED: bool` (false:
// no LOD of the scene has pages, and the page code is left out).
//
// The rules (f32), following the CPU reference (ssbvb-voxel reference/dda.rs):
//
// - Space: the instance's object space; the ray is `camera_object + t * d` with
//   `d = world_to_object * dir` and `dir` the normalized camera-relative world ray, so `t`
//   is the world distance for every instance (no renormalization).
// - Axes with `d < 0` are mirrored (`x -> -x`, cell `i -> n - 1 - i`; exact with dyadic
//   cell boundaries), so the loop only steps forward. Axes with a negligible `d` component
//   are static (the ray stays in one cell on them). A ray exactly in an inner cell plane of
//   a static axis touches the cells on both sides: `march_lod` marches each side (two or
//   four marches, only for such rays) and keeps the reference's choice.
// - Crossing times are computed per plane (`(b_k - o) / d`, never accumulated), exactly
//   like the reference: times are monotone in `k` and two axes tie only when their
//   computed times are equal. Cells are never derived from a rounded position alone: a
//   position estimate is corrected against the plane times (`first_plane`), so the cell a
//   ray is in always agrees with the times, and every step advances at least one plane
//   (guaranteed progress).
// - Hierarchy: in an absent child of the lookup tree (an empty region of 4^m cells per
//   axis, m >= 1) the ray jumps to the first time it reaches the region's far boundary,
//   landing in the state the cell-by-cell loop would reach there. The nodes on the path
//   to the current cell are kept, so a step reads only the nodes below the deepest one
//   that still contains the new cell (usually one: the 4^3 leaf).
// - Ties (the ray crosses several planes at the same time, i.e. passes exactly through an
//   edge or a corner): the cell entered diagonally is tested first, then the cells the ray
//   only touches along the edge, in the reference's rank order; the same where the march
//   starts on inner planes (`start_tie`). tests/tests/gpu/ties.rs holds every rule per
//   pixel on lattice rays.
// - Hit: the voxel's touch time (the latest of its near-plane crossing times, at least 0)
//   and the entered face (the axis crossed at that time; ties to the faster axis; a camera
//   inside the voxel gets the dominant axis of the direction).
// - Pages (under a GPU budget, LodInfo.page_base != NO_PAGES): a page node whose page is
//   not resident ends the march with `missing` set and `t` the time the ray entered the
//   cell it was in; `march_resident` goes on from there in the next coarser LOD. In the
//   instance's own LOD the march first looks past it (up to MISSING_LOOKAHEAD missing
//   pages, skipped as if empty) only to request those pages too, as "ahead" (loaded when
//   there is room, first to leave). Every page node the march enters sets its page's bit
//   in `page_feedback`: "missing" (only when `record`, i.e. in the instance's own LOD) or
//   "touched" (for the page cache's LRU).
// - Every loop iteration counts one step (cells and skipped regions alike); after
//   MAX_STEPS the ray reports no hit.
//
// The fast march (FAST_MARCH, `RayMarchFilter(march: Fast)`) drops the rules that keep the
// march bit-identical with the reference and costs a little accuracy
// (docs/benchmarks.md): every plane time, the box's faces included, is a product with the
// reciprocal direction (one rounding, the same for every plane, so times stay monotone and
// consistent with the cells; accumulating them instead drifted by more than a grazing
// ray's margin), the start cell's position estimate is corrected against the plane times
// by one plane at most (uncorrected, a rounding put rays a cell inside the box: false
// hits), the cells after an empty region are the position estimate (a rounding there
// misplaces a ray by less than f32 resolves; progress still holds: every step crosses at
// least one plane), and a ray through an edge or corner tests only the cell it enters
// diagonally.

// Direction components below this fraction of the largest one are treated as 0: over the
// whole box the ray moves less than 4e-12 object units on that axis, far below a cell of
// any supported level (2^-15), and crossing times stay finite.
const STATIC_AXIS: f32 = 1e-12;
// Cameras farther than this (object units) from an instance see nothing of it (keeps every
// crossing time finite).
const MAX_ORIGIN: f32 = 1e12;

// Loop iterations of every march since the includer last reset it (its counters).
var<private> march_steps: u32;
// Words of lookup nodes every march read since the includer last reset it (3 per node; a
// tie cell's lookup from the root counts as the whole descent, an upper bound).
var<private> march_words: u32;

// Page feedback of the frame (streaming.rs): three sets of a bit per page of every paged
// LOD: the pages a march needed and did not find (FB_MISSING), the pages it entered
// (FB_TOUCHED), and the missing pages it found looking past the first (FB_AHEAD); cleared
// every frame. The includer declares it (`page_feedback: array<atomic<u32>>`): group 0's
// binding 3 is visible to compute shaders only, so a fragment shader binds it in its own
// group.

const FB_MISSING: u32 = 0u;
const FB_TOUCHED: u32 = 1u;
const FB_AHEAD: u32 = 2u;

// Sets bit `page` of set `which`, reading first so that a page many rays enter costs one
// atomic write.
fn note_page(which: u32, page: u32) {
    let w = which * (arrayLength(&page_feedback) / 3u) + (page >> 5u);
    let bit = 1u << (page & 31u);
    if w < arrayLength(&page_feedback) && (atomicLoad(&page_feedback[w]) & bit) == 0u {
        atomicOr(&page_feedback[w], bit);
    }
}

// The global page id of page node `node` (absolute index) of a paged LOD.
fn page_of(lod: LodInfo, node: u32) -> u32 {
    return lod.page_base + (node - lod.node_offset - lod.first_page_node);
}

// An object-space ray in the mirrored frame of one instance's LOD grid.
struct Ray {
    // Origin (negated on mirrored axes).
    o: vec3<f32>,
    // |direction| per axis; 0 on static axes.
    d: vec3<f32>,
    moving: vec3<bool>,
    mirrored: vec3<bool>,
    // Cells per axis and cell size of the grid.
    n: i32,
    s: f32,
    // 1 / s, exact (s is a power of two): a product instead of a division per step.
    cells_per_unit: f32,
    // The ray's interval inside the [-1, 1]^3 box (t_enter > t_exit: it misses).
    t_enter: f32,
    t_exit: f32,
    // FAST_MARCH: 1 / d on moving axes (1 on static ones).
    inv: vec3<f32>,
    // Static axes whose origin lies exactly in an inner cell plane where the march takes
    // the cell below that plane (else the one above).
    lower: vec3<bool>,
}

// The first voxel along a ray.
struct Hit {
    found: bool,
    // Voxel id in the LOD's point cloud.
    id: u32,
    // World distance to the entered face (0 when the camera is inside the voxel).
    t: f32,
    // Entered face, as VoxelSlot.face.
    face: u32,
    // The voxel's cell (grid coordinates).
    cell: vec3<u32>,
    // The LOD-table index of the LOD the voxel belongs to (set by march_resident).
    lod: u32,
    // The march stopped at a page that is not resident (then `t` is where).
    missing: bool,
    // The reference's ranks of the cell among those touched at `t` (bit a: rank 1 on axis
    // a, the cell before the one entered, or the upper cell on a static axis in a plane).
    rank: u32,
}

fn no_hit() -> Hit {
    return Hit(false, 0u, BIG, 0u, vec3(0u), 0u, false, 0u);
}

// The ray `o_obj + t * d_obj` in object space (`d_obj` not normalized: `t` keeps the
// world scale of the includer's direction).
fn make_ray_od(o_obj: vec3<f32>, d_obj: vec3<f32>, level: u32) -> Ray {
    let ad = abs(d_obj);
    let m = max(ad.x, max(ad.y, ad.z));
    var r: Ray;
    r.moving = ad > vec3(m * STATIC_AXIS);
    r.mirrored = r.moving & (d_obj < vec3(0.0));
    r.o = select(o_obj, -o_obj, r.mirrored);
    r.d = select(vec3(0.0), ad, r.moving);
    r.n = 1 << level;
    r.s = cell_size(level);
    r.cells_per_unit = f32(1u << level) * 0.5;
    r.inv = 1.0 / select(vec3(1.0), r.d, r.moving);
    r.lower = vec3(false);
    // Slab test; static axes divide by 1 and are then replaced (no 0 / 0).
    // The fast march multiplies by the same reciprocals as its plane times, so the box's
    // faces are crossed at the times of planes 0 and n (a box entry computed by division
    // could fall a rounding before plane 0 and put the ray one cell in).
    let dd = select(vec3(1.0), r.d, r.moving);
    let t0_div = (vec3(-1.0) - r.o) / dd;
    let t1_div = (vec3(1.0) - r.o) / dd;
    let t0 = select(vec3(-BIG), select(t0_div, (vec3(-1.0) - r.o) * r.inv, FAST_MARCH), r.moving);
    let t1 = select(vec3(BIG), select(t1_div, (vec3(1.0) - r.o) * r.inv, FAST_MARCH), r.moving);
    r.t_enter = max(t0.x, max(t0.y, t0.z));
    r.t_exit = min(t1.x, min(t1.y, t1.z));
    let bad = !(m > 0.0 && m < BIG) || any(!(abs(o_obj) < vec3(MAX_ORIGIN)))
        || any(!r.moving & (abs(r.o) > vec3(1.0)));
    if bad {
        r.t_enter = BIG;
        r.t_exit = -BIG;
    }
    return r;
}

// Time at which the ray crosses plane `k` (at -1 + k * s) of moving axis `a`.
fn plane_t(r: Ray, a: u32, k: i32) -> f32 {
    if FAST_MARCH {
        return ((f32(k) * r.s - 1.0) - r.o[a]) * r.inv[a];
    }
    return ((f32(k) * r.s - 1.0) - r.o[a]) / r.d[a];
}

// The fast march's `plane_t` of plane `k[a]` on every axis at once (meaningless on static
// axes: the caller masks them).
fn plane_t_all(r: Ray, k: vec3<i32>) -> vec3<f32> {
    return ((vec3<f32>(k) * r.s - 1.0) - r.o) * r.inv;
}

fn plane_ok(r: Ray, a: u32, k: i32, t: f32, strict: bool) -> bool {
    let tk = plane_t(r, a, k);
    return select(tk >= t, tk > t, strict);
}

// The smallest plane `k` in [lo, hi] of moving axis `a` crossed at or after `t` (strictly
// after when `strict`), or hi + 1. The position estimate is right but for rounding; a
// binary search fixes whatever it got wrong (far cameras round positions coarsely).
fn first_plane(r: Ray, a: u32, t: f32, lo_in: i32, hi_in: i32, strict: bool) -> i32 {
    var lo = lo_in;
    var hi = hi_in + 1;
    if lo >= hi {
        return lo;
    }
    let x = (r.o[a] + t * r.d[a] + 1.0) * r.cells_per_unit;
    let xs = select(f32(lo), x, x == x);
    let est = i32(clamp(ceil(xs), f32(lo), f32(hi - 1)));
    if FAST_MARCH && !strict {
        // After an empty region: the estimate (its error is a rounding of the position).
        return est;
    }
    if plane_ok(r, a, est, t, strict) {
        if est == lo || !plane_ok(r, a, est - 1, t, strict) {
            return est;
        }
        hi = est - 1;
    } else {
        if est + 1 >= hi || plane_ok(r, a, est + 1, t, strict) {
            return est + 1;
        }
        lo = est + 2;
    }
    if FAST_MARCH {
        // Off by more than one plane (a far camera's coarse positions): the nearest
        // candidate on the side the estimate erred; no search.
        return select(lo, hi, hi < est);
    }
    loop {
        if lo >= hi {
            break;
        }
        let mid = lo + (hi - lo) / 2;
        if plane_ok(r, a, mid, t, strict) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    return lo;
}

// A mirrored-frame cell in the grid's own coordinates.
fn orig_cell(r: Ray, c: vec3<i32>) -> vec3<u32> {
    return vec3<u32>(select(c, vec3(r.n - 1) - c, r.mirrored));
}

// The hit record of occupied cell `c` (mirrored frame): its touch time and entered face.
fn cell_hit(r: Ray, c: vec3<i32>, id: u32) -> Hit {
    var t = -BIG;
    var axis = 3u;
    for (var a = 0u; a < 3u; a++) {
        if r.moving[a] {
            let ta = plane_t(r, a, c[a]);
            if axis == 3u || ta > t || (ta == t && r.d[a] > r.d[axis]) {
                t = ta;
                axis = a;
            }
        }
    }
    if t < 0.0 {
        // The camera is inside the voxel: the dominant axis of the direction.
        t = 0.0;
        if r.d.x >= r.d.y && r.d.x >= r.d.z {
            axis = 0u;
        } else if r.d.y >= r.d.z {
            axis = 1u;
        } else {
            axis = 2u;
        }
    }
    // The entered face's normal points against the ray: -axis (0..2) when moving towards
    // +axis, +axis (3..5) on mirrored axes.
    return Hit(true, id, t, axis + select(0u, 3u, r.mirrored[axis]), orig_cell(r, c), 0u, false, 0u);
}

// The time the ray entered cell `c` (mirrored frame), at least `t0`.
fn cell_entry_t(r: Ray, c: vec3<i32>, t0: f32) -> f32 {
    var t = t0;
    for (var a = 0u; a < 3u; a++) {
        if r.moving[a] {
            t = max(t, plane_t(r, a, c[a]));
        }
    }
    return t;
}

// `lookup_cell` for the march: a cell in a page that is not resident is empty, and the
// page is noted as missing when `record`.
fn march_cell(lod: LodInfo, cell: vec3<u32>, record: bool) -> u32 {
    march_words += 3u * lod.depth;
    let v = lookup_cell_paged(lod, cell);
    if record && v.y != PAGE_MISSING {
        note_page(FB_MISSING, page_of(lod, v.y));
    }
    return v.x;
}

// Missing pages one ray of an instance's own LOD requests per frame at most (it marches
// past the first ones to find them).
const MISSING_LOOKAHEAD: u32 = 4u;

fn missing_hit(t: f32) -> Hit {
    var h = no_hit();
    h.missing = true;
    h.t = t;
    return h;
}

// `h`, unless a missing page came first (`missing_t >= 0`): then that.
fn found_or_missing(h: Hit, missing_t: f32) -> Hit {
    if missing_t >= 0.0 {
        return missing_hit(missing_t);
    }
    return h;
}

// Marches `r` through `lod` from `t_from` (clamped to the box) up to `t_limit`; a page that
// is not resident is noted as missing when `record`.
fn march(r: Ray, lod: LodInfo, t_from: f32, t_limit: f32, record: bool) -> Hit {
    let t0 = max(max(r.t_enter, t_from), 0.0);
    let t_end = min(r.t_exit, t_limit);
    if !(t0 <= t_end) {
        return no_hit();
    }
    // The cell at t0 on each axis: the one the ray is inside of just after t0.
    var c = vec3(0);
    var t_next = vec3(BIG);
    for (var a = 0u; a < 3u; a++) {
        if r.moving[a] {
            let k = first_plane(r, a, t0, 0, r.n, true);
            c[a] = clamp(k - 1, 0, r.n - 1);
            t_next[a] = select(BIG, plane_t(r, a, k), k <= r.n);
        } else {
            let k = static_plane(r, a);
            c[a] = select(axis_cell(r.o[a], r.s, r.n), k - i32(r.lower[a]), k > 0);
        }
    }
    if !FAST_MARCH {
        let h = start_tie(r, lod, c, t0, record);
        if h.found {
            return h;
        }
    }
    // The leaf (4^3 cells) and its parent (16^3) that held the last cell visited, kept in
    // registers (a per-lane array would live in memory): most steps stay in the leaf, and
    // most of the others in its parent, so a step reads at most the nodes below the
    // parent, and the root path only when the ray enters a new 16^3 region.
    let depth = lod.depth;
    // Where the first missing page was entered (-1: none yet), and how many were met.
    var missing_t = -1.0;
    var missing_pages = 0u;
    var leaf_key = vec3(0xffffffffu);
    var leaf: LookupNode;
    var parent_key = vec3(0xffffffffu);
    var parent = 0u;
    // The same for the node of the 64^3 region above the parent, and the root's contents:
    // a ray leaving a 16^3 region mostly stays in its 64^3 one, and every descent from the
    // root would otherwise read the root again.
    var grand_key = vec3(0xffffffffu);
    var grand = 0u;
    let root = lookup_node(lod, lod.node_offset);
    march_words += 3u;
    // A crossing through an edge or corner (the exact march) leaves the step loop with the
    // axes crossed in `tie_crossed`; the cells it touches are tested after that loop, which
    // then goes on. In the loop, that test would cost llvmpipe (which runs a branch no lane
    // takes, masked) a lookup descent per step of every ray (docs/benchmarks.md).
    var step = 0u;
    loop {
        var tie_crossed = 0u;
        loop {
            if step >= MAX_STEPS {
                break;
            }
            step += 1u;
            march_steps += 1u;
            let co = orig_cell(r, c);
            // Descend: an absent child of 2^shift cells per axis is an empty region to skip,
            // twice as wide when its whole 2^3 octant of children is absent (the octant's eight
            // bits are one byte of the mask); an absent single cell is an ordinary DDA step; a
            // present cell is the hit.
            // log2 of the width in cells of the empty region the ray is in (0: none).
            var region_log = 0u;
            if any(co >> vec3(2u) != leaf_key) {
                var node = lod.node_offset;
                var k = 0u;
                if depth >= 2u && all(co >> vec3(4u) == parent_key) {
                    node = parent;
                    k = depth - 2u;
                } else if depth >= 3u && all(co >> vec3(6u) == grand_key) {
                    node = grand;
                    k = depth - 3u;
                }
                loop {
                    var n = root;
                    if k != 0u {
                        n = lookup_node(lod, node);
                        march_words += 3u;
                    }
                    let paged = PAGED && lod.page_base != NO_PAGES;
                    if k + 2u == depth && paged && n.base == PAGE_MISSING {
                        if !(missing_t >= 0.0) {
                            missing_t = cell_entry_t(r, c, t0);
                        }
                        if !record {
                            return missing_hit(missing_t);
                        }
                        // Request it, and look past it (as if it were empty) for the next
                        // missing pages of this ray, so that the pages a ray needs arrive in
                        // fewer frames; what lies past it is not a hit.
                        let which = select(FB_AHEAD, FB_MISSING, missing_pages == 0u);
                        note_page(which, page_of(lod, node));
                        missing_pages += 1u;
                        if missing_pages >= MISSING_LOOKAHEAD {
                            return missing_hit(missing_t);
                        }
                        region_log = 4u;
                        break;
                    }
                    if k + 1u == depth {
                        leaf = n;
                        leaf_key = co >> vec3(2u);
                        break;
                    }
                    let shift = 2u * (depth - 1u - k);
                    let b = child_bit((co >> vec3(shift)) & vec3(3u));
                    if !node_has(n, b) {
                        let octant = select(n.lo, n.hi, b >= 32u) >> (b & 24u);
                        let octant_empty = (octant & 0xffu) == 0u;
                        region_log = select(shift, shift + 1u, octant_empty);
                        break;
                    }
                    node = lod.node_offset + node_child(n, b);
                    k += 1u;
                    if k + 3u == depth {
                        grand = node;
                        grand_key = co >> vec3(6u);
                    }
                    if k + 2u == depth {
                        parent = node;
                        parent_key = co >> vec3(4u);
                        if PAGED && lod.page_base != NO_PAGES {
                            note_page(FB_TOUCHED, page_of(lod, node));
                        }
                    }
                }
            }
            if region_log == 0u {
                let b = child_bit(co & vec3(3u));
                if node_has(leaf, b) {
                    return found_or_missing(cell_hit(r, c, node_child(leaf, b)), missing_t);
                }
                let octant = select(leaf.lo, leaf.hi, b >= 32u) >> (b & 24u);
                let octant_empty = (octant & 0xffu) == 0u;
                region_log = select(0u, 1u, octant_empty);
            }
            if region_log != 0u && FAST_MARCH {
                // The same on all three axes at once (no per-axis branches); the cell after
                // the region is the position estimate (`first_plane`'s fast form).
                let lg = vec3(region_log);
                let u = vec3<i32>(co >> lg);
                let far = select(min((u + 1) << lg, vec3(r.n)), vec3(r.n) - (u << lg), r.mirrored);
                let t_far = select(vec3(BIG), plane_t_all(r, far), r.moving);
                let t_out = min(t_far.x, min(t_far.y, t_far.z));
                if t_out > t_end {
                    return found_or_missing(no_hit(), missing_t);
                }
                let x = (r.o + t_out * r.d + 1.0) * r.cells_per_unit;
                let lo = c + 1;
                let xs = select(vec3<f32>(lo), x, x == x);
                let k = vec3<i32>(clamp(ceil(xs), vec3<f32>(lo), vec3<f32>(far)));
                c = select(c, max(c, k - 1), r.moving);
                t_next = select(t_next, plane_t_all(r, k), r.moving);
            } else if region_log != 0u {
                // Empty region: its far plane per moving axis (mirrored frame), the first time
                // the ray reaches one of them, and the state just before that event.
                var far = vec3(0);
                var t_out = BIG;
                for (var a = 0u; a < 3u; a++) {
                    if r.moving[a] {
                        let u = i32(co[a] >> region_log);
                        let up = min((u + 1) << region_log, r.n);
                        far[a] = select(up, r.n - (u << region_log), r.mirrored[a]);
                        t_out = min(t_out, plane_t(r, a, far[a]));
                    }
                }
                if t_out > t_end {
                    return found_or_missing(no_hit(), missing_t);
                }
                for (var a = 0u; a < 3u; a++) {
                    if r.moving[a] {
                        let k = first_plane(r, a, t_out, c[a] + 1, far[a], false);
                        c[a] = max(c[a], k - 1);
                        t_next[a] = plane_t(r, a, k);
                    }
                }
            }
            // Step to the next event: every axis whose next plane is crossed first.
            let tm = min(t_next.x, min(t_next.y, t_next.z));
            if tm > t_end {
                return found_or_missing(no_hit(), missing_t);
            }
            let cross = r.moving & (t_next == vec3(tm));
            c += select(vec3(0), vec3(1), cross);
            if FAST_MARCH {
                let t_after = select(vec3(BIG), plane_t_all(r, c + 1), c + 1 <= vec3(r.n));
                t_next = select(t_next, t_after, cross);
            } else {
                for (var a = 0u; a < 3u; a++) {
                    if cross[a] {
                        t_next[a] = select(BIG, plane_t(r, a, c[a] + 1), c[a] + 1 <= r.n);
                    }
                }
            }
            if !FAST_MARCH && u32(cross.x) + u32(cross.y) + u32(cross.z) > 1u {
                tie_crossed = select(0u, 1u, cross.x) | select(0u, 2u, cross.y)
                    | select(0u, 4u, cross.z);
                break;
            }
            if any(c >= vec3(r.n)) {
                return found_or_missing(no_hit(), missing_t);
            }
        }
        if tie_crossed == 0u {
            break;
        }
        // Through an edge or corner: the diagonal cell, then the cells touched only along
        // the edge, in the reference's rank order (differ on x, y, z, xy, xz, yz). Masks 0,
        // 1, 2, 4, 3, 5, 6: i with 3 and 4 swapped (no array: llvmpipe would zero a
        // per-lane copy of it for every invocation of the includer).
        let crossed = tie_crossed;
        for (var i = 0u; i < 7u; i++) {
            let mask = select(i, 7u - i, i == 3u || i == 4u);
            if (mask & crossed) != mask {
                continue;
            }
            let back = vec3(i32(mask & 1u), i32((mask >> 1u) & 1u), i32((mask >> 2u) & 1u));
            let cand = c - back;
            if all(cand < vec3(r.n)) {
                let v = march_cell(lod, orig_cell(r, cand), record);
                if v != 0u {
                    var h = cell_hit(r, cand, v - 1u);
                    h.rank = mask;
                    return found_or_missing(h, missing_t);
                }
            }
        }
        if any(c >= vec3(r.n)) {
            return found_or_missing(no_hit(), missing_t);
        }
    }
    return found_or_missing(no_hit(), missing_t);
}

// A march that starts exactly on inner planes of moving axes (the box entered through an
// edge or corner, a camera in a cell plane) touches the cells before those planes at `t0`
// too: the start cell `c`, then those, in the reference's rank order (as at a crossing in
// `march`). No hit when no such plane, or none of them is occupied.
fn start_tie(r: Ray, lod: LodInfo, c: vec3<i32>, t0: f32, record: bool) -> Hit {
    var planes = 0u;
    for (var a = 0u; a < 3u; a++) {
        // The exact time only where the position is within its rounding of the plane (a
        // division per axis and march cost a tenth of the exact march).
        let u = (r.o[a] + t0 * r.d[a] + 1.0) * r.cells_per_unit;
        let slack = (abs(r.o[a]) + abs(t0 * r.d[a]) + 1.0) * r.cells_per_unit * 1e-6;
        if r.moving[a] && c[a] > 0 && abs(u - f32(c[a])) <= slack && plane_t(r, a, c[a]) == t0 {
            planes |= 1u << a;
        }
    }
    if planes == 0u {
        return no_hit();
    }
    for (var i = 0u; i < 8u; i++) {
        let mask = select(i, 7u - i, i == 3u || i == 4u);
        if (mask & planes) != mask {
            continue;
        }
        let cand = c - vec3(i32(mask & 1u), i32((mask >> 1u) & 1u), i32((mask >> 2u) & 1u));
        let v = march_cell(lod, orig_cell(r, cand), record);
        if v != 0u {
            var h = cell_hit(r, cand, v - 1u);
            h.rank = mask;
            return h;
        }
    }
    return no_hit();
}

// The inner plane (0 < k < n) of static axis `a` that the ray's origin lies in exactly, or
// -1.
fn static_plane(r: Ray, a: u32) -> i32 {
    let k = i32(round((r.o[a] + 1.0) * r.cells_per_unit));
    if r.moving[a] || k <= 0 || k >= r.n || f32(k) * r.s - 1.0 != r.o[a] {
        return -1;
    }
    return k;
}

// The reference's order of cells touched at one time: the smaller rank sum, then the
// smaller z rank, y rank, x rank (`rank` bits: x 1, y 2, z 4).
fn rank_key(rank: u32) -> u32 {
    return countOneBits(rank) * 8u + rank;
}

// `march` of the ray `o + t * d` through `lod`. A ray in an inner cell plane of a static
// axis touches the cells on both sides of it: each side is marched (both sides of two such
// planes: four marches) and the first hit kept, on a tie the reference's rank order.
fn march_lod(o: vec3<f32>, d: vec3<f32>, lod: LodInfo, t_from: f32, t_limit: f32, record: bool) -> Hit {
    var r = make_ray_od(o, d, lod.level);
    var planes = 0u;
    if !all(r.moving) {
        for (var a = 0u; a < 3u; a++) {
            if static_plane(r, a) > 0 {
                planes |= 1u << a;
            }
        }
    }
    // One call site of `march` (it is large; a second inlined copy cost a sixth of the
    // filter's time on llvmpipe): without such planes the loop runs it once.
    var best = no_hit();
    var best_key = 0xffffffffu;
    for (var upper = 0u; upper < 8u; upper++) {
        if (upper & planes) != upper {
            continue;
        }
        r.lower = (vec3(upper & 1u, upper & 2u, upper & 4u) == vec3(0u))
        & (vec3(planes & 1u, planes & 2u, planes & 4u) != vec3(0u));
        var h = march(r, lod, t_from, min(t_limit, best.t), record);
        h.rank |= upper;
        let key = rank_key(h.rank);
        if (h.found || h.missing) && (h.t < best.t || (h.t == best.t && key < best_key)) {
            best = h;
            best_key = key;
        }
        if planes == 0u {
            break;
        }
    }
    return best;
}

// Marches the ray `o + t * d` (object space) through LOD `first` (a LOD-table index) from
// `t_from` up to `t_limit`. Where a page of that LOD is not resident, the rest of the ray is
// marched in the next coarser LOD of the object (`first - 1`: an object's LODs are
// consecutive, level 0 first), and so on: the coarsest levels are always resident, so a
// frame shows coarser voxels where pages are streaming in, never a hole (a coarser level
// covers every cell of a finer one). Only the first LOD's missing pages are requested.
fn march_resident(o: vec3<f32>, d: vec3<f32>, first: u32, t_from: f32, t_limit: f32) -> Hit {
    // No pages in the scene: one march, no fallback loop in the pipeline.
    if !PAGED {
        var h = march_lod(o, d, lod_info(first), t_from, t_limit, true);
        h.lod = first;
        return h;
    }
    var li = first;
    var t_start = t_from;
    var record = true;
    loop {
        let lod = lod_info(li);
        var h = march_lod(o, d, lod, t_start, t_limit, record);
        if !h.missing || lod.level == 0u {
            h.lod = li;
            h.missing = false;
            return h;
        }
        t_start = h.t;
        li -= 1u;
        record = false;
    }
    return no_hit();
}
