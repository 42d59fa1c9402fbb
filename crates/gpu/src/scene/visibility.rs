//! Which instances a frame draws and at which level: frustum culling against each
//! instance's bounding sphere, the LOD choice, and the per-frame constants, instance
//! records and instance hierarchy the GPU reads (`Frame`, `Instance`, `BvhNode` in
//! `shaders/common.inc.wgsl`).

use glam::{DAffine3, DMat4, DVec3};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::shading::Light;

use ssbvb_voxel::instance_bvh::{Aabb, InstanceBvh};

use super::description::{LodPolicy, Scene};
use super::layout::{FrameUniform, GpuBvhNode, InstanceUniform, ProxyRange, VisibleInstance};

/// A matrix as WGSL's column-major `mat4x4<f32>`.
pub(crate) fn mat(m: DMat4) -> [[f32; 4]; 4] {
    m.as_mat4().to_cols_array_2d()
}

/// The frame constants for `camera` on a `screen`-sized target, lit by `light` (the
/// visible-instance count is filled in by the caller).
pub fn frame_uniform(camera: &Camera, screen: (u32, u32), light: &Light) -> FrameUniform {
    jittered_frame_uniform(camera, screen, light, [0.0; 2])
}

/// [`frame_uniform`] with the image shifted by `jitter` pixels: pixel `px` shows the
/// camera's ray through `px + jitter` (a temporal anti-aliasing pass's sub-pixel offsets).
pub fn jittered_frame_uniform(
    camera: &Camera,
    screen: (u32, u32),
    light: &Light,
    jitter: [f64; 2],
) -> FrameUniform {
    let (w, h) = (screen.0.max(1) as f64, screen.1.max(1) as f64);
    let aspect = w / h;
    let rot = camera.view_rotation_matrix();
    // A point on the ray through `px + jitter` lands at `px`: NDC moves by -2 jx / w and
    // +2 jy / h (clip x, y by that times w).
    let (sx, sy) = (-2.0 * jitter[0] / w, 2.0 * jitter[1] / h);
    // clip' = clip + (sx, sy) * clip.w: the w row of the input feeds x and y.
    let shear = DMat4::from_cols_array(&[
        1.0, 0.0, 0.0, 0.0, //
        0.0, 1.0, 0.0, 0.0, //
        0.0, 0.0, 1.0, 0.0, //
        sx, sy, 0.0, 1.0,
    ]);
    let proj = shear * camera.projection(aspect);
    let view_proj = proj * rot;
    let (right, up, forward) = camera.basis();
    let tan_y = (camera.fov_y_deg.clamp(1e-9, 179.999).to_radians() * 0.5).tan();
    let tan_x = tan_y * aspect;
    let ld = DVec3::from(light.unit_direction().map(f64::from));
    FrameUniform {
        view_proj: mat(view_proj),
        inv_view_proj: mat(view_proj.inverse()),
        view: mat(rot),
        proj: mat(proj),
        cam_right: (right * tan_x).as_vec3().extend(0.0).into(),
        cam_up: (up * tan_y).as_vec3().extend(0.0).into(),
        cam_forward: forward.as_vec3().extend(0.0).into(),
        screen: [w as f32, h as f32, (1.0 / w) as f32, (1.0 / h) as f32],
        light_dir: [ld.x as f32, ld.y as f32, ld.z as f32, light.ambient],
        light_color: [
            light.color[0],
            light.color[1],
            light.color[2],
            light.specular,
        ],
        shine_near_far_count: [
            light.shininess,
            camera.near as f32,
            if camera.is_infinite() {
                0.0
            } else {
                camera.far as f32
            },
            0.0,
        ],
        jitter: [jitter[0] as f32, jitter[1] as f32, 0.0, 0.0],
        streams: [0; 4],
        prepass: [0; 4],
    }
}

