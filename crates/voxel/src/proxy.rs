//! Conservative proxy meshes (`docs/architecture.md`, "Preparation").
//!
//! The empty-space prepass rasterizes the proxy to find where each pixel's ray enters the
//! object. A proxy that misses any part of any voxel makes holes, so the proxy here is the
//! exact boundary of a union of grid-aligned boxes that contain every voxel:
//!
//! - [`build_proxy`]: the union of the resident 16³ pages (for levels below 4 the single
//!   page is clipped to the grid, i.e. the whole [-1, 1]³ box);
//! - [`build_proxy_bricks`]: the union of occupied bricks of 1, 2, 4, 8 or 16 cells per
//!   side: tighter (fewer empty cells to march) at the price of more triangles.
//!
//! # Construction
//!
//! 1. Every brick face whose neighbour brick is empty (or outside the grid) is a boundary
//!    face; faces are grouped per axis, orientation and plane.
//! 2. Greedy meshing merges each plane's faces into maximal-ish rectangles (row by row:
//!    widen along the first in-plane axis, then grow along the second).
//! 3. **No T-junctions.** Merged rectangles of different sizes meet with the corner of one
//!    lying inside the edge of another. Rasterization is only watertight across edges that
//!    both triangles share with identical endpoints: at a T-junction the long edge and the
//!    two short ones are projected and rounded independently, which can leave sub-pixel
//!    cracks where the prepass sees no proxy (a hole in the final image). So every corner
//!    that lies on another rectangle's edge is inserted into that edge, and a rectangle
//!    with such extra vertices is triangulated as a fan around its centre (one triangle per
//!    boundary segment, none degenerate); plain rectangles stay two triangles. The result
//!    is closed in the strict sense checked by [`check_closed`]: every directed edge is
//!    matched by its reverse (edges where two boxes touch only along a line carry two
//!    such pairs — the union of boxes is not always a manifold, which the rasterizer does
//!    not care about).
//! 4. Triangles are counter-clockwise seen from outside. All vertices lie on the grid
//!    lattice (or half of it, for fan centres), which f32 represents exactly up to level 22,
//!    so the mesh encloses the voxels exactly, with no epsilon.

use std::collections::{HashMap, HashSet};

use glam::DVec3;

use crate::asset::{PAGE_SIZE, ProxyMesh, SparseLookup};
use crate::model::cell_size;

/// The proxy of a level: the boundary of the union of its resident pages (see the module
/// docs). Empty lookups give an empty mesh.
pub fn build_proxy(lookup: &SparseLookup) -> ProxyMesh {
    build_proxy_bricks(lookup, PAGE_SIZE)
}

/// The boundary of the union of occupied bricks of `brick` cells per side (rounded down to
/// a power of two in 1..=16, and to the grid size for small levels). `brick = 16` is
/// [`build_proxy`].
pub fn build_proxy_bricks(lookup: &SparseLookup, brick: u32) -> ProxyMesh {
    let n = 1i64 << lookup.level;
    let brick = 1i64 << (brick.clamp(1, PAGE_SIZE).ilog2());
    let brick = brick.min(n);
    let bricks = occupied_bricks(lookup, brick);
    let rects = merged_faces(&bricks);
    triangulate(&rects, brick, cell_size(lookup.level))
}

/// [`build_proxy`] from the occupied 16³ pages alone (page coordinates; the whole grid
/// for levels below 4): what the streaming preparation has of a level it never holds.
pub fn build_proxy_of_pages(level: u32, pages: &[[u32; 3]]) -> ProxyMesh {
    let brick = i64::from(PAGE_SIZE).min(1i64 << level);
    let bricks: HashSet<[i64; 3]> = pages.iter().map(|p| p.map(i64::from)).collect();
    let rects = merged_faces(&bricks);
    triangulate(&rects, brick, cell_size(level))
}

/// Every occupied brick (coordinates in bricks): the occupied regions of the largest
/// tree node size `4^m ≤ brick`, merged by the remaining factor (1 or 2).
fn occupied_bricks(lookup: &SparseLookup, brick: i64) -> HashSet<[i64; 3]> {
    let m = brick.ilog2() / 2;
    let factor = brick >> (2 * m);
    lookup
        .occupied_regions(m)
        .into_iter()
        .map(|r| r.map(|v| v as i64 / factor))
        .collect()
}

