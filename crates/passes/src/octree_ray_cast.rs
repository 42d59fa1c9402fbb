//! `octree_ray_cast`: the sparse-voxel-octree baseline (`OctreeRayCast`;
//! `shaders/octree_ray_cast.wgsl`).
//!
//! A render pass drawing one fullscreen triangle into the G-buffer (the same attachments,
//! formats, clear/load rules, `Greater` depth test and stencil = voxel as the billboards;
//! see [`crate::triangles`]): per pixel the fragment shader casts the pixel's ray through
//! every visible instance with a stack-based, front-to-back descent of the object's
//! [`Svo`] (the pointer octree of `ssbvb_voxel::svo`, laid out level by level like an ESVO
//! without contours) down to the instance's LOD level, and writes the nearest hit with its
//! exact depth (`frag_depth`) and the entered face's normal. The shared smoothing and
//! composite run after it unchanged.
//!
//! The octree of an object is built lazily with [`Svo::from_asset`], the first frame the
//! object is visible, uploaded as two storage buffers (`svo_nodes`: `SvoNode`s;
//! `svo_level_offsets`: first node of every level) and cached with its bind group for
//! later frames. Node `i` of level `l` is voxel `i` of LOD `l`, so the hit node's colour is
//! read from the shared point cloud of the instance's LOD.
//!
//! # Limits
//!
//! - One octree is bound per frame, so every visible instance must belong to the same
//!   object (instances may use different levels); otherwise the frame fails with
//!   [`PassError::BadScene`].
//! - Levels above [`MAX_OCTREE_LEVEL`] (16, the shader's stack depth) and octrees larger
//!   than the device's storage-binding limit are refused with [`PassError::TooLarge`].
//! - Cost is O(instances × nodes visited along the ray) per pixel, bounded by `max_steps`.

use std::collections::HashMap;

use ssbvb_gpu::wgpu::util::DeviceExt;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::OctreeRayCastParams;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::svo::{Svo, SvoNode};

use crate::bindings::{OwnBinding, OwnKind};
use crate::frame::Recorder;
use crate::gbuffer::PulledPipeline;
use crate::gpu_scene::GpuScene;
use crate::registry::{KindNeeds, PassImpl, PassInit};
use crate::{PassError, PassNode};

/// The finest level the traversal supports (the WGSL stack depth).
pub const MAX_OCTREE_LEVEL: u32 = 16;

/// The compiled octree pass and its cache of uploaded octrees.
pub struct OctreeRayCast {
    pipeline: PulledPipeline,
    /// Object → bind group of its octree buffers (which it keeps alive).
    octrees: HashMap<usize, wgpu::BindGroup>,
}

/// What the octree pass binds itself: the uploaded octree of the visible object.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "svo_nodes",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_level_offsets",
        kind: OwnKind::StorageRead,
    },
];

impl OctreeRayCast {
    /// The object every visible instance belongs to, or `None` when nothing is visible.
    fn chosen(scene: &GpuScene) -> Result<Option<usize>, PassError> {
        let Some(first) = scene.visible.first() else {
            return Ok(None);
        };
        let object = first.object;
        if let Some(other) = scene.visible.iter().find(|v| v.object != object) {
            return Err(PassError::BadScene(format!(
                "OctreeRayCast binds one octree per frame: every visible instance must belong \
                 to the same object, but objects {object} and {} are both visible (render one \
                 object)",
                other.object
            )));
        }
        if let Some(v) = scene.visible.iter().find(|v| v.level > MAX_OCTREE_LEVEL) {
            return Err(PassError::TooLarge(format!(
                "OctreeRayCast: object {object} at level {}; the octree traversal supports \
                 levels up to {MAX_OCTREE_LEVEL}",
                v.level
            )));
        }
        Ok(Some(object))
    }

    /// Builds and uploads the octree of `asset`.
    fn upload(&self, ctx: &GpuContext, asset: &VoxelAsset) -> Result<wgpu::BindGroup, PassError> {
        let svo = Svo::from_asset(asset)
            .map_err(|e| PassError::BadScene(format!("OctreeRayCast: {e}")))?;
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        if svo.bytes() as u64 > limit {
            return Err(PassError::TooLarge(format!(
                "OctreeRayCast: the octree takes {} MiB, above the device's storage binding \
                 limit of {} MiB",
                svo.bytes() >> 20,
                limit >> 20
            )));
        }
        let mut nodes = svo.nodes;
        if nodes.is_empty() {
            nodes.push(SvoNode::default());
        }
        // Empty bindings are invalid: at least 4 entries, padded with the node count.
        let mut offsets = svo.level_offsets;
        let total = offsets.last().copied().unwrap_or(0);
        offsets.resize(offsets.len().max(4), total);
        let label = "octree_ray_cast octree";
        let bind_group = ctx.validated(label, |d| {
            let node_buffer = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("octree_ray_cast svo_nodes"),
                contents: bytemuck::cast_slice(&nodes),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let offset_buffer = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("octree_ray_cast svo_level_offsets"),
                contents: bytemuck::cast_slice(&offsets),
                usage: wgpu::BufferUsages::STORAGE,
            });
            self.pipeline.bindings.own_bind_group(
                d,
                "octree_ray_cast",
                &[
                    ("svo_nodes", node_buffer.as_entire_binding()),
                    ("svo_level_offsets", offset_buffer.as_entire_binding()),
                ],
            )
        })??;
        Ok(bind_group)
    }
}

impl PassImpl for OctreeRayCast {
    type Params = OctreeRayCastParams;
    const SHADER: &'static str = "octree_ray_cast.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = KindNeeds::new(wgpu::DownlevelFlags::empty(), 2);

    /// Compiles the pipeline for the formats bound to `pass`; `max_steps` becomes the WGSL
    /// override `MAX_STEPS`.
    fn new(init: &PassInit<'_>, params: &OctreeRayCastParams) -> Result<Self, PassError> {
        let max_steps = params.max_steps;
        Ok(Self {
            pipeline: PulledPipeline::new::<Self>(init, &[("MAX_STEPS", f64::from(max_steps))])?,
            octrees: HashMap::new(),
        })
    }
}

impl PassNode for OctreeRayCast {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        let chosen = Self::chosen(rec.scene)?;
        if let Some(object) = chosen {
            if !self.octrees.contains_key(&object) {
                let bg = self.upload(rec.gpu, &rec.scene.scene.objects[object].asset)?;
                self.octrees.insert(object, bg);
            }
        }
        let bind_group = chosen.and_then(|o| self.octrees.get(&o));
        self.pipeline.record_fullscreen(encoder, rec, bind_group);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn shader_declares_the_octree_and_max_steps() {
        // Bindings and the SvoNode layout are checked by `cargo xtask validate-shaders`.
        let src = crate::shaders::source("octree_ray_cast.wgsl").unwrap();
        assert!(src.contains("override MAX_STEPS: u32"));
        assert!(src.contains("const STACK_DEPTH: u32 = 16u;"));
        assert_eq!(super::MAX_OCTREE_LEVEL, 16);
    }
}
