//! `ssbvb-passes`: the implementations of the graph's pass kinds — one module and one WGSL
//! file (under `shaders/`, same name) per kind — plus what runs them: the scene on the GPU
//! ([`gpu_scene`]) and the frame executor ([`frame::Renderer`]).
//!
//! Bindings: group 0 is the scene (frame constants, visible instances, every LOD's point
//! cloud, page tables, page pools and coarse occupancy; `shaders/common.inc.wgsl`); group 1
//! holds the pass's graph resources, bound by slot name.

pub mod billboards;
pub mod composite;
pub mod cube_raster;
pub mod dense_dda;
pub mod embed;
pub mod empty_space;
pub mod frame;
pub mod gpu_scene;
pub mod measure;
pub mod octree_ray_cast;
pub mod ray_march_filter;
pub mod scene;
pub mod shaders;
pub mod smooth;
pub mod triangles;

pub use frame::{FrameStats, PassTiming, Profiling, Recorder, Renderer};
pub use gpu_scene::{GpuScene, ObjectMemory};
pub use scene::{LodPolicy, Scene, TriangleObject, VoxelObject};

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
}

/// A pass ready to record: pipelines compiled once, bind groups made per frame.
pub trait PassNode {
    /// Records the pass's work for one frame.
    fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder<'_>,
    ) -> Result<(), PassError>;
}

/// Pass kinds implemented by this crate (their WGSL must exist and match their slots;
/// `cargo xtask validate-shaders` checks it).
pub fn registered_kinds() -> Vec<PassKind> {
    PassKind::all_defaults()
        .into_iter()
        .filter(is_implemented)
        .collect()
}

fn is_implemented(kind: &PassKind) -> bool {
    matches!(
        kind,
        PassKind::EmptySpacePrepass
            | PassKind::RayMarchFilter { .. }
            | PassKind::Smooth { .. }
            | PassKind::Composite
            | PassKind::Billboards { .. }
            | PassKind::Triangles
            | PassKind::DenseDda { .. }
            | PassKind::OctreeRayCast { .. }
            | PassKind::CubeRaster { .. }
    )
}

/// Builds the pass object of a scheduled pass.
pub fn create_pass(
    ctx: &GpuContext,
    scene: &GpuScene,
    pipeline: &ResolvedPipeline,
    pass: &ScheduledPass,
) -> Result<Box<dyn PassNode>, PassError> {
    match pass.kind {
        PassKind::EmptySpacePrepass => Ok(Box::new(empty_space::EmptySpace::new(
            ctx, scene, pipeline, pass,
        )?)),
        PassKind::RayMarchFilter { .. } => Ok(Box::new(ray_march_filter::RayMarchFilter::new(
            ctx, scene, pipeline, pass,
        )?)),
        PassKind::Billboards { .. } => Ok(Box::new(billboards::Billboards::new(
            ctx, scene, pipeline, pass,
        )?)),
        PassKind::Triangles => Ok(Box::new(triangles::Triangles::new(
            ctx, scene, pipeline, pass,
        )?)),
        PassKind::Smooth { .. } => Ok(Box::new(smooth::Smooth::new(ctx, scene, pipeline, pass)?)),
        PassKind::Composite => Ok(Box::new(composite::Composite::new(
            ctx, scene, pipeline, pass,
        )?)),
        PassKind::DenseDda { .. } => Ok(Box::new(dense_dda::DenseDda::new(
            ctx, scene, pipeline, pass,
        )?)),
        PassKind::OctreeRayCast { .. } => Ok(Box::new(octree_ray_cast::OctreeRayCast::new(
            ctx, scene, pipeline, pass,
        )?)),
        PassKind::CubeRaster { .. } => Ok(Box::new(cube_raster::CubeRaster::new(
            ctx, scene, pipeline, pass,
        )?)),
    }
}
