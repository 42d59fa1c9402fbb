//! The filter's entry margin against a rasterizer that snaps vertices. llvmpipe interpolates
//! the prepass's entry points from unsnapped positions, exact to f32; hardware interpolates
//! from vertices snapped to 1/16 pixel or finer, which moves an entry along its ray by up to
//! 1/16 of how much it changes to a neighbouring pixel. The margin allows 1/8, and the test
//! holds it to that: the prepass runs, each entry is then moved 1/8 of its largest change to
//! a 4-neighbour deeper along its ray, and the filter alone runs on the moved entries: it
//! must find the reference's voxel at every pixel. Without the margin's slope term, or with
//! a neighbour of the four left out, it starts grazing faces' marches behind their first
//! voxels.

use glam::DVec3;
use ssbvb_gpu::wgpu;
use ssbvb_passes::kinds::ray_march_filter::VoxelSlot;
use ssbvb_passes::runtime::recorder::Recorder;
use ssbvb_passes::runtime::resources::FrameResources;
use ssbvb_tests::{ctx, grazing_camera, model_asset, reference_of, single_object_scene};
use ssbvb_voxel::accuracy;
use ssbvb_voxel::camera::Camera;

use super::harness::{cell_sizes, hits_of_slots};
use crate::empty_space::{prefilter_pipeline, synthetic_asset};

/// How far an entry is moved, in pixels of its change to a neighbour: the whole 1/8 that
/// the margin allows (twice the 1/16 a rasterizer's snapping may move it).
const SNAP_PX: f64 = 1.0 / 8.0;

/// Moves each covered pixel's entry (`entry`: object-space xyz, instance + 1 in w; one
/// instance, scaled uniformly about the origin at most, so object and world rays have one
/// direction) deeper along its ray by `SNAP_PX` of its largest change along the ray to a
/// 4-neighbour of its instance.
fn snap_entries(entry: &[f32], camera: &Camera, size: (u32, u32)) -> Vec<f32> {
    let at = |x: i64, y: i64| -> Option<[f32; 4]> {
        if x < 0 || y < 0 || x >= size.0 as i64 || y >= size.1 as i64 {
            return None;
        }
        let i = (y as usize * size.0 as usize + x as usize) * 4;
        Some([entry[i], entry[i + 1], entry[i + 2], entry[i + 3]])
    };
    let mut out = entry.to_vec();
    for y in 0..size.1 as i64 {
        for x in 0..size.0 as i64 {
            let e = at(x, y).unwrap();
            if e[3] < 1.0 {
                continue;
            }
            let (_, dir) = camera.ray(x as u32, y as u32, size.0, size.1);
            let d = dir.normalize();
            let p = DVec3::new(e[0] as f64, e[1] as f64, e[2] as f64);
            let change = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .filter_map(|(dx, dy)| at(x + dx, y + dy).filter(|n| n[3] == e[3]))
                .map(|n| {
                    (DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64) - p)
                        .dot(d)
                        .abs()
                })
                .fold(0.0, f64::max);
            let moved = p + d * (SNAP_PX * change);
            let i = (y as usize * size.0 as usize + x as usize) * 4;
            out[i..i + 3].copy_from_slice(&moved.as_vec3().to_array());
        }
    }
    out
}

/// Runs the prepass, snaps its entries, runs the filter on them; returns the same-voxel
/// rate against the reference and the pixels covered (reference, GPU).
fn filter_on_snapped_entries(
    scene: &ssbvb_gpu::scene::Scene,
    camera: &Camera,
    size: (u32, u32),
) -> (f64, usize, usize) {
    let c = ctx();
    let pipeline = ssbvb_graph::resolve_str(&prefilter_pipeline(1024), "snapped").unwrap();
    let mut gpu = ssbvb_gpu::scene::GpuScene::new(c, scene.clone()).unwrap();
    gpu.update(c, camera, size);
    // `entry` is the test's own texture, so that it may be written between the passes.
    let entry = c.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("snapped entry"),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let resources = FrameResources::with_imports(c, &pipeline, size, &[("entry", entry)]).unwrap();
    let entry_tex = &resources
        .texture(pipeline.resource("entry").unwrap())
        .texture;
    for (k, pass) in pipeline.passes.iter().enumerate() {
        let mut node = ssbvb_passes::kinds::create_pass(c, &gpu, &pipeline, pass).unwrap();
        let firsts: Vec<&'static str> = pass.bindings.iter().map(|b| b.slot.name).collect();
        let mut encoder = c.device.create_command_encoder(&Default::default());
        let mut rec = Recorder {
            gpu: c,
            scene: &gpu,
            resources: &resources,
            pass,
            screen: size,
            timestamps: None,
            first_writes: &firsts,
            counting: false,
        };
        c.validated("record", |_| node.record(&mut encoder, &mut rec))
            .unwrap()
            .unwrap();
        c.queue.submit([encoder.finish()]);
        c.wait_idle().unwrap();
        if k == 0 {
            assert_eq!(pass.name, "empty_space");
            let raw = c.read_texture(entry_tex, wgpu::TextureAspect::All).unwrap();
            let snapped = snap_entries(&raw.as_f32(), camera, size);
            c.queue.write_texture(
                entry_tex.as_image_copy(),
                bytemuck::cast_slice(&snapped),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(size.0 * 16),
                    rows_per_image: None,
                },
                entry_tex.size(),
            );
        }
    }
    assert_eq!(pipeline.passes.len(), 2, "the prepass and the filter");
    let buffer = |name: &str| resources.buffer(pipeline.resource(name).unwrap());
    let draw: Vec<u32> =
        bytemuck::pod_collect_to_vec(&c.read_buffer(buffer("billboard_draw")).unwrap());
    let bytes = c.read_buffer(buffer("ssbvb")).unwrap();
    let slots: Vec<VoxelSlot> = bytemuck::pod_collect_to_vec(&bytes[..bytes.len() / 32 * 32]);
    let slots = &slots[..draw[1] as usize];
    let pixels = (size.0 * size.1) as usize;
    let hits = hits_of_slots(scene, camera, size, &gpu.visible, slots, pixels);
    let errs = c.take_uncaptured_errors();
    assert!(errs.is_empty(), "wgpu errors: {errs:#?}");
    let reference = reference_of(scene, camera, size);
    let report = accuracy::compare(&reference, &hits, &cell_sizes(scene, camera, size)).unwrap();
    eprintln!("{report:?}");
    (
        report.same_voxel_rate,
        report.covered_reference,
        report.covered_gpu,
    )
}

