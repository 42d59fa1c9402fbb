//! A Flat billboard's footprint, pixel by pixel, against a CPU model of its quad.
//!
//! The other billboard tests hold the footprint only through coverage IoU and the absence of
//! holes, which any quad somewhat larger than the voxel's projection passes. Here every
//! pixel is checked against the quad the footprint rule defines, computed in f64:
//!
//! - `Box`: of the bounding rectangles of the cell's eight projected corners aligned with
//!   the screen or with one of the three projected edges from corner 0, the one of least
//!   area (the rule of `billboard_quad.inc.wgsl`, written again here);
//! - `Sphere`: the exact slope bounds of the circumscribed sphere, from its tangent lines
//!   through the eye (an independent derivation: angles, not the shader's closed form).
//!
//! Both are widened by the shader's guard (1/1024 pixel). A pixel within [`BAND_PX`] of a
//! quad's edge is left out (f32 against f64), and where two candidate rectangles tie in area
//! within f32's precision a pixel must be inside (or outside) all of them to count.

use glam::{DAffine3, DQuat, DVec2, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_graph::BillboardMode;
use ssbvb_passes::kinds::billboards::Footprint;
use ssbvb_tests::{model_asset, single_object_scene};
use ssbvb_voxel::camera::Camera;

use crate::billboard_harness::{BUNNY, GBuffer, LEVEL, cameras, draw, options};

pub(crate) mod isolated;

const SIZE: (u32, u32) = (96, 72);
/// Pixels this close to a quad's edge are not compared (in pixels).
const BAND_PX: f64 = 2e-3;
/// Candidate rectangles whose areas differ by less than this share tie (f32 picks either).
const AREA_TIE: f64 = 1e-5;

/// A rectangle in slope space (x / -z, y / -z of view space): centre `mid` and half
/// extents `half` in the frame (`axis`, perp(`axis`)).
#[derive(Debug, Clone, Copy)]
struct Rect {
    axis: DVec2,
    mid: DVec2,
    half: DVec2,
}

impl Rect {
    /// How far inside the rectangle slope `s` is (negative: outside), in slope units: the
    /// least margin over both axes.
    fn margin(&self, s: DVec2) -> f64 {
        let perp = DVec2::new(-self.axis.y, self.axis.x);
        let local = DVec2::new(s.dot(self.axis), s.dot(perp)) - self.mid;
        (self.half - local.abs()).min_element()
    }
}

/// The view of a camera: basis, lens and the slope of each pixel centre.
struct View {
    eye: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    tan: DVec2,
    size: (u32, u32),
    near: f64,
    /// World → clip (reversed Z), as the frame's.
    view_proj: glam::DMat4,
}

impl View {
    fn new(camera: &Camera, size: (u32, u32)) -> Self {
        let (right, up, forward) = camera.basis();
        let tan_y = (camera.fov_y_deg.to_radians() * 0.5).tan();
        Self {
            eye: camera.position,
            right,
            up,
            forward,
            tan: DVec2::new(tan_y * size.0 as f64 / size.1 as f64, tan_y),
            size,
            near: camera.near,
            view_proj: camera.view_projection(size.0 as f64 / size.1 as f64),
        }
    }

    /// A camera-relative world vector in view space (x right, y up, z toward the viewer).
    fn to_view(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.right), v.dot(self.up), -v.dot(self.forward))
    }

    /// The slope of pixel `i`'s centre (row 0 at the top).
    fn pixel_slope(&self, i: usize) -> DVec2 {
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let (x, y) = (
            (i % self.size.0 as usize) as f64,
            (i / self.size.0 as usize) as f64,
        );
        let ndc = DVec2::new((x + 0.5) / w * 2.0 - 1.0, 1.0 - (y + 0.5) / h * 2.0);
        ndc * self.tan
    }

    /// The world direction of a ray of slope `s`.
    fn direction(&self, s: DVec2) -> DVec3 {
        self.right * s.x + self.up * s.y + self.forward
    }

    /// One pixel in slope units (vertically).
    fn pixel(&self) -> f64 {
        2.0 * self.tan.y / self.size.1 as f64
    }
}

