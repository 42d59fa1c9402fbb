//! The G-buffer every geometry pass writes (billboards, triangles and the baselines):
//! attachments, formats, stencil values, how a writer begins its render pass, and the
//! octahedral encoding of the geometric normal.
//!
//! | location | slot                       | format        | contents                                               |
//! |----------|----------------------------|---------------|--------------------------------------------------------|
//! | 0        | `gbuffer_albedo`           | `R32Uint`     | linear RGBA8 albedo packed (`pack4x8unorm`), alpha 1 where something was drawn |
//! | 1        | `gbuffer_normal`           | `Rgba16Float` | shading normal: world-space unit, w = 1                |
//! | 2        | `gbuffer_position`         | `Rgba32Float` | camera-relative world position, w = linear depth       |
//! | 3        | `gbuffer_geometric_normal` | `Rg16Float`   | geometric normal, octahedral ([`oct_decode`])          |
//! | depth    | `depth_stencil`            | `Depth32FloatStencil8` (else `Depth24PlusStencil8`) | reversed-Z depth, stencil 1 voxel / 2 triangle |
//!
//! **One meaning per normal, for every technique.** The *shading* normal is what lighting
//! uses: a voxel's stored (smooth) normal, whichever technique found the voxel, and a
//! triangle's interpolated vertex normal; the CPU reference shades with the same, so image
//! errors compare like with like. The *geometric* normal is the surface actually hit: the
//! entered face of the voxel's box (the reference's `Hit::face_normal`; for a Flat
//! billboard the face the pixel's ray enters, or would enter, by the same slab rule) and
//! a triangle's plane, turned towards the camera; geometric accuracy is measured on it.
//! The four colour attachments take 4 + 8 + 16 + 4 = 32 bytes per sample, WebGPU's default
//! limit: hence the two-channel encoding (axis-aligned face normals encode exactly) and the
//! packed albedo (WebGPU counts an `Rgba8Unorm` attachment as 8 bytes). Its bytes read back
//! as RGBA8 all the same.
//!
//! Linear depth is the distance along the camera's forward axis (the reference's
//! `view_depth`). The first pass of the frame that writes a slot clears it (colours to 0,
//! depth to 0 = infinitely far in reversed Z, stencil to 0); later ones load. Depth is tested
//! with `Greater` and written.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{ResolvedPipeline, ScheduledPass};

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::runtime::registry::{PassImpl, PassInit};
use crate::runtime::resources::render_target;
use ssbvb_gpu::shaders;

/// Stencil value of voxel pixels (`STENCIL_VOXEL` in common.inc.wgsl).
pub const STENCIL_VOXEL: u32 = 1;

/// Stencil value of triangle pixels (`STENCIL_TRIANGLE` in common.inc.wgsl).
pub const STENCIL_TRIANGLE: u32 = 2;

/// The colour slots of the G-buffer, in location order.
pub const GBUFFER_COLOR_SLOTS: [&str; 4] = [
    "gbuffer_albedo",
    "gbuffer_normal",
    "gbuffer_position",
    "gbuffer_geometric_normal",
];

/// Colour target states of the G-buffer (locations 0..3) with the formats bound to `pass`.
pub(crate) fn gbuffer_targets(
    ctx: &GpuContext,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
) -> [Option<wgpu::ColorTargetState>; 4] {
    GBUFFER_COLOR_SLOTS.map(|s| Some(slot_format(ctx, pipeline, pass, s).into()))
}

/// Depth `Greater` with write; stencil always passes and replaces with the reference.
pub(crate) fn gbuffer_depth_stencil(
    ctx: &GpuContext,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
) -> wgpu::DepthStencilState {
    let face = wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: wgpu::StencilOperation::Replace,
    };
    wgpu::DepthStencilState {
        format: slot_format(ctx, pipeline, pass, "depth_stencil"),
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Greater),
        stencil: wgpu::StencilState {
            front: face,
            back: face,
            read_mask: 0xff,
            write_mask: 0xff,
        },
        bias: Default::default(),
    }
}

/// Begins a render pass on the G-buffer slots of `rec.pass` (clearing the slots this pass
/// writes first in the frame) with `stencil` as the stencil reference.
pub(crate) fn begin_gbuffer_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    rec: &Recorder<'_>,
    stencil: u32,
) -> wgpu::RenderPass<'e> {
    begin_gbuffer_pass_timed(encoder, rec, stencil, rec.render_timestamps())
}

