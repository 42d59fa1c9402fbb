//! `smooth_compute`: [`crate::kinds::smooth`]'s Gaussian as a compute pass
//! (`SmoothCompute`; `shaders/smooth_compute.wgsl`), for adapters whose fragment work is
//! slow. One thread per pixel reads the stencil aspect of the G-buffer's depth-stencil as a
//! texture (a view this pass makes) instead of stencil-testing two fullscreen draws, and
//! writes the smoothed normal as a storage texture: the same image (GPU test
//! `smooth_composite`).

use ssbvb_gpu::wgpu;
use ssbvb_graph::SmoothComputeParams;

use crate::error::PassError;
use crate::runtime::bindings::PassBindings;
use crate::runtime::node::PassNode;
use crate::runtime::pipelines::{compute_pipeline, pipeline_layout};
use crate::runtime::recorder::Recorder;
use crate::runtime::registry::{OwnBinding, OwnKind, PassImpl, PassInit};
use ssbvb_gpu::shaders;

/// What the pass binds itself: the normals' linear sampler and the stencil's view.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "normal_sampler",
        kind: OwnKind::Sampler(wgpu::SamplerBindingType::Filtering),
    },
    OwnBinding {
        name: "voxel_stencil",
        kind: OwnKind::Texture2dUint,
    },
];

/// Pixels a side of a workgroup.
const TILE: u32 = 8;

/// The compute smoothing pass.
pub struct SmoothCompute {
    pipeline: wgpu::ComputePipeline,
    bindings: PassBindings,
    sampler: wgpu::Sampler,
}

impl PassImpl for SmoothCompute {
    type Params = SmoothComputeParams;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "smooth_compute.wgsl";
    const OWN: &'static [OwnBinding] = OWN;

    /// Compiles the pipeline; `max_i` and `min_dist` become the WGSL overrides of Eq. 1.
    fn new(init: &PassInit<'_>, params: &SmoothComputeParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        // GL keeps a depth-stencil texture's sampled aspect on the texture, not the view:
        // of the two views bound here one would read the other's aspect.
        if ctx.adapter.get_info().backend == wgpu::Backend::Gl {
            return Err(PassError::Unsupported(format!(
                "pass `{}` (SmoothCompute) reads the depth and the stencil of one texture                  in one dispatch, which GL cannot: use Smooth on GL",
                pass.name
            )));
        }
        let module = ctx.shader(
            Self::SHADER,
            &shaders::source_for(Self::SHADER, &scene.bindings)?,
        )?;
        let bindings = PassBindings::new(ctx, pipeline, pass, OWN);
        let constants = [
            ("MAX_I", f64::from(params.max_i)),
            ("MIN_DIST", f64::from(params.min_dist)),
        ];
        let label = format!("pass `{}`: smooth_compute pipeline", pass.name);
        let pipeline = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, &label, scene, Some(&bindings));
            compute_pipeline(d, &layout, &module, "main", &constants)
        })?;
        // The fragment pass's sampler, so that both take the same samples.
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("smooth_compute"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            pipeline,
            bindings,
            sampler,
        })
    }
}

impl PassNode for SmoothCompute {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let ds = &rec.texture("depth_stencil").texture;
        let stencil = ds.create_view(&wgpu::TextureViewDescriptor {
            label: Some("smooth_compute stencil"),
            aspect: wgpu::TextureAspect::StencilOnly,
            ..Default::default()
        });
        let bg = self.bindings.bind_group(
            rec,
            &[
                (
                    "normal_sampler",
                    wgpu::BindingResource::Sampler(&self.sampler),
                ),
                ("voxel_stencil", wgpu::BindingResource::TextureView(&stencil)),
            ],
        )?;
        let out = &rec.texture("smoothed_normal").texture;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&rec.pass.name),
            timestamp_writes: rec.compute_timestamps(),
        });
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, &bg, &[]);
        pass.set_pipeline(&self.pipeline);
        pass.dispatch_workgroups(out.width().div_ceil(TILE), out.height().div_ceil(TILE), 1);
        Ok(())
    }
}
