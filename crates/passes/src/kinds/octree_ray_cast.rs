//! `octree_ray_cast`: the sparse-voxel-octree baseline (`OctreeRayCast`;
//! `shaders/octree_ray_cast.wgsl`).
//!
//! A render pass drawing one fullscreen triangle into the G-buffer (the same attachments,
//! formats, clear/load rules, `Greater` depth test and stencil = voxel as the billboards;
//! see [`crate::kinds::triangles`]): per pixel the fragment shader casts the pixel's ray
//! through every visible instance with a stack-based, front-to-back descent of the object's
//! [`Svo`] (the pointer octree of `ssbvb_voxel::svo`, laid out level by level like an ESVO
//! without contours) down to the instance's LOD level, and writes the nearest hit with its
//! exact depth (`frag_depth`), the voxel's stored normal and the entered face's
//! (`crate::kinds::gbuffer`). The shared smoothing and composite run after it unchanged.
//!
//! The octrees of every object are built with [`Svo::from_asset`] the first frame,
//! concatenated (`svo_nodes_*`: `SvoNode`s of every level but each object's finest, which no
//! traversal reads, child indices shifted by where the object starts; `svo_level_offsets`:
//! per object [`SVO_STRIDE`] entries, the first node of each level and then the end) and
//! bound for every later frame; an instance finds its object's octree through its LOD's
//! `LodInfo::object`. Node `i` of level `l` is voxel `i` of LOD `l`, so the hit node's
//! colour is read from the shared point cloud of the instance's LOD.
//!
//! The upload, the bindings (`shaders/svo_nodes.inc.wgsl`), the recording and the counters
//! are `OctreeCaster`'s, which `EsvoRayCast` (`super::esvo_ray_cast`) shares: the two
//! kinds differ only in their traversal shader.
//!
//! # Limits
//!
//! - Levels above [`MAX_OCTREE_LEVEL`] (16, the shader's stack depth) and octrees larger
//!   than [`NODE_CHUNKS`] bindings of the scene's chunk size are refused with
//!   [`PassError::TooLarge`]; below that the nodes are split over the bindings, so no
//!   binding exceeds the device's limit.
//! - Cost per pixel: the instances whose boxes its ray enters before its best hit (the
//!   instance hierarchy) × the nodes visited along the ray, bounded by `max_steps`.

use ssbvb_gpu::InitBuffer;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::OctreeRayCastParams;
use ssbvb_voxel::asset::VoxelAsset;
use ssbvb_voxel::svo::{Svo, SvoNode};

use crate::runtime::registry::{OwnBinding, OwnKind};
use crate::runtime::counters::FrameCounters;
use crate::kinds::ray_cast_counters::RayCastCounters;
use crate::runtime::recorder::Recorder;
use crate::kinds::gbuffer::PulledPipeline;
use crate::kinds::ray_cast_compute::ComputeCast;
use ssbvb_gpu::scene::GpuScene;
use crate::runtime::registry::{KindNeeds, PassImpl, PassInit};
use ssbvb_graph::KindSpec;
use crate::error::PassError;
use crate::runtime::node::{CounterSource, PassNode};

/// The finest level the traversal supports (the WGSL stack depth).
pub const MAX_OCTREE_LEVEL: u32 = 16;

/// Entries of `svo_level_offsets` per object: levels 0..=16 and the end (`SVO_STRIDE` in
/// the WGSL).
pub const SVO_STRIDE: usize = MAX_OCTREE_LEVEL as usize + 2;

/// Bindings the octree nodes are split over (`svo_nodes_0` … `svo_nodes_7`): with 128 MiB
/// bindings, 2^27 nodes (bunny level 12 has 77 M).
pub const NODE_CHUNKS: usize = 8;

/// The compiled octree pass and the uploaded octrees of the scene.
pub struct OctreeRayCast(OctreeCaster);