/// What a voxel's billboard covers by the model.
enum Model {
    /// The candidate quads: one for `Sphere`, the tied least-area ones for `Box`.
    Quads(Vec<Rect>),
    /// A near-field voxel (its circumscribed sphere reaches within 0.1 % of the near plane):
    /// the pixels whose ray hits its box, drawn at its centre's depth.
    NearField {
        world_to_object: DAffine3,
        lo: DVec3,
        hi: DVec3,
        /// Reversed-Z depth of the voxel's centre.
        depth: f64,
    },
}

/// The footprint of the voxel whose cell is `cell` at `level` of the instance `xf`.
fn model_footprint(
    view: &View,
    xf: &DAffine3,
    cell: [u32; 3],
    level: u32,
    footprint: Footprint,
) -> Model {
    let size = 2.0 / (1u64 << level) as f64;
    let lo_obj = DVec3::from(cell.map(f64::from)) * size - 1.0;
    let centre_obj = lo_obj + 0.5 * size;
    let cv = view.to_view(xf.transform_point3(centre_obj) - view.eye);
    let [a, b, c] = [xf.matrix3.x_axis, xf.matrix3.y_axis, xf.matrix3.z_axis];
    let r = 0.5
        * size
        * [a + b + c, a + b - c, a - b + c, b + c - a]
            .iter()
            .map(|d| d.length())
            .fold(0.0, f64::max);
    if cv.z + r >= -view.near * 1.001 {
        // A centre at or behind the eye is drawn nearest (depth 1), as the reference sees
        // every hit at t >= 0.
        let clip = view.view_proj * xf.transform_point3(centre_obj).extend(1.0);
        let depth = if clip.w > 0.0 {
            (clip.z / clip.w).clamp(0.0, 1.0)
        } else {
            1.0
        };
        return Model::NearField {
            world_to_object: xf.inverse(),
            lo: lo_obj,
            hi: lo_obj + size,
            depth,
        };
    }
    let guard = view.pixel() / 1024.0;
    let rect = |axis: DVec2, lo: DVec2, hi: DVec2| Rect {
        axis,
        mid: (lo + hi) * 0.5,
        half: (hi - lo) * 0.5 + guard,
    };
    Model::Quads(match footprint {
        Footprint::Sphere => {
            // Tangents from the eye to the circle of radius r about (lateral, depth).
            let bounds = |lateral: f64| {
                let depth = -cv.z;
                let centre = lateral.atan2(depth);
                let spread = (r / lateral.hypot(depth)).asin();
                ((centre - spread).tan(), (centre + spread).tan())
            };
            let (x0, x1) = bounds(cv.x);
            let (y0, y1) = bounds(cv.y);
            vec![rect(DVec2::X, DVec2::new(x0, y0), DVec2::new(x1, y1))]
        }
        Footprint::Box => {
            let edges = [a, b, c].map(|e| view.to_view(e * (0.5 * size)));
            let proj: Vec<DVec2> = (0..8)
                .map(|k| {
                    let s = |bit: u32| if k >> bit & 1 == 1 { 1.0 } else { -1.0 };
                    let p = cv + s(0) * edges[0] + s(1) * edges[1] + s(2) * edges[2];
                    DVec2::new(p.x, p.y) / -p.z
                })
                .collect();
            let mut candidates = Vec::new();
            for k in 0..4 {
                let u = if k == 0 {
                    DVec2::X
                } else {
                    let e = proj[1 << (k - 1)] - proj[0];
                    if e.length() <= 1e-12 {
                        continue;
                    }
                    e.normalize()
                };
                let v = DVec2::new(-u.y, u.x);
                let (mut lo, mut hi) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
                for p in &proj {
                    let q = DVec2::new(p.dot(u), p.dot(v));
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
                let ext = hi - lo;
                candidates.push((ext.x * ext.y, rect(u, lo, hi)));
            }
            let best = candidates.iter().map(|c| c.0).fold(f64::MAX, f64::min);
            candidates
                .into_iter()
                .filter(|c| c.0 <= best * (1.0 + AREA_TIE))
                .map(|c| c.1)
                .collect()
        }
    })
}

/// Whether the ray from `o` along `d` (object space) hits the box [`lo`, `hi`] grown by
/// `grow` of its size on every side (negative: shrunk), at t >= 0.
fn ray_hits_box(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3, grow: f64) -> bool {
    let pad = (hi - lo) * grow;
    let (lo, hi) = (lo - pad, hi + pad);
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return false;
            }
            continue;
        }
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    t0 <= t1
}

