// Walking the hierarchy over the visible instances' boxes (`instance_bvh`, common.inc.wgsl;
// built per frame from ssbvb-voxel instance_bvh.rs, whose CPU walk the reference uses):
// nearer child first, skipping every box the ray enters beyond the best hit so far, so a
// pixel's cost follows the instances its ray meets. The includer defines
// `fn bvh_visit(j: u32, dir: vec3<f32>) -> f32`: consider visible instance `j`, return the
// best hit's distance so far (the new limit; a box entered exactly at it is still visited,
// for the reference's exact-tie rule).

// Boxes tested by this invocation (for the includer's counters).
var<private> boxes_tested: u32;

// Entry time (t >= 0) of the camera-relative ray `t * dir` into node `i`'s box, or BIG when
// it misses. Direction components below 1e-20 are treated as 0 (boxes are clamped to 1e37
// and widened, so nothing overflows or is missed).
fn bvh_enter(i: u32, dir: vec3<f32>) -> f32 {
    boxes_tested += 1u;
    let n = instance_bvh[i];
    var enter = 0.0;
    var exit = BIG;
    for (var a = 0u; a < 3u; a++) {
        if abs(dir[a]) < 1e-20 {
            if !(n.lo[a] <= 0.0 && 0.0 <= n.hi[a]) {
                return BIG;
            }
            continue;
        }
        let inv = 1.0 / dir[a];
        let t0 = n.lo[a] * inv;
        let t1 = n.hi[a] * inv;
        enter = max(enter, min(t0, t1));
        exit = min(exit, max(t0, t1));
    }
    return select(BIG, enter, enter <= exit);
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
    var stack: array<u32, BVH_STACK>;
    var stack_t: array<f32, BVH_STACK>;
    var sp = 0u;
    let root_t = bvh_enter(0u, dir);
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
            let node = instance_bvh[stack[sp]];
            if (node.left & BVH_LEAF) != 0u {
                leaf = node.left & ~BVH_LEAF;
                if leaf < count {
                    break;
                }
                continue;
            }
            let tl = bvh_enter(node.left, dir);
            let tr = bvh_enter(node.right, dir);
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
