//! `smooth`: Gaussian smoothing of voxel normals with the paper's distance-dependent offset
//! (Eq. 1), stencil-tested so only voxel pixels change (see `shaders/smooth.wgsl`).
//!
//! The distance comes from the depth, which the pass samples from the depth-stencil it
//! stencil-tests against (a read-only attachment). Devices without read-only depth-stencil
//! attachments (GL, WebGL) cannot bind a texture both ways in one pass: there, and with
//! `copy_depth`, a pass before copies the depth's bits into an `R32Uint` texture of the
//! pass's own (integer targets are renderable everywhere), which the smoothing reads
//! instead. Both paths draw the same image bit for bit (GPU test).

use ssbvb_gpu::wgpu;
use ssbvb_graph::SmoothParams;

use crate::runtime::bindings::PassBindings;
use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::recorder::{Recorder, slot_format};
use crate::kinds::gbuffer::{STENCIL_VOXEL, stencil_test};
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;
use crate::runtime::resources::render_target;
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

/// What the smoothing pass binds itself: the linear sampler of the normals, and the copy
/// of the depth where it smooths from one.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "normal_sampler",
        kind: OwnKind::Sampler(wgpu::SamplerBindingType::Filtering),
    },
    OwnBinding {
        name: "depth_copy",
        kind: OwnKind::Texture2dUint,
    },
];

/// The smoothing pass.
pub struct Smooth {
    smooth: wgpu::RenderPipeline,
    copy: wgpu::RenderPipeline,
    bindings: PassBindings,
    sampler: wgpu::Sampler,
    /// Smoothing from a copy of the depth (no read-only depth-stencil attachments, or
    /// `copy_depth`).
    depth_copy: Option<DepthCopy>,
}

/// The pass that copies the depth's bits, and its target (made at the screen's size).
struct DepthCopy {
    pipeline: wgpu::RenderPipeline,
    bindings: PassBindings,
    target: Option<(wgpu::Texture, wgpu::TextureView)>,
}

impl PassImpl for Smooth {
    type Params = SmoothParams;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "smooth.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    // Samples the depth of the depth-stencil it stencil-tests against.
    const NEEDS: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::empty(), 0);

    /// Compiles both pipelines (voxel pixels smoothed, all others copied).
    fn new(init: &PassInit<'_>, params: &SmoothParams) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let SmoothParams {
            max_i,
            min_dist,
            copy_depth,
        } = *params;
        let copied = copy_depth
            || !ctx
                .adapter
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL);
        let d = &ctx.device;
        let source = shaders::source_for("smooth.wgsl", &scene.bindings)?;
        let module = ctx.shader("smooth.wgsl", &source)?;
        let smooth_entry = if copied { "fs_smooth_copied" } else { "fs_smooth" };
        let used = |entries: &[&str]| -> Result<Vec<u32>, PassError> {
            let mut u = shaders::used_bindings("smooth.wgsl", &source, entries, 1)?.concat();
            u.sort_unstable();
            u.dedup();
            Ok(u)
        };
        let bindings = PassBindings::used_only(
            ctx,
            pipeline,
            pass,
            OWN,
            Some(&used(&["vs_main", smooth_entry, "fs_main"])?),
        );
        let layout = pipeline_layout(d, "smooth", scene, Some(&bindings));
        let ds_format = slot_format(ctx, pipeline, pass, "depth_stencil");
        let targets = [Some(
            slot_format(ctx, pipeline, pass, "smoothed_normal").into(),
        )];
        let constants = [("MAX_I", max_i as f64), ("MIN_DIST", min_dist as f64)];
        let make = |entry: &str, compare: wgpu::CompareFunction| {
            render_pipeline(
                d,
                &RenderSpec {
                    fs_entry: entry,
                    constants: &constants,
                    depth_stencil: Some(stencil_test(ds_format, compare)),
                    ..RenderSpec::new(entry, &module, &layout, &targets)
                },
            )
        };
        let smooth = make(smooth_entry, wgpu::CompareFunction::Equal);
        let copy = make("fs_main", wgpu::CompareFunction::NotEqual);
        let depth_copy = if copied {
            let bindings = PassBindings::used_only(
                ctx,
                pipeline,
                pass,
                OWN,
                Some(&used(&["vs_main", "fs_copy_depth"])?),
            );
            let layout = pipeline_layout(d, "smooth depth copy", scene, Some(&bindings));
            let targets = [Some(wgpu::TextureFormat::R32Uint.into())];
            let pipeline = render_pipeline(
                d,
                &RenderSpec {
                    fs_entry: "fs_copy_depth",
                    ..RenderSpec::new("smooth depth copy", &module, &layout, &targets)
                },
            );
            Some(DepthCopy {
                pipeline,
                bindings,
                target: None,
            })
        } else {
            None
        };
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
            depth_copy,
        })
    }
}

impl DepthCopy {
    /// Draws the depth's bits of `depth_stencil` into the target (made or remade at its
    /// size).
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &Recorder<'_>,
    ) -> Result<(), PassError> {
        let ds = &rec.texture("depth_stencil").texture;
        let size = ds.size();
        if self.target.as_ref().is_none_or(|(t, _)| t.size() != size) {
            let texture = render_target(
                &rec.gpu.device,
                "smooth depth copy",
                (size.width, size.height),
                wgpu::TextureFormat::R32Uint,
                wgpu::TextureUsages::TEXTURE_BINDING,
            );
            let view = texture.create_view(&Default::default());
            self.target = Some((texture, view));
        }
        let (_, view) = self.target.as_ref().expect("made above");
        let bg = self.bindings.bind_group(rec, &[])?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("smooth depth copy"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_bind_group(0, &rec.scene.bind_group, &[]);
        pass.set_bind_group(1, &bg, &[]);
        pass.set_pipeline(&self.pipeline);
        pass.draw(0..3, 0..1);
        Ok(())
    }
}

impl PassNode for Smooth {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        if let Some(c) = &mut self.depth_copy {
            c.record(encoder, rec)?;
        }
        let ds = rec.texture("depth_stencil");
        let mut own = vec![(
            "normal_sampler",
            wgpu::BindingResource::Sampler(&self.sampler),
        )];
        if let Some((_, view)) = self.depth_copy.as_ref().and_then(|c| c.target.as_ref()) {
            own.push(("depth_copy", wgpu::BindingResource::TextureView(view)));
        }
        let bg = self.bindings.bind_group(rec, &own)?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&rec.pass.name),
            color_attachments: &[rec.color_attachment("smoothed_normal")],
            // Read-only: the stencil selects pixels, the depth is sampled for Dist (or its
            // copy, where the device cannot do both in one pass).
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