/// What a ray caster over the scene's octrees holds: its pipelines, the uploaded octrees
/// and its counters. `OctreeRayCast` and `EsvoRayCast` (`super::esvo_ray_cast`) differ
/// only in their shader, which reads the same bindings ([`OWN`], svo_nodes.inc.wgsl).
pub(crate) struct OctreeCaster {
    /// The kind's name, for errors.
    kind: &'static str,
    /// Reads nodes through the chunk switch.
    pipeline: PulledPipeline,
    /// The same shader specialized for octrees that fit one binding (`NODE_CHUNKS_USED =
    /// 1`: no switch per node read, which is costly on the software adapter;
    /// docs/benchmarks.md).
    single: PulledPipeline,
    /// The octrees fit one binding: `single` draws.
    one_chunk: bool,
    /// log2 of the nodes per binding (`NODE_CHUNK_BITS` in the WGSL).
    chunk_bits: u32,
    /// The bind group of every object's octree, made the first frame (and again when the
    /// compute form's hit buffer is resized).
    octrees: Option<wgpu::BindGroup>,
    /// The octrees' node buffers and level offsets, uploaded the first frame.
    buffers: Option<(Vec<wgpu::Buffer>, wgpu::Buffer)>,
    /// Traces in a compute shader and resolves (`compute: true`).
    compute: Option<ComputeCast>,
    /// What the fragment form binds as `cast_hits`, which it does not use.
    no_hits: wgpu::Buffer,
    counters: RayCastCounters,
}

/// What the octree ray casters bind themselves: every object's octree and the counters.
pub const OWN: &[OwnBinding] = &[
    OwnBinding {
        name: "svo_nodes_0",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_nodes_1",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_nodes_2",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_nodes_3",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_nodes_4",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_nodes_5",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_nodes_6",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_nodes_7",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "svo_level_offsets",
        kind: OwnKind::StorageRead,
    },
    OwnBinding {
        name: "ray_counters",
        kind: OwnKind::StorageReadWrite,
    },
    // The compute form's per-pixel hits (`ray_cast_compute`); the fragment form binds its
    // 16-byte `no_hits` buffer here, which its shader never reads.
    OwnBinding {
        name: "cast_hits",
        kind: OwnKind::StorageReadWrite,
    },
];

impl OctreeCaster {
    /// Compiles pass `P`'s shader for the formats bound to `init.pass`; `max_steps`
    /// becomes the WGSL override `MAX_STEPS`; `compute` traces in a compute shader
    /// ([`ComputeCast`]) instead of the fragment shader.
    pub(crate) fn new<P: PassImpl>(
        init: &PassInit<'_>,
        max_steps: u32,
        compute: bool,
    ) -> Result<Self, PassError> {
        let chunk_bits = init.scene.chunks.octree_bits;
        let constants = |chunks: usize| {
            vec![
                ("MAX_STEPS", f64::from(max_steps)),
                ("NODE_CHUNK_BITS", f64::from(chunk_bits)),
                ("NODE_CHUNKS_USED", chunks as f64),
            ]
        };
        let pipeline = |chunks: usize| PulledPipeline::counting::<P>(init, &constants(chunks));
        let pipeline_all = pipeline(NODE_CHUNKS)?;
        let compute = if compute {
            Some(ComputeCast::new::<P>(
                init,
                &pipeline_all.bindings,
                [NODE_CHUNKS, 1],
                &constants,
            )?)
        } else {
            None
        };
        Ok(Self {
            kind: <P::Params as KindSpec>::NAME,
            pipeline: pipeline_all,
            single: pipeline(1)?,
            one_chunk: true,
            chunk_bits,
            octrees: None,
            buffers: None,
            compute,
            no_hits: init.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("ray cast hits (unused)"),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            counters: RayCastCounters::new(init.ctx),
        })
    }

    /// Refuses visible instances finer than the traversal's stack.
    fn check_levels(&self, scene: &GpuScene) -> Result<(), PassError> {
        if let Some(v) = scene.visible.iter().find(|v| v.level > MAX_OCTREE_LEVEL) {
            return Err(PassError::TooLarge(format!(
                "{}: object {} at level {}; the octree traversal supports levels up to \
                 {MAX_OCTREE_LEVEL}",
                self.kind, v.object, v.level
            )));
        }
        Ok(())
    }

