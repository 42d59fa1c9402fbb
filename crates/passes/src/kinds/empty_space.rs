//! `empty_space`: the empty-space prepass (`EmptySpacePrepass`; `shaders/empty_space.wgsl`).
//!
//! Rasterizes the proxy mesh of every visible instance and keeps, per pixel, the nearest
//! proxy surface under reversed Z:
//!
//! - `entry` (Rgba32Float): xyz = the object-space point where the pixel-centre ray enters
//!   that proxy, w = instance index + 1 (index into the frame's visible instances; 0 = no
//!   proxy under the pixel);
//! - `prepass_depth` (Depth32Float): its depth (cleared to 0, test `Greater`).
//!
//! Three pipelines share one render pass:
//!
//! 1. front faces (cull back faces; proxy triangles are counter-clockwise seen from outside,
//!    and the projection keeps that orientation in NDC) write the interpolated object-space
//!    position;
//! 2. back faces (cull front faces) write the camera's object-space position: a back face is
//!    the nearest surface only where the ray starts inside a proxy or where the front face
//!    was clipped by the near plane, and there the ray starts at the camera (`t = 0`). Only
//!    the instances where that can happen draw them (`VisibleInstance::back_faces`: the
//!    camera inside, or the bounding sphere reaching the near plane); the others' back
//!    faces would all fail the depth test, at the price of rasterizing them;
//! 3. for instances whose proxy holds the camera, a full-screen triangle at the far end of
//!    the depth range (`GreaterEqual`, no depth write) writes the camera too: it fills the
//!    pixels where that proxy's back faces were clipped by the near or far plane, so a
//!    camera inside an object never loses the voxels around it.
//!
//! The ray-march filter only uses the entry to choose where to start; it never trusts it
//! for the hit itself (see `ray_march_filter`).

use std::ops::Range;

use ssbvb_gpu::scene::{ProxyRange, VisibleInstance};
use ssbvb_gpu::wgpu;
use ssbvb_graph::EmptySpacePrepassKind;

use crate::runtime::recorder::{Recorder, slot_format};
use crate::runtime::pipelines::{RenderSpec, pipeline_layout, render_pipeline};
use crate::runtime::registry::{PassImpl, PassInit};
use crate::error::PassError;
use crate::runtime::node::PassNode;
use ssbvb_gpu::shaders;

/// The compiled prepass.
pub struct EmptySpace {
    front: wgpu::RenderPipeline,
    back: wgpu::RenderPipeline,
    fill: wgpu::RenderPipeline,
}

impl PassImpl for EmptySpace {
    type Params = EmptySpacePrepassKind;
    const SCENE_FREE: bool = true;
    const SHADER: &'static str = "empty_space.wgsl";

    /// Compiles the three pipelines for `pass` (formats from the graph's resources).
    fn new(init: &PassInit<'_>, _params: &EmptySpacePrepassKind) -> Result<Self, PassError> {
        let (ctx, scene, pipeline, pass) = (init.ctx, init.scene, init.pipeline, init.pass);
        let module = ctx.shader("empty_space.wgsl", &shaders::source_for("empty_space.wgsl", &scene.bindings)?)?;
        let entry_format = slot_format(ctx, pipeline, pass, "entry");
        let depth_format = slot_format(ctx, pipeline, pass, "prepass_depth");
        let label = format!("pass `{}`: empty_space pipelines", pass.name);
        let (front, back, fill) = ctx.validated(&label, |d| {
            let layout = pipeline_layout(d, "empty_space", scene, None);
            let targets = [Some(entry_format.into())];
            let proxy_vertex = [Some(wgpu::VertexBufferLayout {
                array_stride: 16,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x4],
            })];
            let make = |label: &str,
                        vs: &str,
                        fs: &str,
                        buffers: &[Option<wgpu::VertexBufferLayout>],
                        cull: Option<wgpu::Face>,
                        compare: wgpu::CompareFunction,
                        write: bool| {
                render_pipeline(
                    d,
                    &RenderSpec {
                        vs_entry: vs,
                        fs_entry: fs,
                        buffers,
                        cull_mode: cull,
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format: depth_format,
                            depth_write_enabled: Some(write),
                            depth_compare: Some(compare),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        ..RenderSpec::new(label, &module, &layout, &targets)
                    },
                )
            };
            use wgpu::CompareFunction::{Greater, GreaterEqual};
            (
                make(
                    "empty_space front faces",
                    "vs_main",
                    "fs_main",
                    &proxy_vertex,
                    Some(wgpu::Face::Back),
                    Greater,
                    true,
                ),
                make(
                    "empty_space back faces",
                    "vs_main",
                    "fs_back",
                    &proxy_vertex,
                    Some(wgpu::Face::Front),
                    Greater,
                    true,
                ),
                make(
                    "empty_space camera inside",
                    "vs_fill",
                    "fs_back",
                    &[],
                    None,
                    GreaterEqual,
                    false,
                ),
            )
        })?;
        Ok(Self { front, back, fill })
    }
}

