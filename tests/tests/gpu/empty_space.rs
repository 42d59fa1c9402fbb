//! The empty-space prepass: conservative coverage, entry points on the proxy and on the
//! pixel's ray, winding, and a camera inside a proxy. Also the helpers the filter tests
//! share (the pipeline that keeps only these passes, synthetic assets, debug images).

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::Scene;
use ssbvb_tests::{Frame, model_asset, reference_of, render, single_object_scene};
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, SparseLookup, VoxelAsset};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::model::{ObjectSpace, cell_size};

/// The bundled SSBVB pipeline pruned to the prepass and the filter: the output is `entry`
/// and the filter's resources are kept for readback.
pub fn prefilter_pipeline(max_steps: u32) -> String {
    let src = include_str!("../../../assets/pipelines/ssbvb_flat.ron");
    let out = r#"output: "color","#;
    assert!(
        src.contains(out),
        "ssbvb_flat.ron no longer ends with {out}"
    );
    let src = src.replace(
        out,
        r#"output: "entry", keep: ["ssbvb", "billboard_draw"],"#,
    );
    let filter = "RayMarchFilter(max_steps: 1024)";
    assert!(src.contains(filter), "ssbvb_flat.ron has no {filter}");
    src.replace(filter, &format!("RayMarchFilter(max_steps: {max_steps})"))
}

/// `src` with the empty-space prepass in compute (`EmptySpaceCompute`, as
/// `ssbvb_compute.ron` has it): the same `entry`, no depth attachment.
pub fn with_compute_prepass(src: &str) -> String {
    let raster = r#"kind: EmptySpacePrepass, writes: ["entry", "prepass_depth"]"#;
    let depth = "    \"prepass_depth\":    Texture(format: Depth32Float, size: Screen),\n";
    assert!(
        src.contains(raster) && src.contains(depth),
        "no raster prepass"
    );
    src.replace(raster, r#"kind: EmptySpaceCompute(), writes: ["entry"]"#)
        .replace(depth, "")
}

/// The prepass-and-filter pipeline with each form of the prepass: rasterized, and in
/// compute.
pub fn prefilter_forms() -> [(&'static str, String); 2] {
    let raster = prefilter_pipeline(1024);
    let compute = with_compute_prepass(&raster);
    [("raster", raster), ("compute", compute)]
}

/// An asset whose finest level `level` holds exactly `cells` (normals point away from the
/// grid centre, colours from the position); coarser levels are their parents, as the octree
/// would build them.
pub fn synthetic_asset(level: u32, cells: &[[u32; 3]]) -> Arc<VoxelAsset> {
    synthetic_asset_with(level, cells, |c, l| {
        let n = (1u64 << l) as f32;
        let p = c.map(|v| (v as f32 + 0.5) / n * 2.0 - 1.0);
        let col = p.map(|v| v * 0.5 + 0.5);
        PackedVoxel::new(c, p, [col[0], col[1], col[2], 1.0], [0.0; 2])
    })
}

/// [`synthetic_asset`] with each voxel made by `voxel(cell, level)`.
pub fn synthetic_asset_with(
    level: u32,
    cells: &[[u32; 3]],
    voxel: impl Fn([u32; 3], u32) -> PackedVoxel,
) -> Arc<VoxelAsset> {
    let mut lods = Vec::new();
    let mut current: Vec<[u32; 3]> = cells.to_vec();
    for l in (0..=level).rev() {
        // Morton order: the lookup implies voxel ids as Morton ranks.
        current.sort_by_key(|&c| ssbvb_voxel::svo::morton_encode(c));
        current.dedup();
        let voxels: Vec<PackedVoxel> = current.iter().map(|&c| voxel(c, l)).collect();
        let lookup = SparseLookup::from_cells(l, current.iter().copied());
        let proxy = ssbvb_voxel::proxy::build_proxy(&lookup);
        lods.push(LodLevel {
            level: l,
            point_cloud: PointCloud { voxels },
            lookup,
            proxy,
        });
        current = current.iter().map(|c| c.map(|v| v / 2)).collect();
    }
    lods.reverse();
    Arc::new(VoxelAsset {
        object_space: ObjectSpace::from_bounds(DVec3::splat(-1.0), DVec3::ONE),
        lods,
    })
}

/// Cells of a hollow box: the faces of `[lo, hi]³` (inclusive) in a grid.
pub fn hollow_box(lo: u32, hi: u32) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for z in lo..=hi {
        for y in lo..=hi {
            for x in lo..=hi {
                if [x, y, z].iter().any(|&v| v == lo || v == hi) {
                    out.push([x, y, z]);
                }
            }
        }
    }
    out
}

/// Writes an RGBA8 image under `$SSBVB_TEST_PNG` (a folder) when that variable is set, so
/// a developer can look at what a test rendered.
pub fn debug_png(name: &str, width: u32, height: u32, rgba: &[u8]) {
    if let Some(dir) = std::env::var_os("SSBVB_TEST_PNG") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        ssbvb_gpu::readback::write_png_rgba8(&dir.join(format!("{name}.png")), width, height, rgba)
            .unwrap();
    }
}

