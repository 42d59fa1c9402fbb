//! `ssbvb-passes`: the implementations of the graph's pass kinds — one module and one WGSL
//! file (under `shaders/`, same name) per kind — plus what runs them: the scene on the GPU
//! ([`gpu_scene`]) and the frame executor ([`frame::Renderer`]).
//!
//! Bindings: group 0 is the scene (frame constants, visible instances, every LOD's point
//! cloud, page tables, page pools, coarse occupancy and the hierarchy over the visible
//! instances' boxes; `shaders/common.inc.wgsl`); group 1
//! holds the pass's graph resources and its own resources, laid out from the pass's
//! declaration ([`bindings`]).

pub mod adapter_needs;
pub mod animated;
pub mod bindings;
pub mod compute_kernels;
pub mod counters;
pub mod embed;
pub mod frame;
pub mod gbuffer;
pub mod gpu_lod_build;
pub mod gpu_radix_sort;
pub mod gpu_scan;
pub mod gpu_scene;
pub mod gpu_voxelize;
pub mod level_splice;
pub mod measure;
pub mod measure_lighting;
pub mod page_cache;
pub mod pipelines;
pub mod ray_cast_counters;
pub mod registry;
pub mod scene;
pub mod shaders;
pub mod streaming;
pub mod surface_build;
pub mod visibility;
pub mod wgsl_layout;

// The passes: one line each (module and registration), in registration order.
registry::pass_modules! {
    empty_space::EmptySpace,
    ray_march_filter::RayMarchFilter,
    billboards::Billboards,
    triangles::Triangles,
    smooth::Smooth,
    composite::Composite,
    dense_dda::DenseDda,
    octree_ray_cast::OctreeRayCast,
    cube_raster::CubeRaster,
    splat_billboards::SplatBillboards,
    rastavox::RastaVox,
    cone_trace::ConeTrace,
    cone_composite::ConeComposite,
    volume_slices::VolumeSlices,
}

pub use adapter_needs::pipeline_requirements;
pub use counters::FrameCounters;
pub use frame::{FrameStats, PassTiming, Profiling, Recorder, Renderer};
pub use gpu_scene::{DynamicRoom, GpuScene, ObjectMemory, StreamChunks};
pub use registry::{PassImpl, PassInit, Registration};
pub use scene::{LodPolicy, Scene, TriangleObject, VolumeObject, VoxelObject};
pub use streaming::{StreamingOptions, StreamingStats};

use ssbvb_gpu::{GpuContext, GpuError, wgpu};
use ssbvb_graph::{PassKind, ResolvedPipeline, ScheduledPass};

/// Errors of building or running passes.
#[derive(Debug, thiserror::Error)]
pub enum PassError {
    /// wgpu reported an error.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A kind has no implementation yet.
    #[error("pass `{pass}`: pass kind {kind} has no GPU implementation yet")]
    NotImplemented {
        /// Pass name.
        pass: String,
        /// Kind name.
        kind: &'static str,
    },
    /// Something exceeds a device or index limit.
    #[error("too large for the GPU: {0}")]
    TooLarge(String),
    /// The scene is unusable.
    #[error("bad scene: {0}")]
    BadScene(String),
    /// A shader could not be assembled.
    #[error("shader {0}")]
    Shader(String),
    /// A GPU budget smaller than what never leaves the GPU plus one page.
    #[error(
        "a GPU budget of {} MiB is too small for this scene: the lookup trees, the pinned \
         coarse levels and the proxies take {} MiB with one page; use --gpu-budget {} or more",
        .budget.div_ceil(1 << 20), .minimum.div_ceil(1 << 20), .minimum.div_ceil(1 << 20)
    )]
    BudgetTooSmall {
        /// The budget asked for (bytes).
        budget: u64,
        /// The smallest budget that works (bytes).
        minimum: u64,
    },
    /// A pass reads whole levels and cannot run on paged ones.
    #[error(
        "pass `{pass}` (kind {kind}) reads every voxel of a level and cannot run under a GPU budget (--gpu-budget pages levels above {pinned}); only the SSBVB filter's pipelines stream"
    )]
    NeedsWholeLevels {
        /// Pass name.
        pass: String,
        /// Kind name.
        kind: &'static str,
        /// The finest level resident whole.
        pinned: u32,
    },
}

/// A pass ready to record: pipelines compiled once, bind groups made per frame.
pub trait PassNode {
    /// Records the pass's work for one frame.
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError>;

    /// Adds what this pass counted in the last frame to `out` (reads back from the GPU;
    /// call after the frame, as [`Renderer::counters`] does). Most passes count nothing.
    fn counters(&self, _ctx: &GpuContext, _out: &mut FrameCounters) -> Result<(), PassError> {
        Ok(())
    }
}

/// Pass kinds implemented by this crate, with default parameters (their WGSL must exist
/// and match their slots; `cargo xtask validate-shaders` checks it).
pub fn registered_kinds() -> Vec<PassKind> {
    PassKind::all_defaults()
        .into_iter()
        .filter(|k| registry::registration(k).is_some())
        .collect()
}

/// Builds the pass object of a scheduled pass through its [`REGISTRY`] entry.
pub fn create_pass(
    ctx: &GpuContext,
    scene: &GpuScene,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
) -> Result<Box<dyn PassNode>, PassError> {
    let reg = registry::registration(&pass.kind).ok_or_else(|| PassError::NotImplemented {
        pass: pass.name.clone(),
        kind: pass.kind.name(),
    })?;
    (reg.create)(&registry::PassInit {
        ctx,
        scene,
        pipeline,
        pass,
    })
}
