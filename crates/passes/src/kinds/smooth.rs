//! `smooth`: Gaussian smoothing of voxel normals with the paper's distance-dependent offset
//! (Eq. 1), stencil-tested so only voxel pixels change (see `shaders/smooth.wgsl`).

use ssbvb_gpu::wgpu;
use ssbvb_graph::SmoothParams;

use crate::runtime::bindings::PassBindings;
use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::kinds::gbuffer::STENCIL_VOXEL;
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;
use ssbvb_gpu::shaders;

/// Eq. 1 of the paper made total, exactly as `smooth.wgsl` computes it:
/// `I = max(0, min(MaxI / (Dist − MinDist)², MaxI))` for `Dist > MinDist`, and `MaxI` for
/// `Dist ≤ MinDist` (the singularity at `Dist = MinDist` and the rising branch below it
/// both take the limit from above) and for a NaN distance. Always finite, in `[0, MaxI]`.
pub fn smoothing_offset(dist: f32, max_i: f32, min_dist: f32) -> f32 {
    let x = dist - min_dist;
    // Dist <= MinDist, or NaN.
    if x.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return max_i;
    }
    (max_i / (x * x)).clamp(0.0, max_i)
}

/// What the smoothing pass binds itself: the linear sampler of the normals.
pub const OWN: &[OwnBinding] = &[OwnBinding {
    name: "normal_sampler",
    kind: OwnKind::Sampler(wgpu::SamplerBindingType::Filtering),
}];

/// The smoothing pass.
pub struct Smooth {
    smooth: wgpu::RenderPipeline,
    copy: wgpu::RenderPipeline,
    bindings: PassBindings,
    sampler: wgpu::Sampler,
}

impl PassImpl for Smooth {
    type Params = SmoothParams;
    const SHADER: &'static str = "smooth.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    // Samples the depth of the depth-stencil it stencil-tests against.
    const NEEDS: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL, 0);

    /// Compiles both pipelines (voxel pixels smoothed, all others copied).
    fn new(init: &PassInit<'_>, params: &SmoothParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = init.parts();
        let SmoothParams { max_i, min_dist } = *params;
        let d = &ctx.device;
        let module = ctx.shader("smooth.wgsl", &shaders::source_for("smooth.wgsl", &scene.bindings)?)?;
        let bindings = PassBindings::new(ctx, pipeline, pass, OWN);
        let layout = pipeline_layout(d, "smooth", scene, Some(&bindings));
        let ds_format = slot_format(ctx, pipeline, pass, "depth_stencil");
        let targets = [Some(
            slot_format(ctx, pipeline, pass, "smoothed_normal").into(),
        )];
        let constants = [("MAX_I", max_i as f64), ("MIN_DIST", min_dist as f64)];
        let make = |entry: &str, compare: wgpu::CompareFunction| {
            let face = wgpu::StencilFaceState {
                compare,
                fail_op: wgpu::StencilOperation::Keep,
                depth_fail_op: wgpu::StencilOperation::Keep,
                pass_op: wgpu::StencilOperation::Keep,
            };
            render_pipeline(
                d,
                &RenderSpec {
                    fs_entry: entry,
                    constants: &constants,
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: ds_format,
                        depth_write_enabled: Some(false),
                        depth_compare: Some(wgpu::CompareFunction::Always),
                        stencil: wgpu::StencilState {
                            front: face,
                            back: face,
                            read_mask: 0xff,
                            write_mask: 0,
                        },
                        bias: Default::default(),
                    }),
                    ..RenderSpec::new(entry, &module, &layout, &targets)
                },
            )
        };
        let smooth = make("fs_smooth", wgpu::CompareFunction::Equal);
        let copy = make("fs_main", wgpu::CompareFunction::NotEqual);
        let sampler = d.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("smooth"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            smooth,
            copy,
            bindings,
            sampler,
        })
    }
}

impl PassNode for Smooth {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let ds = rec.texture("depth_stencil");
        let bg = self.bindings.bind_group(
            rec,
            &[(
                "normal_sampler",
                wgpu::BindingResource::Sampler(&self.sampler),
            )],
        )?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&rec.pass.name),
            color_attachments: &[rec.color_attachment("smoothed_normal")],
            // Read-only: the stencil selects pixels, the depth is sampled for Dist.
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &ds.view,
                depth_ops: None,
                stencil_ops: None,
            }),
            timestamp_writes: rec.render_timestamps(),
            ..Default::default()
        });
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, &bg, &[]);
        pass.set_stencil_reference(STENCIL_VOXEL);
        pass.set_pipeline(&self.smooth);
        pass.draw(0..3, 0..1);
        pass.set_pipeline(&self.copy);
        pass.draw(0..3, 0..1);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::smoothing_offset;

    #[test]
    fn eq1_is_total_finite_and_monotone() {
        let (max_i, min_dist) = (2.0, 0.5);
        // At, below and far below MinDist: MaxI, never Inf or NaN.
        assert_eq!(smoothing_offset(0.5, max_i, min_dist), max_i);
        assert_eq!(smoothing_offset(0.4999, max_i, min_dist), max_i);
        assert_eq!(smoothing_offset(-1e30, max_i, min_dist), max_i);
        assert_eq!(smoothing_offset(f32::NAN, max_i, min_dist), max_i);
        // Just above: Eq. 1 is clamped to MaxI; then it decays as 1 / x².
        assert_eq!(smoothing_offset(0.5001, max_i, min_dist), max_i);
        assert!((smoothing_offset(2.5, max_i, min_dist) - 0.5).abs() < 1e-6);
        assert!((smoothing_offset(10.5, max_i, min_dist) - 0.02).abs() < 1e-6);
        // Far above: tends to 0, stays finite (1e30² overflows to inf: 2 / inf = 0).
        assert_eq!(smoothing_offset(1e30, max_i, min_dist), 0.0);
        assert_eq!(smoothing_offset(f32::INFINITY, max_i, min_dist), 0.0);
        let mut prev = max_i;
        for i in 0..1000 {
            let v = smoothing_offset(0.5 + i as f32 * 0.01, max_i, min_dist);
            assert!(v.is_finite() && v <= prev && v >= 0.0);
            prev = v;
        }
    }
}
