// Walking the visible instances' boxes (`instance_bvh`, common.inc.wgsl; built per frame
// from ssbvb-voxel instance_bvh.rs, whose CPU walk the reference uses), so a pixel's cost
// follows the instances its ray meets: `instance_walk` scans the list of the pixel's screen
// tile (ssbvb-gpu scene/tile_lists.rs: every instance whose box may cover a pixel of the
// tile, nearest box first), or, where a tile has no list, walks the hierarchy, nearer child
// first; either skips every box the ray enters beyond the best hit so far. The includer defines
// `fn bvh_visit(j: u32, dir: vec3<f32>) -> f32`: consider visible instance `j`, return the
// best hit's distance so far (the new limit; a box entered exactly at it is still visited,
// for the reference's exact-tie rule).

// Boxes tested by this invocation (for the includer's counters).
var<private> boxes_tested: u32;

// The walk's ray, set once per walk: the reciprocal of each direction component, and which
// components are below 1e-20 (treated as 0; their reciprocal is unused). A box test is then
// six products and no division, in vector form (a ray tests dozens of boxes in a crowd;
// docs/benchmarks.md, "The crowd's walk, taken apart").
var<private> walk_inv_dir: vec3<f32>;
var<private> walk_flat: vec3<bool>;
// A distance before which the includer knows the walk can find nothing (0: none known):
// a box the ray leaves before it is passed over with its subtree (the filter's second
// proxy layer; ray_march_filter.wgsl).
var<private> walk_t_min: f32 = 0.0;

// Entry time of the walk's ray into node `i`'s box (`box_enter`).
fn bvh_enter(i: u32) -> f32 {
    return box_enter(bvh_node(i));
}

// Entry time (t >= 0) of the camera-relative ray `t * dir` (the walk's) into the box of
// `n`, or BIG when it misses or leaves it before `walk_t_min`. Boxes are clamped to 1e37
// and widened, so nothing overflows or is missed.
fn box_enter(n: BvhNode) -> f32 {
    boxes_tested += 1u;
    // Parallel to a slab and outside it: missed.
    if any(walk_flat & !((n.lo <= vec3(0.0)) & (vec3(0.0) <= n.hi))) {
        return BIG;
    }
    let t0 = n.lo * walk_inv_dir;
    let t1 = n.hi * walk_inv_dir;
    let near = select(min(t0, t1), vec3(0.0), walk_flat);
    let far = select(max(t0, t1), vec3(BIG), walk_flat);
    let enter = max(max(near.x, near.y), max(near.z, 0.0));
    let exit = min(min(far.x, far.y), min(far.z, BIG));
    return select(BIG, enter, enter <= exit && exit >= walk_t_min);
}

// Visits the instances whose boxes the ray enters at or before the limit, starting from
// `limit`; `count` is the number of visible instances (2 count - 1 nodes). The walk to the
// next leaf is a loop of its own, and the visit comes after it: a SIMD CPU adapter runs a
// loop's whole body, under a lane mask, on every pass that any lane takes (llvmpipe skips
// no branch that no lane takes), so a visit inside the box tests' loop would cost a march
// per box tested (docs/benchmarks.md).
fn bvh_walk(dir: vec3<f32>, limit_in: f32, count: u32) {
    if count == 0u {
        return;
    }
    var limit = limit_in;
    walk_flat = abs(dir) < vec3(1e-20);
    walk_inv_dir = 1.0 / select(dir, vec3(1.0), walk_flat);
    var stack: array<u32, BVH_STACK>;
    var stack_t: array<f32, BVH_STACK>;
    var sp = 0u;
    let root_t = bvh_enter(0u);
    if root_t < BIG {
        stack[0] = 0u;
        stack_t[0] = root_t;
        sp = 1u;
    }
    // Each node is pushed at most once; the bound only guards against a corrupt buffer.
    var popped = 0u;
    loop {
        var leaf = count;
        loop {
            if sp == 0u || popped >= 2u * count {
                break;
            }
            popped += 1u;
            sp -= 1u;
            if stack_t[sp] > limit {
                continue;
            }
            let node = bvh_node(stack[sp]);
            if (node.left & BVH_LEAF) != 0u {
                leaf = node.left & ~BVH_LEAF;
                if leaf < count {
                    break;
                }
                continue;
            }
            let tl = bvh_enter(node.left);
            let tr = bvh_enter(node.right);
            // The farther child goes on the stack first, so the nearer one is popped first.
            let near_is_left = tl <= tr;
            let t_far = select(tl, tr, near_is_left);
            let t_near = select(tr, tl, near_is_left);
            if t_far < BIG && sp < BVH_STACK {
                stack[sp] = select(node.left, node.right, near_is_left);
                stack_t[sp] = t_far;
                sp += 1u;
            }
            if t_near < BIG && sp < BVH_STACK {
                stack[sp] = select(node.right, node.left, near_is_left);
                stack_t[sp] = t_near;
                sp += 1u;
            }
        }
        if leaf >= count {
            break;
        }
        limit = min(limit, bvh_visit(leaf, dir));
    }
}

// A tile's count that means "no list: walk the hierarchy" (scene/tile_lists.rs LIST_WALK).
const LIST_WALK: u32 = 0xffffffffu;

fn bvh_word(w: u32) -> u32 {
    return instance_bvh[w >> 2u][w & 3u];
}

// Visits, as `bvh_walk` does, the instances whose boxes the ray of the pixel centred at `px`
// (screen pixels) enters at or before the limit, by the list of the pixel's tile where the
// frame has lists. The list is sorted by the distance from the camera to each box, a lower
// bound on where every later box is entered: the scan stops at the first box farther than
// the limit (less 1e-5 of it for f32's rounding). Distances are taken with the box clamped
// to 1e18, so a far box's distance stays finite and a lower bound.
fn instance_walk(px: vec2<f32>, dir: vec3<f32>, limit_in: f32, count: u32) {
    let lists = frame.streams.w;
    if count == 0u {
        return;
    }
    var first = 0u;
    var n = LIST_WALK;
    if lists != 0u {
        // x, y: tiles a row and a column; z: a tile's side in pixels.
        let header = instance_bvh[lists];
        let tile = min(vec2<u32>(max(px / f32(header.z), vec2(0.0))), header.xy - 1u);
        let at = 4u * lists + 4u + 2u * (tile.y * header.x + tile.x);
        first = bvh_word(at);
        n = bvh_word(at + 1u);
    }
    if n == LIST_WALK {
        bvh_walk(dir, limit_in, count);
        return;
    }
    var limit = limit_in;
    walk_flat = abs(dir) < vec3(1e-20);
    walk_inv_dir = 1.0 / select(dir, vec3(1.0), walk_flat);
    var i = 0u;
    // As in `bvh_walk`, the scan to the next entered box is a loop of its own and the visit
    // comes after it.
    loop {
        var leaf = count;
        loop {
            if i >= n {
                break;
            }
            let node = bvh_node(bvh_word(first + i));
            i += 1u;
            let gap = min(max(max(node.lo, -node.hi), vec3(0.0)), vec3(1e18));
            if length(gap) * (1.0 - 1e-5) > limit {
                i = n;
                break;
            }
            if box_enter(node) <= limit {
                leaf = node.left & ~BVH_LEAF;
                break;
            }
        }
        if leaf >= count {
            break;
        }
        limit = min(limit, bvh_visit(leaf, dir));
    }
}
