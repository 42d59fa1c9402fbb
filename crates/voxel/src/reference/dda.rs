//! Exact voxel traversal in object space (Amanatides–Woo, f64, closed cells).
//!
//! # What "the first voxel hit" means
//!
//! Cells are **closed** boxes. Along axis `a` the ray `o + t·d` touches cell `i` during
//! the closed interval between the times it crosses the cell's two boundary planes, where
//! the crossing time of plane `k` (at `b_k = -1 + k·s`, `s = 2 / 2^level`) is computed
//! exactly as `t_k = (b_k - o_a) / d_a` (one rounded subtraction, one rounded division;
//! `b_k` itself is exact). On an axis where `d_a == 0` the ray touches the cells whose
//! closed extent holds `o_a` (two cells when `o_a` lies exactly on an inner boundary). A
//! cell is touched during the intersection of its three axis intervals and of `t >= 0`.
//! **The hit is the occupied cell with the smallest touch time** — equivalently, the first
//! point of the ray (from `t = 0`) that lies in the closed box of an occupied voxel. So:
//!
//! - a ray that grazes a voxel face (runs inside its plane) hits the voxel;
//! - a ray through an edge or corner shared by several cells touches all of them;
//! - a ray through a diagonal gap between two voxels that share only an edge hits them;
//! - a camera inside a voxel hits it at `t = 0`.
//!
//! Because crossing times are computed per plane (never accumulated), two axes tie exactly
//! when their computed times are equal, and every traversal (plain, hierarchical, or a
//! brute-force test over all voxels) sees the same numbers.
//!
//! # Tie rule (several occupied cells touched first, at the same time `T`)
//!
//! Each touched cell gets a rank per axis. On an axis the ray moves along, rank 0 is the
//! cell furthest along the ray among those touched at `T` (the cell whose interior the ray
//! enters at `T`), rank 1 the one before it, and so on. On an axis the ray does not move
//! along, rank 0 is the lower cell and rank 1 the upper one (the ray lies on their shared
//! plane). The chosen cell has the smallest rank sum, then the smallest z rank, then y,
//! then x. So a ray that enters an occupied cell through an edge or corner reports that
//! cell; otherwise it reports the occupied neighbour that differs from it on the fewest
//! axes, preferring to differ on x, then y.
//!
//! # Face normal
//!
//! The entered face of the chosen cell is the face whose plane the ray crosses at `T`
//! (`t_k == T` on that axis: "the axis the DDA last stepped on"). When the cell is entered
//! through an edge or corner (several such axes), the axis along which the ray moves
//! fastest (largest `|d_a|`) wins, ties to the lower axis index. When the ray starts inside
//! the voxel (`T == 0` and no plane crossed at 0) the normal is `-sign(d_a)·e_a` on the
//! dominant axis of the direction, and [`ObjectHit::inside`] is set. The normal always
//! points against the ray on its axis.
//!
//! # Traversal
//!
//! Axes with `d_a < 0` are mirrored (`x → -x`, cell `i → 2^level - 1 - i`): with dyadic
//! boundaries this is exact and keeps every crossing time bit-identical, so the loop only
//! ever steps forward. The hierarchical traversal additionally jumps over the empty nodes
//! of the lookup's 64-ary tree (regions of 4³, 16³, 64³, ... cells): when every cell the
//! ray can touch before leaving the current region is empty, it advances to the
//! first crossing time at which the ray reaches the page's far boundary, binary-searching
//! each axis' next plane. The state it lands in is exactly the state the cell-by-cell loop
//! reaches at that time, so both report identical hits (a test checks it on random rays).

use glam::DVec3;

use crate::asset::SparseLookup;
use crate::model::cell_size;

/// How [`trace_object_ray`] walks empty space. Both give bit-identical results.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Traversal {
    /// Skip the empty nodes of the lookup tree in one step each (the default).
    Hierarchical,
    /// Visit every cell (the plain Amanatides–Woo DDA; the test oracle).
    CellByCell,
}

/// The first voxel an object-space ray touches (see the module docs for the rules).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectHit {
    /// Voxel id (index in the LOD's point cloud).
    pub voxel: u32,
    /// The voxel's cell.
    pub cell: [u32; 3],
    /// Ray parameter of the hit (`o + t·d`, in units of the given direction's length).
    pub t: f64,
    /// Axis of the entered face (0 = x, 1 = y, 2 = z).
    pub face_axis: usize,
    /// Object-space unit normal of the entered face (±1 on `face_axis`, against the ray).
    pub face_normal: DVec3,
    /// The ray started inside the voxel (`t == 0`, normal from the dominant axis).
    pub inside: bool,
}

