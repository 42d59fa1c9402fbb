//! A bounding volume hierarchy over instance boxes: what keeps a pixel's cost tied to the
//! instances its ray meets rather than to how many the scene holds.
//!
//! Both the CPU reference ([`crate::reference`]) and the GPU ray-march filter traverse the
//! same hierarchy (the GPU one is built from this one every frame, `ssbvb-gpu`
//! `scene/visibility.rs`), so their candidate sets agree by construction; the exact per-instance
//! slab test and march still decide every hit.
//!
//! **Build:** a binary tree with one instance per leaf, split at the median of the box
//! centres along the axis where the centres spread most. Median splits keep the depth at
//! `ceil(log2 n)` (the GPU's traversal stack is fixed-size: [`MAX_DEPTH`]). Building 4096
//! boxes takes well under a millisecond, so it is rebuilt per frame rather than refitted.
//!
//! **Traversal:** near child first, with a stack; a node is skipped when the ray misses
//! its box or enters it after the best hit so far (`entry > limit`, not `>=`: an instance
//! whose box is entered exactly at the best hit's distance may still win an exact tie,
//! which goes to the lower instance index).
//!
//! Boxes are closed and conservative: [`Aabb::of_instance`] bounds the transformed object
//! box `[-1, 1]³` and callers may widen them ([`Aabb::widened`]) to absorb rounding of
//! the less precise code that tests them.

use glam::{DAffine3, DVec3};

/// Deepest tree [`InstanceBvh::build`] makes: enough for 2^24 instances. The GPU
/// traversal's stack holds this many entries.
pub const MAX_DEPTH: usize = 25;

/// The most items a hierarchy the GPU walks may hold (its stack holds [`MAX_DEPTH`] + 1
/// nodes).
pub const MAX_GPU_ITEMS: usize = 1 << (MAX_DEPTH - 1);

/// Marks a leaf in [`BvhNode::left`]; the low bits are the item index.
pub const LEAF: u32 = 0x8000_0000;

/// An axis-aligned box, closed (`lo <= p <= hi`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub lo: DVec3,
    /// Maximum corner.
    pub hi: DVec3,
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        lo: DVec3::splat(f64::INFINITY),
        hi: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The world box of an instance's object box `[-1, 1]³` under `object_to_world`, or
    /// `None` when the transform is not finite.
    pub fn of_instance(object_to_world: &DAffine3) -> Option<Aabb> {
        Self::of_object_box(object_to_world, DVec3::NEG_ONE, DVec3::ONE)
    }

    /// The world box of the object-space box `[lo, hi]` under `object_to_world` (tight
    /// for that box), or `None` when the result is not finite.
    pub fn of_object_box(object_to_world: &DAffine3, lo: DVec3, hi: DVec3) -> Option<Aabb> {
        let m = object_to_world.matrix3;
        let h = (hi - lo) * 0.5;
        // Half-extent per world axis: the absolute columns weighted by the box's half-size.
        let half = m.x_axis.abs() * h.x + m.y_axis.abs() * h.y + m.z_axis.abs() * h.z;
        let c = object_to_world.transform_point3((lo + hi) * 0.5);
        (half.is_finite() && c.is_finite()).then(|| Aabb {
            lo: c - half,
            hi: c + half,
        })
    }

    /// The smallest box holding both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    /// The box grown by `by` on every side.
    pub fn widened(self, by: f64) -> Aabb {
        Aabb {
            lo: self.lo - by,
            hi: self.hi + by,
        }
    }

    /// Centre.
    pub fn center(&self) -> DVec3 {
        (self.lo + self.hi) * 0.5
    }

    /// The interval `[enter, exit]` of `t >= 0` for which `origin + t·dir` lies in the
    /// box, or `None` when it misses. Zero direction components are handled exactly (the
    /// ray is inside the slab on that axis for every `t`, or never).
    pub fn ray_interval(&self, origin: DVec3, dir: DVec3) -> Option<(f64, f64)> {
        let (mut enter, mut exit) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            let (o, d) = (origin[a], dir[a]);
            if d == 0.0 {
                if !(self.lo[a] <= o && o <= self.hi[a]) {
                    return None;
                }
                continue;
            }
            let (t0, t1) = ((self.lo[a] - o) / d, (self.hi[a] - o) / d);
            let (t0, t1) = if d > 0.0 { (t0, t1) } else { (t1, t0) };
            enter = enter.max(t0);
            exit = exit.min(t1);
        }
        (enter <= exit).then_some((enter, exit))
    }
}

