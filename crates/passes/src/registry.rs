//! The one table of implemented pass kinds: for each, its WGSL file, how to build it and
//! what it needs from an adapter. Adding a pass kind adds one line to [`REGISTRY`] (the
//! recipe is in the README, "Adding a pass kind").

use ssbvb_gpu::requirements::{
    LimitNeed, Requirements, max_bind_groups, max_compute_invocations_per_workgroup,
    max_storage_buffers_per_shader_stage, max_texture_dimension_3d,
};
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_graph::{
    PassKind, PassStage, ResolvedPipeline, ResourceDesc, ResourceUsage, ScheduledPass,
};

use crate::bindings::OwnBinding;
use crate::gpu_scene::GpuScene;
use crate::{
    PassError, PassNode, billboards, composite, cube_raster, dense_dda, empty_space,
    octree_ray_cast, ray_march_filter, smooth, triangles,
};

/// What a pass is built from.
pub struct PassInit<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// The scene (its group-0 layout).
    pub scene: &'a GpuScene,
    /// The whole pipeline (formats of the resources bound to the pass's slots).
    pub pipeline: &'a ResolvedPipeline,
    /// The pass (its kind with parameters, and its bindings).
    pub pass: &'a ScheduledPass,
}

/// What one pass kind needs from an adapter beyond what every pipeline needs.
#[derive(Debug, Clone, Copy)]
pub struct KindNeeds {
    /// Downlevel capabilities.
    pub flags: wgpu::DownlevelFlags,
    /// Storage buffers the pass binds itself, in its busiest stage (the scene's come on
    /// top).
    pub storage_buffers: u64,
    /// Bind groups (the scene's is group 0).
    pub bind_groups: u64,
    /// One further limit.
    pub limit: Option<LimitNeed>,
}

impl KindNeeds {
    const fn new(flags: wgpu::DownlevelFlags, storage_buffers: u64) -> Self {
        Self {
            flags,
            storage_buffers,
            bind_groups: 2,
            limit: None,
        }
    }
}

/// One implemented pass kind.
pub struct Registration {
    /// The kind's name as written in RON (`PassKind::name`).
    pub kind: &'static str,
    /// Its WGSL file under `shaders/` (same name as its module).
    pub shader: &'static str,
    /// Builds the pass.
    pub create: fn(&PassInit<'_>) -> Result<Box<dyn PassNode>, PassError>,
    /// What it needs from an adapter.
    pub needs: KindNeeds,
    /// The resources it binds itself, after its slots in group 1 ([`crate::bindings`]).
    pub own: &'static [OwnBinding],
}

/// `create` of a pass type whose constructor takes a [`PassInit`].
macro_rules! create {
    ($ty:path) => {
        |init| {
            Ok(Box::new(<$ty>::new(
                init.ctx,
                init.scene,
                init.pipeline,
                init.pass,
            )?))
        }
    };
}

use wgpu::DownlevelFlags as F;

/// Every implemented pass kind.
pub const REGISTRY: &[Registration] = &[
    Registration {
        kind: "EmptySpacePrepass",
        shader: "empty_space.wgsl",
        create: create!(empty_space::EmptySpace),
        needs: KindNeeds::new(F::empty(), 0),
        own: &[],
    },
    Registration {
        kind: "RayMarchFilter",
        shader: "ray_march_filter.wgsl",
        create: create!(ray_march_filter::RayMarchFilter),
        // Its output is the billboards' indirect draw; 8×8 threads per workgroup.
        needs: KindNeeds {
            flags: F::COMPUTE_SHADERS.union(F::INDIRECT_EXECUTION),
            storage_buffers: 4,
            bind_groups: 2,
            limit: Some(max_compute_invocations_per_workgroup(64)),
        },
        own: ray_march_filter::OWN,
    },
    Registration {
        kind: "Billboards",
        shader: "billboards.wgsl",
        create: create!(billboards::Billboards),
        needs: KindNeeds::new(F::INDIRECT_EXECUTION, 1),
        own: &[],
    },
    Registration {
        kind: "Triangles",
        shader: "triangles.wgsl",
        create: create!(triangles::Triangles),
        needs: KindNeeds::new(F::empty(), 0),
        own: triangles::OWN,
    },
    Registration {
        kind: "Smooth",
        shader: "smooth.wgsl",
        create: create!(smooth::Smooth),
        // Samples the depth of the depth-stencil it stencil-tests against.
        needs: KindNeeds::new(F::READ_ONLY_DEPTH_STENCIL, 0),
        own: smooth::OWN,
    },
    Registration {
        kind: "Composite",
        shader: "composite.wgsl",
        create: create!(composite::Composite),
        needs: KindNeeds::new(F::empty(), 0),
        own: &[],
    },
    Registration {
        kind: "DenseDda",
        shader: "dense_dda.wgsl",
        create: create!(dense_dda::DenseDda),
        needs: KindNeeds {
            limit: Some(max_texture_dimension_3d(1 << dense_dda::MAX_DENSE_LEVEL)),
            ..KindNeeds::new(F::empty(), 0)
        },
        own: dense_dda::OWN,
    },
    Registration {
        kind: "OctreeRayCast",
        shader: "octree_ray_cast.wgsl",
        create: create!(octree_ray_cast::OctreeRayCast),
        needs: KindNeeds::new(F::empty(), 2),
        own: octree_ray_cast::OWN,
    },
    Registration {
        kind: "CubeRaster",
        shader: "cube_raster.wgsl",
        create: create!(cube_raster::CubeRaster),
        needs: KindNeeds::new(F::empty(), 1),
        own: cube_raster::OWN,
    },
];

/// The registration of `kind`.
pub fn registration(kind: &PassKind) -> Option<&'static Registration> {
    REGISTRY.iter().find(|r| r.kind == kind.name())
}

