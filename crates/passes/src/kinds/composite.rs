//! `composite`: deferred Blinn-Phong (the CPU reference's formula) into the output colour
//! (see `shaders/composite.wgsl`).

use ssbvb_gpu::wgpu;
use ssbvb_graph::CompositeKind;

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::node::PassNode;
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::runtime::registry::{PassImpl, PassInit};
use ssbvb_gpu::shaders;

/// The composite pass.
pub struct Composite {
    pipeline: wgpu::RenderPipeline,
    bindings: PassBindings,
}

impl PassImpl for Composite {
    type Params = CompositeKind;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "composite.wgsl";

    fn new(init: &PassInit<'_>, _params: &CompositeKind) -> Result<Self, PassError> {
        Self::compile(init, Self::SHADER)
    }
}

impl Composite {
    /// Compiles the fullscreen lighting pipeline of `shader` (this pass's, or
    /// `ConeComposite`'s, which differs only in what it reads) for the output's format
    /// (sRGB encoding in the shader for 8-bit non-sRGB targets).
    pub fn compile(init: &PassInit<'_>, shader: &str) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let d = &ctx.device;
        let module = ctx.shader(shader, &shaders::source_for(shader, &scene.bindings)?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, &[]);
        let layout = pipeline_layout(d, shader, scene, Some(&bindings));
        let out = slot_format(ctx, pipeline, pass, "color");
        let encode = matches!(
            out,
            wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Bgra8Unorm
        );
        let constants = [("ENCODE_SRGB", if encode { 1.0 } else { 0.0 })];
        let targets = [Some(out.into())];
        let pipeline = render_pipeline(
            d,
            &RenderSpec {
                constants: &constants,
                ..RenderSpec::new(shader, &module, &layout, &targets)
            },
        );
        Ok(Self { pipeline, bindings })
    }
}

impl PassNode for Composite {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let bg = self.bindings.bind_group(rec, &[])?;
        rec.draw_fullscreen(
            encoder,
            &[rec.color_attachment("color")],
            &self.pipeline,
            &bg,
        );
        Ok(())
    }
}
