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
