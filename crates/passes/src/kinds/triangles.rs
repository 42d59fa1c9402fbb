//! `triangles`: the scene's ordinary triangle meshes drawn into the G-buffer
//! ([`crate::kinds::gbuffer`]) with stencil = triangle (see `shaders/triangles.wgsl`).

use ssbvb_gpu::wgpu;
use ssbvb_graph::TrianglesKind;

use crate::runtime::bindings::PassBindings;
use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::{
    STENCIL_TRIANGLE, begin_gbuffer_pass, gbuffer_depth_stencil, gbuffer_targets,
};
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::registry::{PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;
use ssbvb_gpu::shaders;

/// What the triangles pass binds itself: the uniform of the mesh being drawn.
pub const OWN: &[OwnBinding] = &[OwnBinding {
    name: "mesh",
    kind: OwnKind::Uniform,
}];

/// The triangles pass: one indexed draw per scene mesh.
pub struct Triangles {
    pipeline: wgpu::RenderPipeline,
    bindings: PassBindings,
}

impl PassImpl for Triangles {
    type Params = TrianglesKind;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "triangles.wgsl";
    const OWN: &'static [OwnBinding] = OWN;

    /// Compiles the pipeline for the formats bound to `pass`.
    fn new(init: &PassInit<'_>, _params: &TrianglesKind) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let d = &ctx.device;
        let module = ctx.shader("triangles.wgsl", &shaders::source_for("triangles.wgsl", &scene.bindings)?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, OWN);
        let layout = pipeline_layout(d, "triangles", scene, Some(&bindings));
        let targets = gbuffer_targets(ctx, pipeline, pass);
        // Two-sided: open meshes (a ground plane, the teapot) are visible from both sides;
        // the shader turns the normal towards the camera.
        let pipeline = render_pipeline(
            d,
            &RenderSpec {
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 24,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                })],
                depth_stencil: Some(gbuffer_depth_stencil(ctx, pipeline, pass)),
                ..RenderSpec::new("triangles", &module, &layout, &targets)
            },
        );
        Ok(Self { pipeline, bindings })
    }
}

impl PassNode for Triangles {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let meshes: Vec<_> = rec
            .scene
            .meshes
            .iter()
            .filter(|m| m.index_count > 0 && m.vertices.size() > 0)
            .map(|m| {
                let bg = self
                    .bindings
                    .bind_group(rec, &[("mesh", m.uniform.as_entire_binding())]);
                bg.map(|bg| (m, bg))
            })
            .collect::<Result<_, _>>()?;
        let mut pass = begin_gbuffer_pass(encoder, rec, STENCIL_TRIANGLE);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        for (m, bg) in &meshes {
            pass.set_bind_group(1, bg, &[]);
            pass.set_vertex_buffer(0, m.vertices.slice(..));
            pass.set_index_buffer(m.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..m.index_count, 0, 0..1);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_triangle_stencil_matches_the_shader() {
        // The Mesh layout is checked by `cargo xtask validate-shaders`.
        let src = shaders::source("triangles.wgsl").unwrap();
        assert!(src.contains("const STENCIL_TRIANGLE: u32 = 2u;"));
        assert_eq!(STENCIL_TRIANGLE, 2);
    }
}
