//! Presenting a frame to the page's canvas: the pipeline's output is copied to a sampled
//! texture and drawn into the canvas's texture (`present.wgsl`). WebGPU canvases are
//! render attachments only (no copy into them) and take no sRGB format.

use ssbvb_gpu::{GpuContext, wgpu};

use crate::WebError;

/// The canvas and what draws the frame into it.
pub struct Presenter {
    surface: wgpu::Surface<'static>,
    copy: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    pipeline: wgpu::RenderPipeline,
}

impl Presenter {
    /// Configures `surface` for frames of `output`'s size and format.
    pub fn new(
        ctx: &GpuContext,
        surface: wgpu::Surface<'static>,
        output: &wgpu::Texture,
    ) -> Result<Self, WebError> {
        let caps = surface.get_capabilities(&ctx.adapter);
        let format = *caps
            .formats
            .iter()
            .find(|f| !f.is_srgb())
            .ok_or_else(|| WebError::Gpu("the canvas offers no 8-bit format".into()))?;
        let (width, height) = (output.width(), output.height());
        surface.configure(
            &ctx.device,
            &wgpu::SurfaceConfiguration {
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                format,
                width,
                height,
                present_mode: wgpu::PresentMode::Fifo,
                desired_maximum_frame_latency: 2,
                alpha_mode: wgpu::CompositeAlphaMode::Opaque,
                view_formats: Vec::new(),
                color_space: wgpu::SurfaceColorSpace::Auto,
            },
        );
        let copy = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("canvas frame"),
            size: output.size(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: output.format(),
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let module = ctx
            .shader("present.wgsl", include_str!("present.wgsl"))
            .map_err(|e| WebError::Gpu(e.to_string()))?;
        let encode = if output.format().is_srgb() { 1.0 } else { 0.0 };
        let pipeline = ctx
            .device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("canvas blit"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &[("ENCODE_SRGB", encode)],
                        ..Default::default()
                    },
                    targets: &[Some(format.into())],
                }),
                multiview_mask: None,
                cache: None,
            });
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("canvas blit"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(
                    &copy.create_view(&Default::default()),
                ),
            }],
        });
        Ok(Self {
            surface,
            copy,
            bind_group,
            pipeline,
        })
    }

    /// The canvas's surface, to configure again for another frame size.
    pub fn into_surface(self) -> wgpu::Surface<'static> {
        self.surface
    }

    /// Draws `output` (the frame just rendered) into the canvas.
    pub fn present(&self, ctx: &GpuContext, output: &wgpu::Texture) -> Result<(), WebError> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            other => {
                return Err(WebError::Gpu(format!(
                    "the canvas gave no texture: {other:?}"
                )));
            }
        };
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("canvas"),
            });
        enc.copy_texture_to_texture(
            output.as_image_copy(),
            self.copy.as_image_copy(),
            output.size(),
        );
        {
            let view = frame.texture.create_view(&Default::default());
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("canvas blit"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        ctx.submit("canvas", [enc.finish()]);
        ctx.queue.present(frame);
        Ok(())
    }
}