    /// Uploads the octrees the first frame that draws anything, then draws the fullscreen
    /// triangle with the pipeline for their size.
    pub(crate) fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        self.check_levels(rec.scene)?;
        if self.buffers.is_none() && !rec.scene.visible.is_empty() {
            let assets: Vec<&VoxelAsset> =
                rec.scene.scene.objects.iter().map(|o| &*o.asset).collect();
            self.buffers = Some(self.upload(rec.gpu, &assets)?);
        }
        if let Some(c) = &mut self.compute {
            let (w, h) = rec.screen;
            if c.hits(rec.gpu, self.kind, u64::from(w) * u64::from(h))?.1 {
                self.octrees = None;
            }
        }
        if self.octrees.is_none() && self.buffers.is_some() {
            self.octrees = Some(self.bind_octrees(rec.gpu)?);
        }
        let bind_group = self.octrees.as_ref().filter(|_| !rec.scene.visible.is_empty());
        self.counters.begin_frame(encoder, rec.counting);
        if let Some(c) = &self.compute {
            c.record(encoder, rec, bind_group, self.one_chunk);
            return Ok(());
        }
        let pipeline = if self.one_chunk {
            &self.single
        } else {
            &self.pipeline
        };
        pipeline.record_fullscreen(encoder, rec, bind_group);
        Ok(())
    }

    /// The last counted frame's rays and loop iterations per ray (`octree_nodes_per_ray`).
    pub(crate) fn counters(
        &self,
        frame: &CounterSource<'_>,
        out: &mut FrameCounters,
    ) -> Result<(), PassError> {
        if let Some(c) = self.counters.read(frame.gpu)? {
            out.ray_cast_rays = Some(c.rays);
            out.octree_nodes_per_ray = c.steps_per_ray;
            out.node_words_per_step = c.words_per_step;
        }
        Ok(())
    }

    /// Builds every object's octree and uploads them together: the node chunks and the
    /// level offsets.
    fn upload(
        &mut self,
        ctx: &GpuContext,
        assets: &[&VoxelAsset],
    ) -> Result<(Vec<wgpu::Buffer>, wgpu::Buffer), PassError> {
        let (nodes, offsets) = concatenated_octrees(self.kind, assets)?;
        let chunk = 1usize << self.chunk_bits;
        self.one_chunk = nodes.len() <= chunk;
        let node_bytes = std::mem::size_of::<SvoNode>();
        if nodes.len() > NODE_CHUNKS * chunk {
            return Err(PassError::TooLarge(format!(
                "{}: the octrees take {} MiB; the pass binds at most {NODE_CHUNKS} × {} MiB \
                 of them",
                self.kind,
                (nodes.len() * node_bytes) >> 20,
                (chunk * node_bytes) >> 20
            )));
        }
        let label = format!("{} octrees", self.kind);
        Ok(ctx.validated(&label, |d| {
            let node_buffers: Vec<wgpu::Buffer> = (0..NODE_CHUNKS)
                .map(|i| {
                    let part = nodes.get(i * chunk..).unwrap_or(&[]);
                    let part = &part[..part.len().min(chunk)];
                    // Empty bindings are invalid: an unused chunk gets one node.
                    let zero = [SvoNode::default()];
                    d.init_buffer(&wgpu::util::BufferInitDescriptor {
                        label: Some("octree_ray_cast svo_nodes"),
                        contents: bytemuck::cast_slice(if part.is_empty() { &zero } else { part }),
                        usage: wgpu::BufferUsages::STORAGE,
                    })
                })
                .collect();
            let offset_buffer = d.init_buffer(&wgpu::util::BufferInitDescriptor {
                label: Some("octree_ray_cast svo_level_offsets"),
                contents: bytemuck::cast_slice(&offsets),
                usage: wgpu::BufferUsages::STORAGE,
            });
            (node_buffers, offset_buffer)
        })?)
    }

    /// The bind group of the uploaded octrees, the counters and the hit buffer.
    fn bind_octrees(&self, ctx: &GpuContext) -> Result<wgpu::BindGroup, PassError> {
        let (nodes, offsets) = self.buffers.as_ref().expect("uploaded before binding");
        let hits = self
            .compute
            .as_ref()
            .and_then(ComputeCast::hit_buffer)
            .unwrap_or(&self.no_hits);
        let pipeline = if self.one_chunk {
            &self.single
        } else {
            &self.pipeline
        };
        let label = format!("{} octrees", self.kind);
        ctx.validated(&label, |d| {
            pipeline.bindings.own_bind_group(
                d,
                self.kind,
                &[
                    ("svo_nodes_0", nodes[0].as_entire_binding()),
                    ("svo_nodes_1", nodes[1].as_entire_binding()),
                    ("svo_nodes_2", nodes[2].as_entire_binding()),
                    ("svo_nodes_3", nodes[3].as_entire_binding()),
                    ("svo_nodes_4", nodes[4].as_entire_binding()),
                    ("svo_nodes_5", nodes[5].as_entire_binding()),
                    ("svo_nodes_6", nodes[6].as_entire_binding()),
                    ("svo_nodes_7", nodes[7].as_entire_binding()),
                    ("svo_level_offsets", offsets.as_entire_binding()),
                    ("ray_counters", self.counters.binding()),
                    ("cast_hits", hits.as_entire_binding()),
                ],
            )
        })?
    }
}

