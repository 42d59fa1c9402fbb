//! `splat_billboards`: the SSBVB's billboards splatted in compute (`SplatBillboards`;
//! `shaders/splat_billboards.wgsl`), the compute rasterization of Schütz, Kerbl and Wimmer
//! for adapters whose raster units are weak (a CPU adapter; data-centre GPUs such as the
//! H100/H200, which have little fixed-function raster). Same quads and the same pixel
//! shading as [`crate::kinds::billboards`] (`shaders/billboard_quad.inc.wgsl`), so the G-buffer is
//! the same and smoothing and composite run unchanged.
//!
//! Per frame: the per-pixel words are cleared; one thread turns the filter's entry count
//! into the splat's indirect dispatch arguments (no workgroup for an empty slot: the
//! SSBVB's capacity is the screen, its entries a fraction of it); the splat (one thread per
//! SSBVB entry, 64 per workgroup) offers every pixel its billboard covers the entry and
//! its reversed-Z depth, and keeps the nearest depth and, at equal depths, the lowest
//! entry (as the rasterizer's strict depth test keeps the first of equal-depth quads), and
//! marks the screen tiles (16 × 16 pixels) its quad's pixel range touches; the tiles'
//! words are copied into a vertex buffer, and the resolve draws two triangles per touched
//! tile (an untouched one collapses), writing the winning billboard's fragment with its
//! depth, depth-tested against what is already in the G-buffer (the triangles), stencil =
//! voxel, from the winner's quad depth that the splat kept per entry (rebuilding the quad
//! at every pixel cost the resolve most of its time; a resolve over the whole screen cost
//! as much again for pixels without a quad).
//!
//! Two forms of the splat, the same winners (`shaders/splat_billboards.inc.wgsl` holds what
//! they share):
//!
//! - **One step** (`splat_billboards_wide.wgsl`), where the device has 64-bit atomics
//!   (`SHADER_INT64_ATOMIC_ALL_OPS`: lavapipe, and Vulkan and DX12 GPUs whose drivers
//!   report it): one `atomicMax` of (depth bits << 32 | inverted entry) per covered pixel.
//! - **Two steps** (`splat_billboards.wgsl`) elsewhere (GL, Metal, WebGPU, a device made
//!   with WebGPU's defaults): a first dispatch takes each pixel's nearest depth by
//!   `atomicMax` on its bits, a second dispatch of the same pipeline keeps the lowest entry
//!   where that depth is its own: core 32-bit atomics only, at the price of a second walk
//!   of each quad. One compiled shader for both steps, so that the depths they compute
//!   agree bit for bit.
//!
//! A thread walks its quad's pixel rectangle: cheap for one billboard per visible voxel,
//! costly where quads are large and many (the per-pixel Flat frame seen from up close, as
//! for the rasterizer). In `mode: Pixel` there is no quad: the filter appends every pixel,
//! and each entry is splatted at its own pixel with its ray's hit (the pipeline check
//! makes sure the filter does append every pixel, at the screen's resolution), which the
//! resolve writes as the ray casters' resolve writes theirs.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{BillboardMode, SplatBillboardsParams};

use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::{PulledPipeline, Specialized};
use crate::runtime::bindings::PassBindings;
use crate::runtime::pipelines::pipeline_layout;
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;

/// What the splat binds itself: per pixel the nearest depth's bits and the winning entry
/// (two 32-bit words, or one 64-bit word), then per SSBVB entry its quad's view depth, in
/// one buffer (the pass then
/// fits WebGPU's 8 storage buffers per stage); and the splat steps' indirect dispatch
/// arguments, which only `args_main` binds (a dispatch may not bind the buffer it reads
/// its arguments from).
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "splat_pixels",
        kind: OwnKind::StorageReadWrite,
    },
    OwnBinding {
        name: "splat_dispatch",
        kind: OwnKind::StorageReadWrite,
    },
];