/// What the comparison found.
#[derive(Debug, Default)]
struct Comparison {
    /// Pixels the model says some quad covers, all of which the GPU drew.
    inside: usize,
    /// Pixels no quad covers, none of which the GPU drew.
    outside: usize,
    /// Pixels left out (near an edge, or candidates disagreeing).
    ambiguous: usize,
    /// Pixels where the GPU and the model disagree (the first few listed).
    wrong: Vec<(usize, bool)>,
    voxels: usize,
    /// Near-field voxels among them.
    near_field: usize,
    /// Pixels only a near-field voxel covers: (pixel, GPU depth, its centre's depth).
    near_depths: Vec<(usize, f32, f64)>,
}

/// Where a pixel is against one voxel's model footprint.
#[derive(Clone, Copy, PartialEq)]
enum Side {
    In,
    Out,
    Unsure,
}

impl Model {
    /// Where the pixel of slope `s` is (within `band` slope units of a quad's edge, or of a
    /// box's silhouette by 1e-3 of its size: unsure).
    fn side(&self, view: &View, s: DVec2, band: f64) -> Side {
        match self {
            Model::Quads(q) => {
                if q.iter().all(|rect| rect.margin(s) > band) {
                    Side::In
                } else if q.iter().all(|rect| rect.margin(s) < -band) {
                    Side::Out
                } else {
                    Side::Unsure
                }
            }
            Model::NearField {
                world_to_object: m,
                lo,
                hi,
                ..
            } => {
                let (o, d) = (
                    m.transform_point3(view.eye),
                    m.transform_vector3(view.direction(s)),
                );
                if ray_hits_box(o, d, *lo, *hi, -1e-3) {
                    Side::In
                } else if !ray_hits_box(o, d, *lo, *hi, 1e-3) {
                    Side::Out
                } else {
                    Side::Unsure
                }
            }
        }
    }
}

/// Draws `scene` (one object at a fixed level) with Flat billboards of `footprint` over
/// the reference's SSBVB, and compares every pixel with the union of the model quads.
fn compare(scene: &Scene, camera: &Camera, footprint: Footprint) -> Comparison {
    let mut opts = options(BillboardMode::Flat);
    opts.footprint = footprint;
    // No culling by stored normal: every slotted voxel draws its quad.
    opts.cull_cos = -2.0;
    let (g, r): (GBuffer, _) = draw(scene, camera, SIZE, Some(opts), false);
    let view = View::new(camera, SIZE);
    let obj = &scene.objects[0];
    let LodPolicy::Fixed(level) = obj.lod else {
        panic!("a fixed level")
    };
    let lod = &obj.asset.lods[level as usize];
    let mut voxels: Vec<(u32, u32)> = r
        .hits
        .iter()
        .flatten()
        .map(|h| (h.instance, h.voxel))
        .collect();
    voxels.sort_unstable();
    voxels.dedup();
    let models: Vec<Model> = voxels
        .iter()
        .map(|&(inst, voxel)| {
            let cell = lod.point_cloud.voxels[voxel as usize].cell();
            model_footprint(&view, &obj.instances[inst as usize], cell, level, footprint)
        })
        .collect();
    let band = BAND_PX * view.pixel();
    let mut out = Comparison {
        voxels: voxels.len(),
        near_field: (models.iter())
            .filter(|m| matches!(m, Model::NearField { .. }))
            .count(),
        ..Default::default()
    };
    for i in 0..(SIZE.0 * SIZE.1) as usize {
        let s = view.pixel_slope(i);
        let sides: Vec<Side> = models.iter().map(|m| m.side(&view, s, band)).collect();
        // Inside: some voxel holds the pixel beyond the band (every tied candidate of it);
        // outside: every voxel leaves it beyond the band.
        let surely_in = sides.contains(&Side::In);
        let surely_out = sides.iter().all(|&v| v == Side::Out);
        let drawn = g.covered(i);
        match (surely_in, surely_out) {
            (true, _) if drawn => out.inside += 1,
            (_, true) if !drawn => out.outside += 1,
            (false, false) => out.ambiguous += 1,
            _ => out.wrong.push((i, drawn)),
        }
        let covering: Vec<usize> = (0..models.len())
            .filter(|&k| sides[k] != Side::Out)
            .collect();
        if let [k] = covering[..]
            && let Model::NearField { depth, .. } = models[k]
            && sides[k] == Side::In
            && drawn
            && !g.depth.is_empty()
        {
            out.near_depths.push((i, g.depth[i], depth));
        }
    }
    out
}

