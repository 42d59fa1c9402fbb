//! Allocations the driver may refuse. wgpu reports a refused allocation as an
//! out-of-memory error on the device, after the fact and without saying which resource;
//! the large allocations (the scene's voxel and node streams, which hold the page pools
//! under a budget, and the render graph's resources) go through [`GpuContext::checked_buffer`]
//! and friends instead, each in its own out-of-memory error scope, so a refusal becomes
//! [`GpuError::OutOfMemory`] naming the resource and its size, and the commands can lower
//! a `--gpu-budget` or name the flag that would help.
//!
//! [`GpuContext::refuse_allocation`] is the fault injection of tests
//! (`--inject-fault oom@FRAME`): it makes the next large checked allocation fail exactly
//! as a refused one does, at the same place.

use std::sync::atomic::Ordering;

use wgpu::util::BufferInitDescriptor;

use crate::{GpuContext, GpuError, InitBuffer};

/// `bytes` for messages: MiB with one decimal, or bytes under 1 MiB.
pub fn mib_text(bytes: u64) -> String {
    if bytes < 1 << 20 {
        format!("{bytes} bytes")
    } else {
        format!("{:.1} MiB", bytes as f64 / f64::from(1 << 20))
    }
}

impl GpuContext {
    /// Makes the next checked allocation of at least `min_bytes` fail with
    /// [`GpuError::OutOfMemory`], as a driver that ran out of memory would; the ones
    /// before and after it succeed. Fault injection for tests.
    pub fn refuse_allocation(&self, min_bytes: u64) {
        self.refuse_from.store(min_bytes, Ordering::SeqCst);
    }

    /// Disarms a refusal that has not fired (the work it was meant for allocated less).
    pub fn clear_refusal(&self) {
        self.refuse_from.store(u64::MAX, Ordering::SeqCst);
    }

    /// Whether an allocation of `bytes` is the injected refusal (which then is spent).
    fn refused_now(&self, bytes: u64) -> bool {
        self.refuse_from
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |min| {
                (min != u64::MAX && bytes >= min).then_some(u64::MAX)
            })
            .is_ok()
    }

    /// Runs `create` (an allocation of `bytes` for `resource`) in an out-of-memory error
    /// scope.
    fn allocating<T>(
        &self,
        resource: &str,
        bytes: u64,
        create: impl FnOnce(&wgpu::Device) -> T,
    ) -> Result<T, GpuError> {
        let refused = || GpuError::OutOfMemory {
            resource: resource.to_string(),
            bytes,
        };
        if self.refused_now(bytes) {
            return Err(refused());
        }
        if cfg!(target_arch = "wasm32") {
            // No blocking wait for the scope in the browser (see `GpuContext::validated`).
            return Ok(create(&self.device));
        }
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let out = create(&self.device);
        match pollster::block_on(scope.pop()) {
            Some(e) => {
                log::warn!("{resource} ({}): {e}", mib_text(bytes));
                Err(refused())
            }
            None => Ok(out),
        }
    }

    /// `device.create_buffer(desc)`, or [`GpuError::OutOfMemory`] when the driver
    /// refuses it.
    pub fn checked_buffer(
        &self,
        desc: &wgpu::BufferDescriptor<'_>,
    ) -> Result<wgpu::Buffer, GpuError> {
        self.allocating(desc.label.unwrap_or("a buffer"), desc.size, |d| {
            d.create_buffer(desc)
        })
    }

    /// [`InitBuffer::init_buffer`], or [`GpuError::OutOfMemory`] when the driver refuses
    /// the buffer.
    pub fn checked_init_buffer(
        &self,
        desc: &BufferInitDescriptor<'_>,
    ) -> Result<wgpu::Buffer, GpuError> {
        let bytes = desc.contents.len() as u64;
        self.allocating(desc.label.unwrap_or("a buffer"), bytes, |d| {
            d.init_buffer(desc)
        })
    }

    /// `device.create_texture(desc)`, or [`GpuError::OutOfMemory`] when the driver
    /// refuses it.
    pub fn checked_texture(
        &self,
        desc: &wgpu::TextureDescriptor<'_>,
    ) -> Result<wgpu::Texture, GpuError> {
        let texel = u64::from(desc.format.block_copy_size(None).unwrap_or(4));
        let s = desc.size;
        let bytes = texel
            * u64::from(s.width)
            * u64::from(s.height)
            * u64::from(s.depth_or_array_layers)
            * u64::from(desc.sample_count);
        self.allocating(desc.label.unwrap_or("a texture"), bytes, |d| {
            d.create_texture(desc)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_as_mib_or_bytes() {
        assert_eq!(mib_text(512), "512 bytes");
        assert_eq!(mib_text(3 << 20), "3.0 MiB");
        assert_eq!(mib_text((5 << 20) + (1 << 19)), "5.5 MiB");
    }
}
