//! `temporal`: temporal anti-aliasing (see `shaders/temporal.wgsl`). The renderer jitters
//! each frame of a pipeline with this pass by a sub-pixel offset ([`jitter`]); the pass
//! keeps the previous output (premultiplied, `Rgba16Float`) in two textures it owns, read
//! one and write the other, and the previous frame's camera to reproject it. It draws with
//! one of two pipelines a frame: a still camera's (no reprojection) or a moving one's.

use bytemuck::{Pod, Zeroable};
use ssbvb_gpu::shaders;
use ssbvb_gpu::wgpu;
use ssbvb_graph::TemporalParams;
use ssbvb_voxel::camera::Camera;

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::node::PassNode;
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::runtime::registry::{OwnBinding, OwnKind, PassImpl, PassInit};
use crate::runtime::resources::render_target;

// The renderer jitters the frames this pass averages; the sequence is the runtime's.
pub use crate::runtime::jitter::{JITTER_PERIOD, jitter};

/// What the pass binds itself: its constants, the history it reads and the history's
/// bilinear sampler (the cubic filter's taps).
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "taa",
        kind: OwnKind::Uniform,
    },
    OwnBinding {
        name: "history",
        kind: OwnKind::Texture2dFloat,
    },
    OwnBinding {
        name: "history_sampler",
        kind: OwnKind::Sampler(wgpu::SamplerBindingType::Filtering),
    },
];

/// `Taa` in `temporal.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TaaUniform {
    prev_view_proj: [[f32; 4]; 4],
    /// xyz: this frame's camera minus the previous one's; w: the current frame's weight.
    delta: [f32; 4],
    /// x: the current frame's least weight where the history moved by a pixel or more.
    motion: [f32; 4],
}

const HISTORY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Per pixel, whether its history was rejected (1) or used (0): read back for the quality
/// preset's `history_rejected_share`.
const REJECTED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

/// The temporal pass.
pub struct Temporal {
    /// For a still camera (each pixel's history is its own texel) and a moving one.
    still: wgpu::RenderPipeline,
    moving: wgpu::RenderPipeline,
    bindings: PassBindings,
    params: TemporalParams,
    uniform: wgpu::Buffer,
    sampler: wgpu::Sampler,
    /// The two history textures and their size; `read` is the one holding the last output.
    history: Option<([wgpu::TextureView; 2], (u32, u32))>,
    /// The last frame's rejection mask (same size as the history).
    rejected: Option<wgpu::Texture>,
    read: usize,
    /// Frames blended since the last reset.
    frames: u32,
    previous: Option<Camera>,
}

impl PassImpl for Temporal {
    type Params = TemporalParams;
    const SHADER: &'static str = "temporal.wgsl";
    const OWN: &'static [OwnBinding] = OWN;

    fn new(init: &PassInit<'_>, params: &TemporalParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let d = &ctx.device;
        let module = ctx.shader(Self::SHADER, &shaders::source_for(Self::SHADER, &scene.bindings)?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, OWN);
        let layout = pipeline_layout(d, Self::SHADER, scene, Some(&bindings));
        let out = slot_format(ctx, pipeline, pass, "color");
        // 8-bit targets without hardware sRGB hold encoded values.
        let encoded = matches!(
            out,
            wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Bgra8Unorm
        );
        let flag = |on: bool| if on { 1.0 } else { 0.0 };
        let targets = [
            Some(out.into()),
            Some(HISTORY_FORMAT.into()),
            Some(REJECTED_FORMAT.into()),
        ];
        let pipeline = |moving: bool| {
            let constants = [
                ("ENCODED", flag(encoded)),
                ("DILATE", flag(params.dilate)),
                ("UNJITTER", flag(params.unjitter)),
                ("MOVING", flag(moving)),
            ];
            render_pipeline(
                d,
                &RenderSpec {
                    constants: &constants,
                    ..RenderSpec::new(Self::SHADER, &module, &layout, &targets)
                },
            )
        };
        let uniform = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("temporal constants"),
            size: std::mem::size_of::<TaaUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = d.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("temporal history"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            still: pipeline(false),
            moving: pipeline(true),
            bindings,
            params: *params,
            uniform,
            sampler,
            history: None,
            rejected: None,
            read: 0,
            frames: 0,
            previous: None,
        })
    }
}

impl Temporal {
    /// Whether the move from `prev` to `now` is a cut (the history is dropped).
    fn is_cut(&self, prev: &Camera, now: &Camera) -> bool {
        let reach = (now.position - now.look_at).length().max(1e-9);
        prev.fov_y_deg != now.fov_y_deg
            || (now.position - prev.position).length() > self.params.cut as f64 * reach
    }

