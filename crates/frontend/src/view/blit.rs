//! Copies the renderer's output onto the window surface (`shaders/view_blit.wgsl`).
//!
//! The output texture is only a render attachment (its usage comes from the pipeline
//! graph), so each frame it is first copied into a sampled texture owned here; then a
//! fullscreen triangle loads it texel for texel into the surface, encoding sRGB in the
//! shader when the surface format is not an sRGB one.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_passes::runtime::pipelines::{RenderSpec, render_pipeline};

/// The blit pipeline for one surface format, with the copy of the frame it reads.
pub struct Blit {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    source: Option<(wgpu::Texture, wgpu::BindGroup)>,
}

impl Blit {
    /// Compiles the blit for `target` (the surface format).
    pub fn new(ctx: &GpuContext, target: wgpu::TextureFormat) -> anyhow::Result<Self> {
        let d = &ctx.device;
        let source = ssbvb_gpu::shaders::source("view_blit.wgsl")?;
        let module = ctx.shader("view_blit.wgsl", &source)?;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view blit"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("view blit"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let constants = [("ENCODE_SRGB", if target.is_srgb() { 0.0 } else { 1.0 })];
        let targets = [Some(target.into())];
        let pipeline = ctx.validated("view blit pipeline", |d| {
            render_pipeline(
                d,
                &RenderSpec {
                    constants: &constants,
                    ..RenderSpec::new("view blit", &module, &pl, &targets)
                },
            )
        })?;
        Ok(Self {
            pipeline,
            layout,
            source: None,
        })
    }

    /// Records the copy of `frame` (the renderer's output) into the blit's own texture,
    /// (re)creating it when the size or format changed.
    pub fn copy_frame(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &wgpu::Texture,
    ) {
        let stale = self.source.as_ref().is_none_or(|(t, _)| {
            t.size() != frame.size() || t.format() != frame.format().add_srgb_suffix()
        });
        if stale {
            // An 8-bit output without an sRGB format holds sRGB-encoded bytes (the
            // composites encode for it, `CompositeCompute` always): its copy takes the sRGB
            // format (copies may change only that), so that it decodes as an sRGB output
            // does. No view format: GLES and WebGL have none.
            let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("view frame copy"),
                size: frame.size(),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: frame.format().add_srgb_suffix(),
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let view = texture.create_view(&Default::default());
            let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("view blit"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
            self.source = Some((texture, bind));
        }
        let (copy, _) = self.source.as_ref().expect("created above");
        encoder.copy_texture_to_texture(frame.as_image_copy(), copy.as_image_copy(), frame.size());
    }

    /// Draws the copied frame into `target` (clearing it first).
    pub fn draw(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("view blit"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        if let Some((_, bind)) = &self.source {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
