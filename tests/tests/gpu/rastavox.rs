//! RastaVox: the GPU surface build against the CPU build, and the rendered
//! G-buffer against the reference of the model it draws (each chunk's OR-merged LOD, hit
//! only through its masked faces) and against the finest level.

use glam::{DAffine3, DVec3};
use ssbvb_gpu::scene::{LodPolicy, Scene};
use ssbvb_gpu_build::surface_build::SurfaceBuilder;
use ssbvb_voxel::accuracy::{self, AccuracyReport};
use ssbvb_voxel::asset::{LodLevel, PackedVoxel, PointCloud, SparseLookup};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::{Instance, render};
use ssbvb_voxel::surface::{FaceLod, SurfaceModel, select_chunks};
use ssbvb_voxel::svo::morton_encode;

/// A spherical shell of radius `r` cells around `centre` at `level`, coloured by position.
fn shell(level: u32, centre: [f64; 3], r: f64) -> LodLevel {
    let mut cells = Vec::new();
    let lo = |a: usize| (centre[a] - r - 2.0).max(0.0) as u32;
    let hi = |a: usize| ((centre[a] + r + 2.0) as u32).min((1 << level) - 1);
    for z in lo(2)..=hi(2) {
        for y in lo(1)..=hi(1) {
            for x in lo(0)..=hi(0) {
                let p = [x, y, z].map(|c| c as f64 + 0.5);
                let d = ((p[0] - centre[0]).powi(2)
                    + (p[1] - centre[1]).powi(2)
                    + (p[2] - centre[2]).powi(2))
                .sqrt();
                if (r - 1.5..=r).contains(&d) {
                    cells.push([x, y, z]);
                }
            }
        }
    }
    cells.sort_by_key(|&c| morton_encode(c));
    let voxels = cells
        .iter()
        .map(|&c| {
            let n = [0, 1, 2].map(|a| (c[a] as f64 + 0.5 - centre[a]) as f32);
            let col = [
                c[0] as f32 / 511.0,
                c[1] as f32 / 511.0,
                c[2] as f32 / 511.0,
                1.0,
            ];
            PackedVoxel::new(c, n, col, [0.0; 2])
        })
        .collect();
    LodLevel {
        level,
        point_cloud: PointCloud { voxels },
        lookup: SparseLookup::from_cells(level, cells.iter().copied()),
        proxy: Default::default(),
    }
}

fn assert_same_model(gpu: &SurfaceModel, cpu: &SurfaceModel, what: &str) {
    assert_eq!(
        (gpu.level, gpu.chunk_log2),
        (cpu.level, cpu.chunk_log2),
        "{what}"
    );
    assert_eq!(gpu.chunks, cpu.chunks, "{what}: chunks");
    assert_eq!(gpu.bounds, cpu.bounds, "{what}: bounds");
    assert_eq!(gpu.levels.len(), cpu.levels.len(), "{what}: levels");
    for (k, (g, c)) in gpu.levels.iter().zip(&cpu.levels).enumerate() {
        assert_eq!(g.ranges, c.ranges, "{what} LOD {k}: ranges");
        assert_eq!(g.voxels.len(), c.voxels.len(), "{what} LOD {k}: voxels");
        let wrong = g
            .voxels
            .iter()
            .zip(&c.voxels)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(wrong, 0, "{what} LOD {k}: {wrong} voxels differ");
        let wrong = g
            .colors
            .iter()
            .zip(&c.colors)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(wrong, 0, "{what} LOD {k}: {wrong} colours differ");
        // Normals: one octahedral step at most (GPU sqrt and division round differently).
        let far = g
            .normals
            .iter()
            .zip(&c.normals)
            .filter(|&(&a, &b)| {
                let d = |s: u32| ((a >> s) & 0xff).abs_diff((b >> s) & 0xff);
                d(0) > 1 || d(8) > 1 || a >> 16 != 0
            })
            .count();
        assert_eq!(
            far, 0,
            "{what} LOD {k}: {far} normals differ by more than one step"
        );
    }
}

