//! Objects whose voxels change on the GPU: a mesh voxelized on the GPU (exact path), its
//! LOD chain and lookups built on the GPU, copied into a dynamic object's room and drawn by
//! the SSBVB frame with no CPU preparation, against the reference of the CPU-prepared asset
//! of the same mesh.

use std::sync::Arc;

use glam::DVec3;
use ssbvb_gpu::ResourceError;
use ssbvb_gpu::scene::{DynamicRoom, GpuScene, Scene};
use ssbvb_gpu_build::lod_build::GpuLodBuilder;
use ssbvb_gpu_build::voxelize::{GpuVoxelizeMethod, GpuVoxelizer};
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::accuracy;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::load::load_model;
use ssbvb_voxel::model::{Mesh, Model};

const FLAT: &str = include_str!("../../../assets/pipelines/ssbvb_flat.ron");
const SIZE: (u32, u32) = (160, 120);

fn mesh(file: &str) -> Mesh {
    match load_model(&ssbvb_tests::models_dir().join(file)).unwrap() {
        Model::Mesh(m) => m,
        _ => panic!("{file} is not a mesh"),
    }
}

/// The scene uploaded with room for object 0 to grow `growth`-fold, and the flat SSBVB
/// frame (per-pixel voxel ids, so the same-voxel rate is measured).
fn dynamic_frame(scene: Scene, growth: f64) -> (GpuScene, Renderer) {
    let ctx = ssbvb_tests::ctx();
    let room = DynamicRoom { object: 0, growth };
    let gpu_scene = GpuScene::with_dynamic(ctx, scene, &[room]).unwrap();
    let pipeline = ssbvb_graph::resolve_str(FLAT, "flat").unwrap();
    let renderer = Renderer::new(ctx, &gpu_scene, pipeline, SIZE).unwrap();
    (gpu_scene, renderer)
}

/// Coverage IoU and same-voxel rate of the frame against the reference of `scene`.
fn accuracy_of(
    renderer: &Renderer,
    scene: &Scene,
    cam: &Camera,
    level: u32,
) -> accuracy::AccuracyReport {
    let ctx = ssbvb_tests::ctx();
    let reference = ssbvb_tests::reference_of(scene, cam, SIZE);
    let hits = ssbvb_passes::measure::gbuffer_hits(ctx, renderer).unwrap();
    accuracy::compare(&reference, &hits, &[2.0 / f64::from(1u32 << level)]).unwrap()
}

#[test]
fn a_gpu_built_object_draws_like_its_cpu_prepared_asset() {
    let ctx = ssbvb_tests::ctx();
    let level = 6;
    let bunny = ssbvb_tests::model_asset("bunny.obj", level);
    let teapot = ssbvb_tests::model_asset("teapot.obj", level);
    let scene = ssbvb_tests::single_object_scene(bunny.clone(), level);
    let (mut gpu_scene, mut renderer) = dynamic_frame(scene.clone(), 1.5);
    let cam = Camera::new(DVec3::new(1.6, 1.0, 2.3), DVec3::ZERO);
    let render = |r: &mut Renderer, s: &mut GpuScene| {
        r.render(ctx, s, &cam, Profiling::Off).unwrap();
        ctx.wait_idle().unwrap();
        assert!(ctx.take_uncaptured_errors().is_empty());
    };
    // As uploaded: the bunny, drawn through the room's box proxy.
    render(&mut renderer, &mut gpu_scene);
    let a = accuracy_of(&renderer, &scene, &cam, level);
    // Then the teapot, voxelized and prepared on the GPU, replaces it.
    let vox = GpuVoxelizer::new(ctx).unwrap();
    let lods = GpuLodBuilder::new(ctx).unwrap();
    let (set, _) = vox
        .voxelize_by(
            ctx,
            &mesh("teapot.obj"),
            level,
            None,
            GpuVoxelizeMethod::Exact,
        )
        .unwrap();
    let levels = lods.build(ctx, &set.voxels).unwrap();
    gpu_scene.set_object_levels(ctx, 0, &levels).unwrap();
    render(&mut renderer, &mut gpu_scene);
    let teapot_scene = ssbvb_tests::single_object_scene(teapot.clone(), level);
    let b = accuracy_of(&renderer, &teapot_scene, &cam, level);
    // And it no longer shows the bunny.
    let c = accuracy_of(&renderer, &scene, &cam, level);
    eprintln!(
        "uploaded bunny: IoU {:.4} same voxel {:.4}; GPU-built teapot: IoU {:.4} same voxel {:.4} ({} px); against the bunny IoU {:.4}",
        a.coverage_iou,
        a.same_voxel_rate,
        b.coverage_iou,
        b.same_voxel_rate,
        b.covered_reference,
        c.coverage_iou
    );
    for (r, what) in [(&a, "bunny"), (&b, "teapot")] {
        assert!(r.covered_reference > 2000, "{what}: {r:?}");
        assert!(
            r.coverage_iou >= 0.99 && r.same_voxel_rate >= 0.99,
            "{what}: {r:?}"
        );
    }
    assert!(c.coverage_iou < 0.8, "{c:?}");
    let room = gpu_scene.dynamic_object(0).unwrap();
    assert_eq!(
        room.levels[level as usize].voxels,
        teapot.lods[level as usize].point_cloud.voxels.len() as u32
    );
}

