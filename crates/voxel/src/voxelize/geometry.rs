//! Geometry of the mesh voxelizer: the separating axis test, convex polygon clipping and
//! the walk over the cells a triangle overlaps.

use glam::DVec3;

/// Tolerance, in cells, by which candidate ranges and clip slabs are widened so that
/// rounding never drops a cell the exact separating-axis test would keep. Candidates are
/// always confirmed (by that test, or by a point of the triangle strictly inside the
/// cell), so the tolerance adds work, never voxels.
const EPS: f64 = 1e-7;

/// Whether triangle `tri` overlaps the closed axis-aligned box of centre `center` and half
/// edge `half` (Akenine-Möller's separating axis test, 13 axes). Touching counts as
/// overlapping. Degenerate triangles (segments, points) are handled: their vanishing axes
/// separate nothing, and the remaining axes are exactly the segment/box (or point/box) test.
pub fn triangle_box_overlap(tri: &[DVec3; 3], center: DVec3, half: f64) -> bool {
    let v = [tri[0] - center, tri[1] - center, tri[2] - center];
    // Box face normals: the triangle's bounding box against the box.
    let min = v[0].min(v[1]).min(v[2]);
    let max = v[0].max(v[1]).max(v[2]);
    if min.max_element() > half || max.min_element() < -half {
        return false;
    }
    // Cross products of the triangle edges with the box axes.
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    for e in edges {
        for k in 0..3 {
            // axis = unit_k × e
            let axis = match k {
                0 => DVec3::new(0.0, -e.z, e.y),
                1 => DVec3::new(e.z, 0.0, -e.x),
                _ => DVec3::new(-e.y, e.x, 0.0),
            };
            let p0 = axis.dot(v[0]);
            let p1 = axis.dot(v[1]);
            let p2 = axis.dot(v[2]);
            let r = half * (axis.x.abs() + axis.y.abs() + axis.z.abs());
            if p0.min(p1).min(p2) > r || p0.max(p1).max(p2) < -r {
                return false;
            }
        }
    }
    // The triangle's plane.
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let d = n.dot(v[0]);
    let r = half * (n.x.abs() + n.y.abs() + n.z.abs());
    d.abs() <= r
}

/// A convex polygon (a triangle clipped by up to six planes has at most 9 vertices).
#[derive(Clone, Copy)]
pub(super) struct Poly {
    n: usize,
    p: [DVec3; 10],
}

impl Poly {
    fn triangle(t: &[DVec3; 3]) -> Poly {
        let mut p = [DVec3::ZERO; 10];
        p[..3].copy_from_slice(t);
        Poly { n: 3, p }
    }

    /// Clips to the closed slab `lo <= x[axis] <= hi`.
    fn clip_slab(&self, axis: usize, lo: f64, hi: f64) -> Poly {
        self.clip_half(axis, hi, 1.0).clip_half(axis, -lo, -1.0)
    }

    /// Keeps the part with `sign · x[axis] <= bound` (Sutherland–Hodgman, closed).
    fn clip_half(&self, axis: usize, bound: f64, sign: f64) -> Poly {
        let mut out = Poly {
            n: 0,
            p: [DVec3::ZERO; 10],
        };
        let mut push = |q: DVec3| {
            if out.n < out.p.len() {
                out.p[out.n] = q;
                out.n += 1;
            }
        };
        // A single point (n = 1) is its own edge: kept when inside, never crossing.
        let n = self.n;
        for i in 0..n {
            let a = self.p[i];
            let b = self.p[(i + 1) % n];
            let da = sign * a[axis] - bound;
            let db = sign * b[axis] - bound;
            if da <= 0.0 {
                push(a);
            }
            if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
                let t = da / (da - db);
                let mut q = a + (b - a) * t;
                // Land exactly on the plane so later range tests see it there.
                q[axis] = sign * bound;
                push(q);
            }
        }
        out
    }

    fn range(&self, axis: usize) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for q in &self.p[..self.n] {
            lo = lo.min(q[axis]);
            hi = hi.max(q[axis]);
        }
        (lo, hi)
    }

    /// Mean of the vertices (inside the polygon, as it is convex).
    fn mean(&self) -> DVec3 {
        self.p[..self.n].iter().copied().sum::<DVec3>() / self.n.max(1) as f64
    }

    /// Area of the (planar, convex) polygon.
    pub(super) fn area(&self) -> f64 {
        let pts = &self.p[..self.n];
        let mut sum = DVec3::ZERO;
        for i in 1..self.n.saturating_sub(1) {
            sum += (pts[i] - pts[0]).cross(pts[i + 1] - pts[0]);
        }
        0.5 * sum.length()
    }

    /// Area and area centroid; for a polygon of (near) zero area, the vertex mean.
    pub(super) fn area_centroid(&self) -> (f64, DVec3) {
        if self.n == 0 {
            return (0.0, DVec3::ZERO);
        }
        let pts = &self.p[..self.n];
        let mean = self.mean();
        let mut area = 0.0;
        let mut c = DVec3::ZERO;
        for i in 1..self.n.saturating_sub(1) {
            let a = 0.5 * (pts[i] - pts[0]).cross(pts[i + 1] - pts[0]).length();
            area += a;
            c += (pts[0] + pts[i] + pts[i + 1]) * (a / 3.0);
        }
        if area > 1e-14 && c.is_finite() {
            (area, c / area)
        } else {
            (0.0, mean)
        }
    }
}