/// A frame's camera and screen size in pixels, and the levels finer than Auto LOD's choice
/// its frames resolve ([`GpuScene::lod_bias`](super::GpuScene::lod_bias)).
#[derive(Debug, Clone, Copy)]
pub(crate) struct View<'a> {
    pub camera: &'a Camera,
    pub screen: (u32, u32),
    pub lod_bias: u32,
}

/// Caps on the levels of a frame: the finest level an instance may use, and the finest
/// level whose proxy mesh is drawn (finer levels draw that one's).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LevelCaps {
    pub level: u32,
    pub proxy: u32,
}

/// The instances of `scene` inside the view frustum, in instance-buffer order, with the
/// record of each for the GPU. `lod_base[object]` is the object's level 0 in the LOD table,
/// `proxies[object][level]` its proxy mesh ranges.
/// `held` gives, by scene index, the level each instance was drawn at in the frame before
/// (`None`: not drawn), which Auto LOD keeps within `hysteresis` levels
/// ([`choose_level_held`]).
pub(crate) fn visible_instances(
    scene: &Scene,
    lod_base: &[u32],
    proxies: &[Vec<ProxyRange>],
    view: &View,
    caps: LevelCaps,
    held: &[Option<u32>],
    hysteresis: f64,
) -> (Vec<VisibleInstance>, Vec<InstanceUniform>) {
    let View {
        camera,
        screen,
        lod_bias,
    } = *view;
    let (w, h) = (screen.0.max(1) as f64, screen.1.max(1) as f64);
    let aspect = w / h;
    let eye = camera.position;
    let (right, up, forward) = camera.basis();
    let tan_y = (camera.fov_y_deg.clamp(1e-9, 179.999).to_radians() * 0.5).tan();
    let tan_x = tan_y * aspect;
    // Frustum planes in camera-relative world space (normals pointing inwards).
    let planes = frustum_planes(right, up, forward, tan_x, tan_y);
    let view_rotation = camera.view_rotation_matrix();
    let mut visible = Vec::new();
    let mut uniforms = Vec::new();
    let mut scene_index = 0u32;
    for (oi, obj) in scene.objects.iter().enumerate() {
        let max_level = (obj.asset.lods.len() as u32 - 1).min(caps.level);
        let policy = match obj.lod {
            LodPolicy::Auto { bias, pixel_error } => LodPolicy::Auto {
                bias: bias.saturating_add(i32::try_from(lod_bias).unwrap_or(i32::MAX)),
                pixel_error,
            },
            fixed => fixed,
        };
        for xf in &obj.instances {
            let si = scene_index;
            scene_index += 1;
            if !xf.matrix3.determinant().is_finite()
                || xf.matrix3.determinant() == 0.0
                || !xf.translation.is_finite()
            {
                continue;
            }
            // Bounding sphere of the object box [-1, 1]^3.
            let center = xf.translation - eye;
            let radius = (xf.matrix3 * DVec3::ONE).length().max(
                [
                    DVec3::new(1.0, 1.0, -1.0),
                    DVec3::new(1.0, -1.0, 1.0),
                    DVec3::new(-1.0, 1.0, 1.0),
                ]
                .iter()
                .map(|c| (xf.matrix3 * *c).length())
                .fold(0.0, f64::max),
            );
            if planes.iter().any(|(n, d)| n.dot(center) + d < -radius) {
                continue;
            }
            let previous = held.get(si as usize).copied().flatten();
            let level =
                choose_level_held(policy, xf, camera, screen, max_level, previous, hysteresis);
            let lod_index = lod_base[oi] + level;
            // Camera-relative object → world.
            let rel = DAffine3 {
                matrix3: xf.matrix3,
                translation: center,
            };
            let inv = rel.inverse();
            let cam_obj = inv.transform_point3(DVec3::ZERO);
            // The proxy drawn is that of `proxy_level`: a coarser one under a budget, and
            // one no finer than the view resolves (`proxy_detail`).
            let proxy_level = level.min(caps.proxy).min(proxy_detail(xf, camera, screen));
            let camera_inside =
                inside_resident_page(&obj.asset.lods[proxy_level as usize].lookup, cam_obj);
            // A closed proxy wholly beyond the near plane, seen from outside, hides each of
            // its back faces behind one of its front faces: only a proxy the near plane may
            // cut, or one holding the camera, needs its back faces drawn.
            let back_faces = camera_inside || center.dot(forward) - radius <= camera.near * 1.001;
            let cell_world = 2.0 * scale_of(xf) / (1u64 << level) as f64;
            uniforms.push(InstanceUniform {
                object_to_world: mat(DMat4::from(rel)),
                object_to_view: mat(view_rotation * DMat4::from(rel)),
                world_to_object: mat(DMat4::from(inv)),
                camera_object: [
                    cam_obj.x as f32,
                    cam_obj.y as f32,
                    cam_obj.z as f32,
                    cell_world as f32,
                ],
                lod: lod_index,
                level,
                flags: camera_inside as u32,
                scene_index: si,
            });
            visible.push(VisibleInstance {
                scene_index: si,
                object: oi,
                level,
                proxy: proxies[oi][proxy_level as usize],
                proxy_level,
                camera_inside,
                back_faces,
            });
        }
    }
    (visible, uniforms)
}