#[test]
fn the_gpu_surface_build_equals_the_cpu_build() {
    let ctx = ssbvb_tests::ctx();
    let builder = SurfaceBuilder::new(ctx).unwrap();
    let bunny = ssbvb_tests::model_asset("bunny.obj", 7);
    let knight = ssbvb_tests::model_asset("chr_knight.vox", 6);
    let cases: Vec<(String, LodLevel)> = vec![
        ("bunny level 7".into(), bunny.lods[7].clone()),
        ("bunny level 4".into(), bunny.lods[4].clone()),
        ("knight level 6".into(), knight.lods[6].clone()),
        // Level 9: chunks of 256³, the shell crosses the chunk planes at 256 on every axis.
        (
            "shell level 9".into(),
            shell(9, [250.0, 262.0, 255.0], 40.0),
        ),
    ];
    for (what, lod) in &cases {
        let cpu = SurfaceModel::extract(lod).unwrap();
        let gpu = builder.build(ctx, lod).unwrap();
        assert!(ctx.take_uncaptured_errors().is_empty(), "{what}");
        let back = gpu.read_back(ctx).unwrap();
        eprintln!(
            "{what}: {} points, {} surface voxels, {} chunks, LOD counts {:?}, build {:.3} + {:.3} s",
            lod.point_cloud.voxels.len(),
            cpu.surface_voxels(),
            cpu.chunks.len(),
            cpu.levels
                .iter()
                .map(|l| l.voxels.len())
                .collect::<Vec<_>>(),
            gpu.times.base_seconds,
            gpu.times.lod_seconds,
        );
        assert!(cpu.surface_voxels() > 0, "{what}");
        assert_same_model(&back, &cpu, what);
        assert_eq!(
            gpu.bytes(),
            cpu.bytes().base_voxels + cpu.bytes().base_attributes + cpu.bytes().lod,
            "{what}"
        );
    }
    assert_eq!(SurfaceModel::extract(&cases[3].1).unwrap().chunks.len(), 8);
}

// ---------------------------------------------------------------------------------------
// Rendering against the reference
// ---------------------------------------------------------------------------------------

const RASTAVOX: &str = include_str!("../../../assets/pipelines/rastavox.ron");
const SIZE: (u32, u32) = (160, 120);

fn pipeline(pixel_error: f32) -> String {
    let text = RASTAVOX.replace(
        "RastaVox(pixel_error: 1.0)",
        &format!("RastaVox(pixel_error: {pixel_error:?})"),
    );
    assert!(text.contains(&format!("pixel_error: {pixel_error:?}")));
    text
}

/// The drawn model of a scene: per instance, per chunk the camera sees, its LOD as a
/// face-masked level (in the reference's instance order).
struct Drawn {
    placed: Vec<(DAffine3, FaceLod)>,
    /// Chunks drawn per LOD.
    per_lod: Vec<usize>,
}

fn drawn(scene: &Scene, cam: &Camera, pixel_error: f32) -> Drawn {
    let mut placed = Vec::new();
    let mut per_lod = vec![0; 9];
    for o in &scene.objects {
        let LodPolicy::Fixed(level) = o.lod else {
            panic!("fixed LODs only")
        };
        let model = SurfaceModel::extract(&o.asset.lods[level as usize]).unwrap();
        for xf in &o.instances {
            let chunks = select_chunks(
                model.level,
                model.chunk_log2,
                &model.bounds,
                xf,
                cam,
                SIZE,
                pixel_error,
            );
            for c in chunks {
                per_lod[c.k] += 1;
                placed.push((*xf, model.face_lod(c.chunk, c.k)));
            }
        }
    }
    Drawn { placed, per_lod }
}