/// Lowest cell index whose closed box `[i, i+1]` may touch coordinate `x` (widened by EPS).
fn cell_lo(x: f64) -> i64 {
    (x - EPS).ceil() as i64 - 1
}

/// Highest cell index whose closed box may touch coordinate `x` (widened by EPS).
fn cell_hi(x: f64) -> i64 {
    (x + EPS).floor() as i64
}

/// The axis to walk in depth: the dominant normal axis, or for a degenerate triangle the
/// axis of its largest extent (so a segment becomes a few long columns).
fn depth_axis(t: &[DVec3; 3]) -> usize {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    let v = if n.max_element() > 0.0 {
        n
    } else {
        t[0].max(t[1]).max(t[2]) - t[0].min(t[1]).min(t[2])
    };
    if v.x >= v.y && v.x >= v.z {
        0
    } else if v.y >= v.z {
        1
    } else {
        2
    }
}

/// Calls `f(cell, part)` for every unit cell with index in `lo..=hi` (per axis) whose
/// closed box overlaps the triangle, where `part` is the triangle clipped to the cell.
pub(super) fn for_each_cell(
    tri: &[DVec3; 3],
    lo: [i64; 3],
    hi: [i64; 3],
    mut f: impl FnMut([i64; 3], &Poly),
) {
    let w = depth_axis(tri);
    let a = (w + 1) % 3;
    let b = (w + 2) % 3;
    let full = Poly::triangle(tri);
    let (amin, amax) = full.range(a);
    for i in cell_lo(amin).max(lo[a])..=cell_hi(amax).min(hi[a]) {
        let row = full.clip_slab(a, i as f64 - EPS, (i + 1) as f64 + EPS);
        if row.n == 0 {
            continue;
        }
        let (bmin, bmax) = row.range(b);
        for j in cell_lo(bmin).max(lo[b])..=cell_hi(bmax).min(hi[b]) {
            let col = row.clip_slab(b, j as f64 - EPS, (j + 1) as f64 + EPS);
            if col.n == 0 {
                continue;
            }
            let (wmin, wmax) = col.range(w);
            for k in cell_lo(wmin).max(lo[w])..=cell_hi(wmax).min(hi[w]) {
                let mut cell = [0i64; 3];
                cell[a] = i;
                cell[b] = j;
                cell[w] = k;
                let center = DVec3::new(
                    cell[0] as f64 + 0.5,
                    cell[1] as f64 + 0.5,
                    cell[2] as f64 + 0.5,
                );
                let part = col.clip_slab(w, k as f64 - EPS, (k + 1) as f64 + EPS);
                if part.n == 0 {
                    continue;
                }
                // The vertex mean of the clipped part is a point of the triangle; when it
                // lies well inside the cell the overlap is certain and the separating
                // axis test (the exact arbiter for the near-boundary cases) is skipped.
                let mean = part.mean();
                let inside = (0..3).all(|q| {
                    let c = cell[q] as f64;
                    mean[q] > c + 1e-6 && mean[q] < c + 1.0 - 1e-6
                });
                if inside || triangle_box_overlap(tri, center, 0.5) {
                    f(cell, &part);
                }
            }
        }
    }
}

/// Upper bound of the cells a triangle (in grid units) overlaps, counted per column along
/// the walk axis `w`. The columns touched by the triangle's projection lie inside that
/// projection grown by one cell: at most its area + √2·perimeter + 4 of them (bounded
/// with 2·perimeter). In a column the triangle's `w` range ℓ touches at most ℓ + 2
/// closed cells; ℓ is at most the depth extent and at most the rise across one column:
/// the plane's slopes `(|n_a| + |n_b|) / |n_w|` (≤ 2, `w` being the dominant normal axis),
/// or for a segment-like triangle its rise along a chord of √2.
pub(super) fn cell_estimate(t: &[DVec3; 3]) -> f64 {
    let w = depth_axis(t);
    let a = (w + 1) % 3;
    let b = (w + 2) % 3;
    let p = |v: DVec3| glam::DVec2::new(v[a], v[b]);
    let (p0, p1, p2) = (p(t[0]), p(t[1]), p(t[2]));
    let area = 0.5 * (p1 - p0).perp_dot(p2 - p0).abs();
    let edges = [(p1 - p0).length(), (p2 - p1).length(), (p0 - p2).length()];
    let perim = edges[0] + edges[1] + edges[2];
    let depth = t[0][w].max(t[1][w]).max(t[2][w]) - t[0][w].min(t[1][w]).min(t[2][w]);
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let longest = (t[1] - t[0])
        .length()
        .max((t[2] - t[1]).length())
        .max((t[0] - t[2]).length());
    // A normal within rounding of zero says nothing about the slopes.
    let rise = if n.length() > 1e-9 * longest * longest {
        (n[a].abs() + n[b].abs()) / n[w].abs()
    } else {
        std::f64::consts::SQRT_2 * depth / edges[0].max(edges[1]).max(edges[2])
    };
    // NaN (a point: 0 / 0) falls back to the depth.
    (area + 2.0 * perim + 4.0) * (depth.min(rise) + 2.0)
}

#[cfg(test)]
#[path = "geometry_tests.rs"]
mod tests;