/// The hierarchy over the visible instances' camera-relative world boxes, as the GPU reads
/// it (item `i` is visible instance `i`; empty when none is visible). Each box bounds the
/// voxels of the instance's chosen level (`lod_bounds`, by LOD-table index); an instance
/// without voxels is left out.
///
/// The boxes come from the f32 `object_to_world` the shaders use, computed in f64, then
/// widened by 1e-5 of (distance + size) and rounded outwards: the filter's own slab test
/// runs in f32 in object space, with errors of a few ulps of those magnitudes, and a box
/// that is too tight would drop a candidate (a hole), while one too wide only costs a test.
pub(crate) fn instance_bvh(
    uniforms: &[InstanceUniform],
    lod_bounds: &[Option<(DVec3, DVec3)>],
) -> Vec<GpuBvhNode> {
    let boxes: Vec<Option<Aabb>> = uniforms
        .iter()
        .map(|u| {
            let m = glam::Mat4::from_cols_array_2d(&u.object_to_world).as_dmat4();
            let xf = DAffine3::from_mat4(m);
            let (lo, hi) = lod_bounds.get(u.lod as usize).copied().flatten()?;
            let b = Aabb::of_object_box(&xf, lo, hi)?;
            let size = (b.hi - b.lo).max_element() + b.center().abs().max_element();
            Some(b.widened(size * 1e-5))
        })
        .collect();
    // Shaders may assume no infinities: boxes beyond 1e37 are clamped (such instances
    // are outside the march's range, `MAX_ORIGIN`, anyway).
    let down = |v: f64| {
        let v = v.clamp(-1e37, 1e37);
        let f = v as f32;
        if f as f64 > v { f.next_down() } else { f }
    };
    let up = |v: f64| {
        let v = v.clamp(-1e37, 1e37);
        let f = v as f32;
        if (f as f64) < v { f.next_up() } else { f }
    };
    InstanceBvh::build(&boxes)
        .nodes()
        .iter()
        .map(|n| GpuBvhNode {
            lo: n.bounds.lo.to_array().map(down),
            left: n.left,
            hi: n.bounds.hi.to_array().map(up),
            right: n.right,
        })
        .collect()
}

/// How far past a level's threshold, in levels, the view must move before Auto LOD draws an
/// instance coarser than in the frame before: a camera hovering at a threshold would
/// otherwise switch the instance back and forth every frame (a pop each time). A quarter
/// level: the instance keeps its finer level until its cells project to at most 0.84 of
/// the pixel error (2^-0.25). Switching finer is never delayed, so the pixel-error bound
/// holds in every frame.
pub const DEFAULT_LOD_HYSTERESIS: f64 = 0.25;