/// One node: a box and either two children or one item.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhNode {
    /// The box holding everything below.
    pub bounds: Aabb,
    /// Left child index, or `LEAF | item` for a leaf.
    pub left: u32,
    /// Right child index (0 for a leaf).
    pub right: u32,
}

impl BvhNode {
    /// The item of a leaf.
    pub fn item(&self) -> Option<u32> {
        (self.left & LEAF != 0).then_some(self.left & !LEAF)
    }
}

/// A BVH over item boxes; node 0 is the root. An empty hierarchy has no nodes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InstanceBvh {
    nodes: Vec<BvhNode>,
}

impl InstanceBvh {
    /// Builds the hierarchy over `boxes`; item `i` is `boxes[i]`, and `None` items (hidden
    /// instances) are left out. Its depth is `ceil(log2 n) + 1` nodes; a GPU walk holds
    /// [`MAX_DEPTH`] of them, so GPU scenes stay at or below [`MAX_GPU_ITEMS`] items.
    pub fn build(boxes: &[Option<Aabb>]) -> Self {
        let mut items: Vec<(u32, Aabb)> = boxes
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.map(|b| (i as u32, b)))
            .collect();
        let mut nodes = Vec::with_capacity(items.len() * 2);
        if !items.is_empty() {
            build_node(&mut nodes, &mut items);
        }
        Self { nodes }
    }

    /// The nodes, root first.
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// Visits the items whose boxes `origin + t·dir` (`t >= 0`) enters, nearest box first
    /// among siblings, skipping every subtree entered beyond the current limit.
    /// `visit(item, box_enter)` returns the new limit (the best hit's distance so far, or
    /// infinity). Returns the number of node boxes tested.
    pub fn traverse(
        &self,
        origin: DVec3,
        dir: DVec3,
        mut visit: impl FnMut(u32, f64) -> f64,
    ) -> usize {
        let Some(root) = self.nodes.first() else {
            return 0;
        };
        let mut tested = 1;
        let mut limit = f64::INFINITY;
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(MAX_DEPTH);
        if let Some((enter, _)) = root.bounds.ray_interval(origin, dir) {
            stack.push((0, enter));
        }
        while let Some((i, enter)) = stack.pop() {
            if enter > limit {
                continue;
            }
            let node = &self.nodes[i as usize];
            if let Some(item) = node.item() {
                limit = visit(item, enter).min(limit);
                continue;
            }
            let hit = |c: u32| {
                self.nodes[c as usize]
                    .bounds
                    .ray_interval(origin, dir)
                    .map(|(e, _)| (c, e))
            };
            tested += 2;
            let (l, r) = (hit(node.left), hit(node.right));
            // Push the farther child first so the nearer one is visited first.
            match (l, r) {
                (Some(a), Some(b)) => {
                    let (near, far) = if b.1 < a.1 { (b, a) } else { (a, b) };
                    stack.push(far);
                    stack.push(near);
                }
                (Some(a), None) | (None, Some(a)) => stack.push(a),
                (None, None) => {}
            }
        }
        tested
    }
}