/// A solid plate of 64 × 2 × 64 cells at level 6, its top face at y = 0, scaled by
/// `scale` about the origin (object-space ray directions then have length 1 / `scale`,
/// which the margin divides out).
fn plate(scale: f64) -> ssbvb_gpu::scene::Scene {
    let mut cells = Vec::new();
    for x in 0..64 {
        for y in 30..32 {
            for z in 0..64 {
                cells.push([x, y, z]);
            }
        }
    }
    let mut scene = single_object_scene(synthetic_asset(6, &cells), 6);
    scene.objects[0].instances = vec![glam::DAffine3::from_scale(DVec3::splat(scale))];
    scene
}

/// The unit plate's grazing camera rolled by `turns_of_pi` × π about its view direction.
fn rolled(turns_of_pi: f64) -> Camera {
    let camera = Camera::new(DVec3::new(2.5, 0.06, 0.3), DVec3::new(0.0, 0.0, 0.0));
    let axis = (camera.look_at - camera.position).normalize();
    let roll = glam::DQuat::from_axis_angle(axis, turns_of_pi * std::f64::consts::PI);
    Camera {
        up: roll * DVec3::Y,
        ..camera
    }
}

#[test]
fn snapped_entries_still_find_the_reference_voxels() {
    let level = 6;
    let asset = model_asset("chr_knight.vox", level);
    let knight = single_object_scene(asset.clone(), level);
    let unit_plate = plate(1.0);
    let big_plate = plate(2.0);
    let size = (96, 72);
    for (name, scene, camera) in [
        ("knight grazing", &knight, grazing_camera(&asset, level)),
        (
            "knight oblique",
            &knight,
            Camera::new(DVec3::new(2.2, 0.35, 1.6), DVec3::new(0.0, 0.0, 0.0)),
        ),
        // About 1.4° above the plate's top face: neighbouring rows' entries lie several
        // cells apart along the ray, so 1/8 of that is more than the margin's one cell.
        (
            "plate grazing",
            &unit_plate,
            Camera::new(DVec3::new(2.5, 0.06, 0.3), DVec3::new(0.0, 0.0, 0.0)),
        ),
        (
            "plate x2 grazing",
            &big_plate,
            Camera::new(DVec3::new(5.0, 0.12, 0.6), DVec3::new(0.0, 0.0, 0.0)),
        ),
        // The same view rolled a quarter, a half and three quarters: the far rows, whose
        // entries change most, then end at each side of the image in turn, where a pixel
        // has only the one neighbour of the plate that each offset of the margin names.
        ("plate rolled 90°", &unit_plate, rolled(0.5)),
        ("plate rolled 180°", &unit_plate, rolled(1.0)),
        ("plate rolled 270°", &unit_plate, rolled(1.5)),
        // Rolled off the quarter turns, the far rows' change has both an x and a y part:
        // at the image's side a diagonal neighbour then changes less than the 4-neighbour
        // it would stand in for.
        ("plate rolled 72°", &unit_plate, rolled(0.4)),
        ("plate rolled 108°", &unit_plate, rolled(0.6)),
        ("plate rolled 252°", &unit_plate, rolled(1.4)),
        ("plate rolled 288°", &unit_plate, rolled(1.6)),
    ] {
        let (same, covered_ref, covered_gpu) = filter_on_snapped_entries(scene, &camera, size);
        eprintln!("{name}: same voxel {same}, covered {covered_ref} / {covered_gpu}");
        assert!(covered_ref > 300, "{name}: {covered_ref} covered pixels");
        assert_eq!(covered_gpu, covered_ref, "{name}");
        assert_eq!(same, 1.0, "{name}");
    }
}