/// A merged boundary rectangle, in brick units: normal axis `axis`, `positive` when the
/// outward normal is `+e_axis`, lying in plane `plane`, covering `[u0, u0 + w] × [v0, v0 + h]`
/// of the in-plane axes `u = (axis + 1) % 3`, `v = (axis + 2) % 3`.
#[derive(Debug, Clone, Copy)]
struct Rect {
    axis: usize,
    positive: bool,
    plane: i64,
    u0: i64,
    v0: i64,
    w: i64,
    h: i64,
}

/// Boundary faces of the brick union, greedily merged into rectangles per plane.
fn merged_faces(bricks: &HashSet<[i64; 3]>) -> Vec<Rect> {
    let mut groups: HashMap<(usize, bool, i64), Vec<(i64, i64)>> = HashMap::new();
    for b in bricks {
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for positive in [false, true] {
                let mut nb = *b;
                nb[axis] += if positive { 1 } else { -1 };
                if !bricks.contains(&nb) {
                    let plane = if positive { b[axis] + 1 } else { b[axis] };
                    groups
                        .entry((axis, positive, plane))
                        .or_default()
                        .push((b[v], b[u]));
                }
            }
        }
    }
    // Deterministic output regardless of hash order.
    let mut keys: Vec<_> = groups.keys().copied().collect();
    keys.sort_unstable();
    let mut rects = Vec::new();
    for key in keys {
        let mut faces = groups.remove(&key).unwrap_or_default();
        faces.sort_unstable();
        let mut left: HashSet<(i64, i64)> = faces.iter().copied().collect();
        for &(v0, u0) in &faces {
            if !left.contains(&(v0, u0)) {
                continue;
            }
            let mut w = 1;
            while left.contains(&(v0, u0 + w)) {
                w += 1;
            }
            let mut h = 1;
            while (0..w).all(|i| left.contains(&(v0 + h, u0 + i))) {
                h += 1;
            }
            for dv in 0..h {
                for du in 0..w {
                    left.remove(&(v0 + dv, u0 + du));
                }
            }
            let (axis, positive, plane) = key;
            rects.push(Rect {
                axis,
                positive,
                plane,
                u0,
                v0,
                w,
                h,
            });
        }
    }
    rects
}

