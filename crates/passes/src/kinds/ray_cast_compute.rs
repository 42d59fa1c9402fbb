//! The compute form of the octree ray casters (`OctreeRayCast(compute: true)`,
//! `EsvoRayCast(compute: true)`; `shaders/ray_cast_compute.inc.wgsl`): one compute thread
//! per pixel casts the pixel's ray with the same WGSL as the fragment form and keeps its
//! hit in a per-pixel buffer (`cast_hits`); a fullscreen resolve writes the G-buffer of
//! that hit. The image is the fragment form's bit for bit (a GPU test holds it to that);
//! what changes is the stage the traversal runs in, which on GPUs with slow fragment work
//! (the H200 of docs/benchmarks.md) is the strongest form of the baseline.
//!
//! It launches only the 16 × 16 tiles that some visible instance's box may cover
//! (`mark_cast_tiles` flags each leaf box's projected pixel rectangle, widened;
//! `list_cast_tiles` lists the flagged tiles, `shaders/tile_list.inc.wgsl`; `cs_main` is
//! dispatched indirectly on the list), as the SSBVB filter launches only the tiles with a
//! proxy: a software adapter runs a launched workgroup at nearly full cost whatever its
//! lanes do, and the baseline should not pay for pixels no ray of which can hit.

use ssbvb_gpu::{GpuContext, shaders, wgpu};

use crate::error::PassError;
use crate::kinds::gbuffer::{PulledPipeline, Specialized};
use crate::runtime::bindings::PassBindings;
use crate::runtime::pipelines::pipeline_layout;
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{PassImpl, PassInit};

/// Pixels per tile side, `cs_main`'s workgroup (`TILE` in `shaders/tile_list.inc.wgsl`).
const TILE: u32 = 16;

/// Bytes of one pixel's hit record (four words).
const RECORD_BYTES: u64 = 16;

/// Leaf boxes `mark_cast_tiles` takes per workgroup (`@workgroup_size(64)`).
const MARK_GROUP: u32 = 64;

/// The tiles of a `w` × `h` screen.
fn tile_count(w: u32, h: u32) -> u64 {
    u64::from(w.div_ceil(TILE)) * u64::from(h.div_ceil(TILE))
}