/// Per-ray constants: the ray in the mirrored frame.
struct Frame {
    /// Cells per axis.
    n: i64,
    /// Cell size.
    s: f64,
    /// Origin per axis (negated on mirrored axes).
    o: [f64; 3],
    /// |direction| per axis (0 on static axes).
    d: [f64; 3],
    /// The original direction (for normals and tie rules).
    dir: DVec3,
    /// Axis is mirrored (original direction negative).
    mirrored: [bool; 3],
    /// Axis has a non-zero direction.
    moving: [bool; 3],
}

impl Frame {
    /// Time at which the ray crosses plane `k` of moving axis `a` (mirrored frame).
    #[inline(always)]
    fn t(&self, a: usize, k: i64) -> f64 {
        ((-1.0 + k as f64 * self.s) - self.o[a]) / self.d[a]
    }

    /// Original cell index of a (possibly mirrored) cell index on axis `a`.
    #[inline(always)]
    fn orig(&self, a: usize, i: i64) -> i64 {
        if self.mirrored[a] { self.n - 1 - i } else { i }
    }

    /// The first plane index `k` in `[lo, hi]` with `t(a, k) >= t` (or `> t` when
    /// `strict`), or `hi + 1` if none: crossing times are monotone in `k`.
    fn first_plane(&self, a: usize, mut lo: i64, mut hi: i64, t: f64, strict: bool) -> i64 {
        hi += 1;
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            let tm = self.t(a, mid);
            if (strict && tm > t) || (!strict && tm >= t) {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo
    }
}

/// Traversal state: per moving axis the next plane not yet crossed and its time; per axis
/// the range of cells touched at the current event (mirrored frame on moving axes).
struct State {
    next: [i64; 3],
    t_next: [f64; 3],
    lo: [i64; 3],
    hi: [i64; 3],
}

/// Traces an object-space ray `origin + t·dir` (`t >= 0`, `dir` need not be normalized)
/// through the voxels of `lookup` and returns the first voxel it touches, per the rules in
/// the module docs. Non-finite inputs, a zero direction or a ray that misses [-1, 1]³
/// return `None`.
pub fn trace_object_ray(
    lookup: &SparseLookup,
    origin: DVec3,
    dir: DVec3,
    traversal: Traversal,
) -> Option<ObjectHit> {
    trace_object_ray_faces(lookup, None, origin, dir, traversal)
}

/// [`trace_object_ray`] through face-masked voxels (a RastaVox level,
/// [`crate::surface::FaceLod`]): with `faces`, voxel `id` is hit only where the ray enters
/// it through a face whose bit is set in `faces[id]` (bit `f` = face `f`, −X/−Y/−Z/+X/+Y/+Z),
/// as rasterizing its masked camera-facing faces draws it; a camera inside a voxel sees
/// none of its faces. The reported face is such a face (the fastest axis among them).
pub fn trace_object_ray_faces(
    lookup: &SparseLookup,
    faces: Option<&[u8]>,
    origin: DVec3,
    dir: DVec3,
    traversal: Traversal,
) -> Option<ObjectHit> {
    trace_object_ray_counted(lookup, faces, origin, dir, traversal).0
}

/// The work of one traversal: hardware-independent counts for comparing traversals.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TraceCount {
    /// Crossing events visited after the start (each tests the cells touched at one time).
    pub events: u32,
    /// Empty regions jumped over (hierarchical traversal only).
    pub skips: u32,
    /// Cells looked up in the sparse lookup (including any outside the grid).
    pub lookups: u32,
}

/// [`trace_object_ray_faces`], also returning how much work the traversal did.
pub fn trace_object_ray_counted(
    lookup: &SparseLookup,
    faces: Option<&[u8]>,
    origin: DVec3,
    dir: DVec3,
    traversal: Traversal,
) -> (Option<ObjectHit>, TraceCount) {
    let mut count = TraceCount::default();
    let hit = trace(lookup, faces, origin, dir, traversal, &mut count);
    (hit, count)
}

