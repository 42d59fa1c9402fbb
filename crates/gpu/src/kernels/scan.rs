//! Exclusive prefix sum of a u32 buffer on the GPU (`shaders/gpu_scan.wgsl`): the building
//! block of the radix sort's digit offsets and the surface build's run starts.

use crate::{GpuContext, wgpu};

use crate::ResourceError;
use crate::kernels::{Bind, Kernels, storage, uniform};

/// Elements per block (256 threads × 4).
const BLOCK: u64 = 1024;

/// The compiled scan.
pub struct GpuScan {
    kernels: Kernels,
}

impl GpuScan {
    /// Compiles the scan kernels.
    pub fn new(ctx: &GpuContext) -> Result<Self, ResourceError> {
        Ok(Self {
            kernels: Kernels::new(
                ctx,
                "gpu_scan.wgsl",
                &[Bind::Uniform, Bind::ReadWrite, Bind::ReadWrite],
                &["scan_reduce", "scan_sums", "scan_apply"],
            )?,
        })
    }

    /// Records an in-place exclusive scan of `data[0..n]`. Returns the buffer whose word
    /// [`GpuScan::total_index`]`(n)` holds the sum of all `n` inputs once the work is done.
    pub fn record(
        &self,
        d: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        data: &wgpu::Buffer,
        n: u32,
    ) -> wgpu::Buffer {
        let blocks = u64::from(n).div_ceil(BLOCK) as u32;
        let sums = storage(d, "scan sums", u64::from(blocks) + 1);
        let params = uniform(d, "scan params", &[n, blocks]);
        let bg = self.kernels.bind_group(d, &[&params, data, &sums]);
        self.kernels.dispatch(encoder, "scan_reduce", &bg, blocks);
        self.kernels.dispatch(encoder, "scan_sums", &bg, 1);
        self.kernels.dispatch(encoder, "scan_apply", &bg, blocks);
        sums
    }

    /// Word of the buffer [`GpuScan::record`] returns that holds the total.
    pub fn total_index(n: u32) -> u64 {
        u64::from(n).div_ceil(BLOCK)
    }
}