fn build_node(nodes: &mut Vec<BvhNode>, items: &mut [(u32, Aabb)]) -> u32 {
    let index = nodes.len() as u32;
    let bounds = items.iter().fold(Aabb::EMPTY, |b, (_, x)| b.union(*x));
    if let [(item, b)] = items {
        nodes.push(BvhNode {
            bounds: *b,
            left: LEAF | *item,
            right: 0,
        });
        return index;
    }
    nodes.push(BvhNode {
        bounds,
        left: 0,
        right: 0,
    });
    let centres = items.iter().fold(Aabb::EMPTY, |b, (_, x)| {
        b.union(Aabb {
            lo: x.center(),
            hi: x.center(),
        })
    });
    let spread = centres.hi - centres.lo;
    let axis = if spread.x >= spread.y && spread.x >= spread.z {
        0
    } else if spread.y >= spread.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    // Ties broken by item index, so the tree does not depend on the sort's stability.
    items.select_nth_unstable_by(mid, |a, b| {
        a.1.center()[axis]
            .total_cmp(&b.1.center()[axis])
            .then(a.0.cmp(&b.0))
    });
    let (left, right) = items.split_at_mut(mid);
    let l = build_node(nodes, left);
    let r = build_node(nodes, right);
    nodes[index as usize].left = l;
    nodes[index as usize].right = r;
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    fn random_boxes(n: usize, seed: &mut u64) -> Vec<Option<Aabb>> {
        (0..n)
            .map(|i| {
                if i % 17 == 5 {
                    return None;
                }
                let xf = DAffine3 {
                    matrix3: DMat3::from_rotation_y(lcg(seed) * 6.3) * (0.05 + lcg(seed) * 0.5),
                    translation: DVec3::new(lcg(seed), lcg(seed), lcg(seed)) * 20.0 - 10.0,
                };
                Aabb::of_instance(&xf)
            })
            .collect()
    }

    #[test]
    fn instance_box_holds_every_transformed_corner() {
        let xf = DAffine3 {
            matrix3: DMat3::from_rotation_y(0.7) * DMat3::from_rotation_x(0.3) * 2.5,
            translation: DVec3::new(3.0, -1.0, 7.0),
        };
        let b = Aabb::of_instance(&xf).unwrap();
        let mut touched = [false; 6];
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            let p = xf.transform_point3(c);
            for a in 0..3 {
                assert!(b.lo[a] - 1e-12 <= p[a] && p[a] <= b.hi[a] + 1e-12);
                touched[a] |= (p[a] - b.lo[a]).abs() < 1e-12;
                touched[a + 3] |= (p[a] - b.hi[a]).abs() < 1e-12;
            }
        }
        assert_eq!(
            touched, [true; 6],
            "the box is tight: a corner on every face"
        );
        assert!(Aabb::of_instance(&DAffine3::from_translation(DVec3::NAN)).is_none());
        // A sub-box of unequal sides: the hull of its transformed corners, exactly.
        let (lo, hi) = (DVec3::new(-0.5, 0.0, -1.0), DVec3::new(0.25, 1.0, -0.5));
        let sub = Aabb::of_object_box(&xf, lo, hi).unwrap();
        let hull = (0..8)
            .map(|i| {
                xf.transform_point3(DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                ))
            })
            .fold(Aabb::EMPTY, |b, p| b.union(Aabb { lo: p, hi: p }));
        assert!(
            (hull.lo - sub.lo).abs().max_element() < 1e-12,
            "{hull:?} {sub:?}"
        );
        assert!(
            (hull.hi - sub.hi).abs().max_element() < 1e-12,
            "{hull:?} {sub:?}"
        );
    }

    /// The GPU's item limit is the largest whose tree fits its stack: depth
    /// `ceil(log2 n) + 1` nodes at most MAX_DEPTH, and twice as many items would not.
    #[test]
    fn the_gpu_item_limit_fits_the_walk_stack() {
        let depth = |n: usize| (n as f64).log2().ceil() as usize + 1;
        assert_eq!(MAX_GPU_ITEMS, 1 << 24);
        assert!(depth(MAX_GPU_ITEMS) <= MAX_DEPTH);
        assert!(depth(2 * MAX_GPU_ITEMS) > MAX_DEPTH);
    }

    #[test]
    fn widening_grows_every_side_and_the_centre_is_the_middle() {
        let b = Aabb {
            lo: DVec3::new(1.0, -2.0, 3.0),
            hi: DVec3::new(2.0, 4.0, 7.0),
        };
        let w = b.widened(0.5);
        assert_eq!(w.lo, DVec3::new(0.5, -2.5, 2.5));
        assert_eq!(w.hi, DVec3::new(2.5, 4.5, 7.5));
        assert_eq!(b.center(), DVec3::new(1.5, 1.0, 5.0));
        assert_eq!(b.union(Aabb::EMPTY), b);
    }

    #[test]
    fn ray_interval_matches_sampling_and_handles_axis_parallel_rays() {
        let b = Aabb {
            lo: DVec3::new(1.0, -1.0, -1.0),
            hi: DVec3::new(3.0, 1.0, 1.0),
        };
        assert_eq!(b.ray_interval(DVec3::ZERO, DVec3::X), Some((1.0, 3.0)));
        assert_eq!(b.ray_interval(DVec3::ZERO, DVec3::NEG_X), None);
        assert_eq!(
            b.ray_interval(DVec3::new(2.0, 0.0, 0.0), DVec3::Y),
            Some((0.0, 1.0))
        );
        // Parallel to a face: inside the slab (touching counts) or outside it.
        assert_eq!(
            b.ray_interval(DVec3::new(0.0, 1.0, 0.0), DVec3::X),
            Some((1.0, 3.0))
        );
        assert_eq!(b.ray_interval(DVec3::new(0.0, 1.5, 0.0), DVec3::X), None);
        assert_eq!(b.ray_interval(DVec3::ZERO, DVec3::ZERO), None);
        assert_eq!(Aabb::EMPTY.ray_interval(DVec3::ZERO, DVec3::X), None);
    }

    #[test]
    fn tree_is_balanced_and_holds_every_item_once() {
        let mut seed = 7;
        for n in [0usize, 1, 2, 3, 31, 1000] {
            let boxes = random_boxes(n, &mut seed);
            let bvh = InstanceBvh::build(&boxes);
            let present: Vec<u32> = (0..n as u32)
                .filter(|&i| boxes[i as usize].is_some())
                .collect();
            let mut leaves = Vec::new();
            let mut depth_max = 0;
            let mut stack = vec![(0u32, 1usize)];
            while let Some((i, depth)) = stack.pop().filter(|_| !bvh.nodes.is_empty()) {
                let node = bvh.nodes[i as usize];
                depth_max = depth_max.max(depth);
                match node.item() {
                    Some(item) => {
                        assert_eq!(node.bounds, boxes[item as usize].unwrap());
                        leaves.push(item);
                    }
                    None => {
                        for c in [node.left, node.right] {
                            let cb = bvh.nodes[c as usize].bounds;
                            assert_eq!(cb.union(node.bounds), node.bounds, "child inside");
                            stack.push((c, depth + 1));
                        }
                    }
                }
            }
            leaves.sort_unstable();
            assert_eq!(leaves, present, "{n} items");
            assert_eq!(bvh.nodes().len(), (2 * present.len()).saturating_sub(1));
            let bound = (present.len() as f64).log2().ceil() as usize + 1;
            assert!(depth_max <= bound, "depth {depth_max} > {bound} for {n}");
        }
    }

    fn unit_box(c: DVec3) -> Option<Aabb> {
        Some(Aabb {
            lo: c - 0.5,
            hi: c + 0.5,
        })
    }

    /// Boxes in a row along one axis are split along it: the root's children do not
    /// overlap there. Positions are shuffled against the item order (a split on another
    /// axis falls back to item order).
    #[test]
    fn the_split_follows_the_axis_where_the_centres_spread() {
        // This axis: 200..245 (spread 45, ratio 1.2, sum 445). Other axes: 1 or 2 (spread
        // 1, ratio 2), or 1000 or 1001 (spread 1, sum 2001): a ratio or a sum instead of
        // the spread picks another axis in one of the two.
        for (axis, other) in (0..3).flat_map(|a| [(a, 1.0), (a, 1000.0)]) {
            let boxes: Vec<Option<Aabb>> = (0..16)
                .map(|i| {
                    let mut c = DVec3::splat(other + (i % 2) as f64);
                    c[axis] = 200.0 + 3.0 * ((i * 7) % 16) as f64;
                    unit_box(c)
                })
                .collect();
            let bvh = InstanceBvh::build(&boxes);
            let root = bvh.nodes()[0];
            let (l, r) = (
                bvh.nodes()[root.left as usize],
                bvh.nodes()[root.right as usize],
            );
            assert!(
                l.bounds.hi[axis] < r.bounds.lo[axis],
                "axis {axis}: {l:?} {r:?}"
            );
        }
    }

    /// A ray along a row of boxes whose first box holds the hit at its entry visits that
    /// box only (nearest first, the rest pruned) and tests few boxes; two identical boxes
    /// entered at the best hit's distance are both visited (an exact tie may go to either).
    #[test]
    fn the_walk_visits_nearest_first_prunes_beyond_the_hit_and_keeps_ties() {
        let boxes: Vec<Option<Aabb>> = (0..16)
            .map(|i| unit_box(DVec3::new(2.0 * i as f64, 0.0, 0.0)))
            .collect();
        let bvh = InstanceBvh::build(&boxes);
        for (origin, dir, first) in [
            (DVec3::new(-5.0, 0.1, 0.2), DVec3::X, 0),
            (DVec3::new(40.0, -0.1, 0.2), DVec3::NEG_X, 15),
        ] {
            let mut visited = Vec::new();
            let tested = bvh.traverse(origin, dir, |item, enter| {
                visited.push(item);
                enter
            });
            assert_eq!(visited, vec![first], "{dir}");
            // The root, then two children per level down one path (depth 4).
            assert!(tested <= 9, "{tested} boxes tested");
        }
        let twins = vec![
            unit_box(DVec3::ZERO),
            unit_box(DVec3::new(5.0, 0.0, 0.0)),
            unit_box(DVec3::ZERO),
        ];
        let bvh = InstanceBvh::build(&twins);
        let mut visited = Vec::new();
        bvh.traverse(DVec3::new(-3.0, 0.0, 0.0), DVec3::X, |item, enter| {
            visited.push(item);
            enter
        });
        visited.sort_unstable();
        assert_eq!(visited, vec![0, 2]);
    }

    /// The traversal's nearest-hit answer equals a brute-force loop over every box, with
    /// the hit at each box's entry (the worst case for pruning: every box is solid).
    #[test]
    fn traversal_finds_the_same_nearest_box_as_brute_force_and_tests_fewer() {
        let mut seed = 99;
        let boxes = random_boxes(2000, &mut seed);
        let bvh = InstanceBvh::build(&boxes);
        let mut tested_total = 0;
        for _ in 0..500 {
            let origin = DVec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) * 30.0 - 15.0;
            let dir = DVec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) - 0.5;
            let brute = boxes
                .iter()
                .enumerate()
                .filter_map(|(i, b)| {
                    b.and_then(|b| b.ray_interval(origin, dir))
                        .map(|(e, _)| (e, i as u32))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut best: Option<(f64, u32)> = None;
            tested_total += bvh.traverse(origin, dir, |item, _| {
                let (e, _) = boxes[item as usize]
                    .unwrap()
                    .ray_interval(origin, dir)
                    .unwrap();
                if best.is_none_or(|(t, i)| e < t || (e == t && item < i)) {
                    best = Some((e, item));
                }
                best.map_or(f64::INFINITY, |b| b.0)
            });
            assert_eq!(best, brute);
        }
        let per_ray = tested_total as f64 / 500.0;
        assert!(per_ray < 200.0, "{per_ray} boxes per ray of 2000");
    }
}
