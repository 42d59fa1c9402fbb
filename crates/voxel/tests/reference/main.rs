//! Tests of the CPU reference ray caster against analytic geometry and against two
//! independent oracles (the cell-by-cell DDA and a brute-force test of every voxel).
//!
//! The shared helpers (scenes, analytic intersections, coverage checks) are here; the
//! oracle comparisons, the exact rules, the analytic scenes, the extreme cases and the
//! multi-instance and PNG tests have a module each.

mod analytic;
mod extremes;
mod instances;
mod oracle;
mod outputs;
mod rules;
mod supersample;
mod surface;
mod traversal;

#[path = "../support/rng.rs"]
mod rng;

use glam::{DAffine3, DVec2, DVec3};
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, ProxyMesh, SparseLookup};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::cell_size;
use ssbvb_voxel::reference::{Instance, ReferenceImage, render};
use ssbvb_voxel::shading::Light;
use ssbvb_voxel::svo::morton_encode;

use rng::Rng;

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

/// A LOD level from cells, normals pointing away from the origin. Voxel ids are Morton
/// ranks (the lookup implies them), so the point cloud is sorted: see [`id_of`].
fn lod(level: u32, cells: &[[u32; 3]]) -> LodLevel {
    let s = cell_size(level);
    let mut cells = cells.to_vec();
    cells.sort_by_key(|&c| morton_encode(c));
    let voxels = cells
        .iter()
        .map(|&c| {
            let centre = c.map(|v| (-1.0 + (v as f64 + 0.5) * s) as f32);
            PackedVoxel::new(c, centre, [0.8, 0.6, 0.4, 1.0], [0.0; 2])
        })
        .collect();
    LodLevel {
        level,
        point_cloud: PointCloud { voxels },
        lookup: SparseLookup::from_cells(level, cells.iter().copied()),
        proxy: ProxyMesh::default(),
    }
}

/// The voxel id of `cell` in a level built by [`lod`].
fn id_of(lod: &LodLevel, cell: [u32; 3]) -> u32 {
    lod.lookup.get(cell).expect("cell is a voxel")
}

/// Lower boundary of cell `k` (exact for the levels used here).
fn b(level: u32, k: i64) -> f64 {
    -1.0 + k as f64 * cell_size(level)
}

/// Cells whose centre lies within `r` of the origin.
fn ball_cells(level: u32, r: f64) -> Vec<[u32; 3]> {
    let n = 1u32 << level;
    let s = cell_size(level);
    let mut cells = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = DVec3::new(x as f64, y as f64, z as f64) * s + DVec3::splat(-1.0 + s * 0.5);
                if c.length() <= r {
                    cells.push([x, y, z]);
                }
            }
        }
    }
    cells
}

/// Slab test of a world-space ray against an axis-aligned box: `(t_enter, entry axis)`.
fn ray_box(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, usize, f64)> {
    let (mut t0, mut t1, mut axis, mut second) =
        (f64::NEG_INFINITY, f64::INFINITY, 0, f64::NEG_INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        let (near, far) = (ta.min(tb), ta.max(tb));
        if near > t0 {
            second = t0;
            t0 = near;
            axis = a;
        } else if near > second {
            second = near;
        }
        t1 = t1.min(far);
    }
    // Also return the gap to the runner-up entry plane so callers can skip edge ties.
    (t0 <= t1 && t1 >= 0.0).then_some((t0.max(0.0), axis, t0 - second))
}

/// Ray–sphere (`d` unit): the nearest `t >= 0` or `None`. Uses the closest-approach
/// point, which stays accurate when the eye is 1e7 radii away (the textbook discriminant
/// `b² - c` cancels catastrophically there).
fn ray_sphere(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let t_close = -oc.dot(d);
    let perp = oc + d * t_close;
    let h2 = r * r - perp.length_squared();
    if h2 < 0.0 {
        return None;
    }
    let t = t_close - h2.sqrt();
    (t >= 0.0).then_some(t)
}

fn assert_finite(img: &ReferenceImage) {
    assert!(img.all_finite(), "non-finite value in the reference image");
    for h in img.hits.iter().flatten() {
        let n = DVec3::from(h.face_normal.map(f64::from));
        assert!(
            (n.length() - 1.0).abs() < 1e-5,
            "face normal not unit: {n:?}"
        );
    }
}

