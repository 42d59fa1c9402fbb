//! One-voxel instances (level 0: an instance is one cell) spread over a wide lens, each
//! turned, stretched and sheared its own way: every quad stands alone, so a quad that
//! differs from the model's shows in the union of the coverage instead of hiding under a
//! neighbour's, as it does on the bunny.
//!
//! - Under a 100° lens the cells near the image's corners are strongly distorted, so
//!   which candidate rectangle has the least area varies from cell to cell (the
//!   screen-aligned one wins where the three edges from corner 0 converge away from the
//!   hull's edges).
//! - Sheared cells have four diagonals of different lengths, and each of the four is the
//!   longest for some instance: the circumscribed sphere takes the longest.
//! - Two small cells sit by the near plane: one whose circumscribed sphere ends within
//!   0.05 % beyond it (in the near field: the quad covers the screen, each pixel tests its
//!   ray against the box, and the depth is the centre's), one whose sphere ends at 1.5
//!   times the near distance (a rectangle).

use glam::{DAffine3, DMat3, DQuat, DVec2, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_passes::kinds::billboards::Footprint;
use ssbvb_voxel::camera::Camera;

use super::{Comparison, SIZE, compare};

/// The lens: wide, so that perspective distorts the cells by the image's edges.
const FOV_Y_DEG: f64 = 100.0;
const NEAR: f64 = 0.1;
/// Screen cells across and down, one instance in each (the near pair take two).
const GRID: (u32, u32) = (5, 4);

/// SplitMix64: a fixed sequence of numbers in [0, 1).
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn between(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// The wide lens at the origin, looking along −z.
pub(crate) fn camera() -> Camera {
    let mut cam = Camera::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0));
    cam.fov_y_deg = FOV_Y_DEG;
    cam.near = NEAR;
    cam
}

/// The slope (x / depth, y / depth) of screen cell (`i`, `j`)'s centre.
fn cell_slope(i: u32, j: u32) -> (f64, f64) {
    let tan_y = (FOV_Y_DEG.to_radians() * 0.5).tan();
    let tan_x = tan_y * SIZE.0 as f64 / SIZE.1 as f64;
    let u = (i as f64 + 0.5) / GRID.0 as f64 * 2.0 - 1.0;
    let v = 1.0 - (j as f64 + 0.5) / GRID.1 as f64 * 2.0;
    (u * tan_x * 0.9, v * tan_y * 0.9)
}

/// Signs of the shears (xy, xz, yz): with them positive, diagonal a + b + c is the longest;
/// (+, −, −) makes it a + b − c, (−, +, −) a − b + c, (−, −, +) b + c − a.
const SHEAR_SIGNS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
];

/// A turned, stretched and sheared linear part with half-extent about `h`, sheared with
/// `signs`.
fn sheared(n: &mut Numbers, h: f64, signs: [f64; 3]) -> DMat3 {
    let turn = DQuat::from_euler(
        glam::EulerRot::YXZ,
        n.between(-3.1, 3.1),
        n.between(-1.5, 1.5),
        n.between(-3.1, 3.1),
    );
    let mut shear = |sign: f64| sign * n.between(0.1, 0.3) * h;
    let (xy, xz, yz) = (shear(signs[0]), shear(signs[1]), shear(signs[2]));
    let mut stretch = || n.between(0.7, 1.3) * h;
    let m = DMat3::from_cols(
        DVec3::new(stretch(), xy, xz),
        DVec3::new(xy, stretch(), yz),
        DVec3::new(xz, yz, stretch()),
    );
    DMat3::from_quat(turn) * m
}

/// The scene: one instance per screen cell at 1.5 to 3 units, `size` its half-extent in
/// slope units of its distance; with `near_pair`, the bottom-left two cells hold the
/// cells by the near plane instead.
pub(crate) fn scene(seed: u64, size: f64, near_pair: bool) -> Scene {
    let mut n = Numbers(seed);
    let mut instances = Vec::new();
    for j in 0..GRID.1 {
        for i in 0..GRID.0 {
            let (sx, sy) = cell_slope(i, j);
            let near = near_pair && j == GRID.1 - 1 && i < 2;
            let (depth, m) = if near {
                // A turned cube of half-extent h: circumradius h·√3; its sphere ends at
                // NEAR · 1.0005 (in the near field) or NEAR · 1.5 (a rectangle).
                let h = 0.012;
                let ends = if i == 0 { 1.0005 } else { 1.5 };
                let turn = DQuat::from_euler(glam::EulerRot::YXZ, 0.6, 0.4, 0.3);
                (
                    NEAR * ends + h * 3f64.sqrt(),
                    DMat3::from_quat(turn) * DMat3::from_diagonal(DVec3::splat(h)),
                )
            } else {
                let depth = n.between(1.5, 3.0);
                let signs = SHEAR_SIGNS[instances.len() % 4];
                (depth, sheared(&mut n, size * depth, signs))
            };
            instances.push(DAffine3 {
                matrix3: m,
                translation: DVec3::new(sx * depth, sy * depth, -depth),
            });
        }
    }
    one_voxel_scene(instances)
}

