//! Stable LSD radix sort of 64-bit keys with one u32 payload on the GPU
//! (`shaders/gpu_radix_sort.wgsl`, offsets by [`GpuScan`]): 4 bits per pass, only over the
//! key bits that can differ. Used by the RastaVox build to order the surface voxels the
//! extraction wrote in atomic (arbitrary) order.

use crate::{GpuContext, wgpu};

use crate::ResourceError;
use crate::kernels::scan::GpuScan;
use crate::kernels::{Bind, Kernels, storage, uniform};

/// Keys per tile (256 threads × 4).
const TILE: u64 = 1024;

/// Keys and payloads in three buffers (`lo`, `hi`, `val`, `n` entries each).
pub struct SortBuffers {
    /// Low 32 bits of each key.
    pub lo: wgpu::Buffer,
    /// High 32 bits of each key.
    pub hi: wgpu::Buffer,
    /// The payload.
    pub val: wgpu::Buffer,
}

impl SortBuffers {
    /// Three storage buffers of `n` words.
    pub fn new(d: &wgpu::Device, label: &str, n: u64) -> Self {
        Self {
            lo: storage(d, label, n),
            hi: storage(d, label, n),
            val: storage(d, label, n),
        }
    }
}

/// The compiled sort.
pub struct GpuRadixSort {
    kernels: Kernels,
    scan: GpuScan,
}

impl GpuRadixSort {
    /// Compiles the sort (and its scan).
    pub fn new(ctx: &GpuContext) -> Result<Self, ResourceError> {
        use Bind::*;
        Ok(Self {
            kernels: Kernels::new(
                ctx,
                "gpu_radix_sort.wgsl",
                &[
                    Uniform, Read, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
                ],
                &["radix_histogram", "radix_scatter"],
            )?,
            scan: GpuScan::new(ctx)?,
        })
    }

    /// Records a sort of the first `n` entries of `data` by the key bits `0..bits` (bits
    /// above are ignored but travel with the key), using `scratch` (same size) for the
    /// ping-pong. Returns whether the sorted result ended in `scratch` (an odd number of
    /// passes) rather than in `data`.
    pub fn record(
        &self,
        d: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        data: &SortBuffers,
        scratch: &SortBuffers,
        n: u32,
        bits: u32,
    ) -> bool {
        let tiles = u64::from(n).div_ceil(TILE) as u32;
        let passes = bits.min(64).div_ceil(4);
        let hist = storage(d, "radix hist", 16 * u64::from(tiles));
        for p in 0..passes {
            self.record_pass(d, encoder, (data, scratch), &hist, n, p);
        }
        passes % 2 == 1
    }

    /// [`GpuRadixSort::record`], each pass submitted alone (named `what`): a pass is
    /// bounded work, the whole sort of a large set is not.
    pub fn sort_submitting(
        &self,
        ctx: &GpuContext,
        data: &SortBuffers,
        scratch: &SortBuffers,
        n: u32,
        bits: u32,
        what: &str,
    ) -> bool {
        let d = &ctx.device;
        let tiles = u64::from(n).div_ceil(TILE) as u32;
        let passes = bits.min(64).div_ceil(4);
        let hist = storage(d, "radix hist", 16 * u64::from(tiles));
        for p in 0..passes {
            let mut encoder = d.create_command_encoder(&Default::default());
            self.record_pass(d, &mut encoder, (data, scratch), &hist, n, p);
            ctx.submit(what, [encoder.finish()]);
        }
        passes % 2 == 1
    }

    /// Pass `p`: the 4 key bits from `4 p`, from one buffer of `pair` to the other.
    fn record_pass(
        &self,
        d: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        (data, scratch): (&SortBuffers, &SortBuffers),
        hist: &wgpu::Buffer,
        n: u32,
        p: u32,
    ) {
        let tiles = u64::from(n).div_ceil(TILE) as u32;
        let (src, dst) = if p.is_multiple_of(2) {
            (data, scratch)
        } else {
            (scratch, data)
        };
        let params = uniform(d, "radix params", &[n, 4 * p, tiles, 0]);
        let bg = self.kernels.bind_group(
            d,
            &[
                &params, &src.lo, &src.hi, &src.val, &dst.lo, &dst.hi, &dst.val, hist,
            ],
        );
        self.kernels
            .dispatch(encoder, "radix_histogram", &bg, tiles);
        self.scan.record(d, encoder, hist, 16 * tiles);
        self.kernels.dispatch(encoder, "radix_scatter", &bg, tiles);
    }

    /// The scan it uses (shared with callers that need one).
    pub fn scan(&self) -> &GpuScan {
        &self.scan
    }
}