/// The LOD level of an instance for a camera and screen: fixed, or the coarsest level
/// whose cell projects to at most `pixel_error` pixels at the instance's nearest
/// bounding-sphere point, plus the bias, clamped to `0..=max_level`.
pub fn choose_level(
    policy: LodPolicy,
    xf: &DAffine3,
    camera: &Camera,
    screen: (u32, u32),
    max_level: u32,
) -> u32 {
    choose_level_held(policy, xf, camera, screen, max_level, None, 0.0)
}

/// [`choose_level`] for an instance drawn at level `previous` in the frame before: under
/// Auto LOD a coarser level than `previous` is taken only as far as the view is more than
/// `hysteresis` levels past its threshold (the level chosen as if the view were
/// `hysteresis` levels finer, never finer than `previous`); a finer level at once.
/// `previous` beyond `max_level`, or a hysteresis that is not a finite positive number,
/// holds nothing.
pub fn choose_level_held(
    policy: LodPolicy,
    xf: &DAffine3,
    camera: &Camera,
    screen: (u32, u32),
    max_level: u32,
    previous: Option<u32>,
    hysteresis: f64,
) -> u32 {
    match policy {
        LodPolicy::Fixed(l) => l.min(max_level),
        LodPolicy::Auto { bias, pixel_error } => {
            let ideal = auto_detail(xf, camera, screen, pixel_error);
            let level = |ideal: f64| {
                let l = if ideal == f64::NEG_INFINITY {
                    // Any error is allowed (an infinite pixel_error): the coarsest level.
                    0
                } else if pixel_error > 0.0 && ideal.is_finite() {
                    // A hair below an integer stays there (the rounding of box_px must not
                    // cost a level).
                    (ideal - 1e-9).ceil() as i64
                } else {
                    max_level as i64
                };
                (l + bias as i64).clamp(0, max_level as i64) as u32
            };
            let now = level(ideal);
            match previous {
                Some(p)
                    if p <= max_level && now < p && hysteresis > 0.0 && hysteresis.is_finite() =>
                {
                    level(ideal + hysteresis).min(p)
                }
                _ => now,
            }
        }
    }
}

/// Auto LOD's level before rounding and bias: log2 of the whole box's projected size in
/// pixels at the instance's nearest bounding-sphere point over `pixel_error` (the coarsest
/// level whose cells project to at most `pixel_error` pixels is its ceiling).
fn auto_detail(xf: &DAffine3, camera: &Camera, screen: (u32, u32), pixel_error: f64) -> f64 {
    // Cell size in world units at level L: 2 * scale / 2^L. Projected size in pixels at
    // distance d: cell / (d * 2 tan(fov/2)) * height, i.e. the whole box's `box_px` over
    // 2^L; the coarsest L with box_px / 2^L <= pixel_error.
    let h = screen.1.max(1) as f64;
    let tan_y = (camera.fov_y_deg.clamp(1e-9, 179.999).to_radians() * 0.5).tan();
    let scale = scale_of(xf);
    let radius = scale * 3f64.sqrt();
    let dist = ((xf.translation - camera.position).length() - radius).max(camera.near.max(1e-9));
    let box_px = 2.0 * scale * h / (dist * 2.0 * tan_y);
    (box_px / pixel_error).log2()
}

/// Pixels a proxy brick (16 cells, [`ssbvb_voxel::asset::PAGE_SIZE`]) must span for its
/// level's proxy to be drawn: where a finer proxy's bricks span fewer, its triangles, four
/// times as many per level, cost the prepass more than its tighter entries save the filter
/// (docs/benchmarks.md, "Proxies no finer than the view").
pub const PROXY_BRICK_PX: f64 = 16.0;