/// [`begin_gbuffer_pass`] with the given timestamp writes (a pass whose time began in an
/// earlier compute pass ends it here: [`Recorder::span_end_timestamps`]).
pub(crate) fn begin_gbuffer_pass_timed<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    rec: &Recorder<'_>,
    stencil: u32,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
) -> wgpu::RenderPass<'e> {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(&rec.pass.name),
        color_attachments: &GBUFFER_COLOR_SLOTS.map(|s| rec.color_attachment(s)),
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &rec.texture("depth_stencil").view,
            depth_ops: Some(wgpu::Operations {
                load: rec.load_op("depth_stencil", 0.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: Some(wgpu::Operations {
                load: rec.load_op("depth_stencil", 0),
                store: wgpu::StoreOp::Store,
            }),
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_stencil_reference(stencil);
    pass
}

/// A pass's shader specialized for its data: the WGSL text, and the group-1 bindings its
/// pipelines read (the layout holds only those).
pub(crate) struct Specialized {
    /// The WGSL file it comes from (the pass's own or one of its variants), for errors.
    pub file: &'static str,
    /// The vertex buffers `vs_main` reads (none: it pulls its vertices).
    pub buffers: &'static [Option<wgpu::VertexBufferLayout<'static>>],
    /// The WGSL, includes expanded.
    pub source: String,
    /// Group-1 bindings in the layout.
    pub used: Vec<u32>,
}

/// The compiled pipeline of a G-buffer writer that pulls its own vertices (`vs_main`, no
/// vertex buffers) and writes the G-buffer in `fs_main`: the ray-casting baselines and the
/// cube rasterizer. Group 1 holds only the pass's own resources.
pub(crate) struct PulledPipeline {
    /// The render pipeline.
    pub pipeline: wgpu::RenderPipeline,
    /// The same with the WGSL override `COUNT_WORK` off, for frames that count nothing
    /// (ray casters: [`PulledPipeline::counting`]).
    pub uncounted: Option<wgpu::RenderPipeline>,
    /// Its group-1 layout (own bindings).
    pub bindings: PassBindings,
}

impl PulledPipeline {
    /// Compiles pass `P`'s shader for the formats bound to `init.pass`, with `constants`
    /// as WGSL overrides and `P`'s own bindings as group 1.
    pub fn new<P: PassImpl>(
        init: &PassInit<'_>,
        constants: &[(&str, f64)],
    ) -> Result<Self, PassError> {
        Self::build::<P>(init, constants, false, "fs_main", None)
    }

    /// [`PulledPipeline::new`] of a specialized shader with fragment entry point
    /// `fs_entry` (a resolve of work an earlier compute pass did:
    /// [`PulledPipeline::record_resolve`]).
    pub fn with_fragment_for<P: PassImpl>(
        init: &PassInit<'_>,
        constants: &[(&str, f64)],
        fs_entry: &str,
        special: &Specialized,
    ) -> Result<Self, PassError> {
        Self::build::<P>(init, constants, false, fs_entry, Some(special))
    }

    /// [`PulledPipeline::counting`] for a specialized shader.
    pub fn counting_for<P: PassImpl>(
        init: &PassInit<'_>,
        constants: &[(&str, f64)],
        special: &Specialized,
    ) -> Result<Self, PassError> {
        Self::build::<P>(init, constants, true, "fs_main", Some(special))
    }

    /// [`PulledPipeline::new`] for a shader that counts its work under the WGSL override
    /// `COUNT_WORK`: also compiled with it off, the variant frames that count nothing draw
    /// with (`Recorder::counting`).
    pub fn counting<P: PassImpl>(
        init: &PassInit<'_>,
        constants: &[(&str, f64)],
    ) -> Result<Self, PassError> {
        Self::build::<P>(init, constants, true, "fs_main", None)
    }

    fn build<P: PassImpl>(
        init: &PassInit<'_>,
        constants: &[(&str, f64)],
        with_uncounted: bool,
        fs_entry: &str,
        special: Option<&Specialized>,
    ) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let (shader, own) = (special.map_or(P::SHADER, |s| s.file), P::OWN);
        let module = match special {
            Some(s) => ctx.shader(shader, &s.source)?,
            None => ctx.shader(shader, &shaders::source_for(shader, &scene.bindings)?)?,
        };
        let targets = gbuffer_targets(ctx, pipeline, pass);
        let depth_stencil = gbuffer_depth_stencil(ctx, pipeline, pass);
        let label = format!("pass `{}`: {shader} pipeline", pass.name);
        Ok(ctx.validated(&label, |d| {
            let used = special.map(|s| &s.used[..]);
            let bindings = PassBindings::used_only(ctx, pipeline, pass, own, used);
            let layout = pipeline_layout(d, &label, scene, Some(&bindings));
            let make = |constants: &[(&str, f64)]| {
                render_pipeline(
                    d,
                    &RenderSpec {
                        constants,
                        depth_stencil: Some(depth_stencil.clone()),
                        fs_entry,
                        buffers: special.map_or(&[][..], |s| s.buffers),
                        ..RenderSpec::new(&label, &module, &layout, &targets)
                    },
                )
            };
            let pipeline = make(constants);
            let uncounted = with_uncounted.then(|| {
                let mut off = constants.to_vec();
                off.push(("COUNT_WORK", 0.0));
                make(&off)
            });
            Self {
                pipeline,
                uncounted,
                bindings,
            }
        })?)
    }

    /// Records a ray-casting baseline's frame: the G-buffer pass begins in any case (its
    /// clears happen even when nothing is visible) and one fullscreen triangle is drawn
    /// when there is something to cast against (`bind_group`).
    pub fn record_fullscreen(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        bind_group: Option<&wgpu::BindGroup>,
    ) {
        self.draw_fullscreen(encoder, rec, bind_group, rec.render_timestamps());
    }

    /// [`PulledPipeline::record_fullscreen`] after the pass's compute work, whose compute
    /// pass began the pass's time ([`Recorder::span_begin_timestamps`]): this ends it.
    pub fn record_resolve(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        bind_group: Option<&wgpu::BindGroup>,
    ) {
        self.draw_fullscreen(encoder, rec, bind_group, rec.span_end_timestamps());
    }

    /// [`PulledPipeline::record_resolve`] drawing `vs_main`'s `vertices` for each of
    /// `instances`, with vertex buffer `vertex_buffer` (a resolve that draws only parts of
    /// the screen).
    pub fn record_resolve_instanced(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        bind_group: &wgpu::BindGroup,
        vertex_buffer: &wgpu::Buffer,
        vertices: std::ops::Range<u32>,
        instances: std::ops::Range<u32>,
    ) {
        let mut pass =
            begin_gbuffer_pass_timed(encoder, rec, STENCIL_VOXEL, rec.span_end_timestamps());
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, bind_group, &[]);
        pass.set_vertex_buffer(0, vertex_buffer.slice(..));
        pass.draw(vertices, instances);
    }

    fn draw_fullscreen(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        bind_group: Option<&wgpu::BindGroup>,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = begin_gbuffer_pass_timed(encoder, rec, STENCIL_VOXEL, timestamps);
        if let Some(bg) = bind_group {
            let pipeline = match &self.uncounted {
                Some(uncounted) if !rec.counting => uncounted,
                _ => &self.pipeline,
            };
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &rec.scene.bind_group, &[]);
            pass.set_bind_group(1, bg, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

/// Octahedral encoding of a unit vector into `[-1, 1]²` (the twin of `oct_encode` in
/// common.inc.wgsl): the vector is projected onto the octahedron |x| + |y| + |z| = 1 and
/// the lower half folded over the diagonals. Axis vectors map to 0 and ±1 exactly.
pub fn oct_encode(n: [f32; 3]) -> [f32; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return [0.0, 0.0];
    }
    let (x, y, z) = (n[0] / l1, n[1] / l1, n[2] / l1);
    if z >= 0.0 {
        [x, y]
    } else {
        [
            (1.0 - y.abs()) * sign_not_zero(x),
            (1.0 - x.abs()) * sign_not_zero(y),
        ]
    }
}

/// The unit vector of an octahedral code (inverse of [`oct_encode`]); `[0, 0, 0]` for a
/// non-finite code (a pixel nothing wrote holds 0, which decodes to +Z).
pub fn oct_decode(e: [f32; 2]) -> [f32; 3] {
    let [u, v] = e;
    if !(u.is_finite() && v.is_finite()) {
        return [0.0; 3];
    }
    let z = 1.0 - u.abs() - v.abs();
    let (x, y) = if z < 0.0 {
        (
            (1.0 - v.abs()) * sign_not_zero(u),
            (1.0 - u.abs()) * sign_not_zero(v),
        )
    } else {
        (u, v)
    };
    let l = (x * x + y * y + z * z).sqrt();
    [x / l, y / l, z / l]
}

fn sign_not_zero(x: f32) -> f32 {
    if x >= 0.0 { 1.0 } else { -1.0 }
}

/// A depth-stencil state that only tests the stencil against the reference with
/// `compare` (depth always passes; nothing is written).
pub fn stencil_test(
    format: wgpu::TextureFormat,
    compare: wgpu::CompareFunction,
) -> wgpu::DepthStencilState {
    let face = wgpu::StencilFaceState {
        compare,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: wgpu::StencilOperation::Keep,
    };
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: wgpu::StencilState {
            front: face,
            back: face,
            read_mask: 0xff,
            write_mask: 0,
        },
        bias: Default::default(),
    }
}