#[test]
fn a_level_that_outgrows_its_room_is_refused_with_the_room_needed() {
    let ctx = ssbvb_tests::ctx();
    let small = ssbvb_tests::model_asset("cow.obj", 5);
    let scene = ssbvb_tests::single_object_scene(small, 5);
    let mut gpu_scene = GpuScene::with_dynamic(
        ctx,
        scene,
        &[DynamicRoom {
            object: 0,
            growth: 1.0,
        }],
    )
    .unwrap();
    // The igea at level 5 (3 568 voxels) outgrows the cow's room (1 362 + 1 024).
    let vox = GpuVoxelizer::new(ctx).unwrap();
    let (set, _) = vox.voxelize(ctx, &mesh("igea.ply"), 5).unwrap();
    let levels = GpuLodBuilder::new(ctx)
        .unwrap()
        .build(ctx, &set.voxels)
        .unwrap();
    let room = gpu_scene.dynamic_object(0).unwrap().levels[5];
    if levels[5].count <= room.voxel_capacity {
        panic!(
            "the test needs a set larger than the room: {} ≤ {}",
            levels[5].count, room.voxel_capacity
        );
    }
    let e = gpu_scene.set_object_levels(ctx, 0, &levels).unwrap_err();
    assert!(matches!(e, ResourceError::TooLarge(_)), "{e}");
    assert!(e.to_string().contains("its room holds"), "{e}");
    // Not dynamic, wrong level count: refused too.
    assert!(gpu_scene.set_object_levels(ctx, 1, &levels).is_err());
    assert!(gpu_scene.set_object_levels(ctx, 0, &levels[..3]).is_err());
}

