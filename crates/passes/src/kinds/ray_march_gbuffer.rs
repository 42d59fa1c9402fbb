//! `ray_march_gbuffer`: the filter's march with each pixel's hit written straight into the
//! G-buffer (`RayMarchGBuffer`; `shaders/ray_march_gbuffer.wgsl`).
//!
//! The frame of `ssbvb_pixel.ron` without its SSBVB: there the filter (a compute pass)
//! appends every pixel's hit and `SplatBillboards(mode: Pixel)` writes each at its pixel
//! (a compute step through 64-bit atomics, then a resolve over the touched tiles); here a
//! fragment shader marches its pixel ([`crate::kinds::ray_march_filter`]'s march,
//! `shaders/filter_march.inc.wgsl`) and writes the hit with its depth, stencil = voxel,
//! depth-tested against the triangles already drawn. Same values as that frame's; no
//! append, no per-pixel words to clear, no second pass over the hits. It pays where the
//! adapter's fragment work is as fast as its compute work (a CPU adapter:
//! docs/benchmarks.md); on GPUs whose fragment work is slow the compute forms stay
//! (`ssbvb calibrate` measures both).
//!
//! Per frame: `mark_tiles` (compute) flags the 16 × 16 tiles of the prepass with a proxy,
//! the flags are copied into a vertex buffer, and two triangles are drawn per flagged
//! tile (an unflagged one collapses): most of a frame's tiles have no proxy, and a software
//! adapter would run the march, masked, over every pixel of a fullscreen triangle. The
//! counters are the filter's (rays, steps, boxes, marches, lookup words, tiles), and the
//! fill count is the pixels written (the entries the pixel form's SSBVB would hold).
//!
//! A fragment shader cannot see group 0's page feedback (compute only), and WebGPU refuses
//! a draw or dispatch whose groups bind one buffer writable twice (Dawn checks every
//! group of the layout, whatever its stages), so under a GPU budget the fragment shader
//! sets page bits in the pass's own buffer (group 1, `page_feedback`) and `merge_feedback`
//! ORs them into the scene's after the draw. The prepass must be at the screen's size (one
//! ray per pixel): checked when recording.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{MarchMode, RayMarchGBufferParams};

use super::gbuffer::{begin_gbuffer_pass_timed, gbuffer_depth_stencil, gbuffer_targets};
use super::ray_march_filter::{COUNTER_WORDS, MainVariant, TILE, read_march_counters, tile_count};
use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::counters::FrameCounters;
use crate::runtime::node::{CounterSource, PassNode};
use crate::runtime::pipelines::{
    RenderSpec, VariantCache, compute_pipeline, pipeline_layout, render_pipeline,
};
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{KindNeeds, OwnBinding, OwnKind, PassImpl, PassInit};
use ssbvb_gpu::shaders;

use super::gbuffer::STENCIL_VOXEL;

/// What the pass binds itself: the counters and tile flags (`filter_words`), and its own
/// page feedback, merged into the scene's after the draw (see the WGSL).
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "filter_words",
        kind: OwnKind::StorageReadWrite,
    },
    OwnBinding {
        name: "page_feedback",
        kind: OwnKind::StorageReadWrite,
    },
];

/// The word counting the pixels written (`HITS_AT` in the WGSL): after the counters.
const HITS_AT: u64 = COUNTER_WORDS as u64;

/// The most workgroups `merge_feedback` is dispatched with (a dimension's limit in
/// WebGPU); its threads loop over the words beyond.
const MAX_GROUPS: u64 = 65_535;

/// The word where the tile flags start (`FLAGS_AT` in the WGSL): after the hits.
const FLAGS_AT: u64 = HITS_AT + 1;

/// The draw's vertex buffer: per tile (instance) its flag.
const TILE_VERTICES: [wgpu::VertexBufferLayout<'static>; 1] = [wgpu::VertexBufferLayout {
    array_stride: 4,
    step_mode: wgpu::VertexStepMode::Instance,
    attributes: &[wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Uint32,
        offset: 0,
        shader_location: 0,
    }],
}];