/// The draws of the proxies of the visible instances that `drawn` keeps: runs of
/// consecutive instances sharing one proxy as one instanced draw (its proxy, its range of
/// instance indices). Instances are rasterized in order within an instanced draw as across
/// draws, so the depth test sees the same fragments in the same order; in a crowd, where
/// neighbours share a level, this is a draw per run instead of one per instance (each
/// draw costs a software rasterizer its setup).
pub(crate) fn proxy_runs(
    visible: &[VisibleInstance],
    drawn: impl Fn(&VisibleInstance) -> bool,
) -> Vec<(ProxyRange, Range<u32>)> {
    let mut runs: Vec<(ProxyRange, Range<u32>)> = Vec::new();
    for (i, v) in visible.iter().enumerate() {
        if v.proxy.index_count == 0 || !drawn(v) {
            continue;
        }
        let i = i as u32;
        match runs.last_mut() {
            Some((p, r)) if *p == v.proxy && r.end == i => r.end = i + 1,
            _ => runs.push((v.proxy, i..i + 1)),
        }
    }
    runs
}

impl PassNode for EmptySpace {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let scene = rec.scene;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&rec.pass.name),
            // Cleared to w = 0: no instance.
            color_attachments: &[rec.color_attachment("entry")],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &rec.texture("prepass_depth").view,
                depth_ops: Some(wgpu::Operations {
                    // Reversed Z: 0 is the far end.
                    load: rec.load_op("prepass_depth", 0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: rec.render_timestamps(),
            ..Default::default()
        });
        if scene.visible.is_empty() {
            return Ok(());
        }
        pass.set_bind_group(0, &scene.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.proxy_vertices.slice(..));
        pass.set_index_buffer(scene.proxy_indices.slice(..), wgpu::IndexFormat::Uint32);
        for (pipeline, back) in [(&self.front, false), (&self.back, true)] {
            pass.set_pipeline(pipeline);
            let runs = proxy_runs(&scene.visible, |v| !back || v.back_faces);
            for (p, instances) in runs {
                // instance_index = the instance's entry in `instances`.
                pass.draw_indexed(
                    p.first_index..p.first_index + p.index_count,
                    p.base_vertex,
                    instances,
                );
            }
        }
        pass.set_pipeline(&self.fill);
        for (i, v) in scene.visible.iter().enumerate() {
            if v.camera_inside {
                let i = i as u32;
                pass.draw(0..3, i..i + 1);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn instance(first_index: u32, index_count: u32, back_faces: bool) -> VisibleInstance {
        VisibleInstance {
            scene_index: 0,
            object: 0,
            level: 0,
            proxy: ProxyRange {
                first_index,
                index_count,
                base_vertex: 0,
            },
            proxy_level: 0,
            camera_inside: false,
            back_faces,
        }
    }

    #[test]
    fn consecutive_instances_of_one_proxy_are_one_draw() {
        let visible = [
            instance(0, 36, false),
            instance(0, 36, true),
            instance(0, 36, false),
            instance(36, 12, false),
            // No triangles: no draw, and the run it splits does not continue across it.
            instance(36, 0, false),
            instance(36, 12, true),
            instance(0, 36, true),
        ];
        let proxy = |first_index, index_count| ProxyRange {
            first_index,
            index_count,
            base_vertex: 0,
        };
        assert_eq!(
            proxy_runs(&visible, |_| true),
            vec![
                (proxy(0, 36), 0..3),
                (proxy(36, 12), 3..4),
                (proxy(36, 12), 5..6),
                (proxy(0, 36), 6..7),
            ]
        );
        // The back faces' draws: only the instances that draw them, a gap ending a run.
        assert_eq!(
            proxy_runs(&visible, |v| v.back_faces),
            vec![(proxy(0, 36), 1..2), (proxy(36, 12), 5..6), (proxy(0, 36), 6..7)]
        );
    }
}