/// An animated (twisting) bunny re-voxelized on the GPU at time t matches the reference of
/// its CPU voxelization at t, and differs from its rest pose.
#[test]
fn an_animated_mesh_drawn_at_time_t_matches_its_reference_at_t() {
    use ssbvb_gpu_build::animated::{AnimatedMesh, Animator};
    use ssbvb_voxel::animate::MeshAnimation;
    let ctx = ssbvb_tests::ctx();
    let level = 6;
    let anim = AnimatedMesh::new(
        0,
        mesh("bunny.obj"),
        MeshAnimation::Twist {
            degrees_per_second: 90.0,
        },
        level,
    )
    .unwrap();
    let rest = Arc::new(anim.cpu_asset(0.0).unwrap());
    let scene = ssbvb_tests::single_object_scene(rest.clone(), level);
    let (mut gpu_scene, mut renderer) = dynamic_frame(scene.clone(), 1.5);
    let animator = Animator::new(ctx).unwrap();
    let cam = Camera::new(DVec3::new(0.4, 1.2, 2.8), DVec3::ZERO);
    let t = 0.8;
    let times = animator.update(ctx, &mut gpu_scene, &anim, t).unwrap();
    renderer
        .render(ctx, &mut gpu_scene, &cam, Profiling::Off)
        .unwrap();
    ctx.wait_idle().unwrap();
    assert!(ctx.take_uncaptured_errors().is_empty());
    let at_t = Arc::new(anim.cpu_asset(t).unwrap());
    let r = accuracy_of(
        &renderer,
        &ssbvb_tests::single_object_scene(at_t.clone(), level),
        &cam,
        level,
    );
    let vs_rest = accuracy_of(&renderer, &scene, &cam, level);
    eprintln!(
        "twist at t = {t}: {:?} ({:.1} ms); IoU {:.4} same voxel {:.4} ({} px); against the rest pose IoU {:.4}",
        animator.method(),
        times.total_ms(),
        r.coverage_iou,
        r.same_voxel_rate,
        r.covered_reference,
        vs_rest.coverage_iou
    );
    assert_eq!(
        times.voxels,
        at_t.lods[level as usize].point_cloud.voxels.len() as u64
    );
    assert!(r.covered_reference > 2000, "{r:?}");
    assert!(r.coverage_iou >= 0.99 && r.same_voxel_rate >= 0.99, "{r:?}");
    assert!(
        vs_rest.coverage_iou < 0.95,
        "the twist must show: {vs_rest:?}"
    );
}

/// A spherical shell of radius `r` (object units) at `level`, as an application streams it.
fn shell(level: u32, r: f64) -> ssbvb_voxel::svo::LevelVoxels {
    let n = 1u32 << level;
    let s = 2.0 / f64::from(n);
    let mut cells = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = DVec3::new(x as f64, y as f64, z as f64) * s + DVec3::splat(s * 0.5 - 1.0);
                if (c.length() - r).abs() <= s * 0.87 {
                    cells.push((ssbvb_voxel::svo::morton_encode([x, y, z]), c));
                }
            }
        }
    }
    cells.sort_by_key(|e| e.0);
    ssbvb_voxel::svo::LevelVoxels {
        level,
        codes: cells.iter().map(|e| e.0).collect(),
        normals: cells
            .iter()
            .map(|e| e.1.normalize().as_vec3().to_array())
            .collect(),
        colors: cells
            .iter()
            .map(|e| [0.3, 0.6 + 0.3 * e.1.y as f32, 0.9, 1.0])
            .collect(),
        uvs: vec![[0.0; 2]; cells.len()],
    }
}

/// Voxels supplied by the application each frame (the paper's streamed objects) are drawn
/// as the CPU-prepared asset of the same set; a malformed set is refused.
#[test]
fn streamed_voxels_draw_like_their_prepared_asset() {
    use ssbvb_gpu_build::animated::Animator;
    let ctx = ssbvb_tests::ctx();
    let level = 6;
    let bunny = ssbvb_tests::model_asset("bunny.obj", level);
    let scene = ssbvb_tests::single_object_scene(bunny, level);
    let (mut gpu_scene, mut renderer) = dynamic_frame(scene, 2.0);
    let animator = Animator::new(ctx).unwrap();
    let cam = Camera::new(DVec3::new(1.5, 0.8, 2.6), DVec3::ZERO);
    for r in [0.45, 0.8] {
        let voxels = shell(level, r);
        let times = animator.stream(ctx, &mut gpu_scene, 0, &voxels).unwrap();
        renderer
            .render(ctx, &mut gpu_scene, &cam, Profiling::Off)
            .unwrap();
        ctx.wait_idle().unwrap();
        assert!(ctx.take_uncaptured_errors().is_empty());
        let set = ssbvb_voxel::voxelize::VoxelSet {
            object_space: ssbvb_voxel::model::ObjectSpace::from_bounds(
                DVec3::splat(-1.0),
                DVec3::ONE,
            ),
            voxels: voxels.clone(),
            report: Default::default(),
        };
        let (asset, _) =
            ssbvb_voxel::prepare::prepare_voxel_set(set, &ssbvb_voxel::progress::NoProgress);
        let acc = accuracy_of(
            &renderer,
            &ssbvb_tests::single_object_scene(Arc::new(asset), level),
            &cam,
            level,
        );
        eprintln!(
            "streamed shell r = {r}: {} voxels, LOD {:.1} ms; IoU {:.4} same voxel {:.4} ({} px)",
            times.voxels,
            times.lod_ms,
            acc.coverage_iou,
            acc.same_voxel_rate,
            acc.covered_reference
        );
        assert!(acc.covered_reference > 1000, "{acc:?}");
        assert!(
            acc.coverage_iou >= 0.99 && acc.same_voxel_rate >= 0.99,
            "{acc:?}"
        );
    }
    let mut bad = shell(level, 0.5);
    bad.codes.swap(3, 4);
    let e = animator.stream(ctx, &mut gpu_scene, 0, &bad).unwrap_err();
    assert!(e.to_string().contains("not strictly increasing"), "{e}");
    let mut short = shell(level, 0.5);
    short.colors.pop();
    assert!(animator.stream(ctx, &mut gpu_scene, 0, &short).is_err());
}