/// Group-1 bindings of the splat steps and the resolve: the SSBVB, its entry count and
/// the per-pixel words.
const SPLAT_BINDINGS: [u32; 3] = [0, 1, 2];
/// Group-1 bindings of `args_main`: the SSBVB, its entry count and the arguments.
const ARGS_BINDINGS: [u32; 3] = [0, 1, 3];

/// Bytes of the dispatch arguments: two grids of three `u32`.
const DISPATCH_BYTES: u64 = 24;

/// The one-step form's file.
const WIDE_SHADER: &str = "splat_billboards_wide.wgsl";

/// Pixels per side of the resolve's tiles (WGSL override `TILE_PX`).
const TILE_PX: u32 = 16;

/// The resolve's vertex buffer: per tile (instance) the pair of words the splat marks.
const TILE_VERTICES: [Option<wgpu::VertexBufferLayout<'static>>; 1] =
    [Some(wgpu::VertexBufferLayout {
        array_stride: 8,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &[wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Uint32x2,
            offset: 0,
            shader_location: 0,
        }],
    })];

/// Resolve tiles of a `w` × `h` screen.
fn tile_count(w: u32, h: u32) -> u64 {
    u64::from(w.div_ceil(TILE_PX)) * u64::from(h.div_ceil(TILE_PX))
}

/// Whether the device can run the one-step form (64-bit atomics).
pub fn has_wide_atomics(ctx: &GpuContext) -> bool {
    ctx.has(wgpu::Features::SHADER_INT64) && ctx.has(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS)
}

/// The compiled splat: the arguments, the splat steps and the resolve.
pub struct SplatBillboards {
    /// Writes the splat steps' indirect dispatch arguments.
    args: wgpu::ComputePipeline,
    args_bindings: PassBindings,
    /// The splat: the one step, or both steps (dispatched with one, then two layers of
    /// workgroups).
    splat: wgpu::ComputePipeline,
    /// Whether it is the one-step form (64-bit words).
    one_step: bool,
    resolve: PulledPipeline,
    /// The splat steps' indirect dispatch arguments.
    dispatch: wgpu::Buffer,
    /// The per-pixel words (depth bits, entry), then one per entry (its quad's depth),
    /// then two per resolve tile (touched or not), and how many 32-bit words that is.
    pixels: Option<(wgpu::Buffer, u64)>,
    /// The tiles' words, copied from the splat's for the resolve's vertex buffer.
    tiles: Option<wgpu::Buffer>,
}

impl PassImpl for SplatBillboards {
    type Params = SplatBillboardsParams;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "splat_billboards.wgsl";
    const VARIANTS: &'static [&'static str] = &[WIDE_SHADER];
    const OWN: &'static [OwnBinding] = OWN;
    // Compute splats dispatched indirectly, and a fragment shader that reads the atomics
    // they wrote.
    const NEEDS: KindNeeds = KindNeeds::new(
        wgpu::DownlevelFlags::COMPUTE_SHADERS
            .union(wgpu::DownlevelFlags::INDIRECT_EXECUTION)
            .union(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE),
        3,
    );

    /// Compiles the splat and the resolve; `mode` becomes the WGSL overrides `RAY_BOX` and
    /// `PIXEL`.
    fn new(init: &PassInit<'_>, params: &SplatBillboardsParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let constants = [
            ("SIZE_SCALE", f64::from(params.size_scale)),
            ("CULL_COS", f64::from(crate::kinds::billboards::DEFAULT_CULL_COS)),
            ("BOX_FOOTPRINT", 1.0),
            ("TILE_PX", f64::from(TILE_PX)),
            (
                "RAY_BOX",
                f64::from(u8::from(params.mode == BillboardMode::RayBox)),
            ),
            (
                "PIXEL",
                f64::from(u8::from(params.mode == BillboardMode::Pixel)),
            ),
        ];
        let one_step = has_wide_atomics(ctx);
        let shader = if one_step { WIDE_SHADER } else { Self::SHADER };
        let special = Specialized {
            file: shader,
            buffers: &TILE_VERTICES,
            source: ssbvb_gpu::shaders::source_for(shader, &scene.bindings)?,
            used: SPLAT_BINDINGS.to_vec(),
        };
        let resolve = PulledPipeline::with_fragment_for::<Self>(init, &constants, "fs_main", &special)?;
        let module = ctx.shader(shader, &special.source)?;
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
        let args_bindings = PassBindings::used_only(ctx, pipeline, pass, OWN, Some(&ARGS_BINDINGS));
        let args = ctx.validated(&label, |d| {
            d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("args_main"),
                layout: Some(&pipeline_layout(d, &label, scene, Some(&args_bindings))),
                module: &module,
                entry_point: Some("args_main"),
                compilation_options: Default::default(),
                cache: None,
            })
        })?;
        let dispatch = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("splat dispatch arguments"),
            size: DISPATCH_BYTES,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        Ok(Self {
            args,
            args_bindings,
            splat,
            one_step,
            resolve,
            dispatch,
            pixels: None,
            tiles: None,
        })
    }
}

