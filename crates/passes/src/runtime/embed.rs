//! Embedding: draw ssbvb's voxel objects into a caller's own wgpu frame.
//!
//! The paper's selling point is that SSBVB drops into any raster engine. A [`VoxelLayer`]
//! takes the caller's device and queue, its colour target and its depth-stencil target, and
//! renders the voxel objects of a [`Scene`] into them after the caller has drawn its own
//! geometry: billboards are depth-tested against the caller's depth, mark voxel pixels in
//! the stencil (value 1), smoothing touches only those, and the composite writes only
//! voxel pixels. The caller's depth must be reversed-Z (cleared to 0, compare `Greater`),
//! built with the same [`Camera`] conventions (`ssbvb_voxel::camera`), and its stencil must
//! not use value 1 for its own pixels.

use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::ResolvedPipeline;
use ssbvb_voxel::camera::Camera;

use crate::error::PassError;
use crate::runtime::renderer::{FrameStats, Profiling, Renderer};
use ssbvb_gpu::scene::GpuScene;
use ssbvb_gpu::scene::Scene;

/// The bundled pipeline for embedding (`assets/pipelines/ssbvb_embedded.ron`).
pub const EMBEDDED_PIPELINE: &str = include_str!("../../../../assets/pipelines/ssbvb_embedded.ron");

/// Voxel objects rendered into a caller's targets.
pub struct VoxelLayer {
    ctx: GpuContext,
    scene: GpuScene,
    renderer: Renderer,
}

impl VoxelLayer {
    /// Prepares `scene` on the caller's device to draw into `color` (the pipeline's
    /// `color`, usage RENDER_ATTACHMENT | COPY_SRC) and `depth_stencil` (the pipeline's
    /// `depth_stencil`, usage RENDER_ATTACHMENT | TEXTURE_BINDING | COPY_SRC). `pipeline`
    /// defaults to [`EMBEDDED_PIPELINE`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        instance: &wgpu::Instance,
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: Scene,
        pipeline: Option<ResolvedPipeline>,
        color: &wgpu::Texture,
        depth_stencil: &wgpu::Texture,
    ) -> Result<Self, PassError> {
        let ctx = GpuContext::from_parts(
            instance.clone(),
            adapter.clone(),
            device.clone(),
            queue.clone(),
        );
        let pipeline = match pipeline {
            Some(p) => p,
            None => ssbvb_graph::resolve_str(EMBEDDED_PIPELINE, "ssbvb_embedded.ron")
                .map_err(|e| PassError::BadScene(e.to_string()))?,
        };
        let screen = (color.width(), color.height());
        let gpu_scene = GpuScene::new(&ctx, scene)?;
        let renderer = Renderer::with_imports(
            &ctx,
            &gpu_scene,
            pipeline,
            screen,
            &[
                ("color", color.clone()),
                ("depth_stencil", depth_stencil.clone()),
            ],
        )?;
        Ok(Self {
            ctx,
            scene: gpu_scene,
            renderer,
        })
    }

    /// Renders the voxel objects seen by `camera` into the caller's targets (submitted on
    /// the caller's queue after anything the caller submitted before).
    pub fn render(
        &mut self,
        camera: &Camera,
        profiling: Profiling,
    ) -> Result<FrameStats, PassError> {
        self.renderer
            .render(&self.ctx, &mut self.scene, camera, profiling)
    }

    /// The renderer (resources, fill count).
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    /// The scene on the GPU (memory per object).
    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }
}
