//! `edge_aa`: single-frame anti-aliasing of the output colour for stills (`EdgeAa`;
//! `shaders/edge_aa.wgsl`): one fullscreen pass from the composite's colour to the
//! pipeline's output, FXAA-style. It reads texels only (no sampler): the blend with the
//! neighbour across an edge is the bilinear read FXAA makes, done by hand.

use ssbvb_gpu::{shaders, wgpu};
use ssbvb_graph::EdgeAaParams;

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::node::PassNode;
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::runtime::registry::{PassImpl, PassInit};

/// The edge anti-aliasing pass.
pub struct EdgeAa {
    pipeline: wgpu::RenderPipeline,
    bindings: PassBindings,
}

impl PassImpl for EdgeAa {
    type Params = EdgeAaParams;
    const SHADER: &'static str = "edge_aa.wgsl";

    /// Compiles the pass for the output's format; `threshold` and `subpixel` become the
    /// WGSL overrides `THRESHOLD` and `SUBPIXEL`.
    fn new(init: &PassInit<'_>, params: &EdgeAaParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let d = &ctx.device;
        let module = ctx.shader(Self::SHADER, &shaders::source_for(Self::SHADER, &scene.bindings)?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, &[]);
        let label = format!("pass `{}`: {}", pass.name, Self::SHADER);
        let layout = pipeline_layout(d, &label, scene, Some(&bindings));
        let targets = [Some(slot_format(ctx, pipeline, pass, "color").into())];
        let constants = [
            ("THRESHOLD", f64::from(params.threshold)),
            ("SUBPIXEL", f64::from(params.subpixel)),
        ];
        let pipeline = ctx.validated(&label, |d| {
            render_pipeline(
                d,
                &RenderSpec {
                    constants: &constants,
                    ..RenderSpec::new(&label, &module, &layout, &targets)
                },
            )
        })?;
        Ok(Self { pipeline, bindings })
    }
}

impl PassNode for EdgeAa {
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
