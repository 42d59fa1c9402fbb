//! The CPU side of the tie tests beyond the reference: which occupied cells a point
//! touches, whether a hit lies on an edge, and an independent model of the dense DDA's
//! own tie stepping.

use glam::DVec3;
use ssbvb_gpu::scene::Scene;
use ssbvb_voxel::asset::SparseLookup;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;

use super::{LEVEL, PixelHit};

/// The occupied cells (instance, cell) whose closed box holds the world point `p`.
pub(super) fn touching(scene: &Scene, p: DVec3) -> Vec<(u32, [u32; 3])> {
    let s = cell_size(LEVEL);
    let n = 1i64 << LEVEL;
    let mut out = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let q = o.instances[0].inverse().transform_point3(p);
        let axis = |v: f64| -> Vec<i64> {
            let u = (v + 1.0) / s;
            let r = u.round();
            let c = if (u - r).abs() < 1e-7 {
                vec![r as i64 - 1, r as i64]
            } else {
                vec![u.floor() as i64]
            };
            c.into_iter().filter(|&k| (0..n).contains(&k)).collect()
        };
        let lookup = &o.asset.lods[LEVEL as usize].lookup;
        for &x in &axis(q.x) {
            for &y in &axis(q.y) {
                for &z in &axis(q.z) {
                    let c = [x as u32, y as u32, z as u32];
                    if lookup.get(c).is_some() {
                        out.push((i as u32, c));
                    }
                }
            }
        }
    }
    out
}

/// Whether the reference's hit point lies, besides the entered face's plane, in another
/// cell plane of its instance (the grid's faces included): the ray meets an edge or corner
/// there, or runs inside a cell plane.
pub(super) fn at_edge(scene: &Scene, h: &ssbvb_voxel::reference::Hit) -> bool {
    let s = cell_size(LEVEL);
    let n = (1u64 << LEVEL) as f64;
    let q = scene.objects[h.instance as usize].instances[0]
        .inverse()
        .transform_point3(h.position);
    let face = h.face_normal.iter().position(|v| v.abs() > 0.5);
    (0..3).any(|a| {
        let u = (q[a] + 1.0) / s;
        let r = u.round();
        Some(a) != face && (u - r).abs() < 1e-7 && (0.0..=n).contains(&r)
    })
}

/// The first occupied cell of a cell-by-cell walk of the object-space ray `o + t·d` (f64,
/// per-plane times like the reference; `d` not normalized, so `t` keeps its scale) that
/// steps one axis at a time: the one crossed first, on a tie the largest `|d|`, then the
/// lower axis, the face being the axis last stepped. The independent model of the dense
/// DDA's documented rule (dense_dda.wgsl).
/// Starts at the latest slab entry (ties: largest `|d|`, then the lower axis) in the
/// cell the ray is in just after it, or inside at the floor cell with the dominant axis of
/// `d` as the face; axes with `d == 0` keep the floor cell of the origin.
pub(super) fn walk(lookup: &SparseLookup, o: DVec3, d: DVec3) -> Option<([u32; 3], f64, usize)> {
    let n = 1i64 << LEVEL;
    let s = cell_size(LEVEL);
    let mirrored = [d.x < 0.0, d.y < 0.0, d.z < 0.0];
    let om: [f64; 3] = std::array::from_fn(|a| if mirrored[a] { -o[a] } else { o[a] });
    let da: [f64; 3] = std::array::from_fn(|a| d[a].abs());
    let plane = |a: usize, k: i64| ((-1.0 + k as f64 * s) - om[a]) / da[a];
    let (mut t_enter, mut t_exit, mut enter_axis) = (f64::NEG_INFINITY, f64::INFINITY, 0);
    for a in 0..3 {
        if da[a] == 0.0 {
            if !(-1.0..=1.0).contains(&o[a]) {
                return None;
            }
            continue;
        }
        let te = plane(a, 0);
        if te > t_enter || (te == t_enter && da[a] > da[enter_axis]) {
            (t_enter, enter_axis) = (te, a);
        }
        t_exit = t_exit.min(plane(a, n));
    }
    let t0 = t_enter.max(0.0);
    if t0 > t_exit {
        return None;
    }
    let mut cell = [0i64; 3];
    let mut t_next = [f64::INFINITY; 3];
    for a in 0..3 {
        let p = om[a] + t0 * da[a];
        let mut i = (((p + 1.0) / s).floor() as i64).clamp(0, n - 1);
        if da[a] != 0.0 {
            while i < n - 1 && plane(a, i + 1) <= t0 {
                i += 1;
            }
            while i > 0 && plane(a, i) > t0 {
                i -= 1;
            }
            t_next[a] = plane(a, i + 1);
        }
        cell[a] = i;
    }
    let mut face = enter_axis;
    if t_enter < 0.0 {
        face = if da[0] >= da[1] && da[0] >= da[2] {
            0
        } else if da[1] >= da[2] {
            1
        } else {
            2
        };
    }
    let mut t = t0;
    loop {
        let orig: [u32; 3] =
            std::array::from_fn(|a| if mirrored[a] { n - 1 - cell[a] } else { cell[a] } as u32);
        if lookup.get(orig).is_some() {
            return Some((orig, t, face));
        }
        let tm = t_next.iter().copied().fold(f64::INFINITY, f64::min);
        if tm > t_exit || !tm.is_finite() {
            return None;
        }
        let a = (0..3)
            .filter(|&a| t_next[a] == tm)
            .reduce(|a, b| if da[b] > da[a] { b } else { a })
            .expect("an axis crossed at tm");
        cell[a] += 1;
        if cell[a] >= n {
            return None;
        }
        t_next[a] = plane(a, cell[a] + 1);
        t = tm;
        face = a;
    }
}

/// `walk` over every instance of a scene for pixel `(x, y)`: the nearest hit, ties to the
/// lower index (as the ray casters' instance walk).
pub(super) fn walk_pixel(
    scene: &Scene,
    camera: &Camera,
    n: u32,
    x: u32,
    y: u32,
) -> Option<PixelHit> {
    let (eye, dir) = camera.ray(x, y, n, n);
    let mut best: Option<PixelHit> = None;
    for (i, o) in scene.objects.iter().enumerate() {
        let xf = o.instances[0];
        let inv = xf.inverse();
        let lookup = &o.asset.lods[LEVEL as usize].lookup;
        let Some((cell, t, axis)) = walk(
            lookup,
            inv.transform_point3(eye),
            inv.transform_vector3(dir),
        ) else {
            continue;
        };
        if best.is_none_or(|b| t < b.t) {
            let d = inv.transform_vector3(dir);
            let mut face = [0; 3];
            face[axis] = if d[axis] > 0.0 { -1 } else { 1 };
            best = Some(PixelHit {
                instance: i as u32,
                cell,
                face,
                t,
            });
        }
    }
    best
}