/// Pixels of a depth-stencil texture whose stencil is `value` (read back); `None` when the
/// texture has no stencil. A device that cannot copy a stencil to a buffer (GL) counts by
/// drawing ([`count_stencil_by_drawing`]).
pub fn count_stencil(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    value: u32,
) -> Result<Option<u64>, PassError> {
    if !texture.format().is_depth_stencil_format() {
        return Ok(None);
    }
    let copies = ctx
        .adapter
        .get_downlevel_capabilities()
        .flags
        .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
    if !copies {
        return count_stencil_by_drawing(ctx, texture, value).map(Some);
    }
    let stencil = ctx.read_texture(texture, wgpu::TextureAspect::StencilOnly)?;
    let value = value as u8;
    Ok(Some(
        stencil.bytes.iter().filter(|&&s| s == value).count() as u64
    ))
}

/// [`count_stencil`] without a stencil copy: a fullscreen triangle stencil-tested for
/// `value` writes 1 into an `R32Uint` texture (`shaders/stencil_count.wgsl`), which is read
/// back and summed. `texture` must be a depth-stencil texture that can be attached.
pub fn count_stencil_by_drawing(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    value: u32,
) -> Result<u64, PassError> {
    let d = &ctx.device;
    let module = ctx.shader(
        "stencil_count.wgsl",
        &shaders::source("stencil_count.wgsl")?,
    )?;
    let size = texture.size();
    let (target, pipeline) = ctx.validated("stencil count", |d| {
        let target = render_target(
            d,
            "stencil count",
            (size.width, size.height),
            wgpu::TextureFormat::R32Uint,
            wgpu::TextureUsages::COPY_SRC,
        );
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stencil count"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
        let targets = [Some(wgpu::TextureFormat::R32Uint.into())];
        let pipeline = render_pipeline(
            d,
            &RenderSpec {
                depth_stencil: Some(stencil_test(texture.format(), wgpu::CompareFunction::Equal)),
                ..RenderSpec::new("stencil count", &module, &layout, &targets)
            },
        );
        (target, pipeline)
    })?;
    let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("stencil count"),
    });
    {
        let view = target.create_view(&Default::default());
        let ds = texture.create_view(&Default::default());
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("stencil count"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &ds,
                depth_ops: None,
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_stencil_reference(value);
        pass.draw(0..3, 0..1);
    }
    ctx.submit("stencil count", [enc.finish()]);
    let counted = ctx.read_texture(&target, wgpu::TextureAspect::All)?;
    Ok(counted
        .bytes
        .chunks_exact(4)
        .map(|c| u64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])))
        .sum())
}