/// Renders `scene` with RastaVox at `pixel_error` and compares it with the reference of
/// the same drawn model (the OR-merged LODs, hit through their masked faces) and, for the
/// cost of the pixel error, with the finest level (`reference_of`).
fn compare(
    scene: &Scene,
    cam: &Camera,
    pixel_error: f32,
    what: &str,
) -> (AccuracyReport, AccuracyReport, Drawn) {
    let d = drawn(scene, cam, pixel_error);
    let instances: Vec<Instance> = d
        .placed
        .iter()
        .map(|(xf, face)| Instance {
            lod: &face.lod,
            object_to_world: *xf,
            faces: Some(&face.faces),
        })
        .collect();
    let reference = render(&instances, cam, SIZE.0, SIZE.1, &scene.light);
    let f = ssbvb_tests::render(&pipeline(pixel_error), scene.clone(), cam, SIZE);
    let mut gpu = ssbvb_tests::gbuffer_hits(&f, what);
    let placed: Vec<_> = d
        .placed
        .iter()
        .map(|(xf, face)| (*xf, &face.lod.lookup))
        .collect();
    accuracy::recover_face_voxels(&mut gpu, cam, SIZE, &placed);
    let cells: Vec<f64> = d
        .placed
        .iter()
        .map(|(xf, face)| 2.0 * xf.matrix3.x_axis.length() / (1u64 << face.lod.level) as f64)
        .collect();
    let r = accuracy::compare(&reference, &gpu, &cells).unwrap();
    let finest = ssbvb_tests::reference_of(scene, cam, SIZE);
    let finest_cells = vec![
        f64::MAX;
        finest
            .hits
            .iter()
            .flatten()
            .map(|h| h.instance as usize + 1)
            .max()
            .unwrap_or(0)
    ];
    // Against the finest level only coverage and depth mean something (other voxels).
    let mut unplaced = gpu.clone();
    for h in unplaced.iter_mut().flatten() {
        h.instance = u32::MAX;
    }
    let vs_finest = accuracy::compare(&finest, &unplaced, &finest_cells).unwrap();
    eprintln!(
        "RastaVox {what} pixel error {pixel_error}: chunks per LOD {:?}; vs drawn model IoU {:.4}, same voxel {:.4}, depth median {:.2e} p95 {:.2e} voxels, px {}; vs finest IoU {:.4}",
        &d.per_lod[..d.per_lod.iter().rposition(|&n| n > 0).map_or(1, |i| i + 1)],
        r.coverage_iou,
        r.same_voxel_rate,
        r.depth_error_voxels.median,
        r.depth_error_voxels.p95,
        r.covered_reference,
        vs_finest.coverage_iou,
    );
    (r, vs_finest, d)
}

fn cameras() -> Vec<Camera> {
    vec![
        Camera::new(DVec3::new(1.8, 1.1, 2.4), DVec3::ZERO),
        Camera::new(DVec3::new(-2.6, -0.8, -1.5), DVec3::new(0.0, 0.1, 0.0)),
        Camera::new(DVec3::new(0.0, 0.0, 3.2), DVec3::ZERO),
    ]
}

#[test]
fn rastavox_at_pixel_error_zero_matches_the_finest_reference() {
    let asset = ssbvb_tests::model_asset("bunny.obj", 7);
    for level in [5, 7] {
        for (ci, cam) in cameras().iter().enumerate() {
            let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
            let what = format!("bunny level {level} camera {ci}");
            let (r, vs_finest, d) = compare(&scene, cam, 0.0, &what);
            assert_eq!(d.per_lod[0], d.placed.len(), "{what}: every chunk at LOD 0");
            ssbvb_tests::assert_face_raster_accurate(&r, &what);
            // At LOD 0 the drawn model shows what the solid voxels show.
            assert!(vs_finest.coverage_iou >= 0.995, "{what}: {vs_finest:?}");
        }
    }
}