/// Storage buffers of the scene's bind group (group 0), visible to every stage.
const SCENE_STORAGE_BUFFERS: u64 = 6;

/// What `pipeline` needs from an adapter: the scene's bindings, each live pass kind's
/// needs, every texture resource's format with its usages, and the depth-stencil readback
/// the fill count and `render --json` use.
pub fn pipeline_requirements(pipeline: &ResolvedPipeline) -> Requirements {
    let mut req = Requirements::default();
    // The scene's group 0 is visible to the vertex, fragment and compute stages.
    req.need_flags(
        F::VERTEX_STORAGE | F::FRAGMENT_STORAGE,
        "the scene's bindings (group 0)",
    );
    req.need_limit(
        max_storage_buffers_per_shader_stage(SCENE_STORAGE_BUFFERS),
        "the scene's bindings (group 0)",
    );
    for pass in &pipeline.passes {
        let who = format!("pass `{}` ({})", pass.name, pass.kind.name());
        let Some(reg) = registration(&pass.kind) else {
            continue;
        };
        let n = reg.needs;
        if pass.kind.stage() == PassStage::Compute {
            req.need_flags(F::COMPUTE_SHADERS, &who);
        }
        if !n.flags.is_empty() {
            req.need_flags(n.flags, &who);
        }
        req.need_limit(
            max_storage_buffers_per_shader_stage(SCENE_STORAGE_BUFFERS + n.storage_buffers),
            &who,
        );
        req.need_limit(max_bind_groups(n.bind_groups), &who);
        if let Some(l) = n.limit {
            req.need_limit(l, &who);
        }
    }
    let mut depth_readback = false;
    for r in &pipeline.resources {
        let (ResourceDesc::Texture { format, .. }, ResourceUsage::Texture(usage)) =
            (&r.desc, r.usage)
        else {
            continue;
        };
        let format = format.to_wgpu();
        let who = format!("resource `{}`", r.name);
        let fallbacks: &[wgpu::TextureFormat] = match format {
            // `frame::texture_format` takes this when the device lacks the feature.
            wgpu::TextureFormat::Depth32FloatStencil8 => {
                &[wgpu::TextureFormat::Depth24PlusStencil8]
            }
            _ => &[],
        };
        depth_readback |= format.is_depth_stencil_format();
        req.need_format(
            format,
            usage | wgpu::TextureUsages::COPY_SRC,
            &who,
            fallbacks,
        );
    }
    if depth_readback {
        req.need_flags(
            F::DEPTH_TEXTURE_AND_BUFFER_COPIES,
            "reading back the stencil (fill count, render --json)",
        );
    }
    req
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kind the graph declares but this table lacks fails here (and a pipeline using it
    /// would fail with `PassError::NotImplemented`).
    #[test]
    fn every_declared_kind_is_registered_once() {
        for kind in PassKind::all_defaults() {
            let n = REGISTRY.iter().filter(|r| r.kind == kind.name()).count();
            assert_eq!(n, 1, "pass kind {} is registered {n} times", kind.name());
        }
        assert_eq!(REGISTRY.len(), ssbvb_graph::KIND_NAMES.len());
    }

    #[test]
    fn the_default_pipeline_needs_compute_indirect_and_read_only_depth() {
        let src = include_str!("../../../assets/pipelines/ssbvb.ron");
        let p = ssbvb_graph::resolve_str(src, "ssbvb.ron").unwrap();
        let req = pipeline_requirements(&p);
        let flags = req
            .downlevel
            .iter()
            .fold(F::empty(), |acc, (f, _)| acc | *f);
        for f in [
            F::COMPUTE_SHADERS,
            F::INDIRECT_EXECUTION,
            F::READ_ONLY_DEPTH_STENCIL,
            F::VERTEX_STORAGE,
            F::DEPTH_TEXTURE_AND_BUFFER_COPIES,
        ] {
            assert!(flags.contains(f), "{f:?} missing from {:#?}", req.downlevel);
        }
        let entry = req
            .formats
            .iter()
            .find(|n| n.what == "resource `entry`")
            .expect("the entry texture is a need");
        assert_eq!(entry.format, wgpu::TextureFormat::Rgba32Float);
        assert!(
            entry
                .usages
                .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        );
        let storage = req
            .limits
            .iter()
            .find(|(n, _)| n.name == "max_storage_buffers_per_shader_stage")
            .unwrap();
        assert_eq!(storage.0.at_least, 10, "{storage:?}");
        assert!(storage.1.contains("RayMarchFilter"), "{storage:?}");
    }
}