/// Levels up to this one always draw their own proxy (cheap: about 10⁵ triangles for the
/// bundled models at level 9, and the tests' views keep theirs).
pub const PROXY_LEVEL_FLOOR: u32 = 9;

/// The finest level whose proxy bricks span at least [`PROXY_BRICK_PX`] pixels at the
/// instance's nearest (the bounding sphere's near side, as Auto LOD measures), and at
/// least [`PROXY_LEVEL_FLOOR`]; any proxy encloses every finer level's voxels (a coarse
/// cell is occupied when a finer one is), so the choice moves where rays start, never
/// what they hit.
pub fn proxy_detail(xf: &DAffine3, camera: &Camera, screen: (u32, u32)) -> u32 {
    let brick = ssbvb_voxel::asset::PAGE_SIZE as f64;
    let ideal = auto_detail(xf, camera, screen, PROXY_BRICK_PX / brick);
    if ideal.is_nan() {
        return u32::MAX;
    }
    ideal
        .floor()
        .clamp(f64::from(PROXY_LEVEL_FLOOR), f64::from(u32::MAX)) as u32
}

/// Uniform scale of an instance transform (cube root of |det|).
fn scale_of(xf: &DAffine3) -> f64 {
    xf.matrix3.determinant().abs().cbrt()
}

/// Whether an object-space point lies in a resident page of a lookup (then the proxy,
/// the union of resident pages, contains it and the prepass draws back faces).
fn inside_resident_page(lookup: &ssbvb_voxel::asset::SparseLookup, p: DVec3) -> bool {
    // NaN-safe: a NaN coordinate is not inside.
    if p.abs().max_element().partial_cmp(&1.0) != Some(std::cmp::Ordering::Less) {
        return false;
    }
    let n = (1u64 << lookup.level) as f64;
    let cell = ((p + 1.0) * 0.5 * n).floor();
    let ps = ssbvb_voxel::asset::PAGE_SIZE as f64;
    let page = (cell / ps).floor();
    lookup.page_occupied([page.x as u32, page.y as u32, page.z as u32])
}

