//! Region-local edits of a dynamic object: the blocks a brush touches recomputed on the CPU
//! (`ssbvb_voxel::local_edit`), every level's streams spliced on the GPU
//! (`ssbvb_gpu_build::level_splice`). Oracles: the room's words read back against the CPU
//! preparation of the edited voxel set (exact), and the frame against the reference ray
//! caster of that asset.

use std::sync::Arc;

use glam::{DAffine3, DVec3};
use ssbvb_gpu::ResourceError;
use ssbvb_gpu::scene::{DynamicRoom, GpuScene, Scene};
use ssbvb_gpu_build::level_splice::LevelSplicer;
use ssbvb_passes::{Profiling, Renderer};
use ssbvb_voxel::accuracy;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::edit::{Edit, apply_edits, level_voxels};
use ssbvb_voxel::level_splice::asset_streams;
use ssbvb_voxel::local_edit::LocalEditor;
use ssbvb_voxel::svo::LevelVoxels;

const FLAT: &str = include_str!("../../../assets/pipelines/ssbvb_flat.ron");
const SIZE: (u32, u32) = (160, 120);

/// Per level: colour words, normal halves, lookup nodes.
type Streams = Vec<(Vec<u32>, Vec<u16>, Vec<u32>)>;

fn prepared(voxels: LevelVoxels, like: &VoxelAsset) -> Arc<VoxelAsset> {
    let set = ssbvb_voxel::voxelize::VoxelSet {
        object_space: like.object_space,
        voxels,
        report: Default::default(),
    };
    Arc::new(ssbvb_voxel::prepare::prepare_voxel_set(set, &ssbvb_voxel::progress::NoProgress).0)
}

/// Words `start..start + len` of a stream split in bindings of `chunk` words.
fn read(buffers: &[ssbvb_gpu::wgpu::Buffer], chunk: u64, start: u64, len: u64) -> Vec<u32> {
    let ctx = ssbvb_tests::ctx();
    let mut out = Vec::new();
    let (mut at, mut left) = (start, len);
    while left > 0 {
        let within = at % chunk;
        let n = left.min(chunk - within);
        let words = ssbvb_gpu::kernels::read_words(ctx, &buffers[(at / chunk) as usize], within, n);
        out.extend(words.unwrap());
        (at, left) = (at + n, left - n);
    }
    out
}

/// The room of object 0 as the GPU holds it.
fn room_streams(scene: &GpuScene) -> Streams {
    let room = scene.dynamic_object(0).unwrap();
    let words = 1u64 << scene.chunks.word_bits;
    let node_words = 3u64 << scene.chunks.node_bits;
    room.levels
        .iter()
        .map(|l| {
            let (at, n) = (u64::from(l.voxel_offset), u64::from(l.voxels));
            let halves = read(
                &scene.word_buffers,
                words,
                scene.normal_word_base + at / 2,
                n.div_ceil(2),
            );
            let normals = halves
                .iter()
                .flat_map(|w| [*w as u16, (w >> 16) as u16])
                .take(n as usize)
                .collect();
            (
                read(&scene.word_buffers, words, scene.color_word_base + at, n),
                normals,
                read(
                    &scene.lookup_buffers,
                    node_words,
                    3 * u64::from(l.node_offset),
                    3 * u64::from(l.nodes),
                ),
            )
        })
        .collect()
}

fn assert_same(got: &Streams, want: &Streams, what: &str) {
    assert_eq!(got.len(), want.len());
    for (l, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.0.len(), w.0.len(), "{what}: level {l} voxel count");
        assert!(g.0 == w.0, "{what}: level {l} colours differ");
        assert!(g.1 == w.1, "{what}: level {l} normals differ");
        assert!(g.2 == w.2, "{what}: level {l} lookup nodes differ");
    }
}

/// Two instances of `asset`, the second moved and turned.
fn scene_of(asset: Arc<VoxelAsset>, level: u32) -> Scene {
    let mut s = ssbvb_tests::single_object_scene(asset, level);
    s.objects[0].instances.push(
        DAffine3::from_translation(DVec3::new(2.4, 0.0, -0.5))
            * DAffine3::from_rotation_y(0.9)
            * DAffine3::from_scale(DVec3::splat(0.8)),
    );
    s
}

