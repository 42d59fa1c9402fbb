//! A lost device, on a device of its own (the shared one stays alive for the other
//! tests): `GpuContext` reports the loss with wgpu's reason where commands wait, and
//! creating a buffer with contents does not panic on it (wgpu's `create_buffer_init` does).

use ssbvb_gpu::wgpu::util::BufferInitDescriptor;
use ssbvb_gpu::{GpuContext, GpuError, InitBuffer, wgpu};

#[test]
fn a_lost_device_is_reported_and_uploads_to_it_do_not_panic() {
    let shared = ssbvb_tests::ctx();
    let ctx = GpuContext::from_adapter(shared.instance.clone(), shared.adapter.clone(), Vec::new())
        .unwrap();
    // Contents round-trip, padded to 4 bytes.
    let contents = [1u8, 2, 3, 4, 5];
    let buffer = ctx.device.init_buffer(&BufferInitDescriptor {
        label: Some("test"),
        contents: &contents,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    });
    assert_eq!(buffer.size(), 8);
    let back = ctx.read_buffer(&buffer).unwrap();
    assert_eq!(&back[..5], &contents);
    assert!(ctx.lost().is_none());
    ctx.wait_idle().unwrap();

    ctx.inject_device_loss();
    let reason = ctx.lost().expect("the loss is reported");
    assert!(reason.contains("Destroyed"), "{reason}");
    match ctx.wait_idle() {
        Err(GpuError::DeviceLost { reason }) => assert!(reason.contains("Destroyed"), "{reason}"),
        other => panic!("{other:?}"),
    }
    // What a scene upload does on it: no panic, an unusable buffer.
    let lost = ctx.device.init_buffer(&BufferInitDescriptor {
        label: Some("after the loss"),
        contents: &contents,
        usage: wgpu::BufferUsages::STORAGE,
    });
    drop(lost);
    assert!(ctx.read_buffer(&buffer).is_err());
    // The shared device is untouched.
    assert!(shared.lost().is_none());
}

/// A refused allocation (injected as `--inject-fault oom@FRAME` does) surfaces where it
/// happens as `GpuError::OutOfMemory` naming the resource and its size, through the scene
/// upload and the render graph's resources alike; smaller allocations pass, and the
/// refusal is spent once it fired. On a device of its own: the refusal is per device.
#[test]
fn a_refused_allocation_is_an_error_naming_the_resource_and_its_size() {
    let shared = ssbvb_tests::ctx();
    let ctx = GpuContext::from_adapter(shared.instance.clone(), shared.adapter.clone(), Vec::new())
        .unwrap();
    let buffer = |label: &'static str, size: u64| {
        ctx.checked_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    };
    ctx.refuse_allocation(1 << 20);
    assert!(buffer("small", 4096).is_ok(), "under the size refused");
    match buffer("big", 3 << 20) {
        Err(GpuError::OutOfMemory { resource, bytes }) => {
            assert_eq!((resource.as_str(), bytes), ("big", 3 << 20));
        }
        other => panic!("{other:?}"),
    }
    assert!(
        buffer("big again", 3 << 20).is_ok(),
        "the refusal fires once"
    );

    // The scene: its first large stream is refused, by name.
    let asset = ssbvb_tests::model_asset("bunny.obj", 7);
    let scene = ssbvb_tests::single_object_scene(asset, 7);
    ctx.refuse_allocation(64 << 10);
    match ssbvb_gpu::scene::GpuScene::new(&ctx, scene.clone()) {
        Err(ssbvb_gpu::ResourceError::Gpu(GpuError::OutOfMemory { resource, bytes })) => {
            assert_eq!(resource, "LOD table, voxel colours and normals 0");
            assert!(bytes >= 64 << 10, "{bytes}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("the refused upload succeeded"),
    }
    // The render graph: a frame target is refused, by name, with its size.
    let gpu_scene = ssbvb_gpu::scene::GpuScene::new(&ctx, scene).unwrap();
    let path = format!(
        "{}/../assets/pipelines/ssbvb_unique.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let src = std::fs::read_to_string(&path).unwrap();
    let pipeline = ssbvb_graph::resolve_str(&src, &path).unwrap();
    ctx.refuse_allocation(64 << 10);
    let size = (160, 120);
    match ssbvb_passes::Renderer::new(&ctx, &gpu_scene, pipeline.clone(), size) {
        Err(ssbvb_passes::PassError::Gpu(GpuError::OutOfMemory { resource, bytes })) => {
            assert!(resource.contains("(physical"), "{resource}");
            assert!(
                (64 << 10..=16 * 160 * 120).contains(&bytes),
                "{resource}: {bytes}"
            );
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("the refused renderer was built"),
    }
    ssbvb_passes::Renderer::new(&ctx, &gpu_scene, pipeline, size).unwrap();
    ctx.wait_idle().unwrap();
    assert!(ctx.take_uncaptured_errors().is_empty());
}