/// Builds the mesh: T-junction vertices inserted, centre fans where needed, CCW outside.
/// Vertex keys are doubled cell-lattice coordinates (fan centres may be half-integers).
fn triangulate(rects: &[Rect], brick: i64, s: f64) -> ProxyMesh {
    let corner = |r: &Rect, du: i64, dv: i64| {
        let mut p = [0i64; 3];
        p[r.axis] = 2 * brick * r.plane;
        p[(r.axis + 1) % 3] = 2 * brick * (r.u0 + du);
        p[(r.axis + 2) % 3] = 2 * brick * (r.v0 + dv);
        p
    };
    // Every rectangle corner, indexed by the axis-aligned line through it along each axis.
    let mut lines: HashMap<(usize, i64, i64), Vec<i64>> = HashMap::new();
    for r in rects {
        for (du, dv) in [(0, 0), (r.w, 0), (r.w, r.h), (0, r.h)] {
            let p = corner(r, du, dv);
            for dir in 0..3 {
                let key = (dir, p[(dir + 1) % 3], p[(dir + 2) % 3]);
                lines.entry(key).or_default().push(p[dir]);
            }
        }
    }
    for list in lines.values_mut() {
        list.sort_unstable();
        list.dedup();
    }
    let mut mesh = ProxyMesh::default();
    let mut index: HashMap<[i64; 3], u32> = HashMap::new();
    let mut vertex = |p: [i64; 3], mesh: &mut ProxyMesh| -> u32 {
        *index.entry(p).or_insert_with(|| {
            mesh.positions
                .push(p.map(|c| (-1.0 + c as f64 * 0.5 * s) as f32));
            (mesh.positions.len() - 1) as u32
        })
    };
    for r in rects {
        // Boundary polygon, counter-clockwise seen from +e_axis (e_u × e_v = e_axis), with
        // every corner of another rectangle that lies inside one of its edges.
        let ring = [(0, 0), (r.w, 0), (r.w, r.h), (0, r.h)].map(|(du, dv)| corner(r, du, dv));
        let mut poly: Vec<[i64; 3]> = Vec::with_capacity(8);
        for i in 0..4 {
            let (a, b) = (ring[i], ring[(i + 1) % 4]);
            poly.push(a);
            let dir = (0..3).find(|&d| a[d] != b[d]).unwrap_or(0);
            let key = (dir, a[(dir + 1) % 3], a[(dir + 2) % 3]);
            if let Some(list) = lines.get(&key) {
                let (lo, hi) = (a[dir].min(b[dir]), a[dir].max(b[dir]));
                let start = list.partition_point(|&x| x <= lo);
                let end = list.partition_point(|&x| x < hi);
                let inner = &list[start..end.max(start)];
                let mut push = |x: i64| {
                    let mut p = a;
                    p[dir] = x;
                    poly.push(p);
                };
                if a[dir] < b[dir] {
                    inner.iter().for_each(|&x| push(x));
                } else {
                    inner.iter().rev().for_each(|&x| push(x));
                }
            }
        }
        if !r.positive {
            poly.reverse();
        }
        let ids: Vec<u32> = poly.iter().map(|&p| vertex(p, &mut mesh)).collect();
        if ids.len() == 4 {
            mesh.triangles.push([ids[0], ids[1], ids[2]]);
            mesh.triangles.push([ids[0], ids[2], ids[3]]);
        } else {
            let mut c = corner(r, 0, 0);
            c[(r.axis + 1) % 3] += brick * r.w;
            c[(r.axis + 2) % 3] += brick * r.h;
            let centre = vertex(c, &mut mesh);
            for i in 0..ids.len() {
                mesh.triangles
                    .push([centre, ids[i], ids[(i + 1) % ids.len()]]);
            }
        }
    }
    mesh
}

/// Checks that `mesh` is a closed, consistently oriented surface without cracks: indices
/// in range, finite positions, no degenerate triangle, and every directed edge `a → b`
/// matched by as many `b → a` (this also rejects T-junctions, whose long edge has no
/// reverse).
pub fn check_closed(mesh: &ProxyMesh) -> Result<(), String> {
    let n = mesh.positions.len() as u32;
    if let Some(p) = mesh
        .positions
        .iter()
        .find(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(format!("non-finite vertex {p:?}"));
    }
    let mut balance: HashMap<(u32, u32), i64> = HashMap::new();
    for (i, t) in mesh.triangles.iter().enumerate() {
        if t.iter().any(|&v| v >= n) {
            return Err(format!("triangle {i} {t:?} indexes past {n} vertices"));
        }
        let p = t.map(|v| DVec3::from(mesh.positions[v as usize].map(f64::from)));
        if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() == 0.0 {
            return Err(format!("triangle {i} {t:?} is degenerate"));
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *balance.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
        }
    }
    let mut open: Vec<_> = balance.into_iter().filter(|&(_, c)| c != 0).collect();
    if open.is_empty() {
        return Ok(());
    }
    open.sort_unstable();
    let ((a, b), c) = open[0];
    Err(format!(
        "{} unmatched edges, e.g. {a} {:?} – {b} {:?} (balance {c})",
        open.len(),
        mesh.positions[a as usize],
        mesh.positions[b as usize]
    ))
}

/// Signed volume enclosed by a closed mesh (positive when it is oriented counter-clockwise
/// seen from outside).
pub fn signed_volume(mesh: &ProxyMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let p = t.map(|v| DVec3::from(mesh.positions[v as usize].map(f64::from)));
            p[0].dot(p[1].cross(p[2])) / 6.0
        })
        .sum()
}