/// One object, a single cell at level 0, drawn once per instance.
fn one_voxel_scene(instances: Vec<DAffine3>) -> Scene {
    Scene {
        objects: vec![VoxelObject {
            asset: crate::empty_space::synthetic_asset(0, &[[0, 0, 0]]),
            instances,
            lod: LodPolicy::Fixed(0),
        }],
        ..Default::default()
    }
}

fn assert_isolated_exact(what: &str, c: &Comparison, voxels: usize) {
    c.assert_no_wrong_pixel(what);
    assert_eq!(c.voxels, voxels, "{what}: every instance is seen");
    assert!(c.inside > 800, "{what}: {c:?}");
    assert!(c.ambiguous * 50 < c.inside, "{what}: {c:?}");
}

/// Box footprints of isolated, distorted cells: each the least-area rectangle of the
/// model, and the near-field cell's pixels exactly those whose rays hit its box, at its
/// centre's depth.
#[test]
fn isolated_box_footprints_are_the_least_area_rectangles() {
    let cells = (GRID.0 * GRID.1) as usize;
    for seed in [1, 2] {
        let c = compare(&scene(seed, 0.09, true), &camera(), Footprint::Box);
        assert_isolated_exact(&format!("box, seed {seed}"), &c, cells);
        assert_eq!(c.near_field, 1, "one cell is in the near field");
        assert!(c.near_depths.len() > 20, "{:?}", c.near_depths.len());
        for &(i, gpu, centre) in &c.near_depths {
            assert!(
                (f64::from(gpu) - centre).abs() <= 1e-5 * centre,
                "pixel {i}: depth {gpu}, the near-field cell's centre is at {centre}"
            );
        }
    }
}

/// Sphere footprints of sheared cells: the bound of the sphere through the cell's farthest
/// corners, whichever of the four diagonals is the longest.
#[test]
fn isolated_sphere_footprints_take_the_longest_diagonal() {
    let s = scene(3, 0.06, false);
    // Not vacuous: each diagonal is the longest of some instance.
    let mut longest = [0; 4];
    for xf in &s.objects[0].instances {
        let [a, b, c] = [xf.matrix3.x_axis, xf.matrix3.y_axis, xf.matrix3.z_axis];
        let d = [a + b + c, a + b - c, a - b + c, b + c - a].map(|d| d.length());
        let k = (0..4).max_by(|&p, &q| d[p].total_cmp(&d[q])).unwrap();
        longest[k] += 1;
    }
    assert!(longest.iter().all(|&k| k >= 2), "{longest:?}");
    let c = compare(&s, &camera(), Footprint::Sphere);
    assert_isolated_exact("sphere, sheared", &c, (GRID.0 * GRID.1) as usize);
}

/// Two cells by the eye, in the near field: one whose centre is behind the eye plane (the
/// camera just outside its side), one whose centre lies between the eye and the near
/// plane. Both are drawn where their boxes are hit, nearest (depth 1), as the reference
/// sees every hit at t >= 0.
#[test]
fn near_field_cells_by_the_eye_are_drawn_nearest() {
    let cell = |centre: DVec3| DAffine3 {
        matrix3: DMat3::from_diagonal(DVec3::splat(0.1)),
        translation: centre,
    };
    let scene = one_voxel_scene(vec![
        // Behind the eye plane (view z > 0), left of the camera.
        cell(DVec3::new(-0.15, 0.0, 0.02)),
        // In front of the eye, nearer than the near plane, right of the camera.
        cell(DVec3::new(0.15, 0.0, -0.05)),
    ]);
    let c = compare(&scene, &camera(), Footprint::Box);
    assert_isolated_exact("near field by the eye", &c, 2);
    assert_eq!(c.near_field, 2);
    assert!(c.near_depths.len() > 1000, "{}", c.near_depths.len());
    for &(i, gpu, centre) in &c.near_depths {
        assert_eq!((gpu, centre), (1.0, 1.0), "pixel {i}");
    }
}

/// The slope bounds (x / −z, y / −z; least and greatest) of an axis-aligned box of
/// half-extents `h` centred at `c`, the camera at the origin looking along −z.
fn slope_bounds(c: DVec3, h: DVec3) -> (DVec2, DVec2) {
    (0..8)
        .map(|k| {
            let s = |bit: u32| {
                if k >> bit & 1 == 1 {
                    h[bit as usize]
                } else {
                    -h[bit as usize]
                }
            };
            DVec2::new(c.x + s(0), c.y + s(1)) / -(c.z + s(2))
        })
        .fold((DVec2::MAX, DVec2::MIN), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        })
}