#[cfg(test)]
mod tests {
    use super::{oct_decode, oct_encode};

    /// Angle by atan2(|a × b|, a · b): exact near 0, where acos of a dot product of f32
    /// vectors is not (it reads ~0.03° for identical directions).
    fn angle_deg(a: [f32; 3], b: [f32; 3]) -> f64 {
        let (a, b) = (a.map(f64::from), b.map(f64::from));
        let c = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        (c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
            .sqrt()
            .atan2(d)
            .to_degrees()
    }

    /// Face normals, the normals a voxel technique writes most, survive exactly.
    #[test]
    fn axis_vectors_round_trip_exactly() {
        for axis in 0..3 {
            for s in [-1.0f32, 1.0] {
                let mut n = [0.0f32; 3];
                n[axis] = s;
                let e = oct_encode(n);
                assert!(
                    e.iter().all(|c| [-1.0, 0.0, 1.0].contains(c)),
                    "{n:?} -> {e:?}"
                );
                assert_eq!(oct_decode(e), n, "{n:?}");
            }
        }
    }

    /// Every direction of a dense Fibonacci sphere comes back within 0.001° in f32 and
    /// within 0.1° after rounding the code to f16 (what the Rg16Float target stores).
    #[test]
    fn sphere_round_trips_in_f32_and_f16() {
        let count = 2000;
        let mut worst = (0.0f64, 0.0f64);
        for i in 0..count {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = i as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
            let n = [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32];
            let e = oct_encode(n);
            let half = e.map(|c| half::f16::from_f32(c).to_f32());
            worst.0 = worst.0.max(angle_deg(oct_decode(e), n));
            worst.1 = worst.1.max(angle_deg(oct_decode(half), n));
        }
        assert!(worst.0 < 0.001 && worst.1 < 0.1, "{worst:?}");
        assert!(worst.1 > 0.0, "f16 rounding must lose something: {worst:?}");
    }

    #[test]
    fn unwritten_and_non_finite_codes() {
        assert_eq!(oct_decode([0.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(oct_decode([f32::NAN, 0.0]), [0.0; 3]);
        assert_eq!(oct_encode([0.0; 3]), [0.0, 0.0]);
    }
}