/// The four side planes of the view frustum through the eye (origin), as (inward normal, d).
/// The near and far planes are not used: instances behind the eye fail a side plane test or
/// are handled by the prepass depth test.
fn frustum_planes(
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    tan_x: f64,
    tan_y: f64,
) -> [(DVec3, f64); 4] {
    let n = |v: DVec3| v.normalize_or(forward);
    [
        (n(forward * tan_x + right), 0.0),
        (n(forward * tan_x - right), 0.0),
        (n(forward * tan_y + up), 0.0),
        (n(forward * tan_y - up), 0.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_lod_picks_the_coarsest_level_within_the_pixel_error() {
        let cam = Camera {
            fov_y_deg: 90.0,
            ..Camera::new(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO)
        };
        // tan(45°) = 1: at distance d (to the nearest bounding-sphere point) a screen of
        // height h shows 2d world units, so a cell of 2 / 2^L projects to h / (d 2^L) px.
        let xf = DAffine3::IDENTITY;
        let d = 10.0 - 3f64.sqrt();
        let h = 720u32;
        let cell_px = |level: u32| h as f64 / d / (1u64 << level) as f64;
        let auto = |bias, pixel_error| LodPolicy::Auto { bias, pixel_error };
        for pe in [0.5, 1.0, 2.0, 3.0, 16.0] {
            let l = choose_level(auto(0, pe), &xf, &cam, (1280, h), 12);
            assert!(cell_px(l) <= pe, "pixel error {pe}: level {l}");
            assert!(
                l == 0 || cell_px(l - 1) > pe,
                "pixel error {pe}: {l} is not coarsest"
            );
        }
        let one = choose_level(LodPolicy::AUTO, &xf, &cam, (1280, h), 12);
        assert_eq!(one, (h as f64 / d).log2().ceil() as u32);
        assert_eq!(
            choose_level(auto(0, 2.0), &xf, &cam, (1280, h), 12),
            one - 1
        );
        assert_eq!(
            choose_level(auto(1, 1.0), &xf, &cam, (1280, h), 12),
            one + 1
        );
        assert_eq!(choose_level(auto(-20, 1.0), &xf, &cam, (1280, h), 12), 0);
        assert_eq!(choose_level(auto(0, 0.0), &xf, &cam, (1280, h), 12), 12);
        assert_eq!(
            choose_level(auto(0, f64::NAN), &xf, &cam, (1280, h), 12),
            12
        );
        // Twice the distance: one level coarser; a far object clamps at 0, a near one at max.
        let far = Camera {
            position: DVec3::new(0.0, 0.0, 2.0 * d + 3f64.sqrt()),
            ..cam
        };
        assert_eq!(
            choose_level(LodPolicy::AUTO, &xf, &far, (1280, h), 12),
            one - 1
        );
        let very_far = Camera {
            position: DVec3::new(0.0, 0.0, 1e9),
            ..cam
        };
        assert_eq!(
            choose_level(LodPolicy::AUTO, &xf, &very_far, (1280, h), 12),
            0
        );
        let inside = Camera {
            position: DVec3::new(0.0, 0.0, 0.5),
            ..cam
        };
        assert_eq!(choose_level(LodPolicy::AUTO, &xf, &inside, (1280, h), 9), 9);
        assert_eq!(
            choose_level(LodPolicy::Fixed(15), &xf, &cam, (1280, h), 9),
            9
        );
    }

    /// A held level: coarser only a quarter level past the threshold, finer at once, and
    /// nothing held without a previous level, beyond the cap, or with no hysteresis.
    #[test]
    fn auto_lod_holds_a_finer_level_within_the_hysteresis() {
        let cam_at = |z: f64| Camera {
            fov_y_deg: 90.0,
            ..Camera::new(DVec3::new(0.0, 0.0, z), DVec3::ZERO)
        };
        let xf = DAffine3::IDENTITY;
        let h = 720u32;
        let r = 3f64.sqrt();
        // At distance d the box projects to h / d px: level L's threshold is d = h / 2^L.
        let at = |d: f64| cam_at(d + r);
        let held = |d: f64, previous, hysteresis| {
            choose_level_held(
                LodPolicy::AUTO,
                &xf,
                &at(d),
                (1280, h),
                12,
                previous,
                hysteresis,
            )
        };
        // Level 5 suffices from d = h / 32 on (cells of at most one pixel).
        let threshold = h as f64 / 32.0;
        assert_eq!(held(threshold * 0.99, None, 0.25), 6);
        assert_eq!(held(threshold * 1.01, None, 0.25), 5);
        // Just past the threshold: held at 6 until 2^0.25 = 1.19 of its distance.
        assert_eq!(held(threshold * 1.01, Some(6), 0.25), 6);
        assert_eq!(held(threshold * 1.18, Some(6), 0.25), 6);
        assert_eq!(held(threshold * 1.20, Some(6), 0.25), 5);
        // Far past: as coarse as the hysteresis allows, not the previous level.
        assert_eq!(held(threshold * 4.5, None, 0.0), 3);
        assert_eq!(held(threshold * 4.5, Some(6), 0.25), 4);
        // Finer at once, whatever was held.
        assert_eq!(held(threshold * 0.99, Some(5), 0.25), 6);
        assert_eq!(held(threshold * 0.3, Some(5), 0.25), 7);
        // Nothing held without hysteresis, at a non-finite one, or above the cap.
        assert_eq!(held(threshold * 1.01, Some(6), 0.0), 5);
        assert_eq!(held(threshold * 1.01, Some(6), f64::NAN), 5);
        assert_eq!(held(threshold * 1.01, Some(6), f64::INFINITY), 5);
        assert_eq!(
            choose_level_held(
                LodPolicy::AUTO,
                &xf,
                &at(threshold * 1.01),
                (1280, h),
                5,
                Some(6),
                0.25
            ),
            5
        );
        // A fixed policy ignores the previous level.
        assert_eq!(
            choose_level_held(
                LodPolicy::Fixed(3),
                &xf,
                &at(threshold),
                (1280, h),
                12,
                Some(6),
                0.25
            ),
            3
        );
    }

    /// The GPU nodes hold, rounded outwards to f32 and widened, each instance's box of its
    /// level's voxels; an instance whose level has no voxels is left out.
    #[test]
    fn gpu_hierarchy_boxes_contain_the_voxel_boxes() {
        let xf = |x: f64, s: f64| DAffine3 {
            matrix3: glam::DMat3::from_rotation_y(0.3) * s,
            translation: DVec3::new(x, 1e3 / 3.0, -7.1),
        };
        let uniform = |m: DAffine3, lod: u32| InstanceUniform {
            object_to_world: mat(DMat4::from(m)),
            object_to_view: mat(DMat4::from(m)),
            world_to_object: mat(DMat4::from(m.inverse())),
            camera_object: [0.0; 4],
            lod,
            level: 0,
            flags: 0,
            scene_index: 0,
        };
        let bounds = [
            Some((DVec3::new(-0.5, -1.0, 0.0), DVec3::new(0.5, 0.25, 1.0))),
            None,
        ];
        let xfs = [xf(1.0, 0.7), xf(-4.0, 1.3), xf(9.5, 0.01)];
        let uniforms = [uniform(xfs[0], 0), uniform(xfs[1], 1), uniform(xfs[2], 0)];
        let nodes = instance_bvh(&uniforms, &bounds);
        assert_eq!(nodes.len(), 3, "two items: a root and two leaves");
        let mut items = Vec::new();
        for n in &nodes {
            if n.left & ssbvb_voxel::instance_bvh::LEAF == 0 {
                continue;
            }
            let item = (n.left & !ssbvb_voxel::instance_bvh::LEAF) as usize;
            items.push(item);
            // The box of the f32 transform the shaders use, in f64.
            let m = glam::Mat4::from_cols_array_2d(&uniforms[item].object_to_world).as_dmat4();
            let (lo, hi) = bounds[0].unwrap();
            let exact = Aabb::of_object_box(&DAffine3::from_mat4(m), lo, hi).unwrap();
            for a in 0..3 {
                let (glo, ghi) = (n.lo[a] as f64, n.hi[a] as f64);
                assert!(glo < exact.lo[a] && ghi > exact.hi[a], "{n:?} vs {exact:?}");
                // Widened by 1e-5 of (distance + size), not more than twice that.
                let size = (exact.hi - exact.lo).max_element() + exact.center().abs().max_element();
                assert!(exact.lo[a] - glo < 2e-5 * size, "{n:?} vs {exact:?}");
            }
        }
        items.sort();
        assert_eq!(items, vec![0, 2]);
        assert!(instance_bvh(&[], &bounds).is_empty());
    }

    #[test]
    fn frustum_planes_contain_the_view_axis_and_exclude_what_is_behind() {
        let (r, u, f) = (DVec3::X, DVec3::Y, DVec3::NEG_Z);
        let planes = frustum_planes(r, u, f, 1.0, 1.0);
        let inside = |p: DVec3, radius: f64| planes.iter().all(|(n, d)| n.dot(p) + d >= -radius);
        assert!(inside(DVec3::new(0.0, 0.0, -5.0), 0.1));
        assert!(!inside(DVec3::new(0.0, 0.0, 5.0), 0.1), "behind the camera");
        assert!(!inside(DVec3::new(20.0, 0.0, -5.0), 1.0), "far right");
        assert!(
            inside(DVec3::new(5.5, 0.0, -5.0), 1.0),
            "sphere crossing the right plane"
        );
    }
}