/// An axis-aligned cell of half-extents `h`, 2 units ahead, its centre at height slope
/// `y_slope`, placed (by bisection in f64) so that column `col`'s pixel centres lie
/// `beyond` guards (1/1024 pixel) right of its rectangle's right edge.
fn guard_cell(view: &super::View, col: u32, beyond: f64, h: DVec3, y_slope: f64) -> DAffine3 {
    let target = view.pixel_slope(col as usize).x - beyond * view.pixel() / 1024.0;
    // The edge moves right with the cell.
    let (mut a, mut b) = (-5.0, 5.0);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if slope_bounds(DVec3::new(m, 0.0, -2.0), h).1.x < target {
            a = m;
        } else {
            b = m;
        }
    }
    DAffine3 {
        matrix3: DMat3::from_diagonal(h),
        translation: DVec3::new(0.5 * (a + b), y_slope * 2.0, -2.0),
    }
}

/// Cells across the screen's edges and corners, a near-field cell across the right edge,
/// and a tall cell whose right edge ends 3/4 of a guard short of column 60's pixel centres
/// (a column of centres 1/4096 pixel inside its quad): where `splat::` holds the splat's
/// pixel ranges to the rasterizer's.
pub(crate) fn edge_scene() -> Scene {
    let view = super::View::new(&camera(), SIZE);
    let (tx, ty) = (view.tan.x, view.tan.y);
    let cube = |sx: f64, sy: f64, depth: f64, h: f64| DAffine3 {
        matrix3: DMat3::from_quat(DQuat::from_euler(glam::EulerRot::YXZ, 0.4, 0.3, 0.2))
            * DMat3::from_diagonal(DVec3::splat(h)),
        translation: DVec3::new(sx * depth, sy * depth, -depth),
    };
    let mut instances: Vec<DAffine3> = [
        (-tx, 0.6 * ty),
        (-0.4 * tx, ty),
        (0.0, -ty),
        (-tx, -ty),
        (tx, ty),
        (tx, -ty),
    ]
    .iter()
    .map(|&(sx, sy)| cube(sx, sy, 2.0, 0.15))
    .collect();
    // Near field: its sphere (radius h·√3) ends at 1.0005 × the near distance.
    let h = 0.02;
    instances.push(cube(tx, 0.0, NEAR * 1.0005 + h * 3f64.sqrt(), h));
    instances.push(guard_cell(&view, 60, 0.75, DVec3::new(0.1, 0.6, 0.1), 0.0));
    one_voxel_scene(instances)
}

/// The guard: a quad reaches 1/1024 pixel beyond its rectangle, no more and no less. A cube
/// whose rectangle's right edge ends 3/4 of that short of a column's pixel centres covers
/// them; one whose edge ends 5/4 of it short covers none.
#[test]
fn a_quads_guard_is_a_1024th_of_a_pixel() {
    let cam = camera();
    let view = super::View::new(&cam, SIZE);
    let px = view.pixel();
    let h = 0.1;
    // (column, pixel centres' distance beyond the edge in guards, centre's height slope).
    let cases = [(60u32, 0.75, 0.0), (30u32, 1.25, 0.6)];
    let instances: Vec<DAffine3> = (cases.iter())
        .map(|&(col, beyond, y_slope)| guard_cell(&view, col, beyond, DVec3::splat(h), y_slope))
        .collect();
    let scene = one_voxel_scene(instances);
    let mut opts = crate::billboard_harness::options(ssbvb_graph::BillboardMode::Flat);
    opts.cull_cos = -2.0;
    let (g, _) = crate::billboard_harness::draw(&scene, &cam, SIZE, Some(opts), false);
    for (&(col, beyond, _), xf) in cases.iter().zip(&scene.objects[0].instances) {
        // The rows whose centres lie well inside the cube's vertical extent.
        let (lo, hi) = slope_bounds(xf.translation, DVec3::splat(h));
        let rows: Vec<u32> = (0..SIZE.1)
            .filter(|&r| {
                let y = view.pixel_slope((r * SIZE.0) as usize).y;
                y > lo.y + 0.1 * px && y < hi.y - 0.1 * px
            })
            .collect();
        assert!(rows.len() >= 2, "rows {rows:?}");
        for r in rows {
            let i = (r * SIZE.0 + col) as usize;
            assert!(
                g.covered(i - 1),
                "column {}, row {r}: inside the cube",
                col - 1
            );
            assert_eq!(
                g.covered(i),
                beyond < 1.0,
                "column {col}, row {r}: the centre is {beyond} guards beyond the rectangle"
            );
        }
    }
}