#[test]
fn a_local_edit_rewrites_the_room_exactly_and_draws_like_the_edited_asset() {
    let ctx = ssbvb_tests::ctx();
    let level = 6;
    let bunny = ssbvb_tests::model_asset("bunny.obj", level);
    // The editor and the room start from the same prepared set (see LocalEditor::new).
    let finest = level_voxels(&bunny.lods[level as usize]);
    let start = prepared(finest.clone(), &bunny);
    let scene = scene_of(start.clone(), level);
    let room = DynamicRoom {
        object: 0,
        growth: 1.5,
    };
    let mut gpu_scene = GpuScene::with_dynamic(ctx, scene.clone(), &[room]).unwrap();
    let pipeline = ssbvb_graph::resolve_str(FLAT, "flat").unwrap();
    let mut renderer = Renderer::new(ctx, &gpu_scene, pipeline, SIZE).unwrap();
    let splicer = LevelSplicer::new(ctx).unwrap();
    let mut editor = LocalEditor::new(finest.clone());
    assert_same(
        &room_streams(&gpu_scene),
        &asset_streams(&start),
        "as uploaded",
    );

    let s = ssbvb_voxel::model::cell_size(level);
    let first = [
        Edit::RemoveSphere {
            center: (0.45, 0.1, 0.5),
            radius: 8.0 * s,
        },
        Edit::AddSphere {
            center: (-0.2, 0.75, 0.0),
            radius: 0.15,
            color: (0.9, 0.1, 0.1, 1.0),
        },
    ];
    let second = [Edit::RemoveBox {
        min: (-0.3, -0.2, -1.0),
        max: (-0.1, 0.0, 1.0),
    }];
    let mut expected = finest;
    let near = Camera::new(DVec3::new(1.6, 1.0, 2.3), DVec3::ZERO);
    let far = Camera::new(DVec3::new(4.0, 3.0, 9.0), DVec3::new(1.2, 0.0, 0.0));
    for (k, edits) in [&first[..], &second[..]].into_iter().enumerate() {
        let local = editor.apply(edits).unwrap();
        let (edited, report) = apply_edits(&expected, edits).unwrap();
        assert_eq!(local.report, report);
        assert!(report.removed > 50, "edit {k}: {report:?}");
        let stats = splicer
            .apply(ctx, &mut gpu_scene, 0, &local.patches)
            .unwrap();
        ctx.wait_idle().unwrap();
        assert!(ctx.take_uncaptured_errors().is_empty());
        let before = scene_of(prepared(expected.clone(), &bunny), level);
        expected = edited;
        let asset = prepared(expected.clone(), &bunny);
        assert_same(&room_streams(&gpu_scene), &asset_streams(&asset), "edited");
        let edited_scene = scene_of(asset, level);
        // Pixels each view covers at least (measured: ~6900 and ~930).
        for (cam, name, pixels) in [(&near, "near", 3000), (&far, "far", 500)] {
            renderer
                .render(ctx, &mut gpu_scene, cam, Profiling::Off)
                .unwrap();
            ctx.wait_idle().unwrap();
            assert!(ctx.take_uncaptured_errors().is_empty());
            let hits = ssbvb_passes::measure::gbuffer_hits_in(ctx, &renderer, &gpu_scene).unwrap();
            // World cell size per instance (the second is scaled by 0.8).
            let voxel = [s, 0.8 * s];
            let against = |sc: &Scene| {
                let reference = ssbvb_tests::reference_of(sc, cam, SIZE);
                accuracy::compare(&reference, &hits, &voxel).unwrap()
            };
            let (r, old) = (against(&edited_scene), against(&before));
            eprintln!(
                "local edit {k} ({name}, {} blocks of {}³, {stats:?}): IoU {:.4} same voxel {:.4} ({} px); against the unedited IoU {:.4} same voxel {:.4}",
                local.blocks,
                local.block_side,
                r.coverage_iou,
                r.same_voxel_rate,
                r.covered_reference,
                old.coverage_iou,
                old.same_voxel_rate
            );
            assert!(r.covered_reference > pixels, "{name}: {r:?}");
            assert!(
                r.coverage_iou >= 0.99 && r.same_voxel_rate >= 0.99,
                "{name}: {r:?}"
            );
            assert!(
                old.same_voxel_rate < 0.99,
                "the edit must show ({name}): {old:?}"
            );
        }
    }
    // Patches made for other counts than the room holds are refused, and change nothing.
    let hollow = [Edit::RemoveSphere {
        center: (0.0, 0.0, 0.0),
        radius: 0.3,
    }];
    let mut stale = editor.clone();
    let patches = stale.apply(&hollow).unwrap().patches;
    expected = apply_edits(&expected, &hollow).unwrap().0;
    splicer.apply(ctx, &mut gpu_scene, 0, &patches).unwrap();
    let now = room_streams(&gpu_scene);
    let err = splicer.apply(ctx, &mut gpu_scene, 0, &patches).unwrap_err();
    assert!(
        matches!(&err, ResourceError::BadScene(m) if m.contains("the editor and the scene disagree")),
        "{err}"
    );
    assert_same(&room_streams(&gpu_scene), &now, "after a refused patch");
    // A patch that outgrows the room names the room needed; the editor is reverted and
    // goes on editing the same room.
    let mut editor = stale;
    let fill = editor
        .apply(&[Edit::AddBox {
            min: (-1.0, -1.0, -1.0),
            max: (1.0, 1.0, 1.0),
            color: (1.0, 1.0, 1.0, 1.0),
        }])
        .unwrap();
    let err = splicer
        .apply(ctx, &mut gpu_scene, 0, &fill.patches)
        .unwrap_err();
    assert!(
        matches!(&err, ResourceError::TooLarge(m) if m.contains("upload it with more growth")),
        "{err}"
    );
    assert_same(&room_streams(&gpu_scene), &now, "after a refused growth");
    editor.revert(&fill);
    let dent = [Edit::RemoveSphere {
        center: (-0.3, 0.6, 0.0),
        radius: 4.0 * s,
    }];
    let local = editor.apply(&dent).unwrap();
    splicer
        .apply(ctx, &mut gpu_scene, 0, &local.patches)
        .unwrap();
    let want = apply_edits(&expected, &dent).unwrap().0;
    assert_same(
        &room_streams(&gpu_scene),
        &asset_streams(&prepared(want, &bunny)),
        "an edit after a revert",
    );
}
