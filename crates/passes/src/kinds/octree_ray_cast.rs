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
//! The octrees of every object are built with [`Svo::from_asset`] when the pass is built,
//! concatenated (`svo_nodes_*`, as many bindings as they fill, the shader's `svo_node`
//! generated to read those only: `SvoNode`s of every level but each object's finest, which no
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
//!   binding exceeds the device's limit. The fragment form of octrees within one binding
//!   binds 3 storage buffers of its own (8 with the scene's: WebGPU's default); each
//!   further chunk, and the compute form's hits, one more, which is checked against the
//!   device when the pass is built.
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
use crate::kinds::gbuffer::{PulledPipeline, Specialized};
use crate::kinds::ray_cast_compute::ComputeCast;
use ssbvb_gpu::scene::{GpuScene, chunk_switch};
use ssbvb_gpu::shaders;
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
    /// The fragment form's pipelines, for the chunks the octrees fill (its layout is also
    /// the compute form's).
    pipeline: PulledPipeline,
    /// The bind group of every object's octree (made again when the compute form's hit
    /// buffer is resized).
    octrees: Option<wgpu::BindGroup>,
    /// The octrees' node buffers (as many as they fill) and level offsets.
    buffers: (Vec<wgpu::Buffer>, wgpu::Buffer),
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
    // The compute form's indirect dispatch, bound only to its listing of tiles (a
    // dispatch may not bind the buffer it reads its arguments from).
    OwnBinding {
        name: "cast_dispatch",
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
        let kind = <P::Params as KindSpec>::NAME;
        let chunk_bits = init.scene.chunks.octree_bits;
        let assets: Vec<&VoxelAsset> = init.scene.scene.objects.iter().map(|o| &*o.asset).collect();
        let (nodes, offsets) = concatenated_octrees(kind, &assets)?;
        let buffers = upload(init.ctx, kind, chunk_bits, &nodes, &offsets)?;
        drop((nodes, offsets));
        let special = specialize::<P>(init, buffers.0.len(), compute)?;
        let constants = [
            ("MAX_STEPS", f64::from(max_steps)),
            ("NODE_CHUNK_BITS", f64::from(chunk_bits)),
        ];
        let pipeline = PulledPipeline::counting_for::<P>(init, &constants, &special)?;
        let compute = if compute {
            Some(ComputeCast::new::<P>(
                init,
                &pipeline.bindings,
                &constants,
                &special,
            )?)
        } else {
            None
        };
        Ok(Self {
            kind,
            pipeline,
            octrees: None,
            buffers,
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

    /// Draws the fullscreen triangle (or the compute trace and its resolve).
    pub(crate) fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError> {
        self.check_levels(rec.scene)?;
        if let Some(c) = &mut self.compute {
            let (w, h) = rec.screen;
            if c.hits(rec.gpu, self.kind, (w, h))?.1 {
                self.octrees = None;
            }
        }
        if self.octrees.is_none() {
            self.octrees = Some(self.bind_octrees(rec.gpu)?);
        }
        let bind_group = self.octrees.as_ref().filter(|_| !rec.scene.visible.is_empty());
        self.counters.begin_frame(encoder, rec.counting);
        if let Some(c) = &self.compute {
            c.record(encoder, rec, bind_group);
            return Ok(());
        }
        self.pipeline.record_fullscreen(encoder, rec, bind_group);
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
            if let Some(compute) = &self.compute {
                out.ray_cast_tiles = Some(compute.tiles_launched(frame.gpu)?);
            }
        }
        Ok(())
    }

    /// The bind group of the uploaded octrees, the counters and the hit buffer (the
    /// layout takes those the pipelines read).
    fn bind_octrees(&self, ctx: &GpuContext) -> Result<wgpu::BindGroup, PassError> {
        let (nodes, offsets) = &self.buffers;
        let hits = self
            .compute
            .as_ref()
            .and_then(ComputeCast::hit_buffer)
            .unwrap_or(&self.no_hits);
        let label = format!("{} octrees", self.kind);
        let mut own: Vec<(&'static str, wgpu::BindingResource<'_>)> = NODE_BINDINGS
            .iter()
            .zip(nodes)
            .map(|(name, b)| (*name, b.as_entire_binding()))
            .collect();
        own.extend([
            ("svo_level_offsets", offsets.as_entire_binding()),
            ("ray_counters", self.counters.binding()),
            ("cast_hits", hits.as_entire_binding()),
        ]);
        ctx.validated(&label, |d| {
            self.pipeline.bindings.own_bind_group(d, self.kind, &own)
        })?
    }
}

/// The names of the node bindings, in order.
const NODE_BINDINGS: [&str; NODE_CHUNKS] = [
    "svo_nodes_0",
    "svo_nodes_1",
    "svo_nodes_2",
    "svo_nodes_3",
    "svo_nodes_4",
    "svo_nodes_5",
    "svo_nodes_6",
    "svo_nodes_7",
];

/// Uploads the concatenated octrees: the nodes in as many bindings of `2^chunk_bits` nodes
/// as they fill (at most [`NODE_CHUNKS`]), and the level offsets.
fn upload(
    ctx: &GpuContext,
    kind: &str,
    chunk_bits: u32,
    nodes: &[SvoNode],
    offsets: &[u32],
) -> Result<(Vec<wgpu::Buffer>, wgpu::Buffer), PassError> {
    let chunk = 1usize << chunk_bits;
    let node_bytes = std::mem::size_of::<SvoNode>();
    let chunks = nodes.len().div_ceil(chunk).max(1);
    if chunks > NODE_CHUNKS {
        return Err(PassError::TooLarge(format!(
            "{kind}: the octrees take {} MiB; the pass binds at most {NODE_CHUNKS} × {} MiB \
             of them",
            std::mem::size_of_val(nodes) >> 20,
            (chunk * node_bytes) >> 20
        )));
    }
    let label = format!("{kind} octrees");
    Ok(ctx.validated(&label, |d| {
        let node_buffers: Vec<wgpu::Buffer> = nodes
            .chunks(chunk)
            .map(|part| {
                d.init_buffer(&wgpu::util::BufferInitDescriptor {
                    label: Some("octree_ray_cast svo_nodes"),
                    contents: bytemuck::cast_slice(part),
                    usage: wgpu::BufferUsages::STORAGE,
                })
            })
            .collect();
        let offset_buffer = d.init_buffer(&wgpu::util::BufferInitDescriptor {
            label: Some("octree_ray_cast svo_level_offsets"),
            contents: bytemuck::cast_slice(offsets),
            usage: wgpu::BufferUsages::STORAGE,
        });
        (node_buffers, offset_buffer)
    })?)
}

/// `P`'s shader for octrees in `chunks` node bindings (`svo_node` reads those only), and
/// the group-1 bindings its pipelines read: the fragment form's, or the compute form's
/// trace and resolve. An error naming the limit when they and the scene's bindings exceed
/// the device's storage buffers per stage.
fn specialize<P: PassImpl>(
    init: &PassInit<'_>,
    chunks: usize,
    compute: bool,
) -> Result<Specialized, PassError> {
    let mut read = String::from(
        "// Generated by octree_ray_cast.rs for the chunks the octrees fill.\n\
         fn svo_node(n: u32) -> SvoNode {\n",
    );
    read.push_str(&chunk_switch(
        chunks as u32,
        "NODE_CHUNK_BITS",
        "n",
        "svo_nodes",
    ));
    read.push_str("}\n");
    let source = shaders::source_with(
        P::SHADER,
        &init.scene.bindings,
        &[("svo_node_read.inc.wgsl", &read)],
    )?;
    let entries: &[&str] = if compute {
        &["cs_main", "vs_main", "fs_resolve"]
    } else {
        &["vs_main", "fs_main"]
    };
    let mut used = shaders::used_bindings(P::SHADER, &source, entries, 1)?.concat();
    used.sort_unstable();
    used.dedup();
    // Every own binding of these kinds is a storage buffer.
    let storage = used.len() as u64 + u64::from(init.scene.bindings.max_storage_buffers());
    let allowed = u64::from(init.ctx.device.limits().max_storage_buffers_per_shader_stage);
    if storage > allowed {
        return Err(PassError::TooLarge(format!(
            "pass `{}` ({}{}): octrees in {chunks} binding{} need \
             max_storage_buffers_per_shader_stage >= {storage} (the device allows {allowed})",
            init.pass.name,
            <P::Params as KindSpec>::NAME,
            if compute { ", compute" } else { "" },
            if chunks == 1 { "" } else { "s" },
        )));
    }
    Ok(Specialized {
        file: P::SHADER,
        buffers: &[],
        source,
        used,
    })
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
/// fragment shader; the fragment form of octrees within one binding binds that binding, the
/// level offsets and the counters (more chunks and the compute form's hits are checked
/// against the device when the pass is built, once the octrees' size is known).
pub(crate) const NEEDS: KindNeeds = KindNeeds::new(
    wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE.union(wgpu::DownlevelFlags::COMPUTE_SHADERS),
    3,
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