fn trace(
    lookup: &SparseLookup,
    faces: Option<&[u8]>,
    origin: DVec3,
    dir: DVec3,
    traversal: Traversal,
    count: &mut TraceCount,
) -> Option<ObjectHit> {
    if !origin.is_finite() || !dir.is_finite() || dir == DVec3::ZERO {
        return None;
    }
    let n = 1i64 << lookup.level;
    let mut f = Frame {
        n,
        s: cell_size(lookup.level),
        o: [0.0; 3],
        d: [0.0; 3],
        dir,
        mirrored: [false; 3],
        moving: [false; 3],
    };
    let mut st = State {
        next: [0; 3],
        t_next: [f64::INFINITY; 3],
        lo: [0; 3],
        hi: [0; 3],
    };
    let (mut t_enter, mut t_exit) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if dir[a] == 0.0 {
            let o = origin[a];
            if !(-1.0..=1.0).contains(&o) {
                return None;
            }
            f.o[a] = o;
            // Cells whose closed extent holds `o`. The boundaries `b(k)` are exact and
            // rounding is monotone, so `(o + 1) / s` is never below the cell `c` with
            // `b(c) <= o < b(c + 1)` and at most one above it (when `o + 1` rounds up onto
            // `b(c + 1) + 1`): one comparison settles it. On an inner boundary the cell
            // below touches `o` too.
            let b = |k: i64| -1.0 + k as f64 * f.s;
            let mut i = (((o + 1.0) / f.s).floor() as i64).min(n - 1);
            if b(i) > o {
                i -= 1;
            }
            st.lo[a] = if i > 0 && b(i) == o { i - 1 } else { i };
            st.hi[a] = i;
        } else {
            f.moving[a] = true;
            f.mirrored[a] = dir[a] < 0.0;
            f.o[a] = if f.mirrored[a] { -origin[a] } else { origin[a] };
            f.d[a] = dir[a].abs();
            t_enter = t_enter.max(f.t(a, 0));
            t_exit = t_exit.min(f.t(a, n));
        }
    }
    let t0 = t_enter.max(0.0);
    // An infinite entry time comes from a direction component so small that the crossing
    // time overflows: the ray never gets there.
    if t0 > t_exit || !t0.is_finite() {
        return None;
    }
    for a in (0..3).filter(|&a| f.moving[a]) {
        // k2: first plane crossed strictly after t0; k1: first plane crossed at or after.
        let k2 = f.first_plane(a, 0, n, t0, true);
        let k1 = f.first_plane(a, 0, k2 - 1, t0, false);
        st.lo[a] = (k1 - 1).max(0);
        st.hi[a] = (k2 - 1).min(n - 1);
        st.next[a] = k2;
        st.t_next[a] = if k2 <= n { f.t(a, k2) } else { f64::INFINITY };
    }
    if let Some(hit) = best_touched(&f, &st, lookup, faces, t0, [false; 3], count) {
        return Some(hit);
    }
    let mut skip = SkipCache::default();
    loop {
        // The ray has left the grid once a moving axis has crossed its last plane.
        if (0..3).any(|a| f.moving[a] && st.next[a] > n) {
            return None;
        }
        if traversal == Traversal::Hierarchical && skip.try_skip(&f, &mut st, lookup) {
            count.skips += 1;
        }
        count.events += 1;
        let mut t = f64::INFINITY;
        for a in 0..3 {
            if f.moving[a] {
                t = t.min(st.t_next[a]);
            }
        }
        if !t.is_finite() {
            return None;
        }
        let mut crossing = [false; 3];
        for a in (0..3).filter(|&a| f.moving[a]) {
            let k1 = st.next[a];
            if st.t_next[a] == t {
                // Several planes of one axis cross at once when the origin is so far away
                // that `b - o` rounds consecutive boundaries to one value.
                let mut k2 = k1 + 1;
                while k2 <= n && f.t(a, k2) == t {
                    k2 += 1;
                }
                st.lo[a] = k1 - 1;
                st.hi[a] = (k2 - 1).min(n - 1);
                st.next[a] = k2;
                st.t_next[a] = if k2 <= n { f.t(a, k2) } else { f64::INFINITY };
                crossing[a] = true;
            } else {
                st.lo[a] = k1 - 1;
                st.hi[a] = k1 - 1;
            }
        }
        if let Some(hit) = best_touched(&f, &st, lookup, faces, t, crossing, count) {
            return Some(hit);
        }
    }
}