/// The `entry` texture: per pixel (object-space point, instance + 1).
pub fn entries(frame: &Frame) -> Vec<[f32; 4]> {
    let raw = frame.read_f32("entry");
    raw.chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect()
}

/// `entry` as a picture: object position as colour where covered, the camera-start pixels
/// (entry equal to the camera) white, uncovered black.
fn entry_png(name: &str, frame: &Frame, size: (u32, u32)) {
    let cam = frame.scene.camera.position;
    let rgba: Vec<u8> = entries(frame)
        .iter()
        .flat_map(|e| {
            if e[3] == 0.0 {
                return [0, 0, 0, 255];
            }
            let p = DVec3::new(e[0] as f64, e[1] as f64, e[2] as f64);
            if (p - cam).length() < 1e-4 {
                return [255, 255, 255, 255];
            }
            let c = |v: f32| ((v * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0) as u8;
            [c(e[0]), c(e[1]), c(e[2]), 255]
        })
        .collect();
    debug_png(name, size.0, size.1, &rgba);
}

/// Distance from object-space point `p` to the pixel's ray (the scene's single identity
/// instance: object space is world space).
fn distance_to_ray(camera: &Camera, size: (u32, u32), x: u32, y: u32, p: DVec3) -> f64 {
    let (o, d) = camera.ray(x, y, size.0, size.1);
    let v = p - o;
    (v - d * v.dot(d)).length()
}

#[test]
fn entry_covers_every_reference_hit_and_lies_on_the_proxy_and_the_ray() {
    let level = 6;
    let scene = single_object_scene(model_asset("bunny.obj", level), level);
    let size = (160, 120);
    let asset = scene.objects[0].asset.clone();
    let lookup = &asset.lods[level as usize].lookup;
    let page = cell_size(level) * 16.0;
    for (form, src) in prefilter_forms() {
        for (i, camera) in [
            Camera::new(DVec3::new(1.6, 1.1, 2.4), DVec3::ZERO),
            Camera::new(DVec3::new(-2.5, -0.4, -1.2), DVec3::new(0.1, 0.0, 0.0)),
        ]
        .iter()
        .enumerate()
        {
            let reference = reference_of(&scene, camera, size);
            let frame = render(&src, scene.clone(), camera, size);
            entry_png(&format!("empty_space_{form}_bunny_{i}"), &frame, size);
            let e = entries(&frame);
            let mut covered = 0;
            for y in 0..size.1 {
                for x in 0..size.0 {
                    let v = e[(y * size.0 + x) as usize];
                    assert!(v.iter().all(|c| c.is_finite()), "({x}, {y}): {v:?}");
                    if reference.hit(x, y).is_some() {
                        assert_eq!(v[3], 1.0, "reference hit at ({x}, {y}) outside the proxy");
                    }
                    if v[3] == 0.0 {
                        continue;
                    }
                    assert_eq!(v[3], 1.0);
                    covered += 1;
                    let p = DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                    // On the ray (f32 interpolation of positions of size ~1: 1e-4 is generous
                    // and still far below a cell, 0.03).
                    let dist = distance_to_ray(camera, size, x, y, p);
                    assert!(dist < 1e-4, "({x}, {y}): entry {p} is {dist} off the ray");
                    // On the proxy: the boundary of the union of resident pages, so on a page
                    // plane, with a resident page on one side and an empty one on the other.
                    assert!(p.abs().max_element() <= 1.0 + 1e-5, "{p}");
                    // Interpolated entries are accurate to ~1e-6 object units: 1e-5 of a page.
                    let on_proxy = (0..3).any(|a| {
                        let u = (p[a] + 1.0) / page;
                        if (u - u.round()).abs() > 1e-5 {
                            return false;
                        }
                        let side = |s: f64| {
                            let mut q = p;
                            q[a] += s * page * 0.5;
                            let c = ((q + 1.0) / page).floor();
                            let pages = ((1u32 << lookup.level) / 16).max(1) as f64;
                            (0..3).all(|k| c[k] >= 0.0 && c[k] < pages)
                                && lookup.page_occupied([c.x as u32, c.y as u32, c.z as u32])
                        };
                        side(-1.0) != side(1.0)
                    });
                    assert!(on_proxy, "({x}, {y}): {p} not on the proxy");
                }
            }
            assert!(
                covered >= reference.coverage() && covered > 1000,
                "{covered}"
            );
        }
    }
}

#[test]
fn front_faces_win_so_the_winding_is_right() {
    // One voxel at level 2: the proxy is the whole [-1, 1]³ box. Seen from +Z, the front
    // pipeline must draw the near face (z = +1). With the winding inverted it would cull
    // that face and the back-face pipeline would write the camera position there instead.
    let scene = single_object_scene(synthetic_asset(2, &[[1, 2, 3]]), 2);
    let size = (64, 48);
    for (form, src) in prefilter_forms() {
        for (camera, axis, value) in [
            (Camera::new(DVec3::new(0.3, 0.2, 4.0), DVec3::ZERO), 2, 1.0),
            (
                Camera::new(DVec3::new(-4.0, 0.5, 0.3), DVec3::ZERO),
                0,
                -1.0,
            ),
            (
                Camera {
                    up: DVec3::Z,
                    ..Camera::new(DVec3::new(0.2, 4.0, 0.1), DVec3::ZERO)
                },
                1,
                1.0,
            ),
        ] {
            let frame = render(&src, scene.clone(), &camera, size);
            let e = entries(&frame);
            let covered: Vec<_> = e.iter().filter(|v| v[3] != 0.0).collect();
            assert!(covered.len() > 200, "{form}: {}", covered.len());
            for v in covered {
                assert_eq!(v[3], 1.0);
                assert!(
                    (v[axis] - value).abs() < 1e-5,
                    "{form}, camera {}: entry {v:?} not on the face facing it",
                    camera.position
                );
            }
        }
    }
}

#[test]
fn camera_inside_the_proxy_starts_at_the_camera() {
    // A hollow box of voxels at level 6: the camera sits inside the shell's resident pages
    // (but in no voxel), so the nearest proxy surface along every ray is a back face, or
    // nothing where that face is clipped: the entry must be the camera everywhere.
    let level = 6;
    let scene = single_object_scene(synthetic_asset(level, &hollow_box(8, 55)), level);
    let s = cell_size(level);
    let eye = DVec3::new(-1.0 + 12.5 * s, -1.0 + 30.5 * s, -1.0 + 33.5 * s);
    let size = (96, 64);
    for (form, src) in prefilter_forms() {
        for (look, near, far) in [
            (DVec3::new(1.0, 0.1, 0.2), 0.01, 1000.0),
            (DVec3::new(-1.0, -0.1, 0.0), 0.01, 1000.0),
            // The back faces around the camera all lie beyond the far plane or before the near
            // plane: only the full-screen fill reaches the pixels.
            (DVec3::new(-1.0, -0.1, 0.0), 0.01, 0.02),
        ] {
            let camera = Camera {
                near,
                far,
                ..Camera::new(eye, eye + look)
            };
            let frame = render(&src, scene.clone(), &camera, size);
            assert!(frame.scene.visible[0].camera_inside);
            let cam = eye.as_vec3();
            for (i, v) in entries(&frame).iter().enumerate() {
                assert_eq!(v[3], 1.0, "{form}: pixel {i} has no entry");
                assert!(
                    (v[0] - cam.x).abs() < 1e-6
                        && (v[1] - cam.y).abs() < 1e-6
                        && (v[2] - cam.z).abs() < 1e-6,
                    "pixel {i}: {v:?} is not the camera {cam}"
                );
            }
        }
    }
}

#[test]
fn near_plane_clipping_of_front_faces_starts_at_the_camera() {
    // Outside the proxy, 0.02 in front of its +Z face, with the near plane at 0.05: the
    // front face is clipped, the back face behind survives and the ray starts at the eye.
    let scene = single_object_scene(synthetic_asset(2, &[[1, 2, 3]]), 2);
    let camera = Camera {
        near: 0.05,
        ..Camera::new(DVec3::new(0.1, 0.2, 1.02), DVec3::new(0.1, 0.2, 0.0))
    };
    for (form, src) in prefilter_forms() {
        let frame = render(&src, scene.clone(), &camera, (32, 24));
        let v = &frame.scene.visible[0];
        assert!(v.back_faces && !v.camera_inside);
        for v in entries(&frame) {
            assert_eq!(v[3], 1.0);
            assert!((v[2] - 1.02).abs() < 1e-6, "{form}: {v:?}");
        }
    }
}

#[test]
fn instances_write_their_own_index() {
    // Two instances side by side: each pixel names the instance whose proxy it sees.
    let asset = synthetic_asset(3, &[[0, 0, 0], [7, 7, 7], [3, 4, 5]]);
    let scene = Scene {
        objects: vec![ssbvb_gpu::scene::VoxelObject {
            asset,
            instances: vec![
                DAffine3::from_translation(DVec3::new(-1.5, 0.0, 0.0)),
                DAffine3::from_translation(DVec3::new(1.5, 0.0, 0.0)),
            ],
            lod: ssbvb_gpu::scene::LodPolicy::Fixed(3),
        }],
        ..Default::default()
    };
    let size = (80, 40);
    let camera = Camera::new(DVec3::new(0.0, 0.0, 6.0), DVec3::ZERO);
    for (form, src) in prefilter_forms() {
        let frame = render(&src, scene.clone(), &camera, size);
        // Both proxies lie wholly beyond the near plane: their back faces are not drawn (they
        // could win no depth test), and the front faces alone give every entry.
        assert!(frame.scene.visible.iter().all(|v| !v.back_faces));
        let e = entries(&frame);
        for y in 0..size.1 {
            for x in 0..size.0 {
                let v = e[(y * size.0 + x) as usize];
                if v[3] != 0.0 {
                    let want = if x < size.0 / 2 { 1.0 } else { 2.0 };
                    assert_eq!(v[3], want, "{form}: ({x}, {y})");
                }
            }
        }
        assert!(e.iter().any(|v| v[3] == 1.0) && e.iter().any(|v| v[3] == 2.0));
    }
}