impl Comparison {
    /// Prints the counts and fails on any pixel where the GPU and the model disagree.
    fn assert_no_wrong_pixel(&self, what: &str) {
        eprintln!(
            "{what}: {} voxels ({} near field), {} inside, {} outside, {} left out, {} wrong",
            self.voxels,
            self.near_field,
            self.inside,
            self.outside,
            self.ambiguous,
            self.wrong.len()
        );
        assert!(
            self.wrong.is_empty(),
            "{what}: (pixel, GPU drew it) where the model disagrees: {:?}",
            &self.wrong[..self.wrong.len().min(12)]
        );
    }
}

fn assert_exact(what: &str, c: &Comparison) {
    c.assert_no_wrong_pixel(what);
    // Not vacuous: most covered pixels are decided, and the views cover a good part.
    assert!(c.inside > 300 && c.voxels > 20, "{what}: {c:?}");
    assert!(c.ambiguous * 50 < c.inside, "{what}: {c:?}");
}

#[test]
fn box_footprints_are_the_least_area_rectangles() {
    let scene = single_object_scene(model_asset(BUNNY, LEVEL), LEVEL);
    for (name, cam) in cameras() {
        assert_exact(
            &format!("box, {name}"),
            &compare(&scene, &cam, Footprint::Box),
        );
    }
}

/// A turned and scaled instance: the cell's projected edges lie at every angle, so the
/// edge-aligned candidates win often.
#[test]
fn box_footprints_of_a_turned_instance_are_the_least_area_rectangles() {
    let scene = Scene {
        objects: vec![VoxelObject {
            asset: model_asset(BUNNY, 5),
            instances: vec![DAffine3::from_scale_rotation_translation(
                DVec3::splat(0.8),
                DQuat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 0.2),
                DVec3::new(0.1, -0.2, 0.0),
            )],
            lod: LodPolicy::Fixed(5),
        }],
        ..Default::default()
    };
    let cam = Camera::new(DVec3::new(1.2, 0.9, 2.3), DVec3::ZERO);
    assert_exact(
        "box, turned instance",
        &compare(&scene, &cam, Footprint::Box),
    );
    // Coarse voxels (about eight pixels): each quad's edges show along the silhouette.
    let mut coarse = scene;
    coarse.objects[0].lod = LodPolicy::Fixed(3);
    let c = compare(&coarse, &cam, Footprint::Box);
    assert_exact("box, turned instance, level 3", &c);
}

#[test]
fn sphere_footprints_are_the_circumscribed_spheres_bounds() {
    let scene = single_object_scene(model_asset(BUNNY, LEVEL), LEVEL);
    for (name, cam) in cameras().into_iter().take(2) {
        assert_exact(
            &format!("sphere, {name}"),
            &compare(&scene, &cam, Footprint::Sphere),
        );
    }
    // Coarse cells of a stretched, turned instance, seen from near: the four diagonals of a
    // cell differ in length (the radius is the longest), and a sphere a fifth of its
    // distance wide shows every term of the tangent slopes.
    let stretched = Scene {
        objects: vec![VoxelObject {
            asset: model_asset(BUNNY, 3),
            instances: vec![DAffine3 {
                matrix3: glam::DMat3::from_quat(DQuat::from_euler(
                    glam::EulerRot::YXZ,
                    0.5,
                    0.3,
                    -0.2,
                )) * glam::DMat3::from_cols(
                    DVec3::new(0.9, 0.0, 0.0),
                    DVec3::new(0.25, 0.5, 0.0),
                    DVec3::new(0.0, 0.0, 0.7),
                ),
                translation: DVec3::ZERO,
            }],
            lod: LodPolicy::Fixed(3),
        }],
        ..Default::default()
    };
    let near = Camera::new(DVec3::new(0.6, 0.5, 1.6), DVec3::ZERO);
    for footprint in [Footprint::Sphere, Footprint::Box] {
        assert_exact(
            &format!("{footprint:?}, stretched level 3"),
            &compare(&stretched, &near, footprint),
        );
    }
}
