//! Embedding: `VoxelLayer` draws into a caller's own colour and depth-stencil targets,
//! keeps the caller's pixels where there is no voxel and is depth-tested against the
//! caller's depth.

use glam::DVec3;
use ssbvb_gpu::wgpu;
use ssbvb_passes::Profiling;
use ssbvb_passes::runtime::embed::VoxelLayer;
use ssbvb_voxel::camera::Camera;

const SIZE: (u32, u32) = (96, 72);

fn target(
    c: &ssbvb_gpu::GpuContext,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    c.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host target"),
        size: wgpu::Extent3d {
            width: SIZE.0,
            height: SIZE.1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// The host "draws": clears colour to `clear` and depth to `depth` (reversed Z).
fn host_clear(c: &ssbvb_gpu::GpuContext, color: &wgpu::Texture, ds: &wgpu::Texture, depth: f32) {
    let mut enc = c.device.create_command_encoder(&Default::default());
    {
        let cv = color.create_view(&Default::default());
        let dv = ds.create_view(&Default::default());
        let _pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &cv,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 0.0,
                        g: 0.0,
                        b: 1.0,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(depth),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Store,
                }),
            }),
            ..Default::default()
        });
    }
    c.queue.submit([enc.finish()]);
}

#[test]
fn voxel_layer_composes_onto_the_callers_frame() {
    let c = ssbvb_tests::ctx();
    let color = target(
        c,
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let ds = target(
        c,
        c.depth_stencil_format(),
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    );
    let scene = ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", 6), 6);
    let cam = Camera::new(DVec3::new(1.8, 1.0, 2.4), DVec3::ZERO);
    let reference = ssbvb_tests::reference_of(&scene, &cam, SIZE);
    let mut layer = VoxelLayer::new(
        &c.instance,
        &c.adapter,
        &c.device,
        &c.queue,
        scene,
        None,
        &color,
        &ds,
    )
    .unwrap();

    // Far host depth (0 = infinitely far in reversed Z): voxels show where the reference hits.
    host_clear(c, &color, &ds, 0.0);
    layer.render(&cam, Profiling::Off).unwrap();
    let px = c
        .read_texture(&color, wgpu::TextureAspect::All)
        .unwrap()
        .bytes;
    let (mut voxel, mut kept) = (0, 0);
    for (i, p) in px.chunks(4).enumerate() {
        let hit = reference.hits[i].is_some();
        if p == [0, 0, 255, 255] {
            kept += 1;
            assert!(
                !hit,
                "pixel {i}: the reference sees a voxel, the layer drew nothing"
            );
        } else {
            voxel += 1;
        }
    }
    assert!(
        kept > 1000 && voxel > 500,
        "{kept} host pixels kept, {voxel} voxel pixels"
    );
    assert!(
        voxel >= reference.coverage(),
        "Flat billboards cover at least the reference"
    );
    assert!(c.take_uncaptured_errors().is_empty());

    // Host geometry in front of everything (depth 1 = the near plane): no voxel passes.
    host_clear(c, &color, &ds, 1.0);
    layer.render(&cam, Profiling::Off).unwrap();
    let px = c
        .read_texture(&color, wgpu::TextureAspect::All)
        .unwrap()
        .bytes;
    assert!(
        px.chunks(4).all(|p| p == [0, 0, 255, 255]),
        "voxels drawn over nearer host geometry"
    );
}

#[test]
fn imported_targets_of_the_wrong_size_or_format_are_refused() {
    let c = ssbvb_tests::ctx();
    let scene = ssbvb_tests::single_object_scene(ssbvb_tests::model_asset("bunny.obj", 6), 6);
    let color = target(
        c,
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let ds = target(
        c,
        c.depth_stencil_format(),
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    );
    match VoxelLayer::new(
        &c.instance,
        &c.adapter,
        &c.device,
        &c.queue,
        scene,
        None,
        &color,
        &ds,
    ) {
        Err(e) => assert!(e.to_string().contains("format"), "{e}"),
        Ok(_) => panic!("an Rgba8Unorm target for an Rgba8UnormSrgb output must be refused"),
    }
}