/// The best occupied cell (tie rule in the module docs) among those touched at time `t`
/// (the product of the per-axis ranges in `st`), leaving out the cells every `crossing`
/// axis had already touched before `t` (`lo` on each crossing axis): the previous event
/// (or the empty region skipped) covered them.
fn best_touched(
    f: &Frame,
    st: &State,
    lookup: &SparseLookup,
    faces: Option<&[u8]>,
    t: f64,
    crossing: [bool; 3],
    count: &mut TraceCount,
) -> Option<ObjectHit> {
    let any_crossing = crossing.iter().any(|&c| c);
    let mut best: Option<(u64, u32, [i64; 3])> = None;
    for z in st.lo[2]..=st.hi[2] {
        for y in st.lo[1]..=st.hi[1] {
            for x in st.lo[0]..=st.hi[0] {
                let c = [x, y, z];
                if any_crossing && (0..3).all(|a| !crossing[a] || c[a] == st.lo[a]) {
                    continue;
                }
                let cell = [0, 1, 2].map(|a| f.orig(a, c[a]) as u32);
                count.lookups += 1;
                let Some(voxel) = lookup.get(cell) else {
                    continue;
                };
                if faces.is_some_and(|m| entered_faces(f, c, t, m[voxel as usize]) == 0) {
                    continue;
                }
                let rank = |a: usize| {
                    (if f.moving[a] {
                        st.hi[a] - c[a]
                    } else {
                        c[a] - st.lo[a]
                    }) as u64
                };
                let key = ((rank(0) + rank(1) + rank(2)) << 48)
                    | (rank(2) << 32)
                    | (rank(1) << 16)
                    | rank(0);
                if best.is_none_or(|(k, _, _)| key < k) {
                    best = Some((key, voxel, c));
                }
            }
        }
    }
    let (_, voxel, c) = best?;
    // Entered face: an axis whose near plane of this cell is crossed exactly at `t`.
    let mut face: Option<usize> = None;
    let allowed = faces.map_or(0b111, |m| entered_faces(f, c, t, m[voxel as usize]));
    for a in (0..3).filter(|&a| f.moving[a] && allowed & (1 << a) != 0) {
        if f.t(a, c[a]) == t && face.is_none_or(|b| f.d[a] > f.d[b]) {
            face = Some(a);
        }
    }
    let inside = face.is_none();
    let face_axis = face.unwrap_or_else(|| {
        let d = f.dir.abs();
        if d.x >= d.y && d.x >= d.z {
            0
        } else if d.y >= d.z {
            1
        } else {
            2
        }
    });
    let mut face_normal = DVec3::ZERO;
    face_normal[face_axis] = if f.dir[face_axis] > 0.0 { -1.0 } else { 1.0 };
    Some(ObjectHit {
        voxel,
        cell: [0, 1, 2].map(|a| f.orig(a, c[a]) as u32),
        t,
        face_axis,
        face_normal,
        inside,
    })
}

/// The axes (bit `a`) through whose near face, set in `mask`, the ray enters cell `c`
/// (mirrored frame) at time `t`.
fn entered_faces(f: &Frame, c: [i64; 3], t: f64, mask: u8) -> u32 {
    let mut axes = 0;
    for a in (0..3).filter(|&a| f.moving[a]) {
        // Moving toward +a the ray enters through the −a face (bit a), else the +a face.
        let bit = if f.mirrored[a] { a + 3 } else { a };
        if f.t(a, c[a]) == t && mask & (1 << bit) != 0 {
            axes |= 1 << a;
        }
    }
    axes
}

/// Remembers, per node size of the lookup's tree, the last region found occupied, so the
/// hierarchical traversal queries the tree only when the ray enters a new region.
#[derive(Default)]
struct SkipCache {
    /// `occupied[m]`: the last occupied region of `4^m` cells per axis.
    occupied: Vec<Option<[[i64; 2]; 3]>>,
}

impl SkipCache {
    /// If every cell the ray can touch before leaving the current region of `4^m` cells
    /// (largest `m` first, down to 4³ bricks) is empty, advance `st` to the first crossing
    /// time at which the ray reaches that region's far boundary. Returns whether it skipped.
    fn try_skip(&mut self, f: &Frame, st: &mut State, lookup: &SparseLookup) -> bool {
        let depth = lookup.depth as usize;
        self.occupied.resize(depth, None);
        for m in (1..depth).rev() {
            let unit = 1i64 << (2 * m);
            // The region (in units, original coordinates) holding the current cells.
            let mut region = [[0i64; 2]; 3];
            for (a, r) in region.iter_mut().enumerate() {
                *r = if f.moving[a] {
                    let u = f.orig(a, st.next[a] - 1) / unit;
                    [u, u]
                } else {
                    [st.lo[a] / unit, st.hi[a] / unit]
                };
            }
            if self.occupied[m] == Some(region) {
                continue;
            }
            let mut empty = true;
            'scan: for z in region[2][0]..=region[2][1] {
                for y in region[1][0]..=region[1][1] {
                    for x in region[0][0]..=region[0][1] {
                        if lookup.region_occupied(m as u32, [x as u32, y as u32, z as u32]) {
                            empty = false;
                            break 'scan;
                        }
                    }
                }
            }
            if !empty {
                self.occupied[m] = Some(region);
                continue;
            }
            // Far plane of the region per moving axis, in the mirrored frame.
            let mut far = [0i64; 3];
            let mut t_exit = f64::INFINITY;
            for a in (0..3).filter(|&a| f.moving[a]) {
                let u = region[a][0];
                far[a] = if f.mirrored[a] {
                    f.n - u * unit
                } else {
                    ((u + 1) * unit).min(f.n)
                };
                t_exit = t_exit.min(f.t(a, far[a]));
            }
            // Land exactly where the cell-by-cell loop would be just before the event at
            // `t_exit`: every plane crossed strictly earlier is behind.
            for a in (0..3).filter(|&a| f.moving[a]) {
                let k = f.first_plane(a, st.next[a], far[a], t_exit, false);
                st.next[a] = k;
                st.t_next[a] = f.t(a, k);
            }
            return true;
        }
        false
    }
}
