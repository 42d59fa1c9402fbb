//! `composite_compute`: [`crate::kinds::composite`]'s lighting as a compute pass
//! (`CompositeCompute`; `shaders/composite_compute.wgsl`), for adapters whose fragment work
//! is slow. It writes an `Rgba8Unorm` storage texture, sRGB-encoded in the shader: the
//! bytes `Composite` writes to an `Rgba8Unorm` target (GPU test `smooth_composite`).

use ssbvb_gpu::wgpu;
use ssbvb_graph::CompositeComputeKind;

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::node::PassNode;
use crate::runtime::pipelines::{compute_pipeline, pipeline_layout};
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{PassImpl, PassInit};
use ssbvb_gpu::shaders;

/// Pixels a side of a workgroup.
const TILE: u32 = 8;

/// The compute composite: a pipeline that clears the pixels where nothing was drawn (the
/// output's first writer) and one that leaves them.
pub struct CompositeCompute {
    clearing: wgpu::ComputePipeline,
    keeping: wgpu::ComputePipeline,
    bindings: PassBindings,
}

impl PassImpl for CompositeCompute {
    type Params = CompositeComputeKind;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "composite_compute.wgsl";

    fn new(init: &PassInit<'_>, _params: &CompositeComputeKind) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let module = ctx.shader(
            Self::SHADER,
            &shaders::source_for(Self::SHADER, &scene.bindings)?,
        )?;
        let bindings = PassBindings::new(ctx, pipeline, pass, &[]);
        let label = format!("pass `{}`: composite_compute pipelines", pass.name);
        let [clearing, keeping] = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(&bindings));
            [1.0, 0.0].map(|clear| {
                let constants = [("ENCODE_SRGB", 1.0), ("CLEAR", clear)];
                compute_pipeline(d, &layout, &module, "main", &constants)
            })
        })?;
        Ok(Self {
            clearing,
            keeping,
            bindings,
        })
    }
}

impl PassNode for CompositeCompute {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let bg = self.bindings.bind_group(rec, &[])?;
        let out = &rec.texture("color").texture;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&rec.pass.name),
            timestamp_writes: rec.compute_timestamps(),
        });
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, &bg, &[]);
        pass.set_pipeline(if rec.clears("color") {
            &self.clearing
        } else {
            &self.keeping
        });
        pass.dispatch_workgroups(out.width().div_ceil(TILE), out.height().div_ceil(TILE), 1);
        Ok(())
    }
}
