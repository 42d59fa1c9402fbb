//! `splat_billboards`: the SSBVB's billboards splatted in compute (`SplatBillboards`;
//! `shaders/splat_billboards.wgsl`), the compute rasterization of Schütz, Kerbl and Wimmer
//! for adapters whose raster units are weak (a CPU adapter; data-centre GPUs such as the
//! H100/H200, which have little fixed-function raster). Same quads and the same pixel
//! shading as [`crate::kinds::billboards`] (`shaders/billboard_quad.inc.wgsl`), so the G-buffer is
//! the same and smoothing and composite run unchanged.
//!
//! Per frame: the per-pixel words (depth bits and entry, interleaved) are cleared; a first dispatch (one thread per SSBVB
//! entry, 64 per workgroup, a 2D grid over the SSBVB's capacity) takes the nearest depth of
//! every pixel its billboard covers by `atomicMax` on the reversed-Z depth's bits; a second
//! dispatch of the same pipeline keeps, where that depth is its own, the lowest entry (as
//! the rasterizer's strict depth test keeps the first of equal-depth quads); a fullscreen
//! resolve writes the winning billboard's fragment with its depth, depth-tested against
//! what is already in the G-buffer (the triangles), stencil = voxel. Both splat steps are
//! one compiled shader so that the depths they compute agree bit for bit.
//!
//! Why two 32-bit passes and not one 64-bit `atomicMin` of (depth, entry): the 64-bit
//! form needs `SHADER_INT64_ATOMIC_MIN_MAX`, which Metal and older drivers lack; two
//! passes over the same pixels need only core atomics, cost a second walk of each quad,
//! and give the same winner.
//!
//! A thread walks its quad's pixel rectangle: cheap for the default pipeline (one
//! billboard per visible voxel), costly where quads are large and many (the per-pixel Flat
//! frame seen from up close, as for the rasterizer).

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{BillboardMode, SplatBillboardsParams};

use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::PulledPipeline;
use crate::runtime::pipelines::pipeline_layout;
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;

/// Threads per workgroup of both splat entry points.
const WORKGROUP: u64 = 64;

/// What the splat binds itself: per pixel the nearest depth's bits and the winning entry,
/// interleaved in one buffer (the pass then fits WebGPU's 8 storage buffers per stage).
pub const OWN: &[OwnBinding] = &[OwnBinding {
    name: "splat_pixels",
    kind: OwnKind::StorageReadWrite,
}];

/// The compiled splat: two compute pipelines and the resolve.
pub struct SplatBillboards {
    /// Both splat steps (dispatched with one, then two layers of workgroups).
    splat: wgpu::ComputePipeline,
    resolve: PulledPipeline,
    /// The per-pixel words (depth bits, entry) and the pixels they hold.
    pixels: Option<(wgpu::Buffer, u64)>,
}

impl PassImpl for SplatBillboards {
    type Params = SplatBillboardsParams;
    const SHADER: &'static str = "splat_billboards.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    // Compute splats, and a fragment shader that reads the atomics it wrote.
    const NEEDS: KindNeeds = KindNeeds::new(
        wgpu::DownlevelFlags::COMPUTE_SHADERS.union(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE),
        3,
    );

    /// Compiles the splat and the resolve; `mode` becomes the WGSL override `RAY_BOX`.
    fn new(init: &PassInit<'_>, params: &SplatBillboardsParams) -> Result<Self, PassError> {
        let (ctx, scene, _, pass) = init.parts();
        let constants = [
            ("SIZE_SCALE", f64::from(params.size_scale)),
            ("CULL_COS", f64::from(crate::kinds::billboards::DEFAULT_CULL_COS)),
            ("BOX_FOOTPRINT", 1.0),
            (
                "RAY_BOX",
                f64::from(u8::from(params.mode == BillboardMode::RayBox)),
            ),
        ];
        let resolve = PulledPipeline::new::<Self>(init, &constants)?;
        let module = ctx.shader(
            Self::SHADER,
            &ssbvb_gpu::shaders::source_for(Self::SHADER, &scene.bindings)?,
        )?;
        let label = format!("pass `{}`: splat pipelines", pass.name);
        let splat = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(&resolve.bindings));
            d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("splat_main"),
                layout: Some(&layout),
                module: &module,
                entry_point: Some("splat_main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                },
                cache: None,
            })
        })?;
        Ok(Self {
            splat,
            resolve,
            pixels: None,
        })
    }
}

/// Workgroups for `entries` threads of 64 as a 2D grid (x at most 65535).
pub fn splat_grid(entries: u64) -> (u32, u32) {
    let groups = entries.div_ceil(WORKGROUP).max(1);
    let x = groups.min(65_535);
    (x as u32, groups.div_ceil(x) as u32)
}

impl SplatBillboards {
    /// Makes the per-pixel words for `pixels` pixels unless they exist at that size.
    fn buffers(&mut self, ctx: &GpuContext, pixels: u64) {
        if self.pixels.as_ref().is_none_or(|p| p.1 != pixels) {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("splat pixels"),
                size: (pixels * 8).max(16),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.pixels = Some((buffer, pixels));
        }
    }
}

impl PassNode for SplatBillboards {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let (w, h) = rec.screen;
        let entries = rec.buffer("ssbvb").size() / 32;
        self.buffers(rec.gpu, w as u64 * h as u64);
        let (words, _) = self.pixels.as_ref().expect("made above");
        let bind_group = self
            .resolve
            .bindings
            .bind_group(rec, &[("splat_pixels", words.as_entire_binding())])?;
        encoder.clear_buffer(words, 0, None);
        let (gx, gy) = splat_grid(entries);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&rec.pass.name),
                // The pass's time spans the splats and the resolve.
                timestamp_writes: rec.span_begin_timestamps(),
            });
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, &bind_group, &[]);
            // wgpu orders the dispatches: every depth is in before entries are chosen. One
            // pipeline for both (see the WGSL): z = 1 splats depths, z = 2 entries.
            pass.set_pipeline(&self.splat);
            pass.dispatch_workgroups(gx, gy, 1);
            pass.dispatch_workgroups(gx, gy, 2);
        }
        self.resolve.record_resolve(encoder, rec, Some(&bind_group));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_covers_every_entry_within_the_dispatch_limit() {
        for n in [0u64, 1, 64, 65, 640 * 480, 3840 * 2160, 65_535 * 64 + 1] {
            let (x, y) = splat_grid(n);
            assert!(x <= 65_535 && y >= 1, "{n}: {x} x {y}");
            assert!(x as u64 * y as u64 * WORKGROUP >= n, "{n}: {x} x {y}");
            // No more than one row of workgroups beyond what is needed.
            assert!((x as u64 * (y as u64 - 1)) * WORKGROUP < n.max(1), "{n}: {x} x {y}");
        }
    }
}
