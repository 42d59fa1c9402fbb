//! Buffers created with their contents, without wgpu's `create_buffer_init` panic: that
//! helper maps the new buffer and panics when the mapping fails, which it does on a device
//! that was lost (a driver reset while a scene uploads). [`InitBuffer::init_buffer`] does
//! the same upload and, on a lost device, returns the (invalid) buffer unfilled: the loss
//! then surfaces as [`crate::GpuError::DeviceLost`] at the next wait, where the commands
//! handle it.

use wgpu::util::BufferInitDescriptor;

/// [`wgpu::Device`] creating buffers with their contents.
pub trait InitBuffer {
    /// A buffer of `desc.usage` holding `desc.contents` (size rounded up to 4 bytes, at
    /// least 4), like `wgpu::util::DeviceExt::create_buffer_init`, but unfilled rather than
    /// a panic when the device is lost.
    fn init_buffer(&self, desc: &BufferInitDescriptor<'_>) -> wgpu::Buffer;
}

impl InitBuffer for wgpu::Device {
    fn init_buffer(&self, desc: &BufferInitDescriptor<'_>) -> wgpu::Buffer {
        let align = wgpu::COPY_BUFFER_ALIGNMENT;
        let size = (desc.contents.len() as u64).div_ceil(align).max(1) * align;
        let buffer = self.create_buffer(&wgpu::BufferDescriptor {
            label: desc.label,
            size,
            usage: desc.usage,
            mapped_at_creation: true,
        });
        if let Ok(mut view) = buffer.get_mapped_range_mut(..) {
            view.slice(..desc.contents.len())
                .copy_from_slice(desc.contents);
            drop(view);
            buffer.unmap();
        }
        buffer
    }
}