/// Point-in-mesh queries by signed crossings of a +x ray, with triangles binned by their
/// (y, z) bounds.
struct WindingQuery<'a> {
    mesh: &'a ProxyMesh,
    bins: Vec<Vec<u32>>,
    res: usize,
}

impl<'a> WindingQuery<'a> {
    fn new(mesh: &'a ProxyMesh) -> Self {
        // About two triangles per bin for a surface spread over the square, capped so the
        // bin table stays small.
        let res = ((mesh.triangles.len() as f64).sqrt() as usize).clamp(8, 512);
        let mut bins = vec![Vec::new(); res * res];
        for (i, t) in mesh.triangles.iter().enumerate() {
            let p = t.map(|v| mesh.positions[v as usize]);
            let (y0, y1) = (
                p[0][1].min(p[1][1]).min(p[2][1]),
                p[0][1].max(p[1][1]).max(p[2][1]),
            );
            let (z0, z1) = (
                p[0][2].min(p[1][2]).min(p[2][2]),
                p[0][2].max(p[1][2]).max(p[2][2]),
            );
            let (by0, by1) = (Self::bin(y0 as f64, res), Self::bin(y1 as f64, res));
            let (bz0, bz1) = (Self::bin(z0 as f64, res), Self::bin(z1 as f64, res));
            for bz in bz0..=bz1 {
                for by in by0..=by1 {
                    bins[by + res * bz].push(i as u32);
                }
            }
        }
        Self { mesh, bins, res }
    }

    /// Bin of a coordinate (closed bins: a triangle touching a bin border is in both).
    fn bin(x: f64, res: usize) -> usize {
        (((x + 1.0) * 0.5 * res as f64).floor().max(0.0) as usize).min(res - 1)
    }

    /// Winding number of the mesh around `p`: +1 inside a closed mesh oriented CCW from
    /// outside, 0 outside. Ties (the ray through an edge or vertex) are broken by
    /// simulation of simplicity: `p` is perturbed by `(0, ε, ε²)`, consistently for every
    /// triangle, so each crossing is counted exactly once.
    fn winding(&self, p: DVec3) -> i64 {
        let bin = Self::bin(p.y, self.res) + self.res * Self::bin(p.z, self.res);
        let mut w = 0;
        for &ti in &self.bins[bin] {
            let t = self.mesh.triangles[ti as usize];
            let v = t.map(|i| DVec3::from(self.mesh.positions[i as usize].map(f64::from)));
            // Projected orientation = sign of the normal's x component.
            let area = orient_yz(v[0], v[1], v[2]);
            if area == 0.0 {
                continue;
            }
            let sign = area.signum();
            let inside = (0..3).all(|k| orient_sos(v[k], v[(k + 1) % 3], p) * sign > 0.0);
            if !inside {
                continue;
            }
            // x of the triangle's plane at (p.y, p.z), by barycentric interpolation.
            let b0 = orient_yz(v[1], v[2], p) / area;
            let b1 = orient_yz(v[2], v[0], p) / area;
            let b2 = 1.0 - b0 - b1;
            let x = b0 * v[0].x + b1 * v[1].x + b2 * v[2].x;
            if x > p.x {
                w += sign as i64;
            }
        }
        w
    }
}

/// Twice the signed area of the (y, z) projection of `a, b, c`.
fn orient_yz(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    (b.y - a.y) * (c.z - a.z) - (b.z - a.z) * (c.y - a.y)
}

/// [`orient_yz`] of `a, b, p + (0, ε, ε²)`: never zero for `a ≠ b` in projection.
fn orient_sos(a: DVec3, b: DVec3, p: DVec3) -> f64 {
    let o = orient_yz(a, b, p);
    if o != 0.0 {
        return o;
    }
    // d/dε of (b.y - a.y)(p.z + ε² - a.z) - (b.z - a.z)(p.y + ε - a.y) is -(b.z - a.z);
    // the ε² term breaks the remaining tie.
    let dz = b.z - a.z;
    if dz != 0.0 { -dz } else { b.y - a.y }
}