/// The compiled pass.
pub struct RayMarchGBuffer {
    /// Flags the tiles with a proxy.
    mark_tiles: wgpu::ComputePipeline,
    /// ORs the pass's page feedback into the scene's.
    merge_feedback: wgpu::ComputePipeline,
    /// The pass's page feedback, the size of the scene's.
    feedback: Option<wgpu::Buffer>,
    /// The march and its G-buffer writes, one pipeline per variant a frame has needed.
    draws: VariantCache<MainVariant, wgpu::RenderPipeline>,
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    targets: [Option<wgpu::ColorTargetState>; 4],
    depth_stencil: wgpu::DepthStencilState,
    /// The pass's own overrides (from its parameters).
    constants: [(&'static str, f64); 4],
    label: String,
    bindings: PassBindings,
    /// The counters and tile flags, and the flags' vertex buffer, for this many tiles.
    words: Option<(wgpu::Buffer, wgpu::Buffer, u64)>,
    /// Whether the last recorded frame counted.
    counted: bool,
}

impl PassImpl for RayMarchGBuffer {
    type Params = RayMarchGBufferParams;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "ray_march_gbuffer.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    // A fragment shader that writes its counters and the page feedback.
    const NEEDS: KindNeeds = KindNeeds::new(
        wgpu::DownlevelFlags::COMPUTE_SHADERS.union(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE),
        2,
    );

    /// Compiles `mark_tiles`; the draw is compiled per [`MainVariant`] when a frame first
    /// needs it. `max_steps` becomes `MAX_STEPS`, `march: Fast` `FAST_MARCH`.
    fn new(init: &PassInit<'_>, params: &RayMarchGBufferParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let module = ctx.shader(
            Self::SHADER,
            &shaders::source_for(Self::SHADER, &scene.bindings)?,
        )?;
        let constants = [
            ("MAX_STEPS", f64::from(params.max_steps)),
            ("FAST_MARCH", f64::from(u8::from(params.march == MarchMode::Fast))),
            ("HITS_AT", HITS_AT as f64),
            ("FLAGS_AT", FLAGS_AT as f64),
        ];
        let label = format!("pass `{}`: ray_march_gbuffer pipelines", pass.name);
        let (mark_tiles, merge_feedback, layout, bindings) = ctx.validated(&label, |d| {
            let bindings = PassBindings::new(ctx, pipeline, pass, OWN);
            let layout = pipeline_layout(d, &label, scene, Some(&bindings));
            let mark = compute_pipeline(d, &layout, &module, "mark_tiles", &constants);
            let merge = compute_pipeline(d, &layout, &module, "merge_feedback", &constants);
            (mark, merge, layout, bindings)
        })?;
        let mut this = Self {
            mark_tiles,
            merge_feedback,
            feedback: None,
            draws: VariantCache::default(),
            module,
            layout,
            targets: gbuffer_targets(ctx, pipeline, pass),
            depth_stencil: gbuffer_depth_stencil(ctx, pipeline, pass),
            constants,
            label,
            bindings,
            words: None,
            counted: false,
        };
        // The variant the first frame most likely needs (uncounted, the scene's instance
        // count), so that a pipeline that does not compile fails here, not at that frame.
        this.draw(ctx, MainVariant {
            count_work: false,
            several_instances: scene.scene.voxel_instances() > 1,
            paged: scene.streaming.is_some(),
        })?;
        Ok(this)
    }
}

impl RayMarchGBuffer {
    /// The draw's pipeline for `variant`, compiled when first needed.
    fn draw(
        &mut self,
        ctx: &GpuContext,
        variant: MainVariant,
    ) -> Result<&wgpu::RenderPipeline, PassError> {
        let (module, layout, targets) = (&self.module, &self.layout, &self.targets);
        let (own_constants, depth_stencil) = (&self.constants, &self.depth_stencil);
        let label = format!("{} ({variant:?})", self.label);
        self.draws.get_or_build(variant, || {
            let mut constants = own_constants.to_vec();
            constants.extend(variant.constants());
            ctx.validated(&label, |d| {
                render_pipeline(
                    d,
                    &RenderSpec {
                        constants: &constants,
                        depth_stencil: Some(depth_stencil.clone()),
                        buffers: &[Some(TILE_VERTICES[0].clone())],
                        ..RenderSpec::new(&label, module, layout, targets)
                    },
                )
            })
            .map_err(PassError::from)
        })
    }

    /// The counters and flags for `tiles` tiles, and the flags' vertex buffer (made again
    /// when the tile count changes).
    fn buffers(&mut self, ctx: &GpuContext, tiles: u64) -> Result<(), PassError> {
        if self.words.as_ref().is_some_and(|w| w.2 == tiles) {
            return Ok(());
        }
        let words = ctx.checked_buffer(&wgpu::BufferDescriptor {
            label: Some("ray_march_gbuffer words"),
            size: (FLAGS_AT + tiles) * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })?;
        let flags = ctx.checked_buffer(&wgpu::BufferDescriptor {
            label: Some("ray_march_gbuffer tiles"),
            size: (tiles * 4).max(4),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })?;
        self.words = Some((words, flags, tiles));
        Ok(())
    }

