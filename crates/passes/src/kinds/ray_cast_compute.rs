//! The compute form of the octree ray casters (`OctreeRayCast(compute: true)`,
//! `EsvoRayCast(compute: true)`; `shaders/ray_cast_compute.inc.wgsl`): one compute thread
//! per pixel casts the pixel's ray with the same WGSL as the fragment form and keeps its
//! hit in a per-pixel buffer (`cast_hits`); a fullscreen resolve writes the G-buffer of
//! that hit. The image is the fragment form's bit for bit (a GPU test holds it to that);
//! what changes is the stage the traversal runs in, which on GPUs with slow fragment work
//! (the H200 of docs/benchmarks.md) is the strongest form of the baseline.

use ssbvb_gpu::{GpuContext, wgpu};

use crate::error::PassError;
use crate::kinds::gbuffer::{PulledPipeline, Specialized};
use crate::runtime::bindings::PassBindings;
use crate::runtime::pipelines::pipeline_layout;
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{PassImpl, PassInit};

/// Threads per workgroup side (`@workgroup_size(8, 8)` in the WGSL).
const TILE: u32 = 8;

/// Bytes of one pixel's hit record (`vec4<u32>`).
const RECORD_BYTES: u64 = 16;

/// The compute pipelines and the resolve of one ray-casting pass.
pub(crate) struct ComputeCast {
    /// Indexed `[counting as usize]`: the counters compiled in or out, as the fragment
    /// form's pipelines.
    trace: [wgpu::ComputePipeline; 2],
    resolve: PulledPipeline,
    /// The per-pixel hit records and the pixels they hold.
    hits: Option<(wgpu::Buffer, u64)>,
}

impl ComputeCast {
    /// Compiles `P`'s `cs_main` of `special` with and without counting, over `bindings`'
    /// layout, and the resolve (`fs_resolve`); `constants` are the WGSL overrides.
    pub(crate) fn new<P: PassImpl>(
        init: &PassInit<'_>,
        bindings: &PassBindings,
        constants: &[(&'static str, f64)],
        special: &Specialized,
    ) -> Result<Self, PassError> {
        let (ctx, scene, _, pass) = init.parts();
        let resolve =
            PulledPipeline::with_fragment_for::<P>(init, constants, "fs_resolve", special)?;
        let module = ctx.shader(P::SHADER, &special.source)?;
        let label = format!("pass `{}`: {} compute trace", pass.name, P::SHADER);
        let trace = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(bindings));
            let make = |counting: bool| {
                let mut c = constants.to_vec();
                if !counting {
                    c.push(("COUNT_WORK", 0.0));
                }
                d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(&label),
                    layout: Some(&layout),
                    module: &module,
                    entry_point: Some("cs_main"),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &c,
                        ..Default::default()
                    },
                    cache: None,
                })
            };
            [make(false), make(true)]
        })?;
        Ok(Self {
            trace,
            resolve,
            hits: None,
        })
    }

    /// The hit buffer for `pixels` pixels, and whether it was made anew (bind groups that
    /// hold the old one must be made again). A screen whose hits exceed the device's
    /// storage-binding or buffer size is refused as too large.
    pub(crate) fn hits(
        &mut self,
        ctx: &GpuContext,
        kind: &str,
        pixels: u64,
    ) -> Result<(&wgpu::Buffer, bool), PassError> {
        let fresh = self.hits.as_ref().is_none_or(|h| h.1 != pixels);
        if fresh {
            let size = (pixels * RECORD_BYTES).max(RECORD_BYTES);
            let limits = ctx.device.limits();
            let most = limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size);
            if size > most {
                return Err(PassError::TooLarge(format!(
                    "{kind} (compute): {pixels} pixels need {} MiB of hits, more than the \
                     device binds ({} MiB); use the fragment form (compute: false) or a \
                     smaller image",
                    size >> 20,
                    most >> 20
                )));
            }
            let label = format!("{kind} hits");
            let buffer = ctx.validated(&label, |d| {
                d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&label),
                    size,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                })
            })?;
            self.hits = Some((buffer, pixels));
        }
        Ok((&self.hits.as_ref().expect("made above").0, fresh))
    }

    /// The hit buffer, once made.
    pub(crate) fn hit_buffer(&self) -> Option<&wgpu::Buffer> {
        self.hits.as_ref().map(|h| &h.0)
    }

    /// Records the trace over the screen (when `bind_group` is given: something is
    /// visible) and the resolve, the pass's time spanning both.
    pub(crate) fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        bind_group: Option<&wgpu::BindGroup>,
    ) {
        let (w, h) = rec.screen;
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&rec.pass.name),
                timestamp_writes: rec.span_begin_timestamps(),
            });
            if let Some(bg) = bind_group {
                pass.set_pipeline(&self.trace[usize::from(rec.counting)]);
                pass.set_bind_group(0, &rec.scene.bind_group, &[]);
                pass.set_bind_group(1, bg, &[]);
                pass.dispatch_workgroups(w.div_ceil(TILE), h.div_ceil(TILE), 1);
            }
        }
        self.resolve.record_resolve(encoder, rec, bind_group);
    }
}