/// A brush edit at run time (applied to the voxel set, its levels rebuilt on the GPU)
/// draws like the CPU-prepared asset of the edited set.
#[test]
fn a_runtime_edit_draws_like_the_edited_asset() {
    use ssbvb_gpu_build::animated::Animator;
    use ssbvb_voxel::edit::{Edit, apply_edits, level_voxels};
    let ctx = ssbvb_tests::ctx();
    let level = 6;
    let bunny = ssbvb_tests::model_asset("bunny.obj", level);
    let scene = ssbvb_tests::single_object_scene(bunny.clone(), level);
    let (mut gpu_scene, mut renderer) = dynamic_frame(scene.clone(), 1.5);
    let animator = Animator::new(ctx).unwrap();
    let cam = Camera::new(DVec3::new(1.6, 1.0, 2.3), DVec3::ZERO);
    // Carve 8 voxels deep into the side facing the camera and add a red ball on top.
    let edits = [
        Edit::RemoveSphere {
            center: (0.45, 0.1, 0.5),
            radius: 8.0 * 2.0 / 64.0,
        },
        Edit::AddSphere {
            center: (-0.2, 0.75, 0.0),
            radius: 0.15,
            color: (0.9, 0.1, 0.1, 1.0),
        },
    ];
    let (voxels, report) = apply_edits(&level_voxels(&bunny.lods[level as usize]), &edits).unwrap();
    assert!(report.removed > 50 && report.added > 50, "{report:?}");
    animator.stream(ctx, &mut gpu_scene, 0, &voxels).unwrap();
    renderer
        .render(ctx, &mut gpu_scene, &cam, Profiling::Off)
        .unwrap();
    ctx.wait_idle().unwrap();
    let set = ssbvb_voxel::voxelize::VoxelSet {
        object_space: bunny.object_space,
        voxels,
        report: Default::default(),
    };
    let (edited, _) =
        ssbvb_voxel::prepare::prepare_voxel_set(set, &ssbvb_voxel::progress::NoProgress);
    let r = accuracy_of(
        &renderer,
        &ssbvb_tests::single_object_scene(Arc::new(edited), level),
        &cam,
        level,
    );
    let before = accuracy_of(&renderer, &scene, &cam, level);
    eprintln!(
        "edit {report:?}: IoU {:.4} same voxel {:.4}; against the unedited bunny IoU {:.4} same voxel {:.4}",
        r.coverage_iou, r.same_voxel_rate, before.coverage_iou, before.same_voxel_rate
    );
    assert!(r.coverage_iou >= 0.99 && r.same_voxel_rate >= 0.99, "{r:?}");
    assert!(
        before.same_voxel_rate < 0.97,
        "the edit must show: {before:?}"
    );
}