/// Checks that `proxy` is closed ([`check_closed`]) and encloses every voxel of `lookup`:
/// the centre of each voxel and a point a quarter cell in from each of its corners have
/// winding number exactly 1 (inside, oriented outwards). For lattice-aligned proxies like
/// [`build_proxy`]'s this is exact: such a solid is a union of cells, so a cell is inside
/// iff its centre is.
pub fn proxy_encloses(lookup: &SparseLookup, proxy: &ProxyMesh) -> Result<(), String> {
    check_closed(proxy)?;
    let q = WindingQuery::new(proxy);
    let s = cell_size(lookup.level);
    for c in lookup.cells() {
        let cell = c.map(|v| v as f64);
        let lo = DVec3::from(cell) * s - DVec3::ONE;
        let mut points = vec![lo + DVec3::splat(0.5 * s)];
        for corner in 0..8 {
            let f = |bit: usize| if corner & bit == 0 { 0.25 } else { 0.75 };
            points.push(lo + DVec3::new(f(1), f(2), f(4)) * s);
        }
        for p in points {
            let w = q.winding(p);
            if w != 1 {
                return Err(format!(
                    "voxel at cell {cell:?}: point {p} has winding number {w} (expected 1)"
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_page_is_a_twelve_triangle_box() {
        let l = SparseLookup::from_cells(6, [[17, 3, 40]].into_iter());
        let m = build_proxy(&l);
        assert_eq!((m.positions.len(), m.triangles.len()), (8, 12));
        check_closed(&m).unwrap();
        assert!((signed_volume(&m) - 0.5f64.powi(3)).abs() < 1e-12);
        proxy_encloses(&l, &m).unwrap();
    }

    #[test]
    fn t_junctions_are_split() {
        // An L of pages: a 2×1 rectangle on top meets two 1×1 squares... every merged
        // rectangle whose edge carries another's corner is fanned, and the mesh is closed.
        let l = SparseLookup::from_cells(
            6,
            [[0, 0, 0], [16, 0, 0], [0, 16, 0], [0, 0, 16]].into_iter(),
        );
        let m = build_proxy(&l);
        check_closed(&m).unwrap();
        assert!((signed_volume(&m) - 4.0 * 0.125).abs() < 1e-12);
        proxy_encloses(&l, &m).unwrap();
    }

    #[test]
    fn empty_lookup_gives_empty_mesh() {
        let l = SparseLookup::from_cells(5, std::iter::empty::<[u32; 3]>());
        let m = build_proxy(&l);
        assert!(m.triangles.is_empty() && m.positions.is_empty());
        check_closed(&m).unwrap();
        proxy_encloses(&l, &m).unwrap();
    }

    #[test]
    fn winding_detects_outside_and_wrong_orientation() {
        let l = SparseLookup::from_cells(6, [[17, 3, 40]].into_iter());
        let m = build_proxy(&l);
        let q = WindingQuery::new(&m);
        // The page is x in [-0.5, 0], y in [-1, -0.5], z in [0, 0.5].
        assert_eq!(q.winding(DVec3::new(-0.3, -0.7, 0.3)), 1);
        assert_eq!(q.winding(DVec3::new(0.3, -0.7, 0.3)), 0);
        // The +x ray runs exactly through the diagonal edge of the x faces' triangle
        // pairs: counted once (inside) or once each way (outside).
        assert_eq!(q.winding(DVec3::new(-0.25, -0.75, 0.25)), 1);
        assert_eq!(q.winding(DVec3::new(-0.75, -0.75, 0.25)), 0);
        // On the box's projected outline the perturbation (0, +ε, +ε²) decides: above
        // the top edge y = -0.5 is outside, past the lower corner (y, z) = (-1, 0) inside.
        assert_eq!(q.winding(DVec3::new(-0.25, -0.5, 0.25)), 0);
        assert_eq!(q.winding(DVec3::new(-0.25, -1.0, 0.0)), 1);
        let mut flipped = m.clone();
        flipped.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        assert!(proxy_encloses(&l, &flipped).is_err());
        // A proxy that misses a voxel is rejected.
        let other = SparseLookup::from_cells(6, [[17, 3, 40], [63, 63, 63]].into_iter());
        assert!(proxy_encloses(&other, &m).is_err());
    }
}
