//! The filter's second proxy layer (`RayMarchFilter(peel: true)`; `vs_peel`, `fs_peel` and
//! `peel_bound` in `shaders/ray_march_filter.wgsl`).
//!
//! Before `main`, the pass rasterizes the visible instances' proxies again (front faces,
//! as the prepass draws them) into a texture of its own, keeping per texel the eye
//! distance of the nearest fragment of an instance other than the texel's prepass
//! instance. A proxy encloses its instance's voxels exactly, so no voxel of another
//! instance lies before that distance: a ray whose prepass instance is hit before it
//! (less a margin for rasterization, `peel_bound`) skips the walk over the instances'
//! boxes, which in a crowd was most of the filter's time (docs/benchmarks.md), and a ray
//! that walks passes over the boxes it leaves before the layer. The layer
//! is drawn by the filter because only the filter reads it (no pipeline declares it).
//!
//! A frame where some visible instance's proxy holds the camera or may be cut by the near
//! plane (`VisibleInstance::back_faces`: its proxy is not entered through a front face)
//! clears the layer to 0 instead: no ray skips its walk.

use ssbvb_gpu::wgpu;

use crate::error::PassError;
use crate::kinds::empty_space::proxy_runs;
use crate::runtime::pipelines::{RenderSpec, render_pipeline};
use crate::runtime::recorder::Recorder;

/// The layer's texture format: the bits of an f32 distance.
const LAYER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// Its depth attachment (reversed Z, as the prepass's).
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// What the layer holds where no other proxy was drawn: +inf.
const NO_OTHER_PROXY: f64 = f32::INFINITY.to_bits() as f64;

/// The layer and what draws it.
pub(super) struct Peel {
    /// The layer's pipeline and the layout of its group 1 (the prepass's `entry`), where
    /// the pass has `peel`.
    draw: Option<(wgpu::RenderPipeline, wgpu::BindGroupLayout)>,
    /// The layer, its depth attachment and their size (1 × 1 without `peel`: `main` binds
    /// it, reads nothing).
    targets: Targets,
}

struct Targets {
    size: (u32, u32),
    layer: wgpu::TextureView,
    depth: wgpu::TextureView,
}

impl Targets {
    /// The layer and its depth attachment at `(w, h)`, allocated through `create` (the
    /// device's checked allocation, so a refused one is an error naming its size).
    fn new(
        (w, h): (u32, u32),
        create: impl Fn(&wgpu::TextureDescriptor<'_>) -> Result<wgpu::Texture, PassError>,
    ) -> Result<Self, PassError> {
        let make = |label, format, usage| {
            create(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
            .map(|t| t.create_view(&Default::default()))
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        Ok(Self {
            size: (w, h),
            layer: make(
                "filter peel layer",
                LAYER_FORMAT,
                attach | wgpu::TextureUsages::TEXTURE_BINDING,
            )?,
            depth: make("filter peel depth", DEPTH_FORMAT, attach)?,
        })
    }
}

impl Peel {
    /// The layer's pipeline where `enabled` (from `module`, over the scene's group 0 and a
    /// group 1 of the prepass's `entry`), else a 1 × 1 layer of zeros.
    pub(super) fn new(
        d: &wgpu::Device,
        scene_layout: &wgpu::BindGroupLayout,
        module: &wgpu::ShaderModule,
        enabled: bool,
    ) -> Result<Self, PassError> {
        let draw = enabled.then(|| {
            let entry = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("filter peel entry"),
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
            let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("filter peel"),
                bind_group_layouts: &[Some(scene_layout), Some(&entry)],
                immediate_size: 0,
            });
            let proxy_vertex = [Some(wgpu::VertexBufferLayout {
                array_stride: 16,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x4],
            })];
            let targets = [Some(LAYER_FORMAT.into())];
            let pipeline = render_pipeline(
                d,
                &RenderSpec {
                    vs_entry: "vs_peel",
                    fs_entry: "fs_peel",
                    buffers: &proxy_vertex,
                    cull_mode: Some(wgpu::Face::Back),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Greater),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    ..RenderSpec::new("filter peel", module, &layout, &targets)
                },
            );
            (pipeline, entry)
        });
        Ok(Self {
            draw,
            targets: Targets::new((1, 1), |desc| Ok(d.create_texture(desc)))?,
        })
    }

    /// The layer `main` reads.
    pub(super) fn view(&self) -> &wgpu::TextureView {
        &self.targets.layer
    }

    /// Records the layer over the filter's `size` texels, its render pass taking the
    /// beginning of the pass's time; returns whether it recorded one (then the filter's
    /// compute pass ends the time). Nothing without `peel` or with one visible instance.
    pub(super) fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
        size: (u32, u32),
    ) -> Result<bool, PassError> {
        let visible = &rec.scene.visible;
        // With one instance `main` has no walk and reads no layer (`SEVERAL_INSTANCES`).
        let Some((pipeline, entry_layout)) = self.draw.as_ref().filter(|_| visible.len() > 1)
        else {
            return Ok(false);
        };
        if self.targets.size != size {
            self.targets = Targets::new(size, |desc| Ok(rec.gpu.checked_texture(desc)?))?;
        }
        let drawn = !visible.iter().any(|v| v.back_faces || v.camera_inside);
        let entry = rec.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("filter peel entry"),
            layout: entry_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&rec.texture("entry").view),
            }],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("filter peel"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.targets.layer,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: if drawn { NO_OTHER_PROXY } else { 0.0 },
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.targets.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: rec
                .render_timestamps()
                .map(|t| wgpu::RenderPassTimestampWrites {
                    end_of_pass_write_index: None,
                    ..t
                }),
            ..Default::default()
        });
        if drawn {
            let scene = rec.scene;
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, &entry, &[]);
            pass.set_vertex_buffer(0, scene.proxy_vertices.slice(..));
            pass.set_index_buffer(scene.proxy_indices.slice(..), wgpu::IndexFormat::Uint32);
            for (p, instances) in proxy_runs(visible, |_| true) {
                pass.draw_indexed(
                    p.first_index..p.first_index + p.index_count,
                    p.base_vertex,
                    instances,
                );
            }
        }
        Ok(true)
    }
}