impl SplatBillboards {
    /// Makes the words for `pixels` pixels (two each), `entries` SSBVB entries (one each,
    /// two in the one-step form's 64-bit words) and `tiles` resolve tiles (two each) unless
    /// they exist at that size, and the tiles' vertex buffer; out of memory is an error
    /// (12 or 16 bytes a pixel: 100 or 133 MB at 4K). Returns the byte offset of the tiles'
    /// words.
    fn buffers(
        &mut self,
        ctx: &GpuContext,
        pixels: u64,
        entries: u64,
        tiles: u64,
    ) -> Result<u64, PassError> {
        let per_entry = if self.one_step { 2 } else { 1 };
        let tiles_at = 2 * pixels + per_entry * entries;
        let words = tiles_at + 2 * tiles;
        if self.pixels.as_ref().is_none_or(|p| p.1 != words) {
            let buffer = ctx.checked_buffer(&wgpu::BufferDescriptor {
                label: Some("splat pixels"),
                size: (words * 4).max(16),
                // COPY_SRC: the tiles' words go to the resolve's vertex buffer.
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })?;
            self.pixels = Some((buffer, words));
            self.tiles = Some(ctx.checked_buffer(&wgpu::BufferDescriptor {
                label: Some("splat resolve tiles"),
                size: 8 * tiles,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })?);
        }
        Ok(4 * tiles_at)
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
        let tiles = tile_count(w, h);
        let tiles_at = self.buffers(rec.gpu, w as u64 * h as u64, entries, tiles)?;
        let (words, _) = self.pixels.as_ref().expect("made above");
        let tile_words = self.tiles.as_ref().expect("made above");
        let bind_group = self
            .resolve
            .bindings
            .bind_group(rec, &[("splat_pixels", words.as_entire_binding())])?;
        let args_group = self
            .args_bindings
            .bind_group(rec, &[("splat_dispatch", self.dispatch.as_entire_binding())])?;
        encoder.clear_buffer(words, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&rec.pass.name),
                // The pass's time spans the splats and the resolve.
                timestamp_writes: rec.span_begin_timestamps(),
            });
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, &args_group, &[]);
            pass.set_pipeline(&self.args);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_bind_group(1, &bind_group, &[]);
            // wgpu orders the dispatches: the arguments are in before the splat reads them,
            // and in the two-step form every depth before entries are chosen. One pipeline
            // for both steps (see the WGSL): z = 1 is the first, z = 2 the second.
            pass.set_pipeline(&self.splat);
            pass.dispatch_workgroups_indirect(&self.dispatch, 0);
            if !self.one_step {
                pass.dispatch_workgroups_indirect(&self.dispatch, DISPATCH_BYTES / 2);
            }
        }
        encoder.copy_buffer_to_buffer(words, tiles_at, tile_words, 0, 8 * tiles);
        // Six vertices (two triangles) per tile; untouched tiles collapse (see the WGSL).
        self.resolve.record_resolve_instanced(
            encoder,
            rec,
            &bind_group,
            tile_words,
            0..6,
            0..tiles as u32,
        );
        Ok(())
    }
}