/// The compute pipelines and the resolve of one ray-casting pass.
pub(crate) struct ComputeCast {
    /// Indexed `[counting as usize]`: the counters compiled in or out, as the fragment
    /// form's pipelines.
    trace: [wgpu::ComputePipeline; 2],
    /// Flags the tiles of the visible instances' boxes (`mark_cast_tiles`).
    mark: wgpu::ComputePipeline,
    /// Lists them and writes the trace's indirect dispatch (`list_cast_tiles`), with its
    /// own bindings: the hits and the arguments.
    list: wgpu::ComputePipeline,
    list_bindings: PassBindings,
    /// The trace's indirect dispatch arguments.
    dispatch: wgpu::Buffer,
    resolve: PulledPipeline,
    /// The per-pixel hit records and tile words, the screen they hold, and the listing's
    /// bind group over them.
    hits: Option<(wgpu::Buffer, (u32, u32), wgpu::BindGroup)>,
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
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let resolve =
            PulledPipeline::with_fragment_for::<P>(init, constants, "fs_resolve", special)?;
        let module = ctx.shader(P::SHADER, &special.source)?;
        let label = format!("pass `{}`: {} compute trace", pass.name, P::SHADER);
        let max_grid = f64::from(ctx.device.limits().max_compute_workgroups_per_dimension);
        let make =
            |d: &wgpu::Device, layout: &wgpu::PipelineLayout, entry: &str, counting: bool| {
                let mut c = constants.to_vec();
                c.push(("MAX_GRID", max_grid));
                if !counting {
                    c.push(("COUNT_WORK", 0.0));
                }
                d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(&label),
                    layout: Some(layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &c,
                        ..Default::default()
                    },
                    cache: None,
                })
            };
        let (trace, mark) = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(bindings));
            let trace = [
                make(d, &layout, "cs_main", false),
                make(d, &layout, "cs_main", true),
            ];
            (trace, make(d, &layout, "mark_cast_tiles", true))
        })?;
        let used = shaders::used_bindings(P::SHADER, &special.source, &["list_cast_tiles"], 1)?;
        let list_bindings = PassBindings::used_only(ctx, pipeline, pass, P::OWN, Some(&used[0]));
        let list = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(&list_bindings));
            make(d, &layout, "list_cast_tiles", true)
        })?;
        let dispatch = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ray cast dispatch arguments"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        Ok(Self {
            trace,
            mark,
            list,
            list_bindings,
            dispatch,
            resolve,
            hits: None,
        })
    }

    /// The hit buffer for a `w` × `h` screen (its records, then its tile words), and
    /// whether it was made anew (bind groups that hold the old one must be made again). A
    /// screen whose hits exceed the device's storage-binding or buffer size is refused as
    /// too large.
    pub(crate) fn hits(
        &mut self,
        ctx: &GpuContext,
        kind: &str,
        (w, h): (u32, u32),
    ) -> Result<(&wgpu::Buffer, bool), PassError> {
        let fresh = self.hits.as_ref().is_none_or(|hits| hits.1 != (w, h));
        if fresh {
            let pixels = u64::from(w) * u64::from(h);
            let size = pixels * RECORD_BYTES + (1 + 2 * tile_count(w, h)) * 4;
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
            let (buffer, list_group) = ctx.validated(&label, |d| {
                let buffer = d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&label),
                    size,
                    // COPY_DST: the tile flags are cleared every frame; COPY_SRC: the
                    // tile count is read back for the counters.
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                let group = self.list_bindings.own_bind_group(
                    d,
                    &label,
                    &[
                        ("cast_hits", buffer.as_entire_binding()),
                        ("cast_dispatch", self.dispatch.as_entire_binding()),
                    ],
                );
                (buffer, group)
            })?;
            self.hits = Some((buffer, (w, h), list_group?));
        }
        Ok((&self.hits.as_ref().expect("made above").0, fresh))
    }

    /// The hit buffer, once made.
    pub(crate) fn hit_buffer(&self) -> Option<&wgpu::Buffer> {
        self.hits.as_ref().map(|h| &h.0)
    }

    /// The tiles the last recorded frame listed and traced (0 before any frame).
    pub(crate) fn tiles_launched(&self, ctx: &GpuContext) -> Result<u64, PassError> {
        let Some((buffer, (w, h), _)) = &self.hits else {
            return Ok(0);
        };
        let at = u64::from(*w) * u64::from(*h) * RECORD_BYTES / 4;
        let words = ssbvb_gpu::kernels::read_words(ctx, buffer, at, 1)?;
        Ok(words.first().map_or(0, |&t| u64::from(t)))
    }

    /// Records the trace of the listed tiles (when `bind_group` is given: something is
    /// visible; [`ComputeCast::hits`] was called for this screen) and the resolve, the
    /// pass's time spanning both.
    pub(crate) fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        bind_group: Option<&wgpu::BindGroup>,
    ) {
        let (w, h) = rec.screen;
        if let Some((buffer, _, _)) = &self.hits {
            // The tile count and flags (a frame with nothing visible lists no tile); the
            // records and the list are written before read.
            let at = u64::from(w) * u64::from(h) * RECORD_BYTES;
            encoder.clear_buffer(buffer, at, Some((1 + tile_count(w, h)) * 4));
        }
        let hits = self.hits.as_ref().filter(|_| bind_group.is_some());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&rec.pass.name),
                timestamp_writes: rec.span_begin_timestamps(),
            });
            if let (Some(bg), Some((_, _, list_group))) = (bind_group, hits) {
                let boxes = (2 * rec.scene.visible.len() as u32).saturating_sub(1);
                pass.set_bind_group(0, &rec.scene.bind_group, &[]);
                pass.set_bind_group(1, bg, &[]);
                // wgpu orders the dispatches: tiles flagged, then listed, then traced.
                pass.set_pipeline(&self.mark);
                pass.dispatch_workgroups(boxes.div_ceil(MARK_GROUP), 1, 1);
                pass.set_bind_group(1, list_group, &[]);
                pass.set_pipeline(&self.list);
                pass.dispatch_workgroups(1, 1, 1);
                pass.set_bind_group(1, bg, &[]);
                pass.set_pipeline(&self.trace[usize::from(rec.counting)]);
                pass.dispatch_workgroups_indirect(&self.dispatch, 0);
            }
        }
        self.resolve.record_resolve(encoder, rec, bind_group);
    }
}