    /// The pass's page feedback, made again when the scene's changes size.
    fn feedback(&mut self, ctx: &GpuContext, scene_feedback: &wgpu::Buffer) -> Result<(), PassError> {
        let size = scene_feedback.size();
        if self.feedback.as_ref().is_none_or(|b| b.size() != size) {
            self.feedback = Some(ctx.checked_buffer(&wgpu::BufferDescriptor {
                label: Some("ray_march_gbuffer page feedback"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })?);
        }
        Ok(())
    }
}

impl PassNode for RayMarchGBuffer {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let entry = &rec.texture("entry").texture;
        let (w, h) = (entry.width(), entry.height());
        if (w, h) != rec.screen {
            return Err(PassError::Unsupported(format!(
                "pass `{}` (RayMarchGBuffer) casts one ray per pixel: its `entry` is {w}x{h}, \
                 the screen {}x{}; declare `entry` with `size: Screen`",
                rec.pass.name, rec.screen.0, rec.screen.1
            )));
        }
        let tiles = tile_count(w, h);
        self.buffers(rec.gpu, tiles)?;
        self.counted = rec.counting;
        let variant = MainVariant {
            count_work: self.counted,
            several_instances: rec.scene.visible.len() > 1,
            paged: rec.scene.streaming.is_some(),
        };
        self.draw(rec.gpu, variant)?;
        self.feedback(rec.gpu, rec.scene.page_feedback())?;
        let (words, flags, _) = self.words.as_ref().expect("made above");
        let feedback = self.feedback.as_ref().expect("made above");
        let bind_group = self.bindings.bind_group(
            rec,
            &[
                ("filter_words", words.as_entire_binding()),
                ("page_feedback", feedback.as_entire_binding()),
            ],
        )?;
        let from = if self.counted { 0 } else { FLAGS_AT * 4 };
        encoder.clear_buffer(words, from, None);
        if variant.paged {
            encoder.clear_buffer(feedback, 0, None);
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&rec.pass.name),
                // The pass's time spans the flags and the draw.
                timestamp_writes: rec.span_begin_timestamps(),
            });
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, &bind_group, &[]);
            pass.set_pipeline(&self.mark_tiles);
            pass.dispatch_workgroups(w.div_ceil(TILE), h.div_ceil(TILE), 1);
        }
        encoder.copy_buffer_to_buffer(words, FLAGS_AT * 4, flags, 0, tiles * 4);
        let draw = self.draws.get(variant).expect("compiled above");
        {
            let mut pass =
                begin_gbuffer_pass_timed(encoder, rec, STENCIL_VOXEL, rec.span_end_timestamps());
            pass.set_pipeline(draw);
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, &bind_group, &[]);
            pass.set_vertex_buffer(0, flags.slice(..));
            // Six vertices (two triangles) per tile; unflagged tiles collapse (see the WGSL).
            pass.draw(0..6, 0..tiles as u32);
        }
        if variant.paged {
            // After the pass's timed span: a dispatch over the feedback words (tiny).
            let groups = (feedback.size() / 4).div_ceil(64).min(MAX_GROUPS);
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("ray_march_gbuffer merge_feedback"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, &bind_group, &[]);
            pass.set_pipeline(&self.merge_feedback);
            pass.dispatch_workgroups(groups as u32, 1, 1);
        }
        Ok(())
    }

    /// The pixels the march wrote (what the SSBVB of the pixel form would hold), in a
    /// counted frame.
    fn fill_count(&self, frame: &CounterSource<'_>) -> Result<Option<u32>, PassError> {
        let Some((words, _, _)) = self.words.as_ref().filter(|_| self.counted) else {
            return Ok(None);
        };
        let hits = ssbvb_gpu::kernels::read_words(frame.gpu, words, HITS_AT, 1)?;
        Ok(hits.first().copied())
    }

    fn counters(&self, frame: &CounterSource<'_>, out: &mut FrameCounters) -> Result<(), PassError> {
        if !self.counted {
            return Ok(());
        }
        let Some((words, _, tiles)) = &self.words else {
            return Ok(());
        };
        read_march_counters(frame.gpu, words, out)?;
        let flags = ssbvb_gpu::kernels::read_words(frame.gpu, words, FLAGS_AT, *tiles)?;
        out.filter_tiles = Some(flags.iter().filter(|&&f| f != 0).count() as u64);
        Ok(())
    }
}