/// Convex hull (counter-clockwise) of 2D points, Andrew's monotone chain.
fn convex_hull(mut p: Vec<DVec2>) -> Vec<DVec2> {
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Signed distance-like margin of `q` inside a CCW convex polygon (positive inside).
fn polygon_margin(poly: &[DVec2], q: DVec2) -> f64 {
    let mut m = f64::INFINITY;
    for i in 0..poly.len() {
        let (a, c) = (poly[i], poly[(i + 1) % poly.len()]);
        let e = c - a;
        m = m.min(e.perp_dot(q - a) / e.length());
    }
    m
}

/// Checks a rendered world box pixel by pixel against its analytic projection (convex hull
/// of the 8 projected corners) and its analytic entry depth and face. Returns the number
/// of pixels covered.
fn check_projected_box(img: &ReferenceImage, cam: &Camera, lo: DVec3, hi: DVec3) -> usize {
    let (w, h) = (img.width, img.height);
    let vp = cam.view_projection(w as f64 / h as f64);
    let corners: Vec<DVec2> = (0..8)
        .map(|i| {
            let p = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let c = vp * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            DVec2::new(
                (ndc.x + 1.0) * 0.5 * w as f64,
                (1.0 - ndc.y) * 0.5 * h as f64,
            )
        })
        .collect();
    let hull = convex_hull(corners);
    let mut covered = 0;
    for py in 0..h {
        for px in 0..w {
            let m = polygon_margin(&hull, DVec2::new(px as f64 + 0.5, py as f64 + 0.5));
            let hit = img.hit(px, py);
            if m > 1e-6 {
                let hit =
                    hit.unwrap_or_else(|| panic!("pixel ({px},{py}) inside by {m} but missed"));
                covered += 1;
                let (o, d) = cam.ray(px, py, w, h);
                let (t, axis, gap) = ray_box(o, d, lo, hi).expect("analytic ray misses");
                assert!(
                    (hit.t - t).abs() <= 1e-9 * t.max(1e-300),
                    "({px},{py}) t {} vs {t}",
                    hit.t
                );
                if gap > 1e-9 * t {
                    let mut n = DVec3::ZERO;
                    n[axis] = -d[axis].signum();
                    let got = DVec3::from(hit.face_normal.map(f64::from));
                    assert!(
                        got.dot(n) > 1.0 - 1e-6,
                        "pixel ({px},{py}): normal {got} vs {n}"
                    );
                }
            } else if m < -1e-6 {
                assert!(
                    hit.is_none(),
                    "pixel ({px},{py}) outside by {m} but hit {hit:?}"
                );
            }
        }
    }
    covered
}

/// World box of `cell` of a LOD placed with `xf`, for axis-aligned transforms only.
fn cell_box(level: u32, cell: [u32; 3]) -> (DVec3, DVec3) {
    let s = cell_size(level);
    let lo = DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64) * s - DVec3::ONE;
    (lo, lo + DVec3::splat(s))
}

/// Renders one instance of `l` and checks that every pixel is finite.
fn render_one(l: &LodLevel, xf: DAffine3, cam: &Camera, w: u32, h: u32) -> ReferenceImage {
    let img = render(
        &[Instance {
            lod: l,
            object_to_world: xf,
            faces: None,
        }],
        cam,
        w,
        h,
        &Light::default(),
    );
    assert_finite(&img);
    img
}

/// Checks a ball (cells with centre within `r` of `centre`, all in world units, voxel
/// half-diagonal `hd`) against the analytic sphere. Returns the pixel coverage.
fn check_ball(img: &ReferenceImage, cam: &Camera, centre: DVec3, r: f64, hd: f64) -> usize {
    let (w, h) = (img.width, img.height);
    let mut covered = 0;
    for py in 0..h {
        for px in 0..w {
            let (o, d) = cam.ray(px, py, w, h);
            let hit = img.hit(px, py);
            let outer = ray_sphere(o, d, centre, r + hd);
            let inner = ray_sphere(o, d, centre, r - hd);
            match (hit, outer, inner) {
                (Some(hit), Some(t_out), _) => {
                    covered += 1;
                    let tol = 1e-9 * t_out;
                    assert!(
                        hit.t >= t_out - tol,
                        "({px},{py}) {} before outer {t_out}",
                        hit.t
                    );
                    if let Some(t_in) = inner {
                        assert!(
                            hit.t <= t_in + tol,
                            "({px},{py}) {} after inner {t_in}",
                            hit.t
                        );
                    }
                    let n = DVec3::from(hit.face_normal.map(f64::from));
                    assert!(n.dot(d) < 0.0, "normal faces the ray");
                }
                (Some(hit), None, _) => panic!("({px},{py}) hit {hit:?} outside the outer sphere"),
                (None, _, Some(_)) => panic!("({px},{py}) missed inside the inner sphere"),
                (None, _, None) => {}
            }
        }
    }
    covered
}