    /// The history textures for `size`, made (and the history reset) when it changed.
    fn history_for(&mut self, device: &wgpu::Device, size: (u32, u32)) {
        if self.history.as_ref().is_some_and(|(_, s)| *s == size) {
            return;
        }
        let texture = |label, format, usage| render_target(device, label, size, format, usage);
        let history = || {
            texture(
                "temporal history",
                HISTORY_FORMAT,
                wgpu::TextureUsages::TEXTURE_BINDING,
            )
            .create_view(&Default::default())
        };
        self.history = Some(([history(), history()], size));
        self.rejected = Some(texture(
            "temporal rejection mask",
            REJECTED_FORMAT,
            wgpu::TextureUsages::COPY_SRC,
        ));
        self.frames = 0;
    }
}

impl PassNode for Temporal {
    /// Every frame jittered, and Auto LOD `lod_bias` levels finer (the jittered positions
    /// sample a pixel 4 × 4).
    fn jittered_lod_bias(&self) -> Option<u32> {
        Some(self.params.lod_bias)
    }

    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let t = rec.texture("color").texture.size();
        self.history_for(&rec.gpu.device, (t.width, t.height));
        let now = rec.scene.camera;
        let prev = match self.previous {
            Some(p) if !self.is_cut(&p, &now) => p,
            _ => {
                self.frames = 0;
                now
            }
        };
        let weight = if self.frames == 0 {
            1.0
        } else {
            (1.0 / (self.frames + 1) as f32).max(self.params.blend)
        };
        let screen = (t.width, t.height);
        let prev_frame = ssbvb_gpu::scene::frame_uniform(&prev, screen, &Default::default());
        let delta = now.position - prev.position;
        let constants = TaaUniform {
            prev_view_proj: prev_frame.view_proj,
            delta: [delta.x as f32, delta.y as f32, delta.z as f32, weight],
            motion: [
                weight.max(self.params.motion_blend),
                self.params.variance_clip,
                0.0,
                0.0,
            ],
        };
        // A still frame's reprojection is the identity.
        let pipeline = if prev == now {
            &self.still
        } else {
            &self.moving
        };
        rec.gpu
            .queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&constants));
        let (views, _) = self.history.as_ref().expect("made above");
        let (read, write) = (&views[self.read], &views[1 - self.read]);
        let bg = self.bindings.bind_group(
            rec,
            &[
                ("taa", self.uniform.as_entire_binding()),
                ("history", wgpu::BindingResource::TextureView(read)),
                (
                    "history_sampler",
                    wgpu::BindingResource::Sampler(&self.sampler),
                ),
            ],
        )?;
        let history_out = wgpu::RenderPassColorAttachment {
            view: write,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        };
        let mask = self
            .rejected
            .as_ref()
            .expect("made with the history")
            .create_view(&Default::default());
        let rejected_out = wgpu::RenderPassColorAttachment {
            view: &mask,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        };
        rec.draw_fullscreen(
            encoder,
            &[
                rec.color_attachment("color"),
                Some(history_out),
                Some(rejected_out),
            ],
            pipeline,
            &bg,
        );
        self.read = 1 - self.read;
        self.frames = self.frames.saturating_add(1);
        self.previous = Some(now);
        Ok(())
    }

    fn history_rejected_share(&self, gpu: &ssbvb_gpu::GpuContext) -> Result<Option<f64>, PassError> {
        let Some(mask) = &self.rejected else {
            return Ok(None);
        };
        let data = gpu
            .read_texture(mask, wgpu::TextureAspect::All)
            .map_err(PassError::Gpu)?;
        let rejected = data.bytes.iter().filter(|&&v| v >= 128).count();
        Ok(Some(rejected as f64 / data.bytes.len().max(1) as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_jitter_is_halton_2_3_centred_and_repeats() {
        assert_eq!(jitter(0), [0.0, 1.0 / 3.0 - 0.5]);
        assert_eq!(jitter(1), [-0.25, 2.0 / 3.0 - 0.5]);
        assert_eq!(jitter(2), [0.25, 1.0 / 9.0 - 0.5]);
        assert_eq!(jitter(JITTER_PERIOD), jitter(0));
        // Each period covers the pixel evenly: its mean is near the centre.
        let (mut x, mut y) = (0.0, 0.0);
        for i in 0..JITTER_PERIOD {
            let j = jitter(i);
            assert!(j.iter().all(|v| v.abs() < 0.5), "{j:?}");
            x += j[0];
            y += j[1];
        }
        let n = JITTER_PERIOD as f64;
        assert!((x / n).abs() < 0.05 && (y / n).abs() < 0.05, "{x} {y}");
    }
}
