//! The physical resources of a resolved pipeline at one screen size: one GPU object per
//! physical resource (aliases share one), created or imported from the caller.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{ResolvedPipeline, ResourceDesc, ResourceUsage};

use crate::error::PassError;

/// A texture resource with the views passes need.
/// What the label of a frame resource (a texture or buffer of the render graph) holds
/// between its name and its physical index: `"{name} (physical {i})"`. A refused
/// allocation so named is the frame's, not the scene's (a GPU budget does not size it).
pub const PHYSICAL_LABEL_MARK: &str = " (physical ";

pub struct FrameTexture {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Default view (all aspects).
    pub view: wgpu::TextureView,
    /// Depth-only view for sampling depth(-stencil) textures.
    pub depth_view: Option<wgpu::TextureView>,
}

/// One live resource's GPU object (aliases share one). Few exist per frame, so the
/// size difference of the variants does not matter.
#[allow(clippy::large_enum_variant)]
pub enum FrameResource {
    /// A texture.
    Texture(FrameTexture),
    /// A buffer.
    Buffer(wgpu::Buffer),
}

/// The physical resources of one pipeline at one screen size.
pub struct FrameResources {
    physical: Vec<FrameResource>,
    /// `of_resource[i]`: physical index of resolved resource `i`.
    of_resource: Vec<usize>,
}

impl FrameResources {
    /// Creates every physical resource of `pipeline` at `screen`.
    pub fn new(
        ctx: &GpuContext,
        pipeline: &ResolvedPipeline,
        screen: (u32, u32),
    ) -> Result<Self, PassError> {
        Self::with_imports(ctx, pipeline, screen, &[])
    }

    /// Like [`FrameResources::new`], but the named resources are the caller's textures
    /// (their size must be the resource's size at `screen`, their format its format, their
    /// usage at least what the graph derived). An imported resource must not be aliased.
    pub fn with_imports(
        ctx: &GpuContext,
        pipeline: &ResolvedPipeline,
        screen: (u32, u32),
        imports: &[(&str, wgpu::Texture)],
    ) -> Result<Self, PassError> {
        let mut physical = Vec::new();
        for (i, p) in pipeline.physical.iter().enumerate() {
            let name = pipeline.resources[p.aliases[0]].name.clone();
            let label = format!("{name}{PHYSICAL_LABEL_MARK}{i})");
            if let Some((_, tex)) = imports.iter().find(|(n, _)| *n == name) {
                physical.push(FrameResource::Texture(import(ctx, tex, &name, p, screen)?));
                continue;
            }
            let r = match (&p.desc, p.usage) {
                (ResourceDesc::Texture { format, size }, ResourceUsage::Texture(usage)) => {
                    let (w, h) = size.resolve(screen);
                    let format = texture_format(ctx, *format);
                    let texture = ctx.checked_texture(&wgpu::TextureDescriptor {
                        label: Some(&label),
                        size: wgpu::Extent3d {
                            width: w,
                            height: h,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        // Copies for readback in tests, tools and the embedding API.
                        usage: usage | wgpu::TextureUsages::COPY_SRC,
                        view_formats: &[],
                    })?;
                    let view = texture.create_view(&Default::default());
                    let depth_view = format.is_depth_stencil_format().then(|| {
                        texture.create_view(&wgpu::TextureViewDescriptor {
                            aspect: wgpu::TextureAspect::DepthOnly,
                            ..Default::default()
                        })
                    });
                    FrameResource::Texture(FrameTexture {
                        texture,
                        view,
                        depth_view,
                    })
                }
                (ResourceDesc::Buffer { layout, count }, ResourceUsage::Buffer(usage)) => {
                    let size = count.resolve(screen) * layout.element_size();
                    let max = ctx.device.limits().max_storage_buffer_binding_size;
                    if size > max {
                        return Err(PassError::TooLarge(format!(
                            "resource `{name}` needs {size} bytes, the device binds at most {max}"
                        )));
                    }
                    FrameResource::Buffer(ctx.checked_buffer(&wgpu::BufferDescriptor {
                        label: Some(&label),
                        size: size.max(16),
                        usage,
                        mapped_at_creation: false,
                    })?)
                }
                _ => unreachable!("graph usages match descriptors"),
            };
            physical.push(r);
        }
        let of_resource = pipeline.resources.iter().map(|r| r.physical).collect();
        Ok(Self {
            physical,
            of_resource,
        })
    }

    /// The GPU object of resolved resource `i`.
    pub fn get(&self, i: usize) -> &FrameResource {
        &self.physical[self.of_resource[i]]
    }

    /// The texture of resolved resource `i` (panics if it is a buffer: the graph checked).
    pub fn texture(&self, i: usize) -> &FrameTexture {
        match self.get(i) {
            FrameResource::Texture(t) => t,
            FrameResource::Buffer(_) => panic!("resource {i} is a buffer"),
        }
    }

    /// The buffer of resolved resource `i`.
    pub fn buffer(&self, i: usize) -> &wgpu::Buffer {
        match self.get(i) {
            FrameResource::Buffer(b) => b,
            FrameResource::Texture(_) => panic!("resource {i} is a texture"),
        }
    }
}

/// Checks a caller's texture against a physical resource and wraps it.
fn import(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    name: &str,
    p: &ssbvb_graph::PhysicalResource,
    screen: (u32, u32),
) -> Result<FrameTexture, PassError> {
    if p.aliases.len() > 1 {
        return Err(PassError::BadScene(format!(
            "imported resource `{name}` shares memory with another resource"
        )));
    }
    let (ResourceDesc::Texture { size, format }, ResourceUsage::Texture(usage)) =
        (&p.desc, p.usage)
    else {
        return Err(PassError::BadScene(format!(
            "imported resource `{name}` is not a texture"
        )));
    };
    let want_format = texture_format(ctx, *format);
    if tex.format() != want_format {
        return Err(PassError::BadScene(format!(
            "imported `{name}` has format {:?}; the pipeline needs {want_format:?}",
            tex.format()
        )));
    }
    let want = size.resolve(screen);
    if (tex.width(), tex.height()) != want || !tex.usage().contains(usage) {
        return Err(PassError::BadScene(format!(
            "imported `{name}` is {}x{} with usage {:?}; the pipeline needs {}x{} with {usage:?}",
            tex.width(),
            tex.height(),
            tex.usage(),
            want.0,
            want.1
        )));
    }
    let view = tex.create_view(&Default::default());
    let depth_view = tex.format().is_depth_stencil_format().then(|| {
        tex.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        })
    });
    Ok(FrameTexture {
        texture: tex.clone(),
        view,
        depth_view,
    })
}

/// The wgpu format of a pipeline format on this device (Depth32FloatStencil8 falls back
/// to Depth24PlusStencil8 where the feature is missing).
pub fn texture_format(ctx: &GpuContext, format: ssbvb_graph::Format) -> wgpu::TextureFormat {
    match format.to_wgpu() {
        wgpu::TextureFormat::Depth32FloatStencil8
            if !ctx.has(wgpu::Features::DEPTH32FLOAT_STENCIL8) =>
        {
            wgpu::TextureFormat::Depth24PlusStencil8
        }
        f => f,
    }
}

/// A 2D texture of `size` (each side at least 1) that passes draw into
/// (`RENDER_ATTACHMENT`) and use as `usage` besides: a pass's own targets beside the
/// pipeline's resources (history, accumulation, copies).
pub(crate) fn render_target(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0.max(1),
            height: size.1.max(1),
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | usage,
        view_formats: &[],
    })
}