#[test]
fn rastavox_pixel_error_picks_coarser_lods_and_matches_their_reference() {
    let asset = ssbvb_tests::model_asset("bunny.obj", 7);
    let scene = ssbvb_tests::single_object_scene(asset, 7);
    // A level-7 voxel's worst-case extent (3^¼ × edge) projects to about 0.4 px here
    // (160 × 120, 45°), so pixel errors 2, 4 and 8 allow LODs 2, 3 and 4.
    let cam = Camera::new(DVec3::new(4.5, 2.5, 6.5), DVec3::ZERO);
    let (mut last_coarsest, mut last_iou) = (0, 1.0);
    for pe in [2.0, 4.0, 8.0] {
        let what = format!("bunny level 7 far, pixel error {pe}");
        let (r, vs_finest, d) = compare(&scene, &cam, pe, &what);
        let coarsest = d.per_lod.iter().rposition(|&n| n > 0).unwrap();
        assert!(coarsest > last_coarsest, "{what}: {:?}", d.per_lod);
        last_coarsest = coarsest;
        ssbvb_tests::assert_face_raster_accurate(&r, &what);
        // OR-merged LODs grow rather than lose (§3.2): every pixel of the finest image
        // stays covered (up to edge snapping) while the silhouette widens with the error.
        let kept = vs_finest.covered_both as f64 / vs_finest.covered_reference as f64;
        assert!(kept >= 0.995, "{what}: {vs_finest:?}");
        assert!(
            vs_finest.covered_gpu > vs_finest.covered_reference,
            "{what}"
        );
        assert!(vs_finest.coverage_iou < last_iou, "{what}: {vs_finest:?}");
        last_iou = vs_finest.coverage_iou;
    }
}

#[test]
fn rastavox_draws_many_transformed_instances() {
    let asset = ssbvb_tests::model_asset("bunny.obj", 6);
    let mut scene = ssbvb_tests::single_object_scene(asset, 6);
    let mut instances = Vec::new();
    for i in 0..12 {
        let angle = i as f64 * 0.7;
        let x = (i % 4) as f64 * 1.1 - 1.65;
        let z = (i / 4) as f64 * -1.3;
        let scale = 0.35 + 0.05 * (i % 3) as f64;
        instances.push(
            DAffine3::from_translation(DVec3::new(x, 0.0, z))
                * DAffine3::from_rotation_y(angle)
                * DAffine3::from_scale(DVec3::splat(scale)),
        );
    }
    // One mirrored instance: the face choice must not depend on winding.
    instances.push(
        DAffine3::from_translation(DVec3::new(0.0, 1.0, 0.0))
            * DAffine3::from_scale(DVec3::new(-0.4, 0.4, 0.4)),
    );
    scene.objects[0].instances = instances;
    let cam = Camera::new(DVec3::new(0.3, 1.8, 3.2), DVec3::new(0.0, 0.0, -1.2));
    for pe in [0.0, 1.0] {
        let what = format!("13 bunnies, pixel error {pe}");
        let (r, _, d) = compare(&scene, &cam, pe, &what);
        assert!(d.placed.len() >= 13, "{what}");
        ssbvb_tests::assert_face_raster_accurate(&r, &what);
    }
}

#[test]
fn rastavox_is_exact_with_the_camera_close_to_the_surface() {
    // Inside the bunny's chunk box, a few voxels off its back: the nearest chunk depth is
    // ≤ 0, so every pixel error keeps the finest LOD there, and faces cut by the near
    // plane must not leave holes the reference does not have.
    let asset = ssbvb_tests::model_asset("bunny.obj", 7);
    let scene = ssbvb_tests::single_object_scene(asset, 7);
    let cam = Camera::new(DVec3::new(0.15, 0.35, 0.75), DVec3::new(0.0, 0.1, 0.0));
    for pe in [0.0, 4.0] {
        let what = format!("bunny level 7 near, pixel error {pe}");
        let (r, _, d) = compare(&scene, &cam, pe, &what);
        assert_eq!(d.per_lod[0], 1, "{what}: {:?}", d.per_lod);
        assert!(
            r.covered_reference > 8000,
            "{what}: {} px",
            r.covered_reference
        );
        ssbvb_tests::assert_face_raster_accurate(&r, &what);
    }
}
