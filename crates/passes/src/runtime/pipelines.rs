//! Pipeline creation shared by the passes: the layout (scene group 0, pass group 1) and a
//! render pipeline from the few things that differ between passes. Every render pass here
//! draws counter-clockwise triangle lists without multisampling, and without culling unless
//! it asks (quads and cubes face the camera by construction; open meshes are two-sided; the
//! empty-space prepass culls to separate front and back faces of its proxies).

use ssbvb_gpu::wgpu;

use crate::runtime::bindings::PassBindings;
use ssbvb_gpu::scene::GpuScene;

/// The pipeline layout of a pass: the scene as group 0, its own bindings as group 1 (none
/// when `bindings` is `None`).
pub fn pipeline_layout(
    d: &wgpu::Device,
    label: &str,
    scene: &GpuScene,
    bindings: Option<&PassBindings>,
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = match bindings {
        Some(b) => vec![Some(&scene.layout), Some(&b.layout)],
        None => vec![Some(&scene.layout)],
    };
    d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

/// What differs between the render pipelines of the passes.
pub struct RenderSpec<'a> {
    /// Label for errors and debuggers.
    pub label: &'a str,
    /// The compiled WGSL.
    pub module: &'a wgpu::ShaderModule,
    /// From [`pipeline_layout`].
    pub layout: &'a wgpu::PipelineLayout,
    /// Vertex entry point.
    pub vs_entry: &'a str,
    /// Fragment entry point.
    pub fs_entry: &'a str,
    /// WGSL overrides, given to both stages.
    pub constants: &'a [(&'a str, f64)],
    /// Vertex buffers (empty for passes that pull their vertices).
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    /// Colour targets.
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    /// Depth-stencil state, if the pass has a depth attachment.
    pub depth_stencil: Option<wgpu::DepthStencilState>,
    /// Faces to cull.
    pub cull_mode: Option<wgpu::Face>,
    /// How vertices form triangles (default: a list).
    pub topology: wgpu::PrimitiveTopology,
}

impl<'a> RenderSpec<'a> {
    /// A spec with entry points `vs_main` / `fs_main`, no overrides, no vertex buffers and
    /// no depth-stencil.
    pub fn new(
        label: &'a str,
        module: &'a wgpu::ShaderModule,
        layout: &'a wgpu::PipelineLayout,
        targets: &'a [Option<wgpu::ColorTargetState>],
    ) -> Self {
        Self {
            label,
            module,
            layout,
            vs_entry: "vs_main",
            fs_entry: "fs_main",
            constants: &[],
            buffers: &[],
            targets,
            depth_stencil: None,
            cull_mode: None,
            topology: wgpu::PrimitiveTopology::TriangleList,
        }
    }
}

/// Creates the render pipeline `spec` describes.
pub fn render_pipeline(d: &wgpu::Device, spec: &RenderSpec<'_>) -> wgpu::RenderPipeline {
    let options = || wgpu::PipelineCompilationOptions {
        constants: spec.constants,
        ..Default::default()
    };
    d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some(spec.vs_entry),
            compilation_options: options(),
            buffers: spec.buffers,
        },
        fragment: Some(wgpu::FragmentState {
            module: spec.module,
            entry_point: Some(spec.fs_entry),
            compilation_options: options(),
            targets: spec.targets,
        }),
        primitive: wgpu::PrimitiveState {
            cull_mode: spec.cull_mode,
            topology: spec.topology,
            ..Default::default()
        },
        depth_stencil: spec.depth_stencil.clone(),
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// A compute pipeline of `entry` in `module` with the WGSL overrides `constants`.
pub fn compute_pipeline(
    d: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// Pipelines of one pass compiled per variant of its overrides (which code a frame needs:
/// counting, several instances, pages), each when a frame first needs it.
pub struct VariantCache<V, P> {
    built: Vec<(V, P)>,
}

impl<V: PartialEq + Copy, P> Default for VariantCache<V, P> {
    fn default() -> Self {
        Self { built: Vec::new() }
    }
}

impl<V: PartialEq + Copy, P> VariantCache<V, P> {
    /// The pipeline of `variant`, made by `build` the first time it is asked for.
    pub fn get_or_build<E>(
        &mut self,
        variant: V,
        build: impl FnOnce() -> Result<P, E>,
    ) -> Result<&P, E> {
        let i = match self.built.iter().position(|(v, _)| *v == variant) {
            Some(i) => i,
            None => {
                self.built.push((variant, build()?));
                self.built.len() - 1
            }
        };
        Ok(&self.built[i].1)
    }

    /// The pipeline of `variant`, if built.
    pub fn get(&self, variant: V) -> Option<&P> {
        self.built
            .iter()
            .find(|(v, _)| *v == variant)
            .map(|(_, p)| p)
    }
}