/// Every asset's octree in one node array (child indices shifted by where each starts)
/// and the level offsets, [`SVO_STRIDE`] per asset (levels past an asset's last repeat
/// its end). At least one node.
pub fn concatenated_octrees(
    kind: &str,
    assets: &[&VoxelAsset],
) -> Result<(Vec<SvoNode>, Vec<u32>), PassError> {
    let mut nodes: Vec<SvoNode> = Vec::new();
    let mut offsets = Vec::with_capacity(assets.len() * SVO_STRIDE);
    for asset in assets {
        let svo = Svo::from_asset(asset)
            .map_err(|e| PassError::BadScene(format!("{kind}: {e}")))?;
        if svo.level_offsets.len() > SVO_STRIDE {
            return Err(PassError::TooLarge(format!(
                "{kind}: an octree of {} levels; the traversal supports levels up to \
                 {MAX_OCTREE_LEVEL}",
                svo.level_offsets.len() - 1
            )));
        }
        let base = u32::try_from(nodes.len())
            .map_err(|_| PassError::TooLarge(format!("{kind}: over 2^32 octree nodes")))?;
        // The finest level's nodes are never read (a hit is found in its parent's mask, and
        // level 0 is a hit without a read): they are left out, ~3/4 of a surface's nodes.
        // Their indices remain (virtual, past this object's nodes): ids are `node -
        // offset[level]`.
        let levels = svo.level_offsets.len() - 1;
        let kept = svo.level_offsets[(levels - 1).max(1).min(levels)] as usize;
        nodes.extend(svo.nodes[..kept.min(svo.nodes.len())].iter().map(|n| SvoNode {
            child_mask: n.child_mask,
            first_child: if n.child_mask == 0 { 0 } else { n.first_child + base },
        }));
        let end = base + svo.level_offsets.last().copied().unwrap_or(0);
        let mut own: Vec<u32> = svo.level_offsets.iter().map(|o| o + base).collect();
        own.resize(SVO_STRIDE, end);
        offsets.extend(own);
    }
    if nodes.is_empty() {
        nodes.push(SvoNode::default());
    }
    if offsets.is_empty() {
        offsets.resize(SVO_STRIDE, 0);
    }
    Ok((nodes, offsets))
}

/// What the octree ray casters need from an adapter: the counters are written in the
/// fragment shader; the nodes' bindings, the level offsets and the counters.
pub(crate) const NEEDS: KindNeeds = KindNeeds::new(
    wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE.union(wgpu::DownlevelFlags::COMPUTE_SHADERS),
    NODE_CHUNKS as u64 + 3,
);

impl PassImpl for OctreeRayCast {
    type Params = OctreeRayCastParams;
    const SHADER: &'static str = "octree_ray_cast.wgsl";
    const OWN: &'static [OwnBinding] = OWN;
    const NEEDS: KindNeeds = NEEDS;
    const WHOLE_LEVELS: bool = true;

    /// Compiles the pipeline for the formats bound to `pass`; `max_steps` becomes the WGSL
    /// override `MAX_STEPS`.
    fn new(init: &PassInit<'_>, params: &OctreeRayCastParams) -> Result<Self, PassError> {
        Ok(Self(OctreeCaster::new::<Self>(
            init,
            params.max_steps,
            params.compute,
        )?))
    }
}

impl PassNode for OctreeRayCast {
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        self.0.record(encoder, rec)
    }

    fn counters(&self, frame: &CounterSource<'_>, out: &mut FrameCounters) -> Result<(), PassError> {
        self.0.counters(frame, out)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn shader_declares_the_octree_and_max_steps() {
        // Bindings and the SvoNode layout are checked by `cargo xtask validate-shaders`.
        let src = ssbvb_gpu::shaders::source("octree_ray_cast.wgsl").unwrap();
        assert!(src.contains("override MAX_STEPS: u32"));
        assert!(src.contains("const STACK_DEPTH: u32 = 16u;"));
        assert!(src.contains("const SVO_STRIDE: u32 = 18u;"));
        assert_eq!(super::MAX_OCTREE_LEVEL, 16);
        assert_eq!(super::SVO_STRIDE, 18);
    }
}
